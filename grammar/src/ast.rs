//! The typed syntax tree of one `.pack` file. Every node carries the byte
//! span of its source text; values carry the literal text they were written
//! with so that `fmt` can reprint them unchanged.
//!
//! Invariants: statements are kept in source order, and nothing is resolved
//! here (names are plain text; duplicates and missing statements are the
//! compiler's business).

use crate::span::Span;

#[derive(Debug, Clone, PartialEq)]
pub struct File {
    pub items: Vec<Item>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    Use(Use),
    Cell(Cell),
    Product(Product),
    Inventory(Inventory),
    Order(Order),
    Demo(Demo),
    Demos(Demos),
    Scenario(Scenario),
    Scenarios(Scenarios),
}

impl Item {
    pub fn span(&self) -> Span {
        match self {
            Item::Use(i) => i.span,
            Item::Cell(i) => i.span,
            Item::Product(i) => i.span,
            Item::Inventory(i) => i.span,
            Item::Order(i) => i.span,
            Item::Demo(i) => i.span,
            Item::Demos(i) => i.span,
            Item::Scenario(i) => i.span,
            Item::Scenarios(i) => i.span,
        }
    }
}

/// An identifier as written.
#[derive(Debug, Clone, PartialEq)]
pub struct Name {
    pub text: String,
    pub span: Span,
}

/// A string literal; `value` is unescaped.
#[derive(Debug, Clone, PartialEq)]
pub struct Str {
    pub value: String,
    pub span: Span,
}

/// Length units accepted by the language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    Mm,
    Cm,
    M,
}

impl LengthUnit {
    pub fn as_str(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::Cm => "cm",
            LengthUnit::M => "m",
        }
    }
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Mm => 0.001,
            LengthUnit::Cm => 0.01,
            LengthUnit::M => 1.0,
        }
    }
}

/// A length, converted to metres.
#[derive(Debug, Clone, PartialEq)]
pub struct Length {
    pub metres: f64,
    /// The number as written (`50`, `-0.50`).
    pub number: String,
    pub unit: Option<LengthUnit>,
    pub span: Span,
}

/// Mass units accepted by the language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MassUnit {
    Kg,
    G,
}

impl MassUnit {
    pub fn as_str(self) -> &'static str {
        match self {
            MassUnit::Kg => "kg",
            MassUnit::G => "g",
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Mass {
    pub kg: f64,
    pub number: String,
    pub unit: Option<MassUnit>,
    pub span: Span,
}

/// Time units accepted by the language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeUnit {
    Ms,
    S,
}

impl TimeUnit {
    pub fn as_str(self) -> &'static str {
        match self {
            TimeUnit::Ms => "ms",
            TimeUnit::S => "s",
        }
    }
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::Ms => 0.001,
            TimeUnit::S => 1.0,
        }
    }
}

/// A time, converted to seconds (`100 ms`, `0.5 s`, or a bare number of
/// seconds).
#[derive(Debug, Clone, PartialEq)]
pub struct Time {
    pub seconds: f64,
    /// The number as written.
    pub number: String,
    pub unit: Option<TimeUnit>,
    pub span: Span,
}

/// When the suction's settle time runs: after it grips a product (the
/// suction switched on at the top face) or after it releases one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SettleAfter {
    Grip,
    Release,
}

impl SettleAfter {
    pub fn as_str(self) -> &'static str {
        match self {
            SettleAfter::Grip => "grip",
            SettleAfter::Release => "release",
        }
    }
}

/// A plain whole number (counts, seeds, batch sizes).
#[derive(Debug, Clone, PartialEq)]
pub struct Count {
    pub value: u64,
    pub span: Span,
}

/// A plain number without unit (`keep 0.6`).
#[derive(Debug, Clone, PartialEq)]
pub struct Fraction {
    pub value: f64,
    pub number: String,
    pub span: Span,
}

/// A share, as a percentage (`50 %`) or a plain number (`0.5`).
#[derive(Debug, Clone, PartialEq)]
pub struct Share {
    /// As a fraction (`50 %` is 0.5).
    pub value: f64,
    /// The number as written.
    pub number: String,
    /// Written with `%`.
    pub percent: bool,
    pub span: Span,
}

/// `(x, y)` on the table or `(x, y, z)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub x: Length,
    pub y: Length,
    pub z: Option<Length>,
    pub span: Span,
}

/// `A to B` in `human packs A to B` and `missing A to B`.
#[derive(Debug, Clone, PartialEq)]
pub struct Range {
    pub low: Count,
    pub high: Count,
    pub span: Span,
}

/// A statement with its span (the whole line, without comment).
#[derive(Debug, Clone, PartialEq)]
pub struct Stmt<K> {
    pub kind: K,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Use {
    pub path: Str,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    pub name: Name,
    pub stmts: Vec<Stmt<CellStmt>>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Robot {
    Ur10,
    Urdf(Str),
}

#[derive(Debug, Clone, PartialEq)]
pub enum CellStmt {
    Robot(Robot),
    Base(Point),
    Suction(Length),
    Pending(Point, Point),
    Box {
        name: Name,
        at: Point,
        size: Point,
    },
    Slot {
        name: Name,
        at: Point,
    },
    Lift(Length),
    /// The arm's speed, a share of its full speed.
    Speed(Share),
    /// How long the arm waits, still, after the suction grips or releases
    /// (`settle 100 ms after grip`).
    Settle {
        time: Time,
        after: SettleAfter,
    },
    /// The speed of the guarded descent onto a product's top face, a share
    /// of the cell's speed.
    Descent(Share),
    /// The arm's acceleration limits, rad/s², one per joint.
    Acceleration(JointValues),
    /// The arm's jerk limits, rad/s³, one per joint.
    Jerk(JointValues),
}

/// One plain number per joint, base first (`(2.5, 2.5, 2.5, 4, 4, 4)`);
/// as many as written (the compiler checks the count).
#[derive(Debug, Clone, PartialEq)]
pub struct JointValues {
    pub values: Vec<Fraction>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    Cube(Length),
    Box(Point),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Product {
    pub name: Name,
    pub shape: Shape,
    pub mass: Option<Mass>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Inventory {
    pub name: Name,
    pub cell: Name,
    pub entries: Vec<Stmt<Entry>>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    pub product: Name,
    pub at: Point,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Order {
    pub name: Name,
    pub inventory: Name,
    pub stmts: Vec<Stmt<OrderStmt>>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum OrderStmt {
    Customer(Str),
    Batch(Count),
    Assign { product: Name, slot: Name },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Demo {
    pub name: Name,
    pub order: Name,
    pub stmts: Vec<Stmt<DemoStmt>>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum DemoStmt {
    Sequence(Vec<Name>),
    At { product: Name, at: Point },
}

/// How a generated demonstration orders the selected products.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SequenceMode {
    /// Inventory order.
    Ascending,
    /// Reverse inventory order.
    Descending,
    /// The order of the `choose` list.
    Listed,
    /// A seeded random order per demonstration.
    Random,
}

impl SequenceMode {
    pub fn as_str(self) -> &'static str {
        match self {
            SequenceMode::Ascending => "ascending",
            SequenceMode::Descending => "descending",
            SequenceMode::Listed => "listed",
            SequenceMode::Random => "random",
        }
    }
}

/// `choose N of P.. into S..`
#[derive(Debug, Clone, PartialEq)]
pub struct Choose {
    pub n: Count,
    pub products: Vec<Name>,
    pub slots: Vec<Name>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Demos {
    pub name: Name,
    pub inventory: Name,
    pub stmts: Vec<Stmt<DemosStmt>>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum DemosStmt {
    Choose(Choose),
    Keep(Fraction),
    Jitter(Length),
    Sequence(SequenceMode),
    Repeat(Count),
    Seed(Count),
    HumanPacks(Range),
    Missing(Range),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    pub name: Name,
    pub order: Name,
    pub stmts: Vec<Stmt<ScenarioStmt>>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ScenarioStmt {
    HumanPacked(Vec<Name>),
    Missing(Vec<Name>),
    Jitter(Length),
    Seed(Count),
    At { product: Name, at: Point },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Scenarios {
    pub name: Name,
    pub inventory: Name,
    pub stmts: Vec<Stmt<ScenariosStmt>>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ScenariosStmt {
    Choose(Choose),
    HumanPacks(Range),
    Missing(Range),
    Jitter(Length),
    Count(Count),
    Seed(Count),
}
