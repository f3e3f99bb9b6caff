//! Blended motion: passing through waypoints without stopping at them.
//!
//! [`smooth_path`](crate::smoothing::smooth_path) stops at every waypoint:
//! each leg is a rest-to-rest, phase-synchronised Ruckig move, a straight
//! line in joint space. [`blend`] keeps those very legs and overlaps
//! consecutive ones in time: leg `k + 1` starts before leg `k` has
//! stopped, and the arm follows their sum. Where two legs overlap, the
//! path leaves the corner's two straight segments, but stays inside the
//! triangle they span (each leg is monotone in every joint), and rejoins
//! them once the overlap ends.
//!
//! # Contract
//!
//! - **Limits**: every joint's velocity, acceleration and jerk (the exact
//!   sum of the legs' Ruckig states) stay within its [`Limits`] at all
//!   times (checked exactly, phase by phase: between the legs' phase
//!   boundaries the summed jerk is constant), and its position within
//!   `[lower, upper]` at those boundaries. Each overlap is
//!   the largest of [`CANDIDATES`] fractions of the room there for which
//!   that holds; none (the legs joined at rest, as today) always does.
//! - **Stops**: a waypoint marked as a stop, and the last one, is
//!   commanded exactly, at rest, on a control cycle; the legs either side
//!   of it do not overlap.
//! - **Straight next to every stop**: a leg that leaves or reaches a stop
//!   (or the start, or the end) is overlapped only in its half away from
//!   it, so the arm leaves and reaches each stop along the straight
//!   segment for at least half the leg, as when stopping everywhere: the
//!   descent onto a product's top face and into a slot, and the way back
//!   up, are not cut (the product being picked or just released is no
//!   obstacle to the collision check there).
//! - **At most two legs overlap** at any instant.
//! - The commands are what a caller checks for collisions and sends;
//!   [`Blended::corners`] says how long each corner's overlap is, how close
//!   the motion passes to the waypoint and which samples it shaped, so a
//!   caller whose check fails near a corner can make that corner a stop
//!   ([`checked_blend`](crate::execute::checked_blend) does).

use rsruckig::prelude::*;

use crate::error::{Position, SmoothingError};
use crate::smoothing::{CONTROL_PERIOD, rest_to_rest, ruckig_input};
use packwright_interface::{DOF, Joints, Limits};

/// How many overlaps are tried per corner, from the largest room down.
pub const CANDIDATES: usize = 16;

/// Relative slack on a limit for rounding (Ruckig's own profiles touch
/// their limits within ~1e-12).
const SLACK: f64 = 1e-9;

/// One corner of a blended motion: the waypoint between two legs.
#[derive(Debug, Clone, PartialEq)]
pub struct Corner {
    /// Seconds the two legs overlap (0: the arm stops at the waypoint).
    pub overlap: f64,
    /// How close (rad, the largest joint's difference) the commands pass
    /// to the waypoint: 0 at a stop.
    pub miss: f64,
    /// The commanded samples the overlap shaped (`first..end`; empty at a
    /// stop).
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
    /// stop (and the last waypoint), the sample commanding it.
    pub at: Vec<usize>,
    /// Per waypoint, the index of the first sample its leg moves.
    pub starts: Vec<usize>,
}

impl Blended {
    /// Seconds the commands take.
    pub fn duration(&self) -> f64 {
        self.samples.len() as f64 * CONTROL_PERIOD
    }

    /// The waypoint whose leg sample `i` belongs to: the last leg started
    /// by then (in an overlap, the later of the two).
    pub fn leg_at(&self, i: usize) -> usize {
        self.starts.partition_point(|&s| s <= i).saturating_sub(1)
    }

    /// The blended corner (overlap > 0) whose samples include sample `i`,
    /// else the blended corner nearest it: the one to make a stop when
    /// sample `i` fails a check. `None` when no corner is blended.
    pub fn corner_near(&self, i: usize) -> Option<usize> {
        self.corners
            .iter()
            .enumerate()
            .filter(|(_, c)| c.overlap > 0.0)
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

/// One leg: a rest-to-rest move, placed in time.
struct Leg {
    start: f64,
    from: Joints,
    to: Joints,
    trajectory: Trajectory<DOF>,
    duration: f64,
}

/// Position displacement, velocity, acceleration and jerk of a leg at
/// global time `t` (zero motion outside it; the whole displacement after).
fn leg_state(leg: &Leg, t: f64) -> [Joints; 4] {
    let tau = t - leg.start;
    if tau <= 0.0 {
        return [[0.0; DOF]; 4];
    }
    if tau >= leg.duration {
        let mut d = [0.0; DOF];
        for (j, d) in d.iter_mut().enumerate() {
            *d = leg.to[j] - leg.from[j];
        }
        return [d, [0.0; DOF], [0.0; DOF], [0.0; DOF]];
    }
    let mut p = DataArrayOrVec::Stack([0.0; DOF]);
    let mut v = DataArrayOrVec::Stack([0.0; DOF]);
    let mut a = DataArrayOrVec::Stack([0.0; DOF]);
    let mut jk = DataArrayOrVec::Stack([0.0; DOF]);
    let mut section = None;
    leg.trajectory.at_time(
        tau,
        &mut Some(&mut p),
        &mut Some(&mut v),
        &mut Some(&mut a),
        &mut Some(&mut jk),
        &mut section,
    );
    let mut out = [[0.0; DOF]; 4];
    for j in 0..DOF {
        out[0][j] = p[j] - leg.from[j];
        out[1][j] = v[j];
        out[2][j] = a[j];
        out[3][j] = jk[j];
    }
    out
}

/// The rest-to-rest leg from `from` to `to` (not yet placed in time).
fn leg(
    otg: &mut Ruckig<DOF, ThrowErrorHandler>,
    input: &mut InputParameter<DOF>,
    from: Joints,
    to: Joints,
    waypoint: usize,
) -> Result<Leg, SmoothingError> {
    let trajectory = rest_to_rest(otg, input, from, to, waypoint)?;
    Ok(Leg {
        start: 0.0,
        from,
        to,
        duration: trajectory.get_duration(),
        trajectory,
    })
}

/// The times (global) at which a leg's jerk changes: its profiles' phase
/// boundaries, for every joint.
fn breakpoints(leg: &Leg, into: &mut Vec<f64>) {
    for section in leg.trajectory.get_profiles() {
        for p in section.iter() {
            let offset = leg.start + p.brake.duration;
            into.push(leg.start);
            into.push(offset);
            into.extend(p.t_sum.iter().map(|t| offset + t));
        }
    }
}

/// Whether the sum of legs `a` and `b` keeps every limit from `from` to
/// `to` (global seconds), exactly: between consecutive phase boundaries of
/// either leg both jerks are constant, so the summed jerk is checked
/// inside, the acceleration (linear) at both ends, and the velocity
/// (quadratic) at both ends and where the acceleration crosses zero.
fn overlap_ok(limits: &[Limits; DOF], a: &Leg, b: &Leg, from: f64, to: f64) -> bool {
    let mut times = vec![from, to];
    breakpoints(a, &mut times);
    breakpoints(b, &mut times);
    times.retain(|t| *t >= from && *t <= to);
    times.sort_by(f64::total_cmp);
    times.dedup_by(|x, y| (*x - *y).abs() < 1e-12);
    // Summed state: position, velocity, acceleration, jerk per joint.
    let sum = |t: f64| -> [Joints; 4] {
        let (sa, sb) = (leg_state(a, t), leg_state(b, t));
        let mut out = [[0.0; DOF]; 4];
        for j in 0..DOF {
            out[0][j] = a.from[j] + sa[0][j] + sb[0][j];
            for d in 1..4 {
                out[d][j] = sa[d][j] + sb[d][j];
            }
        }
        out
    };
    let ok = |x: f64, max: f64| x.abs() <= max * (1.0 + SLACK);
    let mut previous = sum(times[0]);
    for w in times.windows(2) {
        let (t0, t1) = (w[0], w[1]);
        let next = sum(t1);
        let inside = sum(0.5 * (t0 + t1));
        for (j, l) in limits.iter().enumerate() {
            let (a0, a1) = (previous[2][j], next[2][j]);
            let turn = if a0 * a1 < 0.0 {
                // The velocity's extremum inside the phase.
                let at = t0 + (t1 - t0) * a0 / (a0 - a1);
                sum(at)[1][j]
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

/// The commands from `start` (at rest) through `waypoints`, stopping at
/// each waypoint `k` with `stops[k]` (a missing entry is not a stop) and
/// at the last, passing through the others with the largest overlap that
/// keeps the limits (module docs).
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
    let (mut otg, mut input) = ruckig_input(&limits, start)?;
    for (i, w) in waypoints.iter().enumerate() {
        crate::smoothing::check_position(&limits, w, Position::Waypoint(i))?;
    }
    let mut legs: Vec<Leg> = Vec::with_capacity(waypoints.len());
    let mut from = start;
    for (i, w) in waypoints.iter().enumerate() {
        legs.push(leg(&mut otg, &mut input, from, *w, i)?);
        from = *w;
    }
    let dt = CONTROL_PERIOD;
    // Place the legs in time, corner by corner.
    let mut overlaps = vec![0.0; legs.len().saturating_sub(1)];
    let mut previous = 0.0;
    let stop_at = |i: usize| i + 1 == waypoints.len() || stops.get(i).copied().unwrap_or(false);
    // A leg leaving or reaching a stop keeps its half next to it straight
    // (rest-to-rest profiles are symmetric: half the time is half the way).
    let half = |leg: &Leg, near_stop: bool| {
        if near_stop {
            0.5 * leg.duration
        } else {
            leg.duration
        }
    };
    for k in 0..overlaps.len() {
        let (done, next) = legs.split_at_mut(k + 1);
        let (a, b) = (&done[k], &mut next[0]);
        let end = a.start + a.duration;
        let leaves_stop = k == 0 || stop_at(k - 1);
        let room = (half(a, leaves_stop) - previous)
            .min(half(b, stop_at(k + 1)))
            .max(0.0);
        let mut chosen = 0.0;
        if !stop_at(k) && room > dt {
            for c in 0..CANDIDATES {
                let o = room * (CANDIDATES - c) as f64 / CANDIDATES as f64;
                b.start = end - o;
                if overlap_ok(&limits, a, b, b.start, end) {
                    chosen = o;
                    break;
                }
            }
        }
        b.start = if chosen > 0.0 {
            end - chosen
        } else {
            // At rest, on a control cycle.
            (end / dt - 1e-9).ceil().max(0.0) * dt
        };
        overlaps[k] = chosen;
        previous = chosen;
    }
    // Sample.
    let end = legs.last().map_or(0.0, |l| l.start + l.duration);
    let count = if legs.is_empty() {
        0
    } else {
        ((end / dt - 1e-9).ceil() as usize).max(1)
    };
    let mut samples = Vec::with_capacity(count);
    let mut completed = 0;
    for i in 1..=count {
        let t = i as f64 * dt;
        while completed < legs.len() && legs[completed].start + legs[completed].duration <= t {
            completed += 1;
        }
        let mut q = if completed == 0 {
            start
        } else {
            legs[completed - 1].to
        };
        for l in legs[completed..].iter().take(2) {
            let [d, ..] = leg_state(l, t);
            for j in 0..DOF {
                q[j] += d[j];
            }
        }
        samples.push(q);
    }
    if let (Some(last), Some(w)) = (samples.last_mut(), waypoints.last()) {
        *last = *w;
    }
    let corners = overlaps
        .iter()
        .enumerate()
        .map(|(k, &overlap)| {
            if overlap <= 0.0 {
                return Corner {
                    overlap: 0.0,
                    miss: 0.0,
                    samples: 0..0,
                };
            }
            let b = &legs[k + 1];
            let first = ((b.start / dt).floor() as usize).saturating_sub(1);
            let end = (((legs[k].start + legs[k].duration) / dt).ceil() as usize).min(count);
            let w = waypoints[k];
            let miss = samples[first.min(end)..end]
                .iter()
                .map(|q| (0..DOF).map(|j| (q[j] - w[j]).abs()).fold(0.0, f64::max))
                .fold(f64::INFINITY, f64::min);
            Corner {
                overlap,
                miss: if miss.is_finite() { miss } else { 0.0 },
                samples: first..end,
            }
        })
        .collect();
    let at = legs
        .iter()
        .map(|l| {
            let i = ((l.start + l.duration) / dt - 1e-9).ceil().max(1.0) as usize;
            i.min(count).saturating_sub(1)
        })
        .collect();
    // Sample i is at (i + 1) dt: the first after a leg's start.
    let starts = legs
        .iter()
        .map(|l| ((l.start / dt + 1e-9).floor() as usize).min(count.saturating_sub(1)))
        .collect();
    Ok(Blended {
        samples,
        corners,
        at,
        starts,
    })
}
