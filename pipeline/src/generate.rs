//! Random valid cells, for tests and benchmarks: develop on many random
//! cells, report on fixed seeds.
//!
//! [`generated_cell`] turns a seed into one self-contained `.pack` file: a
//! UR10 cell (base offset, sometimes on a riser; a box on one side of the
//! robot and the pending area on another), 4 to 10 products, one
//! inventory, one sparse `demos` block (n = 2 or 3 products, half of the
//! combinations, one or two slots never used, a random sequence rule) and
//! six `scenarios` suites that measure what the demonstrations did not
//! show: larger orders, CASE 2, missing stock and the untaught slots.
//!
//! Three families share that recipe ([`Family`]): the standard cells
//! (`gen_<seed>`, [`family_cell`]), which the bundled model was taught on
//! and the reported figures come from; the wide cells (`wide_<seed>`)
//! with the sizes a line engineer's cell may have and ours rarely do:
//! deep boxes, tall products, short lifts, long or short cups, high
//! risers, a slowed arm; and the compact cells (`compact_<seed>`), the
//! standard sizes with the products waiting beside the box, on the same
//! side of the robot. A wide seed draws in the same order as a standard
//! one, from wider ranges, and a compact one differs only where it draws
//! the products' side and place, so adding the families changed no
//! standard cell.
//!
//! A [`Variant`] teaches the same cell as a line engineer does, with a
//! few hand-written `order` + `demo` pairs instead of the `demos` block,
//! and may draw every suite from a second inventory with the products'
//! places reversed; the cell and its suites stay the seed's.
//!
//! Pure and deterministic: every draw comes from one
//! `ChaCha8Rng::seed_from_u64(seed)`, so the same seed gives the same bytes
//! everywhere. Geometry is drawn on a millimetre grid and checked here
//! against the compiler's rules (reach, slots in their box, slot spacing
//! for the largest product, products apart and inside the pending area
//! whatever the jitter), so every file passes `packwright check` and is
//! laid out as `packwright fmt` would lay it out. Slot and product centres
//! stay 0.40 to 0.95 m from the base axis ([`REACH_MIN_MM`],
//! [`REACH_MAX_MM`]), products within 0.60 m when they wait opposite the
//! box ([`OPPOSITE_PRODUCT_REACH_MM`]).

use rand::seq::{IndexedRandom, SliceRandom, index};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::fmt::Write;

/// Jitter of every generated block, millimetres.
pub const JITTER_MM: i64 = 10;
/// Scenarios per suite.
pub const SUITE_COUNT: usize = 50;
/// The `keep` fraction of the demonstrations.
pub const KEEP: f64 = 0.5;
/// Demonstrations a cell aims for (inclusive bounds).
pub const DEMOS_MIN: u64 = 40;
pub const DEMOS_MAX: u64 = 200;
/// Horizontal distance of every slot and product centre from the base
/// axis, millimetres: well inside the UR10's 0.20..1.30 m so that the
/// hover, lift and approach poses above them are reachable too.
pub const REACH_MIN_MM: i64 = 400;
pub const REACH_MAX_MM: i64 = 950;
/// Farthest product centre, millimetres, when the products wait on the
/// side opposite the box: every product then swings 150 to 180 degrees
/// round the base, and the scripted expert's straight joint motions fail
/// more often from products far out (measured over 200 random cells, 3
/// packages each: 33 of 430 such moves failed from 0.55 m and beyond, 6 of
/// 620 nearer; none when the sides are adjacent).
pub const OPPOSITE_PRODUCT_REACH_MM: i64 = 600;
/// Most slots in a box.
pub const MAX_SLOTS: usize = 9;

/// Which cells a seed draws: the same recipe (sides, layout, teaching,
/// suites) with different ranges for the sizes a line engineer's cell may
/// have and ours rarely do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    /// The cells the bundled model was taught on and the reported cells
    /// are drawn from (`gen_<seed>`): boxes 60-100 mm deep, products 25-60
    /// mm, lifts 100-200 mm, cups 80-120 mm, risers to 300 mm, full speed.
    Standard,
    /// Cells unlike those (`wide_<seed>`): boxes to 300 mm deep, products
    /// 30-80 mm across and to 150 mm tall (at most twice their narrow
    /// side, so that they stand), lifts from 20 mm, cups 50-200 mm, risers
    /// to 400 mm, about half of them slowed (`speed`).
    Wide,
    /// The standard sizes with the products waiting beside the box, on
    /// the same side of the robot (`compact_<seed>`): the pending area
    /// 3-8 cm clear of it, the nearest product 11-22 cm from a slot, where
    /// the other families keep the products a whole side away.
    Compact,
}

impl Family {
    pub fn as_str(self) -> &'static str {
        match self {
            Family::Standard => "standard",
            Family::Wide => "wide",
            Family::Compact => "compact",
        }
    }

    /// The prefix of the cell's name (and file stem).
    fn prefix(self) -> &'static str {
        match self {
            Family::Standard => "gen",
            Family::Wide => "wide",
            Family::Compact => "compact",
        }
    }

    /// The `generate` options that draw this family, as the file's header
    /// quotes them.
    fn option(self) -> &'static str {
        match self {
            Family::Standard => "",
            Family::Wide => " --family wide",
            Family::Compact => " --family compact",
        }
    }

    fn ranges(self) -> Ranges {
        match self {
            Family::Standard | Family::Compact => Ranges {
                cube: (30, 60),
                across: (30, 60),
                tall: (25, 60),
                riser: (50, 300),
                suction: (80, 120),
                lift: (100, 200),
                box_depth: (60, 100),
                speed: None,
            },
            Family::Wide => Ranges {
                cube: (30, 80),
                across: (30, 80),
                tall: (25, 150),
                riser: (50, 400),
                suction: (50, 200),
                lift: (20, 300),
                box_depth: (60, 300),
                speed: Some((20, 100)),
            },
        }
    }
}

/// How many times its narrow side a box-shaped product may be tall: one
/// taller topples when it is let go a few centimetres up (over 100 wide
/// cells with products to 7 times as tall as wide, every product the
/// scripted expert dropped beside its slot was over 2 times, or 20 to 25
/// mm thin).
const STANDS: i64 = 2;

/// Inclusive millimetre (or per cent) ranges of one family's draws.
struct Ranges {
    /// A cube's edge.
    cube: (i64, i64),
    /// A box-shaped product's width and depth.
    across: (i64, i64),
    /// A box-shaped product's height.
    tall: (i64, i64),
    /// The riser's height, when the robot stands on one (a third of cells).
    riser: (i64, i64),
    suction: (i64, i64),
    /// The `lift`, when the cell gives one (half of cells).
    lift: (i64, i64),
    /// The box's inside depth (its `size` z).
    box_depth: (i64, i64),
    /// The `speed` in per cent, given by half of the cells when `Some`.
    speed: Option<(i64, i64)>,
}

/// Where something stands, seen from the robot (world frame = table:
/// front is +x, left is +y).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Front,
    Behind,
    Left,
    Right,
}

impl Side {
    pub const ALL: [Side; 4] = [Side::Front, Side::Behind, Side::Left, Side::Right];

    pub fn as_str(self) -> &'static str {
        match self {
            Side::Front => "front",
            Side::Behind => "behind",
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    /// Unit vector from the base axis towards this side.
    fn radial(self) -> [i64; 2] {
        match self {
            Side::Front => [1, 0],
            Side::Behind => [-1, 0],
            Side::Left => [0, 1],
            Side::Right => [0, -1],
        }
    }

    /// The radial direction turned 90 degrees anticlockwise.
    fn tangential(self) -> [i64; 2] {
        let [x, y] = self.radial();
        [-y, x]
    }

    fn phrase(self) -> &'static str {
        match self {
            Side::Front => "in front of the robot",
            Side::Behind => "behind the robot",
            Side::Left => "on the robot's left",
            Side::Right => "on the robot's right",
        }
    }
}

/// Mixed into the seed for a priority list drawn for a listed order that
/// the seed did not draw itself ([`family_cell_taught`]).
const LISTED_STREAM: u64 = 0x6c69_7374_6564;

/// Seeds the hand-written demonstrations' draws ([`Variant::hand`]), so
/// that the rest of the cell stays the seed's.
const HAND_STREAM: u64 = 0x6861_6e64;

/// How a generated cell is taught and where its suites' products wait;
/// the default is the recipe's: one sparse `demos` block, one inventory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Variant {
    /// Taught by this many hand-written `order` + `demo` pairs instead of
    /// the `demos` block, as a line engineer teaches: each order 2 or 3
    /// products in the taught slots, demonstrated once in the cell's rule
    /// (one product sometimes seen up to the jitter off its place).
    pub hand: Option<usize>,
    /// A second inventory of the same products with their places reversed
    /// (the first where the last waits), which every suite draws from: the
    /// products wait where no demonstration picked them.
    pub reversed_stock: bool,
}

impl Variant {
    /// The `generate` options that ask for it, each with a leading space.
    fn options(self) -> String {
        let mut o = String::new();
        if let Some(k) = self.hand {
            let _ = write!(o, " --hand {k}");
        }
        if self.reversed_stock {
            o.push_str(" --reversed-stock");
        }
        o
    }
}

/// The taught sequence rule (`sequence` of the `demos` block).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Sequence {
    /// Inventory order.
    Ascending,
    /// Inventory order reversed.
    Descending,
    /// The order of the `choose` list ([`Generated::priority`]).
    Listed,
}

impl Sequence {
    pub fn as_str(self) -> &'static str {
        match self {
            Sequence::Ascending => "ascending",
            Sequence::Descending => "descending",
            Sequence::Listed => "listed",
        }
    }

    /// "packed in … order".
    fn phrase(self) -> &'static str {
        match self {
            Sequence::Ascending => "product",
            Sequence::Descending => "reverse product",
            Sequence::Listed => "the listed",
        }
    }
}

/// The six suites of every generated cell; a suite is named
/// `<cell>_<suffix>` (`gen_17_case1_n1`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SuiteKind {
    /// CASE 1 with the taught n, any slot of the cell.
    Case1N,
    /// CASE 1 with n + 1 products.
    Case1N1,
    /// CASE 1 with n + 2 products.
    Case1N2,
    /// CASE 2: n + 1 products, a worker packs 1 to n of them first.
    Case2,
    /// n + 1 products, 1 or 2 of them out of stock.
    Missing,
    /// n products into the untaught slots and n - 1 taught ones: every
    /// scenario uses at least one slot no demonstration used.
    Untaught,
}

impl SuiteKind {
    pub const ALL: [SuiteKind; 6] = [
        SuiteKind::Case1N,
        SuiteKind::Case1N1,
        SuiteKind::Case1N2,
        SuiteKind::Case2,
        SuiteKind::Missing,
        SuiteKind::Untaught,
    ];

    pub fn suffix(self) -> &'static str {
        match self {
            SuiteKind::Case1N => "case1_n",
            SuiteKind::Case1N1 => "case1_n1",
            SuiteKind::Case1N2 => "case1_n2",
            SuiteKind::Case2 => "case2",
            SuiteKind::Missing => "missing",
            SuiteKind::Untaught => "untaught",
        }
    }
}

/// One generated `scenarios` block.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GeneratedSuite {
    pub kind: SuiteKind,
    pub name: String,
    /// N of its `choose` (products per package).
    pub n: usize,
    /// The slots of its `into` list.
    pub slots: Vec<String>,
    pub count: usize,
    pub seed: u64,
}

/// A generated cell: the `.pack` text and what a caller needs to know
/// about it without compiling it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Generated {
    pub family: Family,
    pub seed: u64,
    /// `gen_<seed>`: the cell's name and the file's stem. Every global
    /// name in the file starts with it, so that several generated files
    /// can be compiled together.
    pub name: String,
    /// The whole file, formatted canonically.
    pub text: String,
    /// The inventory the teaching draws from.
    pub inventory: String,
    /// The inventory every suite draws from: [`Generated::inventory`], or
    /// the reversed one ([`Variant::reversed_stock`]).
    pub suite_inventory: String,
    /// The `demos` block, or the hand-written `demo` blocks
    /// ([`Variant::hand`]).
    pub demos: Vec<String>,
    pub variant: Variant,
    /// N of the demonstrations (2 or 3).
    pub taught_n: usize,
    pub sequence: Sequence,
    /// The products of the `demos` block's `choose` list: the priority
    /// order when [`Sequence::Listed`], else the inventory order.
    pub priority: Vec<String>,
    /// Products in inventory order (graph node order).
    pub products: Vec<String>,
    /// Slots in declaration order (label i + 1).
    pub slots: Vec<String>,
    /// The slots the teaching may use, in declaration order (hand-written
    /// orders use some of them).
    pub taught_slots: Vec<String>,
    /// The slots no demonstration uses (one or two).
    pub untaught_slots: Vec<String>,
    /// `repeat` of the `demos` block (1 or 2; 1 when taught by hand).
    pub repeat: usize,
    /// How many demonstrations the teaching expands to.
    pub demonstrations: usize,
    pub box_side: Side,
    pub pending_side: Side,
    /// The base, metres (z > 0: on a riser).
    pub base: [f64; 3],
    /// The `speed` in per cent, if the cell gives one.
    pub speed: Option<i64>,
    pub suites: Vec<GeneratedSuite>,
}

impl Generated {
    /// `gen_<seed>.pack`.
    pub fn file_name(&self) -> String {
        format!("{}.pack", self.name)
    }

    /// True when the robot stands on a riser (base z > 0).
    pub fn riser(&self) -> bool {
        self.base[2] > 0.0
    }

    pub fn suite(&self, kind: SuiteKind) -> &GeneratedSuite {
        self.suites
            .iter()
            .find(|s| s.kind == kind)
            .expect("every generated cell has every suite")
    }

    /// The suite names, in file order.
    pub fn suite_names(&self) -> Vec<String> {
        self.suites.iter().map(|s| s.name.clone()).collect()
    }
}

/// The name of the standard cell (and file stem) for `seed`.
pub fn cell_name(seed: u64) -> String {
    family_cell_name(Family::Standard, seed)
}

/// The name of the cell of `family` (and file stem) for `seed`.
pub fn family_cell_name(family: Family, seed: u64) -> String {
    format!("{}_{seed}", family.prefix())
}

/// The suite of `kind` of the standard cell generated from `seed`.
pub fn suite_name(seed: u64, kind: SuiteKind) -> String {
    format!("{}_{}", cell_name(seed), kind.suffix())
}

/// C(n, k).
fn binomial(n: u64, k: u64) -> u64 {
    (0..k).fold(1, |c, i| c * (n - i) / (i + 1))
}

/// n! / (n - k)!.
fn arrangements(n: u64, k: u64) -> u64 {
    (0..k).map(|i| n - i).product()
}

/// Demonstrations of `choose n of <m products> into <k slots>` with
/// `keep` [`KEEP`] and `repeat` 1: the kept combinations (rounded as the
/// compiler rounds) times every arrangement of n of the k slots.
pub fn demonstrations(m: usize, k: usize, n: usize) -> u64 {
    let combos = binomial(m as u64, n as u64);
    let kept = ((KEEP * combos as f64).round() as u64).min(combos);
    kept * arrangements(k as u64, n as u64)
}

/// The taught slots' count and `repeat` that give [`DEMOS_MIN`] to
/// [`DEMOS_MAX`] demonstrations, for n of m products and `slots` slots
/// with `untaught` of them left out; `None` if there is none.
fn repeat_for(m: usize, slots: usize, untaught: usize, n: usize) -> Option<usize> {
    let k = slots.checked_sub(untaught)?;
    if k < n {
        return None;
    }
    let once = demonstrations(m, k, n);
    let repeat = if once < DEMOS_MIN { 2 } else { 1 };
    (DEMOS_MIN..=DEMOS_MAX)
        .contains(&(once * repeat))
        .then_some(repeat as usize)
}

/// `(slots, untaught)` pairs that give a good number of demonstrations.
fn slot_options(m: usize, n: usize) -> Vec<(usize, usize)> {
    (n + 2..=MAX_SLOTS)
        .flat_map(|s| [(s, 1), (s, 2)])
        .filter(|&(s, u)| repeat_for(m, s, u, n).is_some())
        .collect()
}

/// Millimetres as metres with three decimals (`-0.050`).
fn metres(mm: i64) -> String {
    let sign = if mm < 0 { "-" } else { "" };
    format!("{sign}{}.{:03}", mm.abs() / 1000, mm.abs() % 1000)
}

fn point(p: [i64; 2]) -> String {
    format!("({}, {})", metres(p[0]), metres(p[1]))
}

/// A multiple of `step` from `low` to `high` (inclusive).
fn stepped(rng: &mut ChaCha8Rng, low: i64, high: i64, step: i64) -> i64 {
    low + step * rng.random_range(0..=(high - low) / step)
}

fn round_up(v: i64, step: i64) -> i64 {
    (v + step - 1).div_euclid(step) * step
}

/// An axis-aligned rectangle, millimetres.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Rect {
    min: [i64; 2],
    max: [i64; 2],
}

impl Rect {
    /// Clearance between two rectangles (negative if they overlap): the
    /// larger of the gaps along x and along y.
    fn gap(&self, o: &Rect) -> i64 {
        let gx = (o.min[0] - self.max[0]).max(self.min[0] - o.max[0]);
        let gy = (o.min[1] - self.max[1]).max(self.min[1] - o.max[1]);
        gx.max(gy)
    }

    fn contains(&self, o: &Rect) -> bool {
        self.min[0] <= o.min[0]
            && self.min[1] <= o.min[1]
            && o.max[0] <= self.max[0]
            && o.max[1] <= self.max[1]
    }

    fn grown(&self, by: i64) -> Rect {
        Rect {
            min: [self.min[0] - by, self.min[1] - by],
            max: [self.max[0] + by, self.max[1] + by],
        }
    }

    fn centred(c: [i64; 2], half: [i64; 2]) -> Rect {
        Rect {
            min: [c[0] - half[0], c[1] - half[1]],
            max: [c[0] + half[0], c[1] + half[1]],
        }
    }
}

/// A frame on the table: the base's (x, y), a side's radial and
/// tangential directions. Local (r, t) millimetres to world.
struct Frame {
    base: [i64; 2],
    side: Side,
}

impl Frame {
    fn world(&self, r: i64, t: i64) -> [i64; 2] {
        let (u, v) = (self.side.radial(), self.side.tangential());
        [
            self.base[0] + r * u[0] + t * v[0],
            self.base[1] + r * u[1] + t * v[1],
        ]
    }

    /// The world rectangle of local radial `r0..r1` and tangential `t0..t1`.
    fn rect(&self, r: [i64; 2], t: [i64; 2]) -> Rect {
        let a = self.world(r[0], t[0]);
        let b = self.world(r[1], t[1]);
        Rect {
            min: [a[0].min(b[0]), a[1].min(b[1])],
            max: [a[0].max(b[0]), a[1].max(b[1])],
        }
    }
}

struct Product {
    name: String,
    /// Width (x), depth (y), height (z), millimetres.
    size: [i64; 3],
    cube: bool,
    /// Hundredths of a kilogram.
    mass: Option<i64>,
}

impl Product {
    /// Half sizes rounded up: a conservative footprint on the mm grid.
    fn footprint(&self, at: [i64; 2]) -> Rect {
        Rect::centred(at, [(self.size[0] + 1) / 2, (self.size[1] + 1) / 2])
    }
}

struct Layout {
    box_centre: [i64; 2],
    box_size: [i64; 3],
    box_rect: Rect,
    slots: Vec<(String, [i64; 2])>,
    pending: Rect,
    positions: Vec<[i64; 2]>,
}

fn distance(base: [i64; 2], p: [i64; 2]) -> f64 {
    ((p[0] - base[0]) as f64).hypot((p[1] - base[1]) as f64)
}

/// Grid rows for `items` items in at most `max_rows` rows of at most
/// `max_cols` columns, every row used: `(rows, columns)` options.
fn grids(items: usize, max_rows: usize, max_cols: usize) -> Vec<(usize, usize)> {
    (1..=max_rows)
        .map(|rows| (rows, items.div_ceil(rows)))
        .filter(|&(rows, cols)| cols <= max_cols && (rows - 1) * cols < items)
        .collect()
}

/// Draws the box with its slots and the pending area with the products
/// (`beside` the box, on its side of the robot, else on `pending_side`);
/// `None` when the draw breaks a rule (the caller draws again).
#[allow(clippy::too_many_arguments)]
fn draw_layout(
    rng: &mut ChaCha8Rng,
    base: [i64; 2],
    box_side: Side,
    pending_side: Side,
    beside: bool,
    products: &[Product],
    slot_count: usize,
    depth: (i64, i64),
) -> Option<Layout> {
    let largest = products
        .iter()
        .map(|p| p.size[0].max(p.size[1]))
        .max()
        .unwrap_or(0);
    let half = (largest + 1) / 2;

    // The box: rows of slots running across the radial direction, the
    // nearest row first; slots a pitch apart that fits the largest product
    // with a gap, the box a margin wider than the slots' products.
    let bx = Frame {
        base,
        side: box_side,
    };
    let (rows, cols) = *grids(slot_count, 3, 6).choose(rng)?;
    let pitch = round_up(largest + stepped(rng, 15, 30, 5), 10);
    let r0 = stepped(rng, 450, 600, 10);
    let t0 = stepped(rng, -50, 50, 10);
    let margin = stepped(rng, 10, 25, 5);
    let height = stepped(rng, depth.0, depth.1, 10);
    let mut slots = Vec::with_capacity(slot_count);
    for i in 0..slot_count {
        let (row, col) = ((i / cols) as i64, (i % cols) as i64);
        let r = r0 + row * pitch;
        let t = t0 + (2 * col - (cols as i64 - 1)) * pitch / 2;
        let name = format!("{}{}", (b'a' + row as u8) as char, col + 1);
        slots.push((name, bx.world(r, t)));
    }
    let (rows, cols) = (rows as i64, cols as i64);
    let half_r = (rows - 1) * pitch / 2 + half + margin;
    let half_t = (cols - 1) * pitch / 2 + half + margin;
    let centre_r = r0 + (rows - 1) * pitch / 2;
    let box_rect = bx.rect(
        [centre_r - half_r, centre_r + half_r],
        [t0 - half_t, t0 + half_t],
    );
    let box_centre = bx.world(centre_r, t0);
    let box_size = [
        box_rect.max[0] - box_rect.min[0],
        box_rect.max[1] - box_rect.min[1],
        height,
    ];

    // The pending area: products in rows a pitch apart that keeps them
    // apart, and inside the area, whatever the jitter.
    let pf = Frame {
        base,
        side: pending_side,
    };
    let (prows, pcols) = *grids(products.len(), 3, 5).choose(rng)?;
    let ppitch = round_up(largest + 2 * JITTER_MM + stepped(rng, 10, 40, 5), 10);
    let opposite = pending_side.radial() == box_side.radial().map(|v| -v);
    let product_reach = if opposite {
        OPPOSITE_PRODUCT_REACH_MM
    } else {
        REACH_MAX_MM
    };
    let p0 = stepped(rng, 420, if opposite { 470 } else { 520 }, 10);
    let mut pt0 = stepped(rng, -50, 50, 10);
    let edge = half + JITTER_MM + stepped(rng, 10, 30, 5);
    if beside {
        // Beside the box along the tangent, 30-80 mm clear of it, on
        // either hand.
        let clear = stepped(rng, 30, 80, 5);
        let span = (pcols as i64 - 1) * ppitch / 2 + edge;
        let off = half_t + clear + span;
        pt0 = if rng.random_bool(0.5) {
            t0 + off
        } else {
            t0 - off
        };
    }
    let mut positions = Vec::with_capacity(products.len());
    for i in 0..products.len() {
        let (row, col) = ((i / pcols) as i64, (i % pcols) as i64);
        let r = p0 + row * ppitch;
        let t = pt0 + (2 * col - (pcols as i64 - 1)) * ppitch / 2;
        positions.push(pf.world(r, t));
    }
    let (prows, pcols) = (prows as i64, pcols as i64);
    let span_t = (pcols - 1) * ppitch / 2;
    let pending = pf.rect(
        [p0 - edge, p0 + (prows - 1) * ppitch + edge],
        [pt0 - span_t - edge, pt0 + span_t + edge],
    );

    let layout = Layout {
        box_centre,
        box_size,
        box_rect,
        slots,
        pending,
        positions,
    };
    layout_is_valid(&layout, base, products, product_reach).then_some(layout)
}

/// The compiler's rules (and this module's stricter margins) on a layout;
/// products at most `product_reach` millimetres from the base axis.
fn layout_is_valid(l: &Layout, base: [i64; 2], products: &[Product], product_reach: i64) -> bool {
    let within =
        |p: [i64; 2], max: i64| (REACH_MIN_MM as f64..=max as f64).contains(&distance(base, p));
    // Box and pending area apart, with room between them.
    if l.box_rect.gap(&l.pending) < 30 {
        return false;
    }
    // Slots: reachable; every product fits every slot with 5 mm to spare;
    // any two products in any two slots apart by 5 mm.
    for (i, (_, s)) in l.slots.iter().enumerate() {
        if !within(*s, REACH_MAX_MM) {
            return false;
        }
        if products
            .iter()
            .any(|p| !l.box_rect.contains(&p.footprint(*s).grown(5)))
        {
            return false;
        }
        for (_, t) in &l.slots[..i] {
            for a in products {
                for b in products {
                    if a.footprint(*s).gap(&b.footprint(*t)) < 5 {
                        return false;
                    }
                }
            }
        }
    }
    // Products: reachable; inside the pending area and apart, for any
    // jitter up to JITTER_MM on each axis.
    let grown = |p: &Product, at: [i64; 2]| p.footprint(at).grown(JITTER_MM);
    for (i, (p, at)) in products.iter().zip(&l.positions).enumerate() {
        if !within(*at, product_reach) || !l.pending.contains(&grown(p, *at)) {
            return false;
        }
        for (q, other) in products[..i].iter().zip(&l.positions) {
            if grown(p, *at).gap(&grown(q, *other)) < 5 {
                return false;
            }
        }
    }
    true
}

/// One hand-written order and its one demonstration ([`Variant::hand`]).
struct HandOrder {
    /// 1, 2, …: the blocks are `NAME_order<number>` and `NAME_seen<number>`.
    number: usize,
    /// (product, slot) in the order's lines.
    lines: Vec<(String, String)>,
    /// The products in the order the demonstrator packed them.
    sequence: Vec<String>,
    /// A product seen off its place: its name and where it stood, mm.
    seen_at: Option<(String, [i64; 2])>,
}

/// `k` hand-written orders of 2 or 3 products in `taught_slots`, each
/// demonstrated once in `rule` (a listed rule's priority, else inventory
/// order, reversed when descending), from their own random stream.
fn hand_taught(
    seed: u64,
    k: usize,
    products: &[String],
    positions: &[[i64; 2]],
    taught_slots: &[String],
    (rule, priority): (Sequence, &[String]),
) -> Vec<HandOrder> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ HAND_STREAM);
    let rank = |p: &String| priority.iter().position(|q| q == p).unwrap_or(0);
    (1..=k)
        .map(|number| {
            let size = rng
                .random_range(2..=3)
                .min(products.len())
                .min(taught_slots.len());
            let chosen = index::sample(&mut rng, products.len(), size).into_vec();
            let slots = index::sample(&mut rng, taught_slots.len(), size).into_vec();
            let lines: Vec<(String, String)> = chosen
                .iter()
                .zip(&slots)
                .map(|(&p, &s)| (products[p].clone(), taught_slots[s].clone()))
                .collect();
            let mut sequence: Vec<String> = lines.iter().map(|(p, _)| p.clone()).collect();
            sequence.sort_by_key(rank);
            if rule == Sequence::Descending {
                sequence.reverse();
            }
            let seen_at = rng.random_bool(0.5).then(|| {
                let p = chosen[rng.random_range(0..chosen.len())];
                let [x, y] = positions[p];
                let dx = rng.random_range(-JITTER_MM..=JITTER_MM);
                let dy = rng.random_range(-JITTER_MM..=JITTER_MM);
                (products[p].clone(), [x + dx, y + dy])
            });
            HandOrder {
                number,
                lines,
                sequence,
                seen_at,
            }
        })
        .collect()
}

/// The `order` and `demo` blocks of [`hand_taught`] orders.
fn write_hand_taught(
    t: &mut String,
    name: &str,
    inventory: &str,
    orders: &[HandOrder],
    rule: Sequence,
) {
    let _ = writeln!(
        t,
        "# Taught by hand: {} order{}, each demonstrated once, packed in {} order.",
        orders.len(),
        if orders.len() == 1 { "" } else { "s" },
        rule.phrase()
    );
    for (i, o) in orders.iter().enumerate() {
        if i > 0 {
            t.push('\n');
        }
        let order = format!("{name}_order{}", o.number);
        let _ = writeln!(t, "order {order} for {inventory} {{");
        for (p, slot) in &o.lines {
            let _ = writeln!(t, "  {p} -> {slot}");
        }
        let _ = writeln!(t, "}}");
        t.push('\n');
        let _ = writeln!(t, "demo {name}_seen{} for {order} {{", o.number);
        let _ = writeln!(t, "  sequence {}", o.sequence.join(", "));
        if let Some((p, at)) = &o.seen_at {
            let _ = writeln!(t, "  at {p} {}", point(*at));
        }
        let _ = writeln!(t, "}}");
    }
}

/// What the recipe's `demos` block says.
struct SparseTeaching<'a> {
    demos: &'a str,
    inventory: &'a str,
    n: usize,
    m: usize,
    demonstrations: usize,
    priority: &'a [String],
    taught_slots: &'a [String],
    untaught_slots: &'a [String],
    sequence: Sequence,
    repeat: usize,
    seed: u64,
}

/// The recipe's sparse `demos` block, with its comment.
fn write_sparse_teaching(t: &mut String, d: SparseTeaching) {
    let _ = writeln!(
        t,
        "# Sparse teaching: {} of {} products, half of the combinations, {} never used;",
        d.n,
        d.m,
        if d.untaught_slots.len() == 1 {
            format!("slot {}", d.untaught_slots[0])
        } else {
            format!("slots {}", d.untaught_slots.join(" and "))
        }
    );
    let _ = writeln!(
        t,
        "# {} demonstrations, packed in {} order.",
        d.demonstrations,
        d.sequence.phrase()
    );
    let _ = writeln!(t, "demos {} for {} {{", d.demos, d.inventory);
    let _ = writeln!(
        t,
        "  choose {} of {} into {}",
        d.n,
        d.priority.join(", "),
        d.taught_slots.join(", ")
    );
    let _ = writeln!(t, "  keep {KEEP}");
    let _ = writeln!(t, "  jitter {JITTER_MM} mm");
    let _ = writeln!(t, "  sequence {}", d.sequence.as_str());
    if d.repeat > 1 {
        let _ = writeln!(t, "  repeat {}", d.repeat);
    }
    let _ = writeln!(t, "  seed {}", d.seed);
    let _ = writeln!(t, "}}");
}

/// The standard cell generated from `seed`: see the module documentation.
pub fn family_cell(seed: u64) -> Generated {
    family_cell_taught(seed, None)
}

/// The standard cell generated from `seed`, taught in the order `rule`
/// when given: [`generated_cell`] of [`Family::Standard`].
pub fn family_cell_taught(seed: u64, rule: Option<Sequence>) -> Generated {
    generated_cell(Family::Standard, seed, rule)
}

/// The cell of `family` generated from `seed`, taught in the order `rule`
/// when given (else the seed's own): the same cell, products and suites;
/// the teaching is the same block in that order. Cells that teach one
/// model together must agree on the rule (`train` infers one rule from all
/// its demonstrations).
pub fn generated_cell(family: Family, seed: u64, rule: Option<Sequence>) -> Generated {
    generated_variant(family, seed, rule, Variant::default())
}

/// [`generated_cell`] taught and stocked as `variant` says; the cell, its
/// products and its suites' draws are the seed's whatever the variant.
pub fn generated_variant(
    family: Family,
    seed: u64,
    rule: Option<Sequence>,
    variant: Variant,
) -> Generated {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let name = family_cell_name(family, seed);
    let ranges = family.ranges();

    // Sizes: n, m, slots, untaught slots, such that the sparse teaching
    // gives a good number of demonstrations.
    let n: usize = rng.random_range(2..=3);
    let ms: Vec<usize> = (n + 2..=10)
        .filter(|&m| !slot_options(m, n).is_empty())
        .collect();
    let m = *ms.choose(&mut rng).expect("some product count fits");
    let (slot_count, untaught_count) = *slot_options(m, n)
        .choose(&mut rng)
        .expect("some slot count fits");
    let repeat = repeat_for(m, slot_count, untaught_count, n).expect("checked");

    // Products.
    let products: Vec<Product> = (1..=m)
        .map(|i| {
            let cube = rng.random_bool(0.5);
            let size = if cube {
                let l = stepped(&mut rng, ranges.cube.0, ranges.cube.1, 5);
                [l, l, l]
            } else {
                let (across, tall) = (ranges.across, ranges.tall);
                let w = stepped(&mut rng, across.0, across.1, 5);
                let d = stepped(&mut rng, across.0, across.1, 5);
                // Stands: at most STANDS times as tall as its narrow side.
                let high = tall.1.min(STANDS * w.min(d));
                [w, d, stepped(&mut rng, tall.0, high, 5)]
            };
            let mass = rng
                .random_bool(1.0 / 3.0)
                .then(|| stepped(&mut rng, 5, 50, 5));
            Product {
                name: format!("{name}_p{i}"),
                size,
                cube,
                mass,
            }
        })
        .collect();

    // The cell.
    let box_side = *Side::ALL.choose(&mut rng).expect("four sides");
    let beside = family == Family::Compact;
    let pending_side = if beside {
        box_side
    } else {
        let others: Vec<Side> = Side::ALL.into_iter().filter(|s| *s != box_side).collect();
        *others.choose(&mut rng).expect("three sides")
    };
    let base = [
        stepped(&mut rng, -300, 300, 10),
        stepped(&mut rng, -300, 300, 10),
        if rng.random_bool(1.0 / 3.0) {
            stepped(&mut rng, ranges.riser.0, ranges.riser.1, 10)
        } else {
            0
        },
    ];
    let suction = stepped(&mut rng, ranges.suction.0, ranges.suction.1, 5);
    let lift = rng
        .random_bool(0.5)
        .then(|| stepped(&mut rng, ranges.lift.0, ranges.lift.1, 10));
    let layout = (0..1000)
        .find_map(|_| {
            draw_layout(
                &mut rng,
                [base[0], base[1]],
                box_side,
                pending_side,
                beside,
                &products,
                slot_count,
                ranges.box_depth,
            )
        })
        .expect("a valid layout within 1000 draws");

    // Teaching: n of all products into all slots but the untaught ones.
    let mut untaught_idx = index::sample(&mut rng, slot_count, untaught_count).into_vec();
    untaught_idx.sort_unstable();
    let slot_names: Vec<String> = layout.slots.iter().map(|(s, _)| s.clone()).collect();
    let taught_idx: Vec<usize> = (0..slot_count)
        .filter(|i| !untaught_idx.contains(i))
        .collect();
    let taught_slots: Vec<String> = taught_idx.iter().map(|&i| slot_names[i].clone()).collect();
    let untaught_slots: Vec<String> = untaught_idx
        .iter()
        .map(|&i| slot_names[i].clone())
        .collect();
    let drawn = *[Sequence::Ascending, Sequence::Descending, Sequence::Listed]
        .choose(&mut rng)
        .expect("three rules");
    let product_names: Vec<String> = products.iter().map(|p| p.name.clone()).collect();
    let mut priority = product_names.clone();
    if drawn == Sequence::Listed {
        // A priority list that is not the inventory order.
        while priority == product_names {
            priority.shuffle(&mut rng);
        }
    }
    let sequence = rule.unwrap_or(drawn);
    if sequence == Sequence::Listed && priority == product_names {
        // A listed order asked of a seed that drew another rule: its own
        // draws, so that the rest of the cell stays the seed's.
        let mut own = ChaCha8Rng::seed_from_u64(seed ^ LISTED_STREAM);
        while priority == product_names {
            priority.shuffle(&mut own);
        }
    } else if sequence != Sequence::Listed {
        priority = product_names.clone();
    }
    let demos_seed = rng.random_range(1..=9999u64);

    // Suites.
    let mut untaught_into: Vec<usize> = index::sample(&mut rng, taught_idx.len(), n - 1)
        .into_iter()
        .map(|i| taught_idx[i])
        .chain(untaught_idx.iter().copied())
        .collect();
    untaught_into.sort_unstable();
    let suites: Vec<GeneratedSuite> = SuiteKind::ALL
        .into_iter()
        .map(|kind| {
            let (n, slots) = match kind {
                SuiteKind::Case1N => (n, slot_names.clone()),
                SuiteKind::Case1N1 | SuiteKind::Case2 | SuiteKind::Missing => {
                    (n + 1, slot_names.clone())
                }
                SuiteKind::Case1N2 => (n + 2, slot_names.clone()),
                SuiteKind::Untaught => (
                    n,
                    untaught_into
                        .iter()
                        .map(|&i| slot_names[i].clone())
                        .collect(),
                ),
            };
            GeneratedSuite {
                kind,
                name: format!("{name}_{}", kind.suffix()),
                n,
                slots,
                count: SUITE_COUNT,
                seed: rng.random_range(1..=99999u64),
            }
        })
        .collect();

    // Draws only a family with a speed makes, after all the others, so
    // that the rest of a standard cell is what it always was.
    let speed = ranges
        .speed
        .and_then(|(low, high)| {
            rng.random_bool(0.5)
                .then(|| stepped(&mut rng, low, high, 10))
        })
        .filter(|&s| s < 100);

    let inventory = format!("{name}_stock");
    let suite_inventory = if variant.reversed_stock {
        format!("{name}_stock2")
    } else {
        inventory.clone()
    };
    let hand = variant.hand.map(|k| {
        hand_taught(
            seed,
            k,
            &product_names,
            &layout.positions,
            &taught_slots,
            (sequence, &priority),
        )
    });
    let (demos, demonstrations, repeat) = match &hand {
        Some(orders) => (
            orders
                .iter()
                .map(|o| format!("{name}_seen{}", o.number))
                .collect(),
            orders.len(),
            1,
        ),
        None => (
            vec![format!("{name}_teach")],
            demonstrations(m, taught_slots.len(), n) as usize * repeat,
            repeat,
        ),
    };

    // The text, in canonical layout.
    let mut t = String::new();
    let riser = if base[2] > 0 {
        format!(" The robot stands on a {} mm riser.", base[2])
    } else {
        String::new()
    };
    let _ = writeln!(
        t,
        "# {name}: a random cell from `packwright generate{}{} --seed {seed}`;",
        family.option(),
        variant.options()
    );
    let _ = writeln!(t, "# regenerate it rather than edit it.");
    let _ = writeln!(t, "# The box stands {}.", box_side.phrase());
    if family == Family::Compact {
        let _ = writeln!(t, "# The products wait beside it, on the same side.{riser}");
    } else {
        let _ = writeln!(t, "# The products wait {}.{riser}", pending_side.phrase());
    }
    t.push('\n');
    let _ = writeln!(t, "cell {name} {{");
    let _ = writeln!(t, "  robot ur10");
    let _ = writeln!(
        t,
        "  base ({}, {}, {})",
        metres(base[0]),
        metres(base[1]),
        metres(base[2])
    );
    let _ = writeln!(t, "  suction {suction} mm");
    if let Some(lift) = lift {
        let _ = writeln!(t, "  lift {lift} mm");
    }
    if let Some(speed) = speed {
        let _ = writeln!(t, "  speed {speed} %");
    }
    let _ = writeln!(
        t,
        "  pending {} to {}",
        point(layout.pending.min),
        point(layout.pending.max)
    );
    let [w, d, h] = layout.box_size;
    let _ = writeln!(
        t,
        "  box carton {} size ({w} mm, {d} mm, {h} mm)",
        point(layout.box_centre)
    );
    for (s, at) in &layout.slots {
        let _ = writeln!(t, "  slot {s} {}", point(*at));
    }
    let _ = writeln!(t, "}}");
    t.push('\n');
    for p in &products {
        let shape = if p.cube {
            format!("cube {} mm", p.size[0])
        } else {
            format!("box ({} mm, {} mm, {} mm)", p.size[0], p.size[1], p.size[2])
        };
        let mass = p
            .mass
            .map_or(String::new(), |cg| format!(" mass 0.{cg:02}"));
        let _ = writeln!(t, "product {} {shape}{mass}", p.name);
    }
    t.push('\n');
    let _ = writeln!(t, "inventory {inventory} for {name} {{");
    for (p, at) in products.iter().zip(&layout.positions) {
        let _ = writeln!(t, "  {} {}", p.name, point(*at));
    }
    let _ = writeln!(t, "}}");
    t.push('\n');
    if variant.reversed_stock {
        let _ = writeln!(
            t,
            "# The same products with their places reversed: every suite draws from here."
        );
        let _ = writeln!(t, "inventory {suite_inventory} for {name} {{");
        for (p, at) in products.iter().zip(layout.positions.iter().rev()) {
            let _ = writeln!(t, "  {} {}", p.name, point(*at));
        }
        let _ = writeln!(t, "}}");
        t.push('\n');
    }
    match &hand {
        Some(orders) => write_hand_taught(&mut t, &name, &inventory, orders, sequence),
        None => write_sparse_teaching(
            &mut t,
            SparseTeaching {
                demos: &demos[0],
                inventory: &inventory,
                n,
                m,
                demonstrations,
                priority: &priority,
                taught_slots: &taught_slots,
                untaught_slots: &untaught_slots,
                sequence,
                repeat,
                seed: demos_seed,
            },
        ),
    }
    for s in &suites {
        t.push('\n');
        let about = match s.kind {
            SuiteKind::Case1N => "# CASE 1 with the taught n, into any slot.".to_owned(),
            SuiteKind::Case1N1 => "# CASE 1 with one product more than taught.".to_owned(),
            SuiteKind::Case1N2 => "# CASE 1 with two products more than taught.".to_owned(),
            SuiteKind::Case2 => {
                format!(
                    "# CASE 2: a worker first packs 1 to {n} of the {} products.",
                    n + 1
                )
            }
            SuiteKind::Missing => {
                "# Missing stock: 1 or 2 of the products have not arrived.".to_owned()
            }
            SuiteKind::Untaught => {
                "# Untaught slots: every package uses a slot no demonstration used.".to_owned()
            }
        };
        let _ = writeln!(t, "{about}");
        let _ = writeln!(t, "scenarios {} for {suite_inventory} {{", s.name);
        let _ = writeln!(
            t,
            "  choose {} of {} into {}",
            s.n,
            product_names.join(", "),
            s.slots.join(", ")
        );
        match s.kind {
            SuiteKind::Case2 => {
                let _ = writeln!(t, "  human packs 1 to {n}");
            }
            SuiteKind::Missing => {
                let _ = writeln!(t, "  missing 1 to 2");
            }
            _ => {}
        }
        let _ = writeln!(t, "  jitter {JITTER_MM} mm");
        let _ = writeln!(t, "  count {}", s.count);
        let _ = writeln!(t, "  seed {}", s.seed);
        let _ = writeln!(t, "}}");
    }

    Generated {
        family,
        seed,
        name,
        text: t,
        inventory,
        suite_inventory,
        demos,
        variant,
        taught_n: n,
        sequence,
        priority,
        products: product_names,
        slots: slot_names,
        taught_slots,
        untaught_slots,
        repeat,
        demonstrations,
        box_side,
        pending_side,
        base: base.map(|v| v as f64 / 1000.0),
        speed,
        suites,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_compiler::{Compiled, MemoryLoader, check};
    use std::path::PathBuf;

    /// `text` (a generated cell's, or one made from it) checked as `g`'s
    /// file with the UR10's reach; a panic with the diagnostics if not.
    fn compiled(g: &Generated, text: &str) -> Compiled {
        let loader = MemoryLoader::new().with(g.file_name(), text.to_owned());
        check(
            &loader,
            &[PathBuf::from(g.file_name())],
            &crate::reach::RobotWorkspace::new(),
        )
        .unwrap_or_else(|failed| panic!("seed {}:\n{}\n{text}", g.seed, failed.render()))
    }

    #[test]
    fn demonstration_counts_follow_the_compiler() {
        // C(5,3) = 10 combinations, 5 kept, x 3! arrangements of 3 slots.
        assert_eq!(demonstrations(5, 3, 3), 30);
        // C(6,2) = 15, 7.5 rounds to 8, x 4 x 3.
        assert_eq!(demonstrations(6, 4, 2), 96);
        for n in 2..=3 {
            for m in n + 2..=10 {
                for (s, u) in slot_options(m, n) {
                    let r = repeat_for(m, s, u, n).unwrap() as u64;
                    let d = demonstrations(m, s - u, n) * r;
                    assert!((DEMOS_MIN..=DEMOS_MAX).contains(&d), "{m} {s} {u} {n}");
                }
            }
        }
        assert_eq!(metres(-50), "-0.050");
        assert_eq!(metres(0), "0.000");
        assert_eq!(metres(1234), "1.234");
    }

    #[test]
    fn a_generated_cell_compiles_cleanly_and_is_deterministic() {
        for seed in [0, 7, 123] {
            let g = family_cell(seed);
            assert_eq!(g, family_cell(seed));
            assert_eq!(packwright_grammar::format(&g.text).unwrap(), g.text);
            let compiled = compiled(&g, &g.text);
            assert_eq!(
                compiled.demonstrations().expect("demonstrations").len(),
                g.demonstrations
            );
            let names: Vec<&str> = compiled
                .expanded
                .suites
                .iter()
                .map(|s| s.name.as_str())
                .collect();
            assert_eq!(names, g.suite_names());
            assert!(g.untaught_slots.len() == 1 || g.untaught_slots.len() == 2);
        }
        assert_ne!(family_cell(1).text, family_cell(2).text);
    }

    #[test]
    fn a_cell_taught_in_another_order_is_the_same_cell() {
        for seed in 0..12 {
            let own = family_cell(seed);
            assert_eq!(family_cell_taught(seed, None), own);
            for rule in [Sequence::Ascending, Sequence::Descending, Sequence::Listed] {
                let g = family_cell_taught(seed, Some(rule));
                assert_eq!(g.sequence, rule, "seed {seed}");
                assert_eq!(g.demonstrations, own.demonstrations, "seed {seed}");
                assert_eq!(g.suites, own.suites, "seed {seed}");
                assert_eq!(
                    g.priority != g.products,
                    rule == Sequence::Listed,
                    "seed {seed}: a listed order is not the inventory order, and only it"
                );
                let before =
                    |text: &str| text.split("\n# Sparse teaching").next().map(str::to_owned);
                assert_eq!(before(&g.text), before(&own.text), "seed {seed}");
                compiled(&g, &g.text);
            }
        }
    }

    /// A cell taught by hand and stocked reversed is the seed's cell, with
    /// the seed's suites drawn from the reversed inventory, and its few
    /// demonstrations show the rule asked for.
    #[test]
    fn a_hand_taught_cell_is_the_seeds_cell_taught_by_hand() {
        use crate::teach::cell_rule;
        use packwright_interface::SequenceRule;
        let variant = Variant {
            hand: Some(3),
            reversed_stock: true,
        };
        for seed in 0..8 {
            for (rule, expected) in [
                (Sequence::Ascending, SequenceRule::Ascending),
                (Sequence::Descending, SequenceRule::Descending),
            ] {
                let own = family_cell_taught(seed, Some(rule));
                let g = generated_variant(Family::Standard, seed, Some(rule), variant);
                assert_eq!(
                    g,
                    generated_variant(Family::Standard, seed, Some(rule), variant)
                );
                assert_eq!(g.suites, own.suites, "seed {seed}");
                assert_eq!((g.demonstrations, g.demos.len()), (3, 3), "seed {seed}");
                // Below the header line, the cell, its products and its
                // first inventory are the seed's.
                let body = |text: &str| {
                    let after_header = text.split_once('\n').map_or("", |(_, rest)| rest);
                    after_header.split("\n\n#").next().map(str::to_owned)
                };
                assert_eq!(body(&g.text), body(&own.text), "seed {seed}");
                assert!(g.text.contains(&format!(
                    "\ninventory {} for {} {{\n",
                    g.suite_inventory, g.name
                )));
                for suite in &g.suites {
                    let line = format!("\nscenarios {} for {} {{\n", suite.name, g.suite_inventory);
                    assert!(g.text.contains(&line), "seed {seed}: {line}");
                }
                assert_eq!(packwright_grammar::format(&g.text).unwrap(), g.text);
                let compiled = compiled(&g, &g.text);
                assert_eq!(compiled.demonstrations().expect("demonstrations").len(), 3);
                let inferred = cell_rule(&compiled, &g.name)
                    .expect("one rule")
                    .expect("demonstrations");
                assert_eq!(inferred.rule, expected, "seed {seed}");
                assert!(inferred.exceptions.is_empty(), "seed {seed}");
            }
        }
    }

    /// The rule a cell's own demonstrations follow is read from its file
    /// (what a model not taught the cell packs it in): each of the three,
    /// and none for a cell without demonstrations.
    #[test]
    fn a_cells_rule_is_read_from_its_demonstrations() {
        use crate::teach::cell_rule;
        use packwright_interface::SequenceRule;
        for (rule, seed) in [
            (Sequence::Ascending, 3),
            (Sequence::Descending, 3),
            (Sequence::Listed, 4),
        ] {
            let g = family_cell_taught(seed, Some(rule));
            let compiled = compiled(&g, &g.text);
            let inferred = cell_rule(&compiled, &g.name)
                .expect("one rule")
                .expect("demonstrations");
            // A listed order is read as the block writes it, the pairs no
            // demonstration handled together included.
            match (rule, &inferred.rule) {
                (Sequence::Ascending, SequenceRule::Ascending)
                | (Sequence::Descending, SequenceRule::Descending) => {}
                (Sequence::Listed, SequenceRule::Listed(list)) => {
                    assert_eq!(list, &g.priority, "seed {seed}");
                }
                other => panic!("seed {seed}: {other:?}"),
            }
            assert!(inferred.exceptions.is_empty(), "seed {seed}");
            assert!(
                cell_rule(&compiled, "elsewhere")
                    .expect("no error")
                    .is_none()
            );
        }
        // Demonstrations of a `sequence random` block show no order: no
        // rule is read from them, and `execute` and `eval` keep the
        // model's.
        let g = family_cell_taught(3, Some(Sequence::Ascending));
        let text = g
            .text
            .replace("  sequence ascending\n", "  sequence random\n");
        assert_ne!(text, g.text);
        let compiled = compiled(&g, &text);
        assert_eq!(cell_rule(&compiled, &g.name).ok(), Some(None));
    }
}
