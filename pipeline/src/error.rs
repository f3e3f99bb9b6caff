//! The pipeline's error.

use packwright_kinematics::UrdfError;
use packwright_nets::ModelError;
use packwright_sim::SimError;
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum PipelineError {
    #[error("cannot read {path}: {reason}")]
    Read { path: PathBuf, reason: String },
    /// A compiled artifact that does not hold what its schema says.
    #[error("{file}: {problem}")]
    Artifact { file: String, problem: String },
    #[error("{file} has no {what} `{name}`")]
    Unknown {
        file: &'static str,
        what: &'static str,
        name: String,
    },
    #[error("{path}: {source}")]
    Urdf { path: String, source: UrdfError },
    #[error("the arm cannot reach a start pose over the pending area of cell `{cell}`")]
    NoStartPose { cell: String },
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error("{what}: {source}")]
    Model { what: String, source: ModelError },
    /// Demonstrations that follow no one sequence rule.
    #[error(
        "the demonstrations follow no one sequence rule: {detail}. A model learns one rule (ascending, descending or a listed priority) from demonstrations that mostly agree: choose blocks that do with --demos (`sequence random` teaches none)"
    )]
    ContradictorySequence { detail: String },
    #[error("no {what} `{name}`; {known}")]
    NoSuch {
        what: &'static str,
        name: String,
        known: String,
    },
    #[error("{0}")]
    Selection(String),
}

pub type Result<T, E = PipelineError> = std::result::Result<T, E>;
