//! Phase 3b: what the robot can reach. The compiler knows no kinematics:
//! it asks a [`Workspace`] (the robot half implements it, see
//! `packwright_pipeline::reach`) whether every pose of picking a product
//! where it stands, and of placing it in a slot, can be reached, and turns
//! each "no" into an [`Error::Unreachable`] at the statement that asked
//! for it. Runs only on a model the geometric checks passed.
//!
//! What is asked: every (product, slot) pair an order, a demo's or
//! scenario's moved product, or a `choose` allows, picked from where that
//! product stands and placed in that slot (a product nothing packs is not
//! asked about). Each distinct question is asked
//! once and reported once. Jitter is not sampled: the nominal positions
//! are checked.
//!
//! Then what the products standing in the cell block (every product of
//! an inventory stands at its entry when a package starts): a start pose
//! none of whose branches clears them is an [`Error::StartBlocked`] (every
//! package would fail at its first motion); a pick the empty cell allows
//! and the inventory's other products block is a
//! [`Warning::PickBlocked`], and a placing (of a product picked at its
//! written place) a [`Warning::PlaceBlocked`], since whether they still
//! stand depends on the order packed (each of them anywhere the blocks' `jitter` may put
//! it: its footprint widened by the largest).

use crate::error::{Error, Moved, REACH_PROBE};
use crate::model::{Choose, Entry, Inventory, Model, Placed, RobotModel};
use crate::source::Loc;
use crate::warning::Warning;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

/// A pose the robot needs: where it starts, and the six poses of a pick
/// and place (README, "The robot world"): three of picking, three of
/// placing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Pose {
    /// The start: the cup over the middle of the pending area.
    Start,
    /// Above the product, before the descent.
    Hover,
    /// The hover reached from the start pose: the motion there, not the
    /// pose.
    HoverFromStart,
    /// The hover reached from over the box (where the arm is once it has
    /// let the product before go): the motion there, not the pose.
    HoverFromBox,
    /// The cup on the product's top face (suction on).
    TopFace,
    /// The product lifted by the cell's `lift`.
    Lift,
    /// The carrying point between the product and the slot.
    Approach,
    /// Above the slot, the product clear of the box's rim.
    AboveSlot,
    /// The product just above the box floor (suction off), or as high as
    /// the release may be raised.
    Release,
}

impl Pose {
    /// Whether the pose belongs to picking (depends on the product's place
    /// only, not on the slot).
    pub fn is_picking(self) -> bool {
        // (The start is not: it is the cell's.)
        matches!(
            self,
            Pose::Hover | Pose::HoverFromStart | Pose::HoverFromBox | Pose::TopFace | Pose::Lift
        )
    }
}

impl fmt::Display for Pose {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Pose::Start => "its start pose over the middle of the pending area",
            Pose::Hover => "the hover above the product",
            Pose::HoverFromStart => "the hover above the product from the start pose",
            Pose::HoverFromBox => "the hover above the product from over the box",
            Pose::TopFace => "the product's top face",
            Pose::Lift => "the lift",
            Pose::Approach => "the approach point",
            Pose::AboveSlot => "the point above the slot",
            Pose::Release => "the release in the slot",
        })
    }
}

/// What the robot was doing when a pose was out of reach.
#[derive(Debug, Clone, PartialEq)]
pub enum Task {
    /// Starting in cell `cell`.
    Start { cell: String },
    /// Picking `product`, its centre at `position`.
    Pick { product: String, position: [f64; 2] },
    /// Putting `product`, picked at `position`, in `slot`.
    Place {
        product: String,
        position: [f64; 2],
        slot: String,
    },
}

impl fmt::Display for Task {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Task::Start { cell } => write!(f, "in cell `{cell}`"),
            Task::Pick { product, position } => write!(
                f,
                "when it picks product `{product}` at ({:.3}, {:.3})",
                position[0], position[1]
            ),
            Task::Place {
                product,
                position,
                slot,
            } => write!(
                f,
                "when it puts product `{product}` (picked at ({:.3}, {:.3})) in slot `{slot}`",
                position[0], position[1]
            ),
        }
    }
}

/// A pose the robot cannot reach: which, and where the tool tip would be
/// (world frame, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unreached {
    pub pose: Pose,
    pub tip: [f64; 3],
    /// A pick the empty cell allows that the product itself blocks: with
    /// the cup on its top face the wrist (over a short cup) meets it.
    pub meets_itself: bool,
}

/// What the robot does at a release it reaches, where it can tell: how
/// far (m) above its box's floor the product's bottom is when it is let
/// go (the drop it falls; the expert's 5 mm, or more where the arm cannot
/// go lower), and what stops it lower.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Released {
    pub drop: Option<f64>,
    pub lower: Option<Lower>,
}

/// What meets the box where a release is let go lower.
#[derive(Debug, Clone, PartialEq)]
pub enum Lower {
    /// The held product, padded, meets the box (a wall it stands too
    /// near).
    ProductOnBox,
    /// A part of the arm (a link by name, or the cup) meets the box.
    ArmOnBox(String),
    /// Something else, as the robot names it.
    Other(String),
}

/// A product standing in the cell when a package starts: an inventory
/// entry's product (an index into `Model::products`) at its place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Standing {
    pub product: usize,
    pub at: [f64; 2],
    /// How far (m, along x and along y) it may stand from `at` (the
    /// largest `jitter` of the blocks that generate from its inventory):
    /// its footprint is widened by it on every side.
    pub margin: f64,
}

/// A pose the empty cell allows and standing products block: which pose,
/// and the product met (an index into the `standing` asked about), where
/// the robot can tell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blocked {
    pub pose: Pose,
    pub by: Option<usize>,
}

/// The robot's answers. Implementations must be deterministic.
pub trait Workspace {
    /// Why the robot description cell `cell` names cannot be used (a
    /// URDF that is not one 6-axis chain, a collision mesh that cannot be
    /// read), if it cannot; then nothing else is asked about the cell.
    /// Without an answer (the default), every description is usable.
    fn robot(&self, _m: &Model, _cell: usize) -> Option<String> {
        None
    }

    /// The start pose of cell `cell`, if it cannot be reached.
    fn start(&self, m: &Model, cell: usize) -> Option<Unreached>;

    /// Picking product `product` (an index into `m.products`) whose centre
    /// stands at `at` in cell `cell`: the first pose that cannot be
    /// reached, if any.
    fn pick(&self, m: &Model, cell: usize, product: usize, at: [f64; 2]) -> Option<Unreached>;

    /// Placing it, picked at `at`, into slot `slot` of the (empty) cell:
    /// the first placing pose (approach, above the slot, release) that
    /// cannot be reached, else how the product is let go.
    fn place(
        &self,
        m: &Model,
        cell: usize,
        product: usize,
        at: [f64; 2],
        slot: usize,
    ) -> Result<Released, Unreached>;

    /// The start pose of cell `cell` (which the empty cell reaches) with
    /// `standing` products where they stand: the one every branch of it
    /// meets (an index into `standing`), if one is. Without an answer
    /// (the default), nothing is blocked.
    fn start_among(&self, _m: &Model, _cell: usize, _standing: &[Standing]) -> Option<usize> {
        None
    }

    /// Picking `product` at `at` (which the empty cell allows) with the
    /// `standing` products (not it) where they stand: the first pose they
    /// block, if any. Without an answer (the default), nothing is blocked.
    fn pick_among(
        &self,
        _m: &Model,
        _cell: usize,
        _product: usize,
        _at: [f64; 2],
        _standing: &[Standing],
    ) -> Option<Blocked> {
        None
    }

    /// The motion to the hover of `product` at `at` (whose poses the
    /// `standing` products leave free) from the start pose or from over
    /// the box, which the empty cell allows: blocked by them
    /// ([`Pose::HoverFromStart`], [`Pose::HoverFromBox`]) with the product
    /// met, if it is. Asked of an inventory's places only (a search where
    /// they block it; not of each drawn case). Without an answer (the
    /// default), nothing is blocked.
    fn pick_way_among(
        &self,
        _m: &Model,
        _cell: usize,
        _product: usize,
        _at: [f64; 2],
        _standing: &[Standing],
    ) -> Option<Blocked> {
        None
    }

    /// Placing `product`, picked at `at`, into slot `slot` (which the
    /// empty cell allows) with the `standing` products (not it) where
    /// they stand: the first placing pose they block, if any. Without an
    /// answer (the default), nothing is blocked.
    fn place_among(
        &self,
        _m: &Model,
        _cell: usize,
        _product: usize,
        _at: [f64; 2],
        _slot: usize,
        _standing: &[Standing],
    ) -> Option<Blocked> {
        None
    }
}

/// `at` moved `by` (m) along the line from the base axis at `base`: away
/// from it where `by` is positive. `None` on the axis itself.
pub fn along_from_base(base: [f64; 3], at: [f64; 2], by: f64) -> Option<[f64; 2]> {
    let (dx, dy) = (at[0] - base[0], at[1] - base[1]);
    let d = dx.hypot(dy);
    (d > 1e-9).then(|| [at[0] + by * dx / d, at[1] + by * dy / d])
}

/// A workspace that reaches everything: for tools that have no robot model
/// (formatting, the compiler's own tests and benchmarks). Every command
/// that executes or trains uses the robot's.
pub struct Anywhere;

impl Workspace for Anywhere {
    fn start(&self, _: &Model, _: usize) -> Option<Unreached> {
        None
    }

    fn pick(&self, _: &Model, _: usize, _: usize, _: [f64; 2]) -> Option<Unreached> {
        None
    }

    fn place(
        &self,
        _: &Model,
        _: usize,
        _: usize,
        _: [f64; 2],
        _: usize,
    ) -> Result<Released, Unreached> {
        Ok(Released::default())
    }
}

/// How many times its narrow side a product may stand tall, and fall,
/// before a drop can tip it over: a product over twice as tall as it is
/// wide, let go more than twice its width above the floor, can land
/// tilted and fall over (README, W004).
pub const TOPPLE_RATIO: f64 = 2.0;

/// Whether a product `height` tall on a narrow side `side`, let go `drop`
/// above the floor, can fall over ([`TOPPLE_RATIO`]).
pub fn topples(height: f64, side: f64, drop: f64) -> bool {
    height > TOPPLE_RATIO * side && drop > TOPPLE_RATIO * side
}

/// A product's highest drop into a box: the drop (m), what stops it
/// lower, the slot and the statement that asked for it.
type Dropped = (f64, Option<Lower>, usize, Loc);

/// A product's place, as bits, so that each question is asked once.
type Place = (usize, usize, [u64; 2]);

/// A placing the empty cell allows: (inventory, entry, slot, what asked
/// for it).
type Reached = (usize, usize, usize, Loc);

/// A placing blocked by standing products: (entry placed, pose, entry
/// met).
type Met = (usize, Pose, Option<usize>);

struct Asker<'a> {
    m: &'a Model,
    ws: &'a dyn Workspace,
    /// Picking questions asked, and whether every pose was reached.
    picked: BTreeMap<Place, bool>,
    placed: BTreeSet<(Place, usize)>,
    /// Placings the empty cell allows of a product picked at its
    /// entry's written place: (inventory, entry, slot, what asked).
    reached: Vec<Reached>,
    /// The highest drop per (cell, product, box).
    drops: BTreeMap<(usize, usize, usize), Dropped>,
    errors: Vec<Error>,
}

impl Asker<'_> {
    /// Whether product `entry` can be picked at `at` (asked once).
    fn pick(&mut self, inv: &Inventory, entry: usize, at: [f64; 2], loc: Loc) -> bool {
        let product = inv.entries[entry].product;
        let place = (inv.cell, product, at.map(f64::to_bits));
        if let Some(&reached) = self.picked.get(&place) {
            return reached;
        }
        let unreached = self.ws.pick(self.m, inv.cell, product, at);
        if let Some(u) = unreached {
            let reached_moved = self.reached_moved(inv.cell, product, at);
            self.errors.push(Error::Unreachable {
                at: loc,
                task: Task::Pick {
                    product: self.m.products[product].name.clone(),
                    position: at,
                },
                pose: u.pose,
                tip: u.tip,
                meets_itself: u.meets_itself,
                reached_moved,
            });
        }
        self.picked.insert(place, unreached.is_none());
        unreached.is_none()
    }

    /// The way [`REACH_PROBE`] along the line from the cell's base axis
    /// that `product`, unreachable at `at`, would be picked, where only
    /// one way is.
    fn reached_moved(&self, cell: usize, product: usize, at: [f64; 2]) -> Option<Moved> {
        let base = self.m.cells.get(cell)?.base;
        let reached = |by: f64| {
            along_from_base(base, at, by)
                .is_some_and(|moved| self.ws.pick(self.m, cell, product, moved).is_none())
        };
        match (reached(REACH_PROBE), reached(-REACH_PROBE)) {
            (true, false) => Some(Moved::Away),
            (false, true) => Some(Moved::Nearer),
            _ => None,
        }
    }

    /// Placing is asked once its picking was reached (the placing poses
    /// start from the lift).
    /// A picking failure is reported at `at_loc` (where the product's
    /// place is written), a placing one at `loc` (what asked for the slot).
    fn place(&mut self, i: usize, entry: usize, at: ([f64; 2], Loc), slot: usize, loc: Loc) {
        let m = self.m;
        let inv = &m.inventories[i];
        let (at, at_loc) = at;
        if !self.pick(inv, entry, at, at_loc) {
            return;
        }
        let product = inv.entries[entry].product;
        let place = (inv.cell, product, at.map(f64::to_bits));
        if !self.placed.insert((place, slot)) {
            return;
        }
        let placed = self.ws.place(self.m, inv.cell, product, at, slot);
        if placed.is_ok() && at == inv.entries[entry].at {
            self.reached.push((i, entry, slot, loc));
        }
        match placed {
            Err(u) => self.errors.push(Error::Unreachable {
                at: loc,
                task: Task::Place {
                    product: self.m.products[product].name.clone(),
                    position: at,
                    slot: self.m.cells[inv.cell].slots[slot].name.clone(),
                },
                pose: u.pose,
                tip: u.tip,
                meets_itself: u.meets_itself,
                reached_moved: None,
            }),
            Ok(Released {
                drop: Some(drop),
                lower,
            }) => {
                let Some(s) = self.m.cells[inv.cell].slots.get(slot) else {
                    return;
                };
                let key = (inv.cell, product, s.box_index);
                if self.drops.get(&key).is_none_or(|highest| drop > highest.0) {
                    self.drops.insert(key, (drop, lower, slot, loc));
                }
            }
            Ok(Released { drop: None, .. }) => {}
        }
    }

    /// [`Warning::DroppedHigh`] for each product dropped too far for its
    /// shape ([`topples`]), once per box: its highest drop.
    fn dropped_high(&self) -> Vec<Warning> {
        self.drops
            .iter()
            .filter_map(|(&(cell, product, _), (drop, lower, slot, at))| {
                let (drop, slot, at) = (*drop, *slot, *at);
                let p = &self.m.products[product];
                let c = &self.m.cells[cell];
                let s = c.slots.get(slot)?;
                let side = p.size[0].min(p.size[1]);
                topples(p.size[2], side, drop).then(|| Warning::DroppedHigh {
                    at,
                    product: p.name.clone(),
                    product_at: p.loc,
                    slot: s.name.clone(),
                    in_box: c
                        .boxes
                        .get(s.box_index)
                        .map(|b| b.name.clone())
                        .unwrap_or_default(),
                    drop_mm: drop * 1000.0,
                    height_mm: p.size[2] * 1000.0,
                    side_mm: side * 1000.0,
                    lower: lower.clone(),
                })
            })
            .collect()
    }

    fn moved(&mut self, order: usize, placed: &[Placed]) {
        let i = self.m.orders[order].inventory;
        for p in placed {
            let slot = self.m.orders[order]
                .assignment
                .iter()
                .find(|a| a.entry == p.entry)
                .map(|a| a.slot);
            if let Some(slot) = slot {
                self.place(i, p.entry, (p.at, p.loc), slot, p.loc);
            }
        }
    }

    fn choose(&mut self, i: usize, c: &Choose) {
        let m = self.m;
        for &e in &c.entries {
            for &s in &c.slots {
                let entry = &m.inventories[i].entries[e];
                self.place(i, e, (entry.at, entry.loc), s, c.loc);
            }
        }
    }
}

/// Every pose the model's orders, demonstrations and scenarios need,
/// asked of `ws`: one error per unreachable question; then what the
/// products standing in each cell block (errors for a start, warnings for
/// a pick).
pub fn check(m: &Model, ws: &dyn Workspace) -> (Vec<Error>, Vec<Warning>) {
    let mut a = Asker {
        m,
        ws,
        picked: BTreeMap::new(),
        placed: BTreeSet::new(),
        reached: Vec::new(),
        drops: BTreeMap::new(),
        errors: Vec::new(),
    };
    // The cells whose start the empty cell reaches.
    let mut started = BTreeSet::new();
    for (i, cell) in m.cells.iter().enumerate() {
        if let (RobotModel::Urdf(path), Some(reason)) = (&cell.robot, ws.robot(m, i)) {
            a.errors.push(Error::RobotUnusable {
                at: cell.robot_at,
                path: path.clone(),
                reason,
            });
        } else if let Some(u) = ws.start(m, i) {
            a.errors.push(Error::Unreachable {
                at: cell.loc,
                task: Task::Start {
                    cell: cell.name.clone(),
                },
                pose: u.pose,
                tip: u.tip,
                meets_itself: u.meets_itself,
                reached_moved: None,
            });
        } else {
            started.insert(i);
        }
    }
    for order in &m.orders {
        let inv = &m.inventories[order.inventory];
        for asg in &order.assignment {
            let entry = &inv.entries[asg.entry];
            a.place(
                order.inventory,
                asg.entry,
                (entry.at, entry.loc),
                asg.slot,
                asg.loc,
            );
        }
    }
    for demo in &m.demos {
        a.moved(demo.order, &demo.at);
    }
    for sc in &m.scenarios {
        a.moved(sc.order, &sc.at);
    }
    for d in &m.demo_sets {
        a.choose(d.inventory, &d.choose);
    }
    for s in &m.scenario_sets {
        a.choose(s.inventory, &s.choose);
    }
    let mut warnings = a.dropped_high();
    for i in 0..m.inventories.len() {
        let cell = m.inventories[i].cell;
        let stand = standing_in(m, i);
        standing(
            m,
            ws,
            &stand,
            started.contains(&cell),
            &a.picked,
            &mut a.errors,
            &mut warnings,
        );
        place_standing(m, ws, &stand, &a.reached, &a.picked, &mut warnings);
    }
    (a.errors, warnings)
}

/// An inventory's products as they stand when a package starts.
struct Stand {
    /// The inventory (an index into `Model::inventories`).
    i: usize,
    /// Each at its entry.
    at_start: Vec<Standing>,
    /// Each anywhere the blocks that generate from the inventory may draw
    /// it (its footprint widened by their largest `jitter`).
    all: Vec<Standing>,
    /// That jitter (m, each axis).
    jitter: f64,
}

impl Stand {
    /// The products other than entry `k`, each widened by `margin`, and
    /// their entries' indices.
    fn others(&self, k: usize, margin: f64) -> (Vec<Standing>, Vec<usize>) {
        self.all
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != k)
            .map(|(j, s)| (Standing { margin, ..*s }, j))
            .unzip()
    }
}

/// Whether `entry`'s pick in cell `cell` was asked and every pose of it
/// reached.
fn pick_reached(picked: &BTreeMap<Place, bool>, cell: usize, entry: &Entry) -> bool {
    picked.get(&(cell, entry.product, entry.at.map(f64::to_bits))) == Some(&true)
}

/// Inventory `i`'s products standing when a package starts ([`Stand`]).
fn standing_in(m: &Model, i: usize) -> Stand {
    let at_start: Vec<Standing> = m.inventories[i]
        .entries
        .iter()
        .map(|e| Standing {
            product: e.product,
            at: e.at,
            margin: 0.0,
        })
        .collect();
    let jitter = m
        .demo_sets
        .iter()
        .filter(|d| d.inventory == i)
        .map(|d| d.jitter)
        .chain(
            m.scenario_sets
                .iter()
                .filter(|s| s.inventory == i)
                .map(|s| s.jitter),
        )
        .fold(0.0, f64::max);
    let all = at_start
        .iter()
        .map(|s| Standing {
            margin: jitter,
            ..*s
        })
        .collect();
    Stand {
        i,
        at_start,
        all,
        jitter,
    }
}

/// The placings `reached` (in the empty cell) of inventory `i`'s
/// products that its other products, standing at their entries, block:
/// one [`Warning::PlaceBlocked`] per product, pose and product met, with
/// every slot where they meet so (the carry to a box past a tall product
/// standing by the arm's base blocks most slots alike).
fn place_standing(
    m: &Model,
    ws: &dyn Workspace,
    stand: &Stand,
    reached: &[Reached],
    picked: &BTreeMap<Place, bool>,
    warnings: &mut Vec<Warning>,
) {
    let (i, jitter) = (stand.i, stand.jitter);
    let inv = &m.inventories[i];
    // What first asked, and the slots, per (entry, pose, entry met).
    let mut blocked: BTreeMap<Met, (Loc, Vec<usize>)> = BTreeMap::new();
    for &(_, k, slot, loc) in reached.iter().filter(|r| r.0 == i) {
        let Some(e) = inv.entries.get(k) else {
            continue;
        };
        let (standing, index) = stand.others(k, jitter);
        if let Some(b) = ws.place_among(m, inv.cell, e.product, e.at, slot, &standing) {
            let by = b.by.and_then(|b| index.get(b).copied());
            let (_, slots) = blocked.entry((k, b.pose, by)).or_insert((loc, Vec::new()));
            if !slots.contains(&slot) {
                slots.push(slot);
            }
        }
    }
    let name = |j: usize| m.products[inv.entries[j].product].name.clone();
    let cell = &m.cells[inv.cell];
    // Pairs each standing in the way of the other's placing.
    let meets: BTreeSet<(usize, usize)> = blocked
        .keys()
        .filter_map(|&(k, _, by)| Some((k, by?)))
        .collect();
    for ((k, pose, by), (at, slots)) in blocked {
        let e = &inv.entries[k];
        let where_written = jitter <= 0.0 || {
            let (written, _) = stand.others(k, 0.0);
            ws.place_among(m, inv.cell, e.product, e.at, slots[0], &written)
                .is_some()
        };
        let met = by.map(|j| (j, &inv.entries[j]));
        warnings.push(Warning::PlaceBlocked {
            at,
            product: name(k),
            position: e.at,
            slots: slots
                .iter()
                .filter_map(|&s| cell.slots.get(s).map(|s| s.name.clone()))
                .collect(),
            pose,
            by: met.map(|(j, other)| (name(j), other.at, other.loc)),
            by_packed: met.is_some_and(|(_, o)| pick_reached(picked, inv.cell, o)),
            mutual: by.is_some_and(|j| meets.contains(&(j, k))),
            jitter_mm: jitter * 1000.0,
            where_written,
        });
    }
}

/// What inventory `i`'s products, standing at their entries, block: its
/// cell's start (if the empty cell has one: `started`), and each pick the
/// empty cell allows (`picked`: asked and reached).
fn standing(
    m: &Model,
    ws: &dyn Workspace,
    stand: &Stand,
    started: bool,
    picked: &BTreeMap<Place, bool>,
    errors: &mut Vec<Error>,
    warnings: &mut Vec<Warning>,
) {
    let (at_start, jitter) = (&stand.at_start, stand.jitter);
    let inv = &m.inventories[stand.i];
    let name = |j: usize| m.products[inv.entries[j].product].name.clone();
    if started
        && let Some(j) = ws
            .start_among(m, inv.cell, at_start)
            .filter(|&j| j < at_start.len())
    {
        errors.push(Error::StartBlocked {
            at: inv.entries[j].loc,
            cell: m.cells[inv.cell].name.clone(),
            inventory: inv.name.clone(),
            by: name(j),
        });
    }
    for (k, e) in inv.entries.iter().enumerate() {
        if !pick_reached(picked, inv.cell, e) {
            continue;
        }
        // The others, with their entries' indices.
        let (others, index) = stand.others(k, jitter);
        // The poses, then the way to the first.
        let blocked = |standing: &[Standing]| {
            ws.pick_among(m, inv.cell, e.product, e.at, standing)
                .or_else(|| ws.pick_way_among(m, inv.cell, e.product, e.at, standing))
        };
        if let Some(b) = blocked(&others) {
            let met =
                b.by.and_then(|b| index.get(b))
                    .map(|&j| (j, &inv.entries[j]));
            let by = met.map(|(j, other)| (name(j), other.at, other.loc));
            let by_packed = met.is_some_and(|(_, o)| pick_reached(picked, inv.cell, o));
            // Blocked with the others where they are written too, or only
            // where the jitter may draw them (asked again without it).
            let where_written = jitter <= 0.0 || {
                let (written, _) = stand.others(k, 0.0);
                blocked(&written).is_some()
            };
            warnings.push(Warning::PickBlocked {
                at: e.loc,
                product: name(k),
                position: e.at,
                pose: b.pose,
                by,
                by_packed,
                jitter_mm: jitter * 1000.0,
                where_written,
            });
        }
    }
}
