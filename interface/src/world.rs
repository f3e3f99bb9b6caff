//! The interface between the control loop and a robot cell, simulated or
//! real. It carries no simulator types: the simulator
//! (`packwright-sim`) implements it, and so will the real UR10 driver.

use crate::joints::Joints;
use thiserror::Error;

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

impl Observation {
    /// Where the product called `name` is seen (centre, yaw), if it is.
    pub fn find(&self, name: &str) -> Option<([f64; 3], f64)> {
        self.products
            .iter()
            .find(|s| s.name == name)
            .map(|s| (s.centre, s.yaw))
    }
}

/// Why a world refused a command or could not go on.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum WorldError {
    /// A joint command with a NaN or infinite position.
    #[error("non-finite joint command {joints:?}")]
    NonFiniteCommand { joints: Joints },
    /// A joint command outside the arm's position limits.
    #[error("joint command {joints:?} outside the limits")]
    OutsideLimits { joints: Joints },
    /// A product's state became invalid (the physics diverged).
    #[error("product {product} left the simulation")]
    ProductLost { product: String },
    /// A real robot stopped, or its driver stopped commanding it; the fault
    /// is latched and no further command is sent.
    #[error("the robot stopped: {reason}")]
    Stopped { reason: StopReason },
}

/// Why a real robot stopped (or its driver stopped commanding it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StopReason {
    /// The controller's protective stop (a collision or a limit).
    ProtectiveStop,
    /// An emergency stop (the robot's or the system's).
    EmergencyStop,
    /// A safeguard stop (a safety input such as a light curtain).
    SafeguardStop,
    /// Another safety mode than normal or reduced (violation, fault,
    /// recovery...).
    SafetyFault,
    /// The arm is not powered and running (robot mode other than running).
    NotRunning,
    /// The streaming program is not playing (stopped, paused, or never
    /// started: for example a robot not in remote control).
    ProgramNotPlaying,
    /// The connection to the controller closed or failed.
    ConnectionLost,
    /// No data came from the controller for several control periods.
    StalledStream,
    /// A command failed the driver's safety check before it was sent.
    CommandRejected,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StopReason::ProtectiveStop => "protective stop",
            StopReason::EmergencyStop => "emergency stop",
            StopReason::SafeguardStop => "safeguard stop",
            StopReason::SafetyFault => "safety fault",
            StopReason::NotRunning => "the arm is not running",
            StopReason::ProgramNotPlaying => "the streaming program is not playing",
            StopReason::ConnectionLost => "connection to the controller lost",
            StopReason::StalledStream => "no data from the controller",
            StopReason::CommandRejected => "a command failed the safety check",
        })
    }
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
    fn command(&mut self, joints: &Joints) -> Result<(), WorldError>;

    /// Turns the suction on or off.
    fn set_suction(&mut self, on: bool) -> Result<(), WorldError>;

    /// Advances one control cycle.
    fn step(&mut self) -> Result<(), WorldError>;

    /// Contacts of the arm, the cup or a held product with anything else
    /// since the last call (empty when the world cannot tell).
    fn take_collisions(&mut self) -> Vec<Contact>;
}

/// A body of the cell that can take part in a collision.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Body {
    /// An arm link, by its name in the robot description.
    Link(String),
    /// The suction cup.
    Cup,
    /// The product the cup holds.
    Held(String),
    Table,
    /// A box (its floor or a wall), by name.
    Box(String),
    /// A product standing in the cell, by name.
    Product(String),
}

impl std::fmt::Display for Body {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Body::Link(name) => write!(f, "{name}"),
            Body::Cup => write!(f, "cup"),
            Body::Held(name) => write!(f, "held:{name}"),
            Body::Table => write!(f, "table"),
            Body::Box(name) => write!(f, "box:{name}"),
            Body::Product(name) => write!(f, "product:{name}"),
        }
    }
}

/// An unwanted contact: `a` (an arm part or the held product) touched `b`.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    pub time: f64,
    pub a: Body,
    pub b: Body,
}

impl std::fmt::Display for Contact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} with {}", self.a, self.b)
    }
}
