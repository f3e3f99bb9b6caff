//! What the compiler warns about: input that compiles and may still fail
//! on the robot, depending on what happens first (for example which
//! products are still standing). Each variant knows its stable code, its
//! caret label, its notes and its fix, as [`Error`](crate::Error) does;
//! rendering lives in `diagnostic`.

use crate::source::Loc;
use crate::workspace::{Lower, Pose};
use std::fmt;

#[derive(Debug, Clone, PartialEq)]
pub enum Warning {
    /// A product the robot picks in an empty cell, but not while another
    /// product of its inventory stands where it stands.
    PickBlocked {
        /// The picked product's inventory entry.
        at: Loc,
        product: String,
        position: [f64; 2],
        /// The first pose of the pick that the standing products block.
        pose: Pose,
        /// The product met (by the nearest arm pose that meets one), with
        /// its place and its entry.
        by: Option<(String, [f64; 2], Loc)>,
        /// Whether an order or a generator packs the product met (else it
        /// stands there in every package).
        by_packed: bool,
        /// How far (mm) the blocks on the inventory may draw the products
        /// standing beside it from their places (their largest `jitter`;
        /// each was asked about anywhere within it).
        jitter_mm: f64,
        /// Whether the pick is blocked with the others where they are
        /// written too, not only where the jitter may draw them.
        where_written: bool,
    },
    /// A product the robot places in a slot in an empty cell, but not
    /// while another product of its inventory stands where it stands (a
    /// tall product in the upper arm's way to the box: every arm pose at
    /// the approach point meets it).
    PlaceBlocked {
        /// What asked for the placing (an order's assignment, a demo's or
        /// scenario's moved product, a generator).
        at: Loc,
        product: String,
        /// Where it is picked (its entry's written place).
        position: [f64; 2],
        /// Every slot where the same pose meets the same product.
        slots: Vec<String>,
        /// The first pose of the placing that the standing products
        /// block.
        pose: Pose,
        /// The product met, with its place and its entry.
        by: Option<(String, [f64; 2], Loc)>,
        /// Whether an order or a generator packs the product met.
        by_packed: bool,
        /// Whether this product stands in the way of placing the one met
        /// too (in some slot): then packing either first can stop the
        /// other.
        mutual: bool,
        /// The largest `jitter` of the inventory's blocks (mm).
        jitter_mm: f64,
        /// Whether the placing is blocked with the others where they are
        /// written too, not only where the jitter may draw them.
        where_written: bool,
    },
    /// A product the robot picks at its written place, but not in some
    /// of a suite's scenarios, where the jitter draws it and a product
    /// beside it nearer each other than W001 allows for (both move).
    DrawnPickBlocked {
        /// The suite's `jitter` (else the suite).
        at: Loc,
        suite: String,
        /// How many scenarios the suite has.
        suite_cases: usize,
        /// What the suite's cases are.
        draws: Draws,
        product: String,
        /// The product met, and its inventory entry.
        by: String,
        by_at: Loc,
        /// The scenarios where it is met (their numbers, as named).
        cases: Vec<String>,
        jitter_mm: f64,
    },
    /// A product the robot picks at its written place (E039 asks only
    /// there), but not in some of a suite's scenarios, where the jitter
    /// draws it out of the arm's reach (a product near a base on a riser,
    /// drawn nearer the base: the forearm meets the base).
    DrawnOutOfReach {
        /// The suite's `jitter` (else the suite).
        at: Loc,
        suite: String,
        /// How many scenarios the suite has.
        suite_cases: usize,
        /// What the suite's cases are.
        draws: Draws,
        product: String,
        /// Its inventory entry.
        product_at: Loc,
        /// The first pose not reached, in the first such scenario.
        pose: Pose,
        /// The scenarios where it is out of reach (their numbers).
        cases: Vec<String>,
        jitter_mm: f64,
        /// Where every such draw lies: nearer the robot's base axis than
        /// the written place (`Some(true)`), farther (`Some(false)`), or
        /// either.
        nearer: Option<bool>,
    },
    /// Two products placed in neighbouring slots with less room between
    /// them than the planner keeps round a held product
    /// ([`HELD_ROOM`]): the second cannot be lowered past the first, so
    /// it is let go above the first one's top and dropped, and can land
    /// on it.
    TooClose {
        /// The assignment, or the generator that may place them so.
        at: Loc,
        a: String,
        slot_a: String,
        b: String,
        slot_b: String,
        gap_mm: f64,
    },
    /// A product over twice as tall as its narrow side, let go in a slot
    /// more than twice that side above its box's floor: the arm cannot
    /// lower it further (the wrist above a short suction cup meets the
    /// box's rim), and dropped that far it can land tilted and fall over.
    /// Asked of the empty box; a taller product packed beside it first
    /// can make the drop longer.
    DroppedHigh {
        /// The assignment, or the generator that may place it so.
        at: Loc,
        product: String,
        /// Where the product is defined.
        product_at: Loc,
        slot: String,
        in_box: String,
        drop_mm: f64,
        height_mm: f64,
        /// Its narrow side.
        side_mm: f64,
        /// What stops it lower, where the robot can tell.
        lower: Option<Lower>,
    },
    /// A cell's demonstrations follow no one sequence rule: no order
    /// (ascending, descending or one priority list) explains enough of
    /// them, and `train` refuses them. The compiler does not infer rules:
    /// `check` and `compile` ask `packwright-pipeline`'s inference
    /// (`teach::rule_warnings`) and report its answer here.
    NoSequenceRule {
        /// The first demonstration block that breaks the best rule.
        at: Loc,
        cell: String,
        /// The best rule, for people.
        best: String,
        /// How many of the cell's demonstrations it explains.
        agree: usize,
        demonstrations: usize,
        block: String,
        /// That block's first breaking demonstration's products, in the
        /// order handled.
        sequence: Vec<String>,
    },
}

/// The room (m) the motion planner keeps round a held product
/// (`packwright_kinematics::body::HELD_PADDING`; the compiler does not
/// depend on the robot crates, and a test in `packwright-pipeline` checks
/// that the two agree).
pub const HELD_ROOM: f64 = 0.003;

/// How far (mm) above its box's floor the robot lets a product go where
/// nothing stops it lower (`packwright_motion::expert::RELEASE_GAP`; a
/// test in `packwright-pipeline` checks that the two agree).
pub const RELEASE_GAP_MM: f64 = 5.0;

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Warning::PickBlocked {
                product,
                position,
                pose,
                by,
                jitter_mm,
                where_written,
                ..
            } => {
                write!(
                    f,
                    "the robot cannot reach {pose} when it picks product `{product}` at ({:.3}, {:.3}) ",
                    position[0], position[1]
                )?;
                let drawn = *jitter_mm > 0.0 && !where_written;
                match (by, drawn) {
                    (Some(met), _) => write_met(f, met, *jitter_mm, drawn),
                    (None, false) => f.write_str("while the other products of its inventory stand"),
                    (None, true) => write!(
                        f,
                        "while the other products of its inventory stand up to {jitter_mm:.0} mm from their places"
                    ),
                }?;
                match (*jitter_mm > 0.0, drawn) {
                    (true, false) => write!(
                        f,
                        ", or up to {jitter_mm:.0} mm from there (the jitter of its inventory's blocks)"
                    ),
                    (true, true) => f.write_str(
                        " (the jitter of its inventory's blocks); it can with the products where they are written",
                    ),
                    (false, _) => Ok(()),
                }
            }
            Warning::PlaceBlocked {
                product,
                position,
                slots,
                pose,
                by,
                jitter_mm,
                where_written,
                ..
            } => {
                write!(
                    f,
                    "the robot cannot reach {pose} when it puts product `{product}` (picked at ({:.3}, {:.3})) in {} ",
                    position[0],
                    position[1],
                    slot_list(slots)
                )?;
                let drawn = *jitter_mm > 0.0 && !where_written;
                match by {
                    Some(met) => write_met(f, met, *jitter_mm, drawn),
                    None => f.write_str("while the other products of its inventory stand"),
                }
            }
            Warning::DrawnPickBlocked {
                suite,
                suite_cases,
                draws,
                product,
                by,
                cases,
                ..
            } => {
                write_drawn(f, suite, *suite_cases, *draws, cases)?;
                write!(
                    f,
                    " the robot cannot pick `{product}` where the jitter draws it while `{by}` stands"
                )
            }
            Warning::DrawnOutOfReach {
                suite,
                suite_cases,
                draws,
                product,
                pose,
                cases,
                ..
            } => {
                write_drawn(f, suite, *suite_cases, *draws, cases)?;
                write!(
                    f,
                    " the robot cannot pick `{product}` where the jitter draws it: {pose} is out of its reach"
                )
            }
            Warning::TooClose {
                a,
                slot_a,
                b,
                slot_b,
                gap_mm,
                ..
            } => write!(
                f,
                "products `{a}` in slot `{slot_a}` and `{b}` in slot `{slot_b}` are {gap_mm:.1} mm apart, less than the {:.0} mm the robot keeps round a product it holds",
                HELD_ROOM * 1000.0
            ),
            Warning::DroppedHigh {
                product,
                slot,
                in_box,
                drop_mm,
                ..
            } => write!(
                f,
                "product `{product}` is let go {drop_mm:.0} mm above the floor of box `{in_box}` in slot `{slot}`: the arm cannot lower it further"
            ),
            Warning::NoSequenceRule {
                cell,
                best,
                agree,
                demonstrations,
                ..
            } => write!(
                f,
                "the demonstrations of cell `{cell}` follow no one sequence rule: the best, {best}, explains {agree} of {demonstrations}"
            ),
        }
    }
}

/// What the cases of a drawn warning (W003, W006) are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Draws {
    /// A `scenarios` block's scenarios.
    Scenarios,
    /// A single `scenario` (its one case is the block).
    Scenario,
    /// A `demos` block's demonstrations, which the expert replays for
    /// `train`.
    Demonstrations,
}

/// What fails in a drawn warning's cases, for its help: scenarios with
/// every planner (surely, where the pick is out of reach; else they
/// can), or demonstrations that the expert cannot replay.
fn who_fails(draws: Draws, surely: bool) -> &'static str {
    match (draws, surely) {
        (Draws::Scenario, false) => "this scenario can fail with every planner",
        (Draws::Scenarios, false) => "these scenarios can fail with every planner",
        (Draws::Scenario, true) => "this scenario fails with every planner",
        (Draws::Scenarios, true) => "these scenarios fail with every planner",
        (Draws::Demonstrations, _) => {
            "the expert cannot replay these demonstrations, and `train` stops at the first"
        }
    }
}

/// Which cases a drawn warning is about: "in scenario `x`" for a single
/// `scenario`, else "in 2 of 10 scenarios of `suite` (03, 07)" or "in 1
/// of 24 demonstrations of `teach` (05)".
fn write_drawn(
    f: &mut fmt::Formatter<'_>,
    suite: &str,
    suite_cases: usize,
    draws: Draws,
    cases: &[String],
) -> fmt::Result {
    let what = match draws {
        Draws::Scenario => return write!(f, "in scenario `{suite}`"),
        Draws::Scenarios => "scenarios",
        Draws::Demonstrations => "demonstrations",
    };
    write!(
        f,
        "in {} of {suite_cases} {what} of `{suite}` ({})",
        cases.len(),
        cases.join(", ")
    )
}

/// "while `other` stands at (x, y)", or "up to J mm from" there where
/// only the jitter's draws meet it (`drawn`).
fn write_met(
    f: &mut fmt::Formatter<'_>,
    (other, at, _): &(String, [f64; 2], Loc),
    jitter_mm: f64,
    drawn: bool,
) -> fmt::Result {
    let within = if drawn {
        format!("up to {jitter_mm:.0} mm from")
    } else {
        "at".to_owned()
    };
    write!(
        f,
        "while `{other}` stands {within} ({:.3}, {:.3})",
        at[0], at[1]
    )
}

/// Slots for people: "slot `a`", "slots `a` and `b`", "slots `a`, `b`
/// and 3 more".
pub(crate) fn slot_list(slots: &[String]) -> String {
    let named: Vec<String> = slots.iter().take(3).map(|s| format!("`{s}`")).collect();
    match (slots.len(), named.as_slice()) {
        (0, _) => "its slot".to_owned(),
        (1, [one]) => format!("slot {one}"),
        (2, [a, b]) => format!("slots {a} and {b}"),
        (3, [a, b, c]) => format!("slots {a}, {b} and {c}"),
        (n, [a, b, c]) => format!("slots {a}, {b}, {c} and {} more", n - 3),
        _ => format!("{} slots", slots.len()),
    }
}

impl Warning {
    /// Stable code, for documentation and tools.
    pub fn code(&self) -> &'static str {
        match self {
            Warning::PickBlocked { .. } => "W001",
            Warning::PlaceBlocked { .. } => "W007",
            Warning::TooClose { .. } => "W002",
            Warning::DrawnPickBlocked { .. } => "W003",
            Warning::DrawnOutOfReach { .. } => "W006",
            Warning::DroppedHigh { .. } => "W004",
            Warning::NoSequenceRule { .. } => "W005",
        }
    }

    /// Where the caret goes.
    pub fn at(&self) -> Loc {
        match self {
            Warning::PickBlocked { at, .. }
            | Warning::PlaceBlocked { at, .. }
            | Warning::TooClose { at, .. }
            | Warning::DrawnPickBlocked { at, .. }
            | Warning::DrawnOutOfReach { at, .. }
            | Warning::DroppedHigh { at, .. }
            | Warning::NoSequenceRule { at, .. } => *at,
        }
    }

    /// The short text under the caret.
    pub fn label(&self) -> String {
        match self {
            Warning::PickBlocked {
                pose: Pose::HoverFromStart,
                ..
            } => "the arm's every way to it from the start pose meets a product standing".into(),
            Warning::PickBlocked {
                pose: Pose::HoverFromBox,
                ..
            } => "the arm's every way to it from over the box meets a product standing".into(),
            Warning::PickBlocked {
                where_written: false,
                jitter_mm,
                ..
            } => format!(
                "every arm pose that reaches it meets a product beside it drawn up to {jitter_mm:.0} mm nearer"
            ),
            Warning::PickBlocked { .. } => {
                "every arm pose that reaches it meets a product beside it".into()
            }
            Warning::PlaceBlocked {
                pose,
                by: Some((other, ..)),
                ..
            } => format!("every arm pose at {pose} meets `{other}`, standing"),
            Warning::PlaceBlocked { pose, .. } => {
                format!("every arm pose at {pose} meets a product standing")
            }
            Warning::TooClose { .. } => "placed too close together".into(),
            Warning::DrawnPickBlocked { jitter_mm, .. } => format!(
                "moves each product up to {jitter_mm:.0} mm, two products up to {:.0} mm nearer each other",
                2.0 * jitter_mm
            ),
            Warning::DrawnOutOfReach { jitter_mm, .. } => {
                format!("moves each product up to {jitter_mm:.0} mm")
            }
            Warning::DroppedHigh { drop_mm, .. } => format!("drops it {drop_mm:.0} mm"),
            Warning::NoSequenceRule { sequence, .. } => {
                format!("handles {} in another order", sequence.join(", "))
            }
        }
    }

    /// Secondary places: (where, what it is).
    pub fn notes(&self) -> Vec<(Loc, String)> {
        match self {
            Warning::PickBlocked {
                by: Some((other, _, at)),
                ..
            } => vec![(*at, format!("`{other}` stands here"))],
            Warning::PlaceBlocked {
                by: Some((other, _, at)),
                ..
            } => vec![(*at, format!("`{other}` stands here"))],
            Warning::DrawnPickBlocked { by, by_at, .. } => {
                vec![(*by_at, format!("`{by}` stands here"))]
            }
            Warning::DrawnOutOfReach {
                product,
                product_at,
                ..
            } => vec![(*product_at, format!("`{product}` is written here"))],
            Warning::DroppedHigh {
                product,
                product_at,
                height_mm,
                side_mm,
                ..
            } => vec![(
                *product_at,
                format!("`{product}` stands {height_mm:.0} mm tall on a {side_mm:.0} mm side"),
            )],
            Warning::PickBlocked { .. }
            | Warning::PlaceBlocked { .. }
            | Warning::TooClose { .. }
            | Warning::NoSequenceRule { .. } => Vec::new(),
        }
    }

    /// How to fix it.
    pub fn help(&self) -> String {
        match self {
            Warning::PickBlocked {
                by,
                where_written: false,
                ..
            } => {
                let (other, apart) = by.as_ref().map_or(
                    ("the products beside it".to_owned(), "them"),
                    |(o, ..)| (format!("`{o}`"), "the two"),
                );
                format!(
                    "the pick is free with the products where they are written, and blocked where the jitter draws {other} nearer: lower the jitter of the inventory's blocks, or move {apart} further apart"
                )
            }
            Warning::PickBlocked {
                product,
                by: Some((other, ..)),
                by_packed: true,
                ..
            } => format!(
                "a package packs `{product}` only once `{other}` is gone: put `{other}` before it in the order's sequence, or move the two further apart"
            ),
            Warning::PickBlocked {
                by: Some((other, ..)),
                by_packed: false,
                ..
            } => format!(
                "no order or generator packs `{other}`, so it stands there in every package: move the two further apart, or take `{other}` out of the inventory"
            ),
            Warning::PickBlocked { product, .. } => format!(
                "a package packs `{product}` only once the products beside it are gone: pack those first, or give it more room"
            ),
            Warning::PlaceBlocked {
                by,
                where_written: false,
                jitter_mm,
                ..
            } => {
                let other = by
                    .as_ref()
                    .map_or("the products".to_owned(), |(o, ..)| format!("`{o}`"));
                format!(
                    "the placing is free with the products where they are written, and blocked where the jitter draws {other} up to {jitter_mm:.0} mm away: lower the jitter of the inventory's blocks, or move {other} further from the arm's way to the box"
                )
            }
            Warning::PlaceBlocked {
                product,
                by: Some((other, ..)),
                mutual: true,
                ..
            } => format!(
                "`{product}` stands in the way of placing `{other}` too (its own warning), so packing either first can stop the other, with every planner: move one of them (or the box) out of the arm's way to the box"
            ),
            Warning::PlaceBlocked {
                product,
                by: Some((other, ..)),
                by_packed: true,
                ..
            } => format!(
                "a package places `{product}` there only once `{other}` is gone, with every planner: put `{other}` before it in the order's sequence, or move `{other}` (or the box) out of the arm's way to the box"
            ),
            Warning::PlaceBlocked {
                by: Some((other, ..)),
                by_packed: false,
                ..
            } => format!(
                "no order or generator packs `{other}`, so it stands there in every package and every planner fails: move it (or the box) out of the arm's way to the box, or take `{other}` out of the inventory"
            ),
            Warning::PlaceBlocked { product, .. } => format!(
                "a package places `{product}` there only once the products in the arm's way are gone: pack those first, or move them or the box"
            ),
            Warning::DrawnPickBlocked {
                product,
                by,
                draws,
                ..
            } => {
                format!(
                    "{}: move `{product}` and `{by}` further apart, or lower the jitter",
                    who_fails(*draws, false)
                )
            }
            Warning::DrawnOutOfReach {
                product,
                nearer,
                draws,
                ..
            } => {
                let way = match nearer {
                    Some(true) => format!(
                        "move `{product}` further from the robot's base (the draws that fail lie nearer it)"
                    ),
                    Some(false) => format!(
                        "move `{product}` nearer the robot's base (the draws that fail lie farther out)"
                    ),
                    None => format!("move `{product}` where the arm reaches round it"),
                };
                format!(
                    "{}: {way} by the jitter, or lower the jitter",
                    who_fails(*draws, true)
                )
            }
            Warning::TooClose { gap_mm, .. } => format!(
                "the one packed second cannot be lowered past the other: it is let go above the other's top and can land on it; move the slots at least {:.1} mm further apart",
                (HELD_ROOM * 1000.0 - gap_mm).max(0.1)
            ),
            Warning::DroppedHigh { in_box, lower, .. } => {
                let fix = match lower {
                    Some(Lower::ProductOnBox) => format!(
                        "lower down, the product meets box `{in_box}` (the robot keeps {:.0} mm round a product it holds): move the slot further from the box's wall, or use a box with more room",
                        HELD_ROOM * 1000.0
                    ),
                    Some(Lower::ArmOnBox(part)) => format!(
                        "lower down, `{part}` meets box `{in_box}`: a longer suction cup or a shallower box may let the arm lower it to {RELEASE_GAP_MM:.0} mm above the floor"
                    ),
                    Some(Lower::Other(what)) => format!(
                        "lower down, {what}: move the box or the slot where the arm reaches lower"
                    ),
                    None => {
                        "give the slot more room, or use a longer suction cup or a shallower box"
                            .to_owned()
                    }
                };
                format!(
                    "dropped more than twice its width, a product over twice as tall as it is wide can land tilted and fall over, with every planner; {fix}"
                )
            }
            Warning::NoSequenceRule { .. } => "a model learns one order from demonstrations that mostly agree, and `train` refuses these taught on their own (exit 2): make this block's order agree with the others (or write `sequence random` where any order is right), or train on the blocks that agree with `train --demos`".to_owned(),
        }
    }
}
