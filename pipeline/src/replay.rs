//! Expert replays of compiled demonstrations (motion demonstrations), and
//! the sub-goal planner's and dynamics policy's examples from them.

use crate::episode::demonstration_episode;
use crate::error::Result;
use packwright_compiler::artifact::{DemonstrationRecord, WorldFile};
use packwright_interface::SubGoalQuery;
use packwright_interface::record::{self, MotionLog};
use packwright_motion::execute;
use packwright_nets::{ActionExample, SubGoalExample};
use rayon::prelude::*;

/// An expert replay: its motion log, or, for people, why the expert could
/// not complete it (its report's first problem).
pub type Replay = std::result::Result<MotionLog, String>;

/// One demonstration replayed by the expert.
pub fn replay(world: &WorldFile, demo: &DemonstrationRecord) -> Result<Replay> {
    let ep = demonstration_episode(world, demo)?;
    let mut sim = ep.simulator(ep.home()?)?;
    let mut log = MotionLog::default();
    let report = execute::run_recorded(&mut sim, &ep.arm, &ep.task, &mut log);
    Ok(if report.complete {
        Ok(log)
    } else {
        Err(report
            .first_problem()
            .unwrap_or_else(|| "the package is not complete".into()))
    })
}

/// Replays `demos` in parallel (rayon); `tick` is called after each. The
/// logs come back in the order of `demos`.
pub fn replay_all(
    world: &WorldFile,
    demos: &[&DemonstrationRecord],
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<Replay>> {
    demos
        .par_iter()
        .map(|d| {
            let r = replay(world, d);
            tick();
            r
        })
        .collect()
}

fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

/// The sub-goal planner's and the dynamics policy's examples of one log,
/// recorded in a cell whose robot base is at `base`.
pub fn motion_examples(
    log: &MotionLog,
    base: [f64; 3],
) -> (Vec<SubGoalExample>, Vec<ActionExample>) {
    let subgoals = log
        .subgoals
        .iter()
        .map(|s| SubGoalExample {
            query: SubGoalQuery {
                stage: s.stage,
                index: usize::from(s.index),
                feature: f32s(s.feature),
                tool: f32s(s.tool),
                height: s.height as f32,
                base: f32s(base),
            },
            target: f32s(s.target),
        })
        .collect();
    // The dynamics policy learns only the motions it can make (the wrist
    // keeping the cup down; `record::keeps_cup_down`).
    let imitable: Vec<bool> = log
        .subgoals
        .iter()
        .map(|s| record::keeps_cup_down(&s.start, &s.goal))
        .collect();
    let actions = log
        .actions
        .iter()
        .filter(|a| imitable.get(a.subgoal).copied().unwrap_or(false))
        .map(|a| ActionExample {
            delta: f32s(a.delta),
            joints: f32s(a.joints),
            action: f32s(a.action),
        })
        .collect();
    (subgoals, actions)
}
