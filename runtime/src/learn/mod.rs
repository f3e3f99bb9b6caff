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
//! - [`inference`]: a trained model, saved and loaded as safetensors beside
//!   its `config.json`.

pub mod data;
pub mod inference;
pub mod model;
pub mod training;

pub use data::{ActionExample, GraphExample, SubGoalExample, TrainingSet};

pub use model::ModelConfig;

pub use inference::{Choice, Networks, SavedConfig, Task};
pub use training::{Metrics, NetworkMetrics, Progress, TrainConfig, TrainError, train};
