//! Phase 4b: what a suite's draws block. W001 ([`workspace`]) asks about
//! each pick at the product's written place, the products beside it
//! widened by the jitter; but the picked product jitters too, so two
//! products may be drawn up to twice the jitter nearer each other, and a
//! pick W001 passes can be blocked in some scenarios, with every planner.
//! Here the picks the others may block at twice the jitter (a few
//! questions per inventory) are asked again at each scenario's drawn
//! positions, and the scenarios where a product stands in the way are
//! named ([`Warning::DrawnPickBlocked`]).
//!
//! The same for reach: a pick E039 passes at the written place can be out
//! of the arm's reach where a suite's jitter draws it (a product near a
//! base on a riser, drawn nearer the base); the entries that a move by
//! the jitter along the line from the base axis takes out of reach are
//! asked again at each scenario's draw, and the scenarios named
//! ([`Warning::DrawnOutOfReach`]).
//!
//! Invariants: only suites with a jitter are asked about (a `scenarios`
//! block's, or a single `scenario`'s: one case, the order's picks), and
//! only their picks that W001 does not already warn about (at the
//! written places, the others widened by the jitter, the pick is free);
//! one warning per suite, picked product and product met; a case is asked
//! about with the products that stand when its package starts (not those
//! missing, nor those a worker packed), so a product packed before the
//! pick may be gone by then: a warning, not an error.
//!
//! [`workspace`]: crate::workspace

use crate::expand::{Case, Expanded};
use crate::model::{DemosDef, Model};
use crate::source::Loc;
use crate::warning::{Draws, Warning};
use crate::workspace::{Pose, Standing, Workspace, along_from_base};
use packwright_grammar::ast::SequenceMode;
use std::borrow::Cow;
use std::collections::BTreeMap;

/// A suite the jitter draws: a `scenarios` block's cases, a single
/// `scenario`'s one case, or a `demos` block's demonstrations.
struct Drawn<'a> {
    name: &'a str,
    draws: Draws,
    inventory: usize,
    /// The inventory entries its cases may pick.
    picks: Vec<usize>,
    jitter: f64,
    /// Its `jitter` statement, else the block.
    at: Loc,
    cases: Cow<'a, [Case]>,
    /// Each case's order of picks, for demonstrations (their sequences);
    /// empty for scenarios, whose order the demonstrations declare
    /// ([`packed_before`]).
    sequences: Vec<Vec<usize>>,
}

/// The suites of `x` (expanded from `m`) that the jitter draws.
fn drawn<'a>(m: &'a Model, x: &'a Expanded) -> Vec<Drawn<'a>> {
    let cases = |kind: &str, name: &str| {
        x.suites
            .iter()
            .find(|x| x.kind == kind && x.name == name)
            .map(|x| Cow::Borrowed(x.cases.as_slice()))
    };
    let sets = m
        .scenario_sets
        .iter()
        .filter(|s| s.jitter > 0.0)
        .filter_map(|s| {
            Some(Drawn {
                name: &s.name,
                draws: Draws::Scenarios,
                inventory: s.inventory,
                picks: s.choose.entries.clone(),
                jitter: s.jitter,
                at: s.jitter_loc.unwrap_or(s.loc),
                cases: cases("scenarios", &s.name)?,
                sequences: Vec::new(),
            })
        });
    let singles = m
        .scenarios
        .iter()
        .filter(|s| s.jitter > 0.0)
        .filter_map(|s| {
            let order = m.orders.get(s.order)?;
            Some(Drawn {
                name: &s.name,
                draws: Draws::Scenario,
                inventory: order.inventory,
                picks: order.assignment.iter().map(|a| a.entry).collect(),
                jitter: s.jitter,
                at: s.jitter_loc.unwrap_or(s.loc),
                cases: cases("scenario", &s.name)?,
                sequences: Vec::new(),
            })
        });
    sets.chain(singles).chain(demonstrated(m, x)).collect()
}

/// The `demos` blocks with a jitter, each with its demonstrations as
/// cases (numbered among all the file's demonstrations from 1, as
/// `train` names one it cannot replay) and their sequences. None where
/// a demonstration cannot be generated (expansion reported why).
fn demonstrated<'a>(m: &'a Model, x: &'a Expanded) -> Vec<Drawn<'a>> {
    let jittered: Vec<(usize, &DemosDef, usize)> = x
        .blocks
        .iter()
        .enumerate()
        .filter(|(_, b)| b.kind == "demos")
        .filter_map(|(i, b)| {
            let d = m.demo_sets.iter().find(|d| d.name == b.name)?;
            (d.jitter > 0.0).then_some((i, d, b.first_demo))
        })
        .collect();
    if jittered.is_empty() {
        return Vec::new();
    }
    let mut drawn: Vec<Drawn> = jittered
        .iter()
        .map(|(_, d, _)| Drawn {
            name: &d.name,
            draws: Draws::Demonstrations,
            inventory: d.inventory,
            picks: d.choose.entries.clone(),
            jitter: d.jitter,
            at: d.jitter_loc.unwrap_or(d.loc),
            cases: Cow::Owned(Vec::new()),
            sequences: Vec::new(),
        })
        .collect();
    for demo in x.demonstrations(m) {
        let Ok(demo) = demo else {
            return Vec::new();
        };
        let Some(at) = jittered.iter().position(|(b, ..)| *b == demo.block) else {
            continue;
        };
        let first = jittered[at].2;
        let d = &mut drawn[at];
        let number = first + d.cases.len() + 1;
        d.cases.to_mut().push(Case {
            name: number.to_string(),
            setup: demo.setup,
        });
        d.sequences.push(demo.sequence);
    }
    drawn
}

/// The warnings for every suite of `x` (expanded from `m`).
pub fn check(m: &Model, x: &Expanded, ws: &dyn Workspace) -> Vec<Warning> {
    let mut warnings = Vec::new();
    for s in drawn(m, x) {
        for entry in suspects(m, &s, ws) {
            warnings.extend(blocked_in(m, &s, entry, ws));
        }
        for entry in near_the_edge(m, &s, ws) {
            warnings.extend(out_of_reach_in(m, &s, entry, ws));
        }
    }
    warnings
}

/// The entries `s` may pick that the empty cell lets the robot pick at
/// their written place (else E039) but not at one moved by the jitter
/// along the line from the robot's base axis (√2 times it: a draw's
/// farthest reach), nearer or farther: a few questions per entry, asked
/// again at each scenario's draw only for these.
fn near_the_edge(m: &Model, s: &Drawn, ws: &dyn Workspace) -> Vec<usize> {
    let inv = &m.inventories[s.inventory];
    let Some(cell) = m.cells.get(inv.cell) else {
        return Vec::new();
    };
    s.picks
        .iter()
        .copied()
        .filter(|&k| {
            let Some(e) = inv.entries.get(k) else {
                return false;
            };
            let reach = std::f64::consts::SQRT_2 * s.jitter;
            let out_of_reach = |by: f64| {
                along_from_base(cell.base, e.at, by)
                    .is_some_and(|moved| ws.pick(m, inv.cell, e.product, moved).is_some())
            };
            ws.pick(m, inv.cell, e.product, e.at).is_none()
                && (out_of_reach(reach) || out_of_reach(-reach))
        })
        .collect()
}

/// The warning for entry `k` of `s`, if the empty cell does not let the
/// robot pick it where some of the cases draw it.
fn out_of_reach_in(m: &Model, s: &Drawn, k: usize, ws: &dyn Workspace) -> Option<Warning> {
    let inv = &m.inventories[s.inventory];
    let cell = m.cells.get(inv.cell)?;
    let entry = inv.entries.get(k)?;
    let from_base = |at: [f64; 2]| (at[0] - cell.base[0]).hypot(at[1] - cell.base[1]);
    let written = from_base(entry.at);
    let mut out: Vec<(String, Pose, bool)> = Vec::new();
    for case in s.cases.iter() {
        let Some(at) = picked_at(case, k) else {
            continue;
        };
        if let Some(u) = ws.pick(m, inv.cell, entry.product, at) {
            out.push((number(case).to_owned(), u.pose, from_base(at) < written));
        }
    }
    let (_, pose, first_nearer) = out.first()?.clone();
    let nearer = out
        .iter()
        .all(|(_, _, n)| *n == first_nearer)
        .then_some(first_nearer);
    Some(Warning::DrawnOutOfReach {
        at: s.at,
        suite: s.name.to_owned(),
        suite_cases: s.cases.len(),
        draws: s.draws,
        product: m.products[entry.product].name.clone(),
        product_at: entry.loc,
        pose,
        cases: out.into_iter().map(|(name, ..)| name).collect(),
        jitter_mm: s.jitter * 1000.0,
        nearer,
    })
}

/// The entries `s` may pick whose pick is free at the written places with
/// the others widened by the jitter (else W001 warns), and blocked with
/// them widened by twice the jitter.
fn suspects(m: &Model, s: &Drawn, ws: &dyn Workspace) -> Vec<usize> {
    let inv = &m.inventories[s.inventory];
    let others = |k: usize, margin: f64| -> Vec<Standing> {
        inv.entries
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != k)
            .map(|(_, e)| Standing {
                product: e.product,
                at: e.at,
                margin,
            })
            .collect()
    };
    s.picks
        .iter()
        .copied()
        .filter(|&k| {
            let Some(e) = inv.entries.get(k) else {
                return false;
            };
            let blocked = |margin| {
                ws.pick_among(m, inv.cell, e.product, e.at, &others(k, margin))
                    .is_some()
            };
            ws.pick(m, inv.cell, e.product, e.at).is_none()
                && !blocked(s.jitter)
                && blocked(2.0 * s.jitter)
        })
        .collect()
}

/// Where `case` draws entry `k`, when the robot picks it there (its
/// package places it, and no worker packed it first).
fn picked_at(case: &Case, k: usize) -> Option<[f64; 2]> {
    let setup = &case.setup;
    let picked = setup.slot_of(k).is_some() && !setup.human_packed.contains(&k);
    setup.positions.get(k).copied().filter(|_| picked)
}

/// A case's number within its suite, as warnings name it ("04").
fn number(case: &Case) -> &str {
    case.name.rsplit('/').next().unwrap_or(&case.name)
}

/// Whether entry `j` of inventory `i` is packed before entry `k`, by the
/// order the inventory's demonstrations declare, when they all declare
/// the same one: each `demos` block's rule (ascending or descending
/// inventory order, or one `listed` priority naming both) and each
/// hand-written `demo` that moves both (its sequence); by inventory
/// order where nothing demonstrates the inventory (the order packed when
/// no demonstration shows one); `None` when they do not say, or
/// disagree.
fn packed_before(m: &Model, i: usize, j: usize, k: usize) -> Option<bool> {
    let written: Vec<&crate::model::DemoDef> = m
        .demos
        .iter()
        .filter(|d| m.orders.get(d.order).is_some_and(|o| o.inventory == i))
        .collect();
    let blocks: Vec<_> = m.demo_sets.iter().filter(|d| d.inventory == i).collect();
    if blocks.is_empty() && written.is_empty() {
        return Some(j < k);
    }
    let generated = blocks.iter().map(|d| {
        let place = |e: usize| d.choose.entries.iter().position(|&x| x == e);
        match d.sequence {
            SequenceMode::Ascending => Some(j < k),
            SequenceMode::Descending => Some(j > k),
            SequenceMode::Listed => Some(place(j)? < place(k)?),
            SequenceMode::Random => None,
        }
    });
    // A hand-written demonstration says only about the products it moves.
    let shown = written.iter().filter_map(|d| {
        let place = |e: usize| d.sequence.iter().position(|&x| x == e);
        Some(Some(place(j)? < place(k)?))
    });
    let mut rules = generated.chain(shown);
    let first = rules.next()??;
    rules.all(|r| r == Some(first)).then_some(first)
}

/// The warnings for entry `k` of `s`: per product met, the cases where
/// the pick of `k`, at its drawn place, is blocked by it.
fn blocked_in(m: &Model, s: &Drawn, k: usize, ws: &dyn Workspace) -> Vec<Warning> {
    let inv = &m.inventories[s.inventory];
    // The file's order for each other entry, the same in every case.
    let declared: Vec<Option<bool>> = (0..inv.entries.len())
        .map(|j| packed_before(m, s.inventory, j, k))
        .collect();
    let before = |j: usize| declared.get(j).copied().flatten();
    let mut by_other: BTreeMap<usize, Vec<String>> = BTreeMap::new();
    for (c, case) in s.cases.iter().enumerate() {
        let setup = &case.setup;
        let Some(at) = picked_at(case, k) else {
            continue;
        };
        // A demonstration's own sequence says what it packs before `k`.
        let place = |e: usize| s.sequences.get(c)?.iter().position(|&x| x == e);
        let packed_first = |j: usize| match (place(j), place(k)) {
            (Some(pj), Some(pk)) => Some(pj < pk),
            _ => before(j),
        };
        // The others standing when `k` is picked, with their entries: not
        // missing, not packed by a worker, and not packed before it (a
        // product the case packs too, in an order the file does not say,
        // may be gone: not asked about).
        let stands = |j: usize| {
            j != k
                && !setup.missing.contains(&j)
                && !setup.human_packed.contains(&j)
                && (setup.slot_of(j).is_none() || packed_first(j) == Some(false))
        };
        let (standing, entries): (Vec<Standing>, Vec<usize>) = (0..inv.entries.len())
            .filter(|&j| stands(j))
            .filter_map(|j| {
                let at = *setup.positions.get(j)?;
                let product = inv.entries[j].product;
                Some((
                    Standing {
                        product,
                        at,
                        margin: 0.0,
                    },
                    j,
                ))
            })
            .unzip();
        let met = ws
            .pick_among(m, inv.cell, inv.entries[k].product, at, &standing)
            .and_then(|b| b.by)
            .and_then(|i| entries.get(i));
        if let Some(&j) = met {
            by_other.entry(j).or_default().push(number(case).to_owned());
        }
    }
    let name = |j: usize| m.products[inv.entries[j].product].name.clone();
    by_other
        .into_iter()
        .map(|(j, cases)| Warning::DrawnPickBlocked {
            at: s.at,
            suite: s.name.to_owned(),
            suite_cases: s.cases.len(),
            draws: s.draws,
            product: name(k),
            by: name(j),
            by_at: inv.entries[j].loc,
            cases,
            jitter_mm: s.jitter * 1000.0,
        })
        .collect()
}
