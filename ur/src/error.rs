//! The crate's one error type.

use crate::codec::CodecError;
use crate::recipe::RuntimeState;
use crate::safety::Fault;
use std::time::Duration;
use thiserror::Error;

/// Everything that can go wrong talking to a Universal Robots controller.
/// Each variant carries what a caller needs to decide; `Display` is for
/// people.
#[derive(Debug, Error)]
pub enum UrError {
    /// The address did not parse or resolve (`ur10://HOST[:PORT]`).
    #[error("bad robot address `{address}`: {reason}")]
    BadAddress { address: String, reason: String },
    /// Nothing answered at the address (no route, refused, timed out).
    #[error(
        "cannot reach the robot's {service} at {address}: {cause} (is the controller on and on this network?)"
    )]
    Unreachable {
        service: Service,
        address: String,
        /// What the system said (in the message, so not a `source`
        /// too: a chain printed it twice).
        cause: std::io::Error,
    },
    /// A read or write on an open connection failed, or it closed.
    #[error("the connection to the robot's {service} failed: {cause}")]
    Io {
        service: Service,
        /// What the system said (in the message only).
        cause: std::io::Error,
    },
    /// The controller sent no reply (or no data) in time.
    #[error("the robot's {service} sent nothing for {waited:?} (expected {expected})")]
    Timeout {
        service: Service,
        waited: Duration,
        expected: &'static str,
    },
    /// Bytes arrived but made no whole RTDE packet in time: something
    /// else answers on that port (a web server, a serial bridge), whose
    /// first bytes read as a header asking for more than it sends.
    #[error(
        "the robot's {service} sent {pending} bytes in {waited:?} that make no whole RTDE packet (they begin {begins}): is another service listening on that port?"
    )]
    NotRtde {
        service: Service,
        waited: Duration,
        pending: usize,
        /// The first bytes, in hex.
        begins: String,
    },
    /// A malformed packet.
    #[error("malformed packet from the controller: {0}")]
    Codec(CodecError),
    /// The controller refused RTDE protocol version 2.
    #[error(
        "the controller refused RTDE protocol version {version}: packwright needs a controller whose software speaks it (and the input registers from 24 that external clients use); update the controller's software"
    )]
    ProtocolRefused { version: u16 },
    /// A recipe named a field the controller does not know.
    #[error(
        "the controller does not know the RTDE field `{field}` (NOT_FOUND; too old a controller version?)"
    )]
    FieldNotFound { field: String },
    /// A recipe named an input another RTDE client (or a fieldbus adapter)
    /// already writes.
    #[error(
        "the RTDE input `{field}` is in use by another client (IN_USE: a fieldbus adapter or another driver; registers 24-47 must be free)"
    )]
    FieldInUse { field: String },
    /// The controller answered a recipe with other types than expected.
    #[error("the controller gave `{field}` the type {got}, expected {expected}")]
    UnexpectedType {
        field: String,
        got: String,
        expected: String,
    },
    /// The controller refused to start (or pause) the data stream.
    #[error("the controller refused to {what} the RTDE stream")]
    Refused { what: &'static str },
    /// A reply of another kind than the request's.
    #[error("expected a `{expected}` reply, got a `{got}` packet")]
    UnexpectedReply { expected: char, got: char },
    /// The streaming program did not start; `remote` is what the dashboard
    /// said about remote control, when it could be asked.
    #[error("{}", not_started(*.remote))]
    ProgramNotStarted { remote: Option<bool> },
    /// A program is loaded and not stopped (playing, paused): the driver
    /// does not replace a program it did not start.
    #[error(
        "a program is {} on the robot: stop it (pendant, or the dashboard's `stop`) before streaming; packwright does not replace a program it did not start",
        program_state(*.state)
    )]
    ProgramRunning { state: RuntimeState },
    /// The arm would move slower than commanded: the pendant's speed
    /// slider (or the controller's scaling) below 100%.
    #[error(
        "the robot runs at {percent:.0}% speed (the pendant's speed slider, or the controller's speed scaling): packwright streams the speeds it planned, and the arm would fall behind them; set the slider to 100% (a cell's `speed` statement slows the plan itself)"
    )]
    SlowedDown { percent: f64 },
    /// The robot is not ready to move (its state when checked).
    #[error("the robot is not ready: {0}")]
    NotReady(Fault),
    /// The dashboard server refused a command.
    #[error("the dashboard refused `{command}`: {reply}")]
    DashboardRefused { command: String, reply: String },
    /// The product feed sent a line that is not a valid observation.
    #[error("bad product feed line {line}: {reason}")]
    BadFeed { line: u64, reason: String },
}

fn program_state(state: RuntimeState) -> String {
    match state {
        RuntimeState::Playing => "already running".into(),
        RuntimeState::Paused => "paused".into(),
        RuntimeState::Pausing => "pausing".into(),
        RuntimeState::Resuming => "resuming".into(),
        other => format!("in runtime state {other:?}"),
    }
}

fn not_started(remote: Option<bool>) -> &'static str {
    match remote {
        Some(false) => {
            "the robot is not in remote control: switch it to Remote Control on the teach pendant (the streaming program cannot start)"
        }
        _ => {
            "the streaming program did not start (is the robot in remote control, powered on and brakes released?)"
        }
    }
}

/// The controller's TCP services the driver uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Service {
    /// RTDE, port 30004.
    Rtde,
    /// The secondary client interface (URScript programs), port 30002.
    Secondary,
    /// The dashboard server, port 29999.
    Dashboard,
    /// A product feed (vision system) on a local socket.
    Feed,
}

impl std::fmt::Display for Service {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Service::Rtde => "RTDE interface",
            Service::Secondary => "secondary interface",
            Service::Dashboard => "dashboard server",
            Service::Feed => "product feed",
        })
    }
}

/// (By hand, not `#[from]`: that would make the codec error a source as
/// well as part of the message, printed twice in a chain.)
impl From<CodecError> for UrError {
    fn from(e: CodecError) -> UrError {
        UrError::Codec(e)
    }
}
