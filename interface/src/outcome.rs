//! Typed results of packing an order: per product, why it failed, the
//! learned planner's fallbacks and violations, and planning times. Each
//! has a `Display` for people and serialises for `--json`; no caller ever
//! looks inside a message to decide anything.

use crate::world::{Body, Contact, WorldError};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;

/// A product is packed when its centre is this close to its slot goal (m).
pub const SUCCESS_RADIUS: f64 = 0.02;

/// The two stages of handling one product.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    Picking,
    Placing,
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Stage::Picking => "picking",
            Stage::Placing => "placing",
        })
    }
}

/// What a sub-goal is for, in the order a product's motion passes them:
/// each stage's three sub-goals ([`SubGoalKind::of`]), then the back-up
/// from the release.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SubGoalKind {
    /// Above the product to pick.
    Hover,
    /// Onto its top face (the guarded descent; the suction switches on).
    Contact,
    /// Up with the product gripped.
    Lift,
    /// On the way to the box, carrying it.
    Approach,
    /// Above its slot.
    AboveSlot,
    /// Down into the slot (the suction switches off).
    Release,
    /// Back up from the released product.
    BackUp,
}

impl SubGoalKind {
    /// The three sub-goals of `stage`, in order.
    pub fn of(stage: Stage) -> [SubGoalKind; 3] {
        use SubGoalKind::*;
        match stage {
            Stage::Picking => [Hover, Contact, Lift],
            Stage::Placing => [Approach, AboveSlot, Release],
        }
    }
}

impl fmt::Display for SubGoalKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SubGoalKind::Hover => "hover",
            SubGoalKind::Contact => "contact",
            SubGoalKind::Lift => "lift",
            SubGoalKind::Approach => "approach",
            SubGoalKind::AboveSlot => "above slot",
            SubGoalKind::Release => "release",
            SubGoalKind::BackUp => "back-up",
        })
    }
}

/// Which planner packs: the scripted expert, the expert's sub-goals joined
/// by RRT-Connect (the paper's baseline), or the learned networks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlannerKind {
    Expert,
    Rrt,
    Learned,
}

impl PlannerKind {
    pub const ALL: [PlannerKind; 3] = [PlannerKind::Expert, PlannerKind::Rrt, PlannerKind::Learned];

    pub fn name(self) -> &'static str {
        match self {
            PlannerKind::Expert => "expert",
            PlannerKind::Rrt => "rrt",
            PlannerKind::Learned => "learned",
        }
    }
}

impl fmt::Display for PlannerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for PlannerKind {
    type Err = String;

    fn from_str(s: &str) -> Result<PlannerKind, String> {
        PlannerKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown planner `{s}` (expert, rrt or learned)"))
    }
}

/// A collision found by a check before anything moves.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Hit {
    /// Body `a` (an arm part or the held product) would touch `b`.
    Bodies { a: Body, b: Body },
    /// The joints to check are not finite.
    InvalidJoints,
}

impl fmt::Display for Hit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Hit::Bodies { a, b } => write!(f, "{a} with {b}"),
            Hit::InvalidJoints => write!(f, "non-finite joints"),
        }
    }
}

/// Why the robot could not pack one product (the arm then stops).
/// Sub-goals are numbered from 1 within their stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Failure {
    /// No collision-free inverse-kinematics solution puts the cup there.
    Unreachable {
        subgoal: usize,
        tip: [f64; 3],
        /// What the arm pose nearest the arm's meets there, when the cup
        /// can be put there at all (every pose that does collides).
        #[serde(skip_serializing_if = "Option::is_none")]
        met: Option<Hit>,
        /// A release or a lift, whose pose is free: what the straight
        /// motion there from where the arm is meets (a lifted product its
        /// neighbour, the held product a box's wall).
        #[serde(skip_serializing_if = "Option::is_none")]
        way: Option<Box<Hit>>,
    },
    /// RRT-Connect found no path to the sub-goal.
    NoPath { subgoal: usize },
    /// The sub-goal planner gave a sub-goal that is not a finite point.
    NonFiniteSubGoal { subgoal: usize },
    /// The checked motion to the sub-goal would collide.
    WouldCollide { subgoal: usize, hit: Hit },
    /// The smoother found no trajectory (its reason, for people).
    Smoothing { subgoal: usize, reason: String },
    /// The world reported a contact while the arm moved.
    Collision { contact: Contact },
    /// The world refused a command or failed.
    World { error: String },
    /// The product was no longer seen when the robot came to it.
    Disappeared,
    /// The product was released this far (m) from its goal.
    Misplaced { error_m: f64 },
    /// The cup did not grip the product: it still stands where it was
    /// picked from, this far (m) from its goal.
    NotGripped { error_m: f64 },
    /// The product was in its slot, then something moved it out.
    MovedLater,
    /// Planning ran past its wall-clock budget (the arm stops where it is).
    OutOfTime {
        subgoal: usize,
        budget: Budget,
        limit_s: f64,
    },
}

/// Which planning budget ran out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Budget {
    /// Planning one sub-goal (its inverse kinematics, or its motion).
    SubGoal,
    /// Planning the whole package so far.
    Package,
}

impl From<WorldError> for Failure {
    fn from(e: WorldError) -> Failure {
        Failure::World {
            error: e.to_string(),
        }
    }
}

impl Failure {
    /// The sub-goal (from 1) a planning failure is about, if it is one.
    pub fn subgoal(&self) -> Option<usize> {
        match self {
            Failure::Unreachable { subgoal, .. }
            | Failure::NoPath { subgoal }
            | Failure::NonFiniteSubGoal { subgoal }
            | Failure::WouldCollide { subgoal, .. }
            | Failure::Smoothing { subgoal, .. }
            | Failure::OutOfTime { subgoal, .. } => Some(*subgoal),
            Failure::Collision { .. }
            | Failure::World { .. }
            | Failure::Disappeared
            | Failure::Misplaced { .. }
            | Failure::NotGripped { .. }
            | Failure::MovedLater => None,
        }
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Unreachable {
                subgoal,
                tip,
                met,
                way,
            } => {
                write!(
                    f,
                    "sub-goal {subgoal} at ({:.3}, {:.3}, {:.3}) is unreachable",
                    tip[0], tip[1], tip[2]
                )?;
                match (met, way) {
                    (Some(hit), _) => write!(f, ": every arm pose there collides ({hit})"),
                    (None, Some(hit)) => {
                        write!(f, ": the straight motion there collides ({hit})")
                    }
                    (None, None) => Ok(()),
                }
            }
            Failure::NoPath { subgoal } => {
                write!(f, "RRT-Connect found no path to sub-goal {subgoal}")
            }
            Failure::NonFiniteSubGoal { subgoal } => {
                write!(
                    f,
                    "sub-goal {subgoal} is not a finite point (the model's output)"
                )
            }
            Failure::WouldCollide { subgoal, hit } => {
                write!(f, "the motion to sub-goal {subgoal} would collide: {hit}")
            }
            Failure::Smoothing { subgoal, reason } => {
                write!(f, "the motion to sub-goal {subgoal}: {reason}")
            }
            Failure::Collision { contact } => write!(f, "collision: {contact}"),
            Failure::World { error } => write!(f, "{error}"),
            Failure::Disappeared => write!(f, "the product disappeared"),
            Failure::Misplaced { error_m } => write!(f, "released {error_m:.3} m from its goal"),
            Failure::NotGripped { error_m } => write!(
                f,
                "not gripped: it still stands where it was picked from, {error_m:.3} m from its goal"
            ),
            Failure::MovedLater => write!(f, "moved out of its slot later"),
            Failure::OutOfTime {
                subgoal,
                budget: Budget::SubGoal,
                limit_s,
            } => write!(
                f,
                "planning sub-goal {subgoal} took longer than its {limit_s:.1} s budget"
            ),
            Failure::OutOfTime {
                subgoal,
                budget: Budget::Package,
                limit_s,
            } => write!(
                f,
                "planning the package ran past its {limit_s:.1} s budget (at sub-goal {subgoal})"
            ),
        }
    }
}

/// What became of one selected product.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "outcome", content = "reason")]
pub enum Outcome {
    /// Placed by the robot within the success radius.
    Packed,
    /// Already in its slot when the robot came to it (a worker packed it).
    AlreadyPacked,
    /// Not in the cell: waits for restocking.
    Waiting,
    /// The robot could not pack it; the arm stopped.
    Failed(Failure),
    /// Not attempted because the arm stopped earlier.
    NotAttempted,
}

impl Outcome {
    /// Packed by the robot or by a worker.
    pub fn in_slot(&self) -> bool {
        matches!(self, Outcome::Packed | Outcome::AlreadyPacked)
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Outcome::Packed => write!(f, "packed"),
            Outcome::AlreadyPacked => write!(f, "already packed"),
            Outcome::Waiting => write!(f, "waiting (missing)"),
            Outcome::Failed(why) => write!(f, "failed: {why}"),
            Outcome::NotAttempted => write!(f, "not attempted"),
        }
    }
}

/// Why a dynamics-policy rollout did not give a motion.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Shortfall {
    /// The step budget (`steps`) ended this far (m) from the sub-goal.
    Short { steps: usize, distance_m: f64 },
    /// A step would take `joint` (from 0, base first) to `value` (rad),
    /// outside its limits; `joint` is `None` when the wrist could not keep
    /// the cup down.
    Limits { joint: Option<usize>, value: f64 },
    /// The smoother refused the steps (its reason, for people).
    Smoothing { reason: String },
    /// The motion would collide.
    Collides { hit: Hit },
    /// The learned sub-goal where the suction switches lies this far (m,
    /// horizontally) from where the task needs it: the product's centre
    /// (a grip whose cup tip would miss the top face, by the policy's
    /// reach) or the slot (a release more than the success radius off).
    /// No motion is tried to it.
    OffTarget { distance_m: f64, target: Target },
    /// A release raised over the expert's (the product drops the rest of
    /// the way) would drop the product onto its box's wall: it is `by_m`
    /// (horizontally) from letting go with the product inside the walls,
    /// more than a learned release is moved.
    OverWall { by_m: f64 },
    /// A release the arm reaches only with the product's bottom this far
    /// (m) above its box's rim: let go there, it would fall that far and
    /// more.
    DropsFrom { height_m: f64 },
}

/// What a learned grip or release must be near ([`Shortfall::OffTarget`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// A grip: the product's top face, about its centre.
    TopFace,
    /// A release: the slot.
    Slot,
}

/// The arm's joints as people call them, base first (a six-joint arm's;
/// [`Shortfall::kind`] names its limits so).
const JOINT_NAMES: [&str; 6] = ["base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3"];

impl Shortfall {
    /// A short name of the kind, for counting.
    pub fn kind(&self) -> &'static str {
        match self {
            Shortfall::Short { .. } => "short",
            Shortfall::Limits { joint: Some(0), .. } => "base joint limit",
            Shortfall::Limits { joint: Some(1), .. } => "shoulder joint limit",
            Shortfall::Limits { joint: Some(2), .. } => "elbow joint limit",
            Shortfall::Limits { joint: Some(3), .. } => "wrist 1 joint limit",
            Shortfall::Limits { joint: Some(4), .. } => "wrist 2 joint limit",
            Shortfall::Limits { joint: Some(5), .. } => "wrist 3 joint limit",
            Shortfall::Limits { .. } => "cup not kept down",
            Shortfall::Smoothing { .. } => "smoothing",
            Shortfall::Collides { .. } => "would collide",
            Shortfall::OffTarget { .. } => "off target",
            Shortfall::OverWall { .. } => "dropped onto a wall",
            Shortfall::DropsFrom { .. } => "dropped from high",
        }
    }
}

impl fmt::Display for Shortfall {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Shortfall::Short { steps, distance_m } => write!(
                f,
                "{steps} policy steps ended {:.1} mm away",
                distance_m * 1e3
            ),
            Shortfall::Limits {
                joint: Some(j),
                value,
            } => match JOINT_NAMES.get(*j) {
                // Named as `Shortfall::kind` names it (`eval`'s counts).
                Some(name) => write!(
                    f,
                    "a policy step would take the {name} joint (joint {j}) to {value:.3} rad, outside its limits"
                ),
                None => write!(
                    f,
                    "a policy step would take joint {j} to {value:.3} rad, outside its limits"
                ),
            },
            Shortfall::Limits { joint: None, .. } => {
                write!(f, "a policy step would not keep the cup pointing down")
            }
            Shortfall::Smoothing { reason } => {
                write!(f, "the smoother refused the policy's steps ({reason})")
            }
            Shortfall::Collides { hit } => write!(f, "the policy's motion would collide ({hit})"),
            Shortfall::OffTarget {
                distance_m,
                target: Target::TopFace,
            } => write!(
                f,
                "the learned grip is {:.1} mm off the product's centre: the cup would miss its top face, or grip too near its edge",
                distance_m * 1e3
            ),
            Shortfall::OffTarget {
                distance_m,
                target: Target::Slot,
            } => write!(
                f,
                "the learned release is {:.1} mm off the slot, more than the success radius",
                distance_m * 1e3
            ),
            Shortfall::OverWall { by_m } => write!(
                f,
                "let go above the rim, the product would drop onto the box's wall ({:.1} mm from inside it)",
                by_m * 1e3
            ),
            Shortfall::DropsFrom { height_m } => write!(
                f,
                "the release is reached only with the product {:.0} mm above its box's rim: it would fall that far and more",
                height_m * 1e3
            ),
        }
    }
}

/// A stage handed to RRT-Connect by the learned planner: where and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fallback {
    /// The product handled.
    pub product: String,
    pub stage: Stage,
    /// The stage's sub-goal (1, 2, 3) whose rollout fell short; 4 for the
    /// back-up from a release (placing).
    pub subgoal: usize,
    pub why: Shortfall,
    /// The first sub-goal (1, 2, 3) for which RRT-Connect went to the
    /// expert's sub-goal instead of the learned one, which no free joint
    /// motion reached (out of reach, or blocked); `None` when every
    /// learned sub-goal of the stage was reached.
    pub expert_from: Option<usize>,
}

/// What kind of fallback, for counting (stage, sub-goal, shortfall kind).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FallbackKind {
    pub stage: Stage,
    pub subgoal: usize,
    pub why: &'static str,
}

impl fmt::Display for FallbackKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}: {}", self.stage, self.subgoal, self.why)
    }
}

impl Fallback {
    pub fn kind(&self) -> FallbackKind {
        FallbackKind {
            stage: self.stage,
            subgoal: self.subgoal,
            why: self.why.kind(),
        }
    }
}

impl fmt::Display for Fallback {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {}, sub-goal {}: {}",
            self.stage, self.product, self.subgoal, self.why
        )?;
        match self.expert_from {
            Some(k) => write!(f, "; RRT-Connect went to the expert's sub-goal {k}"),
            None => Ok(()),
        }
    }
}

/// A reasoner decision that breaks the order (the arm stops).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Violation {
    /// Chose the box with nothing in the cup.
    BoxWithNothingHeld,
    /// Chose a product the order does not select.
    NotSelected { product: String },
    /// Chose a product already in its slot.
    AlreadyInSlot { product: String },
    /// Gave a slot label while picking.
    LabelWhenPicking { product: String, label: usize },
    /// Chose a product instead of the box while holding one.
    ProductWhileHolding { chosen: String, held: String },
    /// Chose another slot than the order's.
    WrongSlot {
        product: String,
        label: usize,
        slot: String,
        expected: usize,
    },
    /// A decision other than the taught sequence's (judged by `eval`).
    OutOfSequence {
        stage: Stage,
        chosen: Option<String>,
        label: usize,
        expected: String,
        expected_label: usize,
    },
    /// The reasoner went on after every product was handled.
    DidNotFinish,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Violation::BoxWithNothingHeld => write!(f, "chose the box with nothing in the cup"),
            Violation::NotSelected { product } => {
                write!(f, "chose {product}, which the order does not select")
            }
            Violation::AlreadyInSlot { product } => {
                write!(f, "chose {product}, which is already in its slot")
            }
            Violation::LabelWhenPicking { product, label } => {
                write!(f, "gave {product} label {label} when picking it")
            }
            Violation::ProductWhileHolding { chosen, held } => {
                write!(f, "chose {chosen} instead of the box while holding {held}")
            }
            Violation::WrongSlot {
                product,
                label,
                slot,
                expected,
            } => write!(
                f,
                "would put {product} in label {label}, the order says {slot} (label {expected})"
            ),
            Violation::OutOfSequence {
                stage,
                chosen,
                label,
                expected,
                expected_label,
            } => write!(
                f,
                "{stage}: chose {} with label {label}, the demonstrations {} {expected} with label {expected_label}",
                chosen.as_deref().unwrap_or("the box"),
                match stage {
                    Stage::Picking => "pick",
                    Stage::Placing => "place",
                },
            ),
            Violation::DidNotFinish => {
                write!(f, "did not finish within one pick per product")
            }
        }
    }
}

/// What happened to one selected product.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProductReport {
    pub product: String,
    pub slot: String,
    /// Wall-clock seconds spent planning (IK, checks, RRT) for this product.
    pub planning_s: f64,
    /// Simulated (or real) seconds of motion for this product.
    pub execution_s: f64,
    /// A lower bound on `execution_s` for any planner: between the same
    /// stops (where the product's motion starts, the contact with its top
    /// face, the release, and where its motion ends) each joint's own
    /// time-optimal jerk-limited move, the slowest joint's, plus the
    /// suction's settling times. 0 when the arm did not move.
    pub bound_s: f64,
    /// Distance of the product's centre from its slot goal at the end.
    pub error_m: Option<f64>,
    /// Its turn: 1 for the first product the robot handled in this run,
    /// 2 for the next, ... (the rows are in the order's assignment order,
    /// not the order packed); `None` when the robot did not handle it. A
    /// product handled twice keeps its first turn, and its planning,
    /// execution and bound are the sums over both.
    pub turn: Option<usize>,
    #[serde(flatten)]
    pub outcome: Outcome,
    /// Where a failure at a sub-goal ([`Failure::subgoal`]) happened:
    /// picking or placing (sub-goal 1 of either is a long motion, and
    /// "sub-goal 1" alone reads the same for both); `None` otherwise, and
    /// for the way back up from a release.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failed_in: Option<Stage>,
}

impl ProductReport {
    /// Its outcome for people, saying the stage of a failure at a
    /// sub-goal ("failed while placing: the motion to sub-goal 1 ...").
    pub fn outcome_text(&self) -> String {
        match (&self.outcome, self.failed_in) {
            (Outcome::Failed(why), Some(stage)) => format!("failed while {stage}: {why}"),
            (outcome, _) => outcome.to_string(),
        }
    }
}

/// Planning times, microseconds of wall clock.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Timing {
    /// Per decision of what to handle next (the reasoner, or the expert's
    /// sequence rule).
    pub decision_us: Vec<f64>,
    /// Per sub-goal: finding it and planning the motion to it, for every
    /// planner the same sub-goals (the back-up after a release among
    /// them).
    pub subgoal_us: Vec<f64>,
    /// What each of `subgoal_us` was for, in the same order: set only by
    /// [`Timing::subgoal`], which pushes both; read through
    /// [`Timing::subgoals`].
    subgoal_kinds: Vec<SubGoalKind>,
    /// Learned planner only: one sub-goal planner call plus the first
    /// dynamics policy call of its rollout (sub-goals with a rollout).
    pub network_us: Vec<f64>,
}

impl Timing {
    /// Records a sub-goal's planning time.
    pub fn subgoal(&mut self, kind: SubGoalKind, us: f64) {
        self.subgoal_us.push(us);
        self.subgoal_kinds.push(kind);
    }

    /// Each sub-goal's kind and planning time.
    pub fn subgoals(&self) -> impl Iterator<Item = (SubGoalKind, f64)> + '_ {
        self.subgoal_kinds
            .iter()
            .copied()
            .zip(self.subgoal_us.iter().copied())
    }
}

/// The result of packing one order.
/// A product the run never picked that ended more than
/// [`SUCCESS_RADIUS`] from where it stood when the run began: knocked
/// over or pushed (a contact too light for the world to count as a
/// collision can still tip a tall product).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Disturbance {
    pub product: String,
    /// How far its centre moved (m).
    pub moved_m: f64,
}

impl fmt::Display for Disturbance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "`{}`, never picked, moved {:.0} mm from where it stood",
            self.product,
            self.moved_m * 1000.0
        )
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    pub planner: PlannerKind,
    pub products: Vec<ProductReport>,
    /// Every present selected product is packed, nothing collided,
    /// nothing was disturbed and no decision broke the order.
    pub complete: bool,
    /// Contacts the world reported.
    pub collisions: Vec<Contact>,
    /// Products never picked that ended away from where they stood.
    pub disturbed: Vec<Disturbance>,
    /// Simulated (or real) seconds at the end.
    pub time_s: f64,
    /// Learned planner: stages handed to RRT-Connect, and why.
    pub fallbacks: Vec<Fallback>,
    /// Learned planner: a decision that broke the order (the arm stopped).
    pub violations: Vec<Violation>,
    #[serde(skip)]
    pub timing: Timing,
    /// The cup tip at each sub-goal reached, in the order planned (every
    /// planner): what `execute --svg` marks and numbers.
    #[serde(skip)]
    pub subgoals: Vec<[f64; 3]>,
}

impl Report {
    /// The first reason the package is not complete, for people.
    pub fn first_problem(&self) -> Option<String> {
        // The product that failed, wherever it is in the rows (in
        // inventory order, the ones it left unattempted may come first).
        let failed = self
            .products
            .iter()
            .find_map(|p| match &p.outcome {
                Outcome::Failed(why) => Some(match p.failed_in {
                    Some(stage) => format!("{}, {stage}: {why}", p.product),
                    None => format!("{}: {why}", p.product),
                }),
                _ => None,
            })
            .or_else(|| {
                self.products
                    .iter()
                    .find(|p| p.outcome == Outcome::NotAttempted)
                    .map(|p| format!("{}: not attempted", p.product))
            });
        self.violations
            .first()
            .map(|v| format!("the reasoner {v}"))
            .or(failed)
            .or_else(|| self.collisions.first().map(|c| format!("collision: {c}")))
            .or_else(|| self.disturbed.first().map(|d| format!("disturbed: {d}")))
    }
}

impl Serialize for Body {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl Serialize for Contact {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("Contact", 3)?;
        st.serialize_field("time", &self.time)?;
        st.serialize_field("a", &self.a)?;
        st.serialize_field("b", &self.b)?;
        st.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(product: &str, outcome: Outcome) -> ProductReport {
        ProductReport {
            failed_in: None,
            turn: None,
            product: product.into(),
            slot: "s".into(),
            planning_s: 0.0,
            execution_s: 0.0,
            bound_s: 0.0,
            error_m: None,
            outcome,
        }
    }

    /// A joint limit is said with the joint's name, as `eval` counts it
    /// (helper P: "joint 2" in `execute`, "elbow joint limit" in `eval`).
    #[test]
    fn a_joint_past_its_limit_is_named_as_eval_counts_it() {
        for j in 0..6 {
            let why = Shortfall::Limits {
                joint: Some(j),
                value: 3.209,
            };
            let name = why.kind().trim_end_matches(" joint limit");
            let said = why.to_string();
            assert!(
                said.contains(&format!("the {name} joint (joint {j})")),
                "{said}"
            );
        }
    }

    /// A package stopped by its third product leaves the second, earlier in
    /// inventory order, unattempted: the failure is the reason given.
    #[test]
    fn the_first_problem_is_the_failure_not_what_it_left_unattempted() {
        let report = Report {
            planner: PlannerKind::Learned,
            products: vec![
                row("jam", Outcome::Packed),
                row("syrup", Outcome::NotAttempted),
                row("tray", Outcome::Failed(Failure::MovedLater)),
            ],
            complete: false,
            collisions: Vec::new(),
            disturbed: Vec::new(),
            time_s: 1.0,
            fallbacks: Vec::new(),
            violations: Vec::new(),
            timing: Timing::default(),
            subgoals: Vec::new(),
        };
        let problem = report.first_problem().expect("a problem");
        assert!(problem.starts_with("tray: "), "{problem}");
        let stopped = Report {
            products: vec![row("syrup", Outcome::NotAttempted)],
            ..report
        };
        assert_eq!(
            stopped.first_problem().as_deref(),
            Some("syrup: not attempted")
        );
    }
}
