//! A whole training run on a lesson (`packwright_pipeline::teach`): the
//! training set, the expert coach for DAgger, the three networks, and the
//! report saved as `metrics.json`.

use crate::relabel::ExpertCoach;
use crate::training::{Metrics, NetworkMetrics, Progress, TrainError, train};
use crate::{RoundMetrics, Trained};
use packwright_nets::TrainConfig;
use packwright_pipeline::PipelineError;
use packwright_pipeline::teach::{Lesson, Replayed};
use serde::Serialize;

/// `metrics.json` (schema `packwright.metrics/1`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrainingReport {
    pub schema: &'static str,
    pub cell: String,
    pub demos: Vec<String>,
    pub demonstrations: usize,
    pub replayed: usize,
    /// Indices (among the chosen demonstrations) the expert could not
    /// replay.
    pub replay_failures: Vec<usize>,
    pub replay_s: f64,
    pub samples: Samples,
    pub training_s: f64,
    pub reasoner: NetworkMetrics,
    pub subgoal: NetworkMetrics,
    pub dynamics: NetworkMetrics,
    pub dagger: Vec<RoundMetrics>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Samples {
    pub graphs: usize,
    pub subgoals: usize,
    pub actions: usize,
}

#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    #[error(transparent)]
    Train(#[from] TrainError),
}

/// Trains on `lesson` with its `replayed` demonstrations; DAgger's coach is
/// the expert on the lesson's arm and cell.
pub fn run(
    lesson: &Lesson,
    replayed: &Replayed,
    config: &TrainConfig,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(Trained, TrainingReport), JobError> {
    let set = lesson.training_set(replayed)?;
    let ep = lesson.first_episode()?;
    let logs = replayed.complete();
    let coach = ExpertCoach::new(&ep.arm, ep.task.cell.base, ep.task.cell.suction, &logs);
    let (mut trained, metrics) = train(&set, config, Some(&coach), progress)?;
    trained.set_task(lesson.task());
    let Metrics {
        reasoner,
        subgoal,
        dynamics,
        dagger,
        seconds,
    } = metrics;
    let failures = replayed.failures();
    let report = TrainingReport {
        schema: "packwright.metrics/1",
        cell: lesson.cell.clone(),
        demos: lesson.blocks.clone(),
        demonstrations: lesson.chosen.len(),
        replayed: lesson.chosen.len() - failures.len(),
        replay_failures: failures,
        replay_s: replayed.seconds,
        samples: Samples {
            graphs: set.graphs.len(),
            subgoals: set.subgoals.len(),
            actions: set.actions.len(),
        },
        training_s: seconds,
        reasoner,
        subgoal,
        dynamics,
        dagger,
    };
    Ok((trained, report))
}
