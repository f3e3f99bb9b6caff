//! The robot half's interfaces, in plain numbers and names: what every
//! other robot crate agrees on, and nothing that needs a simulator, a
//! collision library or a learning framework (the model: openrr's `arci`).
//!
//! - [`joints`]: joint positions and limits of a 6-axis arm;
//! - [`scene`]: a cell's fixed parts and its products;
//! - [`task`]: an order to pack, in these terms;
//! - [`world`]: the [`World`] trait (observe, command, suction, step) that
//!   the simulator and the real robot driver implement, and what it reports;
//! - [`policy`]: the [`Policy`] trait, the learned decisions the learned
//!   loop asks for;
//! - [`record`]: motion demonstrations recorded from the expert;
//! - [`outcome`]: typed results of a run (per product, failures, fallbacks,
//!   violations, timings).

pub mod joints;
pub mod outcome;
pub mod policy;
pub mod record;
pub mod scene;
pub mod task;
pub mod world;

pub use joints::{DOF, Joints, Limits};
pub use outcome::{
    Budget, Failure, Fallback, FallbackKind, Hit, Outcome, PlannerKind, ProductReport, Report,
    SUCCESS_RADIUS, Shortfall, Stage, SubGoalKind, Timing, Violation,
};
pub use policy::{Choice, Graph, Node, Policy, SequenceRule, SubGoalQuery};
pub use scene::{BoxSpec, CellScene, DEFAULT_MASS, Placement, ProductSpec, SlotSpec};
pub use task::OrderTask;
pub use world::{Body, Contact, Observation, Seen, World, WorldError};
