//! The learned loop (README, "Learning"): at the start of each stage the
//! reasoner chooses (a product or the box, and the label) from the
//! products' positions alone; the sub-goal planner proposes each of the
//! stage's three sub-goals; the dynamics policy steps towards it (at most
//! [`MAX_POLICY_STEPS`] steps of at most 15 degrees, the wrist keeping the
//! cup down). A rollout that does not reach its sub-goal, or whose motion
//! would collide, hands the rest of the stage to RRT-Connect (a
//! [`Fallback`]), which goes to the learned sub-goals, or to the expert's
//! where no free motion reaches a learned one. A learned grip or release
//! more than [`SUCCESS_RADIUS`] off the product's centre or the slot is not
//! tried: RRT-Connect goes to the expert's. A decision that breaks the
//! order stops the arm (a [`Violation`]).

use super::reasoner::{f32s, graph, in_slot, lifted};
use super::station::{
    Connect, Leg, Load, MAX_RAISES, PlanningBudget, RAISE_STEP, Route, SUCCESS_RADIUS, Station,
    Unchecked, judge, leg_end,
};
use super::{checked_samples, expected_next};
use crate::collision::Held;
use crate::expert::{self, SubGoal, Suction, schedule};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use packwright_interface::outcome::{
    Failure, Fallback, Outcome, PlannerKind, ProductReport, Report, Shortfall, Stage, SubGoalKind,
    Violation,
};
use packwright_interface::record;
use packwright_interface::scene::CellScene;
use packwright_interface::{Graph, OrderTask, Policy, SequenceRule, SubGoalQuery, World};
use packwright_kinematics::body::{BOX_WALL, CUP_RADIUS, HELD_PADDING, PADDING};
use packwright_kinematics::{Arm, CupDownTip, Joints};
use std::f64::consts::{FRAC_PI_2, TAU};
use std::time::Instant;

/// Via points of the vertical retreat from a release, when the straight
/// joint motion up would touch the box.
const RETREAT_VIAS: usize = 5;
/// Segments of a learned descent down the vertical over its end, when the
/// straight joint motion would touch a wall ([`descent_vias`]).
const DESCENT_VIAS: usize = 5;
/// Most dynamics-policy steps per sub-goal: a 180-degree swing takes 12
/// full steps, and near 180 degrees, where both ways round are as short,
/// the policy takes a few steps to commit to one; the last steps, near the
/// sub-goal, are short.
pub const MAX_POLICY_STEPS: usize = 30;
/// A sub-goal where the suction switches (the cup on a product's top
/// face, a release in a slot), or the one just before it (the hover, above
/// the slot), is reached when the cup tip is this close (m): the motion
/// between them is then the straight descent the expert showed.
pub const REACHED: f64 = 0.002;
/// Any other via point (the lift, the approach) is reached when the cup tip
/// is this close (m).
pub const REACHED_VIA: f64 = 0.01;
/// The policy's steps end the back-up from a release this close (m) to
/// straight above it: within [`REACHED`], the end's millimetre or two
/// changed the blend into the next hover (one product of the golden
/// `pine_trio` took 0.15 s longer); this close, the executed motion is the
/// inverse kinematics' to the millisecond.
const BACK_UP_REACHED: f64 = 0.0005;

/// How close the cup tip must come to sub-goal `index` (from 0) of `stage`:
/// [`REACHED`] where the suction switches and just before, else
/// [`REACHED_VIA`]. The learned loop and DAgger's coach both use it.
pub fn tolerance(stage: Stage, index: usize) -> f64 {
    let switches = |k: usize| schedule(stage).get(k).is_some_and(|&s| s != Suction::Keep);
    if switches(index) || switches(index + 1) {
        REACHED
    } else {
        REACHED_VIA
    }
}

/// `q` moved by `step` (base, shoulder, elbow), the wrist turned so that the
/// cup keeps pointing down with the same yaw (UR-type wrists); why not when
/// that does not hold for this arm or leaves the joint limits. The base and
/// wrist 3 turn freely here (`q` and `q` ± 2π are the same pose): whoever
/// moves the arm along the steps brings them into the limits
/// ([`Arm::into_limits`]).
pub fn cup_down(
    arm: &Arm,
    base: &Isometry3<f64>,
    q: &Joints,
    step: [f64; 3],
) -> Result<Joints, Shortfall> {
    cup_down_from(arm, base, q, &arm.flange_pose(base, q), step).map(|(next, _)| next)
}

/// [`cup_down`] from `q` whose flange pose `flange` is known, with the
/// flange pose of the joints it returns: stepping along, each pose is
/// computed once (forward kinematics is most of a policy step's own work).
fn cup_down_from(
    arm: &Arm,
    base: &Isometry3<f64>,
    q: &Joints,
    flange: &Isometry3<f64>,
    step: [f64; 3],
) -> Result<(Joints, Isometry3<f64>), Shortfall> {
    let next = stepped(q, step);
    let after = arm.flange_pose(base, &next);
    if flange.rotation.angle_to(&after.rotation) >= 1e-6 {
        return Err(Shortfall::Limits {
            joint: None,
            value: f64::NAN,
        });
    }
    within_limits(arm, next).map(|next| (next, after))
}

/// `q` moved by `step` (base, shoulder, elbow), wrist 1 against shoulder
/// and elbow, wrist 3 with the base.
fn stepped(q: &Joints, step: [f64; 3]) -> Joints {
    let mut next = *q;
    next[0] += step[0];
    next[1] += step[1];
    next[2] += step[2];
    next[3] -= step[1] + step[2];
    next[5] += step[0];
    next
}

/// `q`, or which of joints 2-5 left its limits (the base and wrist 3 turn
/// freely here: [`cup_down`]).
fn within_limits(arm: &Arm, q: Joints) -> Result<Joints, Shortfall> {
    match (1..5).find(|&j| !arm.limits[j].contains(q[j])) {
        Some(j) => Err(Shortfall::Limits {
            joint: Some(j),
            value: q[j],
        }),
        None => Ok(q),
    }
}

/// The dynamics policy's steps from `start` towards the cup-tip position
/// `goal`, with forward kinematics (after the first step the tip in
/// closed form, [`CupDownTip`], where the arm has one), as the learned
/// loop takes them: at
/// most [`MAX_POLICY_STEPS`], each `action(q, delta)` (base, shoulder,
/// elbow, radians; delta = goal − cup tip) scaled down to 15 degrees, the
/// wrist keeping the cup down; until the tip is within `tolerance`. The
/// joints after each step, or why the goal was not reached. DAgger's
/// rollouts step through this too.
pub fn policy_steps(
    arm: &Arm,
    base: &Isometry3<f64>,
    suction: f64,
    start: Joints,
    goal: [f64; 3],
    tolerance: f64,
    action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
) -> Result<Vec<Joints>, Shortfall> {
    let mut q = start;
    let mut flange = arm.flange_pose(base, &q);
    let mut tip = Arm::tip_of(&flange, suction);
    // After the first step, which checks that the wrist keeps the cup
    // down, the tip in closed form where the arm has one (forward
    // kinematics was most of a step's own work).
    let mut closed: Option<CupDownTip> = None;
    let mut steps = Vec::with_capacity(MAX_POLICY_STEPS);
    loop {
        let delta: [f64; 3] = std::array::from_fn(|j| goal[j] - tip[j]);
        let away = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
        if away <= tolerance {
            return Ok(steps);
        }
        if steps.len() == MAX_POLICY_STEPS {
            return Err(Shortfall::Short {
                steps: MAX_POLICY_STEPS,
                distance_m: away,
            });
        }
        let step = record::clip(action(&q, delta).map(f64::from));
        match &closed {
            Some(c) => {
                q = within_limits(arm, stepped(&q, step))?;
                tip = c.at(&q).unwrap_or_else(|| arm.tool_tip(base, &q, suction));
            }
            None => {
                (q, flange) = cup_down_from(arm, base, &q, &flange, step)?;
                tip = Arm::tip_of(&flange, suction);
                closed = arm.cup_down_tip(base, &q, &tip);
            }
        }
        steps.push(q);
    }
}

/// How far round the base (rad) a goal must be from the cup tip for the
/// policy's steps that fall short to be tried again through
/// [`swing_via`]: a third of a turn. Almost behind the arm, turning
/// either way is as short, the policy turns the base little and folds
/// the elbow instead (measured on a development cell: the elbow past its
/// limit, 0.9 m from the goal).
const WIDE_SWING: f64 = TAU / 3.0;

/// A via point half way round the base from cup tip `from` to `goal`
/// (world), at their mean distance from the base's axis and the higher
/// of their heights, turning the way that leaves base joint `q0` nearer
/// the middle of its range (0) at the end; `None` when `goal` is less
/// than [`WIDE_SWING`] round from `from`.
pub fn swing_via(
    base: &Isometry3<f64>,
    q0: f64,
    from: [f64; 3],
    goal: [f64; 3],
) -> Option<[f64; 3]> {
    let local = |p: [f64; 3]| base.inverse_transform_point(&Point3::from(p));
    let (a, b) = (local(from), local(goal));
    let turn = record::short_way(b.y.atan2(b.x) - a.y.atan2(a.x));
    if turn.abs() < WIDE_SWING {
        return None;
    }
    let other = turn - TAU.copysign(turn);
    let swing = if (q0 + turn).abs() <= (q0 + other).abs() {
        turn
    } else {
        other
    };
    let angle = a.y.atan2(a.x) + swing / 2.0;
    let radius = (a.x.hypot(a.y) + b.x.hypot(b.y)) / 2.0;
    let via = Point3::new(radius * angle.cos(), radius * angle.sin(), a.z.max(b.z));
    Some((base * via).coords.into())
}

/// Via points from `start` across to above `end`'s cup tip (at the
/// start's height; none when it is already within `tolerance`), then down
/// the vertical line to it, each reached by the policy's steps
/// ([`policy_steps`]) within `tolerance`, then `end`: at most
/// [`DESCENT_VIAS`] segments. A straight joint motion down into a slot
/// bows sideways (measured: 5-7 mm at the middle of a 14 cm descent),
/// and a learned "above the slot" is a few millimetres beside the learned
/// release, so that even the tip's straight line slants: either way a
/// held product enters a narrow box beside its slot and touches the
/// wall. Going down vertically over the learned release, it enters where
/// it is let go. `None` when the motion is not a descent (it goes
/// sideways at least half as far as it goes down), or the steps fall
/// short or leave the limits.
pub fn descent_vias(
    arm: &Arm,
    base: &Isometry3<f64>,
    suction: f64,
    start: Joints,
    end: Joints,
    tolerance: f64,
    action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
) -> Option<Vec<Joints>> {
    let tip = |q: &Joints| -> [f64; 3] { arm.tool_tip(base, q, suction).coords.into() };
    let (a, b) = (tip(&start), tip(&end));
    let drop = a[2] - b[2];
    if drop <= 0.0 || 2.0 * (b[0] - a[0]).hypot(b[1] - a[1]) >= drop {
        return None;
    }
    let mut near = start;
    let mut vias = Vec::with_capacity(DESCENT_VIAS);
    for i in 1..DESCENT_VIAS {
        let f = (i - 1) as f64 / (DESCENT_VIAS - 1) as f64;
        let via = [b[0], b[1], a[2] + (b[2] - a[2]) * f];
        if i == 1 && (via[0] - a[0]).hypot(via[1] - a[1]) <= tolerance {
            continue;
        }
        let steps = policy_steps(arm, base, suction, near, via, tolerance, action).ok()?;
        near = steps.last().copied().unwrap_or(near);
        if !arm.within_limits(&near) {
            return None;
        }
        vias.push(near);
    }
    vias.push(end);
    Some(vias)
}

/// How far (rad) past its limit the base or wrist 3 may end a motion that
/// starts within it and be held at the limit instead: brought a whole turn
/// back, a release a few milliradians past would spin the arm a full turn
/// on its way down into the box (measured on a development cell: 6 mrad
/// past, the cup against the box's outside). Held, the cup tip ends at
/// most this angle times the reach from where the steps put it.
const LIMIT_SLACK: f64 = 0.01;

/// `q` with the base and wrist 3 held at their limits where they are at
/// most [`LIMIT_SLACK`] past them and `start` is within them.
fn held_at_limits(arm: &Arm, start: &Joints, q: Joints) -> Joints {
    let mut held = q;
    for j in [0, q.len() - 1] {
        let l = &arm.limits[j];
        let clamped = q[j].clamp(l.lower, l.upper);
        if l.contains(start[j]) && (q[j] - clamped).abs() <= LIMIT_SLACK {
            held[j] = clamped;
        }
    }
    held
}

/// Room (rad) a motion's end leaves to the limits of the base and wrist 3,
/// the joints that turn freely: the sub-goals after a swing move them a
/// few degrees further.
const TURN_ROOM: f64 = 0.1;

/// `end` with the base or wrist 3 a whole turn the other way where it ends
/// within [`TURN_ROOM`] of its limit, when the other turn has that room
/// and is at most a quarter turn farther from `start`: a swing of about
/// half a turn (either way round is as short) that ends at the base's
/// limit leaves the descent onto the product a few milliradians on only a
/// whole turn back, and that swing sweeps the arm through the cell
/// (probe cells 3063 and 3081: the cup into the box).
fn with_room(arm: &Arm, start: &Joints, end: Joints) -> Joints {
    let mut out = end;
    for j in [0, end.len() - 1] {
        let l = &arm.limits[j];
        let room = |v: f64| (v - l.lower).min(l.upper - v);
        if room(end[j]) >= TURN_ROOM {
            continue;
        }
        let other = if end[j] - l.lower < l.upper - end[j] {
            end[j] + TAU
        } else {
            end[j] - TAU
        };
        let farther = (other - start[j]).abs() - (end[j] - start[j]).abs();
        if room(other) >= TURN_ROOM && farther <= FRAC_PI_2 {
            out[j] = other;
        }
    }
    out
}

/// How far above the expert's release, or the learned release when that
/// is higher, (m) a learned release whose motion collides may be raised: a
/// learned release a little too low (the held product pressed into the
/// floor) is let go 1 or 2 cm up, as the expert lets go 5 mm up; one
/// beside a wall is not raised until it is clear of the wall (measured:
/// released 9 cm up, a product dropped 29 mm off its slot). A learned
/// release a little higher than the expert's may rise as many steps as
/// the expert's (a short cup in a deep box, where wrist 3 meets the rim
/// unless both are raised twice).
const COLLIDING_RELEASE_RAISE: f64 = 0.02;

/// How far (m) a colliding release may be moved to keep its product and
/// the cup inside the box's walls ([`Inside::keep`]; the policy then
/// reaches it within [`BACK_UP_REACHED`]): about twice the
/// sub-goal planner's error at a release on cells it was not taught, well
/// within [`SUCCESS_RADIUS`].
const KEEP_INSIDE: f64 = 0.006;

/// How far (m) a kept release ([`Inside`]) stays inside the padded
/// walls: it is reached within [`BACK_UP_REACHED`], and as far again is
/// left for rounding and the flange's small tilt.
const KEPT_MARGIN: f64 = 2.0 * BACK_UP_REACHED;

/// Whether `rolled` is a release (`switch`) whose motion would collide.
fn release_collides(switch: Suction, rolled: &Result<Route, Shortfall>) -> bool {
    switch == Suction::Off && matches!(rolled, Err(Shortfall::Collides { .. }))
}

/// What stopped a learned run early.
enum Halt {
    Violation(Violation),
    Failed(Failure),
}

impl From<Failure> for Halt {
    fn from(f: Failure) -> Halt {
        Halt::Failed(f)
    }
}

/// Why the run stopped: a decision that broke the order, or a failure
/// while handling a product (already in its report row).
enum Stopped {
    Violation(Violation),
    Failed(Failure),
}

/// A stage's three sub-goals as proposed, and where the cup tip stopped
/// at each.
struct Reached {
    goals: [[f64; 3]; 3],
    tips: [[f64; 3]; 3],
}

/// One stage's inputs.
struct StagePlan<'l> {
    stage: Stage,
    product: &'l str,
    /// The selected feature: the product's centre (picking) or its box's
    /// top centre (placing).
    feature: [f64; 3],
    /// The handled product's height.
    height: f64,
    /// Picking: the sensed top face, where the cup's descent stops.
    contact: Option<f64>,
    load: Load<'l>,
    /// Picking: the product's size; the sub-goals after the grip (the
    /// lift) carry it off where it stood, hanging from the cup as the
    /// planned contact leaves it.
    gripped: Option<[f64; 3]>,
    /// The expert's sub-goals for the stage: where RRT-Connect goes
    /// instead of a learned sub-goal it cannot reach.
    expert: [SubGoal; 3],
    /// Placing: where the cup tip may let go with the held product and
    /// the cup clear of the box's walls ([`Inside`]).
    inside: Option<Inside>,
}

/// The cup-tip positions (x and y, m) from which a held product, let go,
/// stands clear of its box's inner walls by its padding and
/// [`KEPT_MARGIN`], with the cup clear of them too when the tip is
/// below the rim: the box's inside shrunk by the product's half-extents in
/// the world (moved by where the product hangs from the cup) and by the
/// cup's padded radius. An axis where they do not fit is left as it is.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Inside {
    /// For the product: lowest and highest x, then y.
    product: [(f64, f64); 2],
    /// For the cup.
    cup: [(f64, f64); 2],
    /// The box's rim height: the cup goes into the box below it.
    rim: f64,
}

impl Inside {
    /// For a product of `size` hanging `grip` (world x, y: its centre
    /// minus the cup tip) from a flange turned by `flange`, let go in
    /// `cell`'s box `b`.
    fn new(
        cell: &CellScene,
        b: usize,
        size: [f64; 3],
        grip: [f64; 2],
        flange: &UnitQuaternion<f64>,
    ) -> Option<Inside> {
        let held = cell.boxes.get(b)?;
        let m = flange.to_rotation_matrix().into_inner();
        let half = [size[0] / 2.0, size[1] / 2.0, size[2] / 2.0];
        let extent = |row: usize| (0..3).map(|j| m[(row, j)].abs() * half[j]).sum::<f64>();
        // The inside's bounds on `axis` shrunk by `by`, for a tip `shift`
        // from the body kept inside.
        let bound = |axis: usize, by: f64, shift: f64| {
            let c = held.centre[axis];
            let w = held.size[axis] / 2.0 - BOX_WALL - by - KEPT_MARGIN;
            (c - w - shift, c + w - shift)
        };
        Some(Inside {
            product: [0, 1].map(|a| bound(a, extent(a) + HELD_PADDING, grip[a])),
            cup: [0, 1].map(|a| bound(a, CUP_RADIUS + PADDING, 0.0)),
            rim: held.size[2],
        })
    }

    /// `goal` moved into the inside on each axis where everything fits
    /// (the nearest such point; `goal` itself when it is inside already);
    /// `None` when nothing fits on either axis.
    fn keep(&self, goal: [f64; 3]) -> Option<[f64; 3]> {
        let mut kept = goal;
        let mut fits = false;
        for axis in 0..2 {
            let (mut lo, mut hi) = self.product[axis];
            if goal[2] < self.rim {
                lo = lo.max(self.cup[axis].0);
                hi = hi.min(self.cup[axis].1);
            }
            if lo <= hi {
                kept[axis] = goal[axis].clamp(lo, hi);
                fits = true;
            }
        }
        fits.then_some(kept)
    }
}

/// The learned loop over the shared stepping primitives.
struct Learned<'a, W: World> {
    station: Station<'a, W>,
    policy: &'a dyn Policy,
    /// The policy's taught sequence rule (its chain order).
    rule: SequenceRule,
    seed: u64,
    fallbacks: Vec<Fallback>,
}

impl<W: World> Learned<'_, W> {
    /// The dynamics policy's action at joints `q` for `delta` (sub-goal −
    /// cup tip).
    fn act(&self, q: &Joints, delta: [f64; 3]) -> [f32; 3] {
        self.policy
            .action(f32s(delta), [q[0] as f32, q[1] as f32, q[2] as f32])
    }

    /// The dynamics policy's motion from `start` to `goal`: the checked
    /// commands, or why not. The steps' end point is joined straight when
    /// that is free, else through every step. `first_action_us` gets the
    /// time of the first policy call.
    fn rollout(
        &self,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        load: Load,
        first_action_us: &mut Option<f64>,
    ) -> Result<Route, Shortfall> {
        let s = &self.station;
        let (arm, base, suction) = (s.arm, &s.base, s.task.cell.suction);
        let steps = policy_steps(
            arm,
            base,
            suction,
            start,
            goal,
            tolerance,
            &mut |q, delta| {
                // Only the first call is timed (`get_or_insert` would read the
                // clock at every step).
                let called = first_action_us.is_none().then(Instant::now);
                let action = self.act(q, delta);
                if let Some(called) = called {
                    *first_action_us = Some(called.elapsed().as_secs_f64() * 1e6);
                }
                action
            },
        );
        // A goal far round the base the policy fell short of: through a
        // via point half way round, the way the base has room.
        let steps = steps.or_else(|why| {
            let act = &mut |q: &Joints, delta: [f64; 3]| self.act(q, delta);
            let from: [f64; 3] = s.tip(&start);
            let via = swing_via(base, start[0], from, goal).ok_or(why.clone())?;
            let mut steps = policy_steps(arm, base, suction, start, via, REACHED_VIA, act)
                .map_err(|_| why.clone())?;
            let near = steps.last().copied().unwrap_or(start);
            let rest =
                policy_steps(arm, base, suction, near, goal, tolerance, act).map_err(|_| why)?;
            steps.extend(rest);
            Ok(steps)
        })?;
        let Some(last) = steps.last() else {
            return Ok(Route {
                waypoints: Vec::new(),
                samples: Vec::new(),
            });
        };
        // The base and wrist 3 may have turned past their limits: the same
        // pose a whole turn back, which the straight motion reaches the
        // other way round; a few milliradians past, held at the limit.
        let last = &held_at_limits(s.arm, &start, *last);
        let end = s.arm.into_limits(last, &start).ok_or_else(|| {
            let joint = (0..last.len()).find(|&j| !s.arm.limits[j].contains(last[j]));
            Shortfall::Limits {
                joint,
                value: joint.map_or(f64::NAN, |j| last[j]),
            }
        })?;
        let end = with_room(s.arm, &start, end);
        let why = |e| match e {
            Unchecked::Collides(hit) => Shortfall::Collides { hit },
            Unchecked::Smoothing(reason) => Shortfall::Smoothing { reason },
        };
        let route = |waypoints: Vec<Joints>| {
            checked_samples(s.arm, &s.checker, start, &waypoints, load)
                .map(|samples| Route { waypoints, samples })
        };
        match route(vec![end]) {
            Ok(route) => Ok(route),
            Err(straight) => {
                // A descent (into a slot, onto a top face) whose straight
                // joint motion bows sideways into a wall: across to above
                // its end, then down the vertical, as the expert's descent
                // and the back-up from a release go.
                let act = &mut |q: &Joints, delta: [f64; 3]| self.act(q, delta);
                if let Some(vias) = descent_vias(arm, base, suction, start, end, tolerance, act)
                    && let Ok(route) = route(vias)
                {
                    return Ok(route);
                }
                // Through every step instead (passing through them), when
                // they stay within the limits.
                if steps.iter().all(|q| s.arm.within_limits(q)) {
                    route(steps).map_err(|_| why(straight))
                } else {
                    Err(why(straight))
                }
            }
        }
    }

    /// The rest of a stage's sub-goal `k` (from 0) by RRT-Connect: to
    /// the learned `goal` (raised up to `ceiling` if it is a release), else,
    /// when no free motion reaches it or there is none, to the expert's
    /// sub-goal `k` of the stage (raised up to the expert's previous
    /// sub-goal's height; a release whose straight descent from `start`
    /// collides, through the expert's sub-goal before it). The route, and
    /// whether it went to the expert's sub-goal; the learned sub-goal's
    /// failure when neither is reached.
    fn fall_back(
        &self,
        k: usize,
        start: Joints,
        goal: Option<SubGoal>,
        expert: &[SubGoal; 3],
        load: Load,
        ceiling: f64,
    ) -> Result<(Route, bool), Failure> {
        let s = &self.station;
        let rrt = |goal: &SubGoal, ceiling: f64| {
            let solved = s.solve(goal, k + 1, &start, 0.0, load, ceiling)?;
            s.route_solved(
                Connect::Rrt { seed: self.seed },
                k + 1,
                start,
                solved,
                0.0,
                load,
            )
            .map(|(_, route)| route)
        };
        let experts = || {
            let ceiling = match k {
                0 => expert[0].tip[2],
                _ if expert[k].suction == Suction::Off => expert[k - 1].tip[2],
                _ => expert[k].tip[2],
            };
            rrt(&expert[k], ceiling)
                .or_else(|direct| match k {
                    // A release is solved with its straight descent from
                    // where the arm is: from a learned "above the slot" a
                    // few millimetres off, that slants into the wall of a
                    // narrow box. Through the expert's "above the slot"
                    // first, then down, as the expert goes.
                    1.. if expert[k].suction == Suction::Off && !s.late() => {
                        let above = &expert[k - 1];
                        let how = Connect::Rrt { seed: self.seed };
                        let detour = || -> Result<Route, Failure> {
                            let solved = s.solve(above, k, &start, 0.0, load, above.tip[2])?;
                            let (over, first) = s.route_solved(how, k, start, solved, 0.0, load)?;
                            let solved = s.solve(&expert[k], k + 1, &over, 0.0, load, ceiling)?;
                            let (_, down) = s.route_solved(how, k + 1, over, solved, 0.0, load)?;
                            Ok(Route {
                                waypoints: [first.waypoints, down.waypoints].concat(),
                                samples: [first.samples, down.samples].concat(),
                            })
                        };
                        detour().map_err(|_| direct)
                    }
                    _ => Err(direct),
                })
                .map(|route| (route, true))
        };
        let Some(goal) = goal else {
            return experts();
        };
        match rrt(&goal, ceiling) {
            Ok(route) => Ok((route, false)),
            Err(
                learned @ (Failure::Unreachable { .. }
                | Failure::WouldCollide { .. }
                | Failure::NoPath { .. }),
            ) if !s.late() => experts().map_err(|_| learned),
            Err(other) => Err(other),
        }
    }

    /// One stage with learned sub-goals and motions, planned from where
    /// the `pending` legs of the stage before end (else from where the arm
    /// is) and sent after them ([`Station::send_legs`]; with `keep_tail`,
    /// the legs after the last suction switch are returned unsent): the
    /// sub-goals used.
    fn stage(
        &mut self,
        plan: &StagePlan,
        pending: Vec<Leg>,
        keep_tail: bool,
    ) -> Result<(Reached, Vec<Leg>), Failure> {
        let mut fallen = false;
        let mut goals = [[0.0; 3]; 3];
        let mut tips = [[0.0; 3]; 3];
        let base = f32s(self.station.task.cell.base);
        // The stage is planned to its end before the arm moves, each
        // sub-goal from where the one before leaves the arm.
        let mut start = leg_end(&pending).unwrap_or_else(|| self.station.world.observe().joints);
        let mut legs = pending;
        // The product as it will hang once gripped.
        let mut gripped: Option<Held> = None;
        let kinds = SubGoalKind::of(plan.stage);
        for ((k, switch), kind) in schedule(plan.stage).into_iter().enumerate().zip(kinds) {
            let load = gripped.as_ref().map_or(plan.load, Load::holding);
            // The motion onto a top face is the guarded descent.
            let load = if switch == Suction::On {
                load.guarded(self.station.task.cell.descent)
            } else {
                load
            };
            let started = self.station.begin();
            let tool = f32s(self.station.tip(&start));
            let mut goal = self
                .policy
                .subgoal(&SubGoalQuery {
                    stage: plan.stage,
                    index: k,
                    feature: f32s(plan.feature),
                    tool,
                    height: plan.height as f32,
                    base,
                })
                .map(f64::from);
            // A guarded contact: the cup meets the top face where the
            // product is sensed (its centre plus half its height), as a
            // vacuum sensor would stop the descent; x and y stay learned.
            if let (Suction::On, Some(top)) = (switch, plan.contact) {
                goal[2] = top;
            }
            if goal.iter().any(|v| !v.is_finite()) {
                return Err(Failure::NonFiniteSubGoal { subgoal: k + 1 });
            }
            goals[k] = goal;
            let subgoal_us = started.elapsed().as_secs_f64() * 1e6;
            // A release the wrist cannot reach is raised, as the expert's
            // is, up to the previous sub-goal's height.
            let ceiling = if switch == Suction::Off && k > 0 {
                goals[k - 1][2]
            } else {
                goal[2]
            };
            // A learned grip or release off the product's centre or the slot
            // would pack nothing, however well the arm reached it: the
            // expert's sub-goal is used instead (by RRT-Connect).
            let off = (switch != Suction::Keep)
                .then(|| {
                    let e = plan.expert[k].tip;
                    (goal[0] - e[0]).hypot(goal[1] - e[1])
                })
                .filter(|d| *d > SUCCESS_RADIUS);
            let rolled = (!fallen && off.is_none()).then(|| {
                let tolerance = tolerance(plan.stage, k);
                let mut first_action_us = None;
                // The first attempt's shortfall is the one reported.
                let mut rolled = self.rollout(start, goal, tolerance, load, &mut first_action_us);
                // A release whose motion collides is raised only as far
                // as one too low needs: up to COLLIDING_RELEASE_RAISE above
                // the expert's (or itself, when higher).
                let ceiling = if release_collides(switch, &rolled) {
                    ceiling.min(plan.expert[k].tip[2].max(goal[2]) + COLLIDING_RELEASE_RAISE)
                } else {
                    ceiling
                };
                let mut raised = 1;
                while rolled.is_err()
                    && raised <= MAX_RAISES
                    && !self.station.late()
                    && goal[2] + RAISE_STEP * f64::from(raised) <= ceiling
                {
                    let higher = [goal[0], goal[1], goal[2] + RAISE_STEP * f64::from(raised)];
                    if let Ok(samples) =
                        self.rollout(start, higher, tolerance, load, &mut first_action_us)
                    {
                        rolled = Ok(samples);
                    }
                    raised += 1;
                }
                // A release whose product or cup would touch the box's
                // wall (a learned sub-goal a few millimetres off in a
                // tight box): moved just inside the walls, when that is
                // near, and reached closely (a sub-goal already inside by
                // less than the usual reach too); no lower than the
                // expert's, which lets go 5 mm up (a learned release a
                // little low, held against the floor, was raised, but
                // moved inside at its own height).
                let not_low = [goal[0], goal[1], goal[2].max(plan.expert[k].tip[2])];
                if release_collides(switch, &rolled)
                    && !self.station.late()
                    && let Some(kept) = plan.inside.and_then(|i| i.keep(not_low))
                    && (kept[0] - goal[0]).hypot(kept[1] - goal[1]) <= KEEP_INSIDE
                    && let Ok(route) =
                        self.rollout(start, kept, BACK_UP_REACHED, load, &mut first_action_us)
                {
                    goals[k] = kept;
                    rolled = Ok(route);
                }
                if let Some(action_us) = first_action_us {
                    self.station.timing.network_us.push(subgoal_us + action_us);
                }
                rolled
            });
            // A release whose motion still collides (the held product
            // against a wall: a learned release a few millimetres off in a
            // tight slot) is not tried by RRT-Connect either, which would
            // raise it until free: let go from higher up, the product
            // would drop and land off its slot. The expert's release is
            // used instead.
            let colliding = rolled.as_ref().is_some_and(|r| release_collides(switch, r));
            let route = match rolled {
                Some(Ok(route)) => route,
                other => {
                    let why = match (fallen, off, other) {
                        (false, Some(distance_m), _) => Some(Shortfall::OffTarget { distance_m }),
                        (_, _, Some(Err(why))) => Some(why),
                        _ => None,
                    };
                    if let Some(why) = why {
                        self.fallbacks.push(Fallback {
                            product: plan.product.to_owned(),
                            stage: plan.stage,
                            subgoal: k + 1,
                            why,
                            expert_from: None,
                        });
                    }
                    fallen = true;
                    let target = (off.is_none() && !colliding).then_some(SubGoal {
                        tip: goal,
                        suction: switch,
                    });
                    let (route, expert) =
                        self.fall_back(k, start, target, &plan.expert, load, ceiling)?;
                    if expert {
                        goals[k] = plan.expert[k].tip;
                        if let Some(f) = self.fallbacks.last_mut()
                            && f.product == plan.product
                            && f.stage == plan.stage
                        {
                            f.expert_from.get_or_insert(k + 1);
                        }
                    }
                    route
                }
            };
            let elapsed = self.station.spend(k + 1, started)?;
            self.station.timing.subgoal(kind, elapsed * 1e6);
            if let Some(end) = route.waypoints.last() {
                start = *end;
            }
            tips[k] = self.station.tip(&start);
            self.station.subgoals.push(tips[k]);
            legs.push(Leg::new(route, switch, load));
            if let (Suction::On, Some(size), Some(top)) = (switch, plan.gripped, plan.contact) {
                gripped = Some(self.gripped_at(&start, plan, size, top));
            }
        }
        let tail = self.station.send_legs(legs, keep_tail)?;
        Ok((Reached { goals, tips }, tail))
    }

    /// The product `plan` picks, of `size`, whose top face is at height
    /// `top`, as it hangs from the cup once the suction grips it with the
    /// arm at `contact` (the learned contact is within a tolerance of the
    /// face's centre: the product hangs that far off the cup's axis, and
    /// higher when the tip went below the face), leaving where it stood.
    fn gripped_at(&self, contact: &Joints, plan: &StagePlan, size: [f64; 3], top: f64) -> Held {
        let s = &self.station;
        let tip = s.tip(contact);
        let flange = s.arm.flange_pose(&s.base, contact).rotation;
        let off = Vector3::new(
            plan.feature[0] - tip[0],
            plan.feature[1] - tip[1],
            top - tip[2],
        );
        Held::under_cup(
            plan.product,
            size,
            s.task.cell.suction,
            flange.inverse() * off,
        )
        .leaving_support()
    }

    /// The checked way straight up to the height of `above` (the learned
    /// "above the slot" sub-goal) from the released product `name`, its
    /// end found by the dynamics policy's steps (by inverse kinematics
    /// where they fall short); not sent: it is sent with the next
    /// product's hover (or alone at the end of the run).
    fn retreat(&mut self, above: [f64; 3], name: &str) -> Result<Leg, Failure> {
        let load = Load::ignoring(name);
        // The released product where it lies (its last observed place was
        // under the cup). Observed before the planning is timed, as the
        // other planners observe before they plan their back-up.
        let obs = self.station.world.observe();
        self.station.sync_products(&obs);
        let started = self.station.begin();
        let s = &self.station;
        let start = obs.joints;
        // Straight up from where the cup let go: a learned "above" a few
        // millimetres off in x or y would drag the cup along a wall.
        let [x, y, z0] = s.tip(&start);
        let up = SubGoal {
            tip: [x, y, above[2]],
            suction: Suction::Keep,
        };
        // The dynamics policy's steps up, as every learned motion goes
        // (a step or two, where inverse kinematics weighs every branch);
        // inverse kinematics where they fall short.
        let act = &mut |q: &Joints, delta: [f64; 3]| self.act(q, delta);
        let stepped = policy_steps(
            s.arm,
            &s.base,
            s.task.cell.suction,
            start,
            up.tip,
            BACK_UP_REACHED,
            act,
        )
        .ok()
        .and_then(|steps| s.arm.into_limits(steps.last()?, &start));
        let target = match stepped {
            Some(q) => q,
            None => s.solve(&up, 1, &start, 0.0, load, above[2])?.joints,
        };
        let route = match s.checked(1, start, &[target], load) {
            Ok(route) => route,
            // A straight joint motion bows sideways; from a slot near a
            // wall, go up a vertical line of via points instead.
            Err(straight) => {
                let mut near = start;
                let mut vias = Vec::new();
                for i in 1..=RETREAT_VIAS {
                    let z = z0 + (above[2] - z0) * i as f64 / RETREAT_VIAS as f64;
                    let via = SubGoal {
                        tip: [x, y, z],
                        suction: Suction::Keep,
                    };
                    near = s.solve(&via, 1, &near, 0.0, load, z)?.joints;
                    vias.push(near);
                }
                s.checked(1, start, &vias, load).map_err(|_| straight)?
            }
        };
        // Timed as a sub-goal, as the other planners' back-up is.
        let elapsed = self.station.spend(1, started)?;
        self.station
            .timing
            .subgoal(SubGoalKind::BackUp, elapsed * 1e6);
        Ok(Leg::new(route, Suction::Keep, load))
    }

    /// The reasoner's decision, timed.
    fn reason(&mut self, graph: &Graph) -> packwright_interface::Choice {
        let decided = Instant::now();
        let choice = self.policy.reason(graph);
        self.station
            .timing
            .decision_us
            .push(decided.elapsed().as_secs_f64() * 1e6);
        choice
    }

    /// Picks the product the reasoner chooses and places it where it says:
    /// the product and slot handled, or why the run stops.
    fn product(&mut self, rows: &mut [ProductReport]) -> Result<(), Stopped> {
        let task = self.station.task;
        let obs = self.station.world.observe();
        let (g, which) = graph(task, &obs.products, &self.rule, None);
        let choice = self.reason(&g);
        let stop = Stopped::Violation;
        let node = choice.node.ok_or(stop(Violation::BoxWithNothingHeld))?;
        let p = which[node];
        let product = task.products[p].name.clone();
        let row = task
            .assignment
            .iter()
            .position(|&(q, _)| q == p)
            .ok_or_else(|| {
                stop(Violation::NotSelected {
                    product: product.clone(),
                })
            })?;
        if in_slot(task, &obs.products, p) {
            return Err(stop(Violation::AlreadyInSlot { product }));
        }
        if choice.label != 0 {
            return Err(stop(Violation::LabelWhenPicking {
                product,
                label: choice.label,
            }));
        }
        let s = task.assignment[row].1;
        self.station.restart_clock();
        let result = self.manipulate(p, s).map(|backup| {
            self.station.keep_backup(vec![backup], row);
        });
        self.station.measure(&mut rows[row], p, s);
        let handled = match result {
            // A placing decision that broke the order: the product was
            // not put anywhere (its row stays "not attempted").
            Err(Halt::Violation(v)) => return Err(Stopped::Violation(v)),
            Err(Halt::Failed(why)) => Err(why),
            Ok(()) => Ok(()),
        };
        judge(&mut rows[row], handled).map_err(Stopped::Failed)
    }

    /// Picks product `p` and places it in slot `s`, after the kept back-up
    /// from the product before (blended into the hover): the way back up
    /// from this release, checked, unsent.
    fn manipulate(&mut self, p: usize, s: usize) -> Result<Leg, Halt> {
        let task = self.station.task;
        let cell = &task.cell;
        let spec = &task.products[p];
        let name = spec.name.as_str();
        let obs = self.station.world.observe();
        self.station.sync_products(&obs);
        let (centre, _) = obs.find(name).ok_or(Failure::Disappeared)?;
        // The back-up before is sent with the hover, and the lift with the
        // carry, blended into them.
        let backup = self.station.take_backup();
        let (picked, lift) = self.stage(
            &StagePlan {
                stage: Stage::Picking,
                product: name,
                feature: centre,
                height: spec.size[2],
                contact: Some(centre[2] + spec.size[2] / 2.0),
                load: Load::ignoring(name),
                gripped: Some(spec.size),
                expert: expert::picking(centre, spec.size[2], cell.lift),
                inside: None,
            },
            backup,
            true,
        )?;
        // Placing: the reasoner sees the held product raised by the lift
        // (about to be sent with the carry).
        let obs = self.station.world.observe();
        let mut seen = obs.products.clone();
        if !lift.is_empty() {
            lifted(task, &mut seen, p);
        }
        let (g, which) = graph(task, &seen, &self.rule, Some(p));
        let choice = self.reason(&g);
        if let Some(n) = choice.node {
            return Err(Halt::Violation(Violation::ProductWhileHolding {
                chosen: task.products[which[n]].name.clone(),
                held: name.to_owned(),
            }));
        }
        if choice.label != s + 1 {
            return Err(Halt::Violation(Violation::WrongSlot {
                product: name.to_owned(),
                label: choice.label,
                slot: cell.slots[s].name.clone(),
                expected: s + 1,
            }));
        }
        // The cup met the top face where the learned sub-goal put it, a
        // few millimetres from the product's centre (sensed before the
        // pick): the product hangs that far off the cup. The checker
        // carries it there, and the cup aims that much beside the slot so
        // that the product lands centred. The cup keeps its yaw while it
        // carries, so the offset stays the same in the world.
        let contact = picked.tips[1];
        let grip = [centre[0] - contact[0], centre[1] - contact[1]];
        let raised = leg_end(&lift).unwrap_or(obs.joints);
        let flange = self
            .station
            .arm
            .flange_pose(&self.station.base, &raised)
            .rotation;
        let held = Held::under_cup(
            name,
            spec.size,
            cell.suction,
            flange.inverse() * Vector3::new(grip[0], grip[1], 0.0),
        );
        self.station.sync_products(&obs);
        let rim = task.slot_rim(s);
        let slot = cell.slots[s].position;
        let expert = expert::placing(
            picked.tips[2],
            [slot[0] - grip[0], slot[1] - grip[1]],
            spec.size[2],
            expert::box_height(cell, s),
            [cell.base[0], cell.base[1]],
        );
        let (placed, _) = self.stage(
            &StagePlan {
                stage: Stage::Placing,
                product: name,
                feature: [rim[0] - grip[0], rim[1] - grip[1], rim[2]],
                height: spec.size[2],
                contact: None,
                load: Load::holding(&held),
                gripped: None,
                expert,
                inside: Inside::new(cell, cell.slots[s].box_index, spec.size, grip, &flange),
            },
            lift,
            false,
        )?;
        Ok(self.retreat(placed.goals[1], name)?)
    }
}

/// Packs `task` with `policy`; RRT-Connect (seeded with `seed`) for
/// fallbacks.
pub(super) fn run<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    policy: &dyn Policy,
    seed: u64,
    budget: PlanningBudget,
) -> Report {
    let mut station = Station::new(world, arm, task);
    station.budget = budget;
    let mut runner = Learned {
        station,
        policy,
        rule: policy.sequence(),
        seed,
        fallbacks: Vec::new(),
    };
    let first = runner.station.world.observe();
    let mut rows: Vec<ProductReport> = task
        .assignment
        .iter()
        .map(|&(p, s)| {
            let mut row = runner.station.row(p, s);
            row.error_m = runner.station.error_of(&first, p, s);
            row.outcome = match row.error_m {
                None => Outcome::Waiting,
                Some(e) if e <= SUCCESS_RADIUS => Outcome::AlreadyPacked,
                Some(_) => Outcome::NotAttempted,
            };
            row
        })
        .collect();
    let mut stop = None;
    for _ in 0..task.assignment.len() {
        let obs = runner.station.world.observe();
        // Done when no selected, present product is out of its slot.
        if expected_next(task, &obs.products, &runner.rule).is_none() {
            break;
        }
        if let Err(halt) = runner.product(&mut rows) {
            stop = Some(halt);
            break;
        }
    }
    let mut violations = Vec::new();
    let mut collisions = Vec::new();
    if let Err(Failure::Collision { contact }) = runner.station.flush_backup(&mut rows) {
        collisions.push(contact);
    }
    match stop {
        Some(Stopped::Violation(v)) => violations.push(v),
        Some(Stopped::Failed(Failure::Collision { contact })) => collisions.push(contact),
        Some(Stopped::Failed(_)) | None => {}
    }
    let mut report = runner
        .station
        .finish(PlannerKind::Learned, rows, collisions);
    report.fallbacks = std::mem::take(&mut runner.fallbacks);
    report.complete &= violations.is_empty();
    report.violations = violations;
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    use packwright_interface::scene::BoxSpec;

    /// A cell with one box, 350 mm wide and 80 mm deep, 80 mm high,
    /// centred at (-0.2, 0.65): 36 mm from its centre line to the inside
    /// of its long walls.
    fn narrow_box() -> CellScene {
        CellScene {
            name: "narrow".into(),
            base: [0.0, 0.0, 0.0],
            suction: 0.085,
            lift: 0.1,
            speed: 1.0,
            grip_settle: 0.1,
            release_settle: 0.5,
            descent: 1.0,
            pending: ([0.0, 0.0], [0.1, 0.1]),
            boxes: vec![BoxSpec {
                name: "carton".into(),
                centre: [-0.2, 0.65],
                size: [0.35, 0.08, 0.08],
            }],
            slots: Vec::new(),
        }
    }

    /// The cup pointing down, turned by `yaw`.
    fn down(yaw: f64) -> UnitQuaternion<f64> {
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw)
            * UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0)
    }

    #[test]
    fn a_release_against_a_wall_is_kept_inside_the_box() {
        let cell = narrow_box();
        // A 60 mm deep product: 36 - 30 - 3 mm padding - 1 mm margin
        // leaves 2 mm either way of the centre line.
        let inside = Inside::new(&cell, 0, [0.04, 0.06, 0.05], [0.0, 0.0], &down(0.0))
            .expect("the box exists");
        let at = |y: f64| [-0.2, 0.65 + y, 0.06];
        assert_eq!(inside.keep(at(0.0015)), Some(at(0.0015)), "already inside");
        let kept = inside.keep(at(0.004)).expect("moved");
        assert!((kept[1] - 0.652).abs() < 1e-9, "{kept:?}");
        assert_eq!((kept[0], kept[2]), (-0.2, 0.06), "x and z stay");
        let kept = inside.keep(at(-0.004)).expect("moved");
        assert!((kept[1] - 0.648).abs() < 1e-9, "{kept:?}");
        // Hanging 2 mm off the cup towards +y, the cup lets go 2 mm further
        // towards -y.
        let off = Inside::new(&cell, 0, [0.04, 0.06, 0.05], [0.0, 0.002], &down(0.0))
            .expect("the box exists");
        let kept = off.keep(at(0.001)).expect("moved");
        assert!((kept[1] - 0.65).abs() < 1e-9, "{kept:?}");
        // Turned a quarter, the product's 60 mm lie along x: in y it is
        // 40 mm, and the cup (20 mm and 10 mm padding) is the bound.
        let turned = Inside::new(&cell, 0, [0.04, 0.06, 0.05], [0.0, 0.0], &down(FRAC_PI_2))
            .expect("the box exists");
        let kept = turned.keep(at(0.007)).expect("moved");
        assert!((kept[1] - 0.655).abs() < 1e-9, "{kept:?}");
        // Above the rim, the cup is not in the box: the product's bound.
        let high = [-0.2, 0.665, 0.09];
        assert!((turned.keep(high).expect("moved")[1] - 0.662).abs() < 1e-9);
    }

    #[test]
    fn a_goal_behind_the_arm_is_reached_through_a_via_on_the_side_with_room() {
        // A base on a riser, turned a quarter: the tip along the base's
        // x is along the world's y.
        let base = Isometry3::new(Vector3::new(0.2, -0.3, 0.24), Vector3::z() * FRAC_PI_2);
        let world =
            |x: f64, y: f64, z: f64| -> [f64; 3] { (base * Point3::new(x, y, z)).coords.into() };
        let from = world(0.5, 0.0, 0.3);
        let behind = world(-0.6, 0.05, 0.1);
        let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|j| (a[j] - b[j]).abs() < 1e-9);
        // Behind and a little to the left: with the base turned right
        // (q0 < 0), the short way, to the left, ends nearer the middle of
        // the base's range; turned left, the other way round does.
        let left = swing_via(&base, -0.5, from, behind).expect("behind");
        let turn = record::short_way(0.05f64.atan2(-0.6));
        let r = (0.5 + 0.6f64.hypot(0.05)) / 2.0;
        assert!(
            near(
                left,
                world(r * (turn / 2.0).cos(), r * (turn / 2.0).sin(), 0.3)
            ),
            "{left:?}"
        );
        let right = swing_via(&base, 0.5, from, behind).expect("behind");
        let other = turn - TAU;
        assert!(
            near(
                right,
                world(r * (other / 2.0).cos(), r * (other / 2.0).sin(), 0.3)
            ),
            "{right:?}"
        );
        // A quarter turn round is not wide.
        assert_eq!(swing_via(&base, 0.0, from, world(0.0, 0.6, 0.1)), None);
    }

    #[test]
    fn a_base_a_little_past_its_limit_is_held_there_not_turned_back() {
        let arm = Arm::ur10();
        let upper = arm.limits[0].upper;
        let start = [upper - 0.003, -1.5, 2.0, -2.0, -1.571, 1.5];
        let mut past = start;
        past[0] = upper + 0.006;
        past[5] = arm.limits[5].lower - 0.004;
        let held = held_at_limits(&arm, &start, past);
        assert_eq!((held[0], held[5]), (upper, arm.limits[5].lower));
        assert_eq!(held[1..5], past[1..5], "the other joints stay");
        // Farther past: left to be brought a whole turn back.
        let mut far = start;
        far[0] = upper + 0.05;
        assert_eq!(held_at_limits(&arm, &start, far), far);
        // From outside the limits (a step's own turn past them): left.
        let outside = [upper + 0.002, -1.5, 2.0, -2.0, -1.571, 1.5];
        assert_eq!(held_at_limits(&arm, &outside, past)[0], past[0]);
    }

    #[test]
    fn a_product_wider_than_the_box_is_not_moved() {
        let cell = narrow_box();
        let inside = Inside::new(&cell, 0, [0.04, 0.075, 0.05], [0.0, 0.0], &down(0.0))
            .expect("the box exists");
        // Along the box's length it fits: only that axis is kept.
        assert_eq!(inside.keep([-0.2, 0.653, 0.06]), Some([-0.2, 0.653, 0.06]));
        assert_eq!(inside.keep([-0.4, 0.653, 0.06]).map(|k| k[1]), Some(0.653));
        assert_eq!(
            Inside::new(&cell, 1, [0.04, 0.04, 0.05], [0.0, 0.0], &down(0.0)),
            None
        );
    }

    /// A way of stepping the policy, with the signature of [`policy_steps`].
    type Stepper = fn(
        &Arm,
        &Isometry3<f64>,
        f64,
        Joints,
        [f64; 3],
        f64,
        &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
    ) -> Result<Vec<Joints>, Shortfall>;

    /// The policy's steps as they were taken before each flange pose was
    /// computed once and the tip in closed form: the tip and both sides of
    /// the wrist check each by forward kinematics of their own.
    fn steps_by_separate_poses(
        arm: &Arm,
        base: &Isometry3<f64>,
        suction: f64,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
    ) -> Result<Vec<Joints>, Shortfall> {
        let mut q = start;
        let mut steps = Vec::new();
        loop {
            let tip: [f64; 3] = arm.tool_tip(base, &q, suction).coords.into();
            let delta: [f64; 3] = std::array::from_fn(|j| goal[j] - tip[j]);
            let away = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
            if away <= tolerance {
                return Ok(steps);
            }
            if steps.len() == MAX_POLICY_STEPS {
                return Err(Shortfall::Short {
                    steps: MAX_POLICY_STEPS,
                    distance_m: away,
                });
            }
            let step = record::clip(action(&q, delta).map(f64::from));
            q = cup_down(arm, base, &q, step)?;
            steps.push(q);
        }
    }

    /// Down into a slot, the straight joint motion's tip leaves the
    /// vertical line by millimetres; the descent's via points go across to
    /// it at the start's height (when the start is beside it) and keep to
    /// it on the way down, each within the tolerance, and end where the
    /// motion ends. A motion mostly sideways is no descent.
    #[test]
    fn a_descent_goes_down_the_vertical_over_the_release_where_the_joint_motion_bows() {
        let arm = Arm::ur10();
        let base = Isometry3::identity();
        let suction = 0.1;
        let (x, y, yaw) = (0.55, 0.25, 0.3);
        let tip = |q: &Joints| -> [f64; 3] { arm.tool_tip(&base, q, suction).coords.into() };
        let at = |p: [f64; 3], near: &Joints| {
            arm.tool_down_ik(&base, Point3::from(p), yaw, suction, near)
        };
        let home = [0.0, -1.5, 1.5, -1.6, -1.6, 0.0];
        let end = at([x, y, 0.11], &home).expect("reachable");
        // The expert's step towards the joints of the tip it is sent to.
        let mut act = |q: &Joints, delta: [f64; 3]| {
            let t = tip(q);
            let goal = at(std::array::from_fn(|j| t[j] + delta[j]), q).unwrap_or(*q);
            record::action(q, &goal).map(|v| v as f32)
        };
        let off_line = |q: &Joints| {
            let t = tip(q);
            (t[0] - x).hypot(t[1] - y)
        };
        let tolerance = REACHED;
        // Straight above the release, and 6 mm beside it (as a learned
        // "above the slot" may be): the vias go across first, then down.
        for (beside, across) in [(0.0, false), (0.006, true)] {
            let start = at([x + beside, y, 0.25], &end).expect("reachable");
            let middle: Joints = std::array::from_fn(|j| (start[j] + end[j]) / 2.0);
            assert!(off_line(&middle) > 0.003, "bows {} m", off_line(&middle));
            let vias = descent_vias(&arm, &base, suction, start, end, tolerance, &mut act)
                .expect("a descent");
            assert_eq!(vias.len(), DESCENT_VIAS - usize::from(!across));
            assert_eq!(vias.last(), Some(&end));
            let down = &vias[usize::from(across)..];
            if across {
                assert!(off_line(&vias[0]) <= tolerance, "{:?}", tip(&vias[0]));
                assert!((tip(&vias[0])[2] - 0.25).abs() <= tolerance);
            }
            for (i, q) in down.iter().enumerate() {
                let z = 0.25 - 0.14 * (i + 1) as f64 / (DESCENT_VIAS - 1) as f64;
                assert!(off_line(q) <= tolerance, "via {i} {} m off", off_line(q));
                assert!(
                    (tip(q)[2] - z).abs() <= tolerance,
                    "via {i} at {:?}",
                    tip(q)
                );
            }
        }
        let start = at([x, y, 0.25], &end).expect("reachable");
        let aside = at([x, y + 0.2, 0.11], &start).expect("reachable");
        assert_eq!(
            descent_vias(&arm, &base, suction, start, aside, tolerance, &mut act),
            None
        );
    }

    /// A half-turn swing that ends at the base's limit ends a whole turn
    /// the other way round instead; one ending at the limit a quarter turn
    /// on, or with room, or a short step past where the other turn is far,
    /// is left alone.
    #[test]
    fn a_swing_ending_at_the_base_limit_goes_the_other_way_round() {
        let arm = Arm::ur10();
        let q = |base: f64, wrist3: f64| [base, -1.2, 2.4, -2.8, -FRAC_PI_2, wrist3];
        let limit = arm.limits[0].lower;
        // About half a turn, to within 4 mrad of the limit (probe cell 3081).
        let start = q(-3.315, -1.744);
        let end = q(limit + 0.004, -4.708);
        let turned = with_room(&arm, &start, end);
        assert!((turned[0] - (limit + 0.004 + TAU)).abs() < 1e-12);
        assert_eq!(turned[1..], end[1..]);
        // A quarter turn to the limit: the other way is three quarters.
        let start = q(limit + FRAC_PI_2, 0.0);
        assert_eq!(with_room(&arm, &start, end), end);
        // With room: nothing to do.
        let roomy = q(limit + 0.2, 0.0);
        assert_eq!(with_room(&arm, &start, roomy), roomy);
        // A short step along the limit (a descent after such a swing):
        // the other turn is a whole turn farther.
        let start = q(limit + 0.004, 0.0);
        let step = q(limit + 0.002, 0.0);
        assert_eq!(with_room(&arm, &start, step), step);
        // Wrist 3 as well.
        let start = q(0.0, 3.2);
        let end = q(0.0, arm.limits[5].upper - 0.01);
        let turned = with_room(&arm, &start, end);
        assert!(turned[5] < 0.0, "{turned:?}");
    }

    /// Random actions from cup-down starts give the very same steps and
    /// shortfalls as forward kinematics at every use (the distance left
    /// to within 1e-9 m: the tip is in closed form after the first step):
    /// short of a goal out of reach, at a goal some steps away (within
    /// 1e-9 m), or off the joint limits.
    #[test]
    fn policy_steps_match_separate_forward_kinematics() {
        let arm = Arm::ur10();
        let base = Isometry3::translation(0.1, -0.2, 0.05);
        let suction = 0.12;
        let mut x = 17u64;
        let mut next = move || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 40) as f64 / (1u64 << 24) as f64) * 2.0 - 1.0
        };
        let mut outcomes = Vec::new();
        for _ in 0..40 {
            let tip = Point3::new(0.5 + 0.3 * next(), 0.4 * next(), 0.3 + 0.1 * next());
            let Some(start) = arm.tool_down_ik(
                &base,
                tip,
                next(),
                suction,
                &[0.0, -1.5, 1.5, -1.6, -1.6, 0.0],
            ) else {
                continue;
            };
            let wander: Vec<[f32; 3]> = (0..MAX_POLICY_STEPS)
                .map(|_| {
                    [
                        0.1 * next() as f32,
                        0.1 * next() as f32,
                        0.1 * next() as f32,
                    ]
                })
                .collect();
            // The elbow bends on until it leaves its limits.
            let bend: Vec<[f32; 3]> = wander.iter().map(|a| [a[0], a[1], 0.1]).collect();
            // A goal out of reach, and the tip after a few of the actions.
            let mut after = start;
            for a in &wander[..5] {
                after =
                    cup_down(&arm, &base, &after, record::clip(a.map(f64::from))).unwrap_or(after);
            }
            let near: [f64; 3] = arm.tool_tip(&base, &after, suction).coords.into();
            let far = [3.0, 0.0, 0.5];
            for (actions, goal, tolerance) in [
                (&wander, far, 0.01),
                (&wander, near, 1e-9),
                (&bend, far, 0.01),
            ] {
                let run = |stepper: Stepper| {
                    let mut k = 0;
                    stepper(&arm, &base, suction, start, goal, tolerance, &mut |_, _| {
                        k += 1;
                        actions[k - 1]
                    })
                };
                let (new, old) = (run(policy_steps), run(steps_by_separate_poses));
                // The distance left within 1e-9 m, all else exactly.
                let rounded = |r: &Result<Vec<Joints>, Shortfall>| match r {
                    Err(Shortfall::Short { steps, distance_m }) => Err(Shortfall::Short {
                        steps: *steps,
                        distance_m: (distance_m * 1e9).round(),
                    }),
                    other => other.clone(),
                };
                // Debug prints each value exactly (NaN included).
                let (new, old) = (
                    format!("{:?}", rounded(&new)),
                    format!("{:?}", rounded(&old)),
                );
                assert_eq!(new, old);
                outcomes.push(new.chars().take(8).collect::<String>());
            }
        }
        // Each way of ending was met.
        for ending in ["Ok(", "Err(Shor", "Err(Limi"] {
            assert!(
                outcomes.iter().any(|o| o.starts_with(ending)),
                "no {ending} among {outcomes:?}"
            );
        }
    }
}
