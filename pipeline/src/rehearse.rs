//! Rehearsals: the expert's own motions to the products and slots of a
//! taught cell that no chosen demonstration moved.
//!
//! A person's demonstrations teach the reasoner the order to pack in; the
//! motion networks learn from the expert's replays of them. A handful of
//! hand-written demonstrations moves two or three of a cell's products
//! into two or three of its slots, so the sub-goal planner and the
//! dynamics policy would see only those (a model taught one demonstration
//! of two products hovered beside a third product and came down through
//! the box). The expert can pack any product into any slot, so `train`
//! has it rehearse the rest too: motion examples only, never decisions
//! for the reasoner, whose lessons stay the person's.

use packwright_compiler::artifact::{Assignment, At, DemonstrationRecord, SlotRecord, WorldFile};
use std::collections::{BTreeMap, BTreeSet};

/// The block name rehearsals carry (no `demo` or `demos` block can have
/// it: it is not an identifier of the language).
pub const REHEARSAL: &str = "(rehearsal)";

/// A product waiting within this distance (m) of where it was moved from
/// is not rehearsed again (the same product at the same place in
/// another inventory of the cell).
const SAME_PLACE: f64 = 0.01;

/// The expert's rehearsals for `chosen`: for each inventory of the cells
/// they teach (in file order, those the demonstrations use or not),
/// orders that move each of its products and each of its cell's slots
/// that neither a chosen demonstration nor an earlier rehearsal moved
/// (a product from where it waits in that inventory, within
/// [`SAME_PLACE`]), at
/// least once (paired in listed order, topped up with ones already moved
/// where one side runs out), every product at its inventory position,
/// packed in listed order, as many per order as the most a chosen
/// demonstration of the cell packed. Empty when the demonstrations moved
/// every product of every inventory and every slot; deterministic.
pub fn rehearsals(world: &WorldFile, chosen: &[DemonstrationRecord]) -> Vec<DemonstrationRecord> {
    // Products moved so far (cell, product, where it waits: one waiting
    // where another inventory has it is moved there too), (cell, slot)
    // pairs moved so far, and the most products one demonstration of a
    // cell packed.
    let mut products_moved: Vec<(&str, &str, [f64; 3])> = Vec::new();
    let mut slots_moved: BTreeSet<(&str, &str)> = BTreeSet::new();
    let mut most: BTreeMap<&str, usize> = BTreeMap::new();
    let waiting = |inventory: &str, product: &str| {
        world
            .inventories
            .iter()
            .find(|i| i.name == inventory)
            .and_then(|i| i.products.iter().find(|p| p.product == product))
            .map(|p| p.at)
    };
    for d in chosen {
        for a in &d.assignment {
            if d.sequence.contains(&a.product) {
                if let Some(at) = waiting(&d.inventory, &a.product) {
                    products_moved.push((&d.cell, &a.product, at));
                }
                slots_moved.insert((&d.cell, &a.slot));
            }
        }
        let m = most.entry(&d.cell).or_default();
        *m = (*m).max(d.sequence.len());
    }
    let mut out = Vec::new();
    for inv in &world.inventories {
        let (Some(&most), Some(cell)) = (
            most.get(inv.cell.as_str()),
            world.cells.iter().find(|c| c.name == inv.cell),
        ) else {
            continue;
        };
        let moved = |p: &&At| {
            products_moved.iter().any(|&(c, name, at)| {
                c == inv.cell
                    && name == p.product
                    && (at[0] - p.at[0]).hypot(at[1] - p.at[1]) < SAME_PLACE
            })
        };
        let (products, unmoved_products) = unmoved_first(&inv.products, moved);
        let (slots, unmoved_slots) = unmoved_first(&cell.slots, |s: &&SlotRecord| {
            slots_moved.contains(&(cell.name.as_str(), s.name.as_str()))
        });
        if products.is_empty() || slots.is_empty() {
            continue;
        }
        // Consecutive pairs are distinct products and distinct slots as
        // long as an order holds no more than either list.
        let per_order = most.clamp(1, products.len().min(slots.len()));
        let pairs: Vec<(&At, &SlotRecord)> = (0..unmoved_products.max(unmoved_slots))
            .map(|i| (products[i % products.len()], slots[i % slots.len()]))
            .collect();
        for group in pairs.chunks(per_order) {
            let height = |p: &At| {
                world
                    .products
                    .iter()
                    .find(|r| r.name == p.product)
                    .map_or(0.0, |r| r.size[2])
            };
            let assignment: Vec<Assignment> = group
                .iter()
                .map(|(p, s)| Assignment {
                    product: p.product.clone(),
                    slot: s.name.clone(),
                    label: s.label,
                    goal: [s.position[0], s.position[1], height(p) / 2.0],
                })
                .collect();
            let listed: BTreeSet<&str> = group.iter().map(|(p, _)| p.product.as_str()).collect();
            let sequence = inv
                .products
                .iter()
                .filter(|p| listed.contains(p.product.as_str()))
                .map(|p| p.product.clone())
                .collect();
            out.push(DemonstrationRecord {
                block: REHEARSAL.to_owned(),
                cell: cell.name.clone(),
                inventory: inv.name.clone(),
                assignment,
                sequence,
                human_packed: Vec::new(),
                missing: Vec::new(),
                start: inv.products.clone(),
                first_sample: 0,
                samples: 0,
            });
        }
        for (p, s) in pairs {
            products_moved.push((&cell.name, &p.product, p.at));
            slots_moved.insert((&cell.name, &s.name));
        }
    }
    out
}

/// `items` not yet `moved` first, then the moved ones to top up with, and
/// how many were not yet moved.
fn unmoved_first<T>(items: &[T], moved: impl Fn(&&T) -> bool) -> (Vec<&T>, usize) {
    let (mut first, then): (Vec<&T>, Vec<&T>) = items.iter().partition(|i| !moved(i));
    let unmoved = first.len();
    first.extend(then);
    (first, unmoved)
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_compiler::artifact::{
        CellRecord, InventoryRecord, ProductRecord, RectRecord, RobotRecord,
    };

    fn world(products: usize, slots: usize) -> WorldFile {
        let name = |i: usize| format!("p{i}");
        WorldFile {
            schema: "test".into(),
            version: 0,
            cells: vec![CellRecord {
                name: "c".into(),
                robot: RobotRecord::Ur10,
                base: [0.0; 3],
                suction: 0.1,
                lift: 0.15,
                speed: 1.0,
                grip_settle: 0.5,
                release_settle: 0.5,
                descent: 1.0,
                acceleration: None,
                jerk: None,
                pending: RectRecord {
                    min: [0.0, 0.0],
                    max: [1.0, 1.0],
                },
                boxes: Vec::new(),
                slots: (0..slots)
                    .map(|i| SlotRecord {
                        name: format!("s{i}"),
                        label: i as u32 + 1,
                        box_name: "b".into(),
                        position: [0.1 * i as f64, -0.5],
                    })
                    .collect(),
            }],
            products: (0..products)
                .map(|i| ProductRecord {
                    name: name(i),
                    size: [0.05, 0.05, 0.04],
                    mass: None,
                })
                .collect(),
            inventories: vec![InventoryRecord {
                name: "inv".into(),
                cell: "c".into(),
                products: (0..products)
                    .map(|i| At {
                        product: name(i),
                        at: [0.5, 0.1 * i as f64, 0.02],
                    })
                    .collect(),
            }],
            orders: Vec::new(),
        }
    }

    fn demo(world: &WorldFile, pairs: &[(usize, usize)]) -> DemonstrationRecord {
        DemonstrationRecord {
            block: "seen".into(),
            cell: "c".into(),
            inventory: "inv".into(),
            assignment: pairs
                .iter()
                .map(|&(p, s)| Assignment {
                    product: format!("p{p}"),
                    slot: format!("s{s}"),
                    label: s as u32 + 1,
                    goal: [0.0; 3],
                })
                .collect(),
            sequence: pairs.iter().map(|&(p, _)| format!("p{p}")).collect(),
            human_packed: Vec::new(),
            missing: Vec::new(),
            start: world.inventories[0].products.clone(),
            first_sample: 0,
            samples: 0,
        }
    }

    fn moved(records: &[DemonstrationRecord]) -> (BTreeSet<String>, BTreeSet<String>) {
        let mut products = BTreeSet::new();
        let mut slots = BTreeSet::new();
        for r in records {
            for a in &r.assignment {
                products.insert(a.product.clone());
                slots.insert(a.slot.clone());
            }
        }
        (products, slots)
    }

    /// One demonstration of two of six products into two of eight slots:
    /// the rehearsals move the other four products and six slots, each
    /// order with distinct products and slots, two per order, every
    /// product at its inventory position, in listed order.
    #[test]
    fn what_no_demonstration_moved_is_rehearsed() {
        let w = world(6, 8);
        let d = demo(&w, &[(4, 2), (0, 5)]);
        let r = rehearsals(&w, std::slice::from_ref(&d));
        let (products, slots) = moved(&r);
        for p in ["p1", "p2", "p3", "p5"] {
            assert!(products.contains(p), "{p} rehearsed");
        }
        for s in ["s0", "s1", "s3", "s4", "s6", "s7"] {
            assert!(slots.contains(s), "{s} rehearsed");
        }
        assert_eq!(r.len(), 3, "six pairs, two per order");
        for order in &r {
            assert_eq!(order.block, REHEARSAL);
            assert_eq!(order.assignment.len(), 2);
            assert_ne!(order.assignment[0].product, order.assignment[1].product);
            assert_ne!(order.assignment[0].slot, order.assignment[1].slot);
            assert_eq!(order.start, w.inventories[0].products);
            let mut listed = order.sequence.clone();
            listed.sort();
            assert_eq!(order.sequence, listed, "listed order");
        }
        assert_eq!(rehearsals(&w, std::slice::from_ref(&d)), r, "deterministic");
    }

    /// An inventory of the taught cell that no demonstration used is
    /// rehearsed too: its products each once, but one waiting where a
    /// demonstration moved it from not again (p0), nor the slots the
    /// first inventory's rehearsals moved.
    #[test]
    fn another_inventory_of_the_cell_is_rehearsed_too() {
        let mut w = world(4, 4);
        let mut other = w.inventories[0].clone();
        other.name = "other".into();
        for p in other.products.iter_mut().skip(1) {
            p.at[0] = 0.7;
        }
        w.inventories.push(other);
        let d = demo(&w, &[(0, 0), (1, 1)]);
        let r = rehearsals(&w, std::slice::from_ref(&d));
        let of = |inventory: &str| -> Vec<&DemonstrationRecord> {
            r.iter().filter(|o| o.inventory == inventory).collect()
        };
        let (products, slots) = moved(&of("inv").into_iter().cloned().collect::<Vec<_>>());
        assert_eq!(products, ["p2", "p3"].map(String::from).into());
        assert_eq!(slots, ["s2", "s3"].map(String::from).into());
        let (products, _) = moved(&of("other").into_iter().cloned().collect::<Vec<_>>());
        assert_eq!(products, ["p1", "p2", "p3"].map(String::from).into());
        assert_eq!(of("other").len(), 2, "three products, two per order");
        assert!(
            of("other")
                .iter()
                .all(|o| o.start == w.inventories[1].products)
        );
    }

    /// Demonstrations that moved every product and slot leave nothing to
    /// rehearse.
    #[test]
    fn a_cell_fully_demonstrated_is_not_rehearsed() {
        let w = world(3, 3);
        let d = [demo(&w, &[(0, 0), (1, 1)]), demo(&w, &[(2, 2), (0, 1)])];
        assert!(rehearsals(&w, &d).is_empty());
    }
}
