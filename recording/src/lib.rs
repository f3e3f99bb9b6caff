//! Rerun recordings of a run (`execute --record`, `eval --record`): the
//! arm's links as their collision capsules moving over time, the products
//! and boxes as boxes, the tool path, the sub-goals, the reasoner's
//! decisions and scores as text and bars, joint positions and velocities
//! as time series, and picks, releases, collisions, fallbacks and
//! outcomes as text events, on a sim-time timeline.
//!
//! - [`journal`]: what a run did, collected through a `World` and a
//!   `Policy` wrapper that pass everything through (any planner, any
//!   world);
//! - [`shapes`]: the arm's bodies from the one collision description the
//!   planner and the simulator share;
//! - [`timeline`]: the tool path and the events, each at its sim time;
//! - [`paths`]: the entity paths and the timeline's name (stable: the
//!   README lists them);
//! - `rrd` (feature `rerun`): the `.rrd` bytes of runs, made with the
//!   Rerun SDK (0.36) in memory; the caller writes the file.
//!
//! Without the `rerun` feature (the default) the crate builds no Rerun
//! code: the journal and the timeline still work, and the binary says to
//! rebuild with `--features rerun`.

pub mod journal;
pub mod paths;
pub mod shapes;
pub mod timeline;

#[cfg(feature = "rerun")]
mod error;
#[cfg(feature = "rerun")]
mod rrd;

pub use journal::{Cycle, Entries, FRAME_PERIOD, Journal, JournalPolicy, JournalWorld};
pub use timeline::{Run, Scorer, Scores};

#[cfg(feature = "rerun")]
pub use error::RecordingError;
/// The Rerun SDK this crate records with (its decoder reads recordings
/// back in tests).
#[cfg(feature = "rerun")]
pub use rerun;
#[cfg(feature = "rerun")]
pub use rrd::{APPLICATION, rrd};

/// Whether this build can write recordings (the `rerun` feature).
pub const ENABLED: bool = cfg!(feature = "rerun");
