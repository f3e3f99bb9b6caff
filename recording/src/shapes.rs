//! The arm's collision bodies as a recording draws them, from the one
//! collision description the planner and the simulator share
//! (`packwright_kinematics::body::arm_parts`, without the planner's
//! padding): per link, capsules and cuboids in the link's frame; the cup
//! on the last link.

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use packwright_kinematics::body::{CUP, arm_parts};
use packwright_kinematics::{Arm, DOF};

/// A capsule as Rerun places one: from `translation`, `length` along the
/// z axis turned by `rotation` (x, y, z, w), with `radius`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    pub translation: [f32; 3],
    pub rotation: [f32; 4],
    pub length: f32,
    pub radius: f32,
}

impl Capsule {
    /// The capsule around the segment `a`–`b`.
    pub fn between(a: Point3<f64>, b: Point3<f64>, radius: f64) -> Capsule {
        let axis = b - a;
        let length = axis.norm();
        let rotation = if length > 0.0 {
            UnitQuaternion::rotation_between(&Vector3::z(), &axis).unwrap_or_else(|| {
                // Straight down: any half turn about a horizontal axis.
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
            })
        } else {
            UnitQuaternion::identity()
        };
        Capsule {
            translation: f32s(&a.coords),
            rotation: xyzw(&rotation),
            length: length as f32,
            radius: radius as f32,
        }
    }
}

/// A box: centre, rotation (x, y, z, w) and half extents.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cuboid {
    pub centre: [f32; 3],
    pub rotation: [f32; 4],
    pub half: [f32; 3],
}

/// The bodies of one link, in its frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LinkBodies {
    pub capsules: Vec<Capsule>,
    pub cuboids: Vec<Cuboid>,
}

/// The arm's bodies: the links (0 the base link, then one per joint) and
/// the cup's capsule in the last link's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmBodies {
    pub links: Vec<LinkBodies>,
    pub cup: Vec<Capsule>,
}

/// The bodies of `arm` with a cup `suction` metres long.
pub fn arm_bodies(arm: &Arm, suction: f64) -> ArmBodies {
    let mut links = vec![LinkBodies::default(); DOF + 1];
    let mut cup = Vec::new();
    for part in arm_parts(arm, suction, 0.0) {
        if let Some(c) = part.shape.as_capsule() {
            let end = |v: [f32; 3]| part.local * Point3::from(v.map(f64::from));
            let (a, b) = (c.segment.a, c.segment.b);
            let capsule =
                Capsule::between(end([a.x, a.y, a.z]), end([b.x, b.y, b.z]), c.radius.into());
            if part.part == CUP {
                cup.push(capsule);
            } else if let Some(link) = links.get_mut(part.link()) {
                link.capsules.push(capsule);
            }
        } else if let Some(c) = part.shape.as_cylinder()
            && let Some(link) = links.get_mut(part.link())
        {
            // A mesh's cylinder (a joint housing), drawn as the capsule
            // between its end faces' centres: Rerun draws capsules.
            let end = |y: f32| part.local * Point3::new(0.0, f64::from(y), 0.0);
            link.capsules.push(Capsule::between(
                end(-c.half_height),
                end(c.half_height),
                c.radius.into(),
            ));
        } else if let Some(c) = part.shape.as_cuboid()
            && let Some(link) = links.get_mut(part.link())
        {
            let h = c.half_extents;
            link.cuboids.push(Cuboid {
                centre: f32s(&part.local.translation.vector),
                rotation: xyzw(&part.local.rotation),
                half: [h.x, h.y, h.z],
            });
        }
    }
    ArmBodies { links, cup }
}

pub(crate) fn f32s(v: &Vector3<f64>) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

pub(crate) fn xyzw(q: &UnitQuaternion<f64>) -> [f32; 4] {
    let q = q.quaternion();
    [q.i as f32, q.j as f32, q.k as f32, q.w as f32]
}

/// A pose as (translation, rotation x, y, z, w).
pub fn placement(pose: &Isometry3<f64>) -> ([f32; 3], [f32; 4]) {
    (f32s(&pose.translation.vector), xyzw(&pose.rotation))
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_kinematics::body::{CUP_RADIUS, CUP_SHORT};

    /// Where a capsule placed in a frame at `pose` ends, as Rerun draws
    /// it: the rotation, then the translation, then the frame's pose.
    fn far_end(pose: &Isometry3<f64>, c: &Capsule) -> Point3<f64> {
        let [x, y, z, w] = c.rotation.map(f64::from);
        let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
        let local = q * Vector3::new(0.0, 0.0, f64::from(c.length))
            + Vector3::from(c.translation.map(f64::from));
        pose * Point3::from(local)
    }

    /// Drawn on the last link's pose, the cup ends above the tool tip by
    /// its radius and its gap, straight along the flange: the link frames
    /// and the capsules' placement agree with the forward kinematics.
    #[test]
    fn the_cup_ends_above_the_tool_tip() {
        let arm = Arm::ur10();
        let suction = 0.09;
        let cup = arm_bodies(&arm, suction).cup[0];
        let base = Isometry3::translation(0.3, -0.2, 0.1);
        for q in [[0.0; DOF], [0.4, -1.2, 1.5, -1.9, -1.57, 0.3]] {
            let links = arm.link_poses(&base, &q);
            let flange = arm.flange_pose(&base, &q);
            let tip = arm.tool_tip(&base, &q, suction);
            let expected = tip - flange * Vector3::z() * (CUP_RADIUS + CUP_SHORT);
            let far = far_end(&links[DOF], &cup);
            assert!((far - expected).norm() < 1e-5, "{far} vs {expected}");
        }
    }

    /// Every UR10 link but the base's first is drawn, the cup is one
    /// capsule, and a capsule's far end is where its segment ends.
    #[test]
    fn the_ur10_has_capsules_on_every_link_and_a_cup() {
        let bodies = arm_bodies(&Arm::ur10(), 0.1);
        assert_eq!(bodies.links.len(), DOF + 1);
        assert!(bodies.links.iter().all(|l| !l.capsules.is_empty()));
        assert_eq!(bodies.cup.len(), 1);
        let c = Capsule::between(Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 0.0, -2.0), 0.1);
        let far = far_end(&Isometry3::identity(), &c);
        assert!((far - Point3::new(0.0, 0.0, -2.0)).norm() < 1e-6, "{far}");
        let c = Capsule::between(Point3::new(1.0, 0.0, 0.0), Point3::new(1.0, 3.0, 0.0), 0.1);
        assert!((c.length - 3.0).abs() < 1e-6);
        assert_eq!(c.translation, [1.0, 0.0, 0.0]);
    }
}
