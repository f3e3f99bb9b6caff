//! The learned runtime loop (SPEC §2): at the start of each stage the
//! reasoner chooses (a product or the box, and the label) from the products'
//! positions alone; the sub-goal planner proposes each of the stage's three
//! sub-goals; the dynamics policy steps towards it (at most
//! [`MAX_POLICY_STEPS`] steps of at most 5 degrees, the wrist keeping the
//! cup down). A rollout that does not reach its sub-goal, or whose motion
//! would collide, hands the rest of the stage to RRT-Connect (counted as a
//! fallback). A decision that breaks the order stops the arm (counted as a
//! violation).

use super::*;
use crate::policy::Policy;
use crate::world::Seen;

/// Most dynamics-policy steps per sub-goal.
pub const MAX_POLICY_STEPS: usize = 30;
/// A sub-goal where the suction switches (the cup on a product's top
/// face, a release in a slot) is reached when the cup tip is this close (m).
pub const REACHED: f64 = 0.002;

/// A via point (hover, lift, approach, above the slot) is reached when the
/// cup tip is this close (m).
pub const REACHED_VIA: f64 = 0.01;

/// Why a dynamics-policy rollout did not give a motion.
#[derive(Debug, Clone, PartialEq)]
pub enum Shortfall {
    /// [`MAX_POLICY_STEPS`] steps ended this far (m) from the sub-goal.
    Short(f64),
    /// A step would leave the joint limits (or the wrist could not keep
    /// the cup down).
    Limits,
    /// The motion would collide.
    Collides(String),
}

/// A stage handed to RRT-Connect: where and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Fallback {
    /// The product handled.
    pub product: String,
    /// `true` placing, `false` picking.
    pub placing: bool,
    /// The stage's sub-goal (0, 1, 2) whose rollout fell short.
    pub subgoal: usize,
    pub why: Shortfall,
}

impl Fallback {
    /// A short key for counting fallbacks by kind, e.g. "placing 3: short".
    pub fn kind(&self) -> String {
        format!(
            "{} {}: {}",
            if self.placing { "placing" } else { "picking" },
            self.subgoal + 1,
            match self.why {
                Shortfall::Short(_) => "short",
                Shortfall::Limits => "joint limits",
                Shortfall::Collides(_) => "would collide",
            }
        )
    }
}

impl std::fmt::Display for Fallback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {}, sub-goal {}: ",
            if self.placing { "placing" } else { "picking" },
            self.product,
            self.subgoal + 1
        )?;
        match &self.why {
            Shortfall::Short(d) => write!(
                f,
                "{MAX_POLICY_STEPS} policy steps ended {:.1} mm away",
                d * 1e3
            ),
            Shortfall::Limits => write!(f, "a policy step would leave the joint limits"),
            Shortfall::Collides(why) => write!(f, "the policy's motion would collide ({why})"),
        }
    }
}

/// The suction switch at each of a stage's sub-goals.
const PICK_SUCTION: [Suction; 3] = [Suction::Keep, Suction::On, Suction::Keep];
const PLACE_SUCTION: [Suction; 3] = [Suction::Keep, Suction::Keep, Suction::Off];

fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

/// `q` moved by `step` (base, shoulder, elbow), the wrist turned so that the
/// cup keeps pointing down with the same yaw (UR-type wrists); `None` when
/// that does not hold for this arm or leaves the joint limits.
pub fn cup_down(arm: &Arm, base: &Isometry3<f64>, q: &Joints, step: [f64; 3]) -> Option<Joints> {
    let mut next = *q;
    next[0] += step[0];
    next[1] += step[1];
    next[2] += step[2];
    next[3] -= step[1] + step[2];
    next[5] += step[0];
    let before = arm.flange_pose(base, q).rotation;
    let after = arm.flange_pose(base, &next).rotation;
    let kept = before.angle_to(&after) < 1e-6;
    (kept && arm.within_limits(&next)).then_some(next)
}

/// The dynamics policy's steps from `start` towards the cup-tip position
/// `goal`, with forward kinematics, as the learned loop takes them: at
/// most [`MAX_POLICY_STEPS`], each `action(q, delta)` (base, shoulder,
/// elbow, radians; delta = goal − cup tip) scaled down to 5 degrees, the
/// wrist keeping the cup down; until the tip is within `tolerance`. The
/// joints after each step, or why the goal was not reached. DAgger's
/// rollouts (`crate::relabel`) step through this too.
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
    let mut steps = Vec::new();
    loop {
        let tip: [f64; 3] = arm.tool_tip(base, &q, suction).coords.into();
        let delta: [f64; 3] = std::array::from_fn(|j| goal[j] - tip[j]);
        let away = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
        if away <= tolerance {
            return Ok(steps);
        }
        if steps.len() == MAX_POLICY_STEPS {
            return Err(Shortfall::Short(away));
        }
        let step = record::clip(action(&q, delta).map(f64::from));
        q = cup_down(arm, base, &q, step).ok_or(Shortfall::Limits)?;
        steps.push(q);
    }
}

/// The reasoner's graph: (x, y, z, I) of every product seen, in inventory
/// order, and the product index of each node.
fn graph(task: &OrderTask, seen: &[Seen]) -> (Vec<[f32; 4]>, Vec<usize>) {
    let mut nodes = Vec::new();
    let mut which = Vec::new();
    for (p, spec) in task.products.iter().enumerate() {
        if let Some(s) = seen.iter().find(|s| s.name == spec.name) {
            let selected = task.assignment.iter().any(|&(q, _)| q == p);
            let c = f32s(s.centre);
            nodes.push([c[0], c[1], c[2], if selected { 1.0 } else { 0.0 }]);
            which.push(p);
        }
    }
    (nodes, which)
}

fn slot_of(task: &OrderTask, p: usize) -> Option<usize> {
    task.assignment
        .iter()
        .find(|&&(q, _)| q == p)
        .map(|&(_, s)| s)
}

/// The goal the reasoner's classifier is given for node `node`: the goal of
/// the product there (its own centre when the order does not select it).
fn goal_input(task: &OrderTask, which: &[usize], seen: &[Seen], node: usize) -> [f32; 3] {
    let p = which[node];
    match slot_of(task, p) {
        Some(s) => f32s(task.goal(p, s)),
        None => seen
            .iter()
            .find(|x| x.name == task.products[p].name)
            .map_or([0.0; 3], |x| f32s(x.centre)),
    }
}

/// Whether product `p` already sits in its slot.
fn in_slot(task: &OrderTask, seen: &[Seen], p: usize) -> bool {
    let Some(s) = slot_of(task, p) else {
        return false;
    };
    seen.iter()
        .find(|x| x.name == task.products[p].name)
        .is_some_and(|x| distance(x.centre, task.goal(p, s)) <= SUCCESS_RADIUS)
}

/// The product the demonstrations' rule handles next: the first selected,
/// present product (inventory order) not yet in its slot.
pub fn expected_next(task: &OrderTask, seen: &[Seen]) -> Option<usize> {
    task.assignment
        .iter()
        .map(|&(p, _)| p)
        .find(|&p| seen.iter().any(|x| x.name == task.products[p].name) && !in_slot(task, seen, p))
}

/// Runs the reasoner alone over a whole episode from the products `seen`
/// at the start, moving products as the demonstrator would (lifted by the
/// cell's lift, then into their slot), and compares every decision with
/// the demonstrated rule (inventory order). `Err` names the first wrong
/// decision.
pub fn reasoner_trial(nets: &dyn Policy, task: &OrderTask, seen: &[Seen]) -> Result<(), String> {
    let mut seen = seen.to_vec();
    for _ in 0..=task.assignment.len() {
        let Some(want) = expected_next(task, &seen) else {
            return Ok(());
        };
        let (nodes, which) = graph(task, &seen);
        let choice = nets.reason(&nodes, &|n| {
            n.map_or([0.0; 3], |n| goal_input(task, &which, &seen, n))
        });
        let got = choice.node.map(|n| which[n]);
        if got != Some(want) || choice.label != 0 {
            return Err(format!(
                "picking: chose {} with label {}, the demonstrations pick {}",
                got.map_or("the box", |p| &task.products[p].name),
                choice.label,
                task.products[want].name
            ));
        }
        let s = slot_of(task, want).unwrap_or(0);
        let name = &task.products[want].name;
        if let Some(x) = seen.iter_mut().find(|x| &x.name == name) {
            x.centre[2] += task.cell.lift;
        }
        let (nodes, which) = graph(task, &seen);
        let goal = f32s(task.goal(want, s));
        let choice = nets.reason(&nodes, &|_| goal);
        if choice.node.is_some() || choice.label != s + 1 {
            return Err(format!(
                "placing {name}: chose {} with label {}, the demonstrations use the box, label {}",
                choice
                    .node
                    .map_or("the box", |n| task.products[which[n]].name.as_str()),
                choice.label,
                s + 1
            ));
        }
        if let Some(x) = seen.iter_mut().find(|x| &x.name == name) {
            x.centre = task.goal(want, s);
        }
    }
    Err("the reasoner did not finish within one pick per product".into())
}

impl<W: World> Runner<'_, W> {
    fn tip(&self, q: &Joints) -> [f64; 3] {
        self.arm
            .tool_tip(&self.base, q, self.task.cell.suction)
            .coords
            .into()
    }

    /// The dynamics policy's motion from `start` to `goal`: the checked
    /// commands, or why not (not there in [`MAX_POLICY_STEPS`], a step
    /// out of the joint limits, a collision). The steps' end point is
    /// joined straight when that is free, else through every step.
    /// `first_action_us` gets the time of the first policy call.
    #[allow(clippy::too_many_arguments)]
    fn rollout(
        &mut self,
        nets: &dyn Policy,
        start: Joints,
        goal: [f64; 3],
        tolerance: f64,
        held: Option<&Held>,
        ignore: Option<&str>,
        first_action_us: &mut Option<f64>,
    ) -> Result<Vec<Joints>, Shortfall> {
        let suction = self.task.cell.suction;
        let steps = policy_steps(
            self.arm,
            &self.base,
            suction,
            start,
            goal,
            tolerance,
            &mut |q, delta| {
                let called = Instant::now();
                let action = nets.action(f32s(delta), [q[0] as f32, q[1] as f32, q[2] as f32]);
                first_action_us.get_or_insert(called.elapsed().as_secs_f64() * 1e6);
                action
            },
        )?;
        let Some(&q) = steps.last() else {
            return Ok(Vec::new());
        };
        checked_samples(self.arm, &self.checker, start, &[q], held, ignore)
            .or_else(|_| checked_samples(self.arm, &self.checker, start, &steps, held, ignore))
            .map_err(Shortfall::Collides)
    }

    /// One stage with learned sub-goals and motions.
    #[allow(clippy::too_many_arguments)]
    fn learned_stage(
        &mut self,
        nets: &dyn Policy,
        product: &str,
        feature: [f64; 3],
        label: usize,
        suction: [Suction; 3],
        contact: Option<f64>,
        held: Option<&Held>,
        ignore: Option<&str>,
        fallbacks: &mut Vec<Fallback>,
    ) -> Result<[[f64; 3]; 3], Failure> {
        let mut fallen = false;
        let mut goals = [[0.0; 3]; 3];
        for (k, &switch) in suction.iter().enumerate() {
            let start = self.world.observe().joints;
            let started = Instant::now();
            let goal = nets.subgoal(f32s(feature), f32s(self.tip(&start)), label, k);
            let mut goal = goal.map(f64::from);
            // A guarded contact: the cup meets the top face where the
            // product is sensed (its centre plus half its height), as a
            // vacuum sensor would stop the descent; x and y stay learned.
            if let (Suction::On, Some(top)) = (switch, contact) {
                goal[2] = top;
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
            // `None`: the stage already fell back.
            let planned = (!fallen).then(|| {
                let tolerance = if switch == Suction::Keep {
                    REACHED_VIA
                } else {
                    REACHED
                };
                let mut first_action_us = None;
                let mut rollout = |g: [f64; 3]| {
                    self.rollout(
                        nets,
                        start,
                        g,
                        tolerance,
                        held,
                        ignore,
                        &mut first_action_us,
                    )
                };
                // The first attempt's shortfall is the one reported.
                let mut planned = rollout(goal);
                let mut raised = 1;
                while planned.is_err() && goal[2] + RAISE_STEP * f64::from(raised) <= ceiling {
                    if let Ok(samples) =
                        rollout([goal[0], goal[1], goal[2] + RAISE_STEP * f64::from(raised)])
                    {
                        planned = Ok(samples);
                    }
                    raised += 1;
                }
                if let Some(action_us) = first_action_us {
                    self.timing.network_us.push(subgoal_us + action_us);
                }
                planned
            });
            let samples = match planned {
                Some(Ok(samples)) => samples,
                other => {
                    if let Some(Err(why)) = other {
                        fallbacks.push(Fallback {
                            product: product.to_string(),
                            placing: held.is_some(),
                            subgoal: k,
                            why,
                        });
                    }
                    fallen = true;
                    let target = [SubGoal {
                        tip: goal,
                        suction: switch,
                    }];
                    let plan = self.plan_stage(start, &target, 0.0, held, ignore, Some(ceiling))?;
                    self.timing.subgoal_us.pop();
                    let path = plan.first().map(|(p, _)| p.as_slice()).unwrap_or(&[]);
                    checked_samples(
                        self.arm,
                        &self.checker,
                        start,
                        path.get(1..).unwrap_or(&[]),
                        held,
                        ignore,
                    )
                    .map_err(|why| format!("the motion to sub-goal {}: {why}", k + 1))?
                }
            };
            let elapsed = started.elapsed().as_secs_f64();
            self.timing.subgoal_us.push(elapsed * 1e6);
            self.planning_s += elapsed;
            self.send(&samples, switch)?;
        }
        Ok(goals)
    }
}

/// What stopped a learned run early.
enum Stop {
    Violation(String),
    Failure(usize, Failure),
}

/// Packs `task` with the learned networks; RRT-Connect (seeded with
/// `seed`) for fallbacks.
pub fn run_learned<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    nets: &dyn Policy,
    seed: u64,
) -> Report {
    // The planner is RRT-Connect: it serves the fallbacks.
    let mut runner = Runner::new(world, arm, task, PlannerKind::Rrt { seed }, None);
    let first = runner.world.observe();
    let mut products: Vec<ProductReport> = task
        .assignment
        .iter()
        .map(|&(p, s)| {
            let goal = task.goal(p, s);
            let seen = seen_centre(&first, &task.products[p].name);
            ProductReport {
                product: task.products[p].name.clone(),
                slot: task.cell.slots[s].name.clone(),
                planning_s: 0.0,
                execution_s: 0.0,
                error_m: seen.map(|(c, _)| distance(c, goal)),
                outcome: match seen {
                    None => Outcome::Waiting,
                    Some((c, _)) if distance(c, goal) <= SUCCESS_RADIUS => Outcome::AlreadyPacked,
                    Some(_) => Outcome::NotAttempted,
                },
            }
        })
        .collect();
    let mut fallbacks = Vec::new();
    let mut stop = None;
    for _ in 0..task.assignment.len() {
        let obs = runner.world.observe();
        // Done when no selected, present product is out of its slot.
        if expected_next(task, &obs.products).is_none() {
            break;
        }
        match learned_product(&mut runner, nets, &mut fallbacks, &mut products) {
            Ok(()) => {}
            Err(s) => {
                stop = Some(s);
                break;
            }
        }
    }
    let mut violations = Vec::new();
    let mut collisions = Vec::new();
    match stop {
        Some(Stop::Violation(v)) => violations.push(v),
        Some(Stop::Failure(row, why)) => {
            if why.starts_with("collision") {
                collisions.push(why.clone());
            }
            products[row].outcome = Outcome::Failed(why);
        }
        None => {}
    }
    let mut report = finish(&mut runner, products, collisions, "learned");
    report.fallbacks = fallbacks;
    report.violations = violations;
    report.complete &= report.violations.is_empty();
    report
}

/// One product: decide, pick, decide, place, back off.
fn learned_product<W: World>(
    runner: &mut Runner<'_, W>,
    nets: &dyn Policy,
    fallbacks: &mut Vec<Fallback>,
    products: &mut [ProductReport],
) -> Result<(), Stop> {
    let task = runner.task;
    let obs = runner.world.observe();
    let (nodes, which) = graph(task, &obs.products);
    let decided = Instant::now();
    let choice = nets.reason(&nodes, &|n| {
        n.map_or([0.0; 3], |n| goal_input(task, &which, &obs.products, n))
    });
    runner
        .timing
        .decision_us
        .push(decided.elapsed().as_secs_f64() * 1e6);
    let Some(node) = choice.node else {
        return Err(Stop::Violation(
            "chose the box with nothing in the cup".into(),
        ));
    };
    let p = which[node];
    let name = task.products[p].name.clone();
    let Some(row) = task.assignment.iter().position(|&(q, _)| q == p) else {
        return Err(Stop::Violation(format!(
            "chose {name}, which the order does not select"
        )));
    };
    if in_slot(task, &obs.products, p) {
        return Err(Stop::Violation(format!(
            "chose {name}, which is already in its slot"
        )));
    }
    if choice.label != 0 {
        return Err(Stop::Violation(format!(
            "gave {name} label {} when picking it",
            choice.label
        )));
    }
    let s = task.assignment[row].1;
    runner.planning_s = 0.0;
    runner.execution_steps = 0;
    let result = learned_manipulate(runner, nets, p, s, fallbacks);
    let period = runner.world.control_period();
    let after = runner.world.observe();
    let report = &mut products[row];
    report.planning_s = runner.planning_s;
    report.execution_s = runner.execution_steps as f64 * period;
    report.error_m = seen_centre(&after, &name).map(|(c, _)| distance(c, task.goal(p, s)));
    match result {
        Ok(()) if report.error_m.is_some_and(|e| e <= SUCCESS_RADIUS) => {
            report.outcome = Outcome::Packed;
            Ok(())
        }
        Ok(()) => Err(Stop::Failure(
            row,
            format!(
                "released {:.3} m from its goal",
                report.error_m.unwrap_or(f64::NAN)
            ),
        )),
        Err(Stop::Failure(_, why)) => Err(Stop::Failure(row, why)),
        Err(v) => Err(v),
    }
}

fn learned_manipulate<W: World>(
    runner: &mut Runner<'_, W>,
    nets: &dyn Policy,
    p: usize,
    s: usize,
    fallbacks: &mut Vec<Fallback>,
) -> Result<(), Stop> {
    let task = runner.task;
    let spec = &task.products[p];
    let name = spec.name.clone();
    let fail = |why: Failure| Stop::Failure(0, why);
    let obs = runner.world.observe();
    runner.sync_products(&obs);
    let (centre, _) =
        seen_centre(&obs, &name).ok_or_else(|| fail("the product disappeared".into()))?;
    runner
        .learned_stage(
            nets,
            &name,
            centre,
            0,
            PICK_SUCTION,
            Some(centre[2] + spec.size[2] / 2.0),
            None,
            Some(&name),
            fallbacks,
        )
        .map_err(fail)?;
    // Placing: the reasoner sees the held product raised.
    let obs = runner.world.observe();
    let (nodes, which) = graph(task, &obs.products);
    let goal = f32s(task.goal(p, s));
    let decided = Instant::now();
    let choice = nets.reason(&nodes, &|_| goal);
    runner
        .timing
        .decision_us
        .push(decided.elapsed().as_secs_f64() * 1e6);
    if let Some(n) = choice.node {
        return Err(Stop::Violation(format!(
            "chose {} instead of the box while holding {name}",
            task.products[which[n]].name
        )));
    }
    if choice.label != s + 1 {
        return Err(Stop::Violation(format!(
            "would put {name} in label {}, the order says {} (label {})",
            choice.label,
            task.cell.slots[s].name,
            s + 1
        )));
    }
    let held = Held {
        name: name.clone(),
        size: spec.size,
        in_flange: Isometry3::translation(0.0, 0.0, task.cell.suction + spec.size[2] / 2.0),
    };
    let cell = &task.cell;
    let feature = cell
        .slots
        .get(s)
        .and_then(|sl| cell.boxes.get(sl.box_index))
        .map_or(
            [cell.slots[s].position[0], cell.slots[s].position[1], 0.0],
            |b| [b.centre[0], b.centre[1], b.size[2]],
        );
    runner.sync_products(&obs);
    let goals = runner
        .learned_stage(
            nets,
            &name,
            feature,
            choice.label,
            PLACE_SUCTION,
            None,
            Some(&held),
            None,
            fallbacks,
        )
        .map_err(fail)?;
    // Back off straight up to the learned "above the slot" sub-goal.
    let obs = runner.world.observe();
    let up = [SubGoal {
        tip: goals[1],
        suction: Suction::Keep,
    }];
    let planner = std::mem::replace(&mut runner.planner, PlannerKind::Expert);
    let plan = runner.plan_stage(obs.joints, &up, 0.0, None, Some(&name), None);
    runner.planner = planner;
    runner.timing.subgoal_us.pop();
    let plan = plan.map_err(fail)?;
    runner
        .run_stage(plan, None, Some(&name), None)
        .map_err(fail)
}
