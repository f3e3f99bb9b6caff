//! The interface between the control loop and a robot cell, simulated or
//! real. It carries no simulator types: the real UR10 driver implements it
//! too.

use crate::error::RuntimeError;
use crate::robot::Joints;

/// A product as the world's sensing sees it: its name and the centre of its
/// body. Whether it is packed, held or missing is never said: the caller
/// infers it from positions, as a camera would.
#[derive(Debug, Clone, PartialEq)]
pub struct Seen {
    pub name: String,
    pub centre: [f64; 3],
    /// Rotation about the vertical axis, radians.
    pub yaw: f64,
}

/// One observation of the cell.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Seconds since the start.
    pub time: f64,
    /// Measured joint positions.
    pub joints: Joints,
    /// Whether the suction is on.
    pub suction: bool,
    pub products: Vec<Seen>,
}

/// A robot cell that can be observed and commanded one control cycle at a
/// time.
pub trait World {
    /// The control period in seconds (2 ms for a UR10).
    fn control_period(&self) -> f64;

    /// What the cell looks like now.
    fn observe(&self) -> Observation;

    /// Sets the joint positions to reach at the end of the next cycle. The
    /// caller smooths its commands (jerk-limited) before sending them.
    fn command(&mut self, joints: &Joints) -> Result<(), RuntimeError>;

    /// Turns the suction on or off.
    fn set_suction(&mut self, on: bool) -> Result<(), RuntimeError>;

    /// Advances one control cycle.
    fn step(&mut self) -> Result<(), RuntimeError>;

    /// Contacts of the arm, the cup or a held product with anything else
    /// since the last call (empty when the world cannot tell).
    fn take_collisions(&mut self) -> Vec<Contact>;
}

/// An unwanted contact.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    pub time: f64,
    /// What touched (`"forearm_link"`, `"held:A"`).
    pub a: String,
    /// What it touched (`"table"`, `"box:tray"`, `"product:B"`).
    pub b: String,
}
