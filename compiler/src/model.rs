//! The resolved world: every name replaced by an index, every length in
//! metres, defaults filled in. Built by `resolve`, checked by `validate`,
//! expanded by `expand`.
//!
//! Invariants (after a clean `resolve`): every index points into the vector
//! it names; an inventory's entries are in the listed order, which is the
//! node order of every graph; slots are numbered in declaration order and a
//! slot's label is its index + 1 (label 0 is `pick`).

use crate::source::Loc;
use packwright_grammar::ast::SequenceMode;

/// Lift height when a cell gives none.
pub const DEFAULT_LIFT: f64 = 0.150;
/// The suction cup lengths a cell may declare (m, flange to cup tip).
pub const SUCTION_RANGE: (f64, f64) = (0.020, 0.300);
/// The lift heights a cell may declare (m).
pub const LIFT_RANGE: (f64, f64) = (0.020, 0.500);
/// The speeds a cell may declare, as shares of the arm's full speed.
pub const SPEED_RANGE: (f64, f64) = (0.01, 1.0);
/// How long the arm waits, still, after the suction grips a product when
/// a cell gives no `settle … after grip` (s): the vacuum builds up.
pub const DEFAULT_GRIP_SETTLE: f64 = 0.1;
/// How long the arm waits, still, after releasing a product when a cell
/// gives no `settle … after release` (s): the product drops and comes to
/// rest before the cup backs up.
pub const DEFAULT_RELEASE_SETTLE: f64 = 0.5;
/// The settle times a cell may declare (s).
pub const SETTLE_RANGE: (f64, f64) = (0.0, 5.0);
/// The descent speeds a cell may declare, as shares of its speed.
pub const DESCENT_RANGE: (f64, f64) = (0.01, 1.0);
/// How far from its base (m) any arm packs: no pending area or box of a
/// cell may reach farther, nor a box be larger (the longest industrial
/// arms reach about 4 m). A length beyond it is a typo: a unit left out
/// or the wrong one.
pub const WORKSPACE_RADIUS: f64 = 10.0;
/// How many joints the arm has: an `acceleration` or `jerk` statement
/// gives one value per joint.
pub const ARM_JOINTS: usize = 6;
/// The joint acceleration limits a cell may declare (rad/s²): bounds of
/// sense, not the arm's own (the built-in UR10's are 2.5 and 4 rad/s²).
pub const ACCELERATION_RANGE: (f64, f64) = (0.1, 40.0);
/// The joint jerk limits a cell may declare (rad/s³; the built-in UR10's
/// are 10 and 20 rad/s³).
pub const JERK_RANGE: (f64, f64) = (1.0, 2000.0);
/// UR10 reach, measured horizontally from the base axis.
pub const UR10_REACH_MIN: f64 = 0.20;
pub const UR10_REACH_MAX: f64 = 1.30;

#[derive(Debug, Clone, Default)]
pub struct Model {
    pub cells: Vec<Cell>,
    pub products: Vec<Product>,
    pub inventories: Vec<Inventory>,
    pub orders: Vec<Order>,
    pub demos: Vec<DemoDef>,
    pub demo_sets: Vec<DemosDef>,
    pub scenarios: Vec<ScenarioDef>,
    pub scenario_sets: Vec<ScenariosDef>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum RobotModel {
    Ur10,
    /// Path relative to the working directory (the cell file's folder joined
    /// with the path written).
    Urdf(String),
}

/// An axis-aligned rectangle on the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

impl Rect {
    pub fn centred(c: [f64; 2], w: f64, d: f64) -> Rect {
        Rect {
            min: [c[0] - w / 2.0, c[1] - d / 2.0],
            max: [c[0] + w / 2.0, c[1] + d / 2.0],
        }
    }

    /// How far `inner` sticks out of `self` (0 when inside), in metres.
    /// An edge on `self`'s edge is inside, up to the rounding of decimal
    /// coordinates (`0.80 + 0.05` is a hair over `0.85` in binary).
    pub fn excess(&self, inner: &Rect) -> f64 {
        const EPS: f64 = 1e-9;
        let excess = [
            self.min[0] - inner.min[0],
            self.min[1] - inner.min[1],
            inner.max[0] - self.max[0],
            inner.max[1] - self.max[1],
        ]
        .into_iter()
        .fold(0.0, f64::max);
        if excess <= EPS { 0.0 } else { excess }
    }

    /// The shortest distance between the two (0 when they touch or
    /// overlap), in metres.
    pub fn gap(&self, other: &Rect) -> f64 {
        let apart = |a: usize| {
            (other.min[a] - self.max[a])
                .max(self.min[a] - other.max[a])
                .max(0.0)
        };
        apart(0).hypot(apart(1))
    }

    /// True when the two share some area (touching edges do not count).
    pub fn overlaps(&self, other: &Rect) -> bool {
        const EPS: f64 = 1e-9;
        self.min[0] < other.max[0] - EPS
            && other.min[0] < self.max[0] - EPS
            && self.min[1] < other.max[1] - EPS
            && other.min[1] < self.max[1] - EPS
    }

    pub fn contains(&self, p: [f64; 2]) -> bool {
        p[0] >= self.min[0] && p[0] <= self.max[0] && p[1] >= self.min[1] && p[1] <= self.max[1]
    }
}

#[derive(Debug, Clone)]
pub struct Cell {
    pub name: String,
    pub loc: Loc,
    pub robot: RobotModel,
    /// Where the `robot` statement is (its path, for a URDF).
    pub robot_at: Loc,
    pub base: [f64; 3],
    pub suction: f64,
    pub pending: Rect,
    /// Where the `pending` statement is.
    pub pending_loc: Loc,
    pub lift: f64,
    /// The arm's speed as a share of its full speed (1: the robot's own
    /// limits): every motion keeps its path and takes `1 / speed` as long
    /// (velocity limits times `speed`, accelerations times its square,
    /// jerks times its cube).
    pub speed: f64,
    /// Seconds the arm waits, still, after the suction grips a product.
    pub grip_settle: f64,
    /// Seconds the arm waits, still, after the suction releases a product.
    pub release_settle: f64,
    /// The guarded descent onto a product's top face (from the hover to
    /// the contact) as a share of the cell's speed (1: no slower than
    /// every other motion).
    pub descent: f64,
    /// The arm's acceleration limits (rad/s², base first) in place of its
    /// own (the URDF's, or the built-in UR10's), before `speed` scales
    /// them; `None`: its own.
    pub acceleration: Option<[f64; ARM_JOINTS]>,
    /// The arm's jerk limits (rad/s³), as `acceleration`.
    pub jerk: Option<[f64; ARM_JOINTS]>,
    pub boxes: Vec<BoxDef>,
    pub slots: Vec<Slot>,
}

#[derive(Debug, Clone)]
pub struct BoxDef {
    pub name: String,
    pub loc: Loc,
    pub centre: [f64; 2],
    /// Width (x), depth (y), height (z).
    pub size: [f64; 3],
}

impl BoxDef {
    pub fn footprint(&self) -> Rect {
        Rect::centred(self.centre, self.size[0], self.size[1])
    }
}

#[derive(Debug, Clone)]
pub struct Slot {
    pub name: String,
    pub loc: Loc,
    pub at: [f64; 2],
    /// Index into the cell's boxes.
    pub box_index: usize,
}

#[derive(Debug, Clone)]
pub struct Product {
    pub name: String,
    pub loc: Loc,
    /// Width (x), depth (y), height (z).
    pub size: [f64; 3],
    pub mass: Option<f64>,
}

impl Product {
    pub fn footprint(&self, at: [f64; 2]) -> Rect {
        Rect::centred(at, self.size[0], self.size[1])
    }
}

#[derive(Debug, Clone)]
pub struct Inventory {
    pub name: String,
    pub loc: Loc,
    pub cell: usize,
    pub entries: Vec<Entry>,
}

#[derive(Debug, Clone)]
pub struct Entry {
    pub product: usize,
    pub at: [f64; 2],
    pub loc: Loc,
}

#[derive(Debug, Clone)]
pub struct Order {
    pub name: String,
    pub loc: Loc,
    pub inventory: usize,
    pub customer: Option<String>,
    pub batch: Option<u64>,
    pub assignment: Vec<Assign>,
}

/// One selected product and its slot.
#[derive(Debug, Clone)]
pub struct Assign {
    /// Index into the inventory's entries.
    pub entry: usize,
    /// Index into the cell's slots.
    pub slot: usize,
    pub loc: Loc,
}

#[derive(Debug, Clone)]
pub struct DemoDef {
    pub name: String,
    pub loc: Loc,
    pub order: usize,
    /// Inventory entries in the demonstrated order.
    pub sequence: Vec<usize>,
    pub at: Vec<Placed>,
}

/// A product stood somewhere other than its inventory position.
#[derive(Debug, Clone)]
pub struct Placed {
    pub entry: usize,
    pub at: [f64; 2],
    pub loc: Loc,
}

#[derive(Debug, Clone)]
pub struct Choose {
    pub n: usize,
    /// Inventory entries, as listed.
    pub entries: Vec<usize>,
    /// Cell slots, as listed.
    pub slots: Vec<usize>,
    pub loc: Loc,
}

/// Inclusive range of a count, with where it was written.
#[derive(Debug, Clone, Copy)]
pub struct CountRange {
    pub low: usize,
    pub high: usize,
    pub loc: Option<Loc>,
}

impl CountRange {
    pub const NONE: CountRange = CountRange {
        low: 0,
        high: 0,
        loc: None,
    };
}

#[derive(Debug, Clone)]
pub struct DemosDef {
    pub name: String,
    pub loc: Loc,
    pub inventory: usize,
    pub choose: Choose,
    pub keep: f64,
    pub jitter: f64,
    pub jitter_loc: Option<Loc>,
    pub sequence: SequenceMode,
    pub repeat: usize,
    /// Where `repeat` was written, if it was.
    pub repeat_loc: Option<Loc>,
    pub seed: u64,
    pub human: CountRange,
    pub missing: CountRange,
}

#[derive(Debug, Clone)]
pub struct ScenarioDef {
    pub name: String,
    pub loc: Loc,
    pub order: usize,
    pub human_packed: Vec<usize>,
    pub missing: Vec<usize>,
    pub jitter: f64,
    pub jitter_loc: Option<Loc>,
    pub seed: u64,
    pub at: Vec<Placed>,
}

#[derive(Debug, Clone)]
pub struct ScenariosDef {
    pub name: String,
    pub loc: Loc,
    pub inventory: usize,
    pub choose: Choose,
    pub human: CountRange,
    pub missing: CountRange,
    pub jitter: f64,
    pub jitter_loc: Option<Loc>,
    pub count: usize,
    /// Where `count` was written.
    pub count_loc: Loc,
    pub seed: u64,
}

#[cfg(test)]
mod tests {
    use super::Rect;

    #[test]
    fn the_gap_between_two_rectangles_is_their_nearest_distance() {
        let a = Rect::centred([0.0, 0.0], 0.05, 0.05);
        // Side by side, 2 mm apart.
        assert!((a.gap(&Rect::centred([0.052, 0.01], 0.05, 0.05)) - 0.002).abs() < 1e-12);
        // Corner to corner, 3 mm and 4 mm apart on the axes: 5 mm.
        assert!((a.gap(&Rect::centred([0.053, -0.054], 0.05, 0.05)) - 0.005).abs() < 1e-12);
        // Touching, overlapping: 0.
        assert_eq!(a.gap(&Rect::centred([0.05, 0.0], 0.05, 0.05)), 0.0);
        assert_eq!(a.gap(&Rect::centred([0.01, 0.01], 0.05, 0.05)), 0.0);
    }
}
