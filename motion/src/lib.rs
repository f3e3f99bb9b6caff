//! Motion: everything between a decision and the commands a robot follows.
//!
//! - [`collision`]: the planner's collision checker, on the cell's one
//!   collision description (`packwright_kinematics::body`);
//! - [`smoothing`]: jerk-limited Ruckig smoothing at the control rate;
//! - [`blend`]: passing through waypoints without stopping, within the
//!   same limits;
//! - [`rrt`]: the RRT-Connect planner;
//! - [`expert`]: the scripted demonstrator's sub-goal geometry;
//! - [`execute`]: the execution loops (expert, RRT-Connect, learned) over
//!   any [`World`](packwright_interface::World) and
//!   [`Policy`](packwright_interface::Policy).
//!
//! Nothing here depends on a simulator or a learning framework.

pub mod blend;
pub mod collision;
pub mod error;
pub mod execute;
pub mod expert;
pub mod rrt;
pub mod smoothing;

pub use error::SmoothingError;
