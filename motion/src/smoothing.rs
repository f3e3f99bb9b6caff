//! Jerk-limited joint smoothing at the UR control rate.
//!
//! Planners produce joint-space waypoints; a robot wants one position
//! command every [`CONTROL_PERIOD`] (2 ms, 500 Hz) that it can follow without
//! violating its drives' limits. [`Smoother`] turns the former into the latter
//! with [Ruckig](https://ruckig.com) (the pure-Rust port `rsruckig`), online:
//! one call to [`Smoother::step`] per control cycle, and the target may change
//! at any cycle ([`Smoother::set_target`]), the new motion starting from the
//! current position, velocity and acceleration.
//!
//! # Contract
//!
//! - **What is limited**, per joint, from its [`Limits`]: `|velocity| ≤
//!   velocity`, `|acceleration| ≤ acceleration`, `|jerk| ≤ jerk` (the
//!   trajectory is piecewise cubic: the jerk is piecewise constant, the
//!   acceleration continuous), and the position stays in `[lower, upper]`.
//!   These hold for the continuous trajectory up to Ruckig's numerical
//!   tolerances (positions 1e-8·max(1, |limit|), velocities 1e-8); the
//!   commanded samples are points on it.
//! - **Targets** are joint positions to stop at (zero target velocity and
//!   acceleration). A target outside `[lower, upper]` (beyond
//!   [`POSITION_TOLERANCE`], the tolerance of [`Arm::within_limits`]) or not
//!   finite is an error: it is never clamped.
//! - **Synchronisation**: phase-synchronised: every joint follows the same
//!   normalised profile, so a rest-to-rest move is a straight line in joint
//!   space, the very segment the collision checker verified (with time
//!   synchronisation the joints arrive together but the path bends away
//!   from the checked line, and near a box wall that matters). The move
//!   lasts as long as the slowest joint's time-optimal move.
//! - **The cycle**: each [`Smoother::step`] advances the trajectory by
//!   exactly [`CONTROL_PERIOD`] and returns the state there: the command for
//!   the next cycle.
//! - **Finished** is detected by time, as Ruckig does: the first step whose
//!   time passes the end of the trajectory has `done: true` and commands the
//!   target itself, exactly, with velocity and acceleration zero (Ruckig
//!   lands within ~1e-15 rad of it; the smoother replaces that by the
//!   target), and so does every later step until the target changes. The
//!   last commanded sample of a move is therefore the target, and a move of
//!   duration `d` takes `⌊d / CONTROL_PERIOD⌋ + 1` steps (up to rounding of
//!   the accumulated time).
//!
//! Errors (invalid limits, start or target, a trajectory Ruckig cannot
//! compute, non-finite output) are [`SmoothingError`]; nothing here
//! panics.
//!
//! [`Arm::within_limits`]: packwright_kinematics::Arm::within_limits

use rsruckig::prelude::*;

use crate::error::{Position, SmoothingError};
use packwright_interface::{DOF, Joints, Limits};

/// The control cycle in seconds: Universal Robots controllers take a joint
/// command every 2 ms (500 Hz).
pub const CONTROL_PERIOD: f64 = 0.002;

/// How far (rad) a start or target may lie outside `[lower, upper]` and still
/// count as inside: the same tolerance as
/// [`Arm::within_limits`](packwright_kinematics::Arm::within_limits), so a
/// configuration the arm model accepts is accepted here.
pub const POSITION_TOLERANCE: f64 = 1e-9;

/// How far (rad) from its target Ruckig may finish before that is an error
/// rather than rounding; within it, the final step commands the target
/// exactly.
const FINISH_TOLERANCE: f64 = 1e-6;

/// Ruckig rejects trajectories longer than this (seconds); it also bounds the
/// samples [`smooth_path`] takes for one segment.
const MAX_SEGMENT_DURATION: f64 = 7.6e3;

/// One control cycle's command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Joint positions to command (rad).
    pub position: Joints,
    /// Joint velocities at that instant (rad/s).
    pub velocity: Joints,
    /// Joint accelerations at that instant (rad/s²).
    pub acceleration: Joints,
    /// The target is reached: `position` is the target, at rest.
    pub done: bool,
}

/// An online, jerk-limited trajectory generator for the 6 joints, stepped
/// once per [`CONTROL_PERIOD`]. See the [module documentation](self) for the
/// contract.
///
/// ```
/// use packwright_interface::Limits;
/// use packwright_motion::smoothing::Smoother;
///
/// let limits = [Limits { lower: -6.0, upper: 6.0, velocity: 2.0, acceleration: 2.5, jerk: 15.0 }; 6];
/// let mut smoother = Smoother::new(limits, [0.0; 6])?;
/// smoother.set_target([0.5, -0.2, 0.1, 0.0, 0.3, -1.0])?;
/// loop {
///     let step = smoother.step()?;
///     // send step.position to the robot ...
///     if step.done {
///         break;
///     }
/// }
/// # Ok::<(), packwright_motion::error::SmoothingError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Smoother {
    limits: [Limits; DOF],
    otg: Ruckig<DOF, ThrowErrorHandler>,
    /// The current state (updated every step), the target and the limits.
    input: InputParameter<DOF>,
    output: OutputParameter<DOF>,
}

impl Smoother {
    /// A smoother at rest at `start`, whose target is `start`.
    ///
    /// Errors if a velocity, acceleration or jerk limit is not finite and
    /// positive, a position range is empty or NaN, or `start` is not finite
    /// or outside the position limits.
    pub fn new(limits: [Limits; DOF], start: Joints) -> Result<Smoother, SmoothingError> {
        let input = ruckig_input(&limits, start)?;
        let mut smoother = Smoother {
            limits,
            otg: Ruckig::new(None, CONTROL_PERIOD),
            input,
            output: OutputParameter::new(None),
        };
        smoother.reset(start);
        Ok(smoother)
    }

    /// The limits this smoother enforces.
    pub fn limits(&self) -> &[Limits; DOF] {
        &self.limits
    }

    /// The current target position.
    pub fn target(&self) -> Joints {
        to_joints(&self.input.target_position)
    }

    /// Move to `target` and stop there (zero velocity and acceleration).
    ///
    /// Takes effect at the next [`step`](Self::step), which plans from the
    /// current state: the arm may be moving towards an earlier target.
    /// Errors, leaving the target unchanged, if `target` is not finite or
    /// outside the position limits.
    pub fn set_target(&mut self, target: Joints) -> Result<(), SmoothingError> {
        check_position(&self.limits, &target, Position::Target)?;
        self.input.target_position.copy_from_slice(&target);
        Ok(())
    }

    /// Advance one [`CONTROL_PERIOD`] and return the command for it.
    ///
    /// The first step after a new target (or a [`reset`](Self::reset))
    /// computes the trajectory; the following ones sample it. Errors if
    /// Ruckig finds no trajectory (for instance a new target that cannot be
    /// reached without crossing a position limit given the current
    /// velocity), or after a reset to a non-finite position; the state is
    /// then unchanged.
    pub fn step(&mut self) -> Result<Step, SmoothingError> {
        if !all_finite(&self.input.current_position) {
            return Err(SmoothingError::NonFiniteCurrent {
                position: to_joints(&self.input.current_position),
            });
        }
        let done = match self.otg.update(&self.input, &mut self.output) {
            Ok(RuckigResult::Working) => false,
            Ok(RuckigResult::Finished) => true,
            Ok(other) => {
                return Err(SmoothingError::NoTrajectory {
                    from: to_joints(&self.input.current_position),
                    to: to_joints(&self.input.target_position),
                    reason: format!("Ruckig returned {other:?}"),
                });
            }
            Err(e) => {
                return Err(SmoothingError::NoTrajectory {
                    from: to_joints(&self.input.current_position),
                    to: to_joints(&self.input.target_position),
                    reason: e.to_string(),
                });
            }
        };
        let out = &self.output;
        if !(all_finite(&out.new_position)
            && all_finite(&out.new_velocity)
            && all_finite(&out.new_acceleration))
        {
            return Err(SmoothingError::NonFiniteOutput {
                from: to_joints(&self.input.current_position),
                to: to_joints(&self.input.target_position),
            });
        }
        let mut step = Step {
            position: to_joints(&out.new_position),
            velocity: to_joints(&out.new_velocity),
            acceleration: to_joints(&out.new_acceleration),
            done,
        };
        if done {
            // Ruckig ends within ~1e-15 rad of the target (its profiles are
            // accepted within 1e-8): command the target itself, at rest.
            let target = to_joints(&self.input.target_position);
            let miss = (0..DOF)
                .map(|j| (step.position[j] - target[j]).abs())
                .fold(0.0, f64::max);
            if miss > FINISH_TOLERANCE {
                return Err(SmoothingError::MissedTarget {
                    at: step.position,
                    target,
                    miss,
                });
            }
            step.position = target;
            step.velocity = [0.0; DOF];
            step.acceleration = [0.0; DOF];
        }
        self.input.current_position.copy_from_slice(&step.position);
        self.input.current_velocity.copy_from_slice(&step.velocity);
        self.input
            .current_acceleration
            .copy_from_slice(&step.acceleration);
        Ok(step)
    }

    /// The current (last commanded) position, velocity and acceleration.
    pub fn state(&self) -> (Joints, Joints, Joints) {
        (
            to_joints(&self.input.current_position),
            to_joints(&self.input.current_velocity),
            to_joints(&self.input.current_acceleration),
        )
    }

    /// Stop at `position`, at rest, with `position` as the target: for
    /// example after a protective stop, from the position the robot reports.
    ///
    /// This cannot fail. A position slightly outside the limits is allowed
    /// (the next move may only go back inside); a non-finite one makes every
    /// [`step`](Self::step) an error until the next reset.
    pub fn reset(&mut self, position: Joints) {
        self.input.current_position.copy_from_slice(&position);
        self.input.current_velocity.fill(0.0);
        self.input.current_acceleration.fill(0.0);
        self.input.target_position.copy_from_slice(&position);
        self.input.target_velocity.fill(0.0);
        self.input.target_acceleration.fill(0.0);
        self.otg.reset();
    }
}

/// Every commanded 2 ms position of a motion from `start` (at rest) through
/// each of `waypoints` in turn.
///
/// The arm **stops at every waypoint** (each is a separate rest-to-rest move;
/// no blending), so the result passes exactly through them. `start` itself is
/// not included (it is not commanded); the last sample of each segment is
/// its waypoint. No waypoints: no samples.
pub fn smooth_path(
    limits: [Limits; DOF],
    start: Joints,
    waypoints: &[Joints],
) -> Result<Vec<Joints>, SmoothingError> {
    let mut smoother = Smoother::new(limits, start)?;
    for (i, w) in waypoints.iter().enumerate() {
        check_position(&limits, w, Position::Waypoint(i))?;
    }
    let max_steps = (MAX_SEGMENT_DURATION / CONTROL_PERIOD) as usize + 2;
    let mut samples = Vec::new();
    for (i, w) in waypoints.iter().enumerate() {
        smoother.set_target(*w)?;
        let mut steps = 0;
        loop {
            let step = smoother.step()?;
            samples.push(step.position);
            if step.done {
                break;
            }
            steps += 1;
            if steps > max_steps {
                return Err(SmoothingError::TooLong {
                    waypoint: i,
                    limit_s: MAX_SEGMENT_DURATION,
                });
            }
        }
    }
    Ok(samples)
}

/// The duration (seconds) of the motion [`smooth_path`] commands: the sum of
/// the time-optimal (phase-synchronised) durations of its rest-to-rest
/// segments, each computed offline by Ruckig.
///
/// This is continuous time: [`smooth_path`] returns
/// `⌊d / CONTROL_PERIOD⌋ + 1` samples for a segment of duration `d`, so its
/// samples span at most one control period per segment more.
pub fn duration_of(
    limits: [Limits; DOF],
    start: Joints,
    waypoints: &[Joints],
) -> Result<f64, SmoothingError> {
    let mut input = ruckig_input(&limits, start)?;
    let mut otg = Generator::lend();
    let mut total = 0.0;
    let mut from = start;
    for (i, w) in waypoints.iter().enumerate() {
        check_position(&limits, w, Position::Waypoint(i))?;
        total += rest_to_rest(&mut otg, &mut input, from, *w, i)?.get_duration();
        from = *w;
    }
    Ok(total)
}

/// The least time (seconds) any jerk-limited motion within `limits` needs
/// from rest at `from` to rest at `to`: each joint alone, time-optimal
/// (Ruckig), the slowest joint's. No synchronisation, no path: a lower
/// bound for every planner between the same two stops.
pub fn lower_bound(limits: [Limits; DOF], from: Joints, to: Joints) -> Result<f64, SmoothingError> {
    let mut input = ruckig_input(&limits, from)?;
    let mut otg = Generator::lend();
    check_position(&limits, &to, Position::Target)?;
    Ok(rest_to_rest(&mut otg, &mut input, from, to, 0)?
        .get_independent_min_durations()
        .iter()
        .copied()
        .fold(0.0, f64::max))
}

/// The time-optimal trajectory from rest at `from` to rest at `to` (the
/// leg to waypoint `waypoint`), computed offline with `otg` and `input`
/// ([`ruckig_input`]), its duration checked: what [`duration_of`],
/// [`lower_bound`] and [`blend`](crate::blend::blend) plan with.
pub(crate) fn rest_to_rest(
    otg: &mut Ruckig<DOF, ThrowErrorHandler>,
    input: &mut InputParameter<DOF>,
    from: Joints,
    to: Joints,
    waypoint: usize,
) -> Result<Trajectory<DOF>, SmoothingError> {
    input.current_position.copy_from_slice(&from);
    input.current_velocity.fill(0.0);
    input.current_acceleration.fill(0.0);
    input.target_position.copy_from_slice(&to);
    let mut trajectory = Trajectory::new(None);
    let fail = |reason: String| SmoothingError::NoTrajectory { from, to, reason };
    match otg.calculate(input, &mut trajectory) {
        Ok(RuckigResult::Working) | Ok(RuckigResult::Finished) => {}
        Ok(other) => return Err(fail(format!("Ruckig returned {other:?}"))),
        Err(e) => return Err(fail(e.to_string())),
    }
    let duration = trajectory.get_duration();
    if !duration.is_finite() || duration < 0.0 {
        return Err(SmoothingError::BadDuration { waypoint, duration });
    }
    Ok(trajectory)
}

/// The input for `limits` (phase-synchronised, position interface,
/// continuous durations, the position range with
/// [`POSITION_TOLERANCE`]), at rest at `start`: what [`Smoother`] and
/// [`blend`](crate::blend::blend) plan with, with a generator at the
/// control rate ([`Generator`] offline, the smoother's own online).
pub(crate) fn ruckig_input(
    limits: &[Limits; DOF],
    start: Joints,
) -> Result<InputParameter<DOF>, SmoothingError> {
    check_limits(limits)?;
    check_position(limits, &start, Position::Start)?;
    let mut input = InputParameter::<DOF>::new(None);
    input.synchronization = Synchronization::Phase;
    input.control_interface = ControlInterface::Position;
    input.duration_discretization = DurationDiscretization::Continuous;
    let mut max_position = [0.0; DOF];
    let mut min_position = [0.0; DOF];
    for (j, l) in limits.iter().enumerate() {
        input.max_velocity[j] = l.velocity;
        input.max_acceleration[j] = l.acceleration;
        input.max_jerk[j] = l.jerk;
        max_position[j] = l.upper + POSITION_TOLERANCE;
        min_position[j] = l.lower - POSITION_TOLERANCE;
    }
    input.max_position = Some(DataArrayOrVec::Stack(max_position));
    input.min_position = Some(DataArrayOrVec::Stack(min_position));
    input.current_position.copy_from_slice(&start);
    input.target_position.copy_from_slice(&start);
    Ok(input)
}

type Ruckig6 = Ruckig<DOF, ThrowErrorHandler>;

thread_local! {
    /// This thread's offline generators not lent at the moment.
    static SPARE: std::cell::RefCell<Vec<Box<Ruckig6>>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// An offline Ruckig generator at the control rate, lent from this
/// thread's spares and given back when dropped. A generator is about
/// 32 KB: building one (and moving it) per blend was most of a short
/// blend's fixed cost, and touched more memory than the blend itself.
/// An offline calculation (`Ruckig::calculate`) keeps no state from one
/// call to the next (the calculator's buffers are scratch, rewritten by
/// each), so one generator serves any input; the online update
/// (`Ruckig::update`), which does keep state, is the [`Smoother`]'s own
/// generator's alone, never a lent one's. A test compares a lent
/// generator's trajectories with a new one's, bit for bit.
pub(crate) struct Generator(Option<Box<Ruckig6>>);

impl Generator {
    /// A spare generator of this thread, or a new one.
    pub(crate) fn lend() -> Generator {
        let spare = SPARE.with(|s| s.borrow_mut().pop());
        Generator(Some(
            spare.unwrap_or_else(|| Box::new(Ruckig::new(None, CONTROL_PERIOD))),
        ))
    }
}

impl std::ops::Deref for Generator {
    type Target = Ruckig6;
    fn deref(&self) -> &Ruckig6 {
        // Some until dropped.
        self.0
            .as_deref()
            .unwrap_or_else(|| unreachable!("a generator is lent until dropped"))
    }
}

impl std::ops::DerefMut for Generator {
    fn deref_mut(&mut self) -> &mut Ruckig6 {
        self.0
            .as_deref_mut()
            .unwrap_or_else(|| unreachable!("a generator is lent until dropped"))
    }
}

impl Drop for Generator {
    fn drop(&mut self) {
        if let Some(otg) = self.0.take() {
            // During thread teardown the spares may be gone: then it is freed.
            let _ = SPARE.try_with(|s| s.borrow_mut().push(otg));
        }
    }
}

fn check_limits(limits: &[Limits; DOF]) -> Result<(), SmoothingError> {
    for (j, l) in limits.iter().enumerate() {
        for (name, value) in [
            ("velocity", l.velocity),
            ("acceleration", l.acceleration),
            ("jerk", l.jerk),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(SmoothingError::BadLimit {
                    joint: j,
                    limit: name,
                    value,
                });
            }
        }
        // Infinite position limits (a continuous joint) are allowed.
        if l.lower.is_nan() || l.upper.is_nan() || l.lower > l.upper {
            return Err(SmoothingError::BadRange {
                joint: j,
                lower: l.lower,
                upper: l.upper,
            });
        }
    }
    Ok(())
}

pub(crate) fn check_position(
    limits: &[Limits; DOF],
    q: &Joints,
    at: Position,
) -> Result<(), SmoothingError> {
    for (j, (v, l)) in q.iter().zip(limits).enumerate() {
        if !v.is_finite() {
            return Err(SmoothingError::NonFinite {
                at,
                joint: j,
                value: *v,
            });
        }
        if *v < l.lower - POSITION_TOLERANCE || *v > l.upper + POSITION_TOLERANCE {
            return Err(SmoothingError::OutsideLimits {
                at,
                joint: j,
                value: *v,
                lower: l.lower,
                upper: l.upper,
            });
        }
    }
    Ok(())
}

fn all_finite(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}

fn to_joints(values: &[f64]) -> Joints {
    let mut q = [0.0; DOF];
    q.copy_from_slice(&values[..DOF]);
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_kinematics::Arm;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Every number of a trajectory that the planners read: the duration,
    /// each joint's own minimum duration, and the state at a few times.
    fn fingerprint(t: &Trajectory<DOF>) -> Vec<u64> {
        let mut out = vec![t.get_duration().to_bits()];
        out.extend(
            t.get_independent_min_durations()
                .iter()
                .map(|d| d.to_bits()),
        );
        for share in [0.0, 0.1, 0.37, 0.5, 0.81, 1.0] {
            let mut p = DataArrayOrVec::Stack([0.0; DOF]);
            let mut v = DataArrayOrVec::Stack([0.0; DOF]);
            let mut a = DataArrayOrVec::Stack([0.0; DOF]);
            t.at_time(
                share * t.get_duration(),
                &mut Some(&mut p),
                &mut Some(&mut v),
                &mut Some(&mut a),
                &mut None,
                &mut None,
            );
            for j in 0..DOF {
                out.extend([p[j].to_bits(), v[j].to_bits(), a[j].to_bits()]);
            }
        }
        out
    }

    /// One lent generator, used for hundreds of calculations in a row
    /// (rest to rest and from moving states, phase- and
    /// time-synchronised, full and slowed limits, some failing), gives
    /// each the trajectory a new generator gives, bit for bit.
    #[test]
    fn a_lent_generator_calculates_as_a_new_one() {
        let limits = Arm::ur10().limits;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let joints = |rng: &mut ChaCha8Rng| -> Joints {
            std::array::from_fn(|j| rng.random_range(limits[j].lower / 2.0..limits[j].upper / 2.0))
        };
        let mut lent = Generator::lend();
        let (mut same, mut failed) = (0, 0);
        for k in 0..400 {
            let share = if k % 3 == 0 { 0.3 } else { 1.0 };
            let slow = crate::blend::slowed(&limits, share);
            let mut input =
                ruckig_input(if share < 1.0 { &slow } else { &limits }, joints(&mut rng))
                    .expect("limits");
            if k % 2 == 1 {
                input.synchronization = Synchronization::Time;
                input.current_velocity = DataArrayOrVec::Stack(std::array::from_fn(|j| {
                    rng.random_range(-1.5..1.5) * limits[j].velocity
                }));
                input.current_acceleration = DataArrayOrVec::Stack(std::array::from_fn(|j| {
                    rng.random_range(-1.5..1.5) * limits[j].acceleration
                }));
            }
            input.target_position.copy_from_slice(&joints(&mut rng));
            let mut fresh = Ruckig::<DOF, ThrowErrorHandler>::new(None, CONTROL_PERIOD);
            let (mut a, mut b) = (Trajectory::new(None), Trajectory::new(None));
            let (ra, rb) = (
                lent.calculate(&input, &mut a),
                fresh.calculate(&input, &mut b),
            );
            assert_eq!(format!("{ra:?}"), format!("{rb:?}"), "case {k}");
            if ra.is_ok() {
                assert_eq!(fingerprint(&a), fingerprint(&b), "case {k}");
                same += 1;
            } else {
                failed += 1;
            }
        }
        assert!(same >= 300, "{same} compared, {failed} failed");
    }

    /// A generator given back is lent again (no new one is built), and
    /// two lent at once are two.
    #[test]
    fn generators_are_given_back_and_lent_again() {
        let first: *const Ruckig6 = {
            let lent = Generator::lend();
            &*lent as *const Ruckig6
        };
        let again = Generator::lend();
        assert_eq!(first, &*again as *const Ruckig6);
        let other = Generator::lend();
        assert_ne!(&*again as *const Ruckig6, &*other as *const Ruckig6);
    }
}
