//! Training (the only crate that uses burn: 0.22.1, the pure-Rust `flex`
//! CPU backend): the three networks of the README's "Learning" section
//! (GraphSAGE reasoner, variational sub-goal planner, dynamics policy),
//! seeded Adam with early stopping, and DAgger for the dynamics policy with
//! the scripted expert as its coach. It writes the model directory that
//! `packwright-nets` reads at run time; no tensor type leaves this crate.
//!
//! - [`model`]: the network modules and their forward passes;
//! - [`data`]: batching examples into tensors;
//! - [`training`]: seeded Adam training with early stopping on a held-out
//!   split;
//! - [`dagger`]: DAgger rounds for the dynamics policy through a [`Coach`];
//! - [`relabel`]: the expert coach (rollouts with forward kinematics);
//! - [`model_files`]: a trained model's files and run-time networks;
//! - [`job`]: a whole training run on a compiled lesson, and its report.

pub mod dagger;
mod data;
pub mod job;
mod model;
pub mod model_files;
pub mod relabel;
pub mod training;

pub use dagger::{Coach, Relabelled, RoundMetrics};
pub use model_files::{SaveError, Trained};
pub use relabel::ExpertCoach;
pub use training::{Metrics, Network, NetworkMetrics, Progress, TrainError, train};
