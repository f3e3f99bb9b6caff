//! Phase 3: geometric checks on the resolved model. Every check runs and
//! reports; nothing here stops at the first error.

use crate::error::Error;
use crate::model::*;
use crate::source::Loc;
use crate::warning::{HELD_ROOM, Warning};

/// Slots closer than this are taken for the same slot.
pub const MIN_SLOT_DISTANCE: f64 = 0.010;
/// The built-in UR10's base on the table (m round its axis: its mount is
/// 190 mm across): no box or pending area may stand there.
pub const BASE_RADIUS: f64 = 0.095;

pub fn validate(m: &Model) -> Vec<Error> {
    let mut errors = Vec::new();
    for cell in &m.cells {
        check_cell(cell, &mut errors);
    }
    for inv in &m.inventories {
        let positions: Vec<[f64; 2]> = inv.entries.iter().map(|e| e.at).collect();
        let locs: Vec<Loc> = inv.entries.iter().map(|e| e.loc).collect();
        check_layout(m, inv, &positions, &locs, &mut errors, None);
    }
    for order in &m.orders {
        let inv = &m.inventories[order.inventory];
        let pairs: Vec<(usize, usize, Loc)> = order
            .assignment
            .iter()
            .map(|a| (a.entry, a.slot, a.loc))
            .collect();
        check_placement(m, inv, &pairs, &mut errors);
    }
    for demo in &m.demos {
        let inv = &m.inventories[m.orders[demo.order].inventory];
        check_overrides(m, inv, &demo.at, &mut errors);
    }
    for sc in &m.scenarios {
        let inv = &m.inventories[m.orders[sc.order].inventory];
        check_overrides(m, inv, &sc.at, &mut errors);
    }
    for d in &m.demo_sets {
        check_choose(m, &m.inventories[d.inventory], &d.choose, &mut errors);
    }
    for s in &m.scenario_sets {
        check_choose(m, &m.inventories[s.inventory], &s.choose, &mut errors);
    }
    errors
}

/// What the geometry allows but the robot may fail at: products placed
/// closer together than the room kept round a held product, in an order
/// or by a generator (each slot pair once per generator, with the
/// products that come closest there).
pub fn warnings(m: &Model) -> Vec<Warning> {
    let mut warnings = Vec::new();
    for order in &m.orders {
        let inv = &m.inventories[order.inventory];
        let cell = &m.cells[inv.cell];
        let placed = |i: usize| {
            let a = &order.assignment[i];
            let product = &m.products[inv.entries[a.entry].product];
            (product, a.slot, product.footprint(cell.slots[a.slot].at))
        };
        for i in 0..order.assignment.len() {
            for j in 0..i {
                let ((pa, sa, fa), (pb, sb, fb)) = (placed(j), placed(i));
                if let Some(w) =
                    too_close(cell, order.assignment[i].loc, (pa, sa, fa), (pb, sb, fb))
                {
                    warnings.push(w);
                }
            }
        }
    }
    for (choose, inv) in m
        .demo_sets
        .iter()
        .map(|d| (&d.choose, d.inventory))
        .chain(m.scenario_sets.iter().map(|s| (&s.choose, s.inventory)))
    {
        let inv = &m.inventories[inv];
        let cell = &m.cells[inv.cell];
        if choose.n < 2 {
            continue;
        }
        let product = |e: usize| &m.products[inv.entries[e].product];
        for (i, &s) in choose.slots.iter().enumerate() {
            for &t in &choose.slots[..i] {
                let closest = choose
                    .entries
                    .iter()
                    .flat_map(|&a| {
                        choose
                            .entries
                            .iter()
                            .filter(move |&&b| b != a)
                            .map(move |&b| (a, b))
                    })
                    .map(|(a, b)| {
                        let fa = product(a).footprint(cell.slots[t].at);
                        let fb = product(b).footprint(cell.slots[s].at);
                        (fa.gap(&fb), a, b, fa, fb)
                    })
                    .min_by(|x, y| x.0.total_cmp(&y.0));
                if let Some((_, a, b, fa, fb)) = closest
                    && let Some(w) =
                        too_close(cell, choose.loc, (product(a), t, fa), (product(b), s, fb))
                {
                    warnings.push(w);
                }
            }
        }
    }
    warnings
}

/// [`Warning::TooClose`] for two placed products (product, slot,
/// footprint) in the same box closer than [`HELD_ROOM`] but not
/// overlapping (an error, `PlacedOverlap`).
fn too_close(
    cell: &Cell,
    at: Loc,
    (pa, sa, fa): (&Product, usize, Rect),
    (pb, sb, fb): (&Product, usize, Rect),
) -> Option<Warning> {
    let gap = fa.gap(&fb);
    let same_box = cell.slots[sa].box_index == cell.slots[sb].box_index;
    (same_box && gap < HELD_ROOM - 1e-9 && !fa.overlaps(&fb)).then(|| Warning::TooClose {
        at,
        a: pa.name.clone(),
        slot_a: cell.slots[sa].name.clone(),
        b: pb.name.clone(),
        slot_b: cell.slots[sb].name.clone(),
        gap_mm: gap * 1000.0,
    })
}

fn distance_to_base(cell: &Cell, p: [f64; 2]) -> f64 {
    ((p[0] - cell.base[0]).powi(2) + (p[1] - cell.base[1]).powi(2)).sqrt()
}

/// The UR10's reach; other arms are checked by inverse kinematics at run time.
fn check_reach(cell: &Cell, p: [f64; 2], at: Loc, what: String, errors: &mut Vec<Error>) {
    if cell.robot != RobotModel::Ur10 {
        return;
    }
    let d = distance_to_base(cell, p);
    if !(UR10_REACH_MIN..=UR10_REACH_MAX).contains(&d) {
        errors.push(Error::OutOfReach {
            at,
            what,
            distance: d,
            min: UR10_REACH_MIN,
            max: UR10_REACH_MAX,
        });
    }
}

fn check_cell(cell: &Cell, errors: &mut Vec<Error>) {
    // The robot's base stands on the table: a circle of BASE_RADIUS round
    // its axis for the built-in UR10, its axis for another arm.
    let base = Rect::centred([cell.base[0], cell.base[1]], 0.0, 0.0);
    let base_radius = if cell.robot == RobotModel::Ur10 {
        BASE_RADIUS
    } else {
        0.0
    };
    let over_base = |r: &Rect| r.gap(&base) < base_radius || r.contains(base.min);
    let base_fix = |what: &str| {
        format!(
            "the robot's base stands at ({:.3}, {:.3}), {:.0} mm round its axis: move the {what} away from it, or the `base`",
            cell.base[0],
            cell.base[1],
            base_radius * 1000.0
        )
    };
    // Products cannot stand within the arm's reach from the axis anyway
    // (E036): an area that only clips the base's edge holds none there.
    if cell.pending.contains(base.min) {
        errors.push(Error::BadGeometry {
            at: cell.pending_loc,
            what: "the pending area covers the robot's base axis".into(),
            fix: base_fix("pending area"),
        });
    }
    for (i, b) in cell.boxes.iter().enumerate() {
        if b.footprint().overlaps(&cell.pending) {
            errors.push(Error::BadGeometry {
                at: b.loc,
                what: format!("box `{}` overlaps the pending area", b.name),
                fix: "move the box or the pending area apart".into(),
            });
        }
        if over_base(&b.footprint()) {
            errors.push(Error::BadGeometry {
                at: b.loc,
                what: format!("box `{}` stands over the robot's base", b.name),
                fix: base_fix("box"),
            });
        }
        for a in &cell.boxes[..i] {
            if a.footprint().overlaps(&b.footprint()) {
                errors.push(Error::BadGeometry {
                    at: b.loc,
                    what: format!("boxes `{}` and `{}` overlap", a.name, b.name),
                    fix: "move one of them: each box stands on its own part of the table (a box's position is its centre, its size width, depth and height)".into(),
                });
            }
        }
    }
    for (i, s) in cell.slots.iter().enumerate() {
        let b = &cell.boxes[s.box_index];
        let excess = outside_box(cell, s);
        if excess > 0.0 {
            errors.push(Error::SlotOutsideBox {
                at: s.loc,
                slot: s.name.clone(),
                box_name: b.name.clone(),
                by_mm: excess * 1000.0,
            });
        }
        // The first earlier slot too close, alone: one error per slot
        // (20,000 slots written at one point made 200 million pairs,
        // more than the machine's memory).
        let close = cell.slots[..i].iter().find_map(|t| {
            let d = ((s.at[0] - t.at[0]).powi(2) + (s.at[1] - t.at[1]).powi(2)).sqrt();
            (d < MIN_SLOT_DISTANCE).then_some((t, d))
        });
        if let Some((t, d)) = close {
            errors.push(Error::SlotsOverlap {
                at: s.loc,
                first: t.loc,
                a: t.name.clone(),
                b: s.name.clone(),
                distance_mm: d * 1000.0,
            });
        }
        check_reach(cell, s.at, s.loc, format!("slot `{}`", s.name), errors);
    }
}

/// Products at `positions` (one per inventory entry): inside the pending
/// area, apart, within reach. `only` restricts the checks to some entries
/// (the ones a demo or scenario moved).
fn check_layout(
    m: &Model,
    inv: &Inventory,
    positions: &[[f64; 2]],
    locs: &[Loc],
    errors: &mut Vec<Error>,
    only: Option<&[usize]>,
) {
    let cell = &m.cells[inv.cell];
    let checked = |i: usize| only.is_none_or(|o| o.contains(&i));
    for (i, e) in inv.entries.iter().enumerate() {
        if !checked(i) {
            continue;
        }
        let product = &m.products[e.product];
        let fp = product.footprint(positions[i]);
        let excess = cell.pending.excess(&fp);
        if excess > 0.0 {
            errors.push(Error::OutsidePending {
                at: locs[i],
                product: product.name.clone(),
                cell: cell.name.clone(),
                by_mm: excess * 1000.0,
            });
        }
        // Each pair once: against earlier entries, or any entry not
        // checked; the first overlap alone (one error per product, not
        // one per pair: 8,000 products at one spot made 32 million).
        let overlapping = inv.entries.iter().enumerate().find(|&(j, other)| {
            !(j == i || (j > i && checked(j)))
                && fp.overlaps(&m.products[other.product].footprint(positions[j]))
        });
        if let Some((j, other)) = overlapping {
            errors.push(Error::ProductsOverlap {
                at: locs[i],
                other: locs[j],
                a: product.name.clone(),
                b: m.products[other.product].name.clone(),
            });
        }
        check_reach(
            cell,
            positions[i],
            locs[i],
            format!("product `{}`", product.name),
            errors,
        );
    }
}

fn check_overrides(m: &Model, inv: &Inventory, placed: &[Placed], errors: &mut Vec<Error>) {
    if placed.is_empty() {
        return;
    }
    let mut positions: Vec<[f64; 2]> = inv.entries.iter().map(|e| e.at).collect();
    let mut locs: Vec<Loc> = inv.entries.iter().map(|e| e.loc).collect();
    for p in placed {
        positions[p.entry] = p.at;
        locs[p.entry] = p.loc;
    }
    let moved: Vec<usize> = placed.iter().map(|p| p.entry).collect();
    check_layout(m, inv, &positions, &locs, errors, Some(&moved));
}

/// How far a product in a slot would stick out of the slot's box (0 if
/// not, and 0 for a slot outside its box: E030 says so once, where the
/// slot is written, instead of once per product and statement that uses
/// it).
fn fit_excess(cell: &Cell, product: &Product, slot: usize) -> f64 {
    let s = &cell.slots[slot];
    if outside_box(cell, s) > 0.0 {
        return 0.0;
    }
    cell.boxes[s.box_index]
        .footprint()
        .excess(&product.footprint(s.at))
}

/// How far slot `s`'s centre lies outside its box (m; 0 inside): E030's
/// measure.
fn outside_box(cell: &Cell, s: &Slot) -> f64 {
    cell.boxes[s.box_index]
        .footprint()
        .excess(&Rect::centred(s.at, 0.0, 0.0))
}

/// Each (product, slot) pair fits its box, and no two placed products overlap.
fn check_placement(
    m: &Model,
    inv: &Inventory,
    pairs: &[(usize, usize, Loc)],
    errors: &mut Vec<Error>,
) {
    let cell = &m.cells[inv.cell];
    for (i, &(entry, slot, at)) in pairs.iter().enumerate() {
        let product = &m.products[inv.entries[entry].product];
        let excess = fit_excess(cell, product, slot);
        if excess > 0.0 {
            errors.push(Error::DoesNotFit {
                at,
                product: product.name.clone(),
                slot: cell.slots[slot].name.clone(),
                box_name: cell.boxes[cell.slots[slot].box_index].name.clone(),
                by_mm: excess * 1000.0,
                also: Vec::new(),
            });
        }
        for &(other, other_slot, _) in &pairs[..i] {
            let op = &m.products[inv.entries[other].product];
            if product
                .footprint(cell.slots[slot].at)
                .overlaps(&op.footprint(cell.slots[other_slot].at))
            {
                errors.push(Error::PlacedOverlap {
                    at,
                    a: op.name.clone(),
                    slot_a: cell.slots[other_slot].name.clone(),
                    b: product.name.clone(),
                    slot_b: cell.slots[slot].name.clone(),
                });
            }
        }
    }
}

/// A generator may put any listed product into any listed slot: every pair
/// must fit, and every two products in every two slots must not overlap.
/// Reported once per product (fit) and once per slot pair (overlap).
fn check_choose(m: &Model, inv: &Inventory, c: &Choose, errors: &mut Vec<Error>) {
    let cell = &m.cells[inv.cell];
    let product = |e: usize| &m.products[inv.entries[e].product];
    for &e in &c.entries {
        let misfits: Vec<(usize, f64)> = c
            .slots
            .iter()
            .map(|&s| (s, fit_excess(cell, product(e), s)))
            .filter(|(_, x)| *x > 0.0)
            .collect();
        if let Some((&(slot, excess), rest)) = misfits.split_first() {
            errors.push(Error::DoesNotFit {
                at: c.loc,
                product: product(e).name.clone(),
                slot: cell.slots[slot].name.clone(),
                box_name: cell.boxes[cell.slots[slot].box_index].name.clone(),
                by_mm: excess * 1000.0,
                also: rest
                    .iter()
                    .map(|&(s, _)| cell.slots[s].name.clone())
                    .collect(),
            });
        }
    }
    if c.n < 2 {
        return;
    }
    for (i, &s) in c.slots.iter().enumerate() {
        for &t in &c.slots[..i] {
            let clash = c.entries.iter().find_map(|&a| {
                c.entries
                    .iter()
                    .filter(|&&b| b != a)
                    .find(|&&b| {
                        product(a)
                            .footprint(cell.slots[t].at)
                            .overlaps(&product(b).footprint(cell.slots[s].at))
                    })
                    .map(|&b| (a, b))
            });
            if let Some((a, b)) = clash {
                errors.push(Error::PlacedOverlap {
                    at: c.loc,
                    a: product(a).name.clone(),
                    slot_a: cell.slots[t].name.clone(),
                    b: product(b).name.clone(),
                    slot_b: cell.slots[s].name.clone(),
                });
            }
        }
    }
}
