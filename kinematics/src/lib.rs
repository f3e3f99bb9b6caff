//! A 6-axis arm: its joint chain (from URDF), limits, collision shapes, and
//! kinematics (`kinematics.rs`). The built-in UR10 is `ur10.urdf`, written
//! from the public DH parameters and embedded in the binary.
//!
//! [`body`] is the one collision description of a cell (the arm's parts,
//! the cup, the table and the boxes, which part pairs are never checked):
//! the planner's checker and the simulator both build their geometry from
//! it.

pub mod body;
mod error;
mod kinematics;
mod mesh;
mod urdf;

pub use error::UrdfError;
pub use kinematics::*;
pub use packwright_interface::joints::{DOF, Joints, Limits};
pub use urdf::{
    ACCELERATION_RANGE, DEFAULT_ACCELERATION, DEFAULT_JERK, JERK_RANGE, MeshReader, from_urdf,
    from_urdf_with,
};

use nalgebra::{Isometry3, Point3, Unit, Vector3};

/// A collision primitive, in its link's frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// The segment `a`–`b` swept by a ball of `radius`.
    Capsule {
        a: Point3<f64>,
        b: Point3<f64>,
        radius: f64,
    },
    /// A box with half extents `half`, placed at `pose`.
    Cuboid {
        pose: Isometry3<f64>,
        half: Vector3<f64>,
    },
    /// A cylinder of `radius` between the centres `a` and `b` of its flat
    /// ends: a collision mesh's bound (`mesh.rs`), a housing round a joint.
    Cylinder {
        a: Point3<f64>,
        b: Point3<f64>,
        radius: f64,
    },
}

/// One rigid link and its collision shapes.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    pub name: String,
    pub shapes: Vec<Shape>,
}

/// The DH lengths of a Universal Robots arm (metres), which admit a
/// closed-form inverse kinematics, and how the arm is mounted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UrGeometry {
    /// The DH base frame in the root link's frame: the base joint's origin
    /// is `mount · Tz(d1)`. The identity when the root is the DH base
    /// frame (the built-in UR10); ROS descriptions turn it half a turn
    /// about z (`base_link` faces the other way to the controller's base).
    pub mount: Isometry3<f64>,
    /// The mount's turn about z (radians): the DH base frame's heading at
    /// a base joint of 0 ([`Arm::policy_joints`]).
    pub heading: f64,
    pub d1: f64,
    pub a2: f64,
    pub a3: f64,
    pub d4: f64,
    pub d5: f64,
    pub d6: f64,
    /// Whether the joint origins are the DH encoding to within 1e-6 (the
    /// built-in UR10, a ROS description as shipped). A calibrated arm's
    /// are not: its closed-form solutions are polished to the exact pose,
    /// its branches told apart more loosely, and its cup tip along the
    /// policy's steps found by forward kinematics
    /// ([`Arm::cup_down_tip`] is `None`).
    pub exact: bool,
}

/// A serial 6-axis arm.
///
/// Invariants: `links.len() == DOF + 1` (`links[0]` is the fixed base link,
/// `links[i + 1]` moves with joint `i`); every joint is revolute; `flange`
/// is the tool flange in the last link's frame (z out of the flange).
#[derive(Debug, Clone, PartialEq)]
pub struct Arm {
    pub name: String,
    /// Each joint's frame in its parent link's frame (the URDF origin).
    pub origins: [Isometry3<f64>; DOF],
    /// Each joint's rotation axis in its own frame.
    pub axes: [Unit<Vector3<f64>>; DOF],
    pub limits: [Limits; DOF],
    pub links: Vec<Link>,
    pub flange: Isometry3<f64>,
    /// `Some` when the chain has the UR geometry (closed-form IK).
    pub ur: Option<UrGeometry>,
}

/// The built-in UR10 description.
pub const UR10_URDF: &str = include_str!("ur10.urdf");

impl Arm {
    /// The built-in UR10.
    pub fn ur10() -> Arm {
        match from_urdf(UR10_URDF) {
            Ok(arm) => arm,
            // The embedded file is tested; this cannot happen in a release.
            Err(e) => unreachable!("the built-in UR10 description is invalid: {e}"),
        }
    }

    /// What the dynamics policy reads of joints `q`: the base joint as the
    /// heading of the arm's DH frame (so that a description whose root is
    /// turned, as ROS's `base_link` is, reads as the built-in UR10 does),
    /// then the shoulder and the elbow.
    pub fn policy_joints(&self, q: &Joints) -> [f64; 3] {
        [q[0] + self.heading(), q[1], q[2]]
    }

    /// The heading of the arm's DH base frame at a base joint of 0: the
    /// mount's turn ([`UrGeometry::heading`]), 0 for other arms.
    pub fn heading(&self) -> f64 {
        self.ur.as_ref().map_or(0.0, |g| g.heading)
    }

    /// Joints `q` of the built-in UR10's convention (a pose named by its
    /// joints, such as the usual "ready" pose) in this arm's: the base
    /// joint less the mount's turn.
    pub fn from_ur_convention(&self, q: &Joints) -> Joints {
        let mut out = *q;
        out[0] -= self.heading();
        out
    }

    pub fn within_limits(&self, q: &Joints) -> bool {
        packwright_interface::joints::within(&self.limits, q)
    }

    /// The arm with its acceleration and jerk limits replaced, joint by
    /// joint (base first), where given (a cell's `acceleration` and
    /// `jerk`); positions and velocities keep the arm's own.
    pub fn with_dynamics(
        mut self,
        acceleration: Option<[f64; DOF]>,
        jerk: Option<[f64; DOF]>,
    ) -> Arm {
        for (j, l) in self.limits.iter_mut().enumerate() {
            if let Some(a) = acceleration {
                l.acceleration = a[j];
            }
            if let Some(k) = jerk {
                l.jerk = k[j];
            }
        }
        self
    }

    /// The arm slowed to `speed` (a share of its full speed, in (0, 1]; as
    /// the teach pendant's speed slider does): every motion keeps its path
    /// and takes `1 / speed` as long, with velocity limits times `speed`,
    /// acceleration limits times its square and jerk limits times its
    /// cube. Other values leave the arm as it is.
    pub fn at_speed(mut self, speed: f64) -> Arm {
        if speed > 0.0 && speed < 1.0 {
            for l in &mut self.limits {
                l.velocity *= speed;
                l.acceleration *= speed * speed;
                l.jerk *= speed * speed * speed;
            }
        }
        self
    }
}
