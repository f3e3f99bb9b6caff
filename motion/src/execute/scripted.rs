//! The expert's and RRT-Connect's loop: the next product in the order
//! given (the assignment's, or a sequence rule's chain), the expert's three
//! sub-goals per stage, the inverse-kinematics branch nearest the current
//! joints among the free ones, joined straight or by RRT-Connect (the
//! expert searches too where every straight way collides); the
//! expert's runs can be recorded as motion demonstrations.

use super::station::{
    Connect, Leg, Load, PlanningBudget, SUCCESS_RADIUS, Solved, Station, distance, judge, leg_end,
};
use crate::collision::Held;
use crate::expert::{self, SubGoal, Suction};
use nalgebra::Vector3;
use packwright_interface::outcome::{Failure, Outcome, PlannerKind, Report, Stage, SubGoalKind};
use packwright_interface::record::{self, ActionSample, MotionLog, SubGoalSample};
use packwright_interface::{OrderTask, SequenceRule, World};
use packwright_kinematics::{Arm, Joints};
use std::time::Instant;

/// What a stage's sub-goals are recorded with.
#[derive(Debug, Clone, Copy)]
struct StageInfo {
    stage: Stage,
    feature: [f64; 3],
    label: u32,
    height: f64,
}

struct Scripted<'a, W: World> {
    station: Station<'a, W>,
    connect: Connect,
    log: Option<&'a mut MotionLog>,
}

/// One sub-goal of a stage, solved before the arm moves.
struct Planned {
    goal: SubGoal,
    /// The joints, nearest the previous sub-goal's (with a release's or a
    /// lift's checked straight motion from them).
    solved: Solved,
    /// How high a release may be raised.
    ceiling: f64,
    /// Microseconds its inverse kinematics took.
    solve_us: f64,
    /// Solved in one arm shape with the rest of its stage
    /// ([`Station::grip`]): reached in it, not at another solution.
    in_shape: bool,
}

impl<W: World> Scripted<'_, W> {
    /// Solves every sub-goal of a stage before the arm moves (a release the
    /// wrist cannot reach is raised up to the previous sub-goal's height):
    /// an unreachable sub-goal stops the stage before it starts.
    fn plan_stage(
        &mut self,
        from: Joints,
        goals: &[SubGoal],
        yaw: f64,
        loads: [Load; 3],
    ) -> Result<Vec<Planned>, Failure> {
        let mut out = Vec::new();
        let mut current = from;
        for ((k, g), load) in goals.iter().enumerate().zip(loads) {
            let started = self.station.begin();
            let ceiling = goals
                .get(k.wrapping_sub(1))
                .map_or(g.tip[2], |prev| prev.tip[2]);
            let solved = self.station.solve(g, k + 1, &current, yaw, load, ceiling);
            let took = self.station.spend(k + 1, started)?;
            let solved = solved?;
            current = solved.joints;
            out.push(Planned {
                goal: *g,
                solved,
                ceiling,
                solve_us: took * 1e6,
                in_shape: false,
            });
        }
        Ok(out)
    }

    /// The picking sub-goals solved from the contact's arm shape
    /// ([`Station::grip`]), timed as the hover's, the contact's and the
    /// lift's planning (the search in the first).
    fn grip_stage(
        &mut self,
        from: Joints,
        goals: &[SubGoal; 3],
        yaw: f64,
        loads: [Load; 3],
        lifting: &Held,
    ) -> Option<Vec<Planned>> {
        let started = self.station.begin();
        let [free, guarded, _] = loads;
        let guarded = guarded.guarded(self.station.task.cell.descent);
        let solved = self
            .station
            .grip(goals, &from, yaw, [free, guarded], &|_| lifting.clone());
        let took = self.station.spend(1, started).ok()?;
        let solve_us = [took * 1e6, 0.0, 0.0];
        Some(
            solved?
                .into_iter()
                .zip(goals)
                .zip(solve_us)
                .map(|((solved, goal), solve_us)| Planned {
                    goal: *goal,
                    solved,
                    ceiling: goal.tip[2],
                    solve_us,
                    in_shape: true,
                })
                .collect(),
        )
    }

    /// The placing sub-goals with the point above the slot and the
    /// release solved from the release's arm shape
    /// ([`Station::release_shape`]), the approach as [`plan_stage`]
    /// solves it; timed as the approach's, the point above the slot's
    /// (the search) and the release's planning.
    ///
    /// [`plan_stage`]: Scripted::plan_stage
    fn release_stage(
        &mut self,
        from: Joints,
        goals: &[SubGoal; 3],
        loads: [Load; 3],
    ) -> Option<Vec<Planned>> {
        let mut plan = self
            .plan_stage(from, &goals[..1], 0.0, [loads[0]; 3])
            .ok()?;
        let approach = plan.first()?.solved.joints;
        let started = self.station.begin();
        let shaped = self
            .station
            .release_shape([&goals[1], &goals[2]], &approach, 0.0, loads[1]);
        let took = self.station.spend(2, started).ok()?;
        let [above, release] = shaped?;
        plan.push(Planned {
            goal: goals[1],
            solved: above,
            ceiling: goals[0].tip[2],
            solve_us: took * 1e6,
            in_shape: false,
        });
        plan.push(Planned {
            goal: goals[2],
            solved: release,
            ceiling: goals[1].tip[2],
            solve_us: 0.0,
            in_shape: false,
        });
        Some(plan)
    }

    /// How much the run has recorded: the sub-goals reached and, when
    /// demonstrations are recorded, their samples.
    fn marks(&self) -> [usize; 3] {
        let log = self.log.as_deref();
        [
            self.station.subgoals.len(),
            log.map_or(0, |l| l.subgoals.len()),
            log.map_or(0, |l| l.actions.len()),
        ]
    }

    /// Forgets what a stage that was not sent recorded after `marks`.
    fn rewind(&mut self, [subgoals, samples, actions]: [usize; 3]) {
        self.station.subgoals.truncate(subgoals);
        if let Some(log) = self.log.as_deref_mut() {
            log.subgoals.truncate(samples);
            log.actions.truncate(actions);
        }
    }

    /// Records one sub-goal and the actions along the way to it.
    fn record(
        &mut self,
        info: StageInfo,
        k: usize,
        start: &Joints,
        goal: &Joints,
        samples: &[Joints],
    ) {
        let station = &self.station;
        let Some(log) = self.log.as_deref_mut() else {
            return;
        };
        let target = station.tip(goal);
        log.subgoals.push(SubGoalSample {
            feature: info.feature,
            height: info.height,
            tool: station.tip(start),
            label: info.label,
            stage: info.stage,
            index: k as u8,
            target,
            start: *start,
            goal: *goal,
        });
        let subgoal = log.subgoals.len() - 1;
        let along: Vec<Joints> = std::iter::once(*start)
            .chain(samples.iter().copied())
            .collect();
        for i in record::spread(along.len(), record::SAMPLES_PER_SUBGOAL) {
            let here = station.tip(&along[i]);
            log.actions.push(ActionSample {
                subgoal,
                delta: std::array::from_fn(|j| target[j] - here[j]),
                joints: station.arm.policy_joints(&along[i]),
                action: record::action(&along[i], goal),
            });
        }
    }

    /// Joins, smooths and checks one stage's motions (from where the
    /// `pending` legs of the stage before end, else from where the arm is,
    /// to each planned sub-goal, or to another solution of it when the
    /// planned one cannot be joined; the sub-goals after such a change are
    /// solved again from it), then sends them after the pending ones,
    /// passing through the sub-goals where the suction does not switch
    /// ([`Station::send_legs`]); switches the suction. With `keep_tail`,
    /// the legs after the last switch are returned unsent.
    fn run_stage(
        &mut self,
        plan: Vec<Planned>,
        yaw: f64,
        loads: [Load; 3],
        info: Option<StageInfo>,
        pending: Vec<Leg>,
        keep_tail: bool,
    ) -> Result<Vec<Leg>, Failure> {
        let mut start = leg_end(&pending).unwrap_or_else(|| self.station.world.observe().joints);
        let mut replanned = false;
        let mut legs = pending;
        let descent = self.station.task.cell.descent;
        // No stage: the back-up from a release.
        let kinds = info.map_or([SubGoalKind::BackUp; 3], |i| SubGoalKind::of(i.stage));
        for (((k, planned), load), kind) in plan.into_iter().enumerate().zip(loads).zip(kinds) {
            // The motion onto a top face is the guarded descent.
            let load = if planned.goal.suction == Suction::On {
                load.guarded(descent)
            } else {
                load
            };
            let started = self.station.begin();
            let how = match self.connect {
                Connect::Rrt { seed } => Connect::Rrt {
                    seed: seed.wrapping_add(k as u64),
                },
                straight => straight,
            };
            let planned_joints = planned.solved.joints;
            let in_shape = planned.in_shape && !replanned;
            let solved = if replanned {
                self.station
                    .solve(&planned.goal, k + 1, &start, yaw, load, planned.ceiling)
            } else {
                Ok(planned.solved)
            };
            // The joints alone are kept for a search: a solve's straight
            // route matched nothing if routing from `start` failed.
            let target = solved.as_ref().ok().map(|s| s.joints);
            // A plan solved in one arm shape (`grip_stage`) is reached in
            // it: routed to another solution of the hover (another shape),
            // the descent and the lift were solved again nearest it, and
            // failed as the first plan had.
            let routed = solved.and_then(|solved| {
                if in_shape {
                    self.station.route_in_shape(how, k + 1, start, solved, load)
                } else {
                    self.station
                        .route_solved(how, k + 1, start, solved, yaw, load)
                }
            });
            // The expert's last resort: where the straight motion and both
            // swings collide for every solution (a wrist over a deep box's
            // wall), RRT-Connect's search to the sub-goal (the checks just
            // failed are not repeated), seeded by the sub-goal so that runs
            // stay reproducible; a package, or a demonstration's replay, is
            // not ended for a motion a search finds. If that fails too, the
            // straight motion's collision is the reason.
            let routed = match (how, routed, target) {
                (Connect::Straight, Err(why @ Failure::WouldCollide { .. }), Some(target))
                    if in_shape =>
                {
                    self.station
                        .search(k as u64, k + 1, start, target, load)
                        .map(|route| (target, route))
                        .map_err(|_| why)
                }
                (Connect::Straight, Err(why @ Failure::WouldCollide { .. }), Some(target)) => self
                    .station
                    .search_any(k as u64, k + 1, start, target, yaw, load)
                    .map_err(|_| why),
                (_, routed, _) => routed,
            };
            let elapsed = self.station.spend(k + 1, started)?;
            self.station
                .timing
                .subgoal(kind, planned.solve_us + elapsed * 1e6);
            let (goal, route) = routed?;
            replanned |= goal != planned_joints;
            let reached = self.station.tip(&goal);
            self.station.subgoals.push(reached);
            if let Some(info) = info {
                self.record(info, k, &start, &goal, &route.samples);
            }
            legs.push(Leg::new(route, planned.goal.suction, load));
            start = goal;
        }
        self.station.send_legs(legs, keep_tail)
    }

    /// Picks product `p` and places it in slot `s`, after the kept
    /// back-up from the product before (blended into the hover); the way
    /// back up from this release, checked, unsent.
    fn manipulate(&mut self, p: usize, s: usize) -> Result<Vec<Leg>, Failure> {
        let task = self.station.task;
        let spec = &task.products[p];
        let name = spec.name.as_str();
        let cell = &task.cell;
        let obs = self.station.world.observe();
        self.station.sync_products(&obs);
        let (centre, yaw) = obs.find(name).ok_or(Failure::Disappeared)?;
        let h = spec.size[2];
        let picking = expert::picking(centre, h, cell.lift);
        let free = Load::picking(name);
        // Once gripped, the lift carries the product off where it stood.
        let gripped = Held::under_cup(name, spec.size, cell.suction, Vector3::zeros());
        let lifting = self.station.checker.lifting(gripped.clone(), None);
        let picking_loads = [free, free, Load::holding(&lifting)];
        let from = self.station.backup_end().unwrap_or(obs.joints);
        self.station.stage = Some(Stage::Picking);
        let pick = StageInfo {
            stage: Stage::Picking,
            feature: centre,
            label: 0,
            height: h,
        };
        // The back-up before is sent with the hover, and the lift with the
        // carry, blended into them.
        let backup = self.station.take_backup();
        let marks = self.marks();
        let lift = match self
            .plan_stage(from, &picking, yaw, picking_loads)
            .and_then(|plan| {
                self.run_stage(plan, yaw, picking_loads, Some(pick), backup.clone(), true)
            }) {
            Ok(lift) => lift,
            // No free way down onto the product or up from it with the arm's
            // shape nearest where it is, and nothing sent yet: the stage
            // again from the contact's shape ([`Station::grip`]).
            Err(why) if shape_blocked(&why, 2) && self.station.clock.steps == 0 => {
                self.rewind(marks);
                let plan = self
                    .grip_stage(from, &picking, yaw, picking_loads, &lifting)
                    .ok_or(why)?;
                self.run_stage(plan, yaw, picking_loads, Some(pick), backup, true)?
            }
            Err(why) => return Err(why),
        };

        let obs = self.station.world.observe();
        let held = gripped;
        let slot = expert::release_at(cell, &cell.slots[s], spec.size);
        let placing = expert::placing(
            picking[2].tip,
            slot,
            h,
            expert::box_height(cell, s),
            [cell.base[0], cell.base[1]],
        );
        self.station.sync_products(&obs);
        let carrying = Load::holding(&held);
        // Placing the product square in its slot: yaw 0 (it turns with the cup).
        // Down into the slot, padded as the room beside it allows.
        let lowered =
            self.station
                .checker
                .lowering(held.clone(), expert::released_centre(slot, h), 0.0);
        let loads = [carrying, carrying, Load::holding(&lowered)];
        let from = leg_end(&lift).unwrap_or(obs.joints);
        self.station.stage = Some(Stage::Placing);
        let plan = match self.plan_stage(from, &placing, 0.0, loads) {
            Ok(plan) => plan,
            // No free way down into the slot from the point above it in
            // the arm's shape nearest where it is: the point above the
            // slot in the release's shape ([`Station::release_shape`]).
            Err(why) if shape_blocked(&why, 3) => {
                self.release_stage(from, &placing, loads).ok_or(why)?
            }
            Err(why) => return Err(why),
        };
        let place = StageInfo {
            stage: Stage::Placing,
            feature: task.slot_rim(s),
            label: s as u32 + 1,
            height: h,
        };
        self.run_stage(plan, 0.0, loads, Some(place), lift, false)?;

        // Back up from the released product, which the checker now sees
        // where it lies (its last observed place was under the cup).
        let obs = self.station.world.observe();
        self.station.sync_products(&obs);
        let up = [SubGoal {
            tip: [slot[0], slot[1], placing[1].tip[2]],
            suction: Suction::Keep,
        }];
        let left = Load::released(name);
        self.station.stage = None;
        let plan = self.plan_stage(obs.joints, &up, 0.0, [left; 3])?;
        // Kept, to be sent with the next product's hover.
        self.run_stage(plan, 0.0, [left; 3], None, Vec::new(), true)
    }
}

/// Whether a stage's failure `why`, at sub-goal `first` or after it, can
/// come from the arm's shape there rather than from the budget or the
/// smoother: no free way down onto a product or up from it (picking, from
/// sub-goal 2), or down to the release (placing, sub-goal 3).
fn shape_blocked(why: &Failure, first: usize) -> bool {
    match why {
        Failure::Unreachable { subgoal, .. }
        | Failure::NoPath { subgoal }
        | Failure::WouldCollide { subgoal, .. } => (first..=3).contains(subgoal),
        _ => false,
    }
}

/// The assignment's indices in the order the products are handled: the
/// assignment's own (a demonstration's sequence), or `rule`'s chain (the
/// order the reasoner is judged by), a product the rule does not name
/// after those it does, in the assignment's order.
fn turns(task: &OrderTask, rule: Option<&SequenceRule>) -> Vec<usize> {
    let mut order: Vec<usize> = (0..task.assignment.len()).collect();
    if let Some(rule) = rule {
        let names: Vec<&str> = task.products.iter().map(|p| p.name.as_str()).collect();
        let chain = rule.chain(&names);
        order.sort_by_key(|&i| {
            chain
                .iter()
                .position(|&p| p == task.assignment[i].0)
                .unwrap_or(usize::MAX)
        });
    }
    order
}

/// Packs `task`, handling its products in the assignment's order or, with
/// `rule`, in the rule's; the report's rows are in the assignment's order
/// either way.
pub(super) fn run<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    connect: Connect,
    log: Option<&mut MotionLog>,
    budget: PlanningBudget,
    rule: Option<&SequenceRule>,
) -> Report {
    let planner = match connect {
        Connect::Straight => PlannerKind::Expert,
        Connect::Rrt { .. } => PlannerKind::Rrt,
    };
    let mut station = Station::new(world, arm, task);
    station.budget = budget;
    let mut runner = Scripted {
        station,
        connect,
        log,
    };
    let mut products: Vec<_> = task
        .assignment
        .iter()
        .map(|&(p, s)| runner.station.row(p, s))
        .collect();
    let mut stopped = false;
    let mut collisions = Vec::new();
    for i in turns(task, rule) {
        let (p, s) = task.assignment[i];
        let decided = Instant::now();
        let goal = task.goal(p, s);
        let report = &mut products[i];
        let obs = runner.station.world.observe();
        match obs.find(&report.product) {
            None => report.outcome = Outcome::Waiting,
            Some((c, _)) if distance(c, goal) <= SUCCESS_RADIUS => {
                report.error_m = Some(distance(c, goal));
                report.outcome = Outcome::AlreadyPacked;
            }
            Some(_) if stopped => {}
            Some((stood, _)) => {
                runner
                    .station
                    .timing
                    .decision_us
                    .push(decided.elapsed().as_secs_f64() * 1e6);
                runner.station.restart_clock();
                let result = runner.manipulate(p, s).map(|backup| {
                    runner.station.keep_backup(backup, i);
                });
                runner.station.measure(report, p, s);
                let unmoved = runner.station.unmoved(p, Some(stood));
                if let Err(why) = judge(report, result, unmoved, runner.station.stage) {
                    stopped = true;
                    if let Failure::Collision { contact } = why {
                        collisions.push(contact);
                    }
                }
            }
        }
    }
    if let Err(Failure::Collision { contact }) = runner.station.flush_backup(&mut products) {
        collisions.push(contact);
    }
    runner.station.finish(planner, products, collisions)
}
