//! `body::intersects`'s closed-form answer for two capsules is parry's
//! (GJK) answer: on random capsule pairs, on pairs placed near touching,
//! and on the UR10's own parts at random configurations. For a capsule
//! and a cuboid it is the exact one (a reference by search along the
//! segment), which parry's GJK is not always.

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

/// The squared distance from a point to the box of half extents `h` at
/// the origin.
fn point_box_squared(p: [f64; 3], h: [f64; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let out = (p[k].abs() - h[k]).max(0.0);
            out * out
        })
        .sum()
}

/// The reference: the least squared distance along the segment (convex
/// in its parameter) by a ternary search to well under a nanometre.
fn segment_box_by_search(a: [f64; 3], e: [f64; 3], h: [f64; 3]) -> f64 {
    let at = |t: f64| point_box_squared(std::array::from_fn(|k| a[k] + t * (e[k] - a[k])), h);
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..200 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if at(m1) <= at(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    at((lo + hi) / 2.0)
}

#[test]
fn segment_box_distance_matches_the_search() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    for k in 0..20_000 {
        let mut point = || std::array::from_fn(|_| rng.random_range(-0.6..0.6));
        let a: [f64; 3] = point();
        // Some degenerate, some axis-aligned (as a cup pointing down).
        let e = match k % 4 {
            0 => a,
            1 => [a[0], a[1], a[2] + 0.3],
            _ => point(),
        };
        let h = std::array::from_fn(|_| rng.random_range(0.002..0.3));
        let exact = body::segment_box_distance_squared(a, e, h);
        let searched = segment_box_by_search(a, e, h);
        assert!(
            (exact.sqrt() - searched.sqrt()).abs() < 1e-9,
            "{a:?} {e:?} {h:?}: {exact} against {searched}"
        );
    }
}

/// The capsule's answer against a cuboid from the reference distance, in
/// the cuboid's frame from the same f32 poses; `None` within a micrometre
/// of touching, where rounding may decide.
fn capsule_cuboid_reference(
    pc: &parry3d::math::Pose,
    c: &SharedShape,
    pb: &parry3d::math::Pose,
    b: &SharedShape,
) -> Option<bool> {
    let cap = c.as_capsule().expect("a capsule");
    let half = b.as_cuboid().expect("a cuboid").half_extents;
    let local = |v: Vector| {
        let w = pb.inverse_transform_point(pc.transform_point(v));
        [f64::from(w.x), f64::from(w.y), f64::from(w.z)]
    };
    let h = [f64::from(half.x), f64::from(half.y), f64::from(half.z)];
    let d = segment_box_by_search(local(cap.segment.a), local(cap.segment.b), h).sqrt();
    let r = f64::from(cap.radius);
    ((d - r).abs() > 1e-6).then_some(d < r)
}

#[test]
fn capsule_and_cuboid_pairs_get_the_exact_answer() {
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
        let Some(want) = capsule_cuboid_reference(&pc, &c, &pb, &b) else {
            continue;
        };
        assert_eq!(intersects(&pc, &*c, &pb, &*b), want);
        assert_eq!(intersects(&pb, &*b, &pc, &*c), want);
        if want {
            hits += 1;
        } else {
            misses += 1;
        }
    }
    assert!(hits > 2_000 && misses > 2_000, "{hits} / {misses}");
}

#[test]
fn a_cup_pointing_down_near_boxes_gets_the_exact_answer() {
    // A capsule straight down (the cup over a top face) beside small
    // boxes standing on the table: where parry 0.31's GJK answered
    // "intersecting" for some pairs millimetres apart.
    let mut rng = ChaCha8Rng::seed_from_u64(18);
    let (mut hits, mut misses) = (0, 0);
    for _ in 0..20_000 {
        let len = rng.random_range(0.0..0.4_f32);
        let r = rng.random_range(0.01..0.06_f32);
        let c = SharedShape::capsule(Vector::ZERO, Vector::new(0.0, 0.0, len), r);
        let h: [f32; 3] = std::array::from_fn(|_| rng.random_range(0.003..0.1));
        let b = SharedShape::cuboid(h[0], h[1], h[2]);
        let at = [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
        let pb = pose(&Isometry3::translation(at[0], at[1], f64::from(h[2])));
        let tip = Vector3::new(
            at[0] + rng.random_range(-0.1..0.1),
            at[1] + rng.random_range(-0.1..0.1),
            rng.random_range(0.0..0.3) + f64::from(len + r),
        );
        let pc = pose(&Isometry3::new(tip, Vector3::x() * std::f64::consts::PI));
        let Some(want) = capsule_cuboid_reference(&pc, &c, &pb, &b) else {
            continue;
        };
        assert_eq!(intersects(&pc, &*c, &pb, &*b), want);
        if want {
            hits += 1;
        } else {
            misses += 1;
        }
    }
    assert!(hits > 2_000 && misses > 2_000, "{hits} / {misses}");
    // Helper T's cell 6302: a 140 mm cup (padded radius 30 mm) on a 16 mm
    // cube's top face, a 16 mm tall box 18 mm across standing `gap` mm
    // beside it. Parry's GJK said the 14 and 16 mm gaps meet.
    let cup = SharedShape::capsule(Vector::ZERO, Vector::new(0.0, 0.0, 0.115), 0.03);
    let flange = pose(&Isometry3::new(
        Vector3::new(0.6, 0.0, 0.016 + 0.14),
        Vector3::x() * std::f64::consts::PI,
    ));
    let beside = SharedShape::cuboid(0.009, 0.009, 0.008);
    for (gap_mm, meets) in [
        (4.0, true),
        (8.0, true),
        (10.0, false),
        (14.0, false),
        (16.0, false),
        (20.0, false),
    ] {
        let x = 0.6 + 0.008 + gap_mm / 1000.0 + 0.009;
        let pb = pose(&Isometry3::translation(x, 0.0, 0.008));
        assert_eq!(
            intersects(&flange, &*cup, &pb, &*beside),
            meets,
            "{gap_mm} mm"
        );
    }
}

#[test]
fn capsule_and_cuboid_near_touching_get_the_exact_answer() {
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
        if let Some(want) = capsule_cuboid_reference(&pc, &c, &pb, &b) {
            assert_eq!(intersects(&pc, &*c, &pb, &*b), want);
        }
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
