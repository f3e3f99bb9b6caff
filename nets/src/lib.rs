//! The trained networks at run time (no burn): plain `f32` forward passes
//! of the GraphSAGE reasoner, the variational sub-goal planner and the
//! dynamics policy, over weights read from a model directory's safetensors
//! files; [`Networks`] implements the interface's `Policy`.
//!
//! - [`config`]: `config.json` (architecture, training configuration, the
//!   taught task) and the directory's file names;
//! - [`features`]: the training examples and the input encodings that
//!   training and run time share;
//! - [`forward`]: the forward passes;
//! - [`networks`]: loading and answering;
//! - [`taught`]: the range of the sub-goal queries a model was taught,
//!   which bounds the queries it answers.

pub mod config;
pub mod error;
pub mod features;
pub mod forward;
pub mod networks;
pub mod taught;

pub use config::{FILES, ModelConfig, SavedConfig, Task, TrainConfig};
pub use error::ModelError;
pub use features::{ActionExample, GraphExample, SubGoalExample, TrainingSet};
pub use networks::{Networks, Weights};
pub use taught::TaughtQueries;
