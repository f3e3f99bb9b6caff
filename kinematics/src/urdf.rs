//! Reading an [`Arm`] from a URDF description.
//!
//! The description must be a single chain (no branches) from its root link
//! through exactly [`DOF`] revolute or continuous joints; fixed joints may
//! sit anywhere along it and are folded away (into the next joint's origin,
//! into the flange, and their links' shapes into the moving link they are
//! bolted to). The flange is the link named `tool0` (else `flange`) after
//! the last moving joint, else the chain's last link.
//!
//! Limits: revolute joints need finite `lower < upper` and a positive
//! `velocity`; continuous joints get ±2π. Acceleration and jerk come from the
//! URDF 1.2 attributes `acceleration` (or `deceleration`, whichever is
//! smaller) and `jerk` of `<limit>` (`<robot version="1.2">`); when absent
//! (or for older versions, which ignore them) they default to
//! [`DEFAULT_ACCELERATION`] and [`DEFAULT_JERK`].
//!
//! Collision: `<collision>` cylinders and capsules become [`Shape::Capsule`]s
//! over their axis segment (a capsule contains its cylinder and overhangs
//! each flat end by the radius), spheres become capsules of zero length,
//! boxes become [`Shape::Cuboid`]s. Meshes are ignored: a link described by
//! meshes only has no shapes and is not collision-checked.

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, TAU};

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use urdf_rs::{Geometry, JointType, Pose};

use super::{Arm, DOF, Limits, Link, Shape, UrGeometry};
use crate::error::UrdfError;

/// Acceleration limit (rad/s²) of a joint whose description gives none.
pub const DEFAULT_ACCELERATION: f64 = 2.5;
/// Jerk limit (rad/s³) of a joint whose description gives none.
pub const DEFAULT_JERK: f64 = 10.0;
/// How closely joint origins must match the DH encoding to count as UR.
const UR_TOLERANCE: f64 = 1e-6;

/// Reads a 6-axis arm from URDF text. See the module documentation for what
/// is accepted.
pub fn from_urdf(text: &str) -> Result<Arm, UrdfError> {
    let robot = urdf_rs::read_from_string(text).map_err(|e| UrdfError::Parse {
        reason: e.to_string(),
    })?;
    let links: HashMap<&str, &urdf_rs::Link> =
        robot.links.iter().map(|l| (l.name.as_str(), l)).collect();
    if links.len() != robot.links.len() {
        return Err(UrdfError::DuplicateLink);
    }
    let mut children: HashMap<&str, Vec<&urdf_rs::Joint>> = HashMap::new();
    let mut has_parent: HashMap<&str, &str> = HashMap::new();
    for j in &robot.joints {
        for end in [&j.parent.link, &j.child.link] {
            if !links.contains_key(end.as_str()) {
                return Err(UrdfError::UnknownLink {
                    joint: j.name.clone(),
                    link: end.clone(),
                });
            }
        }
        if let Some(other) = has_parent.insert(&j.child.link, &j.name) {
            return Err(UrdfError::TwoParents {
                link: j.child.link.clone(),
                first: other.to_owned(),
                second: j.name.clone(),
            });
        }
        children.entry(&j.parent.link).or_default().push(j);
    }
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !has_parent.contains_key(n))
        .collect();
    let root = match roots.as_slice() {
        [root] => *root,
        [] if robot.links.is_empty() => return Err(UrdfError::NoLinks),
        [] => return Err(UrdfError::Loop),
        _ => {
            return Err(UrdfError::SeveralRoots {
                roots: roots.iter().map(|r| (*r).to_owned()).collect(),
            });
        }
    };

    let mut chain = Chain::new(root, links[root])?;
    let mut current = root;
    while let Some(next) = children.get(current) {
        let joint = match next.as_slice() {
            [joint] => *joint,
            [] => break,
            many => {
                return Err(UrdfError::Branches {
                    link: current.to_owned(),
                    joints: many.iter().map(|j| j.name.clone()).collect(),
                });
            }
        };
        current = &joint.child.link;
        chain.add(&robot.name, joint, links[current])?;
    }
    chain.finish(&robot.name)
}

/// The arm being assembled while walking the chain.
struct Chain {
    origins: Vec<Isometry3<f64>>,
    axes: Vec<Unit<Vector3<f64>>>,
    limits: Vec<Limits>,
    links: Vec<Link>,
    /// The current link frame in the last moving link's frame (fixed joints
    /// walked since).
    pending: Isometry3<f64>,
    /// The flange candidate after the last moving joint: (priority, frame).
    flange: Option<(u8, Isometry3<f64>)>,
}

impl Chain {
    fn new(root: &str, link: &urdf_rs::Link) -> Result<Chain, UrdfError> {
        let mut base = Link {
            name: root.to_string(),
            shapes: Vec::new(),
        };
        add_shapes(&mut base.shapes, &Isometry3::identity(), link)?;
        Ok(Chain {
            origins: Vec::new(),
            axes: Vec::new(),
            limits: Vec::new(),
            links: vec![base],
            pending: Isometry3::identity(),
            flange: None,
        })
    }

    fn add(
        &mut self,
        robot: &str,
        joint: &urdf_rs::Joint,
        child: &urdf_rs::Link,
    ) -> Result<(), UrdfError> {
        let origin = pose(&joint.origin, &format!("joint `{}`", joint.name))?;
        match joint.joint_type {
            JointType::Fixed => {
                self.pending *= origin;
                let last = self.links.len() - 1;
                add_shapes(&mut self.links[last].shapes, &self.pending, child)?;
                if self.origins.len() == DOF {
                    let priority = match child.name.as_str() {
                        "tool0" => 2,
                        "flange" => 1,
                        _ => 0,
                    };
                    if self.flange.is_none_or(|(p, _)| priority >= p) {
                        self.flange = Some((priority, self.pending));
                    }
                }
                Ok(())
            }
            JointType::Revolute | JointType::Continuous => {
                if self.origins.len() == DOF {
                    return Err(UrdfError::TooManyJoints {
                        robot: robot.to_owned(),
                        joint: joint.name.clone(),
                    });
                }
                let axis = Vector3::from(joint.axis.xyz.0);
                let axis = Unit::try_new(axis, 1e-9)
                    .filter(|a| a.iter().all(|v| v.is_finite()))
                    .ok_or_else(|| UrdfError::NoAxis {
                        joint: joint.name.clone(),
                    })?;
                self.limits.push(limits(joint)?);
                self.origins.push(self.pending * origin);
                self.axes.push(axis);
                self.pending = Isometry3::identity();
                let mut link = Link {
                    name: child.name.clone(),
                    shapes: Vec::new(),
                };
                add_shapes(&mut link.shapes, &Isometry3::identity(), child)?;
                self.links.push(link);
                Ok(())
            }
            JointType::Prismatic => Err(UrdfError::JointKind {
                joint: joint.name.clone(),
                kind: "prismatic".into(),
            }),
            ref other => Err(UrdfError::JointKind {
                joint: joint.name.clone(),
                kind: format!("{other:?}"),
            }),
        }
    }

    fn finish(self, robot: &str) -> Result<Arm, UrdfError> {
        let found = self.origins.len();
        let (Ok(origins), Ok(axes), Ok(limits)) = (
            <[_; DOF]>::try_from(self.origins),
            <[_; DOF]>::try_from(self.axes),
            <[_; DOF]>::try_from(self.limits),
        ) else {
            return Err(UrdfError::JointCount {
                robot: robot.to_owned(),
                found,
            });
        };
        let flange = self.flange.map_or(self.pending, |(_, f)| f);
        let ur = detect_ur(&origins, &axes);
        Ok(Arm {
            name: robot.to_string(),
            origins,
            axes,
            limits,
            links: self.links,
            flange,
            ur,
        })
    }
}

/// A URDF origin: translation, then the rpy rotation (`Rz(y) Ry(p) Rx(r)`).
fn pose(p: &Pose, what: &str) -> Result<Isometry3<f64>, UrdfError> {
    if p.xyz.iter().chain(p.rpy.iter()).any(|v| !v.is_finite()) {
        return Err(UrdfError::Origin {
            what: what.to_owned(),
        });
    }
    let [r, pi, y] = p.rpy.0;
    Ok(Isometry3::from_parts(
        Translation3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
        UnitQuaternion::from_euler_angles(r, pi, y),
    ))
}

fn limits(joint: &urdf_rs::Joint) -> Result<Limits, UrdfError> {
    let l = &joint.limit;
    let name = &joint.name;
    let (lower, upper) = if joint.joint_type == JointType::Continuous {
        (-TAU, TAU)
    } else if !(l.lower.is_finite() && l.upper.is_finite() && l.lower < l.upper) {
        return Err(UrdfError::PositionLimits {
            joint: name.clone(),
            lower: l.lower,
            upper: l.upper,
        });
    } else {
        (l.lower, l.upper)
    };
    if !(l.velocity.is_finite() && l.velocity > 0.0) {
        return Err(UrdfError::Velocity {
            joint: name.clone(),
        });
    }
    let positive = |v: f64, default: f64| if v.is_finite() && v > 0.0 { v } else { default };
    Ok(Limits {
        lower,
        upper,
        velocity: l.velocity,
        acceleration: positive(l.acceleration.min(l.deceleration), DEFAULT_ACCELERATION),
        jerk: positive(l.jerk, DEFAULT_JERK),
    })
}

/// Appends `link`'s collision shapes, placed by `at` (the link's frame in
/// the frame the shapes are kept in).
fn add_shapes(
    shapes: &mut Vec<Shape>,
    at: &Isometry3<f64>,
    link: &urdf_rs::Link,
) -> Result<(), UrdfError> {
    for c in &link.collision {
        let what = format!("a collision shape of link `{}`", link.name);
        let place = at * pose(&c.origin, &what)?;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let bad = || UrdfError::Size { what: what.clone() };
        let segment = |length: f64, radius: f64| -> Result<Shape, UrdfError> {
            if !positive(length) || !positive(radius) {
                return Err(bad());
            }
            Ok(Shape::Capsule {
                a: place * Point3::new(0.0, 0.0, -length / 2.0),
                b: place * Point3::new(0.0, 0.0, length / 2.0),
                radius,
            })
        };
        match &c.geometry {
            Geometry::Cylinder { radius, length } | Geometry::Capsule { radius, length } => {
                shapes.push(segment(*length, *radius)?);
            }
            Geometry::Sphere { radius } => {
                if !positive(*radius) {
                    return Err(bad());
                }
                let centre = place * Point3::origin();
                shapes.push(Shape::Capsule {
                    a: centre,
                    b: centre,
                    radius: *radius,
                });
            }
            Geometry::Box { size } => {
                if !size.iter().all(|v| positive(*v)) {
                    return Err(bad());
                }
                shapes.push(Shape::Cuboid {
                    pose: place,
                    half: Vector3::from(size.0) / 2.0,
                });
            }
            Geometry::Mesh { .. } => {}
        }
    }
    Ok(())
}

/// The UR geometry, when the joint origins are the DH encoding
/// `Tx(a_{i-1}) Rx(alpha_{i-1}) Tz(d_i)` of a UR arm (alpha = π/2, 0, 0, π/2,
/// -π/2; a1 = d2 = d3 = a4 = a5 = 0) with z axes, to within [`UR_TOLERANCE`].
fn detect_ur(
    origins: &[Isometry3<f64>; DOF],
    axes: &[Unit<Vector3<f64>>; DOF],
) -> Option<UrGeometry> {
    if axes
        .iter()
        .any(|a| (a.into_inner() - Vector3::z()).norm() > UR_TOLERANCE)
    {
        return None;
    }
    let alpha = [0.0, FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2];
    for (o, al) in origins.iter().zip(alpha) {
        if o.rotation
            .angle_to(&UnitQuaternion::from_euler_angles(al, 0.0, 0.0))
            > UR_TOLERANCE
        {
            return None;
        }
    }
    let t = |i: usize| origins[i].translation.vector;
    let (d1, a2, a3, d4) = (t(0).z, t(2).x, t(3).x, t(3).z);
    let (d5, d6) = (-t(4).y, t(5).y);
    let expected = [
        Vector3::new(0.0, 0.0, d1),
        Vector3::zeros(),
        Vector3::new(a2, 0.0, 0.0),
        Vector3::new(a3, 0.0, d4),
        Vector3::new(0.0, -d5, 0.0),
        Vector3::new(0.0, d6, 0.0),
    ];
    let matches = (0..DOF).all(|i| (t(i) - expected[i]).norm() <= UR_TOLERANCE);
    // The closed form divides by a2, a3 and d6.
    let proper = [a2, a3, d6].iter().all(|v| v.abs() > UR_TOLERANCE);
    (matches && proper).then_some(UrGeometry {
        d1,
        a2,
        a3,
        d4,
        d5,
        d6,
    })
}
