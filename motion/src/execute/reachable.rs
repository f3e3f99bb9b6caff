//! Whether the expert can reach every pose of a pick and place before
//! anything moves: the same sub-goals ([`expert::picking`],
//! [`expert::placing`]), the same inverse kinematics and collision check
//! against the cell's fixtures, the same raised release and carrying
//! points ([`Station::solve`](super::station::Station::solve)) as
//! `execute`, and
//! the straight moves between them (the descent to the top face, the lift
//! carrying the product, lowered where it must be, the descent into the
//! slot). What it does not know: the carrying motions (lift to approach
//! to above the slot: a swing or a search); `execute` reports those. The
//! products standing in the cell are not obstacles unless given
//! ([`Reachability::among`]: then the same questions tell what they block,
//! a start pose or a pick the empty cell allows).

use super::station::{
    LIFT_VIAS, Load, MAX_CARRY_RAISES, MAX_RAISES, MIN_LIFT, READY, home_on, home_tip, lowerings,
    raises, reach, solutions, swings, tip_line,
};
use crate::collision::{Checker, Held, ProductBody};
use crate::expert::{self, SubGoal};
use crate::rrt::{self, Query, RrtConfig};
use nalgebra::{Point3, Vector3};
use packwright_interface::outcome::{Hit, Stage};
use packwright_interface::scene::{CellScene, SlotSpec};
use packwright_interface::world::Body;
use packwright_kinematics::{Arm, Joints};

/// The most any joint may turn on a straight descent or lift between two
/// solutions of the same arm shape (rad); solutions further apart belong
/// to another shape, and the straight motion between them is no descent.
pub const MAX_DESCENT_TURN: f64 = 1.0;

/// A sub-goal no inverse-kinematics solution reaches free of the cell's
/// fixtures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unreached {
    pub stage: Stage,
    /// From 1, as in [`Failure::Unreachable`](packwright_interface::outcome::Failure).
    pub subgoal: usize,
    pub tip: [f64; 3],
    /// A pick reached in the empty cell but not with the product itself
    /// standing there: with the cup on its top face, a link (wrist 3 over
    /// a cup shorter than the wrist is wide) or the cup's own body meets
    /// it.
    pub meets_itself: bool,
}

/// How the expert lets a product go in a slot it reaches.
#[derive(Debug, Clone, PartialEq)]
pub struct Release {
    /// How far (m) above the box's floor the product's bottom is when it
    /// is let go ([`expert::RELEASE_GAP`], or more where the release is
    /// raised): the drop it falls.
    pub drop: f64,
    /// Where the release is raised: what the arm or the held product
    /// meets at the release's own height.
    pub lower: Option<Hit>,
}

/// A slot from over which the arm finds no way to a pick's hover
/// ([`Reachability::way_to_hover`]).
#[derive(Debug, Clone, PartialEq)]
pub struct NoWay {
    /// The slot (an index into the cell's) the arm started over; `None`:
    /// the start pose.
    pub from: Option<usize>,
    /// The standing product the straight motion meets, if it meets one.
    pub by: Option<String>,
}

/// The reach of one arm in one cell.
#[derive(Clone)]
pub struct Reachability {
    checker: Checker,
    cell: CellScene,
    /// The start pose ([`home`]), if the arm has one in this cell.
    start: Option<Joints>,
    /// Where the inverse kinematics starts (matters for arms without a
    /// closed-form solution): the start pose, or the UR "ready" pose.
    near: Joints,
}

impl Reachability {
    pub fn new(arm: &Arm, cell: &CellScene) -> Reachability {
        let checker = Checker::new(arm, cell);
        let start = home_on(&checker, cell, None);
        Reachability {
            checker,
            cell: cell.clone(),
            start,
            near: start.unwrap_or(arm.from_ur_convention(&READY)),
        }
    }

    /// The same reach with `standing` products where they stand (the
    /// start pose chosen clear of them where a branch is, as `execute`
    /// chooses it).
    pub fn among(&self, standing: &[ProductBody]) -> Reachability {
        let mut checker = self.checker.clone();
        checker.set_products(standing);
        let start = home_on(&self.checker, &self.cell, Some(&checker));
        Reachability {
            checker,
            cell: self.cell.clone(),
            start,
            near: start.unwrap_or(self.checker.arm().from_ur_convention(&READY)),
        }
    }

    /// The standing product the start pose meets, if it meets one (no
    /// free branch of it is clear of them all).
    pub fn start_blocked_by(&self) -> Option<String> {
        let start = self.start?;
        product_hit(self.checker.check(&start, None, None))
    }

    /// The standing product that the nearest solution of `tip` (cup
    /// down) meets, of those clear of the fixtures: what blocks a pose
    /// [`picking`](Self::picking) found unreached among standing products.
    pub fn blocked_by(&self, tip: [f64; 3]) -> Option<String> {
        solutions(&self.checker, Point3::from(tip), 0.0, &self.near)
            .iter()
            .find_map(|q| product_hit(self.checker.check(q, None, None)))
    }

    /// The start pose, or where its cup tip would be ([`home`]: over the
    /// middle of the pending area) when no free solution reaches it.
    pub fn start(&self) -> Result<Joints, [f64; 3]> {
        self.start.ok_or_else(|| home_tip(&self.cell))
    }

    /// The free solutions of `goal` at the first of `heights` that has any
    /// (the release may be raised), reached by a straight joint motion from
    /// one of `from` when given (the descents and the lift, which the
    /// expert moves straight; only from solutions of the same arm shape,
    /// no joint turning more than [`MAX_DESCENT_TURN`]).
    fn step(
        &self,
        goal: &SubGoal,
        heights: &[f64],
        from: Option<&[Joints]>,
        load: Load,
    ) -> Vec<Joints> {
        self.step_on(&self.checker, goal, heights, from, load)
    }

    /// [`Reachability::step`] with `checker`'s bodies.
    fn step_on(
        &self,
        checker: &Checker,
        goal: &SubGoal,
        heights: &[f64],
        from: Option<&[Joints]>,
        load: Load,
    ) -> Vec<Joints> {
        let joined = |q: &Joints| {
            from.is_none_or(|from| {
                from.iter().any(|p| {
                    p.iter()
                        .zip(q)
                        .all(|(a, b)| (a - b).abs() <= MAX_DESCENT_TURN)
                        && checker.check_motion(p, q, load.held, load.ignore).is_none()
                })
            })
        };
        heights
            .iter()
            .map(|z| {
                let tip = Point3::new(goal.tip[0], goal.tip[1], *z);
                solutions(checker, tip, 0.0, &self.near)
                    .into_iter()
                    .filter(|q| checker.check(q, load.held, load.ignore).is_none())
                    .filter(|q| joined(q))
                    .collect::<Vec<_>>()
            })
            .find(|reached| !reached.is_empty())
            .unwrap_or_default()
    }

    fn picking_goals(&self, size: [f64; 3], at: [f64; 2]) -> [SubGoal; 3] {
        expert::picking([at[0], at[1], size[2] / 2.0], size[2], self.cell.lift)
    }

    /// The expert's placing sub-goals of a product of `size` picked at
    /// `at` into slot `slot` (`spec`).
    fn placing_goals(
        &self,
        size: [f64; 3],
        at: [f64; 2],
        slot: usize,
        spec: &SlotSpec,
    ) -> [SubGoal; 3] {
        expert::placing(
            self.picking_goals(size, at)[2].tip,
            expert::release_at(&self.cell, spec, size),
            size[2],
            expert::box_height(&self.cell, slot),
            [self.cell.base[0], self.cell.base[1]],
        )
    }

    /// Picking a product of `size` whose centre stands at `at` (on the
    /// table, square): the first sub-goal no free solution reaches (the
    /// top face and the lift: straight from a free solution of the one
    /// before).
    pub fn picking(&self, size: [f64; 3], at: [f64; 2]) -> Result<(), Unreached> {
        let mut from: Option<Vec<Joints>> = None;
        let goals = self.picking_goals(size, at);
        // The lift carries the product off the table, and may be lowered
        // down to MIN_LIFT above the top face (as `Station::solve` does).
        let gripped = Held::under_cup("held", size, self.cell.suction, Vector3::zeros());
        let standing = picked_body(size, at);
        let lifting = self.checker.lifting(gripped, Some(&standing));
        let lowered: Vec<f64> = std::iter::once(goals[2].tip[2])
            .chain(lowerings(goals[2].tip[2], MAX_RAISES))
            .take_while(|z| *z >= goals[1].tip[2] + MIN_LIFT)
            .collect();
        // The product stands where it is picked, as in `execute`: the cup
        // may touch its top face, nothing else may meet it.
        let itself = self.checker.with_product(&standing);
        let touching = Load::picking(&standing.name);
        for (k, goal) in goals.iter().enumerate() {
            let reached = match k {
                2 => self.lift(goal, &lowered, from.as_deref().unwrap_or(&[]), &lifting),
                _ => self.step_on(&itself, goal, &[goal.tip[2]], from.as_deref(), touching),
            };
            if reached.is_empty() {
                let meets_itself = k < 2
                    && !self
                        .step(goal, &[goal.tip[2]], from.as_deref(), Load::FREE)
                        .is_empty();
                return Err(Unreached {
                    stage: Stage::Picking,
                    subgoal: k + 1,
                    tip: goal.tip,
                    meets_itself,
                });
            }
            from = Some(reached);
        }
        Ok(())
    }

    /// Whether the arm, in its start pose or empty-handed over each slot
    /// as it is once it has backed up from a release there (the point
    /// above the slot, as the expert carries a product of `size` there),
    /// still finds a way to the hover above that product standing at
    /// `at` once the `standing` products stand too. Asked only from where
    /// the empty cell has an easy way (straight to one of the hover's free
    /// solutions, or swung there: the base turned alone first or last,
    /// as `Station::route` tries before it searches); then the way among
    /// them is that, else RRT-Connect with its usual budget to each of the
    /// hover's free solutions, as `execute` searches. The first place it
    /// finds none from; `None` also where the hover itself is not reached
    /// ([`Reachability::picking`] tells that).
    pub fn way_to_hover(
        &self,
        standing: &[ProductBody],
        size: [f64; 3],
        at: [f64; 2],
    ) -> Option<NoWay> {
        let goals = self.picking_goals(size, at);
        let picked = picked_body(size, at);
        let among = self.among(standing);
        let (empty, full) = (
            self.checker.with_product(&picked),
            among.checker.with_product(&picked),
        );
        let touching = Load::picking(&picked.name);
        let hovers = self.step_on(&full, &goals[0], &[goals[0].tip[2]], None, touching);
        if hovers.is_empty() {
            return None;
        }
        // Straight or swung from `start` to `hover` with `checker`'s bodies.
        let easy = |checker: &Checker, start: &Joints, hover: &Joints| {
            let clear = |a: &Joints, b: &Joints| {
                checker
                    .check_motion(a, b, touching.held, touching.ignore)
                    .is_none()
            };
            clear(start, hover)
                || swings(*start, *hover).iter().any(|via| {
                    self.checker.arm().within_limits(via)
                        && checker.check(via, touching.held, touching.ignore).is_none()
                        && clear(start, via)
                        && clear(via, hover)
                })
        };
        let query = Query {
            checker: &full,
            limits: &self.checker.arm().limits,
            held: touching.held,
            ignore: touching.ignore,
        };
        // The point above each slot: the first solution free among the
        // products, nearest the start pose's shape.
        let above = |slot: usize, spec| {
            let tip = self.placing_goals(size, at, slot, spec)[1].tip;
            solutions(&self.checker, Point3::from(tip), 0.0, &self.near)
                .into_iter()
                .find(|q| full.check(q, None, None).is_none())
        };
        let starts = std::iter::once((None, among.start)).chain(
            self.cell
                .slots
                .iter()
                .enumerate()
                .map(|(slot, spec)| (Some(slot), above(slot, spec))),
        );
        starts.into_iter().find_map(|(from, start)| {
            let start = start.filter(|q| full.check(q, None, None).is_none())?;
            // A way only a search finds in the empty cell is not asked:
            // what fails there is not the products' doing.
            let eased = hovers.iter().find(|h| easy(&empty, &start, h))?;
            if hovers.iter().any(|h| easy(&full, &start, h)) {
                return None;
            }
            if hovers
                .iter()
                .any(|h| rrt::search(&query, start, *h, &RrtConfig::default()).is_some())
            {
                return None;
            }
            let by = product_hit(full.check_motion(&start, eased, touching.held, touching.ignore))
                .filter(|name| *name != picked.name);
            Some(NoWay { from, by })
        })
    }

    /// The lift's free solutions, as [`Station::solve`](super::station::Station::solve)
    /// finds them: at the first of `heights` (full, then lowered) joined
    /// straight from one of `from`, a lowered one only where the product
    /// carried on from there is free; else at full height up the cup
    /// tip's line from one of `from`.
    fn lift(&self, goal: &SubGoal, heights: &[f64], from: &[Joints], held: &Held) -> Vec<Joints> {
        let load = Load::holding(held);
        let clear = |q: &Joints| self.checker.clear_to_carry(q, held, None);
        let full = self.step(goal, &heights[..heights.len().min(1)], Some(from), load);
        if !full.is_empty() {
            return full;
        }
        let lowered = heights.iter().skip(1).find_map(|z| {
            let free: Vec<Joints> = self
                .step(goal, &[*z], Some(from), load)
                .into_iter()
                .filter(clear)
                .collect();
            (!free.is_empty()).then_some(free)
        });
        if let Some(lowered) = lowered {
            return lowered;
        }
        let Some(z) = heights.first() else {
            return Vec::new();
        };
        from.iter()
            .filter_map(|p| self.up_the_line(p, [goal.tip[0], goal.tip[1], *z], load))
            .collect()
    }

    /// The end of the way from `from` up the cup tip's straight line to
    /// `to`, through [`LIFT_VIAS`] via points each joined straight to the
    /// one before, when every segment is free.
    fn up_the_line(&self, from: &Joints, to: [f64; 3], load: Load) -> Option<Joints> {
        let a: [f64; 3] = self
            .checker
            .arm()
            .tool_tip(self.checker.base(), from, self.cell.suction)
            .into();
        let mut points = tip_line(&self.checker, *from, a, to, LIFT_VIAS, 0.0, load)?;
        let last = points.last().unwrap_or(from);
        points.push(reach(&self.checker, Point3::from(to), 0.0, last, load)?);
        let mut before = *from;
        for q in &points {
            let free = q
                .iter()
                .zip(&before)
                .all(|(a, b)| (a - b).abs() <= MAX_DESCENT_TURN)
                && self
                    .checker
                    .check_motion(&before, q, load.held, load.ignore)
                    .is_none();
            if !free {
                return None;
            }
            before = *q;
        }
        Some(before)
    }

    /// Placing it, picked at `at`, in slot `slot`: the first sub-goal no
    /// free solution reaches (the release: straight down from a free
    /// solution above the slot, at some height up to that point's, for the
    /// product then drops the rest; the approach and the point above the
    /// slot are joined by a swing or a search, not checked here). When
    /// every sub-goal is reached: how the product is let go.
    pub fn placing(&self, size: [f64; 3], at: [f64; 2], slot: usize) -> Result<Release, Unreached> {
        let Some(spec) = self.cell.slots.get(slot) else {
            return Err(Unreached {
                stage: Stage::Placing,
                subgoal: 2,
                tip: [f64::NAN; 3],
                meets_itself: false,
            });
        };
        let goals = self.placing_goals(size, at, slot, spec);
        let held = Held::under_cup("held", size, self.cell.suction, Vector3::zeros());
        let load = Load::holding(&held);
        // Down into the slot, padded as the room beside it allows.
        let slot_at = expert::release_at(&self.cell, spec, size);
        let lowered =
            self.checker
                .lowering(held.clone(), expert::released_centre(slot_at, size[2]), 0.0);
        let lowering = Load::holding(&lowered);
        let ceiling = goals[1].tip[2];
        let raised: Vec<f64> = std::iter::once(goals[2].tip[2])
            .chain(raises(goals[2].tip[2], MAX_RAISES))
            .take_while(|z| *z <= ceiling)
            .collect();
        // The approach and the point above the slot are raised where every
        // arm pose collides, as `Station::solve` raises them.
        let carried = |goal: &SubGoal| -> Vec<f64> {
            std::iter::once(goal.tip[2])
                .chain(raises(goal.tip[2], MAX_CARRY_RAISES))
                .collect()
        };
        let mut above = Vec::new();
        let mut release = Release {
            drop: expert::RELEASE_GAP,
            lower: None,
        };
        for (k, goal) in goals.iter().enumerate() {
            let reached = match k {
                2 => raised
                    .iter()
                    .find_map(|&z| {
                        let free = self.step(goal, &[z], Some(&above), lowering);
                        (!free.is_empty()).then_some((z, free))
                    })
                    .map(|(z, free)| {
                        let raise = z - goal.tip[2];
                        release.drop = expert::RELEASE_GAP + raise;
                        if raise > 1e-9 {
                            release.lower = self.met_at(goal, &above, lowering);
                        }
                        free
                    })
                    .unwrap_or_default(),
                _ => self.step(goal, &carried(goal), None, load),
            };
            if reached.is_empty() {
                return Err(Unreached {
                    stage: Stage::Placing,
                    subgoal: k + 1,
                    tip: goal.tip,
                    meets_itself: false,
                });
            }
            above = reached;
        }
        Ok(release)
    }

    /// What the arm or the held product meets at `goal` itself: in the
    /// nearest solution's pose, else on its straight motion from one of
    /// `from`.
    fn met_at(&self, goal: &SubGoal, from: &[Joints], load: Load) -> Option<Hit> {
        let tip = Point3::new(goal.tip[0], goal.tip[1], goal.tip[2]);
        solutions(&self.checker, tip, 0.0, &self.near)
            .iter()
            .find_map(|q| {
                self.checker.check(q, load.held, load.ignore).or_else(|| {
                    from.iter()
                        .find_map(|p| self.checker.check_motion(p, q, load.held, load.ignore))
                })
            })
    }
}

/// A product of `size` standing at `at` (on the table, square), as the
/// one being picked: named `held`, as the cup will hold it.
fn picked_body(size: [f64; 3], at: [f64; 2]) -> ProductBody {
    ProductBody {
        name: "held".to_owned(),
        centre: [at[0], at[1], size[2] / 2.0],
        size,
        yaw: 0.0,
    }
}

/// The standing product a hit names, if it names one.
fn product_hit(hit: Option<Hit>) -> Option<String> {
    match hit? {
        Hit::Bodies {
            b: Body::Product(name),
            ..
        } => Some(name),
        _ => None,
    }
}
