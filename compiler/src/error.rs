//! Everything the compiler can report. Each variant is one check, carries
//! the places it speaks of, and knows its stable code, its caret label and
//! its fix (`help`). Rendering lives in `diagnostic`.

use crate::source::{Loc, Unreadable};
use crate::workspace::{Pose, Task};
use packwright_grammar::SyntaxError;
use std::path::PathBuf;
use thiserror::Error;

/// The rules a `demos` block's `sequence` names: in a `demo`'s sequence,
/// which lists products, one is a product unknown by that name.
const SEQUENCE_RULES: [&str; 4] = ["ascending", "descending", "listed", "random"];

/// A top face this low (m) that the cup cannot reach is out of reach
/// because of the table, not of the arm: the planner keeps the cup's body
/// 5 mm clear of everything but the product it picks, and its body ends
/// short of the tip ([`Error::help`]).
const THIN_TOP_FACE: f64 = 0.005;

/// A pick whose tool tip would be higher than this above the table (m)
/// is out of reach for its height: the help asks about the product's
/// height first (the UR10's shoulder is 0.13 m up and its arm 1.3 m long,
/// but over a product beside the base, with the cup pointing down, the
/// wrist reaches far less high).
const HIGH_TIP: f64 = 0.8;
#[derive(Debug, Clone, PartialEq, Error)]
pub enum Error {
    #[error("cannot read `{}`: {reason}", path.display())]
    Read { path: PathBuf, reason: Unreadable },
    #[error("{error}")]
    Syntax { at: Loc, error: SyntaxError },
    #[error("cannot read `{path}`: {reason}")]
    UseMissing {
        at: Loc,
        path: String,
        reason: Unreadable,
    },
    #[error("`use` cycle: {chain}")]
    UseCycle { at: Loc, chain: String },
    #[error("robot description `{path}` cannot be read: {reason}")]
    RobotFileMissing {
        at: Loc,
        path: String,
        reason: Unreadable,
    },
    /// A robot description that is read but cannot be used.
    #[error("`{path}`: {reason}")]
    RobotUnusable {
        at: Loc,
        path: String,
        reason: String,
    },
    #[error("duplicate {kind} `{name}`")]
    Duplicate {
        at: Loc,
        first: Loc,
        kind: &'static str,
        name: String,
    },
    #[error("unknown {kind} `{name}`")]
    Unknown {
        at: Loc,
        kind: &'static str,
        name: String,
        /// Where the name was looked for: "inventory `stock5`".
        scope: String,
        suggestion: Option<String>,
        known: Vec<String>,
    },
    #[error("{item} has no `{statement}` statement")]
    MissingStatement {
        at: Loc,
        item: String,
        statement: &'static str,
        example: String,
    },
    #[error("`{statement}` is given twice")]
    StatementTwice {
        at: Loc,
        first: Loc,
        statement: &'static str,
    },
    #[error("slot `{slot}` comes before any box")]
    SlotBeforeBox { at: Loc, slot: String },
    #[error("{what}")]
    BadGeometry { at: Loc, what: String, fix: String },
    #[error(
        "the arm's speed must be between {min_percent} % and 100 % of its full speed, not {percent} %"
    )]
    SpeedOutOfRange {
        at: Loc,
        percent: f64,
        min_percent: f64,
        /// Written without `%` (a fraction).
        bare: bool,
    },
    #[error(
        "the settle time after a {after} must be between {min_ms} ms and {max_ms} ms, not {ms} ms"
    )]
    SettleOutOfRange {
        at: Loc,
        after: &'static str,
        ms: f64,
        min_ms: f64,
        max_ms: f64,
    },
    #[error(
        "the descent's speed must be between {min_percent} % and 100 % of the cell's speed, not {percent} %"
    )]
    DescentOutOfRange {
        at: Loc,
        percent: f64,
        min_percent: f64,
        /// Written without `%` (a fraction).
        bare: bool,
    },
    #[error("`{statement}` gives one value per joint: {expected}, not {found}")]
    JointCount {
        at: Loc,
        statement: &'static str,
        found: usize,
        expected: usize,
    },
    #[error(
        "the {statement} limit of joint {joint} must be between {min} and {max} {unit}, not {value}"
    )]
    JointLimitOutOfRange {
        at: Loc,
        statement: &'static str,
        joint: usize,
        value: f64,
        min: f64,
        max: f64,
        unit: &'static str,
    },
    #[error("slot `{slot}` is outside box `{box_name}`")]
    SlotOutsideBox {
        at: Loc,
        slot: String,
        box_name: String,
        by_mm: f64,
    },
    #[error("slots `{a}` and `{b}` overlap ({distance_mm:.0} mm apart)")]
    SlotsOverlap {
        at: Loc,
        first: Loc,
        a: String,
        b: String,
        distance_mm: f64,
    },
    #[error("two products in slot `{slot}`: `{product}` and `{other}`")]
    SlotTaken {
        at: Loc,
        first: Loc,
        slot: String,
        product: String,
        other: String,
    },
    #[error("{what} `{name}` is listed twice")]
    ListedTwice {
        at: Loc,
        first: Loc,
        what: &'static str,
        name: String,
    },
    #[error("product `{product}` is outside the pending area of cell `{cell}`")]
    OutsidePending {
        at: Loc,
        product: String,
        cell: String,
        by_mm: f64,
    },
    #[error("products `{a}` and `{b}` overlap")]
    ProductsOverlap {
        at: Loc,
        other: Loc,
        a: String,
        b: String,
    },
    #[error("{what} is out of the robot's reach ({distance:.3} m from the base axis)")]
    OutOfReach {
        at: Loc,
        what: String,
        distance: f64,
        min: f64,
        max: f64,
    },
    #[error("{what} reaches {} from the robot's base, farther than any arm packs ({max} m)", metres(*.distance))]
    FarFromBase {
        at: Loc,
        what: String,
        /// The farthest point's distance from the base, or the box's
        /// largest dimension if that is larger (m).
        distance: f64,
        max: f64,
    },
    #[error("the cell lies {} from the origin, farther than the simulator works ({max} m)", metres(*.coordinate))]
    FarFromOrigin {
        at: Loc,
        /// The largest coordinate of the base, the pending area or a box
        /// (m).
        coordinate: f64,
        max: f64,
    },
    #[error("the robot cannot reach {pose} {task}")]
    Unreachable {
        at: Loc,
        /// What the robot was doing.
        task: Task,
        pose: Pose,
        /// Where the tool tip would be (world frame, m).
        tip: [f64; 3],
        /// Picking: the empty cell allows the pose, the product itself
        /// does not (the wrist over a short cup meets it).
        meets_itself: bool,
        /// Picking: the way [`REACH_PROBE`] along the line from the
        /// robot's base axis that the product would be picked, where one
        /// way is and the other is not (a product too near the base, on
        /// a riser, folds the forearm into the base; one too far out is
        /// beyond the arm).
        reached_moved: Option<Moved>,
    },
    #[error(
        "the robot cannot start in cell `{cell}` while the products of inventory `{inventory}` stand there: every start pose over the middle of the `pending` area meets `{by}`"
    )]
    StartBlocked {
        /// The entry of the product met.
        at: Loc,
        cell: String,
        inventory: String,
        by: String,
    },
    #[error(
        "product `{product}` does not fit in {}: it sticks out of box `{box_name}` by {by_mm:.0} mm",
        crate::warning::slot_list(&[std::slice::from_ref(slot), also].concat())
    )]
    DoesNotFit {
        at: Loc,
        product: String,
        slot: String,
        box_name: String,
        by_mm: f64,
        /// A generator's other slots the product does not fit either
        /// (all said at once: fixing the first showed the next).
        also: Vec<String>,
    },
    #[error("`{a}` in slot `{slot_a}` and `{b}` in slot `{slot_b}` would overlap")]
    PlacedOverlap {
        at: Loc,
        a: String,
        slot_a: String,
        b: String,
        slot_b: String,
    },
    #[error("`choose {n}` needs {n} {what}, but {available} are listed")]
    ChooseTooMany {
        at: Loc,
        n: u64,
        what: &'static str,
        available: usize,
    },
    #[error("`{statement}` must be at least 1")]
    Zero { at: Loc, statement: &'static str },
    #[error("`keep {value}` is outside (0, 1]")]
    FractionOutOfRange { at: Loc, value: f64 },
    #[error("`{statement} {low} to {high}` is not a range within 0 to {n} selected products")]
    RangeTooLarge {
        at: Loc,
        statement: &'static str,
        low: u64,
        high: u64,
        n: u64,
    },
    #[error(
        "a worker may pack {human} and {missing} may be missing, more than the {n} selected products"
    )]
    RangesTooLarge {
        at: Loc,
        human: u64,
        missing: u64,
        n: u64,
    },
    #[error(
        "jitter cannot place product `{product}`: {tries} draws all left the pending area or overlapped another product"
    )]
    JitterImpossible {
        at: Loc,
        product: String,
        tries: u32,
    },
    #[error("`keep {fraction}` keeps no combination of the {combinations}")]
    KeepsNothing {
        at: Loc,
        fraction: f64,
        combinations: u64,
    },
    #[error("{count} goal configurations are more than the {limit} a block may generate")]
    TooManyConfigurations { at: Loc, count: String, limit: u64 },
    #[error(
        "the files together would generate {count} demonstrations and cases, more than the {limit} of one compilation"
    )]
    TooManyInTotal { at: Loc, count: u64, limit: u64 },
    #[error("the sequence does not match order `{order}`")]
    SequenceMismatch {
        at: Loc,
        order: String,
        left_out: Vec<String>,
        not_selected: Vec<String>,
    },
    #[error("product `{product}` is not selected by order `{order}`")]
    NotSelected {
        at: Loc,
        product: String,
        order: String,
    },
    #[error("product `{product}` cannot be both packed by a worker and missing")]
    PackedAndMissing { at: Loc, product: String },
    /// An output file could not be written (the disk is full, ...).
    #[error("cannot write `{file}`: {reason}")]
    Write { file: String, reason: String },
    /// A bug: an artifact could not be serialised.
    #[error("internal error: {what}")]
    Internal { what: String },
}

/// A place this many times farther than the limit it breaks (m, or
/// m beyond a box) was most likely written in millimetres without the
/// unit: the help says so.
const MILLIMETRES_LIKELY: f64 = 10.0;

impl Error {
    /// A stable code, documented in the README.
    pub fn code(&self) -> &'static str {
        match self {
            Error::Write { .. } => "E008",
            Error::Read { .. } => "E009",
            Error::Syntax { error, .. } => error.code(),
            Error::UseMissing { .. } => "E010",
            Error::UseCycle { .. } => "E011",
            Error::RobotFileMissing { .. } => "E012",
            Error::RobotUnusable { .. } => "E013",
            Error::Duplicate { .. } => "E020",
            Error::Unknown { .. } => "E021",
            Error::MissingStatement { .. } => "E022",
            Error::StatementTwice { .. } => "E023",
            Error::SlotBeforeBox { .. } => "E024",
            Error::BadGeometry { .. } => "E025",
            Error::SpeedOutOfRange { .. } => "E026",
            Error::SettleOutOfRange { .. } => "E027",
            Error::DescentOutOfRange { .. } => "E028",
            Error::JointCount { .. } | Error::JointLimitOutOfRange { .. } => "E029",
            Error::SlotOutsideBox { .. } => "E030",
            Error::SlotsOverlap { .. } => "E031",
            Error::SlotTaken { .. } => "E032",
            Error::ListedTwice { .. } => "E033",
            Error::OutsidePending { .. } => "E034",
            Error::ProductsOverlap { .. } => "E035",
            Error::OutOfReach { .. } => "E036",
            Error::Unreachable { .. } => "E039",
            Error::FarFromBase { .. } => "E054",
            Error::FarFromOrigin { .. } => "E055",
            Error::StartBlocked { .. } => "E053",
            Error::DoesNotFit { .. } => "E037",
            Error::PlacedOverlap { .. } => "E038",
            Error::ChooseTooMany { .. } => "E040",
            Error::Zero { .. } => "E041",
            Error::FractionOutOfRange { .. } => "E042",
            Error::RangeTooLarge { .. } => "E043",
            Error::RangesTooLarge { .. } => "E044",
            Error::JitterImpossible { .. } => "E045",
            Error::KeepsNothing { .. } => "E046",
            Error::TooManyConfigurations { .. } => "E047",
            Error::TooManyInTotal { .. } => "E048",
            Error::SequenceMismatch { .. } => "E050",
            Error::NotSelected { .. } => "E051",
            Error::PackedAndMissing { .. } => "E052",
            Error::Internal { .. } => "E099",
        }
    }

    /// Where the caret goes; `None` for errors about a whole file.
    pub fn at(&self) -> Option<Loc> {
        match self {
            Error::Read { .. } | Error::Write { .. } | Error::Internal { .. } => None,
            Error::Syntax { at, .. }
            | Error::UseMissing { at, .. }
            | Error::UseCycle { at, .. }
            | Error::RobotFileMissing { at, .. }
            | Error::RobotUnusable { at, .. }
            | Error::Duplicate { at, .. }
            | Error::Unknown { at, .. }
            | Error::MissingStatement { at, .. }
            | Error::StatementTwice { at, .. }
            | Error::SlotBeforeBox { at, .. }
            | Error::BadGeometry { at, .. }
            | Error::SpeedOutOfRange { at, .. }
            | Error::SettleOutOfRange { at, .. }
            | Error::DescentOutOfRange { at, .. }
            | Error::JointCount { at, .. }
            | Error::JointLimitOutOfRange { at, .. }
            | Error::SlotOutsideBox { at, .. }
            | Error::SlotsOverlap { at, .. }
            | Error::SlotTaken { at, .. }
            | Error::ListedTwice { at, .. }
            | Error::OutsidePending { at, .. }
            | Error::ProductsOverlap { at, .. }
            | Error::OutOfReach { at, .. }
            | Error::Unreachable { at, .. }
            | Error::FarFromBase { at, .. }
            | Error::FarFromOrigin { at, .. }
            | Error::StartBlocked { at, .. }
            | Error::DoesNotFit { at, .. }
            | Error::PlacedOverlap { at, .. }
            | Error::ChooseTooMany { at, .. }
            | Error::Zero { at, .. }
            | Error::FractionOutOfRange { at, .. }
            | Error::RangeTooLarge { at, .. }
            | Error::RangesTooLarge { at, .. }
            | Error::JitterImpossible { at, .. }
            | Error::KeepsNothing { at, .. }
            | Error::TooManyConfigurations { at, .. }
            | Error::TooManyInTotal { at, .. }
            | Error::SequenceMismatch { at, .. }
            | Error::NotSelected { at, .. }
            | Error::PackedAndMissing { at, .. } => Some(*at),
        }
    }

    /// The short text under the caret.
    pub fn label(&self) -> String {
        match self {
            Error::Read { .. } | Error::Write { .. } | Error::Internal { .. } => String::new(),
            Error::Syntax { error, .. } => error.label(),
            Error::UseMissing { .. } => "this file cannot be read".into(),
            Error::UseCycle { .. } => "this `use` closes the cycle".into(),
            Error::RobotFileMissing { .. } => "this file cannot be read".into(),
            Error::RobotUnusable { .. } => "this description".into(),
            Error::Duplicate { .. } => "defined again here".into(),
            Error::Unknown { scope, .. } => format!("not found in {scope}"),
            Error::MissingStatement { .. } => "in this block".into(),
            Error::StatementTwice { .. } => "given again here".into(),
            Error::SlotBeforeBox { .. } => "no box declared above this slot".into(),
            Error::BadGeometry { .. } => "here".into(),
            Error::SpeedOutOfRange { .. } => "out of range".into(),
            Error::SettleOutOfRange { .. } => "out of range".into(),
            Error::DescentOutOfRange { .. } => "out of range".into(),
            Error::JointCount { found, .. } => format!("{found} values"),
            Error::JointLimitOutOfRange { .. } => "out of range".into(),
            Error::SlotOutsideBox { by_mm, .. } => format!("{by_mm:.0} mm outside the box"),
            Error::SlotsOverlap { .. } => "too close to the other slot".into(),
            Error::SlotTaken { .. } => "slot already taken".into(),
            Error::ListedTwice { .. } => "listed again here".into(),
            Error::OutsidePending { by_mm, .. } => {
                format!("{by_mm:.0} mm outside the pending area")
            }
            Error::ProductsOverlap { .. } => "overlaps another product".into(),
            Error::OutOfReach { distance, min, .. } if distance < min => {
                "too close to the base".into()
            }
            Error::OutOfReach { .. } => "too far from the base".into(),
            Error::FarFromBase { .. } => "far beyond any arm's reach".into(),
            Error::FarFromOrigin { coordinate, .. } => {
                format!("{} from the origin", metres(*coordinate))
            }
            Error::Unreachable { tip, .. } => format!(
                "the tool tip would be at ({:.3}, {:.3}, {:.3})",
                tip[0], tip[1], tip[2]
            ),
            Error::StartBlocked { .. } => "the arm meets this product at its start".into(),
            Error::DoesNotFit { .. } => "does not fit".into(),
            Error::PlacedOverlap { .. } => "these products would collide in the box".into(),
            Error::ChooseTooMany { .. } => "too many".into(),
            Error::Zero { .. } => "must be 1 or more".into(),
            Error::FractionOutOfRange { .. } => "not in (0, 1]".into(),
            Error::RangeTooLarge { .. } => "range out of bounds".into(),
            Error::RangesTooLarge { .. } => "together these exceed the selection".into(),
            Error::JitterImpossible { .. } => "this jitter is too large".into(),
            Error::KeepsNothing { .. } => "keeps nothing".into(),
            Error::TooManyConfigurations { .. } => "too many configurations".into(),
            Error::TooManyInTotal { .. } => "this block goes over the total".into(),
            Error::SequenceMismatch { .. } => "this sequence".into(),
            Error::NotSelected { .. } => "not in the order".into(),
            Error::PackedAndMissing { .. } => "both packed and missing".into(),
        }
    }

    /// Secondary places: (where, what it is).
    pub fn notes(&self) -> Vec<(Loc, String)> {
        match self {
            Error::Duplicate { first, .. } => vec![(*first, "first defined here".into())],
            Error::StatementTwice { first, .. } => vec![(*first, "first given here".into())],
            Error::SlotsOverlap { first, .. } => vec![(*first, "the other slot".into())],
            Error::SlotTaken { first, .. } => vec![(*first, "first put in the slot here".into())],
            Error::ListedTwice { first, .. } => vec![(*first, "first listed here".into())],
            Error::ProductsOverlap { other, .. } => vec![(*other, "the other product".into())],
            _ => Vec::new(),
        }
    }

    /// How to fix it.
    pub fn help(&self) -> Option<String> {
        Some(match self {
            Error::Read { reason, .. } => reason.help(),
            Error::Syntax { error, .. } => return error.help(),
            Error::UseMissing {
                reason: Unreadable::Missing,
                ..
            } => "`use` paths are relative to the file that uses them".into(),
            Error::UseMissing { reason, .. } => format!("the file is there but cannot be used: {}", reason.help()),
            Error::UseCycle { .. } => "remove one of the `use` lines; a file cannot use itself, even through others".into(),
            Error::RobotFileMissing {
                reason: Unreadable::Missing,
                ..
            } => "the path is relative to the file that names it".into(),
            Error::RobotFileMissing { .. } => "the file is there but cannot be read: make it a readable UTF-8 URDF file".into(),
            Error::RobotUnusable { .. } => "packwright drives one chain of six revolute joints from the root link to `tool0` (or `flange`); side branches bolted on by fixed joints are fine, collision meshes must be STL or OBJ files it can find".into(),
            Error::Duplicate { kind, .. } => format!("rename one of the two; every {kind} needs its own name"),
            Error::Unknown { kind: "product", name, .. } if SEQUENCE_RULES.contains(&name.as_str()) => format!("a `demo` lists its products in the order they were packed (`sequence A, C, E`); `sequence {name}` belongs in a `demos` block"),
            Error::Unknown {
                suggestion: Some(s), ..
            } => format!("did you mean `{s}`?"),
            Error::Unknown { known, kind, .. } if known.is_empty() => format!("define the {kind} first"),
            Error::Unknown { known, kind, .. } => {
                let mut list = known.iter().take(12).map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
                if known.len() > 12 {
                    list.push_str(", ...");
                }
                format!("the {} known here: {list}", crate::resolve::plural(kind))
            }
            Error::MissingStatement { example, .. } => format!("add a line such as `{example}`"),
            Error::StatementTwice { .. } => "keep only one of them".into(),
            Error::SlotBeforeBox { .. } => "declare the `box` before its slots: a slot belongs to the box above it".into(),
            Error::BadGeometry { fix, .. } => fix.clone(),
            Error::SpeedOutOfRange { percent, bare: true, .. } if (200.0..=10_000.0).contains(percent) => format!("did you mean `speed {} %`? A number without `%` is a fraction of the arm's full speed (`speed 0.3` is 30 %)", percent / 100.0),
            Error::DescentOutOfRange { percent, bare: true, .. } if (200.0..=10_000.0).contains(percent) => format!("did you mean `descent {} %`? A number without `%` is a fraction of the cell's speed (`descent 0.3` is 30 %)", percent / 100.0),
            Error::SpeedOutOfRange { min_percent, .. } => format!("write a share of the arm's full speed from `speed {min_percent} %` to `speed 100 %` (the default, the robot's own limits), or as a fraction (`speed 0.5`); the motions keep their paths and take 1/speed as long"),
            Error::SettleOutOfRange { after, min_ms, max_ms, .. } => format!("write a time from `settle {min_ms} ms after {after}` to `settle {max_ms} ms after {after}` (the default: `settle 100 ms after grip`, `settle 500 ms after release`); the arm waits that long, still, after the suction switches"),
            Error::DescentOutOfRange { min_percent, .. } => format!("write a share of the cell's speed from `descent {min_percent} %` to `descent 100 %` (the default: as fast as every other motion), or as a fraction (`descent 0.25`); the descent from the hover onto a product's top face keeps its path and takes 1/descent as long"),
            Error::JointCount { statement, expected, .. } => format!("write {expected} plain numbers, base first, e.g. `{statement} {}`; leave the statement out for the arm's own limits", if *statement == "jerk" { "(10, 10, 10, 20, 20, 20)" } else { "(2.5, 2.5, 2.5, 4, 4, 4)" }),
            Error::JointLimitOutOfRange { statement, min, max, unit, .. } => format!("write a {statement} limit from {min} to {max} {unit} for each joint, or leave the statement out for the arm's own limits (the built-in UR10's: `acceleration (2.5, 2.5, 2.5, 4, 4, 4)`, `jerk (10, 10, 10, 20, 20, 20)`)"),
            Error::SlotOutsideBox { by_mm, .. } if *by_mm > 1000.0 * MILLIMETRES_LIKELY => "check the numbers and their units: positions are metres unless they carry `mm` or `cm` (`0.58`, `580 mm`); a slot stands inside its box's footprint".into(),
            Error::SlotOutsideBox { .. } => "move the slot inside the box footprint (box centre ± width/2, ± depth/2)".into(),
            Error::SlotsOverlap { .. } => "slots must be at least 10 mm apart; move or remove one".into(),
            Error::SlotTaken { .. } => "give each product its own slot".into(),
            Error::ListedTwice { .. } => "remove the second one".into(),
            Error::OutsidePending { .. } => "move the product so that its whole footprint is inside the `pending` area, or enlarge the area".into(),
            Error::ProductsOverlap { .. } => "move one of them; footprints (centre ± half the width and depth) must not overlap".into(),
            Error::OutOfReach { min, max, distance, .. } if *distance > MILLIMETRES_LIKELY * max => format!("check the numbers and their units: positions are metres unless they carry `mm` or `cm` (`0.58`, `580 mm`); the UR10 reaches between {min:.2} m and {max:.2} m from its base axis"),
            Error::OutOfReach { min, max, .. } => format!("the UR10 reaches between {min:.2} m and {max:.2} m from its base axis; move it or the `base`"),
            Error::FarFromOrigin { max, .. } => format!("move the whole cell nearer the origin (subtract the same x and y from the base, the pending area, the boxes, the slots and every product's place): every coordinate must lie within {max} m of it, where the simulator keeps 10 µm"),
            Error::FarFromBase { max, .. } => format!("check the number and its unit: lengths and positions are metres unless they carry `mm` or `cm` (`0.65`, `650 mm`); every pending area and box lies within {max} m of the cell's `base`"),
            Error::Unreachable { pose: Pose::Start, .. } => "the arm starts with its cup 0.35 m over the middle of the `pending` area, or as low as 0.2 m where it cannot reach that high: bring the area nearer the robot's base (or the `base` nearer the area), or give the arm a shorter `suction` cup".into(),
            Error::Unreachable { meets_itself: true, .. } => "with the cup on the product's top face, the arm's wrist (or the cup's own body) meets the product itself: the cup is too short for this arm. Use a longer cup (`suction`)".into(),
            Error::Unreachable { pose: Pose::TopFace, tip, .. } if tip[2] <= THIN_TOP_FACE => format!("the top face is {:.0} mm above the table, and the cup is kept a few millimetres clear of everything but the product it picks: it would meet the table, wherever the product stands. Check the product's height; one thinner than {:.0} mm cannot be picked by this cup", tip[2] * 1000.0, THIN_TOP_FACE * 1000.0),
            Error::Unreachable { pose, tip, .. } if pose.is_picking() && tip[2] > HIGH_TIP => format!("the tool tip would be {:.2} m above the table, over the product's top face: check the product's height (sizes are metres unless they carry `mm` or `cm`); a product this tall can be picked only near the robot's base, with a low `lift` and a short cup (`suction`)", tip[2]),
            Error::Unreachable { pose, reached_moved: Some(Moved::Away), .. } if pose.is_picking() => format!("the product stands too near the robot's base for the arm to fold over it; {:.0} mm further out it can be picked: move it away from the base (or the `base` away from the products)", REACH_PROBE * 1000.0),
            Error::Unreachable { pose, .. } if pose.is_picking() => "move the product nearer the robot's base (or the `base` nearer the products), or lower the cell's `lift`; the cup (`suction`) reaches down from the wrist, so a shorter cup reaches further".into(),
            Error::Unreachable { pose: Pose::Approach, .. } => "the robot carries the product round its base axis, at the lift's height or clear of the box's rim if that is higher, half-way between the product and the slot: bring the product and the slot nearer each other, lower the cell's `lift`, or use a lower box".into(),
            Error::Unreachable { .. } => "move the slot (or its box) nearer the robot's base, or use a lower box: the product is held above the rim before it goes down".into(),
            Error::StartBlocked { .. } => "the arm starts with its cup 0.35 m over the middle of the `pending` area, and every arm pose that puts it there meets this product: move the product away from the middle of the area, or move the area or the `base`".into(),
            Error::DoesNotFit { .. } => "move the slot further from the box wall, use a larger box, or put a smaller product there".into(),
            Error::PlacedOverlap { .. } => "move the slots further apart".into(),
            Error::ChooseTooMany { .. } => "lower N, or list more products and slots".into(),
            Error::Zero { .. } => "write a number of 1 or more".into(),
            Error::FractionOutOfRange { .. } => "write a training ratio such as `keep 0.6`; `keep 1` keeps every combination".into(),
            Error::RangeTooLarge { n, .. } => format!("write `A to B` with A <= B <= {n}"),
            Error::RangesTooLarge { .. } => "lower one of the two upper bounds".into(),
            Error::JitterImpossible { .. } => "lower the jitter, space the products further apart, or enlarge the pending area".into(),
            Error::KeepsNothing { .. } => "raise `keep`".into(),
            Error::TooManyConfigurations { limit, .. } => format!("generate fewer: `choose` fewer products or slots, `keep` a smaller share of the combinations (counted after `keep`), a lower `repeat`, or (scenarios) a lower `count`; all the blocks of one compilation together may generate at most {limit} too (E048)"),
            Error::TooManyInTotal { .. } => "generate fewer in this or an earlier block (`choose`, `keep`, `repeat`, `count`), or compile the blocks in separate runs".into(),
            Error::SequenceMismatch {
                left_out,
                not_selected,
                ..
            } => {
                let mut parts = Vec::new();
                if !left_out.is_empty() {
                    parts.push(format!("add {}", quoted(left_out)));
                }
                if !not_selected.is_empty() {
                    parts.push(format!("remove {} (not in the order)", quoted(not_selected)));
                }
                format!("{}: a demo's sequence names every product of its order exactly once", parts.join("; "))
            }
            Error::NotSelected { .. } => "a worker can only pack products the order selects".into(),
            Error::PackedAndMissing { .. } => "remove it from one of the two lists".into(),
            Error::Write { .. } => "check that the output's disk has room and is writable; nothing was replaced".into(),
            Error::Internal { .. } => "please report this bug with the input that caused it".into(),
        })
    }
}

fn quoted(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A length for a message: metres with millimetres, or in scientific
/// notation when it is far too large to read that way.
fn metres(m: f64) -> String {
    if m.abs() < 1e6 {
        format!("{m:.3} m")
    } else {
        format!("{m:.1e} m")
    }
}

/// How far (m) an unreachable pick is tried further from and nearer the
/// robot's base axis, to say which way it would be reached
/// ([`Error::Unreachable`]'s `reached_moved`).
pub const REACH_PROBE: f64 = 0.05;

/// Which way along the line from the robot's base axis a pose is reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Moved {
    /// Further from the base axis.
    Away,
    /// Nearer it.
    Nearer,
}
