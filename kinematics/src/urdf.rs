//! Reading an [`Arm`] from a URDF description.
//!
//! The arm is the chain from the root link to the link named `tool0` (else
//! `flange`; else the end of the moving joints) through exactly [`DOF`]
//! revolute or continuous joints; fixed joints may sit anywhere along it
//! and are folded away (into the next joint's origin, into the flange, and
//! their links' shapes into the moving link they are bolted to). Side
//! branches hanging off the chain by fixed joints only (ROS descriptions'
//! `base` and `ft_frame`, a bracket) are folded in the same way; a moving
//! joint off the chain is refused. A fixed mount before the base joint
//! (ROS's `base_link` turned half a turn) is kept in [`UrGeometry`] when
//! the rest is the UR geometry.
//!
//! Limits: revolute joints need finite `lower < upper` and a positive
//! `velocity`; continuous joints get ±2π. Acceleration and jerk come from the
//! URDF 1.2 attributes `acceleration` (or `deceleration`, whichever is
//! smaller) and `jerk` of `<limit>` (`<robot version="1.2">`); when absent
//! (or for older versions, which ignore them) they default to
//! [`DEFAULT_ACCELERATION`] and [`DEFAULT_JERK`]; given, they must lie in
//! [`ACCELERATION_RANGE`] and [`JERK_RANGE`], a cell's own bounds.
//!
//! Collision: `<collision>` cylinders and capsules become [`Shape::Capsule`]s
//! over their axis segment (a capsule contains its cylinder and overhangs
//! each flat end by the radius), spheres become capsules of zero length,
//! boxes become [`Shape::Cuboid`]s. A mesh is read through the caller's
//! [`MeshReader`] (scaled by its `scale`) and bounded by the shapes of
//! `mesh.rs`; [`from_urdf`], which reads no files, refuses meshes.

use std::collections::{HashMap, HashSet};
use std::f64::consts::{FRAC_PI_2, TAU};

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use urdf_rs::{Geometry, JointType, Pose};

use super::{Arm, DOF, Limits, Link, Shape, UrGeometry};
use crate::error::UrdfError;
use crate::mesh;

/// Reads a collision mesh: its `filename` as the description writes it,
/// to the file's bytes, or a short reason why not.
pub type MeshReader<'a> = dyn Fn(&str) -> Result<Vec<u8>, String> + 'a;

/// Acceleration limit (rad/s²) of a joint whose description gives none.
pub const DEFAULT_ACCELERATION: f64 = 2.5;
/// Jerk limit (rad/s³) of a joint whose description gives none.
pub const DEFAULT_JERK: f64 = 10.0;
/// How closely joint origins must match the DH encoding to count as an
/// exact UR arm (the built-in UR10, a ROS description as shipped).
const UR_TOLERANCE: f64 = 1e-6;
/// How closely (radians, metres) joint origins must match the DH encoding
/// to count as a UR arm at all: a calibrated description (ROS's
/// `ur_calibration` writes offsets of about a milliradian and a
/// millimetre into every joint origin) is a UR arm whose closed form is
/// a close first guess, polished to the exact pose
/// ([`UrGeometry::exact`] false). A wrist moved a centimetre is another
/// arm.
const UR_CALIBRATED: f64 = 5e-3;

/// Reads a 6-axis arm from URDF text. See the module documentation for what
/// is accepted. A collision mesh is refused: its file cannot be read
/// here ([`from_urdf_with`] reads them).
pub fn from_urdf(text: &str) -> Result<Arm, UrdfError> {
    from_urdf_with(text, &|_| Err("no mesh files are read here".to_owned()))
}

/// [`from_urdf`], reading collision meshes through `meshes` (a mesh
/// `filename` as the description writes it, such as
/// `package://ur_description/meshes/ur10/collision/base.stl`, to its bytes
/// or the reason why not): the caller resolves and reads files, this
/// crate does no IO.
pub fn from_urdf_with(text: &str, meshes: &MeshReader<'_>) -> Result<Arm, UrdfError> {
    let robot = urdf_rs::read_from_string(text).map_err(|e| UrdfError::Parse {
        reason: e.to_string(),
    })?;
    let links: HashMap<&str, &urdf_rs::Link> =
        robot.links.iter().map(|l| (l.name.as_str(), l)).collect();
    if links.len() != robot.links.len() {
        return Err(UrdfError::DuplicateLink);
    }
    let mut children: HashMap<&str, Vec<&urdf_rs::Joint>> = HashMap::new();
    let mut has_parent: HashMap<&str, &urdf_rs::Joint> = HashMap::new();
    for j in &robot.joints {
        for end in [&j.parent.link, &j.child.link] {
            if !links.contains_key(end.as_str()) {
                return Err(UrdfError::UnknownLink {
                    joint: j.name.clone(),
                    link: end.clone(),
                });
            }
        }
        if let Some(other) = has_parent.insert(&j.child.link, j) {
            return Err(UrdfError::TwoParents {
                link: j.child.link.clone(),
                first: other.name.clone(),
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

    let joints_to = |end: &str| path_to(&has_parent, end);
    let path = chain_path(&robot, root, &children, &joints_to)?;
    let on_path: HashSet<&str> = path.iter().map(|j| j.name.as_str()).collect();

    let mut chain = Chain::new(root, links[root], meshes)?;
    chain.fold_side(&robot.name, root, &children, &links, &on_path)?;
    for joint in &path {
        chain.add(&robot.name, joint, links[joint.child.link.as_str()])?;
        chain.fold_side(&robot.name, &joint.child.link, &children, &links, &on_path)?;
    }
    chain.finish(&robot.name)
}

/// Whether a joint moves (anything but `fixed`).
fn moves(joint: &urdf_rs::Joint) -> bool {
    joint.joint_type != JointType::Fixed
}

/// The joints from the root down to link `end`, root first (the tree has
/// one root and every link one parent, checked before).
fn path_to<'a>(
    parent_joint: &HashMap<&str, &'a urdf_rs::Joint>,
    end: &str,
) -> Vec<&'a urdf_rs::Joint> {
    let mut path = Vec::new();
    let mut link = end;
    while let Some(&joint) = parent_joint.get(link) {
        path.push(joint);
        link = &joint.parent.link;
        if path.len() > parent_joint.len() {
            break; // a loop; refused before, kept finite here
        }
    }
    path.reverse();
    path
}

/// The chain the arm is: the joints from the root to its flange. The
/// flange is `tool0` (else `flange`) when every moving joint lies on the
/// way to it; else the end of the moving joints, followed down through
/// fixed joints while they do not branch. Side branches hanging off the
/// chain by fixed joints only (ROS descriptions' `base`, `ft_frame`, a
/// camera bracket) are folded into the link they hang from by
/// [`Chain::fold_side`]; a moving joint off the chain is refused.
fn chain_path<'a>(
    robot: &'a urdf_rs::Robot,
    root: &'a str,
    children: &HashMap<&str, Vec<&'a urdf_rs::Joint>>,
    joints_to: &dyn Fn(&str) -> Vec<&'a urdf_rs::Joint>,
) -> Result<Vec<&'a urdf_rs::Joint>, UrdfError> {
    let moving: Vec<&urdf_rs::Joint> = robot.joints.iter().filter(|j| moves(j)).collect();
    let covers = |path: &[&urdf_rs::Joint]| {
        let names: HashSet<&str> = path.iter().map(|j| j.name.as_str()).collect();
        moving.iter().all(|j| names.contains(j.name.as_str()))
    };
    for named in ["tool0", "flange"] {
        if robot.links.iter().any(|l| l.name == named) {
            let path = joints_to(named);
            if covers(&path) {
                return Ok(path);
            }
        }
    }
    // The deepest moving joint: the one with the most moving joints above.
    let deepest = moving
        .iter()
        .max_by_key(|j| joints_to(&j.child.link).iter().filter(|j| moves(j)).count());
    let mut path = match deepest {
        Some(j) => joints_to(&j.child.link),
        None => Vec::new(),
    };
    if let Some(off) = moving
        .iter()
        .find(|j| !path.iter().any(|p| p.name == j.name))
    {
        // Where the stray joint's way down leaves the chain.
        let stray = joints_to(&off.child.link);
        let shared = path
            .iter()
            .zip(&stray)
            .take_while(|(a, b)| a.name == b.name)
            .count();
        let link = stray
            .get(shared)
            .map_or(String::new(), |j| j.parent.link.clone());
        let joints = children
            .get(link.as_str())
            .map(|js| js.iter().map(|j| j.name.clone()).collect())
            .unwrap_or_default();
        return Err(UrdfError::Branches { link, joints });
    }
    // On through fixed joints while the chain does not branch.
    let mut end = path.last().map_or(root, |j| j.child.link.as_str());
    while let Some([joint]) = children.get(end).map(Vec::as_slice) {
        path.push(joint);
        end = &joint.child.link;
    }
    Ok(path)
}

/// The arm being assembled while walking the chain.
struct Chain<'r> {
    meshes: &'r MeshReader<'r>,
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

impl<'r> Chain<'r> {
    fn new(
        root: &str,
        link: &urdf_rs::Link,
        meshes: &'r MeshReader<'r>,
    ) -> Result<Chain<'r>, UrdfError> {
        let mut base = Link {
            name: root.to_string(),
            shapes: Vec::new(),
        };
        add_shapes(&mut base.shapes, &Isometry3::identity(), link, meshes)?;
        Ok(Chain {
            meshes,
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
                add_shapes(
                    &mut self.links[last].shapes,
                    &self.pending,
                    child,
                    self.meshes,
                )?;
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
                add_shapes(&mut link.shapes, &Isometry3::identity(), child, self.meshes)?;
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

    /// Folds the shapes of the links hanging from chain link `at` by fixed
    /// joints off the chain (and of everything below them, all fixed:
    /// [`chain_path`] refused moving ones) into the moving link `at` is
    /// bolted to, where they are.
    fn fold_side(
        &mut self,
        robot: &str,
        at: &str,
        children: &HashMap<&str, Vec<&urdf_rs::Joint>>,
        links: &HashMap<&str, &urdf_rs::Link>,
        on_path: &HashSet<&str>,
    ) -> Result<(), UrdfError> {
        let mut stack: Vec<(&str, Isometry3<f64>)> = vec![(at, self.pending)];
        let last = self.links.len() - 1;
        let mut walked = 0;
        while let Some((link, frame)) = stack.pop() {
            for joint in children.get(link).into_iter().flatten() {
                if on_path.contains(joint.name.as_str()) {
                    continue;
                }
                walked += 1;
                if moves(joint) || walked > links.len() {
                    return Err(UrdfError::TooManyJoints {
                        robot: robot.to_owned(),
                        joint: joint.name.clone(),
                    });
                }
                let child = &joint.child.link;
                let place = frame * pose(&joint.origin, &format!("joint `{}`", joint.name))?;
                if let Some(l) = links.get(child.as_str()) {
                    add_shapes(&mut self.links[last].shapes, &place, l, self.meshes)?;
                }
                stack.push((child, place));
            }
        }
        Ok(())
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
        // The base joint's origin is where the arm is mounted, not its
        // length.
        let span: f64 = origins[1..]
            .iter()
            .chain([&flange])
            .map(|o| o.translation.vector.norm())
            .sum();
        if span > MAX_SPAN {
            return Err(UrdfError::SpanTooLong {
                robot: robot.to_owned(),
                span,
                max: MAX_SPAN,
            });
        }
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

/// The joint acceleration limits a description may give (rad/s²): the
/// bounds a cell's `acceleration` statement has (`check`'s E029; a test
/// in `pipeline` keeps the two equal).
pub const ACCELERATION_RANGE: (f64, f64) = (0.1, 40.0);
/// The joint jerk limits a description may give (rad/s³), as
/// [`ACCELERATION_RANGE`].
pub const JERK_RANGE: (f64, f64) = (1.0, 2000.0);

/// The longest an arm may be (m), from its base joint to its flange, and
/// the largest a collision shape may be across: the largest industrial
/// arms reach about 4 m, so more is a description in another unit (a CAD
/// export in millimetres made the UR10 1.5 km long, and `check` only said
/// that its start pose was out of reach).
pub const MAX_SPAN: f64 = 10.0;

/// The slowest joint velocity limit accepted (rad/s): slower, a joint
/// takes minutes per motion and the smoother gives up (a URDF with
/// `velocity="0.0001"` passed `check` and `execute` printed the
/// smoother's raw input).
pub const MIN_VELOCITY: f64 = 0.01;

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
    if !(l.velocity.is_finite() && l.velocity >= MIN_VELOCITY) {
        return Err(UrdfError::Velocity {
            joint: name.clone(),
            velocity: l.velocity,
            min: MIN_VELOCITY,
        });
    }
    // Absent (urdf-rs reads infinity: URDF 1.2's "unlimited"), the
    // default; given, within the bounds a cell's own statements have (1e6
    // rad/s² was taken as it was, and the blend of so short a ramp ran
    // slower than the default's; an explicit 0 was taken as absent).
    let given = |v: f64, default: f64, what: &'static str, (lower, upper): (f64, f64), unit| {
        if v == f64::INFINITY {
            Ok(default)
        } else if (lower..=upper).contains(&v) {
            Ok(v)
        } else {
            Err(UrdfError::Dynamics {
                joint: name.clone(),
                what,
                value: v,
                lower,
                upper,
                unit,
            })
        }
    };
    let acceleration = l.acceleration.min(l.deceleration);
    Ok(Limits {
        lower,
        upper,
        velocity: l.velocity,
        acceleration: given(
            acceleration,
            DEFAULT_ACCELERATION,
            "acceleration",
            ACCELERATION_RANGE,
            "rad/s²",
        )?,
        jerk: given(l.jerk, DEFAULT_JERK, "jerk", JERK_RANGE, "rad/s³")?,
    })
}

/// Appends `link`'s collision shapes, placed by `at` (the link's frame in
/// the frame the shapes are kept in).
fn add_shapes(
    shapes: &mut Vec<Shape>,
    at: &Isometry3<f64>,
    link: &urdf_rs::Link,
    meshes: &MeshReader<'_>,
) -> Result<(), UrdfError> {
    for c in &link.collision {
        let what = format!("a collision shape of link `{}`", link.name);
        let place = at * pose(&c.origin, &what)?;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let bad = || UrdfError::Size { what: what.clone() };
        let within = |across: f64| {
            if across > MAX_SPAN {
                Err(UrdfError::ShapeTooLarge {
                    what: what.clone(),
                    across,
                    max: MAX_SPAN,
                })
            } else {
                Ok(())
            }
        };
        let segment = |length: f64, radius: f64| -> Result<Shape, UrdfError> {
            if !positive(length) || !positive(radius) {
                return Err(bad());
            }
            within(length.max(2.0 * radius))?;
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
                within(2.0 * radius)?;
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
                within(size.iter().fold(0.0, |m, v| m.max(*v)))?;
                shapes.push(Shape::Cuboid {
                    pose: place,
                    half: Vector3::from(size.0) / 2.0,
                });
            }
            Geometry::Mesh { filename, scale } => {
                let refused = |reason: String| UrdfError::Mesh {
                    link: link.name.clone(),
                    file: filename.clone(),
                    reason,
                };
                let scale = scale.map_or(Vector3::repeat(1.0), |s| Vector3::from(s.0));
                if !scale.iter().all(|v| positive(*v)) {
                    return Err(bad());
                }
                let bytes = meshes(filename).map_err(refused)?;
                let mut read = mesh::read(filename, &bytes).map_err(refused)?;
                for p in &mut read.points {
                    p.coords.component_mul_assign(&scale);
                }
                let (low, high) = read.points.iter().fold(
                    (
                        Vector3::repeat(f64::INFINITY),
                        Vector3::repeat(f64::NEG_INFINITY),
                    ),
                    |(low, high), p| (low.inf(&p.coords), high.sup(&p.coords)),
                );
                within((high - low).max())?;
                shapes.extend(mesh::bounds(&read, &place));
            }
        }
    }
    Ok(())
}

/// The UR geometry, when the joint origins are the DH encoding
/// `Tx(a_{i-1}) Rx(alpha_{i-1}) Tz(d_i)` of a UR arm (alpha = π/2, 0, 0, π/2,
/// -π/2; a1 = d2 = d3 = a4 = a5 = 0) with z axes, to within [`UR_CALIBRATED`]
/// (exact within [`UR_TOLERANCE`]), after any fixed mount before the base
/// joint (its origin `mount · Tz(d1)`).
fn detect_ur(
    origins: &[Isometry3<f64>; DOF],
    axes: &[Unit<Vector3<f64>>; DOF],
) -> Option<UrGeometry> {
    // The largest deviation from the DH encoding seen, over the checks.
    let mut worst: f64 = 0.0;
    let mut within = |deviation: f64| {
        worst = worst.max(deviation);
        deviation <= UR_CALIBRATED
    };
    if !axes
        .iter()
        .all(|a| within((a.into_inner() - Vector3::z()).norm()))
    {
        return None;
    }
    // The base joint's origin is the mount, then d1 along its own z.
    let first = origins[0];
    let d1 = (first.rotation.inverse() * first.translation.vector).z;
    let mount = Isometry3::from_parts(
        Translation3::from(first.translation.vector - first.rotation * Vector3::new(0.0, 0.0, d1)),
        first.rotation,
    );
    let mut origins = *origins;
    origins[0] = Isometry3::translation(0.0, 0.0, d1);
    let alpha = [0.0, FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2];
    for (o, al) in origins.iter().zip(alpha) {
        if !within(
            o.rotation
                .angle_to(&UnitQuaternion::from_euler_angles(al, 0.0, 0.0)),
        ) {
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
    let matches = (0..DOF).all(|i| within((t(i) - expected[i]).norm()));
    // The closed form divides by a2, a3 and d6.
    let proper = [a2, a3, d6].iter().all(|v| v.abs() > UR_CALIBRATED);
    let x = mount.rotation * Vector3::x();
    let heading = if x.x == 1.0 { 0.0 } else { x.y.atan2(x.x) };
    (matches && proper).then_some(UrGeometry {
        mount,
        heading,
        d1,
        a2,
        a3,
        d4,
        d5,
        d6,
        exact: worst <= UR_TOLERANCE,
    })
}
