//! The execution loop: observe, choose the next product, plan each stage's
//! three sub-goals, check the motion, smooth it with Ruckig at the control
//! rate, and drive the world.
//!
//! Planners:
//! - `expert`: the scripted demonstrator; straight joint-space motions
//!   between the inverse-kinematics solutions of the sub-goals, and the
//!   demonstrated sequence rule (inventory order) for what comes next;
//! - `rrt`: the same sub-goal poses joined by RRT-Connect (the paper's
//!   RM + RRT-Connect baseline).
//!
//! Every smoothed 2 ms command is collision-checked (parry, at joint steps
//! of at most 1 degree) before it is sent; a plan that would collide or an
//! unreachable sub-goal is reported for that product and the arm stops
//! where it is. Observations are only products' positions: what is packed
//! or missing is inferred from them.

use crate::collision::{Checker, Held, MAX_STEP, ProductBody};
use crate::expert::{self, SubGoal, Suction};
use crate::record::{self, ActionSample, MotionLog, SubGoalSample};
use crate::robot::{Arm, Joints, joint_distance, tool_down_pose};
use crate::rrt::{self, Query, RrtConfig};
use crate::scene::{CellScene, ProductSpec};
use crate::smoothing::smooth_path;
use crate::world::{Observation, World};
use nalgebra::{Isometry3, Point3};
use std::f64::consts::FRAC_PI_2;
use std::time::Instant;

mod learned;
pub use learned::{
    Fallback, MAX_POLICY_STEPS, REACHED, REACHED_VIA, Shortfall, cup_down, expected_next,
    policy_steps, reasoner_trial, run_learned,
};

/// A product is packed when its centre is this close to its slot goal.
pub const SUCCESS_RADIUS: f64 = 0.02;
/// How much a release point is raised at a time when the wrist cannot
/// reach it.
const RAISE_STEP: f64 = 0.01;
/// Cycles to wait after switching the suction (0.1 s).
const SUCTION_SETTLE: usize = 50;
/// Cycles to let a released product settle (0.5 s).
const RELEASE_SETTLE: usize = 250;

/// The order to pack, in the runtime's terms.
#[derive(Debug, Clone, PartialEq)]
pub struct OrderTask {
    pub cell: CellScene,
    /// The inventory's products, in listed order.
    pub products: Vec<ProductSpec>,
    /// (index into `products`, index into `cell.slots`) per selected
    /// product, in inventory order.
    pub assignment: Vec<(usize, usize)>,
}

impl OrderTask {
    /// Where product `p` rests in slot `s`.
    pub fn goal(&self, p: usize, s: usize) -> [f64; 3] {
        let slot = &self.cell.slots[s];
        [
            slot.position[0],
            slot.position[1],
            self.products[p].size[2] / 2.0,
        ]
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlannerKind {
    Expert,
    Rrt { seed: u64 },
}

impl PlannerKind {
    pub fn name(&self) -> &'static str {
        match self {
            PlannerKind::Expert => "expert",
            PlannerKind::Rrt { .. } => "rrt",
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Placed by the robot within the success radius.
    Packed,
    /// Already in its slot when the robot came to it (a worker packed it).
    AlreadyPacked,
    /// Not in the cell: waits for restocking.
    Waiting,
    /// The robot could not pack it; the arm stopped.
    Failed(String),
    /// Not attempted because the arm stopped earlier.
    NotAttempted,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ProductReport {
    pub product: String,
    pub slot: String,
    /// Wall-clock seconds spent planning (IK, checks, RRT) for this product.
    pub planning_s: f64,
    /// Simulated (or real) seconds of motion for this product.
    pub execution_s: f64,
    /// Distance of the product's centre from its slot goal at the end.
    pub error_m: Option<f64>,
    pub outcome: Outcome,
}

/// Planning times, microseconds of wall clock.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Timing {
    /// Per decision of what to handle next (the reasoner, or the expert's
    /// sequence rule).
    pub decision_us: Vec<f64>,
    /// Per sub-goal: finding it and planning the motion to it.
    pub subgoal_us: Vec<f64>,
    /// Learned planner only: one sub-goal planner call plus the first
    /// dynamics policy call of its rollout (sub-goals with a rollout).
    pub network_us: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub planner: &'static str,
    pub products: Vec<ProductReport>,
    /// Every present selected product is packed and nothing collided.
    pub complete: bool,
    /// Contacts the world reported, as "a / b".
    pub collisions: Vec<String>,
    pub time_s: f64,
    /// Learned planner: stages handed to RRT-Connect, and why.
    pub fallbacks: Vec<Fallback>,
    /// Learned planner: decisions that broke the order (a product it does
    /// not select, one already packed, a wrong slot); the arm stopped.
    pub violations: Vec<String>,
    pub timing: Timing,
}

fn seen_centre(obs: &Observation, name: &str) -> Option<([f64; 3], f64)> {
    obs.products
        .iter()
        .find(|s| s.name == name)
        .map(|s| (s.centre, s.yaw))
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// One product's manipulation failed: why.
type Failure = String;

struct Runner<'a, W: World> {
    world: &'a mut W,
    arm: &'a Arm,
    task: &'a OrderTask,
    planner: PlannerKind,
    base: Isometry3<f64>,
    checker: Checker,
    planning_s: f64,
    execution_steps: usize,
    log: Option<&'a mut MotionLog>,
    timing: Timing,
}

/// What a stage's sub-goals are recorded with.
#[derive(Debug, Clone, Copy)]
struct StageInfo {
    stage: u8,
    feature: [f64; 3],
    label: u32,
}

impl<'a, W: World> Runner<'a, W> {
    fn new(
        world: &'a mut W,
        arm: &'a Arm,
        task: &'a OrderTask,
        planner: PlannerKind,
        log: Option<&'a mut MotionLog>,
    ) -> Runner<'a, W> {
        let [x, y, z] = task.cell.base;
        Runner {
            checker: Checker::new(arm, &task.cell),
            world,
            arm,
            task,
            planner,
            base: Isometry3::translation(x, y, z),
            planning_s: 0.0,
            execution_steps: 0,
            log,
            timing: Timing::default(),
        }
    }

    fn sync_products(&mut self, obs: &Observation) {
        let bodies: Vec<ProductBody> = obs
            .products
            .iter()
            .filter_map(|s| {
                let spec = self.task.products.iter().find(|p| p.name == s.name)?;
                Some(ProductBody {
                    name: s.name.clone(),
                    centre: s.centre,
                    size: spec.size,
                    yaw: s.yaw,
                })
            })
            .collect();
        self.checker.set_products(&bodies);
    }

    /// Plans the joint waypoints from `from` to each sub-goal. A release
    /// the wrist cannot reach is raised up to the previous sub-goal's
    /// height; `ceiling` is that height for a release that comes first in
    /// `goals` (else it cannot be raised).
    fn plan_stage(
        &mut self,
        from: Joints,
        goals: &[SubGoal],
        yaw: f64,
        held: Option<&Held>,
        ignore: Option<&str>,
        ceiling: Option<f64>,
    ) -> Result<Vec<(Vec<Joints>, Suction)>, Failure> {
        let started = Instant::now();
        let mut out = Vec::new();
        let mut current = from;
        for (k, g) in goals.iter().enumerate() {
            let subgoal_started = Instant::now();
            let solve = |z: f64| {
                let tip = Point3::new(g.tip[0], g.tip[1], z);
                let q = reach(
                    self.arm,
                    &self.checker,
                    &self.base,
                    tip,
                    yaw,
                    self.task.cell.suction,
                    &current,
                    held,
                    ignore,
                )?;
                // A release the straight descent cannot reach (checked as the
                // commands will be) is no release.
                let blocked = g.suction == Suction::Off
                    && checked_samples(self.arm, &self.checker, current, &[q], held, ignore)
                        .is_err();
                (!blocked).then_some(q)
            };
            // A release point the wrist cannot reach (a deep box, a wall
            // near the slot) is raised until it can: the product drops the
            // rest of the way.
            let release_ceiling = goals
                .get(k.wrapping_sub(1))
                .map_or(ceiling.unwrap_or(g.tip[2]), |prev| prev.tip[2]);
            let target = solve(g.tip[2])
                .or_else(|| {
                    (g.suction == Suction::Off)
                        .then(|| {
                            (1..)
                                .map(|i| g.tip[2] + RAISE_STEP * i as f64)
                                .take_while(|z| *z <= release_ceiling)
                                .find_map(solve)
                        })
                        .flatten()
                })
                .ok_or_else(|| {
                    format!(
                        "sub-goal {} at ({:.3}, {:.3}, {:.3}) is unreachable",
                        k + 1,
                        g.tip[0],
                        g.tip[1],
                        g.tip[2]
                    )
                })?;
            let path = match self.planner {
                PlannerKind::Expert => vec![current, target],
                PlannerKind::Rrt { seed } => {
                    let query = Query {
                        checker: &self.checker,
                        limits: &self.arm.limits,
                        held,
                        ignore,
                    };
                    let config = RrtConfig {
                        seed: seed.wrapping_add(k as u64),
                        ..RrtConfig::default()
                    };
                    rrt::plan(&query, current, target, &config)
                        .ok_or_else(|| format!("RRT-Connect found no path to sub-goal {}", k + 1))?
                }
            };
            out.push((path, g.suction));
            current = target;
            self.timing
                .subgoal_us
                .push(subgoal_started.elapsed().as_secs_f64() * 1e6);
        }
        self.planning_s += started.elapsed().as_secs_f64();
        Ok(out)
    }

    /// Smooths, checks and sends one stage's motions; switches the suction.
    /// Records one sub-goal and the actions along the way to it.
    fn record(
        &mut self,
        info: StageInfo,
        k: usize,
        start: &Joints,
        goal: &Joints,
        samples: &[Joints],
    ) {
        let (arm, base, suction) = (self.arm, self.base, self.task.cell.suction);
        let Some(log) = self.log.as_deref_mut() else {
            return;
        };
        let tip = |q: &Joints| -> [f64; 3] { arm.tool_tip(&base, q, suction).coords.into() };
        let target = tip(goal);
        log.subgoals.push(SubGoalSample {
            feature: info.feature,
            tool: tip(start),
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
            let here = tip(&along[i]);
            log.actions.push(ActionSample {
                subgoal,
                delta: std::array::from_fn(|j| target[j] - here[j]),
                joints: [along[i][0], along[i][1], along[i][2]],
                action: record::action(&along[i], goal),
            });
        }
    }

    fn run_stage(
        &mut self,
        plan: Vec<(Vec<Joints>, Suction)>,
        held: Option<&Held>,
        ignore: Option<&str>,
        info: Option<StageInfo>,
    ) -> Result<(), Failure> {
        for (k, (path, suction)) in plan.into_iter().enumerate() {
            let start = self.world.observe().joints;
            let started = Instant::now();
            let samples = checked_samples(self.arm, &self.checker, start, &path[1..], held, ignore);
            self.planning_s += started.elapsed().as_secs_f64();
            let samples =
                samples.map_err(|why| format!("the motion to sub-goal {}: {why}", k + 1))?;
            if let (Some(info), Some(goal)) = (info, path.last()) {
                self.record(info, k, &start, goal, &samples);
            }
            self.send(&samples, suction)?;
        }
        Ok(())
    }

    /// Sends checked commands, then switches the suction and lets things
    /// settle; fails on any contact the world reports.
    fn send(&mut self, samples: &[Joints], suction: Suction) -> Result<(), Failure> {
        for q in samples {
            self.world.command(q).map_err(|e| e.to_string())?;
            self.world.step().map_err(|e| e.to_string())?;
            self.execution_steps += 1;
        }
        let settle = match suction {
            Suction::Keep => 0,
            Suction::On => {
                self.world.set_suction(true).map_err(|e| e.to_string())?;
                SUCTION_SETTLE
            }
            Suction::Off => {
                self.world.set_suction(false).map_err(|e| e.to_string())?;
                RELEASE_SETTLE
            }
        };
        for _ in 0..settle {
            self.world.step().map_err(|e| e.to_string())?;
            self.execution_steps += 1;
        }
        let contacts = self.world.take_collisions();
        if let Some(c) = contacts.first() {
            return Err(format!("collision: {} with {}", c.a, c.b));
        }
        Ok(())
    }

    /// Picks product `p` and places it in slot `s`.
    fn manipulate(&mut self, p: usize, s: usize) -> Result<(), Failure> {
        let spec = &self.task.products[p];
        let name = spec.name.clone();
        let obs = self.world.observe();
        self.sync_products(&obs);
        let (centre, yaw) = seen_centre(&obs, &name).ok_or("the product disappeared")?;
        let h = spec.size[2];
        let cell = &self.task.cell;
        let picking = expert::picking(centre, h, cell.lift);
        let plan = self.plan_stage(obs.joints, &picking, yaw, None, Some(&name), None)?;
        let pick_info = StageInfo {
            stage: 0,
            feature: centre,
            label: 0,
        };
        self.run_stage(plan, None, Some(&name), Some(pick_info))?;
        let obs = self.world.observe();
        let held = Held {
            name: name.clone(),
            size: spec.size,
            in_flange: Isometry3::translation(0.0, 0.0, cell.suction + h / 2.0),
        };
        let lifted = picking[2].tip;
        let slot = cell.slots[s].position;
        let placing = expert::placing(
            lifted,
            slot,
            h,
            expert::box_height(cell, s),
            [cell.base[0], cell.base[1]],
        );
        self.sync_products(&obs);
        // Placing the product square in its slot: yaw 0 (it turns with the cup).
        let plan = self.plan_stage(obs.joints, &placing, 0.0, Some(&held), None, None)?;
        let box_top = cell
            .slots
            .get(s)
            .and_then(|sl| cell.boxes.get(sl.box_index))
            .map_or([slot[0], slot[1], 0.0], |b| {
                [b.centre[0], b.centre[1], b.size[2]]
            });
        let place_info = StageInfo {
            stage: 1,
            feature: box_top,
            label: s as u32 + 1,
        };
        self.run_stage(plan, Some(&held), None, Some(place_info))?;
        // Back up from the released product.
        let obs = self.world.observe();
        let up = [SubGoal {
            tip: [slot[0], slot[1], placing[1].tip[2]],
            suction: Suction::Keep,
        }];
        let plan = self.plan_stage(obs.joints, &up, 0.0, None, Some(&name), None)?;
        self.run_stage(plan, None, Some(&name), None)
    }
}

/// The smoothed 2 ms commands from `start` through `waypoints`, each
/// checked for collision (the straight joint segment from the last checked
/// sample, at most 1 degree on): the very commands that will be sent, or
/// why they would collide.
pub fn checked_samples(
    arm: &Arm,
    checker: &Checker,
    start: Joints,
    waypoints: &[Joints],
    held: Option<&Held>,
    ignore: Option<&str>,
) -> Result<Vec<Joints>, String> {
    let samples = smooth_path(arm.limits, start, waypoints).map_err(|e| e.to_string())?;
    let mut last = start;
    for (i, q) in samples.iter().enumerate() {
        let span = q
            .iter()
            .zip(&last)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        if span >= MAX_STEP || i + 1 == samples.len() {
            if let Some(hit) = checker.check_motion(&last, q, held, ignore) {
                return Err(format!("would collide: {} with {}", hit.a, hit.b));
            }
            last = *q;
        }
    }
    Ok(samples)
}

/// Joints that put the cup tip at `tip` pointing down with `yaw`, free of
/// collisions: among the inverse-kinematics branches (all eight for a UR
/// arm), the one nearest `near` that the checker finds free.
#[allow(clippy::too_many_arguments)]
pub fn reach(
    arm: &Arm,
    checker: &Checker,
    base: &Isometry3<f64>,
    tip: Point3<f64>,
    yaw: f64,
    suction: f64,
    near: &Joints,
    held: Option<&Held>,
    ignore: Option<&str>,
) -> Option<Joints> {
    let flange = tool_down_pose(tip, yaw, suction);
    let mut candidates: Vec<Joints> = if arm.ur.is_some() {
        arm.ur_ik_branches(base, &flange, near)
            .into_iter()
            .flatten()
            .collect()
    } else {
        arm.pose_ik(base, &flange, near).into_iter().collect()
    };
    candidates.sort_by(|a, b| joint_distance(a, near).total_cmp(&joint_distance(b, near)));
    candidates
        .into_iter()
        .find(|q| checker.check(q, held, ignore).is_none())
}

/// Height of the cup tip in the start pose.
pub const HOME_HEIGHT: f64 = 0.35;

/// The start pose: the cup [`HOME_HEIGHT`] over the middle of the pending
/// area, pointing down, collision-free, on the branch nearest the usual UR
/// "ready" pose.
pub fn home(arm: &Arm, cell: &CellScene) -> Option<Joints> {
    let (lo, hi) = cell.pending;
    let tip = Point3::new((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, HOME_HEIGHT);
    let base = Isometry3::translation(cell.base[0], cell.base[1], cell.base[2]);
    let ready = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];
    let checker = Checker::new(arm, cell);
    reach(
        arm,
        &checker,
        &base,
        tip,
        0.0,
        cell.suction,
        &ready,
        None,
        None,
    )
}

/// Packs `task` in `world` with `arm`. The world's arm starts wherever it
/// is; products are found by name in the observations and handled in the
/// order of `task.assignment`.
pub fn run<W: World>(world: &mut W, arm: &Arm, task: &OrderTask, planner: PlannerKind) -> Report {
    run_recorded(world, arm, task, planner, None)
}

/// [`run`], recording the sub-goals and actions into `log` (motion
/// demonstrations).
pub fn run_recorded<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    planner: PlannerKind,
    log: Option<&mut MotionLog>,
) -> Report {
    let mut runner = Runner::new(world, arm, task, planner, log);
    let period = runner.world.control_period();
    let mut products = Vec::new();
    let mut stopped = false;
    let mut collisions = Vec::new();
    for &(p, s) in &task.assignment {
        let decided = Instant::now();
        let spec = &task.products[p];
        let goal = task.goal(p, s);
        let mut report = ProductReport {
            product: spec.name.clone(),
            slot: task.cell.slots[s].name.clone(),
            planning_s: 0.0,
            execution_s: 0.0,
            error_m: None,
            outcome: Outcome::NotAttempted,
        };
        let obs = runner.world.observe();
        match seen_centre(&obs, &spec.name) {
            None => report.outcome = Outcome::Waiting,
            Some((c, _)) if distance(c, goal) <= SUCCESS_RADIUS => {
                report.error_m = Some(distance(c, goal));
                report.outcome = Outcome::AlreadyPacked;
            }
            Some(_) if stopped => {}
            Some(_) => {
                runner
                    .timing
                    .decision_us
                    .push(decided.elapsed().as_secs_f64() * 1e6);
                runner.planning_s = 0.0;
                runner.execution_steps = 0;
                let result = runner.manipulate(p, s);
                let after = runner.world.observe();
                report.error_m = seen_centre(&after, &spec.name).map(|(c, _)| distance(c, goal));
                report.planning_s = runner.planning_s;
                report.execution_s = runner.execution_steps as f64 * period;
                report.outcome = match result {
                    Ok(()) if report.error_m.is_some_and(|e| e <= SUCCESS_RADIUS) => {
                        Outcome::Packed
                    }
                    Ok(()) => Outcome::Failed(format!(
                        "released {:.3} m from its goal",
                        report.error_m.unwrap_or(f64::NAN)
                    )),
                    Err(why) => Outcome::Failed(why),
                };
                if let Outcome::Failed(why) = &report.outcome {
                    stopped = true;
                    if why.starts_with("collision") {
                        collisions.push(why.clone());
                    }
                }
            }
        }
        products.push(report);
    }
    finish(&mut runner, products, collisions, planner.name())
}

/// The report once the arm has stopped: products knocked out of place
/// later count as failed too.
fn finish<W: World>(
    runner: &mut Runner<'_, W>,
    mut products: Vec<ProductReport>,
    collisions: Vec<String>,
    planner: &'static str,
) -> Report {
    let task = runner.task;
    let last = runner.world.observe();
    for (report, &(p, s)) in products.iter_mut().zip(&task.assignment) {
        if matches!(report.outcome, Outcome::Packed | Outcome::AlreadyPacked) {
            let error = seen_centre(&last, &task.products[p].name)
                .map(|(c, _)| distance(c, task.goal(p, s)));
            report.error_m = error;
            if !error.is_some_and(|e| e <= SUCCESS_RADIUS) {
                report.outcome = Outcome::Failed("moved out of its slot later".into());
            }
        }
    }
    let complete = products
        .iter()
        .all(|r| matches!(r.outcome, Outcome::Packed | Outcome::AlreadyPacked))
        && collisions.is_empty();
    Report {
        planner,
        products,
        complete,
        collisions,
        time_s: last.time,
        fallbacks: Vec::new(),
        violations: Vec::new(),
        timing: std::mem::take(&mut runner.timing),
    }
}
