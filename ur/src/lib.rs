//! A pure-Rust driver for Universal Robots controllers over `std::net`:
//! the real UR10 as the second [`packwright_interface::World`].
//!
//! - [`codec`]: RTDE packets, values and the framer;
//! - [`recipe`]: field names and types, the registers used (24-29), the
//!   robot's state typed;
//! - [`client`]: the RTDE handshake, start and pause, data in and out;
//! - [`script`]: the URScript streaming program (servoj, the watchdog);
//! - [`safety`]: the fault latch, the state checks, the command check;
//! - [`world`]: the real arm, [`Ur10World`], streaming one command per control cycle;
//! - [`products`]: where products are on a real cell ([`ProductSource`]);
//! - [`dashboard`]: the dashboard server, for explicit re-arming;
//! - [`address`]: `ur10://HOST[:PORT]` addresses;
//! - `fake` (feature `fake`): an in-process fake controller for tests;
//! - [`error`]: the crate's error, [`UrError`].
//!
//! It depends on `packwright-interface` only: no kinematics, no
//! simulator, no learning crate.

pub mod address;
pub mod client;
pub mod codec;
pub mod dashboard;
pub mod error;
#[cfg(feature = "fake")]
pub mod fake;
pub mod products;
pub mod recipe;
pub mod safety;
pub mod script;
pub mod world;

pub use address::RobotAddress;
pub use error::UrError;
pub use products::ProductSource;
pub use safety::Fault;
pub use world::{FULL_SPEED, Settings, SuctionSensor, Ur10World, read_state, ready_to_stream};
