//! What a model directory's `config.json` says: the architecture, how it
//! was trained, and what it was taught.

use crate::taught::TaughtQueries;
use packwright_interface::SequenceRule;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The architecture: everything needed to rebuild the modules before their
/// weights are loaded. Saved as `config.json` beside the weights.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelConfig {
    /// Width of the GraphSAGE embeddings.
    pub graph_hidden: usize,
    /// Number of GraphSAGE layers (0: none; the box's score then reads
    /// the max of the raw node inputs alone). README, "Learning", says
    /// why the default is 0.
    pub graph_layers: usize,
    /// Width of the slot pointer's hidden layers.
    pub pointer_hidden: usize,
    /// Width of the sub-goal planner's hidden layers.
    pub subgoal_hidden: usize,
    /// Size of the sub-goal planner's latent variable.
    pub subgoal_latent: usize,
    /// Width of the dynamics policy's hidden layers (32: its weights are
    /// read at every policy step; at 64 wide they took 18 KB of the
    /// cache that the collision check after the steps then missed).
    pub dynamics_hidden: usize,
}

impl Default for ModelConfig {
    fn default() -> ModelConfig {
        ModelConfig::new()
    }
}

impl ModelConfig {
    pub fn new() -> ModelConfig {
        ModelConfig {
            graph_hidden: 32,
            graph_layers: 0,
            pointer_hidden: 16,
            subgoal_hidden: 64,
            subgoal_latent: 4,
            dynamics_hidden: 32,
        }
    }
}

/// Hyperparameters (saved in `config.json` beside the weights).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    pub seed: u64,
    /// Most epochs per network; a network still improving at the last
    /// one gets up to as many again (and is reported as not converged if
    /// it still improves).
    pub epochs: usize,
    /// Mini-batches per epoch, whatever the number of samples: a large
    /// set is visited over several epochs, a small one several times per
    /// epoch, so the optimiser's budget does not shrink with the data.
    pub batches_per_epoch: usize,
    /// Stop after this many epochs without a better held-out loss (a
    /// plateau).
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
            dagger_rounds: 2,
            dagger_epochs: 60,
        }
    }
}

/// What the model was taught. A model answers about any cell (its
/// inputs are relative: see `features`); what it needs to know of a cell
/// it was not taught comes from the `.pack` files at run time (the base,
/// the slots and their box, the products' sizes and the order's goals).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Task {
    /// The cells of the demonstrations.
    pub cells: Vec<String>,
    /// The sequence rule the demonstrations follow (inferred by `train`);
    /// the reasoner's chain order, and what `eval` judges it against.
    pub sequence: SequenceRule,
    /// Taught with several cells: the cells whose own demonstrations
    /// follow another rule, which the model keeps for them
    /// ([`Task::rule_for`]). Absent in models taught one rule.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub cell_rules: BTreeMap<String, SequenceRule>,
    /// The demonstration blocks taught.
    pub demos: Vec<String>,
}

impl Task {
    /// The rule the model follows in `cell`: the cell's own, else the one
    /// for every cell.
    pub fn rule_for(&self, cell: &str) -> &SequenceRule {
        self.cell_rules.get(cell).unwrap_or(&self.sequence)
    }
}

/// `config.json`: enough to rebuild the networks and to know what they do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedConfig {
    pub schema: String,
    pub model: ModelConfig,
    pub training: TrainConfig,
    pub task: Task,
    /// The range of the sub-goal planner's inputs over the queries it was
    /// taught, per sub-goal kind: a query beyond them is answered as at
    /// their edge ([`TaughtQueries`]).
    pub taught_queries: TaughtQueries,
}

/// The schema `config.json` declares.
pub const SCHEMA: &str = "packwright.model/10";

/// The files of a model directory.
pub const FILES: [&str; 4] = [
    "config.json",
    "reasoner.safetensors",
    "subgoal.safetensors",
    "dynamics.safetensors",
];
