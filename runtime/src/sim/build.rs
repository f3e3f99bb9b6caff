//! Building the physics world from a cell: the table, the boxes, the
//! products and the arm's bodies and colliders; and finding the arm part
//! pairs that touch by construction.

use super::convert::{to_pose, to_vector};
use super::{CUP, CUP_RADIUS, CUP_SHORT, FRICTION, Part};
use crate::error::RuntimeError;
use crate::robot::{Arm, DOF, Joints, Shape as LinkShape};
use crate::scene::{BOX_WALL, CellScene, Placement};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::parry::query;
use rapier3d::prelude::*;

/// Largest coordinate or size accepted, metres (f32 keeps ~10 µm there).
const MAX_COORD: f64 = 100.0;
/// Smallest product dimension, metres.
const MIN_SIZE: f64 = 0.001;
/// Range of product masses, kilograms.
const MIN_MASS: f64 = 1e-3;
const MAX_MASS: f64 = 1e3;

/// One collision primitive of the arm: which part it belongs to (0..=6 the
/// links, [`CUP`] the cup), its pose in its link's frame and its shape.
pub(super) struct ArmPart {
    pub part: usize,
    pub local: Isometry3<f64>,
    pub shape: SharedShape,
}

pub(super) fn check(ok: bool, what: impl FnOnce() -> String) -> Result<(), RuntimeError> {
    if ok {
        Ok(())
    } else {
        Err(RuntimeError::Simulation(what()))
    }
}

fn coord(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_COORD
}

fn size(v: f64) -> bool {
    v.is_finite() && v > 0.0 && v <= MAX_COORD
}

/// Checks the inputs of [`super::Simulator::new`].
pub(super) fn validate(
    arm: &Arm,
    cell: &CellScene,
    products: &[Placement],
    start: &Joints,
) -> Result<(), RuntimeError> {
    check(arm.links.len() == DOF + 1, || {
        format!(
            "the arm has {} links, expected {}",
            arm.links.len(),
            DOF + 1
        )
    })?;
    check(cell.base.iter().all(|v| coord(*v)), || {
        format!("invalid robot base {:?}", cell.base)
    })?;
    check(
        cell.suction.is_finite() && (0.0..=1.0).contains(&cell.suction),
        || format!("invalid suction cup length {}", cell.suction),
    )?;
    for (a, b) in cell.pending.0.iter().zip(&cell.pending.1) {
        check(coord(*a) && coord(*b), || {
            format!("invalid pending area {:?}", cell.pending)
        })?;
    }
    for b in &cell.boxes {
        check(b.centre.iter().all(|v| coord(*v)), || {
            format!("box {}: invalid centre", b.name)
        })?;
        check(
            b.size.iter().all(|v| size(*v))
                && b.size[0] > 2.0 * BOX_WALL
                && b.size[1] > 2.0 * BOX_WALL,
            || format!("box {}: invalid size {:?}", b.name, b.size),
        )?;
    }
    for p in products {
        let name = &p.product.name;
        check(p.centre.iter().all(|v| coord(*v)), || {
            format!("product {name}: invalid centre {:?}", p.centre)
        })?;
        check(
            p.product.size.iter().all(|v| size(*v) && *v >= MIN_SIZE),
            || format!("product {name}: invalid size {:?}", p.product.size),
        )?;
        check((MIN_MASS..=MAX_MASS).contains(&p.product.mass), || {
            format!("product {name}: invalid mass {} kg", p.product.mass)
        })?;
    }
    check(
        start.iter().all(|v| v.is_finite()) && arm.within_limits(start),
        || format!("start joints {start:?} are invalid or outside the limits"),
    )?;
    let shapes_ok = arm.links.iter().flat_map(|l| &l.shapes).all(|s| match s {
        LinkShape::Capsule { a, b, radius } => {
            a.coords.iter().chain(b.coords.iter()).all(|v| coord(*v)) && size(*radius)
        }
        LinkShape::Cuboid { pose, half } => finite_pose(pose) && half.iter().all(|v| size(*v)),
    });
    check(shapes_ok, || {
        "the arm has an invalid collision shape".into()
    })?;
    let base = Isometry3::translation(cell.base[0], cell.base[1], cell.base[2]);
    let poses_ok = arm.link_poses(&base, start).iter().all(finite_pose) && finite_pose(&arm.flange);
    check(poses_ok, || {
        "the arm's kinematics give non-finite poses".into()
    })
}

fn finite_pose(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|v| coord(*v))
        && pose.rotation.coords.iter().all(|v| v.is_finite())
}

/// The table: a 0.1 m thick slab whose top is z = 0, centred under
/// everything the cell holds, at least 4 m × 4 m.
pub(super) fn add_table(world: &mut PhysicsWorld, cell: &CellScene) {
    let mut lo = [cell.base[0], cell.base[1]];
    let mut hi = lo;
    let mut grow = |x: f64, y: f64| {
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    };
    grow(cell.pending.0[0], cell.pending.0[1]);
    grow(cell.pending.1[0], cell.pending.1[1]);
    for b in &cell.boxes {
        grow(b.centre[0] - b.size[0] / 2.0, b.centre[1] - b.size[1] / 2.0);
        grow(b.centre[0] + b.size[0] / 2.0, b.centre[1] + b.size[1] / 2.0);
    }
    let half = |k: usize| ((hi[k] - lo[k]) / 2.0 + 0.5).max(2.0);
    let centre = Vector3::new((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, -0.05);
    let body = world.insert_body(RigidBodyBuilder::fixed().translation(to_vector(&centre)));
    world.insert_collider(
        ColliderBuilder::cuboid(half(0) as f32, half(1) as f32, 0.05)
            .friction(FRICTION)
            .restitution(0.0)
            .user_data(Part::Table.encode()),
        Some(body),
    );
}

/// Each box: a fixed body at its footprint's centre with a floor of
/// thickness [`BOX_WALL`] just below z = 0 (its top coincides with the
/// table top: the specification puts the floor at table height) and four
/// walls of thickness [`BOX_WALL`] inside the outside footprint, from z = 0
/// to the box height.
pub(super) fn add_boxes(world: &mut PhysicsWorld, cell: &CellScene) {
    for (k, b) in cell.boxes.iter().enumerate() {
        let [w, d, h] = b.size;
        let t = BOX_WALL / 2.0;
        let centre = Vector3::new(b.centre[0], b.centre[1], 0.0);
        let body = world.insert_body(RigidBodyBuilder::fixed().translation(to_vector(&centre)));
        let parts = [
            ([0.0, 0.0, -t], [w / 2.0, d / 2.0, t]),
            ([-w / 2.0 + t, 0.0, h / 2.0], [t, d / 2.0, h / 2.0]),
            ([w / 2.0 - t, 0.0, h / 2.0], [t, d / 2.0, h / 2.0]),
            (
                [0.0, -d / 2.0 + t, h / 2.0],
                [w / 2.0 - BOX_WALL, t, h / 2.0],
            ),
            (
                [0.0, d / 2.0 - t, h / 2.0],
                [w / 2.0 - BOX_WALL, t, h / 2.0],
            ),
        ];
        for (at, half) in parts {
            world.insert_collider(
                ColliderBuilder::cuboid(half[0] as f32, half[1] as f32, half[2] as f32)
                    .translation(to_vector(&Vector3::from(at)))
                    .friction(FRICTION)
                    .restitution(0.0)
                    .user_data(Part::Box(k).encode()),
                Some(body),
            );
        }
    }
}

/// The products: dynamic cuboids at rest at their placements.
pub(super) fn add_products(
    world: &mut PhysicsWorld,
    products: &[Placement],
) -> Vec<RigidBodyHandle> {
    products
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let [w, d, h] = p.product.size;
            let body = world.insert_body(
                RigidBodyBuilder::dynamic().translation(to_vector(&Vector3::from(p.centre))),
            );
            world.insert_collider(
                ColliderBuilder::cuboid((w / 2.0) as f32, (d / 2.0) as f32, (h / 2.0) as f32)
                    .mass(p.product.mass as f32)
                    .friction(FRICTION)
                    .restitution(0.0)
                    .user_data(Part::Product(k).encode()),
                Some(body),
            );
            body
        })
        .collect()
}

/// The arm's collision primitives: every link's shapes, and the cup (a
/// cylinder of radius [`CUP_RADIUS`] from the flange down the flange's z
/// axis, stopping [`CUP_SHORT`] above the tool tip; none when the cup is
/// shorter than that).
pub(super) fn arm_parts(arm: &Arm, suction: f64) -> Vec<ArmPart> {
    let mut parts = Vec::new();
    for (i, link) in arm.links.iter().enumerate() {
        for s in &link.shapes {
            parts.push(match s {
                LinkShape::Capsule { a, b, radius } => ArmPart {
                    part: i,
                    local: Isometry3::identity(),
                    shape: SharedShape::capsule(
                        to_vector(&a.coords),
                        to_vector(&b.coords),
                        *radius as f32,
                    ),
                },
                LinkShape::Cuboid { pose, half } => ArmPart {
                    part: i,
                    local: *pose,
                    shape: SharedShape::cuboid(half.x as f32, half.y as f32, half.z as f32),
                },
            });
        }
    }
    let length = suction - CUP_SHORT;
    if length > 1e-3 {
        // A rapier cylinder's axis is its local y: turn it onto the flange z.
        let local = arm.flange
            * Translation3::new(0.0, 0.0, length / 2.0)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
        parts.push(ArmPart {
            part: CUP,
            local,
            shape: SharedShape::cylinder((length / 2.0) as f32, CUP_RADIUS as f32),
        });
    }
    parts
}

/// The arm's bodies (a fixed body for the base link, a kinematic one for
/// each moving link) with their colliders, at joints `q`. The arm's
/// colliders also detect contacts with fixed and kinematic bodies (for
/// reporting only: those pairs exert no force).
pub(super) fn add_arm(
    world: &mut PhysicsWorld,
    arm: &Arm,
    base: &Isometry3<f64>,
    q: &Joints,
    parts: &[ArmPart],
) -> Vec<RigidBodyHandle> {
    let poses = arm.link_poses(base, q);
    let bodies: Vec<RigidBodyHandle> = poses
        .iter()
        .enumerate()
        .map(|(i, pose)| {
            let builder = if i == 0 {
                RigidBodyBuilder::fixed()
            } else {
                RigidBodyBuilder::kinematic_position_based()
            };
            world.insert_body(builder.pose(to_pose(pose)))
        })
        .collect();
    let types = ActiveCollisionTypes::default()
        | ActiveCollisionTypes::KINEMATIC_KINEMATIC
        | ActiveCollisionTypes::KINEMATIC_FIXED;
    for p in parts {
        let link = p.part.min(DOF);
        world.insert_collider(
            ColliderBuilder::new(p.shape.clone())
                .position(to_pose(&p.local))
                .friction(if p.part == CUP { FRICTION } else { 0.5 })
                .restitution(0.0)
                .active_collision_types(types)
                .user_data(Part::Arm(p.part).encode()),
            Some(bodies[link]),
        );
    }
    bodies
}

/// Arm part pairs that are not adjacent but touch by construction: in
/// contact at the zero pose, or in at least 90% of 256 seeded random
/// configurations (the same rule as the planner's collision checker).
/// Sorted `(low, high)` part indices.
pub(super) fn neighbours(arm: &Arm, parts: &[ArmPart]) -> Vec<(usize, usize)> {
    let base = Isometry3::identity();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let samples = 256usize;
    let n = CUP + 1;
    let mut counts = vec![0usize; n * n];
    let mut allowed = Vec::new();
    for k in 0..=samples {
        let q: Joints = if k == 0 {
            [0.0; DOF]
        } else {
            std::array::from_fn(|j| {
                let l = &arm.limits[j];
                let (lo, hi) = (
                    l.lower.max(-std::f64::consts::PI),
                    l.upper.min(std::f64::consts::PI),
                );
                if lo < hi {
                    rng.random_range(lo..=hi)
                } else {
                    lo
                }
            })
        };
        let links = arm.link_poses(&base, &q);
        let poses: Vec<_> = parts
            .iter()
            .map(|p| to_pose(&(links[p.part.min(DOF)] * p.local)))
            .collect();
        let mut hits = Vec::new();
        for (i, a) in parts.iter().enumerate() {
            for (j, b) in parts.iter().enumerate().skip(i + 1) {
                let (la, lb) = (a.part.min(b.part), a.part.max(b.part));
                if super::adjacent(la, lb) {
                    continue;
                }
                let hit = query::intersection_test(
                    &poses[i],
                    a.shape.as_ref(),
                    &poses[j],
                    b.shape.as_ref(),
                )
                .map_or(true, |h| h.intersecting);
                if hit && !hits.contains(&(la, lb)) {
                    hits.push((la, lb));
                }
            }
        }
        for (la, lb) in hits {
            if k == 0 {
                allowed.push((la, lb));
            } else {
                counts[la * n + lb] += 1;
            }
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            if counts[i * n + j] * 10 >= samples * 9 && !allowed.contains(&(i, j)) {
                allowed.push((i, j));
            }
        }
    }
    allowed.sort_unstable();
    allowed
}
