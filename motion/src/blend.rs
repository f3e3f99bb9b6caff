//! Blended motion: passing through waypoints without stopping at them.
//!
//! [`smooth_path`](crate::smoothing::smooth_path) stops at every waypoint:
//! each leg is a rest-to-rest, phase-synchronised Ruckig move, a straight
//! line in joint space. [`blend`] keeps those very legs and, at a corner
//! passed through, leaves leg `k` before it has stopped and joins leg
//! `k + 1` after it has started by a *transition*: the time-optimal Ruckig
//! trajectory (time-synchronised) from leg `k`'s state (position, velocity,
//! acceleration) at the leaving time to leg `k + 1`'s state at the joining
//! time. Outside the transitions the arm is on the straight legs. A
//! transition is never slower than overlapping the two legs in time (that
//! sum joins the same two states within the same limits, and Ruckig's is
//! the fastest way to), and unlike the sum it cannot add the legs' jerks.
//!
//! # Contract
//!
//! - **Limits**: every joint's velocity, acceleration and jerk stay within
//!   its [`Limits`] at all times: on the legs by Ruckig's construction, on
//!   each transition checked exactly, phase by phase (between its phase
//!   boundaries the jerk is constant), with the position within
//!   `[lower, upper]` at those boundaries. At the joins position, velocity
//!   and acceleration are continuous. Each corner's transition is the one
//!   saving the most time among [`CANDIDATES`] fractions of the room there
//!   (capped per corner by the caller, [`blend_capped`]); none (the legs
//!   joined at rest, as when stopping everywhere) always keeps the limits.
//! - **Stops**: a waypoint marked as a stop, and the last one, is
//!   commanded exactly, at rest, on a control cycle; no transition passes
//!   it.
//! - **Straight next to every stop**: a leg that leaves or reaches a stop
//!   (or the start, or the end) keeps a part of its way next to it on the
//!   straight segment: at least [`MIN_STRAIGHT`] of its time
//!   (rest-to-rest profiles are symmetric: half the time is half the
//!   way), or, with [`blend_straight`], at least the share of its way the
//!   caller gives per leg and end. The caller
//!   ([`checked_blend`](crate::execute::checked_blend)) gives the share up
//!   to where the cup tip is a clearance from the stop: the final straight
//!   descent onto a top face or into a slot, the start of the lift, and
//!   the first straight part of the way back up, where the product being
//!   picked or just released is no obstacle to the cup's check (it checks
//!   the transitions with that product as an obstacle).
//! - **Transitions are disjoint**: each leg is left after it was joined, so
//!   at most one transition is running at any instant.
//! - The commands are what a caller checks for collisions and sends;
//!   [`Blended::corners`] says how much time each corner's transition
//!   saves, how close the motion passes to the waypoint and which samples
//!   the transition shaped, so a caller whose check fails near a corner can
//!   cap that corner or make it a stop
//!   ([`checked_blend`](crate::execute::checked_blend) does).

use rsruckig::prelude::*;

use crate::error::{Position, SmoothingError};
use crate::smoothing::{CONTROL_PERIOD, Generator, rest_to_rest, ruckig_input};
use packwright_interface::{DOF, Joints, Limits};

/// How many transitions are tried per corner: these fractions of the room
/// there, from all of it down.
pub const CANDIDATES: usize = 4;

/// The least share of its time a leg leaving or reaching a stop keeps on
/// its straight segment next to the stop.
pub const MIN_STRAIGHT: f64 = 0.5;

/// Relative slack on a limit for rounding (Ruckig's own profiles touch
/// their limits within ~1e-12).
const SLACK: f64 = 1e-9;

/// One corner of a blended motion: the waypoint between two legs.
#[derive(Debug, Clone, PartialEq)]
pub struct Corner {
    /// Seconds the corner's transition saves against stopping there (0:
    /// the arm stops at the waypoint).
    pub saved: f64,
    /// How close (rad, the largest joint's difference) the commands pass
    /// to the waypoint: 0 at a stop.
    pub miss: f64,
    /// The commanded samples the transition shaped (`first..end`; empty at
    /// a stop).
    pub samples: std::ops::Range<usize>,
}

/// A blended motion's commands.
#[derive(Debug, Clone, PartialEq)]
pub struct Blended {
    /// Every commanded position, one per [`CONTROL_PERIOD`], the start
    /// excluded, the last waypoint last.
    pub samples: Vec<Joints>,
    /// One per waypoint but the last.
    pub corners: Vec<Corner>,
    /// Per waypoint, the index of the sample at the end of its leg: at a
    /// stop (and the last waypoint), the sample commanding it; at a corner
    /// passed through, the sample where its transition ends.
    pub at: Vec<usize>,
    /// Per waypoint, the index of the first sample its leg moves (the
    /// transition into it included).
    pub starts: Vec<usize>,
}

impl Blended {
    /// Seconds the commands take.
    pub fn duration(&self) -> f64 {
        self.samples.len() as f64 * CONTROL_PERIOD
    }

    /// The waypoint whose leg sample `i` belongs to: the last leg started
    /// by then (in a transition, the leg it joins).
    pub fn leg_at(&self, i: usize) -> usize {
        self.starts.partition_point(|&s| s <= i).saturating_sub(1)
    }

    /// Whether sample `i` was shaped by a transition.
    pub fn shaped(&self, i: usize) -> bool {
        self.corners.iter().any(|c| c.samples.contains(&i))
    }

    /// Whether some sample of `range` was shaped by a transition.
    pub fn shaped_within(&self, range: std::ops::Range<usize>) -> bool {
        self.corners
            .iter()
            .any(|c| c.samples.start < range.end && range.start < c.samples.end)
    }

    /// The blended corner (saved > 0) whose samples include sample `i`,
    /// else the blended corner nearest it: the one to cap or make a stop
    /// when sample `i` fails a check. `None` when no corner is blended.
    pub fn corner_near(&self, i: usize) -> Option<usize> {
        self.corners
            .iter()
            .enumerate()
            .filter(|(_, c)| c.saved > 0.0)
            .min_by_key(|(_, c)| {
                if c.samples.contains(&i) {
                    0
                } else {
                    c.samples.start.abs_diff(i).min(c.samples.end.abs_diff(i))
                }
            })
            .map(|(k, _)| k)
    }
}

/// One leg: a rest-to-rest move from `from` to `to`, in its own time.
struct Leg {
    from: Joints,
    to: Joints,
    trajectory: Trajectory<DOF>,
    duration: f64,
}

/// Position, velocity, acceleration and jerk of `trajectory` at its own
/// time `t`: [`Trajectory::at_time`]'s values, bit for bit ([`along`]).
fn state(trajectory: &Trajectory<DOF>, t: f64) -> [Joints; 4] {
    let mut out = [[0.0; DOF]; 4];
    along(trajectory, t, |j, p, v, a, jerk| {
        out[0][j] = p;
        out[1][j] = v;
        out[2][j] = a;
        out[3][j] = jerk;
    });
    out
}

/// The position of `trajectory` at its own time `t` ([`state`]'s first
/// row, computed alone: the commands need no more).
fn position(trajectory: &Trajectory<DOF>, t: f64) -> Joints {
    let mut out = [0.0; DOF];
    along(trajectory, t, |j, p, _, _, _| out[j] = p);
    out
}

/// Calls `set(joint, position, velocity, acceleration, jerk)` for each
/// joint of `trajectory` at its own time `t`, with exactly the arithmetic
/// of rsruckig's `Trajectory::at_time` (3.0: the phase found the same way,
/// the same integration formula), without its per-call buffers, for a
/// trajectory of one section (every trajectory here: no intermediate
/// waypoints); any other goes through `at_time` itself. A test compares
/// the two bit for bit.
fn along(trajectory: &Trajectory<DOF>, t: f64, mut set: impl FnMut(usize, f64, f64, f64, f64)) {
    let integrate = |t: f64, p0: f64, v0: f64, a0: f64, j: f64| {
        (
            p0 + t * (v0 + t * (a0 / 2.0 + t * j / 6.0)),
            v0 + t * (a0 + t * j / 2.0),
            a0 + t * j,
        )
    };
    let profiles = trajectory.get_profiles();
    let duration = trajectory.get_duration();
    let single = profiles.len() == 1
        && (t >= duration || trajectory.cumulative_times.first().is_some_and(|c| *c > t));
    if !single {
        let [p, v, a, jk] = at_time(trajectory, t);
        for j in 0..DOF {
            set(j, p[j], v[j], a[j], jk[j]);
        }
        return;
    }
    let section = &profiles[0];
    for j in 0..DOF {
        let p = &section[j];
        if t >= duration {
            let local = t - (p.brake.duration + p.t_sum[6]);
            let (q, v, a) = integrate(local, p.p[7], p.v[7], p.a[7], 0.0);
            set(j, q, v, a, 0.0);
            continue;
        }
        let mut local = t;
        if p.brake.duration > 0.0 {
            if local < p.brake.duration {
                let index = if local < p.brake.t[0] { 0 } else { 1 };
                if index > 0 {
                    local -= p.brake.t[index - 1];
                }
                let b = &p.brake;
                let (q, v, a) = integrate(local, b.p[index], b.v[index], b.a[index], b.j[index]);
                set(j, q, v, a, b.j[index]);
                continue;
            }
            local -= p.brake.duration;
        }
        if local >= p.t_sum[6] {
            let (q, v, a) = integrate(local - p.t_sum[6], p.p[7], p.v[7], p.a[7], 0.0);
            set(j, q, v, a, 0.0);
            continue;
        }
        let phase = p.t_sum.iter().position(|s| *s > local).unwrap_or(6);
        if phase > 0 {
            local -= p.t_sum[phase - 1];
        }
        let (q, v, a) = integrate(local, p.p[phase], p.v[phase], p.a[phase], p.j[phase]);
        set(j, q, v, a, p.j[phase]);
    }
}

/// Position, velocity, acceleration and jerk of `trajectory` at its own
/// time `t`, by rsruckig's `at_time`.
fn at_time(trajectory: &Trajectory<DOF>, t: f64) -> [Joints; 4] {
    let mut p = DataArrayOrVec::Stack([0.0; DOF]);
    let mut v = DataArrayOrVec::Stack([0.0; DOF]);
    let mut a = DataArrayOrVec::Stack([0.0; DOF]);
    let mut jk = DataArrayOrVec::Stack([0.0; DOF]);
    let mut section = None;
    trajectory.at_time(
        t,
        &mut Some(&mut p),
        &mut Some(&mut v),
        &mut Some(&mut a),
        &mut Some(&mut jk),
        &mut section,
    );
    let mut out = [[0.0; DOF]; 4];
    for j in 0..DOF {
        out[0][j] = p[j];
        out[1][j] = v[j];
        out[2][j] = a[j];
        out[3][j] = jk[j];
    }
    out
}

/// The rest-to-rest leg from `from` to `to`.
fn leg(
    otg: &mut Ruckig<DOF, ThrowErrorHandler>,
    input: &mut InputParameter<DOF>,
    from: Joints,
    to: Joints,
    waypoint: usize,
) -> Result<Leg, SmoothingError> {
    let trajectory = rest_to_rest(otg, input, from, to, waypoint)?;
    Ok(Leg {
        from,
        to,
        duration: trajectory.get_duration(),
        trajectory,
    })
}

/// The time on `leg` (its own) where it has covered `share` of its way,
/// by its joint that moves most (the legs are phase-synchronised: every
/// joint covers the same share at the same time): with `after`, the
/// earliest time from which it has covered at least that share, else the
/// latest time until which it has covered at most that share (within
/// 1e-9 s, on the safe side either way).
fn time_at_share(leg: &Leg, share: f64, after: bool) -> f64 {
    if share <= 0.0 {
        return 0.0;
    }
    if share >= 1.0 {
        return leg.duration;
    }
    let (j, delta) = (0..DOF)
        .map(|j| (j, leg.to[j] - leg.from[j]))
        .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))
        .unwrap_or((0, 0.0));
    if delta == 0.0 {
        return if after { leg.duration } else { 0.0 };
    }
    let covered = |t: f64| (position(&leg.trajectory, t)[j] - leg.from[j]) / delta;
    let (mut lo, mut hi) = (0.0, leg.duration);
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if covered(mid) < share {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if after { hi } else { lo }
}

/// The times at which a trajectory's jerk changes: its profiles' phase
/// boundaries, for every joint.
fn breakpoints(trajectory: &Trajectory<DOF>, into: &mut Vec<f64>) {
    for section in trajectory.get_profiles() {
        for p in section.iter() {
            let offset = p.brake.duration;
            into.push(offset);
            into.extend(p.t_sum.iter().map(|t| offset + t));
        }
    }
}

/// Whether `trajectory` keeps every limit over its whole duration,
/// exactly: between consecutive phase boundaries the jerk is constant, so
/// it is checked inside, the acceleration (linear) at both ends, and the
/// velocity (quadratic) at both ends and where the acceleration crosses
/// zero; the position at the boundaries.
fn keeps_limits(limits: &[Limits; DOF], trajectory: &Trajectory<DOF>) -> bool {
    let duration = trajectory.get_duration();
    let mut times = vec![0.0, duration];
    breakpoints(trajectory, &mut times);
    times.retain(|t| *t >= 0.0 && *t <= duration);
    times.sort_by(f64::total_cmp);
    times.dedup_by(|x, y| (*x - *y).abs() < 1e-12);
    let at = |t: f64| state(trajectory, t);
    let ok = |x: f64, max: f64| x.abs() <= max * (1.0 + SLACK);
    let mut previous = at(times[0]);
    for w in times.windows(2) {
        let (t0, t1) = (w[0], w[1]);
        let next = at(t1);
        let inside = at(0.5 * (t0 + t1));
        for (j, l) in limits.iter().enumerate() {
            let (a0, a1) = (previous[2][j], next[2][j]);
            let turn = if a0 * a1 < 0.0 {
                // The velocity's extremum inside the phase.
                at(t0 + (t1 - t0) * a0 / (a0 - a1))[1][j]
            } else {
                0.0
            };
            let fine = [previous[0][j], next[0][j]]
                .iter()
                .all(|q| *q >= l.lower - 1e-9 && *q <= l.upper + 1e-9)
                && [previous[1][j], next[1][j], turn]
                    .iter()
                    .all(|v| ok(*v, l.velocity))
                && ok(a0, l.acceleration)
                && ok(a1, l.acceleration)
                && ok(inside[3][j], l.jerk);
            if !fine {
                return false;
            }
        }
        previous = next;
    }
    true
}

/// How far a transition may end from the state it was asked for
/// (position rad, velocity rad/s, acceleration rad/s²) before it is
/// refused: a jump at the join of `e` in position shows in the commands'
/// third difference as a jerk of `e / CONTROL_PERIOD³` (1.25e8 e), so the
/// join must be exact to rounding for the commands to keep the limits.
const JOIN_TOLERANCE: [f64; 3] = [1e-14, 1e-12, 1e-10];

/// The time-optimal trajectory from state `from` to state `to` (position,
/// velocity, acceleration), time-synchronised, when Ruckig finds one
/// within the limits that lands on `to`.
fn transition(
    otg: &mut Ruckig<DOF, ThrowErrorHandler>,
    input: &mut InputParameter<DOF>,
    limits: &[Limits; DOF],
    from: &[Joints; 4],
    to: &[Joints; 4],
) -> Option<Trajectory<DOF>> {
    input.current_position.copy_from_slice(&from[0]);
    input.current_velocity.copy_from_slice(&from[1]);
    input.current_acceleration.copy_from_slice(&from[2]);
    input.target_position.copy_from_slice(&to[0]);
    input.target_velocity.copy_from_slice(&to[1]);
    input.target_acceleration.copy_from_slice(&to[2]);
    let mut trajectory = Trajectory::new(None);
    match otg.calculate(input, &mut trajectory) {
        Ok(RuckigResult::Working) | Ok(RuckigResult::Finished) => {}
        _ => return None,
    }
    let duration = trajectory.get_duration();
    if !duration.is_finite() || duration <= 0.0 {
        return None;
    }
    let end = state(&trajectory, duration);
    let lands = (0..DOF).all(|j| {
        (0..3).all(|d| (end[d][j] - to[d][j]).abs() <= JOIN_TOLERANCE[d] * to[d][j].abs().max(1.0))
    });

    (lands && keeps_limits(limits, &trajectory)).then_some(trajectory)
}

/// A chosen transition at a corner: where it leaves leg `k` and joins leg
/// `k + 1` (their own times) and its trajectory.
struct Join {
    leave: f64,
    join: f64,
    trajectory: Trajectory<DOF>,
}

/// The commands from `start` (at rest) through `waypoints`, stopping at
/// each waypoint `k` with `stops[k]` (a missing entry is not a stop) and
/// at the last, passing through the others with the transition that saves
/// the most time within the limits (module docs).
///
/// Errors as [`smooth_path`](crate::smoothing::smooth_path) does: invalid
/// limits, a start or waypoint outside them or not finite, a leg Ruckig
/// cannot compute.
pub fn blend(
    limits: [Limits; DOF],
    start: Joints,
    waypoints: &[Joints],
    stops: &[bool],
) -> Result<Blended, SmoothingError> {
    blend_capped(limits, start, waypoints, &full_caps(waypoints.len(), stops))
}

/// The caps of `n` corners with `stops` (a missing entry is not a stop):
/// 0 at a stop, the whole room (1) elsewhere.
pub fn full_caps(n: usize, stops: &[bool]) -> Vec<f64> {
    (0..n)
        .map(|k| {
            if stops.get(k).copied().unwrap_or(false) {
                0.0
            } else {
                1.0
            }
        })
        .collect()
}

/// [`blend`] with a cap per corner: `caps[k]` (in `[0, 1]`, a missing
/// entry is 1) is the largest share of the room at waypoint `k` its
/// transition may use; 0 makes it a stop.
pub fn blend_capped(
    limits: [Limits; DOF],
    start: Joints,
    waypoints: &[Joints],
    caps: &[f64],
) -> Result<Blended, SmoothingError> {
    blend_slowed(limits, start, waypoints, caps, &[])
}

/// `limits` slowed to `share` of their speed (in (0, 1)), as the teach
/// pendant's speed slider does: velocities times `share`, accelerations
/// times its square, jerks times its cube, so a rest-to-rest leg keeps its
/// path and takes `1 / share` as long.
pub fn slowed(limits: &[Limits; DOF], share: f64) -> [Limits; DOF] {
    let mut out = *limits;
    for l in &mut out {
        l.velocity *= share;
        l.acceleration *= share * share;
        l.jerk *= share * share * share;
    }
    out
}

/// [`blend_capped`] with a speed per leg: leg `k` (the one reaching
/// waypoint `k`) is the rest-to-rest leg within `limits` [`slowed`] to
/// `speeds[k]` when that is in (0, 1) (a missing entry, or any other
/// value, is full speed). The transitions keep `limits`: a slowed leg is
/// on its straight segment, at its own speed, wherever no transition
/// shapes it; next to a stop that is at least [`MIN_STRAIGHT`] of its
/// time (a guarded descent onto a top face; [`blend_straight`] can give
/// another share).
pub fn blend_slowed(
    limits: [Limits; DOF],
    start: Joints,
    waypoints: &[Joints],
    caps: &[f64],
    speeds: &[f64],
) -> Result<Blended, SmoothingError> {
    blend_straight(limits, start, waypoints, caps, speeds, &[])
}

/// [`blend_slowed`] with the straight part next to each stop given per
/// leg: `straight[k] = Some([leaving, reaching])` keeps leg `k` on its
/// straight segment over at least that share of its *way* (the joint
/// segment) next to the stop it leaves and next to the stop it reaches
/// (each clamped to `[0, 1]`; 1 keeps the whole leg straight on that
/// side). `None`, or a missing entry, keeps [`MIN_STRAIGHT`] of its time
/// at both ends, as [`blend_slowed`] does. The legs are
/// phase-synchronised, so a share of the way is where every joint has
/// covered that share of its move (measured on the joint moving most,
/// rounded to the safe side).
pub fn blend_straight(
    limits: [Limits; DOF],
    start: Joints,
    waypoints: &[Joints],
    caps: &[f64],
    speeds: &[f64],
    straight: &[Option<[f64; 2]>],
) -> Result<Blended, SmoothingError> {
    let mut input = ruckig_input(&limits, start)?;
    let mut otg = Generator::lend();
    for (i, w) in waypoints.iter().enumerate() {
        crate::smoothing::check_position(&limits, w, Position::Waypoint(i))?;
    }
    let mut legs: Vec<Leg> = Vec::with_capacity(waypoints.len());
    let mut from = start;
    for (i, w) in waypoints.iter().enumerate() {
        let share = speeds.get(i).copied().unwrap_or(1.0);
        let l = if share > 0.0 && share < 1.0 {
            let mut slow_input = ruckig_input(&slowed(&limits, share), from)?;
            leg(&mut otg, &mut slow_input, from, *w, i)?
        } else {
            leg(&mut otg, &mut input, from, *w, i)?
        };
        legs.push(l);
        from = *w;
    }
    let dt = CONTROL_PERIOD;
    let cap = |k: usize| caps.get(k).copied().unwrap_or(1.0).clamp(0.0, 1.0);
    let stop_at = |k: usize| k + 1 == waypoints.len() || cap(k) <= 0.0;
    // Transitions: time-synchronised, any boundary state.
    // (The legs' generator: an offline calculation keeps no state from
    // one call to the next.)
    let mut free_input = input.clone();
    free_input.synchronization = Synchronization::Time;
    let mut joins: Vec<Option<Join>> = Vec::with_capacity(legs.len());
    // Where the leg in hand was joined (its own time).
    let mut joined: f64 = 0.0;
    for k in 0..legs.len().saturating_sub(1) {
        let (a, b) = (&legs[k], &legs[k + 1]);
        let leaves_stop = k == 0 || stop_at(k - 1);
        let earliest = if leaves_stop {
            joined.max(match straight.get(k).copied().flatten() {
                None => MIN_STRAIGHT * a.duration,
                Some(s) => time_at_share(a, s[0].clamp(0.0, 1.0), true),
            })
        } else {
            joined
        };
        // A leg reaching a stop keeps its end straight; one passing
        // through keeps its second half for the next corner.
        let latest = if stop_at(k + 1) {
            match straight.get(k + 1).copied().flatten() {
                None => (1.0 - MIN_STRAIGHT) * b.duration,
                Some(s) => time_at_share(b, 1.0 - s[1].clamp(0.0, 1.0), false),
            }
        } else {
            0.5 * b.duration
        };
        let (room_a, room_b) = ((a.duration - earliest).max(0.0), latest.max(0.0));
        let mut best: Option<(f64, Join)> = None;
        if !stop_at(k) && room_a > dt && room_b > dt {
            for c in 0..CANDIDATES {
                let share = cap(k) * (CANDIDATES - c) as f64 / CANDIDATES as f64;
                let (leave, join) = (a.duration - share * room_a, share * room_b);
                let Some(trajectory) = transition(
                    &mut otg,
                    &mut free_input,
                    &limits,
                    &state(&a.trajectory, leave),
                    &state(&b.trajectory, join),
                ) else {
                    continue;
                };
                let saved = (a.duration - leave) + join - trajectory.get_duration();
                if saved > dt && best.as_ref().is_none_or(|(s, _)| saved > *s) {
                    best = Some((
                        saved,
                        Join {
                            leave,
                            join,
                            trajectory,
                        },
                    ));
                }
            }
        }
        joined = best.as_ref().map_or(0.0, |(_, j)| j.join);
        joins.push(best.map(|(_, j)| j));
    }
    sample(start, waypoints, &legs, &joins)
}

/// One stretch of the commands, in global time from `begin` to `end`.
enum Piece<'l> {
    /// Leg `k` from its own time `from` on.
    Leg { k: usize, from: f64 },
    /// At rest at waypoint `k` (a stop, until the next control cycle).
    Rest { k: usize },
    /// The transition at corner `k`.
    Join { trajectory: &'l Trajectory<DOF> },
}

/// Samples the legs and their joins every control cycle.
fn sample(
    start: Joints,
    waypoints: &[Joints],
    legs: &[Leg],
    joins: &[Option<Join>],
) -> Result<Blended, SmoothingError> {
    let dt = CONTROL_PERIOD;
    // The pieces, each with its global start and end.
    let mut pieces: Vec<(f64, f64, Piece)> = Vec::with_capacity(3 * legs.len());
    // Per leg, the global time its leg (or the transition into it) starts,
    // and where it ends (a stop) or where the transition out of it ends.
    let mut starts_at = Vec::with_capacity(legs.len());
    let mut ends_at = Vec::with_capacity(legs.len());
    let mut corner_times = Vec::with_capacity(joins.len());
    let mut t = 0.0;
    let mut entered = 0.0;
    for (k, l) in legs.iter().enumerate() {
        if k == 0 {
            starts_at.push(0.0);
        }
        let leave = joins
            .get(k)
            .and_then(|j| j.as_ref())
            .map_or(l.duration, |j| j.leave);
        let stretch = (leave - entered).max(0.0);
        pieces.push((t, t + stretch, Piece::Leg { k, from: entered }));
        t += stretch;
        match joins.get(k) {
            Some(Some(j)) => {
                let d = j.trajectory.get_duration();
                starts_at.push(t);
                pieces.push((
                    t,
                    t + d,
                    Piece::Join {
                        trajectory: &j.trajectory,
                    },
                ));
                corner_times.push(Some((t, t + d)));
                t += d;
                ends_at.push(t);
                entered = j.join;
            }
            Some(None) => {
                // At rest, the next leg starting on a control cycle.
                ends_at.push(t);
                let resume = (t / dt - 1e-9).ceil().max(0.0) * dt;
                pieces.push((t, resume, Piece::Rest { k }));
                t = resume;
                starts_at.push(t);
                corner_times.push(None);
                entered = 0.0;
            }
            None => ends_at.push(t),
        }
    }
    let end = t;
    let count = if legs.is_empty() {
        0
    } else {
        ((end / dt - 1e-9).ceil() as usize).max(1)
    };
    let mut samples = Vec::with_capacity(count);
    let mut piece = 0;
    for i in 1..=count {
        let t = i as f64 * dt;
        while piece + 1 < pieces.len() && pieces[piece].1 < t - 1e-12 {
            piece += 1;
        }
        let (begin, _, ref p) = pieces[piece];
        let q = match *p {
            Piece::Leg { k, from } => {
                let local = from + (t - begin);
                let l = &legs[k];
                if local >= l.duration - 1e-12 {
                    l.to
                } else if local <= 1e-12 {
                    l.from
                } else {
                    position(&l.trajectory, local)
                }
            }
            Piece::Rest { k } => waypoints[k],
            Piece::Join { trajectory } => {
                position(trajectory, (t - begin).min(trajectory.get_duration()))
            }
        };
        if q.iter().any(|v| !v.is_finite()) {
            return Err(SmoothingError::NonFiniteOutput {
                from: start,
                to: waypoints.last().copied().unwrap_or(start),
            });
        }
        samples.push(q);
    }
    if let (Some(last), Some(w)) = (samples.last_mut(), waypoints.last()) {
        *last = *w;
    }
    let index_after = |g: f64| (((g / dt) + 1e-9).floor() as usize).min(count.saturating_sub(1));
    let index_at = |g: f64| {
        (((g / dt) - 1e-9).ceil().max(1.0) as usize)
            .min(count)
            .saturating_sub(1)
    };
    let corners = corner_times
        .iter()
        .enumerate()
        .map(|(k, times)| {
            let (Some((g0, g1)), Some(Some(j))) = (times, joins.get(k)) else {
                return Corner {
                    saved: 0.0,
                    miss: 0.0,
                    samples: 0..0,
                };
            };
            let a = &legs[k];
            let saved = (a.duration - j.leave) + j.join - (g1 - g0);
            let first = index_after(*g0).saturating_sub(1);
            let end = (index_at(*g1) + 2).min(count);
            let w = waypoints[k];
            let miss = samples[first.min(end)..end]
                .iter()
                .map(|q| (0..DOF).map(|n| (q[n] - w[n]).abs()).fold(0.0, f64::max))
                .fold(f64::INFINITY, f64::min);
            Corner {
                saved,
                miss: if miss.is_finite() { miss } else { 0.0 },
                samples: first..end,
            }
        })
        .collect();
    let at = ends_at.iter().map(|&g| index_at(g)).collect();
    let starts = starts_at.iter().map(|&g| index_after(g)).collect();
    Ok(Blended {
        samples,
        corners,
        at,
        starts,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_kinematics::Arm;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// `state` and `position` give `at_time`'s values bit for bit, on
    /// rest-to-rest legs and on transitions between random moving states
    /// (some of them beyond the limits, so Ruckig brakes first), at random
    /// times, phase boundaries, before the start and past the end.
    #[test]
    fn state_is_at_time_bit_for_bit() {
        let arm = Arm::ur10();
        let limits = arm.limits;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let joints = |rng: &mut ChaCha8Rng| -> Joints {
            std::array::from_fn(|j| rng.random_range(limits[j].lower / 2.0..limits[j].upper / 2.0))
        };
        let mut input = ruckig_input(&limits, [0.0; DOF]).expect("limits");
        let mut otg = Generator::lend();
        let mut free_input = ruckig_input(&limits, [0.0; DOF]).expect("limits");
        let mut free = Generator::lend();
        free_input.synchronization = Synchronization::Time;
        let (mut compared, mut braking) = (0, 0);
        for k in 0..300 {
            let trajectory = if k % 2 == 0 {
                rest_to_rest(&mut otg, &mut input, joints(&mut rng), joints(&mut rng), 0)
                    .expect("a leg")
            } else {
                // Up to 1.5 times the velocity and acceleration limits.
                let moving = |rng: &mut ChaCha8Rng, q: Joints| -> [Joints; 4] {
                    [
                        q,
                        std::array::from_fn(|j| rng.random_range(-1.5..1.5) * limits[j].velocity),
                        std::array::from_fn(|j| {
                            rng.random_range(-1.5..1.5) * limits[j].acceleration
                        }),
                        [0.0; DOF],
                    ]
                };
                let q = joints(&mut rng);
                let (from, to) = (moving(&mut rng, q), joints(&mut rng));
                free_input.current_position.copy_from_slice(&from[0]);
                free_input.current_velocity.copy_from_slice(&from[1]);
                free_input.current_acceleration.copy_from_slice(&from[2]);
                free_input.target_position.copy_from_slice(&to);
                free_input.target_velocity.fill(0.0);
                free_input.target_acceleration.fill(0.0);
                let mut trajectory = Trajectory::new(None);
                match free.calculate(&free_input, &mut trajectory) {
                    Ok(RuckigResult::Working) | Ok(RuckigResult::Finished) => trajectory,
                    _ => continue,
                }
            };
            let duration = trajectory.get_duration();
            braking += usize::from(
                trajectory.get_profiles()[0]
                    .iter()
                    .any(|p| p.brake.duration > 0.0),
            );
            let mut times = vec![-0.01, 0.0, duration, duration + 0.013];
            breakpoints(&trajectory, &mut times);
            times.extend((0..40).map(|_| rng.random_range(0.0..duration.max(1e-6))));
            for t in times {
                let (fast, slow) = (state(&trajectory, t), at_time(&trajectory, t));
                for d in 0..4 {
                    for j in 0..DOF {
                        assert_eq!(
                            fast[d][j].to_bits(),
                            slow[d][j].to_bits(),
                            "derivative {d}, joint {j}, t {t}"
                        );
                    }
                }
                assert_eq!(position(&trajectory, t), slow[0]);
                compared += 1;
            }
        }
        assert!(compared > 10_000 && braking > 10, "{compared} / {braking}");
    }
}
