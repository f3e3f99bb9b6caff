//! The arm model: the built-in UR10, URDF reading (`kinematics/urdf.rs`),
//! forward kinematics (here), inverse kinematics (`kinematics/ik.rs`), and
//! that none of it panics.

#[path = "kinematics/ik.rs"]
mod ik;
#[path = "kinematics/urdf.rs"]
mod urdf;

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use packwright_kinematics::{
    Arm, DOF, Joints, Shape, UR10_URDF, from_urdf, from_urdf_with, joint_distance, tool_down_pose,
};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

// The public UR10 DH lengths.
const D1: f64 = 0.1273;
const A2: f64 = -0.612;
const A3: f64 = -0.5723;
const D4: f64 = 0.163941;
const D5: f64 = 0.1157;
const D6: f64 = 0.0922;
const SUCTION: f64 = 0.12;

fn close(a: Vector3<f64>, b: Vector3<f64>, tol: f64) {
    assert!((a - b).norm() < tol, "{a:?} != {b:?}");
}

/// An upright base, moved and turned about z.
fn base() -> Isometry3<f64> {
    Isometry3::new(Vector3::new(0.4, -0.3, 0.75), Vector3::z() * 0.7)
}

fn random_joints(arm: &Arm, rng: &mut ChaCha8Rng) -> Joints {
    std::array::from_fn(|i| rng.random_range(arm.limits[i].lower..arm.limits[i].upper))
}

/// Random joints with the cup pointing down (upright base). From the DH
/// product: the flange z axis is `-sin θ5` times frame 4's x axis (plus
/// `cos θ5` times joint 2's axis, horizontal), and frame 4's x axis is
/// `cos s (cos θ1, sin θ1, 0) + sin s (0, 0, 1)` with `s = θ2 + θ3 + θ4`. So
/// the cup points down when θ5 = σ π/2 and s = σ π/2, σ = ±1.
fn tool_down_joints(arm: &Arm, rng: &mut ChaCha8Rng) -> Joints {
    let mut q = random_joints(arm, rng);
    let sigma = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    q[4] = sigma * FRAC_PI_2;
    let s4 = sigma * FRAC_PI_2 - q[1] - q[2];
    q[3] = s4 - (s4 / TAU).round() * TAU;
    q
}

fn yaw_of(pose: &Isometry3<f64>) -> f64 {
    let x = pose.rotation * Vector3::x();
    x.y.atan2(x.x)
}

/// The UR10 description with one edit.
fn edited(from: &str, to: &str) -> String {
    assert!(UR10_URDF.contains(from), "{from}");
    UR10_URDF.replacen(from, to, 1)
}

#[test]
fn forward_kinematics_matches_hand_computed_poses() {
    let arm = Arm::ur10();
    let id = Isometry3::identity();
    let flange = |q: Joints| arm.flange_pose(&id, &q);

    // q = 0: Tz(d1) Rx(π/2), then Tx(a2 + a3) Tz(d4) moves by Rx(π/2)(a2 + a3,
    // 0, d4) = (a2 + a3, -d4, 0); joint 5's (0, -d5, 0) becomes (0, 0, -d5)
    // and the frame turns to Rx(π); joint 6's (0, d6, 0) becomes (0, -d6, 0)
    // and the frame ends at Rx(π/2): flange z = (0, -1, 0).
    let f = flange([0.0; DOF]);
    close(
        f.translation.vector,
        Vector3::new(A2 + A3, -(D4 + D6), D1 - D5),
        1e-12,
    );
    close(
        f.translation.vector,
        Vector3::new(-1.1843, -0.256141, 0.0116),
        1e-12,
    );
    close(f.rotation * Vector3::z(), -Vector3::y(), 1e-12);

    // Shoulder at -π/2: Rx(π/2) Rz(-π/2) maps x to (0, 0, -1) so the arm
    // (along -x) points up, z to (0, -1, 0) (d4 and d6 along -y), and joint
    // 5's (0, -d5, 0) to (-d5, 0, 0).
    let f = flange([0.0, -FRAC_PI_2, 0.0, 0.0, 0.0, 0.0]);
    close(
        f.translation.vector,
        Vector3::new(-D5, -(D4 + D6), D1 - A2 - A3),
        1e-12,
    );

    // Base at π/2 turns the zero pose: (x, y) -> (-y, x).
    let f = flange([FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0]);
    close(
        f.translation.vector,
        Vector3::new(D4 + D6, A2 + A3, D1 - D5),
        1e-12,
    );

    // A tool-down pose: θ2 + θ3 + θ4 = θ5 = -π/2. The planar arm puts the
    // wrist-1 frame at (a3, -a2, d4) in joint 2's frame, i.e. (a3, -d4, d1 -
    // a2) in the world, then d5 along -x and d6 down.
    let f = flange([0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0]);
    close(
        f.translation.vector,
        Vector3::new(A3 - D5, -D4, D1 - A2 - D6),
        1e-12,
    );
    close(f.rotation * Vector3::z(), -Vector3::z(), 1e-12);
    close(f.rotation * Vector3::x(), Vector3::y(), 1e-12);
}

#[test]
fn link_poses_flange_and_tip_agree() {
    let arm = Arm::ur10();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..100 {
        let q = random_joints(&arm, &mut rng);
        let poses = arm.link_poses(&base(), &q);
        assert_eq!(poses[0], base());
        let flange = arm.flange_pose(&base(), &q);
        assert!((poses[DOF] * arm.flange).translation.vector.relative_eq(
            &flange.translation.vector,
            1e-12,
            1e-12
        ));
        // Moving the base moves everything with it.
        let local = arm.flange_pose(&Isometry3::identity(), &q);
        assert!((base() * local).translation.vector.relative_eq(
            &flange.translation.vector,
            1e-12,
            1e-12
        ));
        let tip = arm.tool_tip(&base(), &q, SUCTION);
        close(
            tip.coords,
            (flange * Point3::new(0.0, 0.0, SUCTION)).coords,
            1e-12,
        );
    }
}

fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -10.0..10.0f64,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => any::<f64>(),
    ]
}

fn check_total(
    arm: &Arm,
    q: Joints,
    near: Joints,
    p: [f64; 6],
    yaw: f64,
    suction: f64,
) -> Result<(), TestCaseError> {
    let base = Isometry3::new(Vector3::new(p[0], p[1], p[2]), Vector3::new(0.0, 0.0, p[3]));
    let tip = Point3::new(p[4], p[5], yaw);
    let _ = arm.link_poses(&base, &q);
    let _ = arm.tool_tip(&base, &q, suction);
    for sol in [
        arm.tool_down_ik(&base, tip, yaw, suction, &near),
        arm.yaw_free_tool_down_ik(&base, tip, suction, &near),
        arm.pose_ik(&base, &arm.flange_pose(&base, &q), &near),
    ]
    .into_iter()
    .flatten()
    {
        prop_assert!(arm.within_limits(&sol) && sol.iter().all(|v| v.is_finite()));
    }
    Ok(())
}

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config(300))]
    #[test]
    fn closed_form_kinematics_is_total(
        q in prop::array::uniform6(any_f64()),
        near in prop::array::uniform6(any_f64()),
        p in prop::array::uniform6(any_f64()),
        yaw in any_f64(),
        suction in any_f64(),
    ) {
        check_total(&Arm::ur10(), q, near, p, yaw, suction)?;
    }
}

proptest! {
    #![proptest_config(config(60))]
    #[test]
    fn numeric_kinematics_is_total(
        q in prop::array::uniform6(any_f64()),
        near in prop::array::uniform6(any_f64()),
        p in prop::array::uniform6(any_f64()),
        yaw in any_f64(),
        suction in any_f64(),
    ) {
        let arm = from_urdf(&edited(r#"xyz="0 -0.1157 0""#, r#"xyz="0.01 -0.1157 0""#)).unwrap();
        check_total(&arm, q, near, p, yaw, suction)?;
    }
}

proptest! {
    #![proptest_config(config(300))]
    /// A configuration turned past its limits by whole turns is brought
    /// back within them, the same pose, and the joints within their limits
    /// are kept.
    #[test]
    fn into_limits_keeps_the_pose(
        seed in any::<u64>(),
        turns in prop::array::uniform6(-2i32..=2),
    ) {
        let arm = Arm::ur10();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let q = random_joints(&arm, &mut rng);
        let near = random_joints(&arm, &mut rng);
        let turned: Joints = std::array::from_fn(|i| q[i] + f64::from(turns[i]) * TAU);
        let back = arm.into_limits(&turned, &near).expect("a whole turn back fits");
        prop_assert!(arm.within_limits(&back));
        for i in 0..DOF {
            if arm.limits[i].contains(turned[i]) {
                prop_assert_eq!(back[i], turned[i]);
            }
        }
        let (a, b) = (arm.flange_pose(&base(), &q), arm.flange_pose(&base(), &back));
        close(a.translation.vector, b.translation.vector, 1e-9);
        prop_assert!(a.rotation.angle_to(&b.rotation) < 1e-9);
    }
}

proptest! {
    #![proptest_config(config(300))]
    /// Along a straight joint segment, the cup tip never moves farther
    /// than `Arm::tip_radii` allows, for any pair of points on it.
    #[test]
    fn tip_radii_bound_the_tip_motion(seed in any::<u64>(), suction in 0.0..0.3f64) {
        let arm = Arm::ur10();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let radii = arm.tip_radii(suction);
        let base = Isometry3::translation(0.1, -0.2, 0.8);
        let a = random_joints(&arm, &mut rng);
        let b = random_joints(&arm, &mut rng);
        let along = |s: f64| -> Joints { std::array::from_fn(|j| a[j] + s * (b[j] - a[j])) };
        let per_share: f64 = (0..DOF).map(|j| radii[j] * (b[j] - a[j]).abs()).sum();
        for k in 0..16 {
            let (s0, s1) = (k as f64 / 16.0, rng.random_range(0.0..1.0));
            let moved = (arm.tool_tip(&base, &along(s1), suction)
                - arm.tool_tip(&base, &along(s0), suction))
            .norm();
            prop_assert!(moved <= per_share * (s1 - s0).abs() + 1e-12,
                "moved {moved} > bound {}", per_share * (s1 - s0).abs());
        }
        // Tight enough to be worth it: a whole turn of the base alone
        // moves the tip across the arm's reach, not many times it.
        prop_assert!(radii[0] < 2.5);
    }
}
