//! Inverse kinematics: closed-form round trips, reach, branch choice, the
//! free yaw, singular configurations, and the numeric solver.

use super::*;

#[test]
fn closed_form_ik_round_trips_tool_down_poses() {
    let arm = Arm::ur10();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut solved, mut max_pos, mut max_rot) = (0, 0.0_f64, 0.0_f64);
    const N: usize = 10_000;
    for _ in 0..N {
        let q = tool_down_joints(&arm, &mut rng);
        let flange = arm.flange_pose(&base(), &q);
        close(flange.rotation * Vector3::z(), -Vector3::z(), 1e-9);
        let (tip, yaw) = (arm.tool_tip(&base(), &q, SUCTION), yaw_of(&flange));
        let near = random_joints(&arm, &mut rng);
        let Some(sol) = arm.tool_down_ik(&base(), tip, yaw, SUCTION, &near) else {
            continue;
        };
        solved += 1;
        assert!(arm.within_limits(&sol));
        let got = arm.flange_pose(&base(), &sol);
        max_pos = max_pos.max((arm.tool_tip(&base(), &sol, SUCTION) - tip).norm());
        max_rot = max_rot.max(
            got.rotation
                .angle_to(&tool_down_pose(tip, yaw, SUCTION).rotation),
        );
        // From the sampled joints themselves, IK gives them back.
        let back = arm
            .tool_down_ik(&base(), tip, yaw, SUCTION, &q)
            .expect("reachable");
        assert!(joint_distance(&back, &q) < 1e-14, "{back:?} vs {q:?}");
    }
    eprintln!(
        "closed-form IK: {solved}/{N} solved, max tip error {max_pos:.2e} m, max orientation error {max_rot:.2e} rad"
    );
    assert!(solved as f64 / N as f64 >= 0.99);
    assert!(max_pos < 1e-6 && max_rot < 1e-6);
}

/// Whether the tool-down tip (base at the origin) is reachable, from the
/// geometry alone: the wrist point p5 sits d6 above the flange; joint 2's
/// axis z1 is horizontal, p5 is d4 along it and `t = ±√(|p5_xy|² - d4²)`
/// across it; the wrist-1 point is d5 further across (either way), level
/// with p5; the planar arm must reach it from the shoulder (0, 0, d1).
fn reachable(tip: Point3<f64>, margin: f64) -> bool {
    let p5 = tip.coords + Vector3::z() * (SUCTION + D6);
    let r2 = p5.x * p5.x + p5.y * p5.y - D4 * D4;
    if r2 < 0.0 {
        return false;
    }
    let (lo, hi) = (
        (A2.abs() - A3.abs()).abs() + margin,
        A2.abs() + A3.abs() - margin,
    );
    let across = [
        r2.sqrt() + D5,
        r2.sqrt() - D5,
        -r2.sqrt() + D5,
        -r2.sqrt() - D5,
    ];
    across
        .iter()
        .any(|h| (lo..=hi).contains(&h.hypot(p5.z - D1)))
}

#[test]
fn ik_reaches_every_reachable_point_of_the_work_annulus() {
    let arm = Arm::ur10();
    let id = Isometry3::identity();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (mut reach, mut solved, mut extra) = (0, 0, 0);
    let near = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];
    for _ in 0..10_000 {
        let (r, a) = (rng.random_range(0.3..1.2), rng.random_range(-PI..PI));
        let tip = Point3::new(r * f64::cos(a), r * f64::sin(a), rng.random_range(0.0..0.6));
        let yaw = rng.random_range(-PI..PI);
        let sol = arm.tool_down_ik(&id, tip, yaw, SUCTION, &near);
        if let Some(q) = &sol {
            assert!((arm.tool_tip(&id, q, SUCTION) - tip).norm() < 1e-6);
        }
        if reachable(tip, 1e-4) {
            reach += 1;
            solved += usize::from(sol.is_some());
        } else if sol.is_some() && !reachable(tip, -1e-4) {
            extra += 1;
        }
    }
    eprintln!("annulus: {solved}/{reach} reachable points solved; {extra} solved outside");
    assert!(reach > 5_000, "{reach}");
    assert!(solved as f64 >= 0.99 * reach as f64);
    assert_eq!(extra, 0);
}

#[test]
fn ik_picks_the_branch_nearest_to_near() {
    let arm = Arm::ur10();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut branches_seen = 0;
    for _ in 0..2_000 {
        let q = tool_down_joints(&arm, &mut rng);
        let target = arm.flange_pose(&base(), &q);
        let near = random_joints(&arm, &mut rng);
        let best = arm.pose_ik(&base(), &target, &near).expect("reachable");
        let branches = arm.ur_ik_branches(&base(), &target, &near);
        for b in branches.iter().flatten() {
            branches_seen += 1;
            assert!(joint_distance(&best, &near) <= joint_distance(b, &near) + 1e-12);
            // No other turn of any joint is nearer within the limits.
            for i in 0..DOF {
                for turn in [-TAU, TAU] {
                    let mut other = *b;
                    other[i] += turn;
                    if arm.within_limits(&other) {
                        assert!(joint_distance(b, &near) <= joint_distance(&other, &near));
                    }
                }
            }
        }
        assert!(branches.contains(&Some(best)));
    }
    // Most tool-down targets have all eight branches.
    assert!(branches_seen > 2_000 * 6, "{branches_seen}");
}

/// Every branch's solution is found on that branch: `ur_branch` names
/// the index `ur_ik_branches` gave it, for random tool-down targets.
#[test]
fn each_branch_solution_is_on_its_branch() {
    let arm = Arm::ur10();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut named = 0;
    for _ in 0..500 {
        let q = tool_down_joints(&arm, &mut rng);
        let target = arm.flange_pose(&base(), &q);
        let near = random_joints(&arm, &mut rng);
        for (i, b) in arm
            .ur_ik_branches(&base(), &target, &near)
            .iter()
            .enumerate()
        {
            if let Some(b) = b {
                assert_eq!(arm.ur_branch(&base(), b), Some(i), "{b:?}");
                named += 1;
            }
        }
    }
    assert!(named > 500 * 6, "{named}");
}

#[test]
fn yaw_free_ik_keeps_the_last_joint_still() {
    let arm = Arm::ur10();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..500 {
        let tip = arm.tool_tip(&base(), &tool_down_joints(&arm, &mut rng), SUCTION);
        let near = random_joints(&arm, &mut rng);
        let q = arm
            .yaw_free_tool_down_ik(&base(), tip, SUCTION, &near)
            .expect("reachable");
        assert_eq!(q[5], near[5]);
        let f = arm.flange_pose(&base(), &q);
        assert!((arm.tool_tip(&base(), &q, SUCTION) - tip).norm() < 1e-6);
        close(f.rotation * Vector3::z(), -Vector3::z(), 1e-6);
        for k in 0..16 {
            let yaw = k as f64 * PI / 8.0;
            if let Some(other) = arm.tool_down_ik(&base(), tip, yaw, SUCTION, &near) {
                assert!(joint_distance(&q, &near) <= joint_distance(&other, &near) + 1e-9);
            }
        }
    }
}

#[test]
fn closed_form_ik_handles_singular_configurations() {
    let arm = Arm::ur10();
    let id = Isometry3::identity();
    // Wrist singular (joint 5 at 0 or π: joints 4 and 6 coaxial), elbow
    // stretched, elbow folded, shoulder over the base.
    for q in [
        [0.3, -1.0, 1.2, 0.1, 0.0, 0.5],
        [0.3, -1.0, 1.2, 0.1, PI, 0.5],
        [-0.2, -0.7, 0.0, 0.4, 1.0, -0.3],
        [1.0, -2.0, PI, 0.4, 1.0, -0.3],
        [0.0, -FRAC_PI_2, 0.0, -FRAC_PI_2, 0.0, 0.0],
    ] {
        let target = arm.flange_pose(&id, &q);
        for near in [q, [0.0; DOF], [1.0, -1.0, -1.0, 1.0, 1.0, 1.0]] {
            let sol = arm
                .pose_ik(&id, &target, &near)
                .unwrap_or_else(|| panic!("{q:?} from {near:?}"));
            let got = arm.flange_pose(&id, &sol);
            assert!(
                (got.translation.vector - target.translation.vector).norm() < 1e-9,
                "{q:?}"
            );
            assert!(got.rotation.angle_to(&target.rotation) < 1e-9, "{q:?}");
        }
        let back = arm.pose_ik(&id, &target, &q).unwrap();
        assert!(joint_distance(&back, &q) < 1e-12, "{back:?} vs {q:?}");
    }
}

#[test]
fn a_non_dh_arm_is_solved_numerically() {
    // Wrist 2 moved 1 cm sideways: no longer the UR geometry.
    let arm = from_urdf(&edited(r#"xyz="0 -0.1157 0""#, r#"xyz="0.01 -0.1157 0""#)).unwrap();
    assert!(arm.ur.is_none());
    let ur10 = Arm::ur10();
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let (mut solved, mut max_err) = (0, 0.0_f64);
    for _ in 0..300 {
        // A nearby configuration of the real UR10 as the starting guess, with
        // the elbow well bent: near the stretched or folded elbow, the moved
        // wrist puts the target out of reach of `near`'s branch.
        let q = loop {
            let q = tool_down_joints(&ur10, &mut rng);
            if (0.3..PI - 0.3).contains(&q[2].abs()) {
                break q;
            }
        };
        let tip = ur10.tool_tip(&base(), &q, SUCTION);
        let yaw = yaw_of(&ur10.flange_pose(&base(), &q));
        if let Some(sol) = arm.tool_down_ik(&base(), tip, yaw, SUCTION, &q) {
            solved += 1;
            let f = arm.flange_pose(&base(), &sol);
            max_err = max_err.max((arm.tool_tip(&base(), &sol, SUCTION) - tip).norm());
            max_err = max_err.max(
                f.rotation
                    .angle_to(&tool_down_pose(tip, yaw, SUCTION).rotation),
            );
            assert!(arm.within_limits(&sol));
        }
    }
    eprintln!("numeric IK: {solved}/300, max error {max_err:.2e}");
    assert!(solved >= 290, "{solved}");
    assert!(max_err < 1e-6);

    // On the UR10 itself, the numeric solver converges from nearby (the
    // elbow again well bent).
    for _ in 0..200 {
        let mut q = random_joints(&ur10, &mut rng);
        q[2] = q[2].signum() * q[2].abs().clamp(0.3, PI - 0.3);
        let target = ur10.flange_pose(&base(), &q);
        let mut near = q;
        near.iter_mut()
            .for_each(|v| *v += rng.random_range(-0.2..0.2));
        let sol = ur10
            .numeric_ik(&base(), &target, &near)
            .expect("converges from nearby");
        let got = ur10.flange_pose(&base(), &sol);
        assert!((got.translation.vector - target.translation.vector).norm() < 1e-9);
        assert!(got.rotation.angle_to(&target.rotation) < 1e-9);
    }
}

/// A generic 6-axis arm (shoulder and elbow about y, a roll-pitch-roll
/// wrist, the tool along the last roll axis): not the UR geometry.
const GENERIC_6R: &str = r#"<?xml version="1.0"?>
<robot name="generic6">
  <link name="base_link"/><link name="l1"/><link name="l2"/><link name="l3"/>
  <link name="l4"/><link name="l5"/><link name="l6"/><link name="tool0"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="l1"/><origin xyz="0 0 0.4"/><axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.1 0 0"/><axis xyz="0 1 0"/><limit lower="-1.8" upper="1.8" velocity="2"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.6"/><axis xyz="0 1 0"/><limit lower="-3.0" upper="1.2" velocity="2"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/><origin xyz="0.15 0 0.1"/><axis xyz="1 0 0"/><limit lower="-3.14" upper="3.14" velocity="3"/></joint>
  <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/><origin xyz="0.45 0 0"/><axis xyz="0 1 0"/><limit lower="-2.1" upper="2.1" velocity="3"/></joint>
  <joint name="j6" type="revolute"><parent link="l5"/><child link="l6"/><origin xyz="0.1 0 0"/><axis xyz="1 0 0"/><limit lower="-6.28" upper="6.28" velocity="4"/></joint>
  <joint name="flange" type="fixed"><parent link="l6"/><child link="tool0"/><origin rpy="0 1.5707963267948966 0"/></joint>
</robot>"#;

#[test]
fn a_generic_arm_is_solved_from_a_pose_of_another_convention() {
    // The start pose's search begins at the UR "ready" joints, which on
    // this arm are far from any solution (the elbow beyond its limit): the
    // local descent alone fails there; the spread seeds find the pose.
    let arm = from_urdf(GENERIC_6R).unwrap();
    assert!(arm.ur.is_none());
    let ready = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];
    let origin = Isometry3::identity();
    for tip in [
        Point3::new(0.65, -0.3, 0.35),
        Point3::new(0.5, -0.2, 0.15),
        Point3::new(0.0, 0.6, 0.2),
    ] {
        let q = arm
            .yaw_free_tool_down_ik(&origin, tip, SUCTION, &ready)
            .unwrap_or_else(|| panic!("{tip} reachable"));
        assert!(arm.within_limits(&q));
        assert!((arm.tool_tip(&origin, &q, SUCTION) - tip).norm() < 1e-6);
    }
}
