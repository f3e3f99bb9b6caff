//! DAgger for the dynamics policy (Ross et al., 2011), on the training
//! side: after the first training, each round asks a [`Coach`] to roll the
//! policy out and label the states it visits with the expert's actions,
//! adds them, and trains again on everything so far. The coach lives
//! outside this module (`crate::relabel`): it needs the arm, not burn.

use crate::model::DynamicsPolicy;
use crate::training::{NetworkMetrics, Progress, train_dynamics};
use burn::prelude::*;
use packwright_nets::TrainConfig;
use packwright_nets::features::{ACTION_SCALE, ActionExample};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// One pass of policy rollouts from the demonstrated starts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoundMetrics {
    /// 0: rollouts of the policy trained on the demonstrations alone.
    pub round: usize,
    pub rollouts: usize,
    /// Rollouts that reached their sub-goal within the step budget.
    pub reached: usize,
    /// Labelled states added to the training set after this pass.
    pub added: usize,
    pub seconds: f64,
}

/// The expert side of DAgger (Ross et al., 2011): rolls a dynamics policy
/// out and labels every state it visits with the expert's action there.
/// `policy(delta, joints)` gives base, shoulder and elbow steps (radians).
pub trait Coach: Sync {
    fn relabel(&self, policy: &(dyn Fn([f32; 3], [f32; 3]) -> [f32; 3] + Sync)) -> Relabelled;
}

/// What a [`Coach`] returns.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Relabelled {
    /// The visited states with the expert's actions.
    pub actions: Vec<ActionExample>,
    pub rollouts: usize,
    pub reached: usize,
}

/// DAgger rounds after the first training: each round rolls the policy
/// out (the coach), adds the labelled states, and trains on all samples
/// so far for at most `config.dagger_epochs`; a last pass of rollouts
/// measures the final policy.
#[allow(clippy::too_many_arguments)]
pub(super) fn dagger(
    coach: &dyn Coach,
    trained: (DynamicsPolicy, NetworkMetrics),
    demonstrated: &[ActionExample],
    config: &TrainConfig,
    rng: &mut ChaCha8Rng,
    plain: &Device,
    device: &Device,
    progress: &(dyn Fn(Progress) + Sync),
) -> (DynamicsPolicy, NetworkMetrics, Vec<RoundMetrics>) {
    let (mut model, mut metrics) = trained;
    let mut actions = demonstrated.to_vec();
    let mut rounds = Vec::new();
    let round_config = TrainConfig {
        epochs: config.dagger_epochs.max(1),
        ..config.clone()
    };
    for round in 0..=config.dagger_rounds {
        let started = Instant::now();
        let Some(weights) = model.weights() else {
            break;
        };
        let policy = |delta: [f32; 3], joints: [f32; 3]| {
            weights.action(delta, joints).map(|a| a * ACTION_SCALE)
        };
        let relabelled = coach.relabel(&policy);
        let last = round == config.dagger_rounds;
        rounds.push(RoundMetrics {
            round,
            rollouts: relabelled.rollouts,
            reached: relabelled.reached,
            added: if last { 0 } else { relabelled.actions.len() },
            seconds: started.elapsed().as_secs_f64(),
        });
        if last || relabelled.actions.is_empty() {
            break;
        }
        actions.extend(relabelled.actions);
        (model, metrics) = train_dynamics(
            &actions,
            &round_config,
            round + 1,
            model,
            rng,
            plain,
            device,
            progress,
        );
    }
    (model, metrics, rounds)
}
