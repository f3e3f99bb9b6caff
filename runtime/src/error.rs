//! The runtime's error type.

use thiserror::Error;

#[derive(Debug, Error)]
pub enum RuntimeError {
    /// A robot description that cannot be used, with the reason.
    #[error("robot description: {0}")]
    Urdf(String),
    /// A pose the arm cannot reach with the cup pointing down.
    #[error("no inverse-kinematics solution for the tool at ({x:.3}, {y:.3}, {z:.3})")]
    Unreachable { x: f64, y: f64, z: f64 },
    /// The smoother refused a target (outside the limits, or invalid).
    #[error("smoothing: {0}")]
    Smoothing(String),
    /// The simulator refused an input or lost its state.
    #[error("simulation: {0}")]
    Simulation(String),
    /// A model directory that cannot be loaded or saved.
    #[error("model: {0}")]
    Model(String),
}
