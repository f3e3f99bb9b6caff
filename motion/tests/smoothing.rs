//! The jerk-limited smoother: it reaches its targets and stops, every
//! commanded 2 ms sample respects the UR10's position, velocity,
//! acceleration and jerk limits, durations are plausible, and bad input is
//! an error rather than a panic.

use std::f64::consts::{PI, TAU};

use packwright_kinematics::{DOF, Joints, Limits};
use packwright_motion::SmoothingError;
use packwright_motion::smoothing::{
    CONTROL_PERIOD, POSITION_TOLERANCE, Smoother, Step, duration_of, smooth_path,
};
use proptest::prelude::*;

const DEG: f64 = PI / 180.0;

/// UR10-like limits: ±360° on every joint; 120°/s on the base and shoulder,
/// 180°/s on the others; 2.5 rad/s² and 15 rad/s³ everywhere.
fn ur10() -> [Limits; DOF] {
    let mut limits = [Limits {
        lower: -TAU,
        upper: TAU,
        velocity: 180.0 * DEG,
        acceleration: 2.5,
        jerk: 15.0,
    }; DOF];
    limits[0].velocity = 120.0 * DEG;
    limits[1].velocity = 120.0 * DEG;
    limits
}

/// Ruckig keeps positions within 1e-8·max(1, |limit|) of a position limit
/// (`position_limit_tolerance` in rsruckig), and the smoother hands it the
/// limits widened by `POSITION_TOLERANCE` (the tolerance of
/// `Arm::within_limits`).
fn position_slack(limit: f64) -> f64 {
    POSITION_TOLERANCE + 1e-8 * limit.abs().max(1.0)
}

/// Velocity and acceleration: Ruckig's profiles meet their limits up to its
/// internal precision (1e-8); 1e-6 leaves room for the sampling arithmetic.
const VA_SLACK: f64 = 1e-6;

/// Jerk is measured as the difference of successive commanded accelerations
/// over one period. Ruckig's acceleration is continuous and piecewise linear
/// in time with slopes bounded by the jerk limit, so that difference quotient
/// is a mean of the jerk over the period and cannot exceed the limit: a move
/// switching jerk sign mid-period only lowers it, and the first sample after
/// rest starts from zero acceleration. What remains is rounding: the
/// accelerations carry errors of ~1e-12 rad/s² from the profile breakpoints,
/// multiplied by 1/CONTROL_PERIOD = 500 (about 1e-13 rad/s³ is observed).
/// 1e-6 rad/s³ (7e-8 of the limit) is far above that and far below anything
/// a real violation would produce (a missed jerk phase is O(jerk)).
const JERK_SLACK: f64 = 1e-6;

/// Drive `smoother` to its target, returning every step; panics (fails the
/// test) past `max_steps`.
fn run_to_done(smoother: &mut Smoother, max_steps: usize) -> Vec<Step> {
    let mut steps = Vec::new();
    loop {
        let step = smoother.step().expect("step");
        steps.push(step);
        if step.done {
            return steps;
        }
        assert!(steps.len() < max_steps, "not done after {max_steps} steps");
    }
}

/// Drive through each waypoint in turn, as `smooth_path` does, keeping the
/// whole state of every step.
fn drive(limits: [Limits; DOF], start: Joints, waypoints: &[Joints]) -> Vec<Step> {
    let mut smoother = Smoother::new(limits, start).expect("new");
    let mut steps = Vec::new();
    for w in waypoints {
        smoother.set_target(*w).expect("set_target");
        steps.extend(run_to_done(&mut smoother, 100_000));
        let last = steps.last().unwrap();
        assert_eq!(last.position, *w);
    }
    steps
}

/// Every sample within position, velocity, acceleration and jerk limits,
/// starting at rest at `start`. Also checks the position and velocity
/// difference quotients (means of velocity and acceleration over a period),
/// which ties the reported velocity and acceleration to the positions.
fn assert_within_limits(limits: &[Limits; DOF], start: Joints, steps: &[Step]) {
    let mut prev = Step {
        position: start,
        velocity: [0.0; DOF],
        acceleration: [0.0; DOF],
        done: true,
    };
    for (k, s) in steps.iter().enumerate() {
        for (j, l) in limits.iter().enumerate() {
            let (p, v, a) = (s.position[j], s.velocity[j], s.acceleration[j]);
            let ctx = || format!("sample {k}, joint {j}: p {p}, v {v}, a {a}");
            assert!(p >= l.lower - position_slack(l.lower), "{}", ctx());
            assert!(p <= l.upper + position_slack(l.upper), "{}", ctx());
            assert!(v.abs() <= l.velocity + VA_SLACK, "velocity: {}", ctx());
            assert!(
                a.abs() <= l.acceleration + VA_SLACK,
                "acceleration: {}",
                ctx()
            );
            let jerk = (a - prev.acceleration[j]) / CONTROL_PERIOD;
            assert!(jerk.abs() <= l.jerk + JERK_SLACK, "jerk {jerk}: {}", ctx());
            let mean_v = (p - prev.position[j]) / CONTROL_PERIOD;
            assert!(
                mean_v.abs() <= l.velocity + VA_SLACK,
                "mean velocity {mean_v}: {}",
                ctx()
            );
            let mean_a = (v - prev.velocity[j]) / CONTROL_PERIOD;
            assert!(
                mean_a.abs() <= l.acceleration + VA_SLACK,
                "mean acceleration {mean_a}: {}",
                ctx()
            );
        }
        prev = *s;
    }
}

/// The slowest joint at full speed, no acceleration phase: a lower bound on
/// the duration of a rest-to-rest move.
fn speed_bound(limits: &[Limits; DOF], from: &Joints, to: &Joints) -> f64 {
    (0..DOF)
        .map(|j| (to[j] - from[j]).abs() / limits[j].velocity)
        .fold(0.0, f64::max)
}

fn max_abs_diff(a: &Joints, b: &Joints) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn is_smoothing_error<T: std::fmt::Debug>(r: Result<T, SmoothingError>) -> bool {
    r.is_err()
}

#[test]
fn a_move_reaches_its_target_exactly_and_stops() {
    let limits = ur10();
    let start = [0.0, -1.57, 1.2, -1.2, -1.57, 0.0];
    let target = [1.3, -0.8, 2.0, -2.5, -1.0, 3.0];
    let mut smoother = Smoother::new(limits, start).unwrap();
    assert_eq!(smoother.state(), (start, [0.0; DOF], [0.0; DOF]));
    smoother.set_target(target).unwrap();
    assert_eq!(smoother.target(), target);

    let steps = run_to_done(&mut smoother, 10_000);
    assert!(
        steps.len() > 100,
        "a 3 rad move cannot take {} cycles",
        steps.len()
    );
    assert!(steps[..steps.len() - 1].iter().all(|s| !s.done));
    let last = steps.last().unwrap();
    assert!(max_abs_diff(&last.position, &target) < 1e-6, "{last:?}");
    assert!(max_abs_diff(&last.velocity, &[0.0; DOF]) < 1e-9, "{last:?}");
    assert!(
        max_abs_diff(&last.acceleration, &[0.0; DOF]) < 1e-9,
        "{last:?}"
    );
    assert_eq!(smoother.state().0, last.position);
    assert_within_limits(&limits, start, &steps);

    // It stays there, done, until the target changes.
    for _ in 0..50 {
        let s = smoother.step().unwrap();
        assert!(s.done);
        assert!(max_abs_diff(&s.position, &target) < 1e-6, "{s:?}");
        assert!(max_abs_diff(&s.velocity, &[0.0; DOF]) < 1e-9, "{s:?}");
    }
}

#[test]
fn a_target_equal_to_the_current_position_is_done_at_once() {
    let start = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
    let mut smoother = Smoother::new(ur10(), start).unwrap();
    let s = smoother.step().unwrap();
    assert!(s.done);
    assert_eq!(s.position, start);
    assert_eq!(smoother_path_len(start, &[start]), 1);
}

fn smoother_path_len(start: Joints, waypoints: &[Joints]) -> usize {
    smooth_path(ur10(), start, waypoints).unwrap().len()
}

#[test]
fn joints_are_time_synchronised() {
    // Without synchronisation the 0.1 rad joint would arrive in ~0.35 s, the
    // 3 rad joint in ~1.9 s. Synchronised, both are mid-way at half time.
    let limits = ur10();
    let start = [0.0; DOF];
    let target = [3.0, 0.0, 0.0, 0.0, 0.0, 0.1];
    let steps = drive(limits, start, &[target]);
    let half = &steps[steps.len() / 2];
    for j in [0, 5] {
        let fraction = half.position[j] / target[j];
        assert!(
            (0.2..0.8).contains(&fraction),
            "joint {j} at {fraction} of its move at half time"
        );
    }
    // The still joints never move.
    assert!(steps.iter().all(|s| s.position[1..5] == [0.0; 4]));
    // Every moving joint arrives at the last sample only.
    let before_last = &steps[steps.len() - 2];
    assert!(before_last.position[0] != 3.0 && before_last.position[5] != 0.1);
}

/// Phase synchronisation: a rest-to-rest move is the straight joint-space
/// segment that the collision checker verified, not a curve near it.
#[test]
fn moves_are_straight_lines_in_joint_space() {
    let start = [0.3, -1.2, 1.0, -0.5, -1.57, 0.2];
    let target = [-1.1, -0.4, 2.0, -1.9, -1.2, 2.9];
    let steps = drive(ur10(), start, &[target]);
    for s in &steps {
        let f0 = (s.position[0] - start[0]) / (target[0] - start[0]);
        for j in 1..DOF {
            let f = (s.position[j] - start[j]) / (target[j] - start[j]);
            assert!((f - f0).abs() < 1e-6, "joint {j} at {f}, joint 0 at {f0}");
        }
    }
}

#[test]
fn targets_at_the_position_limits_are_reachable() {
    let limits = ur10();
    let start = [0.0; DOF];
    let corners = [
        [TAU, -TAU, TAU, -TAU, TAU, -TAU],
        [-TAU, TAU, -TAU, TAU, -TAU, TAU],
        // Within POSITION_TOLERANCE outside counts as inside.
        [TAU + 0.5e-9, 0.0, 0.0, 0.0, 0.0, -TAU - 0.5e-9],
    ];
    let steps = drive(limits, start, &corners);
    assert_within_limits(&limits, start, &steps);
}

#[test]
fn online_retargeting_respects_the_limits() {
    // Heading at full speed for the upper limit, then sent back: the
    // smoother brakes (within the jerk limit) and reverses without crossing
    // the limit.
    let limits = ur10();
    let start = [-6.0, 0.0, -6.0, 0.0, 0.0, 0.0];
    let mut smoother = Smoother::new(limits, start).unwrap();
    smoother.set_target([TAU, 0.0, TAU, 0.0, 0.0, 0.0]).unwrap();
    let mut steps = Vec::new();
    for _ in 0..2800 {
        steps.push(smoother.step().unwrap());
    }
    let (p, v, _) = smoother.state();
    assert!(
        p[2] > 4.5 && v[2] > 2.0,
        "state before the retarget: {p:?} {v:?}"
    );
    let back = [0.0, 1.0, 0.0, -1.0, 0.0, 0.0];
    smoother.set_target(back).unwrap();
    steps.extend(run_to_done(&mut smoother, 10_000));
    assert_eq!(steps.last().unwrap().position, back);
    assert_within_limits(&limits, start, &steps);
}

#[test]
fn smooth_path_stops_at_every_waypoint() {
    let limits = ur10();
    let start = [0.0; DOF];
    let waypoints = [
        [1.0, -1.0, 0.5, 0.0, 0.2, 0.0],
        [1.0, -1.0, 0.5, 0.0, 0.2, 0.0],
        [-0.5, 0.0, 1.5, 1.0, 0.0, 2.0],
    ];
    let path = smooth_path(limits, start, &waypoints).unwrap();
    let steps = drive(limits, start, &waypoints);
    assert_eq!(path, steps.iter().map(|s| s.position).collect::<Vec<_>>());
    for w in &waypoints {
        let k = steps
            .iter()
            .position(|s| s.position == *w)
            .expect("waypoint reached");
        assert!(steps[k].done && steps[k].velocity.iter().all(|v| v.abs() < 1e-9));
    }
    assert!(smooth_path(limits, start, &[]).unwrap().is_empty());
    assert_eq!(duration_of(limits, start, &[]).unwrap(), 0.0);
}

#[test]
fn invalid_targets_are_errors() {
    let limits = ur10();
    let start = [0.0; DOF];
    let mut smoother = Smoother::new(limits, start).unwrap();
    let good = [0.5; DOF];
    smoother.set_target(good).unwrap();
    let mut bad = Vec::new();
    for value in [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        TAU + 1e-3,
        -TAU - 1e-6,
        100.0,
    ] {
        for j in [0, 3, 5] {
            let mut target = good;
            target[j] = value;
            bad.push(target);
        }
    }
    for target in &bad {
        assert!(
            is_smoothing_error(smoother.set_target(*target)),
            "{target:?}"
        );
        assert_eq!(
            smoother.target(),
            good,
            "a refused target must not replace the old one"
        );
        assert!(
            is_smoothing_error(smooth_path(limits, start, &[good, *target])),
            "{target:?}"
        );
        assert!(
            is_smoothing_error(duration_of(limits, start, &[good, *target])),
            "{target:?}"
        );
    }
    // The smoother still works.
    let steps = run_to_done(&mut smoother, 10_000);
    assert_eq!(steps.last().unwrap().position, good);
}

#[test]
fn invalid_limits_and_starts_are_errors() {
    let start = [0.0; DOF];
    for (j, field, value) in [
        (0, "velocity", f64::NAN),
        (1, "velocity", 0.0),
        (2, "acceleration", -1.0),
        (3, "acceleration", f64::INFINITY),
        (4, "jerk", 0.0),
        (5, "jerk", f64::INFINITY),
        (0, "lower", f64::NAN),
        (1, "upper", -7.0),
    ] {
        let mut limits = ur10();
        let l = &mut limits[j];
        match field {
            "velocity" => l.velocity = value,
            "acceleration" => l.acceleration = value,
            "jerk" => l.jerk = value,
            "lower" => l.lower = value,
            _ => l.upper = value,
        }
        assert!(
            is_smoothing_error(Smoother::new(limits, start)),
            "joint {j} {field} {value}"
        );
        assert!(
            is_smoothing_error(smooth_path(limits, start, &[start])),
            "joint {j} {field} {value}"
        );
        assert!(
            is_smoothing_error(duration_of(limits, start, &[start])),
            "joint {j} {field} {value}"
        );
    }
    for bad_start in [[f64::NAN; DOF], [0.0, 0.0, 7.0, 0.0, 0.0, 0.0]] {
        assert!(is_smoothing_error(Smoother::new(ur10(), bad_start)));
    }
    // Continuous joints (infinite position limits) are fine.
    let mut limits = ur10();
    limits[5].lower = f64::NEG_INFINITY;
    limits[5].upper = f64::INFINITY;
    let path = smooth_path(limits, start, &[[0.0, 0.0, 0.0, 0.0, 0.0, 20.0]]).unwrap();
    assert_eq!(path.last().unwrap()[5], 20.0);
}

#[test]
fn reset_stops_at_the_given_position() {
    let limits = ur10();
    let mut smoother = Smoother::new(limits, [0.0; DOF]).unwrap();
    smoother.set_target([2.0; DOF]).unwrap();
    for _ in 0..300 {
        smoother.step().unwrap();
    }
    let (_, v, _) = smoother.state();
    assert!(v.iter().any(|v| v.abs() > 0.1), "moving before the reset");

    let here = [0.3, 0.2, 0.1, 0.0, -0.1, -0.2];
    smoother.reset(here);
    assert_eq!(smoother.state(), (here, [0.0; DOF], [0.0; DOF]));
    assert_eq!(smoother.target(), here);
    let s = smoother.step().unwrap();
    assert!(s.done);
    assert_eq!(s.position, here);

    // A non-finite reset cannot fail, but stepping from it does, until a
    // valid reset.
    smoother.reset([f64::NAN; DOF]);
    assert!(is_smoothing_error(smoother.step()));
    assert!(is_smoothing_error(smoother.step()));
    smoother.reset(here);
    smoother.set_target([0.0; DOF]).unwrap();
    let steps = run_to_done(&mut smoother, 10_000);
    assert_within_limits(&limits, here, &steps);
}

fn joints_within_limits() -> impl Strategy<Value = Joints> {
    prop::array::uniform6(-TAU..=TAU)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn moves_respect_all_limits(start in joints_within_limits(), target in joints_within_limits()) {
        let limits = ur10();
        let steps = drive(limits, start, &[target]);
        assert_within_limits(&limits, start, &steps);
        let last = steps.last().unwrap();
        prop_assert!(max_abs_diff(&last.position, &target) < 1e-6);
    }

    #[test]
    fn paths_respect_all_limits(
        start in joints_within_limits(),
        waypoints in prop::collection::vec(joints_within_limits(), 1..5),
    ) {
        let limits = ur10();
        let steps = drive(limits, start, &waypoints);
        assert_within_limits(&limits, start, &steps);
        let path = smooth_path(limits, start, &waypoints).unwrap();
        prop_assert_eq!(path, steps.iter().map(|s| s.position).collect::<Vec<_>>());
    }

    #[test]
    fn retargeting_mid_move_respects_all_limits(
        start in joints_within_limits(),
        first in joints_within_limits(),
        second in joints_within_limits(),
        after in 1usize..1500,
    ) {
        let limits = ur10();
        let mut smoother = Smoother::new(limits, start).unwrap();
        smoother.set_target(first).unwrap();
        let mut steps = Vec::new();
        for _ in 0..after {
            steps.push(smoother.step().unwrap());
        }
        smoother.set_target(second).unwrap();
        steps.extend(run_to_done(&mut smoother, 100_000));
        assert_within_limits(&limits, start, &steps);
        prop_assert_eq!(steps.last().unwrap().position, second);
    }

    #[test]
    fn durations_are_at_least_the_slowest_joint_at_full_speed(
        start in joints_within_limits(),
        waypoints in prop::collection::vec(joints_within_limits(), 1..5),
    ) {
        let limits = ur10();
        let duration = duration_of(limits, start, &waypoints).unwrap();
        let mut bound = 0.0;
        let mut from = start;
        for w in &waypoints {
            bound += speed_bound(&limits, &from, w);
            from = *w;
        }
        prop_assert!(duration >= bound, "duration {} < {}", duration, bound);
        // And smooth_path's samples span that duration, plus at most one
        // period per segment (each segment's last sample is the first one
        // past its end).
        let span = smooth_path(limits, start, &waypoints).unwrap().len() as f64 * CONTROL_PERIOD;
        prop_assert!(span >= duration - 1e-9, "{} < {}", span, duration);
        prop_assert!(
            span <= duration + waypoints.len() as f64 * CONTROL_PERIOD + 1e-9,
            "{} vs {}", span, duration
        );
    }
}
