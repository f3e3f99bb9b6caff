//! Building the physics world from a cell's one collision description
//! (`packwright_kinematics::body`): the fixtures, the products and the
//! arm's bodies and colliders; and checking the inputs first.

use super::Part;
use super::convert::{to_pose, to_vector};
use crate::error::SimError;
use nalgebra::{Isometry3, Vector3};
use packwright_interface::scene::{CellScene, Placement};
use packwright_kinematics::body::{ArmPart, BOX_WALL, CUP, Fixture, Owner};
use packwright_kinematics::{Arm, DOF, Joints, Shape as LinkShape};
use rapier3d::prelude::*;

/// Friction of products, the table, the boxes and the cup.
const FRICTION: f32 = 0.8;

/// Largest coordinate or size accepted, metres (f32 keeps ~10 µm there).
pub const MAX_COORD: f64 = 100.0;
/// Smallest product dimension, metres (`check` refuses less: E025).
pub const MIN_SIZE: f64 = 0.001;
/// Range of product masses, kilograms.
const MIN_MASS: f64 = 1e-3;
const MAX_MASS: f64 = 1e3;

fn check(ok: bool, error: impl FnOnce() -> SimError) -> Result<(), SimError> {
    if ok { Ok(()) } else { Err(error()) }
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
) -> Result<(), SimError> {
    check(arm.links.len() == DOF + 1, || SimError::LinkCount {
        found: arm.links.len(),
    })?;
    check(cell.base.iter().all(|v| coord(*v)), || SimError::Base {
        base: cell.base,
    })?;
    check(
        cell.suction.is_finite() && (0.0..=1.0).contains(&cell.suction),
        || SimError::Suction {
            length: cell.suction,
        },
    )?;
    for (a, b) in cell.pending.0.iter().zip(&cell.pending.1) {
        check(coord(*a) && coord(*b), || SimError::Pending)?;
    }
    for b in &cell.boxes {
        check(b.centre.iter().all(|v| coord(*v)), || SimError::Box {
            name: b.name.clone(),
        })?;
        check(
            b.size.iter().all(|v| size(*v))
                && b.size[0] > 2.0 * BOX_WALL
                && b.size[1] > 2.0 * BOX_WALL,
            || SimError::Box {
                name: b.name.clone(),
            },
        )?;
    }
    for p in products {
        let name = &p.product.name;
        let bad = |field| SimError::Product {
            name: name.clone(),
            field,
        };
        check(p.centre.iter().all(|v| coord(*v)), || bad("centre"))?;
        check(
            p.product.size.iter().all(|v| size(*v) && *v >= MIN_SIZE),
            || bad("size"),
        )?;
        check((MIN_MASS..=MAX_MASS).contains(&p.product.mass), || {
            bad("mass")
        })?;
    }
    check(
        start.iter().all(|v| v.is_finite()) && arm.within_limits(start),
        || SimError::Start { joints: *start },
    )?;
    let shapes_ok = arm.links.iter().flat_map(|l| &l.shapes).all(|s| match s {
        LinkShape::Capsule { a, b, radius } | LinkShape::Cylinder { a, b, radius } => {
            a.coords.iter().chain(b.coords.iter()).all(|v| coord(*v)) && size(*radius)
        }
        LinkShape::Cuboid { pose, half } => finite_pose(pose) && half.iter().all(|v| size(*v)),
    });
    check(shapes_ok, || SimError::ArmShape)?;
    let base = Isometry3::translation(cell.base[0], cell.base[1], cell.base[2]);
    let poses_ok = arm.link_poses(&base, start).iter().all(finite_pose) && finite_pose(&arm.flange);
    check(poses_ok, || SimError::ArmPoses)
}

fn finite_pose(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|v| coord(*v))
        && pose.rotation.coords.iter().all(|v| v.is_finite())
}

/// The fixtures (table, box floors and walls), each a fixed body.
pub(super) fn add_fixtures(world: &mut PhysicsWorld, fixtures: &[Fixture]) {
    for f in fixtures {
        let centre = Vector3::from(f.centre);
        let body = world.insert_body(RigidBodyBuilder::fixed().translation(to_vector(&centre)));
        let part = match f.owner {
            Owner::Table => Part::Table,
            Owner::Box(k) => Part::Box(k),
        };
        world.insert_collider(
            ColliderBuilder::cuboid(f.half[0] as f32, f.half[1] as f32, f.half[2] as f32)
                .friction(FRICTION)
                .restitution(0.0)
                .user_data(part.encode()),
            Some(body),
        );
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
        let link = p.link();
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
