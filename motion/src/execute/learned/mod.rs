//! The learned loop (README, "Learning"): at the start of each stage the
//! reasoner chooses (a product or the box, and the label) from the
//! products' positions alone; the sub-goal planner proposes each of the
//! stage's three sub-goals; the dynamics policy steps towards it (at most
//! [`MAX_POLICY_STEPS`] steps of at most 15 degrees, the wrist keeping the
//! cup down). A rollout that does not reach its sub-goal, or whose motion
//! would collide, hands the rest of the stage to RRT-Connect (a
//! [`Fallback`]), which goes to the learned sub-goals, or to the expert's
//! where no free motion reaches a learned one. A learned grip or release
//! more than [`SUCCESS_RADIUS`] off the product's centre or the slot, or a
//! grip whose cup tip would miss the top face ([`on_face`]), is not
//! tried: RRT-Connect goes to the expert's. A decision that breaks the
//! order stops the arm (a [`Violation`]).

mod guards;
mod regrip;
mod steps;

use steps::{Hold, MORE_STEPS, policy_steps_near};
pub use steps::{MAX_POLICY_STEPS, REACHED, REACHED_VIA, cup_down, policy_steps, tolerance};

use super::reasoner::{f32s, graph, in_slot, lifted};
use super::station::{
    Connect, Leg, Load, MAX_CARRY_RAISES, MAX_RAISES, PlanningBudget, RAISE_STEP, READY, Route,
    SUCCESS_RADIUS, Station, Unchecked, judge, leg_end, raises,
};
use super::{checked_samples, expected_next};
use crate::collision::Held;
use crate::expert::{self, SubGoal, Suction, schedule};
use guards::{
    COLLIDING_RELEASE_RAISE, Inside, KEEP_INSIDE, MAX_ABOVE_RIM, descent_vias, held_at_limits,
    in_other_branches, level_vias, nearer_middle, other_shapes, release_collides, shorter_turn,
    swing_via, with_room,
};
use nalgebra::Vector3;
use packwright_interface::outcome::{
    Failure, Fallback, Hit, Outcome, PlannerKind, ProductReport, Report, Shortfall, Stage,
    SubGoalKind, Target, Violation,
};
use packwright_interface::{Body, Graph, OrderTask, Policy, SequenceRule, SubGoalQuery, World};
use packwright_kinematics::body::wrist_around_tool;
use packwright_kinematics::{Arm, Joints, joint_distance};
use std::f64::consts::TAU;
use std::time::Instant;
use steps::BACK_UP_REACHED;

/// Via points of the vertical retreat from a release, when the straight
/// joint motion up would touch the box.
const RETREAT_VIAS: usize = 5;
/// Via points of that retreat where the segments between
/// [`RETREAT_VIAS`] still bow into a wall: a quarter as long, they bow a
/// sixteenth as far (development cell 2612: the cup 0.05 mm inside the
/// padded wall of a box 70 mm wide, where the expert's release is on
/// the centre line).
const FINE_RETREAT_VIAS: usize = 20;

/// How many [`RAISE_STEP`]s a carried point or a hover is raised by
/// while every way of [`Learned::rollout`] is tried
/// ([`Learned::raised_over`]; the straight way alone up to
/// [`MAX_CARRY_RAISES`]).
const ALL_WAYS_RAISES: u32 = 20;

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

/// Which ways [`Learned::rollout`] (and [`Learned::way_up`]) try to
/// a goal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ways {
    /// The policy's steps' end, joined straight: one motion to check.
    Straight,
    /// That, then, where it collides, down the vertical, through every
    /// step, and across at the higher end's height (the way up: a
    /// vertical line of via points).
    All,
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
    /// What each sub-goal's motion carries and may touch (picking: until
    /// the grip, then `gripped`'s product; placing: the held product,
    /// padded down into the slot as the room beside it allows).
    loads: [Load<'l>; 3],
    /// Picking: the product's size; the sub-goals after the grip (the
    /// lift) carry it off where it stood, hanging from the cup as the
    /// planned contact leaves it.
    gripped: Option<[f64; 3]>,
    /// Picking: the product's yaw as seen (its top face's).
    yaw: f64,
    /// The expert's sub-goals for the stage: where RRT-Connect goes
    /// instead of a learned sub-goal it cannot reach.
    expert: [SubGoal; 3],
    /// Placing: where the cup tip may let go with the held product and
    /// the cup clear of the box's walls ([`Inside`]).
    inside: Option<Inside>,
}

/// Whether a grip `(dx, dy)` from the centre of a product of `size` seen
/// at `yaw` puts the cup tip on its top face, by as much as the policy's
/// steps may end from it ([`REACHED`]): the simulator grips only there,
/// as a cup sealing on the face does.
fn on_face(dx: f64, dy: f64, size: [f64; 3], yaw: f64) -> bool {
    let (sin, cos) = yaw.sin_cos();
    let along = cos * dx + sin * dy;
    let across = -sin * dx + cos * dy;
    along.abs() <= size[0] / 2.0 - REACHED && across.abs() <= size[1] / 2.0 - REACHED
}

/// The back-up from a release, counted as the placing stage's fourth
/// sub-goal when it falls back ([`Fallback::subgoal`]).
const BACK_UP_SUBGOAL: usize = 4;

/// Whether `rolled` collides with an arm link against a box.
fn arm_against_box(rolled: &Result<Route, Shortfall>) -> bool {
    matches!(
        rolled,
        Err(Shortfall::Collides {
            hit: Hit::Bodies {
                a: Body::Link(_),
                b: Body::Box(_)
            }
        })
    )
}

/// Which arm shapes [`Learned::reshaped`] tries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Shapes {
    /// The branch the policy was taught on, from an arm on another.
    Taught,
    /// Every branch but the arm's own.
    Others,
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
        let joints = self.station.arm.policy_joints(q);
        self.policy.action(f32s(delta), joints.map(|v| v as f32))
    }

    /// The policy's steps from `start` towards `goal`
    /// ([`policy_steps_near`]) with this cell's arm, base and cup.
    fn steps(
        &self,
        more: usize,
        hold: Hold,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        act: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
    ) -> Result<Vec<Joints>, Shortfall> {
        let s = &self.station;
        let (arm, base, suction) = (s.arm, &s.base, s.task.cell.suction);
        policy_steps_near(more, hold, arm, base, suction, start, goal, tolerance, act)
    }

    /// The dynamics policy's motion from `start` to `goal`: the checked
    /// commands, or why not. The steps' end point is joined straight when
    /// that is free, else (with [`Ways::All`]) down the vertical, through
    /// every step or across at the higher end's height. `first_action_us`
    /// gets the time of the first policy call.
    fn rollout(
        &self,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        load: Load,
        first_action_us: &mut Option<f64>,
        ways: Ways,
    ) -> Result<Route, Shortfall> {
        let s = &self.station;
        let (arm, base, suction) = (s.arm, &s.base, s.task.cell.suction);
        // Steps that spiral in on the goal, a little short of it, go on
        // for a few more (the first shortfall is the one reported).
        let steps = self.steps(
            MORE_STEPS,
            Hold::Nothing,
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
            let mut steps = self
                .steps(0, Hold::ShoulderElbow, start, via, REACHED_VIA, act)
                .map_err(|_| why.clone())?;
            let near = steps.last().copied().unwrap_or(start);
            let rest = self
                .steps(0, Hold::ShoulderElbow, near, goal, tolerance, act)
                .map_err(|_| why)?;
            steps.extend(rest);
            Ok(steps)
        });
        // Steps that overshoot the shoulder's or the elbow's limit on the
        // way (an elbow folded near its limit to reach near the base),
        // where no swing through a via point helps: those joints held
        // inside their limits. After the swing: near half a turn, the
        // held steps may go the long way round (probe cell 6003: a hover
        // 188 degrees round, 3.7 s more than through the swing's via).
        let steps = match steps {
            Err(Shortfall::Limits {
                joint: Some(1 | 2), ..
            }) => self
                .steps(
                    MORE_STEPS,
                    Hold::ShoulderElbow,
                    start,
                    goal,
                    tolerance,
                    &mut |q, delta| self.act(q, delta),
                )
                .or(steps),
            steps => steps,
        }?;
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
        // Nearly half a turn round: the other way, when it leaves the base
        // nearer the middle of its range and is free.
        if let Some(other) = nearer_middle(arm, &start, &end)
            && let Ok(route) = route(vec![other])
        {
            return Ok(route);
        }
        match route(vec![end]) {
            Ok(route) => Ok(route),
            Err(straight) if ways == Ways::Straight => Err(why(straight)),
            // Every other way ends where this one does: where the end
            // itself collides (a release a millimetre or two low, the
            // held product on the floor), none of them is tried. Steps
            // that ended in another arm shape than they started in (the
            // shoulder swung back over the top to a point behind the
            // base, the forearm on the table) take the same pose in the
            // nearest other shape that stands free, as the expert's
            // inverse kinematics takes its nearest free solution.
            Err(Unchecked::Collides(hit))
                if s.checker.check(&end, load.held, load.ignore).is_some() =>
            {
                other_shapes(arm, base, &start, &end)
                    .into_iter()
                    .filter(|q| s.checker.check(q, load.held, load.ignore).is_none())
                    .find_map(|q| s.route(Connect::Straight, 0, start, q, load).ok())
                    .ok_or(Shortfall::Collides { hit })
            }
            Err(straight) => {
                // A descent (into a slot, onto a top face) whose straight
                // joint motion bows sideways into a wall: across to above
                // its end, then down the vertical, as the expert's descent
                // and the back-up from a release go.
                // The vias (or steps, below) a straight joint motion can
                // skip are left out first (`Station::through`): the blend
                // speeds up on longer legs, and a descent through five
                // vias stops short of each.
                let through = |points: Vec<Joints>| s.through(0, start, points, load);
                let act = &mut |q: &Joints, delta: [f64; 3]| self.act(q, delta);
                if let Some(vias) = descent_vias(arm, base, suction, start, end, tolerance, act)
                    && let Some(route) = through(vias)
                {
                    return Ok(route);
                }
                // Through the steps instead (passing through them), when
                // they stay within the limits.
                if steps.iter().all(|q| s.arm.within_limits(q))
                    && let Some(route) = through(steps)
                {
                    return Ok(route);
                }
                // Across at the higher end's height.
                let act = &mut |q: &Joints, delta: [f64; 3]| self.act(q, delta);
                level_vias(arm, base, suction, start, end, tolerance, act)
                    .and_then(|vias| route(vias).ok())
                    .ok_or_else(|| why(straight))
            }
        }
    }

    /// A stage's first motion from an arm on another inverse-kinematics
    /// branch than the policy was taught on ([`Shapes::Taught`]), or a
    /// motion that keeping the arm's shape cannot make free
    /// ([`Shapes::Others`]): the policy's steps from the joints of another
    /// branch for `start`'s flange pose, their end reached from `start` by
    /// the straight joint motion or a swing ([`Station::route`]), or
    /// `start` brought to those joints where it stands and the steps
    /// followed from there. A regrip's contact shape (the wrist flipped,
    /// or the elbow below, to grip beside a taller product) leaves the arm
    /// on another branch, where the policy's steps fold the forearm into
    /// wrist 2 over the box; a deep box near the base puts the upper arm
    /// of the shape the arm started in over its wall. The arm changes its
    /// shape on the way, as it does to the expert's nearest free
    /// inverse-kinematics solution; with several shapes, the steps' end
    /// nearest `start` first. `None` on a non-UR arm, on the taught branch
    /// with [`Shapes::Taught`], or where no way is free.
    fn reshaped(
        &self,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        load: Load,
        shapes: Shapes,
    ) -> Option<Route> {
        self.reshaped_then(start, goal, tolerance, load, shapes, &mut |_| Some(()))
            .map(|(route, ())| route)
    }

    /// [`Learned::reshaped`], taking only a shape from whose end `then`
    /// finds its way on: the route and what `then` found.
    fn reshaped_then<T>(
        &self,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        load: Load,
        shapes: Shapes,
        then: &mut dyn FnMut(&Route) -> Option<T>,
    ) -> Option<(Route, T)> {
        let s = &self.station;
        let (arm, base) = (s.arm, &s.base);
        let own = arm.ur_branch(base, &start)?;
        let flange = arm.flange_pose(base, &start);
        let branches = arm.ur_ik_branches(base, &flange, &start);
        let tried: Vec<usize> = match shapes {
            Shapes::Taught => {
                let taught = self.taught_branch()?;
                if own == taught {
                    return None;
                }
                vec![taught]
            }
            Shapes::Others => (0..branches.len()).filter(|&b| b != own).collect(),
        };
        let act = &mut |q: &Joints, delta: [f64; 3]| self.act(q, delta);
        let mut ends: Vec<(Joints, Joints)> = tried
            .into_iter()
            .filter_map(|b| {
                let from = (*branches.get(b)?)?;
                let steps = self
                    .steps(MORE_STEPS, Hold::Nothing, from, goal, tolerance, act)
                    .ok()?;
                let last = steps.last().copied().unwrap_or(from);
                let end = arm.into_limits(&held_at_limits(arm, &from, last), &from)?;
                let end = with_room(arm, &from, end);
                // An end whose own pose collides is not routed to.
                s.checker
                    .check(&end, load.held, load.ignore)
                    .is_none()
                    .then_some((from, end))
            })
            .collect();
        ends.sort_by(|a, b| joint_distance(&a.1, &start).total_cmp(&joint_distance(&b.1, &start)));
        // Then the end the policy's steps reach in the start's own shape,
        // in each other shape (the same flange pose): where the policy
        // was taught one shape only (a model taught one demonstration),
        // its steps from another shape's joints fall short, and the
        // expert's hover over a flat product beside a crate is in the
        // elbow's other shape.
        if matches!(shapes, Shapes::Others)
            && let Ok(steps) = self.steps(MORE_STEPS, Hold::Nothing, start, goal, tolerance, act)
            && let Some(&last) = steps.last()
            && let Some(reached) = arm.into_limits(&held_at_limits(arm, &start, last), &start)
        {
            let pose = arm.flange_pose(base, &reached);
            let more: Vec<(Joints, Joints)> =
                in_other_branches(arm, base, &pose, &reached, own, &start)
                    .into_iter()
                    .filter(|end| s.checker.check(end, load.held, load.ignore).is_none())
                    .filter(|end| ends.iter().all(|(_, e)| e != end))
                    .map(|end| (end, end))
                    .collect();
            ends.extend(more);
        }
        let mut tried = |from: Joints, end: Joints| {
            // Wrist 1 either way round: turning it the shorter way can
            // fold wrist 2 into the forearm as the wrist flips.
            let turns = [0.0, -TAU, TAU].map(|t| {
                let mut turned = [from, end];
                turned.iter_mut().for_each(|q| q[3] += t);
                turned
            });
            turns
                .into_iter()
                .filter(|[from, end]| arm.within_limits(from) && arm.within_limits(end))
                .find_map(|[from, end]| {
                    // Through `from` where it is another point (an end
                    // taken in another shape starts nowhere else: its
                    // straight motion was just checked).
                    s.route(Connect::Straight, 0, start, end, load)
                        .ok()
                        .or_else(|| {
                            let waypoints = vec![from, end];
                            (from != end)
                                .then(|| checked_samples(arm, &s.checker, start, &waypoints, load))
                                .and_then(Result::ok)
                                .map(|samples| Route { waypoints, samples })
                        })
                })
                .and_then(|route| then(&route).map(|found| (route, found)))
        };
        if let Some(found) = ends.iter().find_map(|&(from, end)| tried(from, end)) {
            return Some(found);
        }
        // Another shape's joints come with the base in its first turn,
        // which can leave it more than half a turn round from `start`: the
        // swing there sweeps the arm the long way round, through what
        // stands near the base (a box behind the base, reached past a tall
        // product beside it), where the expert's nearest solution turns
        // the short way. The same ends a whole turn round.
        ends.iter().find_map(|&(from, end)| {
            let turn = shorter_turn(start[0], end[0])?;
            let [from, end] = [from, end].map(|mut q| {
                q[0] += turn;
                q
            });
            tried(from, end)
        })
    }

    /// The inverse-kinematics branch the policy was taught on: that of the
    /// UR "ready" pose (`None` on a non-UR arm).
    fn taught_branch(&self) -> Option<usize> {
        let s = &self.station;
        s.arm.ur_branch(&s.base, &s.arm.from_ur_convention(&READY))
    }

    /// The policy's steps from an arm on another inverse-kinematics branch
    /// than it was taught on, taken on the taught branch (its joints for
    /// `start`'s flange pose) and each brought back to `start`'s own
    /// branch through inverse kinematics: the cup follows the policy's
    /// path, the arm keeps its shape. An arm that changed its shape on the
    /// way to a box (the upper arm over its rim in the taught shape) stays
    /// in the other one for every later pick and place, where the policy's
    /// own steps can turn the shoulder past its limit (helper T's cell
    /// 6311 with the bundled model: 23 fallbacks in 32 packages). The
    /// end joined straight, else through the steps brought back. `None`
    /// on a non-UR arm, on the taught branch, where a step has no
    /// solution on `start`'s branch within the limits, or where no way is
    /// free.
    fn in_own_shape(
        &self,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        load: Load,
    ) -> Option<Route> {
        let s = &self.station;
        let (arm, base) = (s.arm, &s.base);
        let own = arm.ur_branch(base, &start)?;
        let taught = self.taught_branch()?;
        if own == taught {
            return None;
        }
        let from = (*arm
            .ur_ik_branches(base, &arm.flange_pose(base, &start), &start)
            .get(taught)?)?;
        let act = &mut |q: &Joints, delta: [f64; 3]| self.act(q, delta);
        let steps = self
            .steps(MORE_STEPS, Hold::Nothing, from, goal, tolerance, act)
            .ok()?;
        let mut near = start;
        let mut back = Vec::with_capacity(steps.len());
        for q in &steps {
            let flange = arm.flange_pose(base, q);
            near = (*arm.ur_ik_branches(base, &flange, &near).get(own)?)?;
            back.push(near);
        }
        let end = *back.last()?;
        checked_samples(arm, &s.checker, start, &[end], load)
            .ok()
            .map(|samples| Route {
                waypoints: vec![end],
                samples,
            })
            .or_else(|| s.through(0, start, back, load))
    }

    /// The approach from `from` planned again in another arm shape
    /// ([`Learned::reshaped_then`]), from whose end the policy's motion
    /// reaches `above` (above the slot) free: both routes.
    fn approach_reshaped(
        &self,
        from: Joints,
        approach: [f64; 3],
        above: [f64; 3],
        tolerance: f64,
        load: Load,
    ) -> Option<(Route, Route)> {
        self.reshaped_then(
            from,
            approach,
            steps::tolerance(Stage::Placing, 0),
            load,
            Shapes::Others,
            &mut |route| {
                let end = *route.waypoints.last()?;
                let mut unused = None;
                self.rollout(end, above, tolerance, load, &mut unused, Ways::All)
                    .ok()
            },
        )
    }

    /// The policy's motion to a release `kept` inside the box's walls
    /// ([`Inside`]), reached within [`BACK_UP_REACHED`], by any way.
    fn kept(
        &self,
        start: Joints,
        kept: [f64; 3],
        load: Load,
        first_action_us: &mut Option<f64>,
    ) -> Option<Route> {
        let reached = BACK_UP_REACHED;
        self.rollout(start, kept, reached, load, first_action_us, Ways::All)
            .ok()
    }

    /// The policy's motion to `goal` raised [`RAISE_STEP`] at a time (at
    /// most [`MAX_RAISES`] times, to heights above `above` and no higher
    /// than `ceiling`, while the sub-goal's budget lasts): the first that
    /// [`Learned::rollout`] reaches and finds free.
    fn raised(
        &self,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        load: Load,
        (above, ceiling): (f64, f64),
        first_action_us: &mut Option<f64>,
    ) -> Option<Route> {
        self.raise_heights(goal[2], (above, ceiling)).find_map(|z| {
            self.rollout(
                start,
                [goal[0], goal[1], z],
                tolerance,
                load,
                first_action_us,
                Ways::All,
            )
            .ok()
        })
    }

    /// A carried point or a hover `goal` whose motion collides, raised
    /// [`RAISE_STEP`] at a time, at most [`MAX_CARRY_RAISES`] times (while
    /// the sub-goal's budget lasts): first the lowest height whose steps'
    /// end joined straight is free (one check a height), then, where none
    /// is, the lowest that [`Learned::rollout`] reaches by any of its
    /// ways, up to [`ALL_WAYS_RAISES`] steps up. Most heights under
    /// something standing in the way fail, and each of the other ways is
    /// a motion of its own to blend and check
    /// (measured on a florist's cell with 250-280 mm vases: 8 to 12
    /// heights tried, 3 to 17 ms each).
    fn raised_over(
        &self,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        load: Load,
        first_action_us: &mut Option<f64>,
    ) -> Option<Route> {
        let over = (goal[2], goal[2] + RAISE_STEP * f64::from(MAX_CARRY_RAISES));
        self.raise_heights(goal[2], over)
            .find_map(|z| {
                let raised = [goal[0], goal[1], z];
                self.rollout(
                    start,
                    raised,
                    tolerance,
                    load,
                    first_action_us,
                    Ways::Straight,
                )
                .ok()
            })
            .or_else(|| {
                // Every way, at the lower heights only: at each, the
                // descent's vias, the steps and the level way are motions
                // of their own to blend and check (a box right behind the
                // base, the upper arm over its wall at every height: 50
                // heights took 0.75 s).
                let lower = (goal[2], goal[2] + RAISE_STEP * f64::from(ALL_WAYS_RAISES));
                self.raised(start, goal, tolerance, load, lower, first_action_us)
            })
    }

    /// The heights a release at height `from` is raised to, [`RAISE_STEP`]
    /// at a time (at most [`MAX_RAISES`] times), above `above` and no
    /// higher than `ceiling`, while the sub-goal's budget lasts.
    fn raise_heights(
        &self,
        from: f64,
        (above, ceiling): (f64, f64),
    ) -> impl Iterator<Item = f64> + '_ {
        raises(from, MAX_RAISES)
            .skip_while(move |z| *z <= above)
            .take_while(move |z| *z <= ceiling && !self.station.late())
    }

    /// The height at which the expert lets go of sub-goal `k` of `plan`
    /// (a release) from `start`: its release, raised (up to `ceiling`)
    /// as far as its straight descent needs ([`Station::solve`]); `None`
    /// where it finds none.
    fn experts_release(
        &self,
        k: usize,
        plan: &StagePlan,
        start: Joints,
        load: Load,
        ceiling: f64,
    ) -> Option<f64> {
        let s = &self.station;
        let solved = s
            .solve(&plan.expert[k], k + 1, &start, 0.0, load, ceiling)
            .ok()?;
        Some(s.tip(&solved.joints)[2])
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
        let rrt = |goal: &SubGoal, ceiling: f64| self.rrt_to(goal, k + 1, start, load, ceiling);
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
                            Ok(first.then(down))
                        };
                        // The release's other arm shapes, as the expert's
                        // own placing tries them (`Station::release_shape`):
                        // the shape the policy left the arm in can fold
                        // the upper arm into wrist 1 at every release
                        // nearest it (a UR16e's shorter links), where
                        // another shape lets go free.
                        let shaped = || -> Option<Route> {
                            let [over, down] =
                                s.release_shape([above, &expert[k]], &start, 0.0, load)?;
                            let (at, first) = s.route_in_shape(how, k, start, over, load).ok()?;
                            let (_, down) = s.route_solved(how, k + 1, at, down, 0.0, load).ok()?;
                            Some(first.then(down))
                        };
                        detour()
                            .ok()
                            .or_else(|| (!s.late()).then(shaped).flatten())
                            .ok_or(direct)
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
        self.station.stage = Some(plan.stage);
        let mut fallen = false;
        let mut goals = [[0.0; 3]; 3];
        let mut tips = [[0.0; 3]; 3];
        let base = f32s(self.station.task.cell.base);
        // The stage is planned to its end before the arm moves, each
        // sub-goal from where the one before leaves the arm.
        let mut start = leg_end(&pending).unwrap_or_else(|| self.station.world.observe().joints);
        let (from, pending_legs, subgoals_before) =
            (start, pending.len(), self.station.subgoals.len());
        let mut legs = pending;
        // The product as it will hang once gripped.
        let mut gripped: Option<Held> = None;
        let kinds = SubGoalKind::of(plan.stage);
        'subgoals: for ((k, switch), kind) in
            schedule(plan.stage).into_iter().enumerate().zip(kinds)
        {
            let load = gripped.as_ref().map_or(plan.loads[k], Load::holding);
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
            // A grip must also put the cup on the top face: a small
            // product's (a 21 mm cube) is narrower than that radius.
            let off = (switch != Suction::Keep)
                .then(|| {
                    let e = plan.expert[k].tip;
                    let (dx, dy) = (goal[0] - e[0], goal[1] - e[1]);
                    let beside = switch == Suction::On
                        && plan
                            .gripped
                            .is_some_and(|size| !on_face(dx, dy, size, plan.yaw));
                    let d = dx.hypot(dy);
                    (d > SUCCESS_RADIUS || beside).then_some(d)
                })
                .flatten();
            // A placing stage's approach planned again in another arm
            // shape (below), replacing the one planned.
            let mut approach_again: Option<Route> = None;
            let rolled = (!fallen && off.is_none()).then(|| {
                let tolerance = tolerance(plan.stage, k);
                let mut first_action_us = None;
                // The first attempt's shortfall is the one reported.
                let mut rolled = self.rollout(
                    start,
                    goal,
                    tolerance,
                    load,
                    &mut first_action_us,
                    Ways::All,
                );
                // A stage's first motion from an arm a regrip left on
                // another shape than the policy was taught in: the arm
                // changes its shape on the way.
                if k == 0
                    && rolled.is_err()
                    && let Some(route) = self.reshaped(start, goal, tolerance, load, Shapes::Taught)
                {
                    rolled = Ok(route);
                }
                // An arm on another shape than the policy was taught in,
                // whose steps fail: the taught shape's steps, in its own.
                if rolled.is_err()
                    && !self.station.late()
                    && let Some(route) = self.in_own_shape(start, goal, tolerance, load)
                {
                    rolled = Ok(route);
                }
                // A point the product is carried through (the approach,
                // above the slot) whose motion meets what stands under the
                // way (a bottle taller than the carrying height) is
                // raised, as the expert's is (`Station::solve`); the
                // sub-goal is then where it was raised to (the back-up from
                // the release rises as high). So is a hover, whose motion
                // sweeps the wrist past a product standing taller than it
                // (a 280 mm vase beside a packet); the guarded descent
                // onto the top face is then longer. The expert goes there
                // with another arm shape instead, which the policy's
                // steps, keeping the start's shape, cannot reach.
                let raisable = plan.stage == Stage::Placing || k == 0;
                // Above the slot, an arm link against a box (the upper
                // arm over the wall of a box near the base) is a matter of
                // the arm's shape, not of height: the shape is changed
                // (below) before every height is tried (1.2 s on a box
                // 300 mm deep behind the base).
                let shape_first = plan.stage == Stage::Placing
                    && k == 1
                    && arm_against_box(&rolled)
                    && !self.station.late();
                if shape_first
                    && let Some((approach, route)) =
                        self.approach_reshaped(from, goals[0], goal, tolerance, load)
                {
                    approach_again = Some(approach);
                    rolled = Ok(route);
                }
                if switch == Suction::Keep
                    && raisable
                    && matches!(rolled, Err(Shortfall::Collides { .. }))
                    && let Some(route) =
                        self.raised_over(start, goal, tolerance, load, &mut first_action_us)
                    && let Some(end) = route.waypoints.last()
                {
                    goals[k][2] = goal[2].max(self.station.tip(end)[2]);
                    rolled = Ok(route);
                }
                // Above the slot, where the arm must change its shape (a
                // box close behind the base: the upper arm of the arm's
                // shape across it): changed on the way to the approach
                // instead, a long swing already, when the policy's steps
                // from there reach above the slot free (the arm's elbow
                // flipped between the two took up to 1.3 s more). Tried
                // before the heights where an arm link meets the box (above).
                if !shape_first
                    && plan.stage == Stage::Placing
                    && k == 1
                    && matches!(rolled, Err(Shortfall::Collides { .. }))
                    && !self.station.late()
                    && let Some((approach, route)) =
                        self.approach_reshaped(from, goals[0], goal, tolerance, load)
                {
                    approach_again = Some(approach);
                    rolled = Ok(route);
                }
                // One that no height makes free (a deep box near the base,
                // or behind it: the upper arm of the arm's shape over the
                // box's wall, at every height the arm reaches): the arm
                // changes its shape on the way, as the expert's does.
                if switch == Suction::Keep
                    && raisable
                    && matches!(rolled, Err(Shortfall::Collides { .. }))
                    && !self.station.late()
                    && let Some(route) = self.reshaped(start, goal, tolerance, load, Shapes::Others)
                {
                    rolled = Ok(route);
                }
                // A release whose motion collides is raised only as far
                // as one too low needs: up to COLLIDING_RELEASE_RAISE above
                // the expert's (or itself, when higher).
                let colliding = release_collides(switch, &rolled);
                let room = ceiling;
                let mut ceiling = if colliding {
                    room.min(plan.expert[k].tip[2].max(goal[2]) + COLLIDING_RELEASE_RAISE)
                } else {
                    room
                };
                if rolled.is_err()
                    && let Some(route) = self.raised(
                        start,
                        goal,
                        tolerance,
                        load,
                        (goal[2], ceiling),
                        &mut first_action_us,
                    )
                {
                    rolled = Ok(route);
                }
                // Where the expert's own release from here is raised too
                // (the arm cannot reach so deep: a deep box near the base,
                // the forearm over its wall; or the cup does not fit in
                // the box), as far above that.
                let mut experts_height = None;
                if colliding
                    && rolled.is_err()
                    && !self.station.late()
                    && let Some(experts) = self.experts_release(k, plan, start, load, room)
                    && experts > plan.expert[k].tip[2]
                {
                    experts_height = Some(experts);
                    let above = ceiling;
                    ceiling = room.min(experts.max(goal[2]) + COLLIDING_RELEASE_RAISE);
                    if let Some(route) = self.raised(
                        start,
                        goal,
                        tolerance,
                        load,
                        (above, ceiling),
                        &mut first_action_us,
                    ) {
                        rolled = Ok(route);
                    }
                }
                // A release whose product or cup would touch the box's
                // wall (a learned sub-goal a few millimetres off in a
                // tight box): moved just inside the walls, when that is
                // near, and reached closely (a sub-goal already inside by
                // less than the usual reach too); no lower than the
                // expert's, which lets go 5 mm up (a learned release a
                // little low, held against the floor, was raised, but
                // moved inside at its own height). Where something above
                // the cup still meets the rim there (wrist 3 over a deep
                // box: inside the cup's bounds, but at their edge), the
                // kept release is raised as the learned one is.
                let not_low = [goal[0], goal[1], goal[2].max(plan.expert[k].tip[2])];
                if release_collides(switch, &rolled)
                    && !self.station.late()
                    && let Some(kept) = plan.inside.and_then(|i| i.keep(not_low))
                    && (kept[0] - goal[0]).hypot(kept[1] - goal[1]) <= KEEP_INSIDE
                    && let Some(route) =
                        self.kept(start, kept, load, &mut first_action_us)
                            .or_else(|| {
                                self.raised(
                                    start,
                                    kept,
                                    BACK_UP_REACHED,
                                    load,
                                    (kept[2], ceiling),
                                    &mut first_action_us,
                                )
                            })
                {
                    goals[k] = kept;
                    rolled = Ok(route);
                }
                // Kept inside again at each raised height: across a box
                // narrower than the wrist, the wrist fits only as it rises
                // out over the rim, and only near the middle (a 120 mm
                // carton 300 mm deep, on a wide development cell: the
                // expert lets go 12 cm up, the kept release 2 mm beside it
                // put wrist 3 on the wall). Only points the pass above did
                // not try.
                if release_collides(switch, &rolled)
                    && let Some(inside) = plan.inside
                {
                    let tried = inside.keep(not_low);
                    let found = self
                        .raise_heights(not_low[2], (not_low[2], ceiling))
                        .filter_map(|h| inside.keep([goal[0], goal[1], h]))
                        .filter(|kept| {
                            (kept[0] - goal[0]).hypot(kept[1] - goal[1]) <= KEEP_INSIDE
                                && tried.is_none_or(|t| (t[0], t[1]) != (kept[0], kept[1]))
                        })
                        .find_map(|kept| {
                            self.kept(start, kept, load, &mut first_action_us)
                                .map(|route| (kept, route))
                        });
                    if let Some((kept, route)) = found {
                        goals[k] = kept;
                        rolled = Ok(route);
                    }
                }
                // A release that no height makes free in the arm's own
                // shape (a 15 mm product let go in a tote 350 mm deep:
                // the forearm of the shape it was carried in against the
                // near wall at every height): the same release in another
                // arm shape, raised as the learned one is, as the
                // expert's inverse kinematics takes its nearest free
                // solution there (helper AA's cells: every such release
                // went to RRT-Connect). First one motion there at any
                // height, as the expert's is (from the height the
                // expert's own lets go at, then the lower ones: 36 ms a
                // release from the lowest up), then through the other
                // shape's joints above the slot (a second longer, where
                // the swing at the lowest height dragged the cup along
                // the wall). Only a shape from which the back-up finds
                // its way up (in some, the forearm folds into wrist 2 on
                // every way up: 1.5 s of searching, then RRT-Connect).
                if release_collides(switch, &rolled) && !self.station.late() {
                    let up = Load::released(plan.product);
                    let above = goals[1][2];
                    let mut heights: Vec<f64> = std::iter::once(goal[2])
                        .chain(self.raise_heights(goal[2], (goal[2], ceiling)))
                        .collect();
                    if let Some(experts) = experts_height {
                        let lower = heights.iter().take_while(|z| **z < experts - 1e-9).count();
                        heights.rotate_left(lower);
                    }
                    let reshaped = |direct: bool| {
                        let budget = |_: &&f64| !self.station.late();
                        heights.iter().take_while(budget).find_map(|&z| {
                            let raised = [goal[0], goal[1], z];
                            self.reshaped_then(
                                start,
                                raised,
                                tolerance,
                                load,
                                Shapes::Others,
                                &mut |route| {
                                    let end = *route.waypoints.last()?;
                                    (!direct || route.waypoints.len() == 1)
                                        .then(|| self.way_up(end, above, up, Ways::All).ok())
                                        .flatten()
                                        .map(|_| ())
                                },
                            )
                        })
                    };
                    if let Some((route, ())) = reshaped(true).or_else(|| reshaped(false)) {
                        rolled = Ok(route);
                    }
                }
                // A release raised over the expert's lets the product drop
                // past the rim, where one a millimetre over a wall lands
                // on it and tips (a 10 mm tray in a slot flush with the
                // wall, let go 10 cm up over it: 24 mm off its slot): its
                // product is kept inside the walls at that height, or,
                // where it would land on a wall and keeping it inside
                // moves it more than a learned release is moved (or finds
                // no way there), the expert's release is used.
                let dropped = rolled
                    .as_ref()
                    .ok()
                    .and_then(|r| r.waypoints.last())
                    .map(|end| [goals[k][0], goals[k][1], self.station.tip(end)[2]])
                    .filter(|aim| {
                        switch == Suction::Off && aim[2] >= plan.expert[k].tip[2] + RAISE_STEP
                    });
                if let Some(aim) = dropped
                    && !self.station.late()
                    && let Some(inside) = plan.inside
                    && let (kept, over) = inside.keep_dropped(aim)
                    && kept != aim
                {
                    let by_m = (kept[0] - aim[0]).hypot(kept[1] - aim[1]);
                    let route = (by_m <= KEEP_INSIDE)
                        .then(|| self.kept(start, kept, load, &mut first_action_us))
                        .flatten();
                    match route {
                        Some(route) => {
                            goals[k] = kept;
                            rolled = Ok(route);
                        }
                        None if over > 0.0 => rolled = Err(Shortfall::OverWall { by_m }),
                        None => {}
                    }
                }
                // A release reached only with the product far above its
                // box's rim (the point above the slot raised over what
                // stood under the carry, and the release from there raised
                // as far as the expert's own from there would be): the
                // product would fall that far (helper R's cell 6210: 0.46
                // m over the rim, onto the arm). The expert's release
                // instead. In a deep box the expert's own release rises to
                // about the rim, and so may the learned one.
                if switch == Suction::Off
                    && plan.stage == Stage::Placing
                    && let Ok(route) = &rolled
                    && let Some(end) = route.waypoints.last()
                    && let height_m = self.station.tip(end)[2] - plan.height - plan.feature[2]
                    && height_m > MAX_ABOVE_RIM
                {
                    rolled = Err(Shortfall::DropsFrom { height_m });
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
            // used instead, as for a release dropped onto a wall.
            let colliding = rolled.as_ref().is_some_and(|r| {
                release_collides(switch, r)
                    || matches!(
                        r,
                        Err(Shortfall::OverWall { .. } | Shortfall::DropsFrom { .. })
                    )
            });
            let route = match rolled {
                Some(Ok(route)) => {
                    // The approach, in the shape the motion above the
                    // slot kept (the leg before this one).
                    if let Some(approach) = approach_again
                        && let Some(end) = approach.waypoints.last().copied()
                        && let Some(leg) = legs.last_mut()
                    {
                        *leg = Leg::new(approach, Suction::Keep, load);
                        tips[0] = self.station.tip(&end);
                        if let Some(reached) = self.station.subgoals.last_mut() {
                            *reached = tips[0];
                        }
                    }
                    route
                }
                other => 'fell: {
                    let why = match (fallen, off, other) {
                        (false, Some(distance_m), _) => Some(Shortfall::OffTarget {
                            distance_m,
                            target: match switch {
                                Suction::On => Target::TopFace,
                                _ => Target::Slot,
                            },
                        }),
                        (_, _, Some(Err(why))) => Some(why),
                        _ => None,
                    };
                    // A learned contact that collides (the arm's shape
                    // kept from the stage's start puts a wrist or the
                    // forearm into a taller product standing beside, or
                    // folds the forearm into the base): RRT-Connect from
                    // the learned hover would change the arm's shape down
                    // among the products, and leave the lift in a shape
                    // the next stage's steps cannot follow. The stage
                    // again from its start instead, as for a lift with no
                    // way up: first with a free grip shape at the learned
                    // sub-goals, the arm changing its shape on the way to
                    // the learned hover (not a fallback; so is a learned
                    // lift that collides), else by the expert's
                    // sub-goals (a fallback, below).
                    let shape_blocked = regrip::contact_blocked(plan, k, why.as_ref());
                    if (shape_blocked || regrip::lift_collides(plan, k, why.as_ref()))
                        && !self.station.late()
                        && let Some(hover) = legs.get(pending_legs).map(|l| &l.route)
                        && let Some((gripped, lift)) =
                            self.grip_learned(plan, from, hover, goals[1])
                    {
                        let elapsed = self.station.spend(k + 1, started)?;
                        self.station.timing.subgoal(kind, elapsed * 1e6);
                        tips = self.replan(&mut legs, pending_legs, subgoals_before, gripped);
                        goals[2] = lift;
                        break 'subgoals;
                    }
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
                    let again = (shape_blocked && !self.station.late())
                        .then(|| self.regrip(plan, from))
                        .flatten();
                    let regripped = match again {
                        Some(regripped) => regripped,
                        None => {
                            let target = (off.is_none() && !colliding).then_some(SubGoal {
                                tip: goal,
                                suction: switch,
                            });
                            match self.fall_back(k, start, target, &plan.expert, load, ceiling) {
                                Ok((route, expert)) => {
                                    if expert {
                                        goals[k] = plan.expert[k].tip;
                                        if let Some(f) = self.fallbacks.last_mut()
                                            && f.product == plan.product
                                            && f.stage == plan.stage
                                        {
                                            f.expert_from.get_or_insert(k + 1);
                                        }
                                    }
                                    break 'fell route;
                                }
                                // No way up from the contact reached: the
                                // stage again from its start, gripping with
                                // a shape the lift leaves freely.
                                Err(why)
                                    if regrip::lift_blocked(plan, k, &why)
                                        && !self.station.late() =>
                                {
                                    let Some(regripped) = self.regrip(plan, from) else {
                                        return Err(why);
                                    };
                                    regripped
                                }
                                Err(why) => return Err(why),
                            }
                        }
                    };
                    let elapsed = self.station.spend(k + 1, started)?;
                    self.station.timing.subgoal(kind, elapsed * 1e6);
                    tips = self.replan(&mut legs, pending_legs, subgoals_before, regripped);
                    goals = plan.expert.each_ref().map(|g| g.tip);
                    if let Some(f) = self.fallbacks.last_mut()
                        && f.product == plan.product
                        && f.stage == plan.stage
                    {
                        f.expert_from = Some(1);
                    }
                    break 'subgoals;
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

    /// The picking stage's legs after the first `pending` replaced by
    /// `gripped` (hover, contact, lift: a stage planned again from its
    /// start), and its sub-goals after the first `subgoals_before` by
    /// where those legs end: the cup tip at each.
    fn replan(
        &mut self,
        legs: &mut Vec<Leg>,
        pending: usize,
        subgoals_before: usize,
        gripped: regrip::StageLegs,
    ) -> [[f64; 3]; 3] {
        legs.truncate(pending);
        self.station.subgoals.truncate(subgoals_before);
        gripped.map(|(leg, end)| {
            let tip = self.station.tip(&end);
            self.station.subgoals.push(tip);
            legs.push(leg);
            tip
        })
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
        let held = Held::under_cup(
            plan.product,
            size,
            s.task.cell.suction,
            flange.inverse() * off,
        );
        s.checker.lifting(held, None)
    }

    /// The checked way from `start`, where the cup let go, straight up to
    /// height `z`: its end found by the dynamics policy's steps (by
    /// inverse kinematics where they fall short), joined straight, or
    /// (with [`Ways::All`]) up a vertical line of via points where that
    /// collides.
    fn way_up(&self, start: Joints, z: f64, load: Load, ways: Ways) -> Result<Route, Failure> {
        let s = &self.station;
        // Straight up from where the cup let go: a learned "above" a few
        // millimetres off in x or y would drag the cup along a wall.
        let [x, y, z0] = s.tip(&start);
        let up = SubGoal {
            tip: [x, y, z],
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
        let solved = || {
            s.solve(&up, 1, &start, 0.0, load, z)
                .map(|solved| solved.joints)
        };
        let target = match stepped {
            Some(q) => q,
            None => solved()?,
        };
        let straight = s.checked(1, start, &[target], load).or_else(|why| {
            // Steps from an arm a fallback left on another shape than the
            // policy was taught in can fold the forearm into wrist 2 (the
            // expert's release beside a tall bottle, wrist flipped): up
            // to the solution nearest the start instead, in the start's
            // own shape. Searching ever higher for a free end of the
            // steps took 0.9 s there.
            match stepped {
                Some(_) => solved()
                    .ok()
                    .filter(|q| *q != target)
                    .and_then(|q| s.checked(1, start, &[q], load).ok())
                    .ok_or(why),
                None => Err(why),
            }
        });
        match straight {
            Ok(route) => Ok(route),
            Err(straight) if ways == Ways::Straight => Err(straight),
            // A straight joint motion bows sideways; from a slot near a
            // wall, go up a vertical line of via points instead, and of
            // more where their segments still bow into the wall (a cup a
            // fraction of a millimetre inside a narrow box's padded wall).
            Err(straight) => {
                let line = |n: usize| -> Result<Vec<Joints>, Failure> {
                    let mut near = start;
                    let mut vias = Vec::with_capacity(n);
                    for i in 1..=n {
                        let h = z0 + (z - z0) * i as f64 / n as f64;
                        let via = SubGoal {
                            tip: [x, y, h],
                            suction: Suction::Keep,
                        };
                        near = s.solve(&via, 1, &near, 0.0, load, h)?.joints;
                        vias.push(near);
                    }
                    Ok(vias)
                };
                s.checked(1, start, &line(RETREAT_VIAS)?, load)
                    .or_else(|_| s.checked(1, start, &line(FINE_RETREAT_VIAS)?, load))
                    .map_err(|_| straight)
            }
        }
    }

    /// The checked way straight up to the height of `above` (the learned
    /// "above the slot" sub-goal), or [`RAISE_STEP`]s higher where that
    /// is blocked, from the released product `name` ([`Learned::way_up`]);
    /// not sent: it is sent with the next product's hover (or alone at
    /// the end of the run).
    fn retreat(&mut self, above: [f64; 3], name: &str) -> Result<Leg, Failure> {
        self.station.stage = None;
        let load = Load::released(name);
        // The released product where it lies (its last observed place was
        // under the cup). Observed before the planning is timed, as the
        // other planners observe before they plan their back-up.
        let obs = self.station.world.observe();
        self.station.sync_products(&obs);
        let started = self.station.begin();
        let start = obs.joints;
        let route = match self.way_up(start, above[2], load, Ways::All) {
            Ok(route) => route,
            // Up to a learned "above the slot" lower than what stands
            // beside the slot (wrist 3 against a tall product packed next
            // to it): higher, as far as that needs; first straight up
            // alone at each height (one check), as
            // [`Learned::raised_over`] tries its heights.
            Err(first) => {
                let heights =
                    || raises(above[2], MAX_CARRY_RAISES).take_while(|_| !self.station.late());
                let learned = heights()
                    .find_map(|z| self.way_up(start, z, load, Ways::Straight).ok())
                    .or_else(|| {
                        heights().find_map(|z| self.way_up(start, z, load, Ways::All).ok())
                    });
                match learned {
                    Some(route) => route,
                    // No way up from where the product was let go (the
                    // forearm folded into wrist 2 on every way up, close to
                    // the base): the product is in its slot, so the
                    // back-up goes as RRT-Connect's does, to the solution
                    // above the release (a fallback, not a failure).
                    None => {
                        let route = self
                            .backed_up(start, above[2], load)
                            .ok_or_else(|| first.clone())?;
                        let why = match first {
                            Failure::WouldCollide { hit, .. }
                            | Failure::Unreachable { met: Some(hit), .. } => {
                                Shortfall::Collides { hit }
                            }
                            Failure::Unreachable { way: Some(hit), .. } => {
                                Shortfall::Collides { hit: *hit }
                            }
                            Failure::Smoothing { reason, .. } => Shortfall::Smoothing { reason },
                            _ => Shortfall::Short {
                                steps: 0,
                                distance_m: (above[2] - self.station.tip(&start)[2]).abs(),
                            },
                        };
                        self.fallbacks.push(Fallback {
                            product: name.to_owned(),
                            stage: Stage::Placing,
                            subgoal: BACK_UP_SUBGOAL,
                            why,
                            expert_from: None,
                        });
                        route
                    }
                }
            }
        };
        // Timed as a sub-goal, as the other planners' back-up is.
        let elapsed = self.station.spend(1, started)?;
        self.station
            .timing
            .subgoal(SubGoalKind::BackUp, elapsed * 1e6);
        Ok(Leg::new(route, Suction::Keep, load))
    }

    /// RRT-Connect's way from `start` to `goal` (sub-goal `subgoal`),
    /// solved as the expert solves it, raised no higher than `ceiling`.
    fn rrt_to(
        &self,
        goal: &SubGoal,
        subgoal: usize,
        start: Joints,
        load: Load,
        ceiling: f64,
    ) -> Result<Route, Failure> {
        let s = &self.station;
        let solved = s.solve(goal, subgoal, &start, 0.0, load, ceiling)?;
        let how = Connect::Rrt { seed: self.seed };
        s.route_solved(how, subgoal, start, solved, 0.0, load)
            .map(|(_, route)| route)
    }

    /// RRT-Connect's way from `start`, where the cup let go, to straight
    /// above it at height `z` ([`Learned::rrt_to`]).
    fn backed_up(&self, start: Joints, z: f64, load: Load) -> Option<Route> {
        let [x, y, _] = self.station.tip(&start);
        let up = SubGoal {
            tip: [x, y, z],
            suction: Suction::Keep,
        };
        self.rrt_to(&up, 1, start, load, z).ok()
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
        let stood = obs.find(&product).map(|(centre, _)| centre);
        self.station.measure(&mut rows[row], p, s);
        let unmoved = self.station.unmoved(p, stood);
        let handled = match result {
            // A placing decision that broke the order: the product was
            // not put anywhere (its row stays "not attempted").
            Err(Halt::Violation(v)) => return Err(Stopped::Violation(v)),
            Err(Halt::Failed(why)) => Err(why),
            Ok(()) => Ok(()),
        };
        judge(&mut rows[row], handled, unmoved, self.station.stage).map_err(Stopped::Failed)
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
        let (centre, yaw) = obs.find(name).ok_or(Failure::Disappeared)?;
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
                loads: [Load::picking(name); 3],
                gripped: Some(spec.size),
                yaw,
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
        let slot = expert::release_at(cell, &cell.slots[s], spec.size);
        let expert = expert::placing(
            picked.tips[2],
            [slot[0] - grip[0], slot[1] - grip[1]],
            spec.size[2],
            expert::box_height(cell, s),
            [cell.base[0], cell.base[1]],
        );
        let carrying = Load::holding(&held);
        // Down into the slot, padded as the room beside it allows, the
        // product turned as the cup carries it.
        let m = flange.to_rotation_matrix().into_inner();
        let lowered = self.station.checker.lowering(
            held.clone(),
            expert::released_centre(slot, spec.size[2]),
            m[(1, 0)].atan2(m[(0, 0)]),
        );
        let (placed, _) = self.stage(
            &StagePlan {
                stage: Stage::Placing,
                product: name,
                feature: [rim[0] - grip[0], rim[1] - grip[1], rim[2]],
                height: spec.size[2],
                contact: None,
                loads: [carrying, carrying, Load::holding(&lowered)],
                gripped: None,
                yaw: 0.0,
                expert,
                inside: Inside::new(
                    cell,
                    cell.slots[s].box_index,
                    spec.size,
                    grip,
                    &flange,
                    lowered.side_pad,
                )
                .map(|inside| inside.with_wrist(cell.suction, wrist_around_tool(self.station.arm))),
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
            // A product not attempted has no final distance from its slot
            // (as the other planners report it): only one already packed.
            let error = runner.station.error_of(&first, p, s);
            row.outcome = match error {
                None => Outcome::Waiting,
                Some(e) if e <= SUCCESS_RADIUS => {
                    row.error_m = error;
                    Outcome::AlreadyPacked
                }
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
    use super::on_face;

    /// A grip 9 mm off the centre of a 21 mm cube misses its face; 7 mm
    /// off along both sides, it is on it. A 60 x 30 mm face turned a
    /// quarter turn is 60 mm along y: 25 mm along y is on it, 25 mm along
    /// x is not.
    #[test]
    fn a_grip_is_on_the_face_only_within_its_sides() {
        let small = [0.021, 0.021, 0.021];
        assert!(!on_face(0.009, 0.0, small, 0.0));
        assert!(on_face(0.007, -0.007, small, 0.0));
        let long = [0.06, 0.03, 0.05];
        let quarter = std::f64::consts::FRAC_PI_2;
        assert!(on_face(0.0, 0.025, long, quarter));
        assert!(!on_face(0.025, 0.0, long, quarter));
        assert!(on_face(0.025, 0.0, long, 0.0));
    }
}
