//! The stepping primitives both execution loops are built on: the arm in
//! its world with the cell's collision checker, and what a loop does with
//! it: find the joints of a sub-goal (inverse kinematics, raising a
//! release the wrist cannot reach), connect two configurations (straight,
//! or RRT-Connect), smooth and check the commands, send them and switch the
//! suction. Each returns a typed [`Failure`] naming the sub-goal.
//!
//! Invariant: nothing reaches the world that [`checked_blend`] did not
//! return.

use super::vias::fewer_vias;
use crate::blend::{Blended, blend_straight};
use crate::collision::{Checker, Held, HeldPose, MAX_STEP, ProductBody, Touch};
use crate::expert::{SubGoal, Suction};
use crate::rrt::{self, Query, RrtConfig};
use crate::smoothing::lower_bound;
use nalgebra::{Isometry3, Point3};
use packwright_interface::outcome::{
    Budget, Disturbance, Failure, Hit, Outcome, PlannerKind, ProductReport, Report, Stage, Timing,
};
use packwright_interface::world::{Contact, Observation, Seen, World};
use packwright_interface::{CellScene, OrderTask};
use packwright_kinematics::{Arm, DOF, Joints, joint_distance, tool_down_pose};
use std::f64::consts::{FRAC_PI_2, TAU};
use std::time::{Duration, Instant};

/// How much a release point is raised at a time when the wrist cannot
/// reach it.
pub(crate) const RAISE_STEP: f64 = 0.01;
/// Most raises of a release point (1 m in all): the search is bounded
/// whatever the sub-goal.
pub(crate) const MAX_RAISES: u32 = 100;
/// The heights `times` [`RAISE_STEP`]s above `z`, the nearest first (`z`
/// itself not among them): the candidates of every raise the planners
/// search, and [`Reachability`](super::reachable::Reachability) with
/// them, from one expression so that they agree to the bit.
pub(crate) fn raises(z: f64, times: u32) -> impl Iterator<Item = f64> {
    (1..=times).map(move |i| z + RAISE_STEP * f64::from(i))
}

/// [`raises`] downwards: a lift lowered.
pub(crate) fn lowerings(z: f64, times: u32) -> impl Iterator<Item = f64> {
    (1..=times).map(move |i| z - RAISE_STEP * f64::from(i))
}

/// Paths [`Station::search`] tries before it gives up on one whose
/// commands collide.
pub(crate) const SEARCH_TRIES: u64 = 4;
/// How far apart the seeds of those tries are (the next sub-goal's search
/// is seeded one more).
const SEARCH_SEED_STRIDE: u64 = 1_000_003;
/// The lowest a lift may be lowered to, above where the cup gripped (m):
/// the cell language's smallest `lift`.
pub(crate) const MIN_LIFT: f64 = 0.02;
/// Most raises of a point a held product is carried through (the approach,
/// above the slot) where every arm pose collides (0.5 m in all): a
/// product standing taller than the carrying height under the way.
pub(crate) const MAX_CARRY_RAISES: u32 = 50;
/// Height of the cup tip in the start pose.
pub const HOME_HEIGHT: f64 = 0.35;

/// A checked motion towards one sub-goal: the joint waypoints it passes
/// (the sub-goal's joints last) and the commands joining them from where
/// it starts, blended through the waypoints and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Route {
    pub waypoints: Vec<Joints>,
    pub samples: Vec<Joints>,
}

impl Route {
    /// This route, then `next` (which starts where this one ends).
    pub fn then(self, next: Route) -> Route {
        Route {
            waypoints: [self.waypoints, next.waypoints].concat(),
            samples: [self.samples, next.samples].concat(),
        }
    }
}

/// A sub-goal's joints ([`Station::solve`]), with the checked straight
/// motion to them when the solve checked it (a release, a lift): where it
/// started and its commands.
#[derive(Debug, Clone)]
pub struct Solved {
    pub joints: Joints,
    straight: Option<(Joints, Route)>,
}

impl Solved {
    /// The joints with the straight motion the solve checked, when that
    /// started at `from`; else the joints alone, to be routed to.
    fn kept_from(self, from: Joints) -> Result<(Joints, Route), Joints> {
        match self.straight {
            Some((start, route)) if start == from => Ok((self.joints, route)),
            _ => Err(self.joints),
        }
    }
}

/// The two swings from `from` to `to` that [`Station::route`] tries after
/// the straight motion, as via points: the base turned alone first (the
/// wrist keeping the cup's yaw), or last.
pub(crate) fn swings(from: Joints, to: Joints) -> [Joints; 2] {
    let turn = to[0] - from[0];
    let mut swing_first = from;
    swing_first[0] = to[0];
    swing_first[5] += turn;
    let mut swing_last = to;
    swing_last[0] = from[0];
    swing_last[5] -= turn;
    [swing_first, swing_last]
}

/// One leg to send: its route, the suction switched at its end, and what
/// it carries and may touch (owned, so that a leg can wait for the next
/// stage's: [`Station::send_legs`]).
#[derive(Debug, Clone)]
pub(crate) struct Leg {
    pub route: Route,
    pub suction: Suction,
    pub held: Option<Held>,
    /// The product the cup may touch, and whether it was just released
    /// (else it is being picked: [`Touch`]).
    pub ignore: Option<String>,
    pub released: bool,
    pub speed: f64,
}

/// Via points of a lift up the cup tip's line ([`Station::up_the_line`]).
pub(crate) const LIFT_VIAS: usize = 5;

/// The free inverse-kinematics solutions of the cup tip's straight line
/// from `a` to `b` at `n - 1` points evenly between (the ends left out),
/// each nearest the one before, from `from`; `None` where a point has
/// none.
pub(crate) fn tip_line(
    checker: &Checker,
    from: Joints,
    a: [f64; 3],
    b: [f64; 3],
    n: usize,
    yaw: f64,
    load: Load,
) -> Option<Vec<Joints>> {
    let mut near = from;
    (1..n)
        .map(|i| {
            let t = i as f64 / n as f64;
            let tip = Point3::from(std::array::from_fn::<f64, 3, _>(|j| {
                a[j] + (b[j] - a[j]) * t
            }));
            near = reach(checker, tip, yaw, &near, load)?;
            Some(near)
        })
        .collect()
}

/// Where the last of `legs` leaves the arm.
pub(crate) fn leg_end(legs: &[Leg]) -> Option<Joints> {
    legs.last().and_then(|l| l.route.waypoints.last().copied())
}

impl Leg {
    pub fn new(route: Route, suction: Suction, load: Load) -> Leg {
        Leg {
            route,
            suction,
            held: load.held.cloned(),
            ignore: load.ignore.map(|t| t.product().to_owned()),
            released: matches!(load.ignore, Some(Touch::Released(_))),
            speed: load.speed,
        }
    }

    pub fn load(&self) -> Load<'_> {
        Load {
            held: self.held.as_ref(),
            ignore: self.ignore.as_deref().map(|name| match self.released {
                true => Touch::Released(name),
                false => Touch::Picking(name),
            }),
            speed: self.speed,
        }
    }
}

/// How to join two configurations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Connect {
    /// A straight joint-space segment.
    Straight,
    /// RRT-Connect, seeded.
    Rrt { seed: u64 },
}

/// Wall-clock planning allowed, per sub-goal and for a whole package. Every
/// planning loop is bounded by counts too (RRT-Connect's samples, the
/// policy's steps, the raises of a release); the budget bounds the time
/// those counts can take on a slow or loaded machine. A run that goes
/// over stops with [`Failure::OutOfTime`]. The defaults are far above
/// what any measured plan took (README, "Reliability").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanningBudget {
    pub subgoal: Duration,
    pub package: Duration,
}

impl Default for PlanningBudget {
    fn default() -> PlanningBudget {
        PlanningBudget {
            subgoal: Duration::from_secs(10),
            package: Duration::from_secs(120),
        }
    }
}

/// Wall-clock planning and simulated motion of the product in hand.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Clock {
    pub planning_s: f64,
    pub steps: usize,
    /// The lower bound on the motion so far ([`ProductReport::bound_s`]):
    /// up to `stop`, where the arm last had to be at rest.
    pub bound_s: f64,
    pub stop: Option<Joints>,
}

/// What a motion carries and may touch: the product held, and the one
/// being picked or just released (the cup may touch it: [`Touch`]); and
/// how fast it moves.
#[derive(Debug, Clone, Copy)]
pub struct Load<'h> {
    pub held: Option<&'h Held>,
    pub ignore: Option<Touch<'h>>,
    /// The share of the arm's speed the motion moves at: 1, but on the
    /// guarded descent onto a top face the cell's `descent`
    /// ([`Load::guarded`]; [`blend_slowed`](crate::blend::blend_slowed) says how a share in (0, 1)
    /// slows a leg, and that any other value is full speed).
    pub speed: f64,
}

impl Default for Load<'_> {
    fn default() -> Self {
        Load::FREE
    }
}

impl<'h> Load<'h> {
    /// Nothing held, nothing ignored.
    pub const FREE: Load<'static> = Load {
        held: None,
        ignore: None,
        speed: 1.0,
    };

    /// Nothing held; the cup goes to pick the product `name`, whose top
    /// face it may touch from above ([`Touch::Picking`]).
    pub fn picking(name: &'h str) -> Load<'h> {
        Load {
            held: None,
            ignore: Some(Touch::Picking(name)),
            speed: 1.0,
        }
    }

    /// Nothing held; the cup leaves the product `name` it just let go,
    /// which it may touch anywhere ([`Touch::Released`]).
    pub fn released(name: &'h str) -> Load<'h> {
        Load {
            held: None,
            ignore: Some(Touch::Released(name)),
            speed: 1.0,
        }
    }

    /// Carrying `held`.
    pub fn holding(held: &'h Held) -> Load<'h> {
        Load {
            held: Some(held),
            ignore: None,
            speed: 1.0,
        }
    }

    /// This load on the guarded descent onto a top face: the motion at
    /// `speed` (the cell's `descent`, a share of the arm's speed).
    pub fn guarded(self, speed: f64) -> Load<'h> {
        Load { speed, ..self }
    }
}

/// The arm in its world, with the cell's checker.
pub(crate) struct Station<'a, W: World> {
    pub world: &'a mut W,
    pub arm: &'a Arm,
    pub task: &'a OrderTask,
    pub base: Isometry3<f64>,
    pub checker: Checker,
    pub clock: Clock,
    pub timing: Timing,
    /// The cup tip at each sub-goal reached, in order.
    pub subgoals: Vec<[f64; 3]>,
    pub budget: PlanningBudget,
    /// Planning spent on the package so far.
    pub package_planning: Duration,
    /// When the sub-goal being planned must be done (RRT-Connect stops
    /// searching then).
    pub deadline: Option<Instant>,
    /// The stage being planned or run (`None` for the way back up from a
    /// release): where a failure at a sub-goal happened
    /// (`ProductReport::failed_in`).
    pub stage: Option<Stage>,
    /// The way back up from the last release, checked but not sent yet.
    backup: Option<Backup>,
    /// How many products the robot has handled ([`Station::measure`]).
    handled: usize,
    /// The products where they stood when the station began: a product
    /// the run never picks must end there (`Report::disturbed`).
    standing: Vec<Seen>,
}

/// The way back up from a release, planned and checked right after it but
/// not sent: it is sent with the next product's first legs, so that the
/// arm passes over the slot into the next hover without stopping
/// ([`Station::keep_backup`]); at the end of a run it is sent alone
/// ([`Station::flush_backup`]).
///
/// Time accounting: a product's clock runs from where the previous
/// product's release settled to where its own release settles, so the
/// back-up of product `i` (blended into product `i + 1`'s hover) counts
/// for product `i + 1`, and the last back-up for the product it follows.
/// The sum over a run is the whole motion.
#[derive(Debug, Clone)]
struct Backup {
    legs: Vec<Leg>,
    /// The report row of the product it backs up from.
    row: usize,
}

impl<'a, W: World> Station<'a, W> {
    pub fn new(world: &'a mut W, arm: &'a Arm, task: &'a OrderTask) -> Station<'a, W> {
        let [x, y, z] = task.cell.base;
        let standing = world.observe().products;
        Station {
            standing,
            checker: Checker::new(arm, &task.cell),
            world,
            arm,
            task,
            base: Isometry3::translation(x, y, z),
            clock: Clock::default(),
            timing: Timing::default(),
            subgoals: Vec::new(),
            budget: PlanningBudget::default(),
            package_planning: Duration::ZERO,
            deadline: None,
            stage: None,
            backup: None,
            handled: 0,
        }
    }

    /// Keeps `legs`, the checked way back up from the release of the
    /// product in report row `row`, to be sent with the next motion
    /// ([`Backup`]).
    pub fn keep_backup(&mut self, legs: Vec<Leg>, row: usize) {
        self.backup = (!legs.is_empty()).then_some(Backup { legs, row });
    }

    /// Where the kept back-up leaves the arm.
    pub fn backup_end(&self) -> Option<Joints> {
        self.backup.as_ref().and_then(|b| leg_end(&b.legs))
    }

    /// The kept back-up legs (none when none is kept), to be sent first
    /// with the next product's legs: its motion is planned from where
    /// they end.
    pub fn take_backup(&mut self) -> Vec<Leg> {
        self.backup.take().map(|b| b.legs).unwrap_or_default()
    }

    /// Sends a kept back-up alone (the run ends, or stops) and adds its
    /// planning, motion and lower bound to its product's row in `rows`.
    pub fn flush_backup(&mut self, rows: &mut [ProductReport]) -> Result<(), Failure> {
        let Some(Backup { legs, row }) = self.backup.take() else {
            return Ok(());
        };
        self.restart_clock();
        let sent = self.send_legs(legs, false).map(|_| ());
        let end = self.world.observe().joints;
        self.stopped_at(end);
        let Clock {
            planning_s,
            steps,
            bound_s,
            ..
        } = self.restart_clock();
        if let Some(r) = rows.get_mut(row) {
            r.planning_s += planning_s;
            r.execution_s += steps as f64 * self.world.control_period();
            r.bound_s += bound_s;
        }
        sent
    }

    /// Starts planning a sub-goal: its deadline is the sooner of its own
    /// budget and what is left of the package's.
    pub fn begin(&mut self) -> Instant {
        let now = Instant::now();
        let left = self.budget.package.saturating_sub(self.package_planning);
        self.deadline = Some(now + self.budget.subgoal.min(left));
        now
    }

    /// Whether the sub-goal being planned is past its deadline.
    pub fn late(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    /// Ends planning sub-goal `k` (from 1) begun at `started`: its time
    /// counts for the product and the package, and a budget it overran
    /// stops the run. The seconds it took.
    pub fn spend(&mut self, k: usize, started: Instant) -> Result<f64, Failure> {
        let took = started.elapsed();
        self.deadline = None;
        self.clock.planning_s += took.as_secs_f64();
        self.package_planning += took;
        let over = |budget, limit: Duration| Failure::OutOfTime {
            subgoal: k,
            budget,
            limit_s: limit.as_secs_f64(),
        };
        if took > self.budget.subgoal {
            Err(over(Budget::SubGoal, self.budget.subgoal))
        } else if self.package_planning > self.budget.package {
            Err(over(Budget::Package, self.budget.package))
        } else {
            Ok(took.as_secs_f64())
        }
    }

    /// The cup tip at joints `q`.
    pub fn tip(&self, q: &Joints) -> [f64; 3] {
        self.arm
            .tool_tip(&self.base, q, self.task.cell.suction)
            .coords
            .into()
    }

    /// The checker's products, from an observation.
    pub fn sync_products(&mut self, obs: &Observation) {
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

    /// Joints that put the cup tip at sub-goal `goal` (number `k`, from 1)
    /// from `from`. A release the straight descent cannot reach (checked
    /// as the commands will be) is raised [`RAISE_STEP`] at a time up to
    /// `ceiling`: the product drops the rest of the way. A lift (the
    /// product just gripped, [`Held::leaving_support`]) must be reached by
    /// the straight motion too, carrying the product: where that motion
    /// cannot (the arm's shape at full height differs, and the joint
    /// motion to another shape would drag the product), it is lowered
    /// [`RAISE_STEP`] at a time down to [`MIN_LIFT`] above where the cup
    /// gripped. A point the product is carried through (the approach,
    /// above the slot) where every arm pose collides is raised
    /// [`RAISE_STEP`] at a time, at most [`MAX_CARRY_RAISES`] times: a
    /// product standing taller than the carrying height under the way (a
    /// bottle beside the pending area, the held product or the wrist
    /// against it). The straight motion checked for a release or a lift is
    /// kept with the joints ([`Solved`]): routing to them from `from`
    /// ([`Station::route_solved`]) sends it without checking it again.
    pub fn solve(
        &self,
        goal: &SubGoal,
        k: usize,
        from: &Joints,
        yaw: f64,
        load: Load,
        ceiling: f64,
    ) -> Result<Solved, Failure> {
        if goal.tip.iter().any(|v| !v.is_finite()) {
            return Err(Failure::NonFiniteSubGoal { subgoal: k });
        }
        let lifting = goal.suction == Suction::Keep && load.held.is_some_and(|h| h.leaving_support);
        let carried =
            goal.suction == Suction::Keep && load.held.is_some_and(|h| !h.leaving_support);
        // `line`: a lift up the cup tip's line where the straight joint
        // motion collides.
        let solve_by = |z: f64, line: bool| {
            let tip = Point3::new(goal.tip[0], goal.tip[1], z);
            let joints = reach(&self.checker, tip, yaw, from, load)?;
            // A release or a lift its straight motion cannot reach is
            // blocked (None).
            let straight = if goal.suction == Suction::Off || lifting {
                let route = self.checked(k, *from, &[joints], load).ok().or_else(|| {
                    line.then(|| self.up_the_line(k, *from, joints, yaw, load))
                        .flatten()
                })?;
                Some((*from, route))
            } else {
                None
            };
            Some(Solved { joints, straight })
        };
        let solve = |z: f64| solve_by(z, false);
        // A lowered lift leaves the product where the next motion, which
        // carries it padded all round, starts free: not down among its
        // neighbours, nor hanging beside one (the carry moves it
        // sideways).
        let clear_when_carried = |solved: &Solved| {
            load.held
                .is_none_or(|h| self.checker.clear_to_carry(&solved.joints, h, load.ignore))
        };
        solve(goal.tip[2])
            .or_else(|| {
                (goal.suction == Suction::Off)
                    .then(|| {
                        raises(goal.tip[2], MAX_RAISES)
                            .take_while(|z| *z <= ceiling)
                            .find_map(solve)
                    })
                    .flatten()
            })
            .or_else(|| {
                lifting
                    .then(|| {
                        let floor = self.tip(from)[2] + MIN_LIFT;
                        lowerings(goal.tip[2], MAX_RAISES)
                            .take_while(|z| *z >= floor)
                            .find_map(|z| solve(z).filter(clear_when_carried))
                    })
                    .flatten()
            })
            // Up the line last: the blend stops short of its vias.
            .or_else(|| lifting.then(|| solve_by(goal.tip[2], true)).flatten())
            .or_else(|| {
                carried
                    .then(|| raises(goal.tip[2], MAX_CARRY_RAISES).find_map(solve))
                    .flatten()
            })
            .ok_or_else(|| {
                // Where the cup can be put there but every arm pose
                // collides, what the nearest meets: a carried product over
                // a tall one is no matter of reach.
                let tip = Point3::new(goal.tip[0], goal.tip[1], goal.tip[2]);
                let met = solutions(&self.checker, tip, yaw, from)
                    .first()
                    .and_then(|q| self.checker.check(q, load.held, load.ignore));
                // A release or a lift whose pose is free: what its
                // straight motion meets.
                let way = (met.is_none() && (goal.suction == Suction::Off || lifting))
                    .then(|| reach(&self.checker, tip, yaw, from, load))
                    .flatten()
                    .and_then(|q| match self.checked(k, *from, &[q], load) {
                        Err(Failure::WouldCollide { hit, .. }) => Some(Box::new(hit)),
                        _ => None,
                    });
                Failure::Unreachable {
                    subgoal: k,
                    tip: goal.tip,
                    met,
                    way,
                }
            })
    }

    /// The checked way from `from` up the cup tip's straight line to
    /// `to`, through [`LIFT_VIAS`] via points (inverse kinematics, each
    /// nearest the one before), where the straight joint motion bows
    /// sideways into a neighbour: a product lifted from between others a
    /// few millimetres away. `None` when a via has no free solution or
    /// the way collides.
    fn up_the_line(
        &self,
        k: usize,
        from: Joints,
        to: Joints,
        yaw: f64,
        load: Load,
    ) -> Option<Route> {
        let (a, b) = (self.tip(&from), self.tip(&to));
        let mut vias = tip_line(&self.checker, from, a, b, LIFT_VIAS, yaw, load)?;
        vias.push(to);
        // Only beside the neighbours does the line matter.
        self.through(k, from, vias, load)
    }

    /// The checked commands from `from` through `points`, the points a
    /// straight joint motion skips left out first ([`fewer_vias`]: the
    /// blend stops short of each via, and speeds up on longer legs), else
    /// through every one.
    pub fn through(
        &self,
        k: usize,
        from: Joints,
        points: Vec<Joints>,
        load: Load,
    ) -> Option<Route> {
        let free = |a: &Joints, b: &Joints| {
            self.checker
                .check_motion(a, b, load.held, load.ignore)
                .is_none()
        };
        let fewer = fewer_vias(from, &points, free);
        (fewer.len() < points.len())
            .then(|| self.checked(k, from, &fewer, load).ok())
            .flatten()
            .or_else(|| self.checked(k, from, &points, load).ok())
    }

    /// A picking stage's sub-goals (hover, contact, lift) solved from the
    /// contact's arm shape rather than from where the arm is: for each
    /// free contact solution, nearest `from` first, the hover of the same
    /// shape (the solution nearest the contact) and the lift from the
    /// contact (carrying `held` gripped there), when the straight descent
    /// and the lift are free. The shape nearest the arm can leave no free
    /// way down or up: by a product close to the base the descent flips
    /// the wrist through a neighbour, or every way up folds the forearm
    /// into the base. The descent and the lift are kept, checked, with
    /// their joints; the way to the hover is the caller's. `None` when no
    /// shape does, or the sub-goal's budget runs out.
    pub fn grip(
        &self,
        goals: &[SubGoal; 3],
        from: &Joints,
        yaw: f64,
        loads: [Load; 2],
        held: &dyn Fn(&Joints) -> Held,
    ) -> Option<[Solved; 3]> {
        self.grips(goals, from, yaw, loads, held).next()
    }

    /// Every shape [`Station::grip`] finds free, nearest `from` first,
    /// each solved when it is asked for: a caller that cannot reach one
    /// shape's hover goes on to the next.
    pub fn grips<'s>(
        &'s self,
        goals: &'s [SubGoal; 3],
        from: &Joints,
        yaw: f64,
        loads: [Load<'s>; 2],
        held: &'s dyn Fn(&Joints) -> Held,
    ) -> impl Iterator<Item = [Solved; 3]> + 's {
        let [hover, contact, lift] = goals;
        let [free, guarded] = loads;
        let point = |g: &SubGoal| Point3::new(g.tip[0], g.tip[1], g.tip[2]);
        solutions(&self.checker, point(contact), yaw, from)
            .into_iter()
            .filter(move |q| {
                self.arm.within_limits(q)
                    && self
                        .checker
                        .check(q, guarded.held, guarded.ignore)
                        .is_none()
            })
            .take_while(|_| !self.late())
            .filter_map(move |at| {
                let gripped = held(&at);
                let up = self
                    .solve(lift, 3, &at, yaw, Load::holding(&gripped), lift.tip[2])
                    .ok()?;
                up.straight.as_ref().filter(|(start, _)| *start == at)?;
                let [over, down] =
                    self.descent_in_shape(2, point(hover), at, yaw, [free, guarded])?;
                Some([over, down, up])
            })
    }

    /// Sub-goal `k` reached straight down from `over` in the arm's shape
    /// at `at`: `over`'s free solution nearest `at` (free carrying
    /// `loads[0]`) and `at` with the checked straight descent to it
    /// (carrying `loads[1]`).
    fn descent_in_shape(
        &self,
        k: usize,
        over: Point3<f64>,
        at: Joints,
        yaw: f64,
        loads: [Load; 2],
    ) -> Option<[Solved; 2]> {
        let above = reach(&self.checker, over, yaw, &at, loads[0])?;
        let down = self.checked(k, above, &[at], loads[1]).ok()?;
        Some([
            Solved {
                joints: above,
                straight: None,
            },
            Solved {
                joints: at,
                straight: Some((above, down)),
            },
        ])
    }

    /// A placing stage's point above the slot and release solved from
    /// the release's arm shape rather than from where the arm is: for
    /// each free release solution (at the release's height, then raised
    /// as [`Station::solve`] raises it, up to the point above the slot),
    /// nearest `from` first, the point above the slot in the same shape
    /// (its free solution nearest the release) when the straight descent
    /// between them is free. The shape nearest the arm can leave no free
    /// way down: a box far behind the base, reached low with the upper
    /// arm over the table. The descent is kept, checked, with its joints;
    /// the way to the point above the slot is the caller's. `None` when
    /// no shape does, or the sub-goal's budget runs out.
    pub fn release_shape(
        &self,
        goals: [&SubGoal; 2],
        from: &Joints,
        yaw: f64,
        load: Load,
    ) -> Option<[Solved; 2]> {
        let [above, release] = goals;
        let point = |g: &SubGoal, z: f64| Point3::new(g.tip[0], g.tip[1], z);
        std::iter::once(release.tip[2])
            .chain(raises(release.tip[2], MAX_RAISES))
            .take_while(|z| *z <= above.tip[2])
            .take_while(|_| !self.late())
            .find_map(|z| {
                solutions(&self.checker, point(release, z), yaw, from)
                    .into_iter()
                    .filter(|q| {
                        self.arm.within_limits(q)
                            && self.checker.check(q, load.held, load.ignore).is_none()
                    })
                    .take_while(|_| !self.late())
                    .find_map(|at| {
                        self.descent_in_shape(3, point(above, above.tip[2]), at, yaw, [load; 2])
                    })
            })
    }

    /// The checked commands from `from` to `to` for sub-goal `k`.
    ///
    /// Both ways first try the straight joint-space motion and, when its
    /// commands collide, a swing: the base turned alone with the arm's
    /// shape kept (the wrist keeping the cup's yaw), then the rest of the
    /// motion, or the rest first and the swing last. On a front-to-back
    /// swing the straight line folds the wrist into the forearm half-way,
    /// where the arm held in shape sweeps clear. `Connect::Straight` then
    /// gives up with the straight motion's collision (the expert's loop
    /// searches after every other solution failed too, `scripted.rs`);
    /// `Connect::Rrt` searches. Every
    /// candidate is checked once, as the commands that will be sent.
    pub fn route(
        &self,
        how: Connect,
        k: usize,
        from: Joints,
        to: Joints,
        load: Load,
    ) -> Result<Route, Failure> {
        let straight = match self.checked(k, from, &[to], load) {
            Ok(route) => return Ok(route),
            Err(why @ Failure::WouldCollide { .. }) => why,
            Err(other) => return Err(other),
        };
        for via in swings(from, to) {
            if self.arm.within_limits(&via)
                && let Ok(route) = self.checked(k, from, &[via, to], load)
            {
                return Ok(route);
            }
        }
        match how {
            Connect::Straight => Err(straight),
            Connect::Rrt { seed } => self.search(seed, k, from, to, load),
        }
    }

    /// RRT-Connect's search from `from` to `to` (seeded by `seed`, within
    /// the planning deadline), its path checked as the commands that will
    /// be sent; [`Failure::NoPath`] if it finds none. A path whose
    /// commands collide (its edges pass the search's check, the commands
    /// graze an obstacle the start stands close to: wrist 3 beside a tall
    /// product packed next to the slot it backed up from) is searched for
    /// again with the next seeds, up to [`SEARCH_TRIES`] paths in all;
    /// the first path's collision is the one reported.
    pub fn search(
        &self,
        seed: u64,
        k: usize,
        from: Joints,
        to: Joints,
        load: Load,
    ) -> Result<Route, Failure> {
        let query = Query {
            checker: &self.checker,
            limits: &self.arm.limits,
            held: load.held,
            ignore: load.ignore,
        };
        let mut first = None;
        for attempt in 0..SEARCH_TRIES {
            let config = RrtConfig {
                seed: seed.wrapping_add(attempt.wrapping_mul(SEARCH_SEED_STRIDE)),
                deadline: self.deadline,
                ..RrtConfig::default()
            };
            let Some(path) = rrt::search(&query, from, to, &config) else {
                break;
            };
            match self.checked(k, from, path.get(1..).unwrap_or(&[]), load) {
                Ok(route) => return Ok(route),
                Err(why) => {
                    first.get_or_insert(why);
                }
            }
            if self.late() {
                break;
            }
        }
        Err(first.unwrap_or(Failure::NoPath { subgoal: k }))
    }

    /// The checked commands from `from` to a solved sub-goal: the
    /// straight motion its solve checked, when that started at `from`;
    /// else [`Station::route_any`]. `load` must be the one it was solved
    /// with (a release's and a lift's are not guarded).
    pub fn route_solved(
        &self,
        how: Connect,
        k: usize,
        from: Joints,
        solved: Solved,
        yaw: f64,
        load: Load,
    ) -> Result<(Joints, Route), Failure> {
        match solved.kept_from(from) {
            Ok(kept) => Ok(kept),
            Err(joints) => self.route_any(how, k, from, joints, yaw, load),
        }
    }

    /// The checked commands from `from` to a solved sub-goal in its own
    /// arm shape: the straight motion its solve checked, when that started
    /// at `from`, else [`Station::route`] to its joints (never another
    /// solution, as [`Station::route_solved`] may take: a plan solved in
    /// one shape, [`Station::grip`], re-solved nearest another shape
    /// failed as the first plan had).
    pub fn route_in_shape(
        &self,
        how: Connect,
        k: usize,
        from: Joints,
        solved: Solved,
        load: Load,
    ) -> Result<(Joints, Route), Failure> {
        match solved.kept_from(from) {
            Ok(kept) => Ok(kept),
            Err(joints) => self
                .route(how, k, from, joints, load)
                .map(|route| (joints, route)),
        }
    }

    /// [`Station::route`] to `target`, else to another free
    /// inverse-kinematics solution of the same cup pose (nearest `from`
    /// first, joined straight or by a swing): the nearest solution can have
    /// another wrist or shoulder shape, whose motion folds the arm into
    /// itself where one a little further away sweeps clear. The joints
    /// reached and the commands, or the first failure.
    pub fn route_any(
        &self,
        how: Connect,
        k: usize,
        from: Joints,
        target: Joints,
        yaw: f64,
        load: Load,
    ) -> Result<(Joints, Route), Failure> {
        let first = match self.route(how, k, from, target, load) {
            Ok(route) => return Ok((target, route)),
            Err(why @ (Failure::WouldCollide { .. } | Failure::NoPath { .. })) => why,
            Err(other) => return Err(other),
        };
        let others = self.other_solutions(from, target, yaw, load);
        let straight = others.iter().find_map(|&q| {
            self.route(Connect::Straight, k, from, q, load)
                .ok()
                .map(|route| (q, route))
        });
        match (straight, how) {
            (Some(found), _) => Some(found),
            (None, Connect::Rrt { seed }) => {
                let targets = self.searched_too(target, others);
                self.search_among(seed, k, from, &targets, load)
            }
            (None, Connect::Straight) => None,
        }
        .ok_or(first)
    }

    /// What a search goes on to after `target` ([`Station::search_any`]):
    /// its `others` (the other free solutions), then `target` and those
    /// with one joint a whole turn round.
    fn searched_too(&self, target: Joints, others: Vec<Joints>) -> Vec<Joints> {
        let turned: Vec<Joints> = std::iter::once(target)
            .chain(others.iter().copied())
            .flat_map(|q| self.turned_round(q))
            .collect();
        others.into_iter().chain(turned).collect()
    }

    /// The free inverse-kinematics solutions of `target`'s cup pose other
    /// than `target`, nearest `from` first.
    fn other_solutions(&self, from: Joints, target: Joints, yaw: f64, load: Load) -> Vec<Joints> {
        let tip = self
            .arm
            .tool_tip(&self.base, &target, self.task.cell.suction);
        solutions(&self.checker, tip, yaw, &from)
            .into_iter()
            .filter(|q| {
                joint_distance(q, &target) > 1e-12
                    && self.checker.check(q, load.held, load.ignore).is_none()
            })
            .collect()
    }

    /// [`Station::search`] to each of `targets` in turn while the
    /// deadline lasts: the first found, with the joints it reaches.
    fn search_among(
        &self,
        seed: u64,
        k: usize,
        from: Joints,
        targets: &[Joints],
        load: Load,
    ) -> Option<(Joints, Route)> {
        targets
            .iter()
            .take_while(|_| !self.late())
            .find_map(|&q| self.search(seed, k, from, q, load).ok().map(|r| (q, r)))
    }

    /// [`Station::search`] to `target`, else to another free
    /// inverse-kinematics solution of the same cup pose, nearest `from`
    /// first, else to the same solutions with one joint a whole turn
    /// round (within its limits): the expert's last resort. Which of a
    /// joint's two angles a solution takes decides how far the search
    /// has to go, through what: swinging from a far corner of a box in
    /// front to a tall product behind, wrist 1 had to turn 3.1 rad to
    /// 4.17 rad, past the forearm, and 4,000 samples found no way, where
    /// the same pose with wrist 1 at -2.11 rad was found at once. The
    /// joints reached and the commands, or the search's failure to
    /// `target`.
    pub fn search_any(
        &self,
        seed: u64,
        k: usize,
        from: Joints,
        target: Joints,
        yaw: f64,
        load: Load,
    ) -> Result<(Joints, Route), Failure> {
        let first = match self.search(seed, k, from, target, load) {
            Ok(route) => return Ok((target, route)),
            Err(why) => why,
        };
        let others = self.other_solutions(from, target, yaw, load);
        let targets = self.searched_too(target, others);
        self.search_among(seed, k, from, &targets, load)
            .ok_or(first)
    }

    /// `q` with one joint a whole turn round, each way, where that stays
    /// within the joint's limits: the same pose.
    fn turned_round(&self, q: Joints) -> Vec<Joints> {
        (0..q.len())
            .flat_map(|j| [-TAU, TAU].map(move |turn| (j, turn)))
            .map(|(j, turn)| {
                let mut p = q;
                p[j] += turn;
                p
            })
            .filter(|p| self.arm.within_limits(p))
            .collect()
    }

    /// The checked commands from `start` through `waypoints` towards
    /// sub-goal `k`.
    pub fn checked(
        &self,
        k: usize,
        start: Joints,
        waypoints: &[Joints],
        load: Load,
    ) -> Result<Route, Failure> {
        checked_samples(self.arm, &self.checker, start, waypoints, load)
            .map(|samples| Route {
                waypoints: waypoints.to_vec(),
                samples,
            })
            .map_err(|e| match e {
                Unchecked::Collides(hit) => Failure::WouldCollide { subgoal: k, hit },
                Unchecked::Smoothing(reason) => Failure::Smoothing { subgoal: k, reason },
            })
    }

    /// Sends `legs` from where the arm is, blended through the sub-goals
    /// where the suction does not switch (the arm stops only where it
    /// does) when those commands pass the check too, each sample checked
    /// with its leg's load (in an overlap, the later leg's); else each
    /// leg's own checked commands, stopping at every sub-goal. The suction
    /// switches at the end of each leg that says so.
    ///
    /// With `keep_tail`, the legs after the last switch are not sent but
    /// returned, to be sent with the next stage's (the lift blends into the
    /// carry that follows); else everything is sent and the arm stops at
    /// the end.
    pub fn send_legs(&mut self, legs: Vec<Leg>, keep_tail: bool) -> Result<Vec<Leg>, Failure> {
        let split = if keep_tail {
            legs.iter()
                .rposition(|l| l.suction != Suction::Keep)
                .map_or(0, |i| i + 1)
        } else {
            legs.len()
        };
        let mut legs = legs;
        let tail = legs.split_off(split);
        if legs.is_empty() {
            return Ok(tail);
        }
        let start = self.world.observe().joints;
        let started = std::time::Instant::now();
        let mut waypoints = Vec::new();
        let mut stops = Vec::new();
        // The leg of each waypoint, and the waypoint ending each leg.
        let mut owner = Vec::new();
        let mut ends = Vec::new();
        for (j, leg) in legs.iter().enumerate() {
            let n = leg.route.waypoints.len();
            let switches = leg.suction != Suction::Keep;
            for (i, w) in leg.route.waypoints.iter().enumerate() {
                waypoints.push(*w);
                stops.push(i + 1 == n && switches);
                owner.push(j);
            }
            // A leg that does not move (its sub-goal already reached)
            // switches where the leg before it ends: the arm stops there.
            if n == 0
                && switches
                && let Some(last) = stops.last_mut()
            {
                *last = true;
            }
            ends.push(waypoints.len().checked_sub(1));
        }
        let load_of = |w: usize| owner.get(w).map_or(Load::FREE, |&j| legs[j].load());
        let blended = (legs.len() > 1)
            .then(|| {
                checked_blend_by(self.arm, &self.checker, start, &waypoints, &stops, load_of).ok()
            })
            .flatten();
        let took = started.elapsed();
        self.clock.planning_s += took.as_secs_f64();
        self.package_planning += took;
        let Some(blended) = blended else {
            for leg in &legs {
                self.send(&leg.route.samples, leg.suction)?;
            }
            return Ok(tail);
        };
        // Split at the stops: the commands up to each, then its switch.
        let mut from = 0;
        for (leg, end) in legs.iter().zip(ends) {
            let last = end.is_some_and(|e| e + 1 == waypoints.len());
            if leg.suction == Suction::Keep && !last {
                continue;
            }
            // No waypoint yet: the arm is at rest where it starts.
            let to = end.map_or(0, |e| {
                blended.at.get(e).map_or(blended.samples.len(), |&i| i + 1)
            });
            self.send(blended.samples.get(from..to).unwrap_or(&[]), leg.suction)?;
            from = to;
        }
        Ok(tail)
    }

    /// Sends checked commands, then switches the suction and lets things
    /// settle, the arm still, for the cell's settle time (its
    /// `grip_settle` after switching on, `release_settle` after switching
    /// off, in whole control cycles: [`settle_cycles`]); fails on any
    /// contact the world reports.
    pub fn send(&mut self, samples: &[Joints], suction: Suction) -> Result<(), Failure> {
        if self.clock.stop.is_none() {
            self.clock.stop = Some(self.world.observe().joints);
        }
        for q in samples {
            self.world.command(q)?;
            self.world.step()?;
            self.clock.steps += 1;
        }
        let period = self.world.control_period();
        let cell = &self.task.cell;
        let settle = match suction {
            Suction::Keep => 0,
            Suction::On => {
                self.world.set_suction(true)?;
                settle_cycles(cell.grip_settle, period)
            }
            Suction::Off => {
                self.world.set_suction(false)?;
                settle_cycles(cell.release_settle, period)
            }
        };
        for _ in 0..settle {
            self.world.step()?;
            self.clock.steps += 1;
        }
        if suction != Suction::Keep
            && let Some(&end) = samples.last()
        {
            self.stopped_at(end);
            self.clock.bound_s += settle as f64 * period;
        }
        match self.world.take_collisions().into_iter().next() {
            Some(contact) => Err(Failure::Collision { contact }),
            None => Ok(()),
        }
    }

    /// The arm had to be at rest at `q` (a contact, a release, the end of
    /// a product): the bound grows by the least time from the last such
    /// stop.
    fn stopped_at(&mut self, q: Joints) {
        if let Some(from) = self.clock.stop {
            // Both are within the limits (they were commanded), so Ruckig
            // has a trajectory; if not, the bound stays what it was.
            self.clock.bound_s += lower_bound(self.arm.limits, from, q).unwrap_or(0.0);
        }
        self.clock.stop = Some(q);
    }

    /// The clock of the product in hand, restarted.
    pub fn restart_clock(&mut self) -> Clock {
        std::mem::take(&mut self.clock)
    }

    /// A report row for the selected product `p` going to slot `s`.
    pub fn row(&self, p: usize, s: usize) -> ProductReport {
        ProductReport {
            product: self.task.products[p].name.clone(),
            slot: self.task.cell.slots[s].name.clone(),
            planning_s: 0.0,
            execution_s: 0.0,
            bound_s: 0.0,
            error_m: None,
            turn: None,
            outcome: packwright_interface::Outcome::NotAttempted,
            failed_in: None,
        }
    }

    /// Whether product `p` is seen within [`UNMOVED`] of `stood` (where
    /// it stood when its handling began).
    pub fn unmoved(&self, p: usize, stood: Option<[f64; 3]>) -> bool {
        let now = self.world.observe();
        match (now.find(&self.task.products[p].name), stood) {
            (Some((centre, _)), Some(stood)) => distance(centre, stood) <= UNMOVED,
            _ => false,
        }
    }

    /// Fills in `row` (product `p` for slot `s`) after the robot handled
    /// it: the planning and motion time since [`restart_clock`] and the
    /// product's distance from its goal now. A product handled again (let
    /// go off its slot, then picked from where it fell) keeps its first
    /// turn, and its times are the sum of both: the rows add up to the
    /// package's time.
    ///
    /// [`restart_clock`]: Station::restart_clock
    pub fn measure(&mut self, row: &mut ProductReport, p: usize, s: usize) {
        self.handled += 1;
        row.turn.get_or_insert(self.handled);
        let period = self.world.control_period();
        let after = self.world.observe();
        row.error_m = self.error_of(&after, p, s);
        self.stopped_at(after.joints);
        let Clock {
            planning_s,
            steps,
            bound_s,
            ..
        } = self.restart_clock();
        row.planning_s += planning_s;
        row.execution_s += steps as f64 * period;
        row.bound_s += bound_s;
    }

    /// How far product `p` is from its goal in slot `s` now.
    pub fn error_of(&self, obs: &Observation, p: usize, s: usize) -> Option<f64> {
        obs.find(&self.task.products[p].name)
            .map(|(c, _)| distance(c, self.task.goal(p, s)))
    }

    /// The products seen at `last` that the run never picked (not selected,
    /// or not attempted: `products` are the report rows, in assignment
    /// order) and that are more than [`SUCCESS_RADIUS`] from where they
    /// stood when the station began.
    fn disturbed(&self, last: &Observation, products: &[ProductReport]) -> Vec<Disturbance> {
        let handled = |name: &str| {
            self.task
                .assignment
                .iter()
                .zip(products)
                .any(|(&(p, _), row)| {
                    self.task.products[p].name == name && row.outcome != Outcome::NotAttempted
                })
        };
        self.standing
            .iter()
            .filter(|seen| !handled(&seen.name))
            .filter_map(|seen| {
                let (now, _) = last.find(&seen.name)?;
                let moved_m = distance(now, seen.centre);
                (moved_m > SUCCESS_RADIUS).then(|| Disturbance {
                    product: seen.name.clone(),
                    moved_m,
                })
            })
            .collect()
    }

    /// The report once the arm has stopped: products knocked out of place
    /// later count as failed too.
    pub fn finish(
        &mut self,
        planner: PlannerKind,
        mut products: Vec<ProductReport>,
        collisions: Vec<Contact>,
    ) -> Report {
        let task = self.task;
        let last = self.world.observe();
        for (report, &(p, s)) in products.iter_mut().zip(&task.assignment) {
            if report.outcome.in_slot() {
                let error = self.error_of(&last, p, s);
                report.error_m = error;
                if !error.is_some_and(|e| e <= SUCCESS_RADIUS) {
                    report.outcome = packwright_interface::Outcome::Failed(Failure::MovedLater);
                }
            }
        }
        let disturbed = self.disturbed(&last, &products);
        let complete = products.iter().all(|r| r.outcome.in_slot())
            && collisions.is_empty()
            && disturbed.is_empty();
        Report {
            planner,
            products,
            complete,
            collisions,
            disturbed,
            time_s: last.time,
            fallbacks: Vec::new(),
            violations: Vec::new(),
            timing: std::mem::take(&mut self.timing),
            subgoals: std::mem::take(&mut self.subgoals),
        }
    }
}

pub(crate) use packwright_interface::outcome::SUCCESS_RADIUS;

/// The whole control cycles of `period` seconds a settle time of
/// `seconds` takes, rounded to the nearest (the default 0.1 s and 0.5 s
/// are 50 and 250 cycles of 2 ms). A time that is not finite or not
/// positive, or a period that is not, is no wait.
pub(crate) fn settle_cycles(seconds: f64, period: f64) -> usize {
    let cycles = seconds / period;
    if cycles.is_finite() && cycles > 0.0 {
        // The compiler bounds settle times to seconds: far below usize.
        cycles.round() as usize
    } else {
        0
    }
}

/// How far (m) a product may be seen from where it stood when its
/// handling began and still count as never moved (the simulator's
/// products settle by a fraction of a millimetre).
pub(crate) const UNMOVED: f64 = 0.003;

/// The outcome of a measured `row` whose handling ended with `result`:
/// packed when it rests within [`SUCCESS_RADIUS`] of its goal, else the
/// failure (the handling's, or how far it was released from its goal,
/// or, when it still stands where it was picked from (`unmoved`), that
/// the cup did not grip it).
pub(crate) fn judge(
    row: &mut ProductReport,
    result: Result<(), Failure>,
    unmoved: bool,
    stage: Option<Stage>,
) -> Result<(), Failure> {
    row.failed_in = result.as_ref().err().and_then(Failure::subgoal).and(stage);
    let result = result.and_then(|()| match row.error_m {
        Some(e) if e <= SUCCESS_RADIUS => Ok(()),
        Some(error_m) if unmoved => Err(Failure::NotGripped { error_m }),
        e => Err(Failure::Misplaced {
            error_m: e.unwrap_or(f64::NAN),
        }),
    });
    row.outcome = match &result {
        Ok(()) => packwright_interface::Outcome::Packed,
        Err(why) => packwright_interface::Outcome::Failed(why.clone()),
    };
    result
}

pub(crate) fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Why [`checked_samples`] gave no commands.
#[derive(Debug, Clone, PartialEq)]
pub enum Unchecked {
    /// A command would collide.
    Collides(Hit),
    /// The smoother refused (its reason, for people).
    Smoothing(String),
}

/// The smoothed 2 ms commands from `start` through `waypoints`, passing
/// through the waypoints before the last without stopping where the
/// check allows ([`checked_blend`] with no stops): the very commands that
/// will be sent, or why they would not do.
pub fn checked_samples(
    arm: &Arm,
    checker: &Checker,
    start: Joints,
    waypoints: &[Joints],
    load: Load,
) -> Result<Vec<Joints>, Unchecked> {
    checked_blend(arm, checker, start, waypoints, &[], load).map(|b| b.samples)
}

/// The blended 2 ms commands from `start` through `waypoints`, stopping
/// where `stops` says (and at the last), each checked for collision (the
/// straight joint segment from the last checked sample, at most 1 degree
/// on). The product a load ignores (the cup touching its top face) is
/// ignored only on the straight segments: a transition's commands are
/// checked with it as an obstacle. Each leg keeps straight next to a stop
/// until the cup tip is [`STOP_CLEARANCE`] from it (a slowed leg: half its
/// time). A corner whose blended commands would collide gets a smaller
/// transition, then becomes a stop, and the motion is blended again, so
/// the commands are never less safe than stopping at every waypoint: when
/// that collides too, this is the collision.
pub fn checked_blend(
    arm: &Arm,
    checker: &Checker,
    start: Joints,
    waypoints: &[Joints],
    stops: &[bool],
    load: Load,
) -> Result<Blended, Unchecked> {
    checked_blend_by(arm, checker, start, waypoints, stops, |_| load)
}

/// The smallest cap ([`blend_capped`]) a corner whose transition
/// collides is halved to before it becomes a stop.
const MIN_CAP: f64 = 0.2;

/// [`checked_blend`] with a load per leg: `load_of(k)` for the leg ending
/// at waypoint `k`; a sample is checked with its leg's load (in an
/// overlap, the later leg's), and the leg moves at its load's speed
/// ([`blend_slowed`](crate::blend::blend_slowed)).
pub fn checked_blend_by<'h>(
    arm: &Arm,
    checker: &Checker,
    start: Joints,
    waypoints: &[Joints],
    stops: &[bool],
    load_of: impl Fn(usize) -> Load<'h>,
) -> Result<Blended, Unchecked> {
    let mut caps = crate::blend::full_caps(waypoints.len(), stops);
    // Each round halves one corner's cap, and a cap at MIN_CAP or below
    // makes it a stop: at most four rounds per waypoint.
    // The start is where the arm is: checked once, with the first leg's
    // load.
    let first = load_of(0);
    if let (false, Some(hit)) = (
        waypoints.is_empty(),
        checker.check(&start, first.held, first.ignore),
    ) {
        return Err(Unchecked::Collides(hit));
    }
    let mut previous: Option<(Blended, Checked)> = None;
    // Each leg's speed: its load's (the guarded descent is slowed).
    let speeds: Vec<f64> = (0..waypoints.len()).map(|k| load_of(k).speed).collect();
    let straight = straight_shares(checker, start, waypoints, &speeds);
    loop {
        let motion = blend_straight(arm.limits, start, waypoints, &caps, &speeds, &straight)
            .map_err(|e| Unchecked::Smoothing(e.to_string()))?;
        // A capped corner changes the samples from its transition on
        // only: those before it passed in the round before.
        let from_start = Checked::at(checker, 0, start, first.held);
        let mut checked = previous.as_ref().map_or(from_start, |(before, checked)| {
            resume_point(before, &motion, *checked, from_start)
        });
        let Some((i, hit)) = first_collision(checker, &motion, &load_of, &mut checked) else {
            return Ok(motion);
        };
        let near = motion.corner_near(i);
        previous = Some((motion, checked));
        match near {
            Some(k) => {
                caps[k] = if caps[k] > MIN_CAP {
                    caps[k] / 2.0
                } else {
                    0.0
                }
            }
            None => return Err(Unchecked::Collides(hit)),
        }
    }
}

/// How far from a stop's tip position (m) a leg next to it keeps to its
/// straight joint segment ([`blend_straight`]), when the leg is long
/// enough. Next to a stop the cup touches a top face (the product picked,
/// or just released, which the leg's check ignores for the cup) or a held
/// product touches its support or nearly the box floor. The padded cup
/// reaches [`PADDING`](packwright_kinematics::body::PADDING) −
/// [`CUP_SHORT`](packwright_kinematics::body::CUP_SHORT) = 5 mm below the
/// tip, a held product's box [`HELD_PADDING`](packwright_kinematics::body::HELD_PADDING)
/// = 3 mm beyond its faces; at 2 cm both are clear of the face by 15 mm
/// or more, so the transition's commands, which are checked with nothing
/// ignored ([`checked_blend`]), can pass the check there.
pub const STOP_CLEARANCE: f64 = 0.02;

/// Per leg, the shares of its way kept straight next to a stop it leaves
/// and one it reaches ([`blend_straight`]): up to where the cup tip is
/// [`STOP_CLEARANCE`] from its position at that end (the whole leg when
/// it never gets that far). A slowed leg (the guarded descent onto a top
/// face) keeps [`MIN_STRAIGHT`](crate::blend::MIN_STRAIGHT) of its time
/// (`None`): the cell asked for that descent at its own speed.
fn straight_shares(
    checker: &Checker,
    start: Joints,
    waypoints: &[Joints],
    speeds: &[f64],
) -> Vec<Option<[f64; 2]>> {
    let tip = |q: &Joints| checker.arm().tool_tip(checker.base(), q, checker.suction());
    let radii = checker.arm().tip_radii(checker.suction());
    // The least share of the way from `stop` to `other` beyond which the
    // tip is STOP_CLEARANCE or more from the tip at `stop`, on a grid of
    // SHARES steps (rounded up: the next grid point after the last one
    // nearer).
    const SHARES: usize = 64;
    let share = |stop: &Joints, other: &Joints| -> f64 {
        let at = tip(stop);
        // How far the tip can move from one grid point to the next
        // (`Arm::tip_radii`).
        let per_step = (0..DOF)
            .map(|j| radii[j] * (other[j] - stop[j]).abs())
            .sum::<f64>()
            / SHARES as f64;
        // The last grid point nearer than STOP_CLEARANCE, scanning back
        // from the far end: a point `d` away proves the `m` points before
        // it farther than STOP_CLEARANCE too, for `m * per_step` up to
        // `d - STOP_CLEARANCE` (less 1 nm, far above rounding), so they
        // are skipped. The same point as testing every one.
        let mut i = SHARES;
        let last_near = loop {
            if i == 0 {
                break 0;
            }
            let s = i as f64 / SHARES as f64;
            let q: Joints = std::array::from_fn(|j| stop[j] + s * (other[j] - stop[j]));
            let d = (tip(&q) - at).norm();
            if d < STOP_CLEARANCE {
                break i;
            }
            let far = ((d - STOP_CLEARANCE - 1e-9) / per_step).floor();
            let skip = if far.is_finite() && far > 0.0 {
                (far as usize).min(i)
            } else {
                0
            };
            i = i.saturating_sub(skip + 1);
        };
        ((last_near + 1) as f64 / SHARES as f64).min(1.0)
    };
    let mut from = start;
    waypoints
        .iter()
        .zip(speeds)
        .map(|(to, speed)| {
            let slowed = *speed > 0.0 && *speed < 1.0;
            let shares = (!slowed).then(|| [share(&from, to), share(to, &from)]);
            from = *to;
            shares
        })
        .collect()
}

/// How far a check of a motion's samples got: the first sample not yet
/// checked, the configuration fully checked last, and the held product's
/// box there (for the next sample's load) to sweep it from.
#[derive(Debug, Clone, Copy)]
struct Checked {
    from: usize,
    last: Joints,
    held: Option<HeldPose>,
}

impl Checked {
    /// Fully checked up to sample `from`, last at `q`, where `held` (the
    /// next sample's) hangs from the cup.
    fn at(checker: &Checker, from: usize, q: Joints, held: Option<&Held>) -> Checked {
        Checked {
            from,
            last: q,
            held: held.map(|h| checker.held_pose(&q, h)),
        }
    }

    /// Whether `q` is a degree or more from the last full check in some
    /// joint: the arm, padded by a centimetre, must be checked again.
    fn far(&self, q: &Joints) -> bool {
        span(q, &self.last) >= MAX_STEP
    }
}

/// The largest joint difference between `a` and `b`.
fn span(a: &Joints, b: &Joints) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The first of `motion`'s samples whose configuration collides, checking
/// from `done` on; `done` is left at how far the check got before it.
///
/// Which samples are checked (each with its leg's load, but that a sample
/// a transition shaped ([`Blended::shaped`]) ignores no product: the load's
/// ignored product is no obstacle on the straight segment next to its
/// stop only): the last one,
/// the last of each leg, and otherwise a sample when the next one is
/// [`MAX_STEP`] or more (in some joint) from the last checked one. So
/// consecutive checked configurations are less than [`MAX_STEP`] apart in
/// every joint (two commands 2 ms apart differ by at most 0.24 degree at
/// the UR10's speeds), and every command lies within [`MAX_STEP`] of the
/// checked command before it: the spacing [`Checker::check_motion`] gives
/// a straight motion, with every checked configuration a commanded one.
/// Where a checked sample is [`MAX_STEP`] or more from the one before
/// (the first after `start` or after a resumed check), the straight motion
/// between them is checked at that spacing instead. A held product is
/// swept from each checked sample to the next through the commands
/// between ([`Checker::sweep`]), ignoring no product where a transition
/// shaped any of them.
fn first_collision<'h>(
    checker: &Checker,
    motion: &Blended,
    load_of: &impl Fn(usize) -> Load<'h>,
    done: &mut Checked,
) -> Option<(usize, Hit)> {
    let samples = &motion.samples;
    for i in done.from..samples.len() {
        let q = &samples[i];
        let leg = motion.leg_at(i);
        let last_one = i + 1 == samples.len();
        let changes = !last_one && motion.leg_at(i + 1) != leg;
        let next_far = samples.get(i + 1).is_none_or(|next| done.far(next));
        if !(last_one || changes || next_far) {
            continue;
        }
        let load = load_of(leg);
        // The product a leg ignores is ignored on its straight segment
        // only: a transition's commands must keep the cup off it too.
        let ignore = if motion.shaped(i) { None } else { load.ignore };
        // Far from the last full check: the straight motion to it, the
        // held product swept along it.
        let far = done.far(q);
        let posed = if far {
            checker.check_motion_posed(&done.last, q, load.held, ignore)
        } else {
            checker.check_posed(q, load.held, ignore)
        };
        let at = match posed {
            Ok(at) => at,
            Err(hit) => return Some((i, hit)),
        };
        // The held product from the last full check to this one, through
        // the commands between.
        let between = &samples[done.from..i];
        if !(far && between.is_empty())
            && let (Some(held), Some(from), Some(to)) = (load.held, &done.held, &at)
        {
            let ignore = if motion.shaped_within(done.from..i + 1) {
                None
            } else {
                load.ignore
            };
            if let Some(hit) = checker.sweep(&done.last, from, q, to, between, held, ignore) {
                return Some((i, hit));
            }
        }
        let next_held = if changes {
            load_of(motion.leg_at(i + 1)).held
        } else {
            load.held
        };
        *done = if next_held == load.held {
            Checked {
                from: i + 1,
                last: *q,
                held: at,
            }
        } else {
            Checked::at(checker, i + 1, *q, next_held)
        };
    }
    None
}

/// Where a check of `motion` can resume after `before` (the motion of the
/// round before, checked up to `checked`): the samples both have alike, with
/// the same legs, passed already; from the start when they differ before.
fn resume_point(before: &Blended, motion: &Blended, checked: Checked, start: Checked) -> Checked {
    let alike = (0..checked.from).all(|i| {
        motion.samples.get(i) == before.samples.get(i) && motion.leg_at(i) == before.leg_at(i)
    });
    if alike { checked } else { start }
}

/// Joints that put the cup tip at `tip` pointing down with `yaw`, free of
/// collisions: among the inverse-kinematics branches (all eight for a UR
/// arm), the one nearest `near` that `checker` (its arm, base and cup)
/// finds free.
pub fn reach(
    checker: &Checker,
    tip: Point3<f64>,
    yaw: f64,
    near: &Joints,
    load: Load,
) -> Option<Joints> {
    solutions(checker, tip, yaw, near)
        .into_iter()
        .find(|q| checker.check(q, load.held, load.ignore).is_none())
}

/// Every inverse-kinematics solution for the cup tip at `tip` pointing
/// down with `yaw`, nearest `near` first, not yet checked for collisions
/// (callers check lazily: the nearest free one is usually the first).
pub(crate) fn solutions(
    checker: &Checker,
    tip: Point3<f64>,
    yaw: f64,
    near: &Joints,
) -> Vec<Joints> {
    let (arm, base) = (checker.arm(), checker.base());
    let flange = tool_down_pose(tip, yaw, checker.suction());
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
}

/// Where the cup tip starts: [`HOME_HEIGHT`] over the middle of the
/// pending area.
pub fn home_tip(cell: &CellScene) -> [f64; 3] {
    let (lo, hi) = cell.pending;
    [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, HOME_HEIGHT]
}

/// The start pose: the cup [`HOME_HEIGHT`] over the middle of the
/// pending area (lower, down to 0.2 m, where the arm reaches no free pose
/// there: [`START_HEIGHTS`]), pointing down, collision-free, on the branch nearest the usual UR
/// "ready" pose among those that can go straight down from there to
/// [`START_CHECK_HEIGHT`] over the table (any free one if none can). A
/// branch that cannot (the upper arm pointing back over the table, the
/// elbow below it) sends the first descent through the arm's stretched
/// pose, folding the forearm into the cup.
pub fn home(arm: &Arm, cell: &CellScene) -> Option<Joints> {
    home_among(arm, cell, &[])
}

/// [`home`] with the products standing in the cell (`standing`, where
/// they wait at the start): a branch whose arm meets one of them is taken
/// only where every free branch does (then the first motion reports the
/// collision). A cup close to the base over tall products can put the
/// elbow of the branch nearest "ready" down among them.
pub fn home_among(arm: &Arm, cell: &CellScene, standing: &[ProductBody]) -> Option<Joints> {
    let checker = Checker::new(arm, cell);
    let among = (!standing.is_empty()).then(|| {
        let mut among = checker.clone();
        among.set_products(standing);
        among
    });
    home_on(&checker, cell, among.as_ref())
}

/// [`home_among`] with the cell's checkers already built: `checker` with
/// its fixtures only (the descent it tries is a proxy for reaching down
/// to a small product, not a motion among the standing ones), `among`
/// with the standing products too, if any stand.
pub(crate) fn home_on(
    checker: &Checker,
    cell: &CellScene,
    among: Option<&Checker>,
) -> Option<Joints> {
    let top = home_tip(cell);
    let low = Point3::new(top[0], top[1], START_CHECK_HEIGHT);
    let ready = checker.arm().from_ur_convention(&READY);
    // The highest of the start heights with a free pose: a smaller arm
    // than the UR10 (a UR3e's 0.5 m reach) cannot hold its cup 0.35 m
    // over a pending area 0.37 m out, and reaches every pose the packing
    // needs there.
    let free: Vec<Joints> = START_HEIGHTS
        .iter()
        .map(|&z| {
            solutions(checker, Point3::new(top[0], top[1], z), 0.0, &ready)
                .into_iter()
                .filter(|q| checker.check(q, None, None).is_none())
                .collect::<Vec<_>>()
        })
        .find(|free| !free.is_empty())?;
    let descends = |q: &&Joints| {
        reach(checker, low, 0.0, q, Load::FREE)
            .is_some_and(|down| checker.check_motion(q, &down, None, None).is_none())
    };
    let clear = |q: &&Joints| among.is_none_or(|c| c.check(q, None, None).is_none());
    free.iter()
        .filter(clear)
        .find(descends)
        .or_else(|| free.iter().find(clear))
        .or_else(|| free.iter().find(descends))
        .or(free.first())
        .copied()
}

/// The usual UR "ready" pose: where the start pose's inverse kinematics
/// looks first.
pub(crate) const READY: Joints = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];

/// The heights (m) over the table the start pose's cup tip is tried at,
/// highest first: [`HOME_HEIGHT`], then lower for an arm that cannot reach
/// that high over the pending area.
pub const START_HEIGHTS: [f64; 4] = [HOME_HEIGHT, 0.30, 0.25, 0.20];

/// How low over the table [`home`] checks that the arm can go straight
/// down from its start (a hover over a small product).
pub const START_CHECK_HEIGHT: f64 = 0.12;

#[cfg(test)]
#[path = "station_tests.rs"]
mod tests;
