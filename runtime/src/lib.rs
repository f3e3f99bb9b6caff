//! The robot world: the arm model and its kinematics, collision checking,
//! jerk-limited smoothing, the physical simulator, planners and drivers.
//!
//! Each concern sits behind a small interface: [`robot::Arm`] (geometry and
//! kinematics of a 6-axis arm), `World` (observe, command, suction, step;
//! the simulator and the real robot implement it).

pub mod collision;
pub mod error;
pub mod execute;
pub mod expert;
pub mod learn;
pub mod policy;
pub mod record;
pub mod relabel;
pub mod robot;
pub mod rrt;
pub mod scene;
pub mod sim;
pub mod smoothing;
pub mod world;

pub use error::RuntimeError;
pub use robot::{Arm, DOF, Joints};
