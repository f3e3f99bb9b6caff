//! The motion crate's error: what the smoother refuses.

use packwright_interface::Joints;
use std::fmt;
use thiserror::Error;

/// Which position a smoothing error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Position {
    Start,
    Target,
    Waypoint(usize),
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Position::Start => write!(f, "start"),
            Position::Target => write!(f, "target"),
            Position::Waypoint(i) => write!(f, "waypoint {i}"),
        }
    }
}

/// Why the smoother gave no commands.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SmoothingError {
    #[error("joint {joint}: the {limit} limit {value} is not a finite positive number")]
    BadLimit {
        joint: usize,
        limit: &'static str,
        value: f64,
    },
    #[error("joint {joint}: the position limits [{lower}, {upper}] are not a range")]
    BadRange {
        joint: usize,
        lower: f64,
        upper: f64,
    },
    #[error("{at}: joint {joint} position {value} is not finite")]
    NonFinite {
        at: Position,
        joint: usize,
        value: f64,
    },
    #[error("{at}: joint {joint} position {value} is outside its limits [{lower}, {upper}]")]
    OutsideLimits {
        at: Position,
        joint: usize,
        value: f64,
        lower: f64,
        upper: f64,
    },
    #[error("current position {position:?} is not finite (reset to a valid position)")]
    NonFiniteCurrent { position: Joints },
    /// Ruckig found no trajectory (its own words in `reason`).
    #[error("no trajectory from {from:?} to {to:?}: {reason}")]
    NoTrajectory {
        from: Joints,
        to: Joints,
        reason: String,
    },
    #[error("Ruckig produced a non-finite state moving from {from:?} to {to:?}")]
    NonFiniteOutput { from: Joints, to: Joints },
    #[error("Ruckig finished at {at:?}, {miss} rad from the target {target:?}")]
    MissedTarget {
        at: Joints,
        target: Joints,
        miss: f64,
    },
    #[error("the move to waypoint {waypoint} did not finish within {limit_s} s")]
    TooLong { waypoint: usize, limit_s: f64 },
    #[error("Ruckig returned the duration {duration} for the move to waypoint {waypoint}")]
    BadDuration { waypoint: usize, duration: f64 },
}
