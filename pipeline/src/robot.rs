//! The real UR10 for an episode: the glue between `packwright-ur` (which
//! has no kinematics) and the arm's forward kinematics.
//!
//! - [`tool_tip`]: the cup tip and its turn about the vertical for measured
//!   joints, so that a gripped product follows the tool in the nominal
//!   product source;
//! - [`nominal_products`]: the episode's products where the `.pack` file
//!   puts them (a jig or fixture), the documented default source of
//!   product positions on a real cell;
//! - [`connect`]: an [`Ur10World`] for the episode (its arm's limits,
//!   products from the nominal positions or a vision feed);
//! - [`dry_run`]: connect, read the joints, plan everything in the
//!   simulator from them, check the first command against the measured
//!   joints; nothing moves.

use crate::episode::Episode;
use crate::error::{PipelineError, Result};
use nalgebra::{Isometry3, Point3, Vector3};
use packwright_interface::world::{Contact, Observation, World, WorldError};
use packwright_interface::{Joints, Report, Seen, SequenceRule};
use packwright_motion::execute::{self, Planner};
use packwright_ur::codec::ControllerVersion;
use packwright_ur::dashboard::remote_control;
use packwright_ur::products::{JsonFeed, Known, Nominal, ProductSource, ToolTip};
use packwright_ur::recipe::RobotState;
use packwright_ur::safety::{CommandCheck, CommandProblem, Fault, check_state};
use packwright_ur::{RobotAddress, Settings, Ur10World, UrError};
use std::time::Duration;

/// The cup tip's world position and the flange's turn about the vertical
/// (the angle of its x axis in the table's plane) for joints `q`.
pub fn tool_tip(ep: &Episode) -> ToolTip {
    let arm = ep.arm.clone();
    let b = ep.task.cell.base;
    let base = Isometry3::translation(b[0], b[1], b[2]);
    let suction = ep.task.cell.suction;
    Box::new(move |q: &Joints| {
        let flange = arm.flange_pose(&base, q);
        let tip = flange * Point3::new(0.0, 0.0, suction);
        let x = flange.rotation * Vector3::x();
        ([tip.x, tip.y, tip.z], x.y.atan2(x.x))
    })
}

/// The episode's products at their start positions (the `.pack` file's
/// inventory, or a scenario's), each following the tool while gripped.
pub fn nominal_products(ep: &Episode) -> Nominal {
    let known = ep
        .placements
        .iter()
        .map(|p| Known {
            seen: Seen {
                name: p.product.name.clone(),
                centre: p.centre,
                yaw: 0.0,
            },
            size: p.product.size,
        })
        .collect();
    Nominal::new(known, tool_tip(ep))
}

/// Where product positions come from on the real cell.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Products {
    /// The `.pack` file's positions ([`nominal_products`]).
    Nominal,
    /// A vision system's line-delimited JSON on a local socket
    /// (`host:port`).
    Feed(String),
}

/// The driver's settings for an episode's arm at `address` (the
/// defaults of [`Settings::new`] with the arm's limits).
pub fn settings(ep: &Episode, address: &RobotAddress) -> Settings {
    Settings::new(address.clone(), ep.arm.limits)
}

/// Connects the real robot for `ep`.
pub fn connect(ep: &Episode, address: &RobotAddress, products: &Products) -> Result<Ur10World> {
    let source: Box<dyn ProductSource> = match products {
        Products::Nominal => Box::new(nominal_products(ep)),
        Products::Feed(at) => Box::new(JsonFeed::connect(at, Duration::from_secs(2))?),
    };
    Ok(Ur10World::connect(&settings(ep, address), source)?)
}

/// What a dry run found.
#[derive(Debug)]
pub struct DryRun {
    pub controller: ControllerVersion,
    /// The robot's state when read.
    pub state: RobotState,
    /// The plan, executed in the simulator from the measured joints.
    pub report: Report,
    /// Commands the plan would stream.
    pub commands: usize,
    /// The first command, if any, and its check against the measured
    /// joints (one cycle's travel, the limits).
    pub first: Option<(Joints, std::result::Result<(), CommandProblem>)>,
}

/// Reads the robot's joints without taking control, plans the whole
/// episode in the simulator from them, and checks the first command
/// against the measured joints. Nothing moves; the expert and RRT-Connect
/// handle the products in `rule`'s order. Errors: the robot cannot be
/// reached, or is not ready (a protective stop, not running), or would
/// refuse the streaming program (another program loaded and not stopped,
/// the speed slider below 100%, not in remote control).
pub fn dry_run(
    ep: &Episode,
    address: &RobotAddress,
    planner: &Planner,
    rule: &SequenceRule,
) -> Result<DryRun> {
    let (controller, state) = packwright_ur::read_state(address)?;
    if let Err(f @ (Fault::Safety(_) | Fault::Robot(_))) = check_state(&state) {
        return Err(UrError::NotReady(f).into());
    }
    // What `execute` would refuse at connection, asked without taking
    // control: another program loaded, the speed slider below 100%, and
    // (where the dashboard says so) a robot not in remote control.
    packwright_ur::ready_to_stream(&state)?;
    let remote = remote_control(&address.dashboard_addr());
    if remote == Some(false) {
        return Err(UrError::ProgramNotStarted { remote }.into());
    }
    let sim = ep.simulator(state.actual_q)?;
    let mut recording = Recording {
        inner: sim,
        commands: Vec::new(),
    };
    let report = execute::run_in_order(&mut recording, &ep.arm, &ep.task, planner, rule);
    let s = settings(ep, address);
    let check = CommandCheck {
        limits: s.limits,
        period: 1.0 / controller.frequency(),
        tracking: s.tracking,
    };
    let first = recording.commands.first().map(|q| {
        let verdict = check.check(q, &state.actual_q, &state.actual_q);
        (*q, verdict)
    });
    Ok(DryRun {
        controller,
        state,
        report,
        commands: recording.commands.len(),
        first,
    })
}

/// A world that remembers every command it was sent.
pub struct Recording<W: World> {
    pub inner: W,
    pub commands: Vec<Joints>,
}

impl<W: World> World for Recording<W> {
    fn control_period(&self) -> f64 {
        self.inner.control_period()
    }
    fn observe(&self) -> Observation {
        self.inner.observe()
    }
    fn command(&mut self, joints: &Joints) -> std::result::Result<(), WorldError> {
        self.commands.push(*joints);
        self.inner.command(joints)
    }
    fn set_suction(&mut self, on: bool) -> std::result::Result<(), WorldError> {
        self.inner.set_suction(on)
    }
    fn step(&mut self) -> std::result::Result<(), WorldError> {
        self.inner.step()
    }
    fn take_collisions(&mut self) -> Vec<Contact> {
        self.inner.take_collisions()
    }
}

impl From<UrError> for PipelineError {
    fn from(source: UrError) -> PipelineError {
        PipelineError::Robot { source }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_interface::OrderTask;
    use packwright_interface::scene::{CellScene, Placement, ProductSpec};
    use packwright_kinematics::Arm;

    fn episode() -> Episode {
        let spec = ProductSpec {
            name: "a".into(),
            size: [0.06, 0.06, 0.1],
            mass: 0.2,
        };
        Episode {
            arm: Arm::ur10(),
            task: OrderTask {
                cell: CellScene {
                    name: "c".into(),
                    base: [0.0, 0.0, 0.0],
                    suction: 0.1,
                    lift: 0.15,
                    speed: 1.0,
                    grip_settle: 0.1,
                    release_settle: 0.5,
                    descent: 1.0,
                    pending: ([0.3, -0.3], [0.7, 0.3]),
                    boxes: Vec::new(),
                    slots: Vec::new(),
                },
                products: vec![spec.clone()],
                assignment: Vec::new(),
            },
            placements: vec![Placement {
                product: spec,
                centre: [0.5, 0.1, 0.05],
            }],
        }
    }

    #[test]
    fn a_gripped_product_follows_the_tool_tip_by_forward_kinematics() {
        let ep = episode();
        let base = Isometry3::identity();
        let at = |x: f64, y: f64, z: f64, yaw: f64| {
            ep.arm
                .tool_down_ik(
                    &base,
                    Point3::new(x, y, z),
                    yaw,
                    0.1,
                    &[0.0, -1.5, 1.5, -1.5, -1.5, 0.0],
                )
                .expect("reachable")
        };
        let tip = tool_tip(&ep);
        let on_top = at(0.5, 0.1, 0.1, 0.0);
        let (t, _) = tip(&on_top);
        assert!((t[0] - 0.5).abs() < 1e-6 && (t[2] - 0.1).abs() < 1e-6);
        let mut products = nominal_products(&ep);
        products.update(&on_top, false);
        products.update(&on_top, true);
        assert_eq!(products.held(), Some("a"));
        let away = at(0.3, -0.4, 0.35, 0.0);
        products.update(&away, true);
        let c = products.products()[0].centre;
        assert!(
            (c[0] - 0.3).abs() < 1e-6 && (c[1] + 0.4).abs() < 1e-6 && (c[2] - 0.3).abs() < 1e-6,
            "{c:?}"
        );
        products.update(&away, false);
        assert_eq!(products.held(), None);
        assert!((products.products()[0].centre[2] - 0.05).abs() < 1e-9);
    }
}
