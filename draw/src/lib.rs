//! Pictures as SVG text: a cell in top and side view at true scale (with
//! its products, an order's assignment, a scenario's worker-packed and
//! missing products, diagnostics where they are, and an executed tool
//! path), and the charts of an evaluation.
//!
//! Pure: every function takes plain data (the interface's [`CellScene`]
//! and this crate's own small types) and returns a `String`; the caller
//! writes files. The output depends on the input alone: no clock, numbers
//! in one fixed format, so pictures can be compared byte for byte.
//!
//! - [`cell`]: the cell picture (plain SVG from a tiny writer, [`svg`]:
//!   true-scale views are shapes in metres, not a chart);
//! - [`path`]: the tool path from what a `World` saw, with stages and
//!   events;
//! - [`charts`]: evaluation charts (plotters, SVG backend, no font
//!   backend).
//!
//! [`CellScene`]: packwright_interface::CellScene

pub mod cell;
pub mod charts;
mod error;
pub mod path;
pub mod svg;
mod view;

pub use cell::{Mark, Picture, Place, Product, ProductState, Reach, UR10_REACH, picture};
pub use charts::{Latencies, ProductTimes, SuccessRate};
pub use error::DrawError;
pub use path::{Event, EventKind, Sample, Stage, ToolPath};
pub use view::SCALE;

#[cfg(test)]
mod tests;
