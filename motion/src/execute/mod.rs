//! The execution loops: observe, choose the next product, plan each stage's
//! three sub-goals, check the motion, smooth it with Ruckig at the control
//! rate, and drive the world.
//!
//! Planners ([`Planner`]):
//! - `Expert`: the scripted demonstrator; straight joint-space motions
//!   between the inverse-kinematics solutions of the sub-goals, and the
//!   demonstrated sequence rule (inventory order) for what comes next;
//! - `Rrt`: the same sub-goal poses joined by RRT-Connect (the paper's
//!   RM + RRT-Connect baseline);
//! - `Learned`: a [`Policy`]'s reasoner, sub-goal planner and dynamics
//!   policy, with RRT-Connect for the rest of a stage when a rollout falls
//!   short (a counted fallback).
//!
//! Both loops ([`scripted`], [`learned`]) are built on the same stepping
//! primitives ([`station`]: inverse kinematics, connecting, checking,
//! sending). Every smoothed 2 ms command is collision-checked (parry, at
//! joint steps of at most 1 degree) before it is sent; a plan that would
//! collide or an unreachable sub-goal is reported for that product
//! ([`Failure`]) and the arm stops where it is. Observations are only
//! products' positions: what is packed or missing is inferred from them.

mod learned;
mod reachable;
mod reasoner;
mod scripted;
mod station;
mod vias;

pub use learned::{MAX_POLICY_STEPS, REACHED, REACHED_VIA, cup_down, policy_steps, tolerance};
pub use reachable::{Reachability, Release, Unreached};
pub use reasoner::{demonstrated_decisions, expected_next, graph, reasoner_trial};
pub use station::{
    HOME_HEIGHT, Load, PlanningBudget, STOP_CLEARANCE, Unchecked, checked_blend, checked_blend_by,
    checked_samples, home, home_among, home_tip, reach,
};

use packwright_interface::outcome::{PlannerKind, Report};
use packwright_interface::record::MotionLog;
use packwright_interface::{OrderTask, Policy, SequenceRule, World};
use packwright_kinematics::Arm;

/// How to pack.
#[derive(Clone, Copy)]
pub enum Planner<'a> {
    /// The scripted expert.
    Expert,
    /// The expert's sub-goals joined by RRT-Connect, seeded.
    Rrt { seed: u64 },
    /// A trained policy; RRT-Connect (seeded) for fallbacks.
    Learned { policy: &'a dyn Policy, seed: u64 },
}

impl<'a> Planner<'a> {
    /// The planner of `kind`, seeded; the learned one needs `policy`
    /// (`None` without it).
    pub fn of(kind: PlannerKind, policy: Option<&'a dyn Policy>, seed: u64) -> Option<Planner<'a>> {
        Some(match kind {
            PlannerKind::Learned => Planner::Learned {
                policy: policy?,
                seed,
            },
            PlannerKind::Rrt => Planner::Rrt { seed },
            PlannerKind::Expert => Planner::Expert,
        })
    }

    pub fn kind(&self) -> PlannerKind {
        match self {
            Planner::Expert => PlannerKind::Expert,
            Planner::Rrt { .. } => PlannerKind::Rrt,
            Planner::Learned { .. } => PlannerKind::Learned,
        }
    }
}

/// Packs `task` in `world` with `arm`. The world's arm starts wherever it
/// is; products are found by name in the observations.
pub fn run<W: World>(world: &mut W, arm: &Arm, task: &OrderTask, planner: &Planner) -> Report {
    run_within(world, arm, task, planner, PlanningBudget::default())
}

/// [`run`] with a planning budget other than the default: a product whose
/// planning overruns it fails with [`Failure::OutOfTime`] and the arm
/// stops.
///
/// [`Failure::OutOfTime`]: packwright_interface::Failure::OutOfTime
pub fn run_within<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    planner: &Planner,
    budget: PlanningBudget,
) -> Report {
    run_planned(world, arm, task, planner, budget, None)
}

/// [`run`] with the expert and RRT-Connect handling the products in
/// `rule`'s order, the order the learned planner's reasoner is taught and
/// judged by (with the same rule, the planners pack the same sequence and
/// their times compare), rather than the assignment's. The learned
/// planner's reasoner chooses by its own rule either way.
pub fn run_in_order<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    planner: &Planner,
    rule: &SequenceRule,
) -> Report {
    run_planned(
        world,
        arm,
        task,
        planner,
        PlanningBudget::default(),
        Some(rule),
    )
}

fn run_planned<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    planner: &Planner,
    budget: PlanningBudget,
    rule: Option<&SequenceRule>,
) -> Report {
    let straight = station::Connect::Straight;
    match *planner {
        Planner::Expert => scripted::run(world, arm, task, straight, None, budget, rule),
        Planner::Rrt { seed } => scripted::run(
            world,
            arm,
            task,
            station::Connect::Rrt { seed },
            None,
            budget,
            rule,
        ),
        Planner::Learned { policy, seed } => learned::run(world, arm, task, policy, seed, budget),
    }
}

/// The expert's run, recording the sub-goals and actions into `log`
/// (motion demonstrations).
pub fn run_recorded<W: World>(
    world: &mut W,
    arm: &Arm,
    task: &OrderTask,
    log: &mut MotionLog,
) -> Report {
    let budget = PlanningBudget::default();
    scripted::run(
        world,
        arm,
        task,
        station::Connect::Straight,
        Some(log),
        budget,
        None,
    )
}
