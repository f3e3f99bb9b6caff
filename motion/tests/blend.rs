//! Blended motion: it keeps every limit in the commands a robot receives,
//! stops exactly where told, is never slower than stopping everywhere, and
//! stopping everywhere is what `smooth_path` commands.

use packwright_kinematics::{Arm, DOF, Joints, Limits};
use packwright_motion::blend::{blend, blend_capped, blend_slowed, blend_straight, slowed};
use packwright_motion::smoothing::{CONTROL_PERIOD, smooth_path};
use proptest::prelude::*;

/// The built-in UR10's limits (`kinematics/src/ur10.urdf`).
fn ur10() -> [Limits; DOF] {
    Arm::ur10().limits
}

/// The commands' finite differences, as a drive sees them: by the mean
/// value theorem a difference quotient is a derivative somewhere in its
/// span, so a trajectory within its limits everywhere has quotients within
/// them (up to rounding: 1e-6 relative).
fn check_limits(limits: &[Limits; DOF], start: Joints, samples: &[Joints]) {
    let dt = CONTROL_PERIOD;
    // The start is at rest: pad with it.
    let mut q = vec![start; 3];
    q.extend_from_slice(samples);
    // And the end: the last command is held.
    let last = *samples.last().unwrap();
    q.extend([last; 3]);
    for (j, l) in limits.iter().enumerate() {
        for w in q.windows(4) {
            let v = (w[3][j] - w[2][j]) / dt;
            let a = (w[3][j] - 2.0 * w[2][j] + w[1][j]) / dt.powi(2);
            let jerk = (w[3][j] - 3.0 * w[2][j] + 3.0 * w[1][j] - w[0][j]) / dt.powi(3);
            assert!(l.contains(w[3][j]), "joint {j} at {} out of range", w[3][j]);
            assert!(
                v.abs() <= l.velocity * (1.0 + 1e-6),
                "joint {j} velocity {v}"
            );
            assert!(
                a.abs() <= l.acceleration * (1.0 + 1e-6) + 1e-6,
                "joint {j} acceleration {a}"
            );
            // Positions carry ~1e-16 rad of rounding; a third difference
            // over 2 ms multiplies it by 1.25e8.
            assert!(
                jerk.abs() <= l.jerk * (1.0 + 1e-6) + 1e-5,
                "joint {j} jerk {jerk}"
            );
        }
    }
}

const START: Joints = [0.0, -1.57, 1.2, -1.2, -1.57, 0.0];

#[test]
fn stopping_everywhere_is_what_smooth_path_commands() {
    let limits = ur10();
    let waypoints = [
        [0.4, -1.2, 1.5, -1.8, -1.57, 0.4],
        [1.2, -1.0, 1.0, -1.6, -1.57, 1.2],
        [1.2, -1.3, 1.4, -1.7, -1.57, 1.2],
    ];
    let stopped = blend(limits, START, &waypoints, &[true; 3]).unwrap();
    let smoothed = smooth_path(limits, START, &waypoints).unwrap();
    assert!(stopped.samples.len().abs_diff(smoothed.len()) <= waypoints.len());
    // Both stop at every waypoint, exactly.
    for w in &waypoints {
        assert!(stopped.samples.contains(w));
        assert!(smoothed.contains(w));
    }
    assert!(
        stopped
            .corners
            .iter()
            .all(|c| c.saved == 0.0 && c.miss == 0.0)
    );
}

#[test]
fn passing_through_is_faster_and_within_limits() {
    let limits = ur10();
    // Hover, top face, lift, approach, above the slot, release: the shape
    // of a product's motion.
    let waypoints = [
        [0.3, -1.4, 1.6, -1.8, -1.57, 0.3],
        [0.3, -1.3, 1.7, -1.95, -1.57, 0.3],
        [0.3, -1.4, 1.6, -1.8, -1.57, 0.3],
        [1.0, -1.5, 1.4, -1.5, -1.57, 1.0],
        [1.7, -1.4, 1.5, -1.7, -1.57, 1.7],
        [1.7, -1.3, 1.7, -1.95, -1.57, 1.7],
    ];
    let stops = [false, true, false, false, false, true];
    let stopped = blend(limits, START, &waypoints, &[true; 6]).unwrap();
    let blended = blend(limits, START, &waypoints, &stops).unwrap();
    check_limits(&limits, START, &blended.samples);
    assert!(
        blended.duration() < 0.9 * stopped.duration(),
        "blended {:.3} s, stopped {:.3} s",
        blended.duration(),
        stopped.duration()
    );
    // The stops are commanded exactly, and the last sample is the last
    // waypoint.
    assert!(blended.samples.contains(&waypoints[1]));
    assert_eq!(blended.samples.last(), Some(&waypoints[5]));
    assert_eq!(blended.corners[1].saved, 0.0);
    // Corners passed through are blended where the limits allow (where a
    // joint goes on the same way, the legs' jerk phases cannot overlap),
    // and say how close they pass.
    let passed: Vec<usize> = [0, 2, 3, 4]
        .into_iter()
        .filter(|&k| blended.corners[k].saved > 0.0)
        .collect();
    assert!(!passed.is_empty(), "blended corners: {passed:?}");
    for k in passed {
        let c = &blended.corners[k];
        assert!(c.miss > 0.0 && c.miss < 0.5, "corner {k} miss {}", c.miss);
        assert!(!c.samples.is_empty());
        let middle = (c.samples.start + c.samples.end) / 2;
        assert_eq!(blended.corner_near(middle), Some(k));
    }
}

#[test]
fn no_waypoints_no_samples() {
    let b = blend(ur10(), START, &[], &[]).unwrap();
    assert!(b.samples.is_empty() && b.corners.is_empty());
}

#[test]
fn bad_waypoints_are_errors() {
    let mut far = START;
    far[1] = 10.0;
    assert!(blend(ur10(), START, &[far], &[]).is_err());
    let mut nan = START;
    nan[2] = f64::NAN;
    assert!(blend(ur10(), START, &[START, nan], &[]).is_err());
}

fn joints() -> impl Strategy<Value = Joints> {
    prop::array::uniform6(-2.5f64..2.5)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Over thousands of random waypoint sequences with random stops:
    /// every command keeps the limits, every stop is commanded exactly,
    /// the last command is the last waypoint, and blending never takes
    /// longer than stopping everywhere.
    #[test]
    fn blended_motion_keeps_its_contract(
        waypoints in prop::collection::vec(joints(), 1..7),
        stops in prop::collection::vec(any::<bool>(), 7),
        scale in 0.001f64..1.0,
    ) {
        // Small moves too: scale the sequence towards the start.
        let waypoints: Vec<Joints> = waypoints
            .iter()
            .map(|w| std::array::from_fn(|j| START[j] + scale * (w[j] - START[j])))
            .collect();
        let limits = ur10();
        let blended = blend(limits, START, &waypoints, &stops).unwrap();
        let stopped = blend(limits, START, &waypoints, &[true; 7]).unwrap();
        prop_assert!(!blended.samples.is_empty());
        check_limits(&limits, START, &blended.samples);
        prop_assert_eq!(blended.samples.last(), waypoints.last());
        for (k, w) in waypoints.iter().enumerate().take(waypoints.len() - 1) {
            if stops[k] {
                prop_assert!(blended.samples.contains(w), "stop {} not commanded", k);
                prop_assert_eq!(blended.corners[k].saved, 0.0);
            }
        }
        prop_assert!(blended.samples.len() <= stopped.samples.len());
        // Consecutive commands are never further apart than one cycle at
        // full speed.
        let mut last = START;
        for q in &blended.samples {
            for j in 0..DOF {
                prop_assert!((q[j] - last[j]).abs() <= limits[j].velocity * CONTROL_PERIOD * (1.0 + 1e-6));
            }
            last = *q;
        }
    }
}

#[test]
fn a_slowed_leg_keeps_its_path_at_its_own_speed() {
    // Hover, then down onto a top face (a stop): the descent at a quarter
    // of the speed takes four times as long on the same straight segment,
    // within the slowed limits wherever no transition shapes it (its
    // second half at least, next to the stop), and within the arm's
    // everywhere; the leg before it is unchanged.
    let limits = ur10();
    let hover = [0.4, -1.2, 1.5, -1.8, -1.57, 0.4];
    let top = [0.4, -1.1, 1.6, -2.0, -1.57, 0.4];
    let waypoints = [hover, top];
    let full = blend_capped(limits, START, &waypoints, &[]).expect("blends");
    let slow = blend_slowed(limits, START, &waypoints, &[], &[1.0, 0.25]).expect("blends");
    check_limits(&limits, START, &slow.samples);
    assert_eq!(slow.samples.last(), Some(&top));
    // The descent's own samples, after the transition into it.
    let descent = |b: &packwright_motion::blend::Blended| b.samples.len() - b.at[0] - 1;
    let (f, s) = (descent(&full), descent(&slow));
    assert!(
        s as f64 > 3.0 * f as f64,
        "descent {s} samples slowed against {f}"
    );
    let quarter = slowed(&limits, 0.25);
    let second_half = slow.samples.len() - s / 2;
    // Its velocities and accelerations there (it ends at rest).
    let mut q = slow.samples[second_half..].to_vec();
    q.extend([top; 2]);
    let dt = packwright_motion::smoothing::CONTROL_PERIOD;
    for w in q.windows(3) {
        for (j, l) in quarter.iter().enumerate() {
            let v = (w[2][j] - w[1][j]) / dt;
            let a = (w[2][j] - 2.0 * w[1][j] + w[0][j]) / dt.powi(2);
            assert!(
                v.abs() <= l.velocity * (1.0 + 1e-6),
                "joint {j} velocity {v}"
            );
            assert!(
                a.abs() <= l.acceleration * (1.0 + 1e-6) + 1e-6,
                "joint {j} acceleration {a}"
            );
        }
    }
    // Each sample of the descent's straight part lies on the segment.
    for q in &slow.samples[second_half..] {
        let t = (q[1] - hover[1]) / (top[1] - hover[1]);
        for j in 0..DOF {
            let on = hover[j] + t * (top[j] - hover[j]);
            assert!((q[j] - on).abs() < 1e-9, "joint {j}: {} against {on}", q[j]);
        }
    }
    // Full speed, or a share that is no slowing, is blend_capped.
    for speeds in [&[][..], &[1.0, 1.0], &[0.0, 2.0]] {
        let same = blend_slowed(limits, START, &waypoints, &[], speeds).expect("blends");
        assert_eq!(same, full);
    }
}

/// Where `q` is on the joint segment from `a` to `b`: the share of the
/// way (by the joint moving most) when it lies on it (1e-9 rad), else
/// `None`.
/// How far `q` is along the leg from `a` to `b`: the share of the way of
/// the joint moving most.
fn along(a: &Joints, b: &Joints, q: &Joints) -> f64 {
    let d = (0..DOF)
        .max_by(|&x, &y| (b[x] - a[x]).abs().total_cmp(&(b[y] - a[y]).abs()))
        .unwrap();
    (q[d] - a[d]) / (b[d] - a[d])
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    /// `blend_straight` with random shares per leg and end: the contract
    /// (limits, stops exact, never slower than stopping everywhere), and
    /// next to each stop (the start and the last waypoint too) no
    /// transition shapes the commands (they are the leg's own, on its
    /// straight segment when Ruckig could phase-synchronise it) over at
    /// least the share of its way given for that end (to within the few
    /// commands' margin of a corner's `samples`).
    #[test]
    fn blended_motion_keeps_the_straight_share_it_is_given(
        waypoints in prop::collection::vec(joints(), 1..6),
        stops in prop::collection::vec(any::<bool>(), 6),
        shares in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, any::<bool>()), 6),
        scale in 0.01f64..1.0,
    ) {
        let waypoints: Vec<Joints> = waypoints
            .iter()
            .map(|w| std::array::from_fn(|j| START[j] + scale * (w[j] - START[j])))
            .collect();
        let limits = ur10();
        let n = waypoints.len();
        let straight: Vec<Option<[f64; 2]>> = shares
            .iter()
            .map(|&(a, b, given)| given.then_some([a, b]))
            .collect();
        let caps = packwright_motion::blend::full_caps(n, &stops);
        let blended = blend_straight(limits, START, &waypoints, &caps, &[], &straight).unwrap();
        let stopped = blend(limits, START, &waypoints, &[true; 6]).unwrap();
        check_limits(&limits, START, &blended.samples);
        prop_assert_eq!(blended.samples.last(), waypoints.last());
        prop_assert!(blended.samples.len() <= stopped.samples.len());
        let is_stop = |k: usize| k + 1 == n || stops[k];
        let from = |k: usize| if k == 0 { START } else { waypoints[k - 1] };
        // The least share of each end's way kept straight.
        let wanted = |k: usize, end: usize| match straight[k] {
            Some(s) => s[end],
            None => packwright_motion::blend::MIN_STRAIGHT,
        };
        for (k, &b) in waypoints.iter().enumerate() {
            let a = from(k);
            let delta = (0..DOF).map(|j| (b[j] - a[j]).abs()).fold(0.0, f64::max);
            if delta < 1e-6 {
                continue;
            }
            // One command's progress at most, on this leg.
            let step = (0..DOF)
                .filter(|&j| (b[j] - a[j]).abs() > 0.0)
                .map(|j| limits[j].velocity * CONTROL_PERIOD / (b[j] - a[j]).abs())
                .fold(0.0, f64::max);
            // A corner's samples reach two commands past its transition.
            let step = (3.0 * step).min(1.0) * 1.01 + 1e-9;
            if is_stop(k) {
                // Backwards from the command at the stop.
                let at = blended.at[k];
                let mut reach = 1.0;
                for i in (0..=at).rev() {
                    if blended.shaped(i) || blended.leg_at(i) != k {
                        break;
                    }
                    reach = along(&a, &b, &blended.samples[i]);
                }
                prop_assert!(1.0 - reach >= wanted(k, 1) - step, "leg {} reaches its stop straight over {} of its way, wanted {}", k, 1.0 - reach, wanted(k, 1));
            }
            if k == 0 || is_stop(k - 1) {
                // Forwards from the command at the stop it leaves.
                let at = if k == 0 { 0 } else { blended.at[k - 1] + 1 };
                let mut reach = 0.0;
                for i in at..blended.samples.len() {
                    if blended.shaped(i) || blended.leg_at(i) != k {
                        break;
                    }
                    reach = along(&a, &b, &blended.samples[i]);
                }
                prop_assert!(reach >= wanted(k, 0) - step, "leg {} leaves its stop straight over {} of its way, wanted {}", k, reach, wanted(k, 0));
            }
        }
    }
}
