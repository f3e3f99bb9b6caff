//! Phase 2: resolve names and statements into the [`Model`]. Reports
//! duplicate and unknown names (with suggestions), missing and repeated
//! statements, and value ranges that need no geometry. Items whose own
//! references fail are left out of the model but keep their name, so that
//! their users are not reported again (no cascades).

use crate::error::Error;
use crate::model::*;
use crate::source::{FileId, Loader, Loc, SourceMap, normalize};
use packwright_grammar::ast::{self, SequenceMode};
use packwright_grammar::closest;
use std::collections::HashMap;
use std::path::Path;

/// A namespace of one kind of item.
struct Table {
    kind: &'static str,
    /// Name -> (index in the model, or `None` if the item is broken; where).
    names: HashMap<String, (Option<usize>, Loc)>,
    listed: Vec<String>,
}

enum Lookup {
    Found(usize),
    /// Defined, but broken: its error was already reported.
    Broken,
    Unknown,
}

impl Table {
    fn new(kind: &'static str) -> Table {
        Table {
            kind,
            names: HashMap::new(),
            listed: Vec::new(),
        }
    }

    /// Declares a name; reports a duplicate (and returns false) if taken.
    fn declare(&mut self, name: &str, at: Loc, errors: &mut Vec<Error>) -> bool {
        if let Some((_, first)) = self.names.get(name) {
            errors.push(Error::Duplicate {
                at,
                first: *first,
                kind: self.kind,
                name: name.to_owned(),
            });
            return false;
        }
        self.names.insert(name.to_owned(), (None, at));
        self.listed.push(name.to_owned());
        true
    }

    fn set_index(&mut self, name: &str, index: usize) {
        if let Some(entry) = self.names.get_mut(name) {
            entry.0 = Some(index);
        }
    }

    fn lookup(&self, name: &str) -> Lookup {
        match self.names.get(name) {
            Some((Some(i), _)) => Lookup::Found(*i),
            Some((None, _)) => Lookup::Broken,
            None => Lookup::Unknown,
        }
    }

    /// Resolves a reference, reporting an unknown name.
    fn resolve(&self, name: &ast::Name, file: FileId, errors: &mut Vec<Error>) -> Option<usize> {
        match self.lookup(&name.text) {
            Lookup::Found(i) => Some(i),
            Lookup::Broken => None,
            Lookup::Unknown => {
                errors.push(unknown(
                    self.kind,
                    name,
                    file,
                    format!("the {}", plural(self.kind)),
                    &self.listed,
                ));
                None
            }
        }
    }
}

pub fn plural(kind: &str) -> String {
    match kind.strip_suffix('y') {
        Some(stem) => format!("{stem}ies"),
        None => format!("{kind}s"),
    }
}

fn unknown(
    kind: &'static str,
    name: &ast::Name,
    file: FileId,
    scope: String,
    known: &[String],
) -> Error {
    Error::Unknown {
        at: Loc::new(file, name.span),
        kind,
        name: name.text.clone(),
        scope,
        suggestion: closest(&name.text, known.iter().map(String::as_str)).map(str::to_owned),
        known: known.to_vec(),
    }
}

/// A statement that may be given at most once.
struct Once<T> {
    statement: &'static str,
    value: Option<(T, Loc)>,
}

impl<T> Once<T> {
    fn new(statement: &'static str) -> Once<T> {
        Once {
            statement,
            value: None,
        }
    }

    fn set(&mut self, value: T, at: Loc, errors: &mut Vec<Error>) {
        match &self.value {
            Some((_, first)) => errors.push(Error::StatementTwice {
                at,
                first: *first,
                statement: self.statement,
            }),
            None => self.value = Some((value, at)),
        }
    }

    fn get(self) -> Option<T> {
        self.value.map(|(v, _)| v)
    }

    fn loc(&self) -> Option<Loc> {
        self.value.as_ref().map(|(_, l)| *l)
    }

    /// The value, or a "missing statement" error on the block.
    fn required(
        self,
        block: Loc,
        item: String,
        example: impl Into<String>,
        errors: &mut Vec<Error>,
    ) -> Option<T> {
        if self.value.is_none() {
            errors.push(Error::MissingStatement {
                at: block,
                item,
                statement: self.statement,
                example: example.into(),
            });
        }
        self.get()
    }
}

struct Resolver<'a> {
    loader: &'a dyn Loader,
    sources: &'a SourceMap,
    errors: Vec<Error>,
    model: Model,
    cells: Table,
    products: Table,
    inventories: Table,
    orders: Table,
    demos: Table,
    scenarios: Table,
}

pub fn resolve(
    loader: &dyn Loader,
    sources: &SourceMap,
    files: &[(FileId, ast::File)],
) -> (Model, Vec<Error>) {
    let mut r = Resolver {
        loader,
        sources,
        errors: Vec::new(),
        model: Model::default(),
        cells: Table::new("cell"),
        products: Table::new("product"),
        inventories: Table::new("inventory"),
        orders: Table::new("order"),
        demos: Table::new("demonstration"),
        scenarios: Table::new("scenario"),
    };
    // Items refer only to kinds resolved before them, in this order.
    let items = || {
        files
            .iter()
            .flat_map(|(f, file)| file.items.iter().map(move |i| (*f, i)))
    };
    for (f, item) in items() {
        match item {
            ast::Item::Cell(c) => r.cell(f, c),
            ast::Item::Product(p) => r.product(f, p),
            _ => {}
        }
    }
    for (f, item) in items() {
        if let ast::Item::Inventory(i) = item {
            r.inventory(f, i);
        }
    }
    for (f, item) in items() {
        if let ast::Item::Order(o) = item {
            r.order(f, o);
        }
    }
    for (f, item) in items() {
        match item {
            ast::Item::Demo(d) => r.demo(f, d),
            ast::Item::Demos(d) => r.demo_set(f, d),
            ast::Item::Scenario(s) => r.scenario(f, s),
            ast::Item::Scenarios(s) => r.scenario_set(f, s),
            _ => {}
        }
    }
    (r.model, r.errors)
}

fn xy(p: &ast::Point) -> [f64; 2] {
    [p.x.metres, p.y.metres]
}

/// Whether the pending area and every box lie within
/// [`WORKSPACE_RADIUS`] of the base (and every box is smaller); else an
/// error for each that does not. Farther lengths are typos, and would
/// make every later distance and picture meaningless.
fn within_workspace(
    base: [f64; 3],
    pending: Rect,
    pending_at: Loc,
    boxes: &[BoxDef],
    errors: &mut Vec<Error>,
) -> bool {
    // Areas and boxes stand on the table (z = 0): a base written in
    // millimetres (`base (0, 0, 400)`) puts them 400 m below it.
    let farthest = |r: &Rect| {
        let dx = (r.min[0] - base[0]).abs().max((r.max[0] - base[0]).abs());
        let dy = (r.min[1] - base[1]).abs().max((r.max[1] - base[1]).abs());
        dx.hypot(dy).hypot(base[2])
    };
    let mut far = vec![(
        "the pending area".to_string(),
        pending_at,
        farthest(&pending),
    )];
    for b in boxes {
        let size = b.size.iter().copied().fold(0.0, f64::max);
        far.push((
            format!("box `{}`", b.name),
            b.loc,
            farthest(&b.footprint()).max(size),
        ));
    }
    let mut ok = true;
    for (what, at, distance) in far {
        if distance.is_nan() || distance > WORKSPACE_RADIUS {
            errors.push(Error::FarFromBase {
                at,
                what,
                distance,
                max: WORKSPACE_RADIUS,
            });
            ok = false;
        }
    }
    ok
}

/// The farthest a cell's base, pending area or boxes may lie from the
/// origin on any axis (m): the simulator works in single precision, which
/// keeps about 10 µm there (`packwright_sim`'s own limit, which refused
/// such a cell only in `execute`).
pub const MAX_COORDINATE: f64 = 100.0;

/// Whether the base, the pending area and every box (already within
/// [`WORKSPACE_RADIUS`] of the base) lie within [`MAX_COORDINATE`] of
/// the origin on every axis; else one error, at the base: a cell moved
/// far from the origin (its coordinates in a plant's frame) is moved back
/// as a whole.
fn near_origin(
    base: [f64; 3],
    base_at: Loc,
    pending: Rect,
    boxes: &[BoxDef],
    errors: &mut Vec<Error>,
) -> bool {
    let corners = |r: Rect| [r.min[0], r.min[1], r.max[0], r.max[1]];
    let farthest = base
        .into_iter()
        .chain(corners(pending))
        .chain(boxes.iter().flat_map(|b| corners(b.footprint())))
        .map(f64::abs)
        .fold(0.0, f64::max);
    if farthest <= MAX_COORDINATE {
        return true;
    }
    errors.push(Error::FarFromOrigin {
        at: base_at,
        coordinate: farthest,
        max: MAX_COORDINATE,
    });
    false
}

/// How to write a length that must be above zero.
const POSITIVE_LENGTH: &str = "write a positive length";

/// The lightest product mass, kilograms: the simulator's lightest body.
pub const MIN_MASS: f64 = 0.001;
/// The heaviest product mass, kilograms: the UR10's rated payload.
pub const MAX_MASS: f64 = 10.0;

/// The largest side a product may have (m): a box of it held by the cup
/// would reach past the UR10's 1.3 m from any slot.
pub const MAX_PRODUCT_SIZE: f64 = 1.0;
/// The shortest product side (m): the simulator builds nothing thinner.
pub const MIN_PRODUCT_SIZE: f64 = 0.001;

impl Resolver<'_> {
    /// Whether `value` is above zero; else an error saying that `what`
    /// must be, and how to write it (`fix`).
    fn positive(&mut self, value: f64, at: Loc, what: &str, fix: &str) -> bool {
        if value > 0.0 {
            return true;
        }
        self.errors.push(Error::BadGeometry {
            at,
            what: format!("{what} must be greater than zero"),
            fix: fix.into(),
        });
        false
    }

    /// A bare mass this large is taken for grams in the fix
    /// ([`Resolver::mass_in_range`]).
    const GRAMS_LIKELY: f64 = 100.0;

    /// Whether a product's mass `kg` is one the robot world handles: from
    /// [`MIN_MASS`] (the simulator's lightest) to [`MAX_MASS`] (the UR10's
    /// rated payload); else an error saying so (a bare number in range
    /// as grams: "did you mean `300 g`?").
    fn mass_in_range(&mut self, mass: &ast::Mass, at: Loc) -> bool {
        let kg = mass.kg;
        if (MIN_MASS..=MAX_MASS).contains(&kg) {
            return true;
        }
        let what = if kg < MIN_MASS {
            "a mass must be at least 1 g"
        } else {
            "a mass must be at most 10 kg"
        };
        let range = "a mass from 0.001 (1 g) to 10 kg: the simulator models products from 1 g, and a UR10 carries at most 10 kg (its rated payload)";
        // A bare 100 or more is no product's kilograms, and in range as
        // grams (40 might be an anvil's kilograms).
        let grams = mass.unit.is_none()
            && kg >= Self::GRAMS_LIKELY
            && (MIN_MASS..=MAX_MASS).contains(&(kg / 1000.0));
        let fix = if grams {
            format!(
                "a bare mass is in kilograms: did you mean `{} g`? Write {range}",
                mass.number
            )
        } else {
            format!("write {range}")
        };
        self.errors.push(Error::BadGeometry {
            at,
            what: what.into(),
            fix,
        });
        false
    }

    /// Whether `value` (m) lies within `range` (m); else an error naming
    /// `what`, the range, and `why` the range.
    fn bounded(&mut self, value: f64, at: Loc, what: &str, range: (f64, f64), why: &str) -> bool {
        let (lo, hi) = range;
        if (lo..=hi).contains(&value) {
            return true;
        }
        let mm = |v: f64| format!("{:.0} mm", v * 1000.0);
        self.errors.push(Error::BadGeometry {
            at,
            what: format!("{what} must be between {} and {}", mm(lo), mm(hi)),
            fix: format!("write a length from {} to {}: {why}", mm(lo), mm(hi)),
        });
        false
    }

    /// One limit per joint, each in `range` (reported in `unit`): the
    /// values, or `None` after reporting a wrong count or each value out
    /// of range.
    fn joint_values(
        &mut self,
        f: FileId,
        v: &ast::JointValues,
        statement: &'static str,
        (min, max): (f64, f64),
        unit: &'static str,
    ) -> Option<[f64; ARM_JOINTS]> {
        let Ok(values) = <[ast::Fraction; ARM_JOINTS]>::try_from(v.values.clone()) else {
            self.errors.push(Error::JointCount {
                at: Loc::new(f, v.span),
                statement,
                found: v.values.len(),
                expected: ARM_JOINTS,
            });
            return None;
        };
        let mut ok = true;
        for (j, value) in values.iter().enumerate() {
            if !(min..=max).contains(&value.value) {
                self.errors.push(Error::JointLimitOutOfRange {
                    at: Loc::new(f, value.span),
                    statement,
                    joint: j + 1,
                    value: value.value,
                    min,
                    max,
                    unit,
                });
                ok = false;
            }
        }
        ok.then(|| values.map(|v| v.value))
    }

    /// A position on the table: `(x, y)`, or `(x, y, 0)`. Products stand
    /// on the table and box floors lie on it, so another height is an error.
    fn table_point(&mut self, p: &ast::Point, f: FileId) -> [f64; 2] {
        if let Some(z) = p.z.as_ref().filter(|z| z.metres != 0.0) {
            self.errors.push(Error::BadGeometry {
                at: Loc::new(f, z.span),
                what: format!(
                    "a position on the table must be at z = 0, not at z = {} m",
                    z.metres
                ),
                fix: "write `(x, y)` or `(x, y, 0)`: products stand on the table and box floors lie on it; \
                      heights are measured from the table, and a robot on a riser has its `base` higher"
                    .into(),
            });
        }
        xy(p)
    }

    fn cell(&mut self, f: FileId, c: &ast::Cell) {
        let at = Loc::new(f, c.name.span);
        if !self.cells.declare(&c.name.text, at, &mut self.errors) {
            return;
        }
        let block = Loc::new(f, c.span);
        let mut robot = Once::new("robot");
        let mut robot_path_at: Option<Loc> = None;
        let mut base = Once::new("base");
        let mut suction = Once::new("suction");
        let mut pending = Once::new("pending");
        let mut lift = Once::new("lift");
        let mut speed = Once::new("speed");
        let mut grip_settle = Once::new("settle … after grip");
        let mut release_settle = Once::new("settle … after release");
        let mut descent = Once::new("descent");
        let mut acceleration = Once::new("acceleration");
        let mut jerk = Once::new("jerk");
        let mut boxes: Vec<BoxDef> = Vec::new();
        let mut slots: Vec<Slot> = Vec::new();
        let mut ok = true;
        for st in &c.stmts {
            let sl = Loc::new(f, st.span);
            match &st.kind {
                ast::CellStmt::Robot(ast::Robot::Ur10) => {
                    robot.set(RobotModel::Ur10, sl, &mut self.errors)
                }
                ast::CellStmt::Robot(ast::Robot::Urdf(path)) => {
                    let dir = self
                        .sources
                        .get(f)
                        .and_then(|s| s.path.parent())
                        .map(Path::to_path_buf)
                        .unwrap_or_default();
                    let full = normalize(&dir.join(&path.value));
                    if let Err(reason) = self.loader.read_named(&full) {
                        self.errors.push(Error::RobotFileMissing {
                            at: Loc::new(f, path.span),
                            path: full.display().to_string(),
                            reason,
                        });
                        ok = false;
                    }
                    robot_path_at.get_or_insert(Loc::new(f, path.span));
                    robot.set(
                        RobotModel::Urdf(full.display().to_string()),
                        sl,
                        &mut self.errors,
                    );
                }
                ast::CellStmt::Base(p) => {
                    let z = p.z.as_ref().map_or(0.0, |z| z.metres);
                    // A base below the table puts the arm inside it: every
                    // pose would collide, and the reach check would only
                    // say that the start pose cannot be reached.
                    if let Some(at) = p.z.as_ref().filter(|z| z.metres < 0.0) {
                        self.errors.push(Error::BadGeometry {
                            at: Loc::new(f, at.span),
                            what: format!(
                                "the robot's base is {} m below the table; it must stand on the table or on a riser (z ≥ 0)",
                                -z
                            ),
                            fix: "heights are measured from the table top, where the products stand: write `base (x, y)` for a robot on the table, or `base (x, y, h)` with h > 0 for one on a riser".into(),
                        });
                        ok = false;
                    }
                    base.set([p.x.metres, p.y.metres, z], sl, &mut self.errors);
                }
                ast::CellStmt::Suction(l) => {
                    ok &= self.bounded(
                        l.metres,
                        Loc::new(f, l.span),
                        "the suction cup's length (flange to cup tip)",
                        SUCTION_RANGE,
                        "a longer cup puts the sub-goals out of the arm's reach, a shorter one brings the wrist against the products",
                    );
                    suction.set(l.metres, sl, &mut self.errors);
                }
                ast::CellStmt::Lift(l) => {
                    ok &= self.bounded(
                        l.metres,
                        Loc::new(f, l.span),
                        "the lift height",
                        LIFT_RANGE,
                        "a lower lift drags the product over the table, a higher one carries it out of the arm's reach",
                    );
                    lift.set(l.metres, sl, &mut self.errors);
                }
                ast::CellStmt::Speed(s) => {
                    let (lo, hi) = SPEED_RANGE;
                    if !(lo..=hi).contains(&s.value) {
                        self.errors.push(Error::SpeedOutOfRange {
                            at: Loc::new(f, s.span),
                            percent: s.value * 100.0,
                            min_percent: lo * 100.0,
                            bare: !s.percent,
                        });
                        ok = false;
                    }
                    speed.set(s.value, sl, &mut self.errors);
                }
                ast::CellStmt::Acceleration(v) => {
                    let values =
                        self.joint_values(f, v, "acceleration", ACCELERATION_RANGE, "rad/s²");
                    ok &= values.is_some();
                    acceleration.set(values, sl, &mut self.errors);
                }
                ast::CellStmt::Jerk(v) => {
                    let values = self.joint_values(f, v, "jerk", JERK_RANGE, "rad/s³");
                    ok &= values.is_some();
                    jerk.set(values, sl, &mut self.errors);
                }
                ast::CellStmt::Descent(s) => {
                    let (lo, hi) = DESCENT_RANGE;
                    if !(lo..=hi).contains(&s.value) {
                        self.errors.push(Error::DescentOutOfRange {
                            at: Loc::new(f, s.span),
                            percent: s.value * 100.0,
                            min_percent: lo * 100.0,
                            bare: !s.percent,
                        });
                        ok = false;
                    }
                    descent.set(s.value, sl, &mut self.errors);
                }
                ast::CellStmt::Settle { time, after } => {
                    let (lo, hi) = SETTLE_RANGE;
                    if !(lo..=hi).contains(&time.seconds) {
                        self.errors.push(Error::SettleOutOfRange {
                            at: Loc::new(f, time.span),
                            after: after.as_str(),
                            ms: time.seconds * 1000.0,
                            min_ms: lo * 1000.0,
                            max_ms: hi * 1000.0,
                        });
                        ok = false;
                    }
                    let once = match after {
                        ast::SettleAfter::Grip => &mut grip_settle,
                        ast::SettleAfter::Release => &mut release_settle,
                    };
                    once.set(time.seconds, sl, &mut self.errors);
                }
                ast::CellStmt::Pending(a, b) => {
                    let (a, b) = (self.table_point(a, f), self.table_point(b, f));
                    let rect = Rect {
                        min: [a[0].min(b[0]), a[1].min(b[1])],
                        max: [a[0].max(b[0]), a[1].max(b[1])],
                    };
                    if rect.max[0] - rect.min[0] <= 0.0 || rect.max[1] - rect.min[1] <= 0.0 {
                        self.errors.push(Error::BadGeometry {
                            at: sl,
                            what: "the pending area has no surface".into(),
                            fix: "give two opposite corners: `pending (x0, y0) to (x1, y1)`".into(),
                        });
                        ok = false;
                    }
                    pending.set(rect, sl, &mut self.errors);
                }
                ast::CellStmt::Box { name, at, size } => {
                    let nl = Loc::new(f, name.span);
                    if let Some(first) = boxes.iter().find(|b| b.name == name.text) {
                        self.errors.push(Error::Duplicate {
                            at: nl,
                            first: first.loc,
                            kind: "box",
                            name: name.text.clone(),
                        });
                        ok = false;
                        continue;
                    }
                    let Some(h) = &size.z else {
                        self.errors.push(Error::BadGeometry {
                            at: Loc::new(f, size.span),
                            what: "a box size needs width, depth and height".into(),
                            fix: "write `size (w, d, h)`".into(),
                        });
                        ok = false;
                        continue;
                    };
                    let dims = [size.x.metres, size.y.metres, h.metres];
                    if dims.iter().any(|d| *d <= 0.0) {
                        ok &= self.positive(
                            0.0,
                            Loc::new(f, size.span),
                            "every box dimension",
                            POSITIVE_LENGTH,
                        );
                    }
                    boxes.push(BoxDef {
                        name: name.text.clone(),
                        loc: nl,
                        centre: self.table_point(at, f),
                        size: dims,
                    });
                }
                ast::CellStmt::Slot { name, at } => {
                    let nl = Loc::new(f, name.span);
                    if let Some(first) = slots.iter().find(|s| s.name == name.text) {
                        self.errors.push(Error::Duplicate {
                            at: nl,
                            first: first.loc,
                            kind: "slot",
                            name: name.text.clone(),
                        });
                        ok = false;
                        continue;
                    }
                    if boxes.is_empty() {
                        self.errors.push(Error::SlotBeforeBox {
                            at: nl,
                            slot: name.text.clone(),
                        });
                        ok = false;
                        continue;
                    }
                    slots.push(Slot {
                        name: name.text.clone(),
                        loc: nl,
                        at: self.table_point(at, f),
                        box_index: boxes.len() - 1,
                    });
                }
            }
        }
        let item = format!("cell `{}`", c.name.text);
        let e = &mut self.errors;
        let robot_at = robot_path_at.or(robot.loc()).unwrap_or(at);
        let pending_at = pending.loc().unwrap_or(block);
        let robot = robot.required(block, item.clone(), "robot ur10", e);
        let base_at = base.loc().unwrap_or(block);
        let base = base.required(block, item.clone(), "base (0, 0, 0)", e);
        let suction = suction.required(block, item.clone(), "suction 100 mm", e);
        let pending = pending.required(
            block,
            item.clone(),
            "pending (0.45, -0.50) to (0.85, -0.10)",
            e,
        );
        let lift = lift.get().unwrap_or(DEFAULT_LIFT);
        let speed = speed.get().unwrap_or(1.0);
        let grip_settle = grip_settle.get().unwrap_or(DEFAULT_GRIP_SETTLE);
        let release_settle = release_settle.get().unwrap_or(DEFAULT_RELEASE_SETTLE);
        let descent = descent.get().unwrap_or(1.0);
        let acceleration = acceleration.get().flatten();
        let jerk = jerk.get().flatten();
        if boxes.is_empty() {
            e.push(Error::MissingStatement {
                at: block,
                item: item.clone(),
                statement: "box",
                example: "box tray (0.00, 0.65) size (0.40, 0.30, 0.08)".into(),
            });
            ok = false;
        } else if slots.is_empty() {
            e.push(Error::MissingStatement {
                at: block,
                item,
                statement: "slot",
                example: "slot g1 (0.00, 0.60)".into(),
            });
            ok = false;
        }
        if let (Some(base), Some(pending)) = (base, pending) {
            ok &= within_workspace(base, pending, pending_at, &boxes, e)
                && near_origin(base, base_at, pending, &boxes, e);
        }
        let (Some(robot), Some(base), Some(suction), Some(pending), true) =
            (robot, base, suction, pending, ok)
        else {
            return;
        };
        self.cells.set_index(&c.name.text, self.model.cells.len());
        self.model.cells.push(Cell {
            name: c.name.text.clone(),
            loc: at,
            robot,
            robot_at,
            base,
            suction,
            pending,
            pending_loc: pending_at,
            lift,
            speed,
            grip_settle,
            release_settle,
            descent,
            acceleration,
            jerk,
            boxes,
            slots,
        });
    }

    fn product(&mut self, f: FileId, p: &ast::Product) {
        let at = Loc::new(f, p.name.span);
        if !self.products.declare(&p.name.text, at, &mut self.errors) {
            return;
        }
        let size = match &p.shape {
            ast::Shape::Cube(l) => [l.metres; 3],
            ast::Shape::Box(s) => match &s.z {
                Some(h) => [s.x.metres, s.y.metres, h.metres],
                None => {
                    self.errors.push(Error::BadGeometry {
                        at: Loc::new(f, s.span),
                        what: "a box product needs width, depth and height".into(),
                        fix: "write `box (w, d, h)`".into(),
                    });
                    return;
                }
            },
        };
        let shape_span = match &p.shape {
            ast::Shape::Cube(l) => l.span,
            ast::Shape::Box(s) => s.span,
        };
        if size.iter().any(|d| *d <= 0.0) {
            self.positive(
                0.0,
                Loc::new(f, shape_span),
                "every product dimension",
                POSITIVE_LENGTH,
            );
            return;
        }
        // A product larger than the arm could ever carry into a box is a
        // unit slip (`60 m` for `60 mm`): said on its own line, rather
        // than as its overlaps and misfits everywhere it is used.
        let lengths: Vec<&ast::Length> = match &p.shape {
            ast::Shape::Cube(l) => vec![l],
            ast::Shape::Box(s) => [Some(&s.x), Some(&s.y), s.z.as_ref()]
                .into_iter()
                .flatten()
                .collect(),
        };
        let oversized: Vec<&ast::Length> = lengths
            .iter()
            .copied()
            .filter(|l| l.metres > MAX_PRODUCT_SIZE)
            .collect();
        for l in &oversized {
            // `60 m` for `60 mm` is a slip of the unit; `1.2 m` could be
            // 120 mm or 12 cm: no guess.
            let whole = !l.number.contains('.');
            let fix = match l.unit {
                Some(ast::LengthUnit::M) if whole => format!(
                    "did you mean `{} mm`? A product is at most 1 m on a side: the UR10 reaches 1.3 m",
                    l.number
                ),
                _ => "check the unit (sizes are metres unless they carry `mm` or `cm`): a product is at most 1 m on a side, the UR10 reaches 1.3 m".to_owned(),
            };
            self.errors.push(Error::BadGeometry {
                at: Loc::new(f, l.span),
                what: "a product side must be at most 1 m".into(),
                fix,
            });
        }
        let thin: Vec<&ast::Length> = lengths
            .iter()
            .copied()
            .filter(|l| l.metres < MIN_PRODUCT_SIZE)
            .collect();
        for l in &thin {
            self.errors.push(Error::BadGeometry {
                at: Loc::new(f, l.span),
                what: "a product side must be at least 1 mm".into(),
                fix: "check the number and its unit (sizes are metres unless they carry `mm` or `cm`): nothing thinner than 1 mm can be picked by a suction cup".into(),
            });
        }
        if !oversized.is_empty() || !thin.is_empty() {
            return;
        }
        if let Some(m) = &p.mass
            && !(self.positive(
                m.kg,
                Loc::new(f, m.span),
                "a mass",
                "write the mass in kilograms, above zero (`mass 0.3`)",
            ) && self.mass_in_range(m, Loc::new(f, m.span)))
        {
            return;
        }
        self.products
            .set_index(&p.name.text, self.model.products.len());
        self.model.products.push(Product {
            name: p.name.text.clone(),
            loc: at,
            size,
            mass: p.mass.as_ref().map(|m| m.kg),
        });
    }

    fn inventory(&mut self, f: FileId, inv: &ast::Inventory) {
        let at = Loc::new(f, inv.name.span);
        if !self
            .inventories
            .declare(&inv.name.text, at, &mut self.errors)
        {
            return;
        }
        let cell = self.cells.resolve(&inv.cell, f, &mut self.errors);
        let mut ok = cell.is_some();
        let mut entries: Vec<Entry> = Vec::new();
        for st in &inv.entries {
            let e = &st.kind;
            let Some(product) = self.products.resolve(&e.product, f, &mut self.errors) else {
                ok = false;
                continue;
            };
            let pl = Loc::new(f, e.product.span);
            if let Some(first) = entries.iter().find(|x| x.product == product) {
                self.errors.push(Error::ListedTwice {
                    at: pl,
                    first: first.loc,
                    what: "product",
                    name: e.product.text.clone(),
                });
                ok = false;
                continue;
            }
            entries.push(Entry {
                product,
                at: self.table_point(&e.at, f),
                loc: pl,
            });
        }
        if inv.entries.is_empty() {
            self.errors.push(Error::MissingStatement {
                at: Loc::new(f, inv.span),
                item: format!("inventory `{}`", inv.name.text),
                statement: "PRODUCT (x, y)",
                example: "A (0.50, -0.20)".into(),
            });
            ok = false;
        }
        let (Some(cell), true) = (cell, ok) else {
            return;
        };
        self.inventories
            .set_index(&inv.name.text, self.model.inventories.len());
        self.model.inventories.push(Inventory {
            name: inv.name.text.clone(),
            loc: at,
            cell,
            entries,
        });
    }

    /// Finds a product among an inventory's entries.
    fn entry(&mut self, inv: usize, name: &ast::Name, f: FileId) -> Option<usize> {
        let inventory = &self.model.inventories[inv];
        let found = inventory
            .entries
            .iter()
            .position(|e| self.model.products[e.product].name == name.text);
        if found.is_none() {
            let known: Vec<String> = inventory
                .entries
                .iter()
                .map(|e| self.model.products[e.product].name.clone())
                .collect();
            let scope = format!("inventory `{}`", inventory.name);
            self.errors.push(unknown("product", name, f, scope, &known));
        }
        found
    }

    /// Finds a slot in an inventory's cell.
    fn slot(&mut self, inv: usize, name: &ast::Name, f: FileId) -> Option<usize> {
        let cell = &self.model.cells[self.model.inventories[inv].cell];
        let found = cell.slots.iter().position(|s| s.name == name.text);
        if found.is_none() {
            let known: Vec<String> = cell.slots.iter().map(|s| s.name.clone()).collect();
            let scope = format!("cell `{}`", cell.name);
            self.errors.push(unknown("slot", name, f, scope, &known));
        }
        found
    }

    /// Resolves a list of products in an inventory, reporting repeats.
    fn entry_list(&mut self, inv: usize, names: &[ast::Name], f: FileId) -> Option<Vec<usize>> {
        let mut out: Vec<(usize, Loc)> = Vec::new();
        let mut ok = true;
        for n in names {
            let Some(e) = self.entry(inv, n, f) else {
                ok = false;
                continue;
            };
            let at = Loc::new(f, n.span);
            if let Some((_, first)) = out.iter().find(|(x, _)| *x == e) {
                self.errors.push(Error::ListedTwice {
                    at,
                    first: *first,
                    what: "product",
                    name: n.text.clone(),
                });
                ok = false;
                continue;
            }
            out.push((e, at));
        }
        ok.then(|| out.into_iter().map(|(e, _)| e).collect())
    }

    fn order(&mut self, f: FileId, o: &ast::Order) {
        let at = Loc::new(f, o.name.span);
        if !self.orders.declare(&o.name.text, at, &mut self.errors) {
            return;
        }
        let Some(inv) = self.inventories.resolve(&o.inventory, f, &mut self.errors) else {
            return;
        };
        let mut customer = Once::new("customer");
        let mut batch = Once::new("batch");
        let mut assignment: Vec<Assign> = Vec::new();
        let mut ok = true;
        for st in &o.stmts {
            let sl = Loc::new(f, st.span);
            match &st.kind {
                ast::OrderStmt::Customer(s) => customer.set(s.value.clone(), sl, &mut self.errors),
                ast::OrderStmt::Batch(c) => {
                    if c.value == 0 {
                        self.errors.push(Error::Zero {
                            at: Loc::new(f, c.span),
                            statement: "batch",
                        });
                        ok = false;
                    }
                    batch.set(c.value, sl, &mut self.errors);
                }
                ast::OrderStmt::Assign { product, slot } => {
                    let e = self.entry(inv, product, f);
                    let s = self.slot(inv, slot, f);
                    let (Some(entry), Some(slot_index)) = (e, s) else {
                        ok = false;
                        continue;
                    };
                    if let Some(first) = assignment.iter().find(|a| a.entry == entry) {
                        self.errors.push(Error::ListedTwice {
                            at: Loc::new(f, product.span),
                            first: first.loc,
                            what: "product",
                            name: product.text.clone(),
                        });
                        ok = false;
                        continue;
                    }
                    if let Some(first) = assignment.iter().find(|a| a.slot == slot_index) {
                        let inventory = &self.model.inventories[inv];
                        let other =
                            &self.model.products[inventory.entries[first.entry].product].name;
                        self.errors.push(Error::SlotTaken {
                            at: Loc::new(f, slot.span),
                            first: first.loc,
                            slot: slot.text.clone(),
                            product: product.text.clone(),
                            other: other.clone(),
                        });
                        ok = false;
                        continue;
                    }
                    assignment.push(Assign {
                        entry,
                        slot: slot_index,
                        loc: Loc::new(f, product.span),
                    });
                }
            }
        }
        if o.stmts
            .iter()
            .all(|s| !matches!(s.kind, ast::OrderStmt::Assign { .. }))
        {
            self.errors.push(Error::MissingStatement {
                at: Loc::new(f, o.span),
                item: format!("order `{}`", o.name.text),
                statement: "PRODUCT -> SLOT",
                example: "A -> g1".into(),
            });
            ok = false;
        }
        if !ok {
            return;
        }
        // Selected products in inventory order.
        assignment.sort_by_key(|a| a.entry);
        self.orders.set_index(&o.name.text, self.model.orders.len());
        self.model.orders.push(Order {
            name: o.name.text.clone(),
            loc: at,
            inventory: inv,
            customer: customer.get(),
            batch: batch.get(),
            assignment,
        });
    }

    /// `at PRODUCT (x, y)` overrides, one per product.
    fn placements(
        &mut self,
        inv: usize,
        list: &[(&ast::Name, &ast::Point)],
        f: FileId,
    ) -> Option<Vec<Placed>> {
        let mut out: Vec<Placed> = Vec::new();
        let mut ok = true;
        for (name, point) in list {
            let Some(entry) = self.entry(inv, name, f) else {
                ok = false;
                continue;
            };
            let at = Loc::new(f, name.span);
            if let Some(first) = out.iter().find(|p| p.entry == entry) {
                self.errors.push(Error::ListedTwice {
                    at,
                    first: first.loc,
                    what: "position of product",
                    name: name.text.clone(),
                });
                ok = false;
                continue;
            }
            out.push(Placed {
                entry,
                at: self.table_point(point, f),
                loc: Loc::new(f, point.span),
            });
        }
        ok.then_some(out)
    }

    fn demo(&mut self, f: FileId, d: &ast::Demo) {
        let at = Loc::new(f, d.name.span);
        if !self.demos.declare(&d.name.text, at, &mut self.errors) {
            return;
        }
        let Some(order) = self.orders.resolve(&d.order, f, &mut self.errors) else {
            return;
        };
        let inv = self.model.orders[order].inventory;
        let mut sequence = Once::new("sequence");
        let mut ats = Vec::new();
        for st in &d.stmts {
            match &st.kind {
                ast::DemoStmt::Sequence(names) => {
                    sequence.set((names, st.span), Loc::new(f, st.span), &mut self.errors)
                }
                ast::DemoStmt::At { product, at } => ats.push((product, at)),
            }
        }
        let block = Loc::new(f, d.span);
        let item = format!("demo `{}`", d.name.text);
        // The example lists the order's own products.
        let products: Vec<&str> = self.model.orders[order]
            .assignment
            .iter()
            .filter_map(|a| self.model.inventories[inv].entries.get(a.entry))
            .map(|e| self.model.products[e.product].name.as_str())
            .collect();
        let example = match products.as_slice() {
            [] => "sequence A, C, E".to_owned(),
            names => format!("sequence {}", names.join(", ")),
        };
        let Some((names, seq_span)) = sequence.required(block, item, example, &mut self.errors)
        else {
            return;
        };
        let seq = self.entry_list(inv, names, f);
        let placed = self.placements(inv, &ats, f);
        let (Some(seq), Some(placed)) = (seq, placed) else {
            return;
        };
        let selected: Vec<usize> = self.model.orders[order]
            .assignment
            .iter()
            .map(|a| a.entry)
            .collect();
        let name_of = |e: &usize| {
            let inventory = &self.model.inventories[inv];
            self.model.products[inventory.entries[*e].product]
                .name
                .clone()
        };
        let left_out: Vec<String> = selected
            .iter()
            .filter(|e| !seq.contains(e))
            .map(name_of)
            .collect();
        let not_selected: Vec<String> = seq
            .iter()
            .filter(|e| !selected.contains(e))
            .map(name_of)
            .collect();
        if !left_out.is_empty() || !not_selected.is_empty() {
            self.errors.push(Error::SequenceMismatch {
                at: Loc::new(f, seq_span),
                order: self.model.orders[order].name.clone(),
                left_out,
                not_selected,
            });
            return;
        }
        self.demos.set_index(&d.name.text, self.model.demos.len());
        self.model.demos.push(DemoDef {
            name: d.name.text.clone(),
            loc: at,
            order,
            sequence: seq,
            at: placed,
        });
    }

    fn choose(&mut self, inv: usize, c: &ast::Choose, at: Loc) -> Option<Choose> {
        let f = at.file;
        let entries = self.entry_list(inv, &c.products, f);
        let mut slots: Vec<(usize, Loc)> = Vec::new();
        let mut ok = entries.is_some();
        for s in &c.slots {
            let Some(i) = self.slot(inv, s, f) else {
                ok = false;
                continue;
            };
            let sl = Loc::new(f, s.span);
            if let Some((_, first)) = slots.iter().find(|(x, _)| *x == i) {
                self.errors.push(Error::ListedTwice {
                    at: sl,
                    first: *first,
                    what: "slot",
                    name: s.text.clone(),
                });
                ok = false;
                continue;
            }
            slots.push((i, sl));
        }
        let n = usize::try_from(c.n.value).unwrap_or(usize::MAX);
        let nl = Loc::new(f, c.n.span);
        if n == 0 {
            self.errors.push(Error::Zero {
                at: nl,
                statement: "choose",
            });
            ok = false;
        }
        if n > c.products.len() {
            self.errors.push(Error::ChooseTooMany {
                at: nl,
                n: c.n.value,
                what: "products",
                available: c.products.len(),
            });
            ok = false;
        }
        if n > c.slots.len() {
            self.errors.push(Error::ChooseTooMany {
                at: nl,
                n: c.n.value,
                what: "slots",
                available: c.slots.len(),
            });
            ok = false;
        }
        let entries = entries?;
        ok.then(|| Choose {
            n,
            entries,
            slots: slots.into_iter().map(|(s, _)| s).collect(),
            loc: at,
        })
    }

    /// Checks `human packs` and `missing` ranges against N.
    fn ranges(
        &mut self,
        human: CountRange,
        missing: CountRange,
        human_r: Option<&ast::Range>,
        missing_r: Option<&ast::Range>,
        n: usize,
    ) -> bool {
        let mut ok = true;
        for (range, r, statement) in [
            (human, human_r, "human packs"),
            (missing, missing_r, "missing"),
        ] {
            if let (Some(r), Some(at)) = (r, range.loc)
                && (range.low > range.high || range.high > n)
            {
                self.errors.push(Error::RangeTooLarge {
                    at,
                    statement,
                    low: r.low.value,
                    high: r.high.value,
                    n: n as u64,
                });
                ok = false;
            }
        }
        if ok && human.high.saturating_add(missing.high) > n {
            let at = missing.loc.or(human.loc).unwrap_or_default();
            self.errors.push(Error::RangesTooLarge {
                at,
                human: human.high as u64,
                missing: missing.high as u64,
                n: n as u64,
            });
            ok = false;
        }
        ok
    }

    fn jitter(&mut self, l: &ast::Length, f: FileId) -> f64 {
        if l.metres < 0.0 {
            self.errors.push(Error::BadGeometry {
                at: Loc::new(f, l.span),
                what: "jitter cannot be negative".into(),
                fix: "write a length such as `20 mm`, or leave the statement out for none".into(),
            });
            return 0.0;
        }
        l.metres
    }

    fn count_at_least_one(&mut self, c: &ast::Count, f: FileId, statement: &'static str) -> usize {
        if c.value == 0 {
            self.errors.push(Error::Zero {
                at: Loc::new(f, c.span),
                statement,
            });
        }
        usize::try_from(c.value).unwrap_or(usize::MAX)
    }

    /// What `demos` and `scenarios` share: the required `choose`, and the
    /// `human packs` and `missing` ranges checked against its N.
    fn generator(
        &mut self,
        inv: usize,
        block: Loc,
        item: String,
        choose: Once<&ast::Choose>,
        human: Once<&ast::Range>,
        missing: Once<&ast::Range>,
    ) -> Option<(Choose, CountRange, CountRange)> {
        let choose_loc = choose.loc().unwrap_or(block);
        let (human_loc, missing_loc) = (human.loc(), missing.loc());
        let (human_r, missing_r) = (human.get(), missing.get());
        let example = "choose 3 of A, B, C, D, E into g1, g2, g3";
        let c = choose.required(block, item, example, &mut self.errors)?;
        let choose = self.choose(inv, c, choose_loc)?;
        let human = count_range(human_r, human_loc);
        let missing = count_range(missing_r, missing_loc);
        self.ranges(human, missing, human_r, missing_r, choose.n)
            .then_some((choose, human, missing))
    }

    fn demo_set(&mut self, f: FileId, d: &ast::Demos) {
        let at = Loc::new(f, d.name.span);
        if !self.demos.declare(&d.name.text, at, &mut self.errors) {
            return;
        }
        let Some(inv) = self.inventories.resolve(&d.inventory, f, &mut self.errors) else {
            return;
        };
        let before = self.errors.len();
        let mut choose = Once::new("choose");
        let mut keep = Once::new("keep");
        let mut jitter = Once::new("jitter");
        let mut sequence = Once::new("sequence");
        let mut repeat = Once::new("repeat");
        let mut seed = Once::new("seed");
        let mut human = Once::new("human packs");
        let mut missing = Once::new("missing");
        for st in &d.stmts {
            let sl = Loc::new(f, st.span);
            match &st.kind {
                ast::DemosStmt::Choose(c) => choose.set(c, sl, &mut self.errors),
                ast::DemosStmt::Keep(k) => {
                    if !(k.value > 0.0 && k.value <= 1.0) {
                        self.errors.push(Error::FractionOutOfRange {
                            at: Loc::new(f, k.span),
                            value: k.value,
                        });
                    }
                    keep.set(k.value, sl, &mut self.errors);
                }
                ast::DemosStmt::Jitter(l) => {
                    let j = self.jitter(l, f);
                    jitter.set(j, sl, &mut self.errors);
                }
                ast::DemosStmt::Sequence(m) => sequence.set(*m, sl, &mut self.errors),
                ast::DemosStmt::Repeat(c) => {
                    let r = self.count_at_least_one(c, f, "repeat");
                    repeat.set(r, sl, &mut self.errors);
                }
                ast::DemosStmt::Seed(c) => seed.set(c.value, sl, &mut self.errors),
                ast::DemosStmt::HumanPacks(r) => human.set(r, sl, &mut self.errors),
                ast::DemosStmt::Missing(r) => missing.set(r, sl, &mut self.errors),
            }
        }
        let block = Loc::new(f, d.span);
        let item = format!("demos block `{}`", d.name.text);
        let jitter_loc = jitter.loc();
        let repeat_loc = repeat.loc();
        let Some((choose, human, missing)) =
            self.generator(inv, block, item, choose, human, missing)
        else {
            return;
        };
        if self.errors.len() > before {
            return;
        }
        self.demos
            .set_index(&d.name.text, self.model.demo_sets.len());
        self.model.demo_sets.push(DemosDef {
            name: d.name.text.clone(),
            loc: at,
            inventory: inv,
            choose,
            keep: keep.get().unwrap_or(1.0),
            jitter: jitter.get().unwrap_or(0.0),
            jitter_loc,
            sequence: sequence.get().unwrap_or(SequenceMode::Ascending),
            repeat: repeat.get().unwrap_or(1),
            repeat_loc,
            seed: seed.get().unwrap_or(0),
            human,
            missing,
        });
    }

    fn scenario(&mut self, f: FileId, s: &ast::Scenario) {
        let at = Loc::new(f, s.name.span);
        if !self.scenarios.declare(&s.name.text, at, &mut self.errors) {
            return;
        }
        let Some(order) = self.orders.resolve(&s.order, f, &mut self.errors) else {
            return;
        };
        let inv = self.model.orders[order].inventory;
        let before = self.errors.len();
        let mut packed = Once::new("human packed");
        let mut missing = Once::new("missing");
        let mut jitter = Once::new("jitter");
        let mut seed = Once::new("seed");
        let mut ats = Vec::new();
        for st in &s.stmts {
            let sl = Loc::new(f, st.span);
            match &st.kind {
                ast::ScenarioStmt::HumanPacked(names) => packed.set(names, sl, &mut self.errors),
                ast::ScenarioStmt::Missing(names) => missing.set(names, sl, &mut self.errors),
                ast::ScenarioStmt::Jitter(l) => {
                    let j = self.jitter(l, f);
                    jitter.set(j, sl, &mut self.errors);
                }
                ast::ScenarioStmt::Seed(c) => seed.set(c.value, sl, &mut self.errors),
                ast::ScenarioStmt::At { product, at } => ats.push((product, at)),
            }
        }
        let jitter_loc = jitter.loc();
        let packed_names = packed.get().map(|v| v.as_slice()).unwrap_or_default();
        let missing_names = missing.get().map(|v| v.as_slice()).unwrap_or_default();
        let human_packed = self.entry_list(inv, packed_names, f).unwrap_or_default();
        let missing = self.entry_list(inv, missing_names, f).unwrap_or_default();
        let placed = self.placements(inv, &ats, f).unwrap_or_default();
        let selected: Vec<usize> = self.model.orders[order]
            .assignment
            .iter()
            .map(|a| a.entry)
            .collect();
        for (name, e) in packed_names.iter().zip(&human_packed) {
            if !selected.contains(e) {
                self.errors.push(Error::NotSelected {
                    at: Loc::new(f, name.span),
                    product: name.text.clone(),
                    order: self.model.orders[order].name.clone(),
                });
            }
        }
        for (name, e) in missing_names.iter().zip(&missing) {
            if human_packed.contains(e) {
                self.errors.push(Error::PackedAndMissing {
                    at: Loc::new(f, name.span),
                    product: name.text.clone(),
                });
            }
        }
        if self.errors.len() > before {
            return;
        }
        self.scenarios
            .set_index(&s.name.text, self.model.scenarios.len());
        self.model.scenarios.push(ScenarioDef {
            name: s.name.text.clone(),
            loc: at,
            order,
            human_packed,
            missing,
            jitter: jitter.get().unwrap_or(0.0),
            jitter_loc,
            seed: seed.get().unwrap_or(0),
            at: placed,
        });
    }

    fn scenario_set(&mut self, f: FileId, s: &ast::Scenarios) {
        let at = Loc::new(f, s.name.span);
        if !self.scenarios.declare(&s.name.text, at, &mut self.errors) {
            return;
        }
        let Some(inv) = self.inventories.resolve(&s.inventory, f, &mut self.errors) else {
            return;
        };
        let before = self.errors.len();
        let mut choose = Once::new("choose");
        let mut human = Once::new("human packs");
        let mut missing = Once::new("missing");
        let mut jitter = Once::new("jitter");
        let mut count = Once::new("count");
        let mut seed = Once::new("seed");
        for st in &s.stmts {
            let sl = Loc::new(f, st.span);
            match &st.kind {
                ast::ScenariosStmt::Choose(c) => choose.set(c, sl, &mut self.errors),
                ast::ScenariosStmt::HumanPacks(r) => human.set(r, sl, &mut self.errors),
                ast::ScenariosStmt::Missing(r) => missing.set(r, sl, &mut self.errors),
                ast::ScenariosStmt::Jitter(l) => {
                    let j = self.jitter(l, f);
                    jitter.set(j, sl, &mut self.errors);
                }
                ast::ScenariosStmt::Count(c) => {
                    let n = self.count_at_least_one(c, f, "count");
                    count.set(n, sl, &mut self.errors);
                }
                ast::ScenariosStmt::Seed(c) => seed.set(c.value, sl, &mut self.errors),
            }
        }
        let block = Loc::new(f, s.span);
        let item = format!("scenarios block `{}`", s.name.text);
        let jitter_loc = jitter.loc();
        let count_loc = count.loc();
        let count = count.required(block, item.clone(), "count 100", &mut self.errors);
        let Some((choose, human, missing)) =
            self.generator(inv, block, item, choose, human, missing)
        else {
            return;
        };
        if self.errors.len() > before {
            return;
        }
        let Some(count) = count else {
            return;
        };
        self.scenarios
            .set_index(&s.name.text, self.model.scenario_sets.len());
        self.model.scenario_sets.push(ScenariosDef {
            name: s.name.text.clone(),
            loc: at,
            inventory: inv,
            choose,
            human,
            missing,
            jitter: jitter.get().unwrap_or(0.0),
            jitter_loc,
            count,
            count_loc: count_loc.unwrap_or(block),
            seed: seed.get().unwrap_or(0),
        });
    }
}

fn count_range(r: Option<&ast::Range>, loc: Option<Loc>) -> CountRange {
    match r {
        Some(r) => CountRange {
            low: usize::try_from(r.low.value).unwrap_or(usize::MAX),
            high: usize::try_from(r.high.value).unwrap_or(usize::MAX),
            loc,
        },
        None => CountRange::NONE,
    }
}
