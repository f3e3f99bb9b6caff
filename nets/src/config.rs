//! What a model directory's `config.json` says: the architecture, how it
//! was trained, and what it was taught.

use serde::{Deserialize, Serialize};

/// The architecture: everything needed to rebuild the modules before their
/// weights are loaded. Saved as `config.json` beside the weights.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelConfig {
    /// Number of labels: `pick` plus one per slot.
    pub labels: usize,
    /// Width of the GraphSAGE embeddings.
    pub graph_hidden: usize,
    /// Number of GraphSAGE layers.
    pub graph_layers: usize,
    /// Width of the label classifier's hidden layers.
    pub classifier_hidden: usize,
    /// Width of the sub-goal planner's hidden layers.
    pub subgoal_hidden: usize,
    /// Size of the sub-goal planner's latent variable.
    pub subgoal_latent: usize,
    /// Width of the dynamics policy's hidden layers.
    pub dynamics_hidden: usize,
}

impl ModelConfig {
    pub fn new(labels: usize) -> ModelConfig {
        ModelConfig {
            labels,
            graph_hidden: 32,
            graph_layers: 3,
            classifier_hidden: 32,
            subgoal_hidden: 64,
            subgoal_latent: 4,
            dynamics_hidden: 64,
        }
    }
}

/// Hyperparameters (saved in `config.json` beside the weights).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    pub seed: u64,
    /// Most epochs per network.
    pub epochs: usize,
    /// Most mini-batches per epoch: a large sample set is visited over
    /// several epochs (one shuffled pass after another), so that every
    /// network gets a similar number of optimiser steps.
    pub batches_per_epoch: usize,
    /// Stop after this many epochs without a better held-out loss.
    pub patience: usize,
    /// Adam's learning rate at the start; it decays exponentially to a
    /// tenth of it at the last epoch.
    pub learning_rate: f64,
    /// Fraction of each network's samples held out for validation.
    pub holdout: f64,
    pub graph_batch: usize,
    pub subgoal_batch: usize,
    pub action_batch: usize,
    /// Weight of the sub-goal planner's KL term.
    pub kl_weight: f64,
    /// Standard deviation (m) of the noise added to the products'
    /// positions while the reasoner trains (sensing noise, a held product
    /// a little lower than demonstrated).
    #[serde(default)]
    pub position_noise: f64,
    /// DAgger rounds for the dynamics policy (with a coach): roll the
    /// policy out from the demonstrated starts, label the states it
    /// visits with the expert's action, train on everything so far.
    #[serde(default)]
    pub dagger_rounds: usize,
    /// Most epochs of each DAgger round's training.
    #[serde(default)]
    pub dagger_epochs: usize,
}

impl Default for TrainConfig {
    fn default() -> TrainConfig {
        TrainConfig {
            seed: 0,
            epochs: 300,
            batches_per_epoch: 25,
            patience: 40,
            learning_rate: 1e-3,
            holdout: 0.2,
            graph_batch: 32,
            subgoal_batch: 64,
            action_batch: 256,
            kl_weight: 1e-3,
            position_noise: 0.0,
            dagger_rounds: 2,
            dagger_epochs: 60,
        }
    }
}

/// What the model was taught on, for the runtime to check an order against.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Task {
    /// The cell of the demonstrations.
    pub cell: String,
    /// Label names: `pick`, then the cell's slots in order.
    pub labels: Vec<String>,
    /// The demonstration blocks taught.
    pub demos: Vec<String>,
}

/// `config.json`: enough to rebuild the networks and to know what they do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedConfig {
    pub schema: String,
    pub model: ModelConfig,
    pub training: TrainConfig,
    pub task: Task,
}

/// The schema `config.json` declares.
pub const SCHEMA: &str = "packwright.model/1";

/// The files of a model directory.
pub const FILES: [&str; 4] = [
    "config.json",
    "reasoner.safetensors",
    "subgoal.safetensors",
    "dynamics.safetensors",
];
