//! `body::intersects`'s closed-form answer for two capsules is parry's
//! (GJK) answer: on random capsule pairs, on pairs placed near touching,
//! and on the UR10's own parts at random configurations.

use nalgebra::{Isometry3, Vector3};
use packwright_kinematics::body::{
    self, DECIDED_MARGIN, PADDING, exact_intersects, intersects, pose, segments_distance_squared,
};
use packwright_kinematics::{Arm, Joints};
use parry3d::math::Vector;
use parry3d::shape::SharedShape;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_pose(rng: &mut ChaCha8Rng, spread: f64) -> Isometry3<f64> {
    Isometry3::new(
        Vector3::new(
            rng.random_range(-spread..spread),
            rng.random_range(-spread..spread),
            rng.random_range(-spread..spread),
        ),
        Vector3::new(
            rng.random_range(-3.2..3.2),
            rng.random_range(-3.2..3.2),
            rng.random_range(-3.2..3.2),
        ),
    )
}

fn random_capsule(rng: &mut ChaCha8Rng) -> SharedShape {
    let end = |rng: &mut ChaCha8Rng| {
        Vector::new(
            rng.random_range(-0.4..0.4_f32),
            rng.random_range(-0.4..0.4_f32),
            rng.random_range(-0.4..0.4_f32),
        )
    };
    let a = end(rng);
    // One in ten is a ball (a degenerate segment).
    let b = if rng.random_range(0..10) == 0 {
        a
    } else {
        end(rng)
    };
    SharedShape::capsule(a, b, rng.random_range(0.01..0.1_f32))
}

fn random_cuboid(rng: &mut ChaCha8Rng) -> SharedShape {
    SharedShape::cuboid(
        rng.random_range(0.002..0.5_f32),
        rng.random_range(0.002..0.5_f32),
        rng.random_range(0.002..0.5_f32),
    )
}

#[test]
fn random_capsule_pairs_get_parrys_answer() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (mut hits, mut misses) = (0, 0);
    for _ in 0..20_000 {
        let (s1, s2) = (random_capsule(&mut rng), random_capsule(&mut rng));
        let (p1, p2) = (
            pose(&random_pose(&mut rng, 0.2)),
            pose(&random_pose(&mut rng, 0.2)),
        );
        let fast = intersects(&p1, &*s1, &p2, &*s2);
        assert_eq!(fast, exact_intersects(&p1, &*s1, &p2, &*s2));
        if fast {
            hits += 1;
        } else {
            misses += 1;
        }
    }
    assert!(hits > 2_000 && misses > 2_000, "{hits} / {misses}");
}

#[test]
fn capsule_and_cuboid_pairs_get_parrys_answer() {
    // Either order; cuboids from wall-thin to half a metre, some of them
    // axis-aligned as the fixtures are.
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let (mut hits, mut misses) = (0, 0);
    for k in 0..20_000 {
        let (c, b) = (random_capsule(&mut rng), random_cuboid(&mut rng));
        let pc = pose(&random_pose(&mut rng, 0.4));
        let pb = if k % 3 == 0 {
            pose(&Isometry3::translation(
                rng.random_range(-0.4..0.4),
                rng.random_range(-0.4..0.4),
                rng.random_range(-0.4..0.4),
            ))
        } else {
            pose(&random_pose(&mut rng, 0.4))
        };
        let fast = intersects(&pc, &*c, &pb, &*b);
        assert_eq!(fast, exact_intersects(&pc, &*c, &pb, &*b));
        assert_eq!(
            intersects(&pb, &*b, &pc, &*c),
            exact_intersects(&pb, &*b, &pc, &*c)
        );
        if fast {
            hits += 1;
        } else {
            misses += 1;
        }
    }
    assert!(hits > 2_000 && misses > 2_000, "{hits} / {misses}");
}

#[test]
fn capsule_and_cuboid_near_touching_get_parrys_answer() {
    // The capsule pushed along a cuboid axis until its segment's nearest
    // end is its radius, give or take a few margins, from that face.
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    for _ in 0..5_000 {
        let (c, b) = (random_capsule(&mut rng), random_cuboid(&mut rng));
        let cap = c.as_capsule().expect("a capsule");
        let half = b.as_cuboid().expect("a cuboid").half_extents;
        let pb = pose(&random_pose(&mut rng, 0.3));
        let mut pc = pose(&random_pose(&mut rng, 0.3));
        let k = rng.random_range(0..3);
        let axis = pb.rotation * Vector::AXES[k];
        let ends = [
            pb.inverse_transform_point(pc.transform_point(cap.segment.a))[k],
            pb.inverse_transform_point(pc.transform_point(cap.segment.b))[k],
        ];
        let gap = rng.random_range(-5.0..5.0_f32) * DECIDED_MARGIN as f32;
        let shift = half[k] + cap.radius + gap - ends[0].min(ends[1]);
        pc.translation += axis * shift;
        assert_eq!(
            intersects(&pc, &*c, &pb, &*b),
            exact_intersects(&pc, &*c, &pb, &*b)
        );
    }
}

#[test]
fn capsules_near_touching_get_parrys_answer() {
    // The second capsule moved along the direction joining the closest
    // points until the gap is a given few margins from touching.
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..5_000 {
        let (s1, s2) = (random_capsule(&mut rng), random_capsule(&mut rng));
        let (c1, c2) = (
            s1.as_capsule().expect("a capsule"),
            s2.as_capsule().expect("a capsule"),
        );
        let p1 = pose(&random_pose(&mut rng, 0.3));
        let p2 = pose(&random_pose(&mut rng, 0.3));
        let w = |p: &parry3d::math::Pose, v: Vector| {
            let x = p.transform_point(v);
            [f64::from(x.x), f64::from(x.y), f64::from(x.z)]
        };
        let d = segments_distance_squared(
            w(&p1, c1.segment.a),
            w(&p1, c1.segment.b),
            w(&p2, c2.segment.a),
            w(&p2, c2.segment.b),
        )
        .sqrt();
        let reach = f64::from(c1.radius + c2.radius);
        // A shift along the line between the segments' centres changes
        // the gap by at most its length: a gap in [-5, 5] margins.
        let gap = rng.random_range(-5.0..5.0) * DECIDED_MARGIN;
        let centre =
            |p: &parry3d::math::Pose, a: Vector, b: Vector| p.transform_point((a + b) / 2.0);
        let dir = (centre(&p2, c2.segment.a, c2.segment.b)
            - centre(&p1, c1.segment.a, c1.segment.b))
        .normalize_or_zero();
        let mut moved = p2;
        moved.translation += dir * ((reach + gap - d) as f32);
        assert_eq!(
            intersects(&p1, &*s1, &moved, &*s2),
            exact_intersects(&p1, &*s1, &moved, &*s2)
        );
    }
}

#[test]
fn segment_distance_matches_sampling() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let mut point = || {
        [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ]
    };
    for k in 0..2_000 {
        let (p1, q1, p2) = (point(), point(), point());
        // Some parallel and some degenerate second segments.
        let q2 = match k % 4 {
            0 => p2,
            1 => [
                p2[0] + q1[0] - p1[0],
                p2[1] + q1[1] - p1[1],
                p2[2] + q1[2] - p1[2],
            ],
            _ => point(),
        };
        let exact = segments_distance_squared(p1, q1, p2, q2).sqrt();
        let at = |a: [f64; 3], b: [f64; 3], s: f64| {
            [
                a[0] + (b[0] - a[0]) * s,
                a[1] + (b[1] - a[1]) * s,
                a[2] + (b[2] - a[2]) * s,
            ]
        };
        let n = 200;
        let mut sampled = f64::INFINITY;
        for i in 0..=n {
            let x = at(p1, q1, i as f64 / n as f64);
            for j in 0..=n {
                let y = at(p2, q2, j as f64 / n as f64);
                let d =
                    ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt();
                sampled = sampled.min(d);
            }
        }
        // Never above the sampled minimum, and within the sampling step.
        assert!(exact <= sampled + 1e-12, "{exact} > {sampled}");
        assert!(sampled - exact < 0.03, "{exact} vs {sampled}");
    }
}

#[test]
fn the_ur10_parts_get_parrys_answer_at_random_configurations() {
    let arm = Arm::ur10();
    let parts = body::arm_parts(&arm, 0.1, PADDING);
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let mut colliding = 0;
    for _ in 0..3_000 {
        let q: Joints = std::array::from_fn(|j| {
            let l = &arm.limits[j];
            rng.random_range(l.lower.max(-3.2)..=l.upper.min(3.2))
        });
        let links = arm.link_poses(&Isometry3::identity(), &q);
        let poses: Vec<_> = parts
            .iter()
            .map(|p| pose(&(links[p.link()] * p.local)))
            .collect();
        for i in 0..parts.len() {
            for j in i + 1..parts.len() {
                let fast = intersects(&poses[i], &*parts[i].shape, &poses[j], &*parts[j].shape);
                let exact =
                    exact_intersects(&poses[i], &*parts[i].shape, &poses[j], &*parts[j].shape);
                assert_eq!(fast, exact, "parts {i} and {j} at {q:?}");
                colliding += usize::from(fast);
            }
        }
    }
    assert!(colliding > 1_000, "{colliding}");
}

fn random_cylinder(rng: &mut ChaCha8Rng) -> SharedShape {
    let (half, radius) = (
        rng.random_range(0.005..0.3_f32),
        rng.random_range(0.01..0.1_f32),
    );
    if rng.random_bool(0.5) {
        SharedShape::cylinder(half, radius)
    } else {
        SharedShape::round_cylinder(half, radius, rng.random_range(0.001..0.02_f32))
    }
}

#[test]
fn pairs_with_a_cylinder_get_parrys_answer() {
    // A collision mesh's cylinder (plain, or grown by the padding) against
    // capsules, cuboids and cylinders, in either order: the capsule round
    // it only ever says "apart" where parry does.
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let (mut hits, mut misses) = (0, 0);
    for k in 0..20_000 {
        let cylinder = random_cylinder(&mut rng);
        let other = match k % 3 {
            0 => random_capsule(&mut rng),
            1 => random_cuboid(&mut rng),
            _ => random_cylinder(&mut rng),
        };
        let (p1, p2) = (
            pose(&random_pose(&mut rng, 0.25)),
            pose(&random_pose(&mut rng, 0.25)),
        );
        let (s1, s2) = if k % 2 == 0 {
            (&cylinder, &other)
        } else {
            (&other, &cylinder)
        };
        let fast = intersects(&p1, &**s1, &p2, &**s2);
        assert_eq!(fast, exact_intersects(&p1, &**s1, &p2, &**s2), "case {k}");
        if fast {
            hits += 1;
        } else {
            misses += 1;
        }
    }
    assert!(hits > 2_000 && misses > 2_000, "{hits} / {misses}");
}
