//! The headless physical simulator of a cell (rapier3d): a UR10 with a
//! suction cup, the table, the boxes and the products.
//!
//! - **Frame and time.** z up, gravity (0, 0, −9.81), metres. One
//!   [`World::step`] is one 2 ms control cycle and one rapier step of
//!   dt = 2 ms (no substepping: rapier's solver already runs
//!   `num_solver_iterations` = 4 internal substeps). Contact recycling is
//!   off so that contact distances are exact each step. Single-threaded, no
//!   randomness: the same inputs give the same trajectory bit for bit.
//! - **Table.** A fixed 0.1 m slab whose top is z = 0, at least 4 m × 4 m,
//!   centred under the base, the pending area and the boxes.
//! - **Boxes.** Fixed; the floor is a [`BOX_WALL`]-thick cuboid whose top
//!   is z = 0 (coincident with the table top: the floor is at table height,
//!   so a slot's goal is z = height / 2); four equally thick walls
//!   inside the outside footprint, from z = 0 to the box height.
//! - **Products.** Dynamic cuboids (their size and mass, friction 0.8,
//!   restitution 0) at rest at their placements.
//! - **Arm.** A fixed body for the base link and one kinematic
//!   (position-based) body per moving link, carrying the link's capsules
//!   and cuboids, moved every step to the forward kinematics of the
//!   commanded joints. The arm follows commands exactly; the measured joints
//!   are the commanded ones of the last step.
//! - **Cup.** A capsule of radius [`CUP_RADIUS`] on the last link, from
//!   the flange down to [`CUP_SHORT`] (5 mm) above the tool tip (its
//!   rounded end), so that the tip reaching a product's top does not
//!   shove it.
//! - **Suction.** When the suction is turned on, the simulator looks for a
//!   product whose upward-facing face is within [`SUCTION_REACH`] (5 mm) of
//!   the tool tip along the face normal, with the tip inside the face; the
//!   nearest is attached to the last link by a fixed joint at its current
//!   relative pose (no contacts between them). While the suction stays on
//!   with nothing held, it keeps trying after every step, but then the tip
//!   must touch the face: at most [`SEAL_REACH`] (1 mm) above it (and at
//!   most 5 mm below). So a cup that comes down onto a top face with the
//!   suction already on grips when it touches, as a vacuum cup seals, and
//!   does not grip 5 mm early and then press the product into the table.
//!   Turning the suction off removes the joint: the product falls or rests.
//! - **Collisions.** After each step, the narrow phase's contact pairs
//!   involving an arm part (a link or the cup) or the held product are
//!   checked. An arm part counts when it is within [`ARM_TOUCH`] (0.5 mm)
//!   of anything (touching, or pushing something away), except: adjacent
//!   parts (the cup and the last link are neighbours); non-adjacent parts
//!   that touch by construction (`body::touching_pairs`, the planner's
//!   list); the base and shoulder
//!   links against the table they stand on; the cup and last link against
//!   the held product, and against a product just released until they have
//!   been apart for [`RELEASE_GRACE`] steps. The held product counts
//!   against the table, boxes and other products only when it penetrates
//!   them by more than [`HELD_PENETRATION`] (1 mm). Products on their own
//!   never count. A contact is reported once when it starts (by name pair);
//!   it is reported again only after the pair has been apart for a step.

mod build;
mod contacts;
mod convert;
mod error;

pub use build::{MAX_COORD, MIN_SIZE};
pub use error::SimError;
pub use packwright_kinematics::body::{BOX_WALL, CUP_RADIUS, CUP_SHORT};

use convert::{from_pose, to_pose};
use nalgebra::{Isometry3, Point3};
use packwright_interface::scene::{CellScene, Placement};
use packwright_interface::world::{Body, Contact, Observation, Seen, World, WorldError};
use packwright_kinematics::body::{self, CUP};
use packwright_kinematics::{Arm, DOF, Joints};
use rapier3d::prelude::*;

/// The control period and integration step, seconds.
pub const PERIOD: f64 = 0.002;
/// Largest distance between the tool tip and a product's top face for the
/// suction to grip it, metres.
pub const SUCTION_REACH: f64 = 0.005;
/// Largest height of the tool tip above a product's top face for a
/// suction that is already on to grip it (the cup seals), metres.
pub const SEAL_REACH: f64 = 0.001;
/// Distance under which an arm part touches something, metres.
pub const ARM_TOUCH: f64 = 0.0005;
/// Penetration beyond which a held product collides, metres.
pub const HELD_PENETRATION: f64 = 0.001;
/// Steps a released product must stay apart from the cup before their
/// contacts count again.
pub const RELEASE_GRACE: u32 = 25;

/// What a collider belongs to, stored in its `user_data`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Part {
    /// 0..=6 the links (0 the base), [`CUP`] the cup.
    Arm(usize),
    Table,
    Box(usize),
    Product(usize),
}

impl Part {
    fn encode(self) -> u128 {
        let (kind, index) = match self {
            Part::Arm(i) => (1u128, i),
            Part::Table => (2, 0),
            Part::Box(i) => (3, i),
            Part::Product(i) => (4, i),
        };
        (kind << 64) | index as u128
    }

    fn decode(data: u128) -> Option<Part> {
        let index = usize::try_from(data & u128::from(u64::MAX)).ok()?;
        match data >> 64 {
            1 => Some(Part::Arm(index)),
            2 => Some(Part::Table),
            3 => Some(Part::Box(index)),
            4 => Some(Part::Product(index)),
            _ => None,
        }
    }
}

struct Product {
    name: String,
    half: [f64; 3],
    body: RigidBodyHandle,
}

struct Held {
    product: usize,
    joint: ImpulseJointHandle,
}

/// The simulated cell. See the module documentation for the model.
pub struct Simulator {
    arm: Arm,
    base: Isometry3<f64>,
    suction_length: f64,
    world: PhysicsWorld,
    /// Base link body (fixed) then one kinematic body per moving link.
    links: Vec<RigidBodyHandle>,
    products: Vec<Product>,
    cell: CellScene,
    /// Non-adjacent arm part pairs that touch by construction.
    neighbours: Vec<(usize, usize)>,
    /// Target of the next step.
    commanded: Joints,
    /// Where the arm is (the target of the last step).
    measured: Joints,
    suction: bool,
    held: Option<Held>,
    /// A product just released, and for how many steps it has been apart
    /// from the cup.
    released: Option<(usize, u32)>,
    steps: u64,
    /// Name pairs in contact at the last step.
    touching: Vec<(Body, Body)>,
    collisions: Vec<Contact>,
}

impl Simulator {
    /// A simulator of `cell` with `arm` at joints `start` and `products`
    /// standing at their placements, suction off, time 0.
    pub fn new(
        arm: Arm,
        cell: &CellScene,
        products: &[Placement],
        start: Joints,
    ) -> Result<Simulator, SimError> {
        build::validate(&arm, cell, products, &start)?;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -9.81);
        world.integration_parameters.dt = PERIOD as f32;
        world.integration_parameters.contact_recycling = false;
        let base = Isometry3::translation(cell.base[0], cell.base[1], cell.base[2]);
        build::add_fixtures(&mut world, &body::fixtures(cell));
        let bodies = build::add_products(&mut world, products);
        let parts = body::arm_parts(&arm, cell.suction, 0.0);
        let links = build::add_arm(&mut world, &arm, &base, &start, &parts);
        let neighbours = body::touching_pairs(&arm, cell.suction);
        let products = products
            .iter()
            .zip(bodies)
            .map(|(p, body)| Product {
                name: p.product.name.clone(),
                half: p.product.size.map(|v| v / 2.0),
                body,
            })
            .collect();
        Ok(Simulator {
            arm,
            base,
            suction_length: cell.suction,
            world,
            links,
            products,
            cell: cell.clone(),
            neighbours,
            commanded: start,
            measured: start,
            suction: false,
            held: None,
            released: None,
            steps: 0,
            touching: Vec::new(),
            collisions: Vec::new(),
        })
    }

    /// The seconds simulated so far.
    pub fn time(&self) -> f64 {
        self.steps as f64 * PERIOD
    }

    /// The name of the held product, if any.
    pub fn held(&self) -> Option<&str> {
        self.held
            .as_ref()
            .map(|h| self.products[h.product].name.as_str())
    }

    /// The world pose of product `k`'s body.
    fn product_pose(&self, k: usize) -> Option<Isometry3<f64>> {
        self.world
            .bodies
            .get(self.products[k].body)
            .map(|b| from_pose(b.position()))
    }

    /// Attaches the product under the tool tip, if the tip is inside its
    /// top face, at most `above` above it and [`SUCTION_REACH`] below.
    fn try_attach(&mut self, above: f64) {
        let tip = self
            .arm
            .tool_tip(&self.base, &self.measured, self.suction_length);
        let mut best: Option<(usize, f64)> = None;
        for k in 0..self.products.len() {
            if let Some(d) = self.pose_reach(k, &tip, above)
                && best.is_none_or(|(_, b)| d < b)
            {
                best = Some((k, d));
            }
        }
        let Some((k, _)) = best else { return };
        let (Some(link), Some(product)) = (
            self.world.bodies.get(self.links[DOF]),
            self.world.bodies.get(self.products[k].body),
        ) else {
            return;
        };
        let relative = link.position().inv_mul(product.position());
        let joint = FixedJointBuilder::new()
            .local_frame1(relative)
            .local_frame2(Pose::IDENTITY)
            .contacts_enabled(false);
        let handle =
            self.world
                .impulse_joints
                .insert(self.links[DOF], self.products[k].body, joint, true);
        self.held = Some(Held {
            product: k,
            joint: handle,
        });
        if self.released.is_some_and(|(r, _)| r == k) {
            self.released = None;
        }
    }

    /// How far the tip is from product `k`'s upward-facing face, when the
    /// tip is within reach of it (inside the face, at most `above` above it
    /// and [`SUCTION_REACH`] below along its normal).
    fn pose_reach(&self, k: usize, tip: &Point3<f64>, above: f64) -> Option<f64> {
        let pose = self.product_pose(k)?;
        let local = pose.inverse_transform_point(tip);
        let half = self.products[k].half;
        for axis in 0..3 {
            for sign in [1.0, -1.0] {
                let mut normal = nalgebra::Vector3::zeros();
                normal[axis] = sign;
                // A face counts as a top face when it points within ~25° of up.
                if (pose.rotation * normal).z < 0.9 {
                    continue;
                }
                let height = sign * local[axis] - half[axis];
                let inside = (0..3)
                    .filter(|&j| j != axis)
                    .all(|j| local[j].abs() <= half[j]);
                if inside && (-SUCTION_REACH..=above).contains(&height) {
                    return Some(height.abs());
                }
            }
        }
        None
    }

    fn release(&mut self) {
        if let Some(h) = self.held.take() {
            self.world.impulse_joints.remove(h.joint, true);
            self.world.wake_up(self.products[h.product].body, true);
            self.released = Some((h.product, 0));
        }
    }
}

impl World for Simulator {
    fn control_period(&self) -> f64 {
        PERIOD
    }

    fn observe(&self) -> Observation {
        let products = (0..self.products.len())
            .filter_map(|k| {
                let pose = self.product_pose(k)?;
                let t = pose.translation.vector;
                Some(Seen {
                    name: self.products[k].name.clone(),
                    centre: [t.x, t.y, t.z],
                    yaw: pose.rotation.euler_angles().2,
                })
            })
            .collect();
        Observation {
            time: self.time(),
            joints: self.measured,
            suction: self.suction,
            products,
        }
    }

    fn command(&mut self, joints: &Joints) -> Result<(), WorldError> {
        if joints.iter().any(|v| !v.is_finite()) {
            return Err(WorldError::NonFiniteCommand { joints: *joints });
        }
        if !self.arm.within_limits(joints) {
            return Err(WorldError::OutsideLimits { joints: *joints });
        }
        self.commanded = *joints;
        Ok(())
    }

    fn set_suction(&mut self, on: bool) -> Result<(), WorldError> {
        self.suction = on;
        if on {
            if self.held.is_none() {
                self.try_attach(SUCTION_REACH);
            }
        } else {
            self.release();
        }
        Ok(())
    }

    fn step(&mut self) -> Result<(), WorldError> {
        let poses = self.arm.link_poses(&self.base, &self.commanded);
        for (handle, pose) in self.links.iter().zip(&poses).skip(1) {
            if let Some(body) = self.world.bodies.get_mut(*handle) {
                body.set_next_kinematic_position(to_pose(pose));
            }
        }
        self.world.step();
        self.steps += 1;
        self.measured = self.commanded;
        let broken = self.products.iter().find(|p| {
            self.world
                .bodies
                .get(p.body)
                .is_none_or(|b| !b.position().is_finite() || !b.linvel().is_finite())
        });
        if let Some(p) = broken {
            return Err(WorldError::ProductLost {
                product: p.name.clone(),
            });
        }
        if self.suction && self.held.is_none() {
            self.try_attach(SEAL_REACH);
        }
        self.collect_contacts();
        Ok(())
    }

    fn take_collisions(&mut self) -> Vec<Contact> {
        std::mem::take(&mut self.collisions)
    }
}
