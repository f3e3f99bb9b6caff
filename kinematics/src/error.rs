//! The robot-model crate's error.

use thiserror::Error;

/// A robot description that cannot be used, and why (for people: the
/// reasons are as many as URDF's ways to be wrong, and no caller tells
/// them apart).
#[derive(Debug, Clone, PartialEq, Error)]
#[error("robot description: {0}")]
pub struct UrdfError(pub String);
