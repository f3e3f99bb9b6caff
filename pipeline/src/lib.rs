//! The glue between the language half and the robot half, for any front
//! end (the `packwright` command line is one): episodes from the
//! compiler's model or compiled artifacts, artifact readers, expert
//! replays and rehearsals, training lessons, model directories and the bundled model,
//! evaluation rows and their statistics. No burn: training itself is
//! `packwright-train`.

pub mod artifacts;
pub mod episode;
pub mod error;
pub mod evaluate;
pub mod generate;
pub mod models;
pub mod motion_file;
pub mod reach;
pub mod regular;
pub mod rehearse;
pub mod replay;
pub mod robot;
pub mod stats;
pub mod teach;

pub use error::{NotCompiled, PipelineError, Result};
