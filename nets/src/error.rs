//! The run-time networks' error: a model directory that cannot be used.

use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// `config.json` is not JSON of the expected shape.
    #[error("config.json: {reason}")]
    Config { reason: String },
    #[error(
        "config.json has schema {found:?}, this packwright reads {expected:?}: train the model again with this packwright (`packwright train`)"
    )]
    Schema {
        found: String,
        expected: &'static str,
    },
    #[error("config.json describes an impossible architecture")]
    Architecture,
    /// A weights file is not safetensors.
    #[error("{file} is not a safetensors file: {reason}")]
    NotSafetensors { file: &'static str, reason: String },
    #[error("{file} has no tensor `{tensor}`")]
    Missing { file: &'static str, tensor: String },
    #[error("{file}: tensor `{tensor}` is {found}, expected F32 of shape {expected:?}")]
    Shape {
        file: &'static str,
        tensor: String,
        found: String,
        expected: Vec<usize>,
    },
    #[error("{file}: tensor `{tensor}` holds a value that is not finite (NaN or infinite)")]
    NotFinite { file: &'static str, tensor: String },
    /// The weights are finite but the networks' answers on a probe input
    /// are not (weights so large that the arithmetic overflows).
    #[error("the {network} gives non-finite outputs on a probe input: its weights are unusable")]
    NonFiniteOutput { network: &'static str },
    /// The sub-goal planner answers a probe query with a point further
    /// from the product than any arm reaches: finite weights far beyond
    /// any trained ones (every weight 1e20 saturates the network, whose
    /// answer is then finite but kilometres away).
    #[error(
        "the sub-goal planner answers a probe input with a point {distance_m:.3e} m from the product, beyond any arm's reach: its weights are unusable"
    )]
    SubGoalOutOfReach { distance_m: f64 },
    /// `taught_queries` holds a bound that is not finite, or a low end
    /// above its high end.
    #[error(
        "config.json: `taught_queries` holds a bound that is not a finite range: train the model again (`packwright train`)"
    )]
    TaughtQueries,
    #[error("cannot write config.json: {reason}")]
    Write { reason: String },
}
