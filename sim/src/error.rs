//! The simulator's error: inputs it cannot simulate.

use packwright_interface::Joints;
use thiserror::Error;

/// Why a simulator could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SimError {
    #[error("the arm has {found} links, expected 7")]
    LinkCount { found: usize },
    #[error("invalid robot base {base:?}")]
    Base { base: [f64; 3] },
    #[error("invalid suction cup length {length}")]
    Suction { length: f64 },
    #[error("invalid pending area")]
    Pending,
    #[error("box {name}: invalid centre or size")]
    Box { name: String },
    #[error("product {name}: invalid {field}")]
    Product { name: String, field: &'static str },
    #[error("start joints {joints:?} are invalid or outside the limits")]
    Start { joints: Joints },
    #[error("the arm has an invalid collision shape")]
    ArmShape,
    #[error("the arm's kinematics give non-finite poses")]
    ArmPoses,
}
