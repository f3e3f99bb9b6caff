//! Learning: the three networks of SPEC §2 (GraphSAGE reasoner, variational
//! sub-goal planner, dynamics policy), their training and their inference.
//!
//! All `burn` code lives in this module (burn 0.22.1, the pure-Rust `flex`
//! CPU backend): the rest of the code base hands it plain samples
//! ([`data`]) and gets back plain numbers ([`inference::Networks`]), never a
//! tensor type.
//!
//! - [`model`]: the network modules and their forward passes;
//! - [`data`]: training samples and batching into tensors;
//! - [`training`]: seeded Adam training with early stopping on a held-out
//!   split;
//! - `dagger`: DAgger rounds for the dynamics policy through a [`Coach`];
//! - [`inference`]: a trained model, saved and loaded as safetensors beside
//!   its `config.json`;
//! - `forward`: the same forward passes on plain `f32` slices,
//!   which [`inference::Networks`] answers with at run time (burn costs
//!   microseconds per tensor op at batch 1).

mod dagger;
pub mod data;
mod forward;
pub mod inference;
pub mod model;
pub mod training;

pub use data::{ActionExample, GraphExample, SubGoalExample, TrainingSet};

pub use model::ModelConfig;

pub use dagger::{Coach, Relabelled, RoundMetrics};
pub use inference::{Choice, Networks, SavedConfig, Task};
pub use training::{Metrics, NetworkMetrics, Progress, TrainConfig, TrainError, train};
