//! `orders.json` on its own, and the records every file shares: a cell,
//! an assignment, the products present at the start.

use super::check::Check;
use crate::artifacts::field::Field;
use crate::error::{ArtifactProblem as P, Result};
use packwright_compiler::artifact::*;
use packwright_compiler::model::{
    ACCELERATION_RANGE, DESCENT_RANGE, JERK_RANGE, LIFT_RANGE, SETTLE_RANGE, SPEED_RANGE,
    SUCTION_RANGE,
};
use std::collections::HashMap;

/// `orders.json`, checked, with its names' indices: what the other files
/// refer to.
pub(super) struct World<'w> {
    pub(super) file: &'w WorldFile,
    cells: HashMap<&'w str, usize>,
    inventories: HashMap<&'w str, usize>,
    orders: HashMap<&'w str, usize>,
}

impl<'w> World<'w> {
    pub(super) fn check(c: &Check, w: &'w WorldFile) -> Result<World<'w>> {
        let root = Field::ROOT;
        let list = root.key("cells");
        let cells = c.unique(
            &list,
            "name",
            "cell",
            w.cells.iter().map(|x| x.name.as_str()),
        )?;
        for (i, cell) in w.cells.iter().enumerate() {
            cell_record(c, &list.index(i), cell)?;
        }
        let list = root.key("products");
        let products = c.unique(
            &list,
            "name",
            "product",
            w.products.iter().map(|x| x.name.as_str()),
        )?;
        for (i, p) in w.products.iter().enumerate() {
            let at = list.index(i);
            c.size(&at.key("size"), &p.size)?;
            if let Some(mass) = p.mass {
                c.above(&at.key("mass"), mass, 0.0)?;
            }
        }
        let list = root.key("inventories");
        let inventories = c.unique(
            &list,
            "name",
            "inventory",
            w.inventories.iter().map(|x| x.name.as_str()),
        )?;
        for (i, inv) in w.inventories.iter().enumerate() {
            let at = list.index(i);
            if !cells.contains_key(inv.cell.as_str()) {
                return Err(c.unknown(&at.key("cell"), "cell", &inv.cell));
            }
            let entries = at.key("products");
            c.unique(
                &entries,
                "product",
                "product of the inventory",
                inv.products.iter().map(|x| x.product.as_str()),
            )?;
            for (j, entry) in inv.products.iter().enumerate() {
                let at = entries.index(j);
                if !products.contains_key(entry.product.as_str()) {
                    return Err(c.unknown(&at.key("product"), "product", &entry.product));
                }
                c.point(&at.key("at"), &entry.at)?;
            }
        }
        let list = root.key("orders");
        let orders = c.unique(
            &list,
            "name",
            "order",
            w.orders.iter().map(|x| x.name.as_str()),
        )?;
        let mut world = World {
            file: w,
            cells,
            inventories,
            orders: HashMap::new(),
        };
        for (i, order) in w.orders.iter().enumerate() {
            let at = list.index(i);
            let (cell, inv) = world.setting(c, &at, &order.cell, &order.inventory)?;
            assignment(c, &at.key("assignment"), &order.assignment, cell, inv)?;
        }
        world.orders = orders;
        Ok(world)
    }

    /// The cell and inventory a record at `at` names (`cell`, `inventory`),
    /// the inventory in that cell.
    pub(super) fn setting(
        &self,
        c: &Check,
        at: &Field,
        cell: &str,
        inventory: &str,
    ) -> Result<(&'w CellRecord, &'w InventoryRecord)> {
        let Some(&ci) = self.cells.get(cell) else {
            return Err(c.unknown(&at.key("cell"), "cell in orders.json", cell));
        };
        let Some(&ii) = self.inventories.get(inventory) else {
            return Err(c.unknown(&at.key("inventory"), "inventory in orders.json", inventory));
        };
        let (Some(cell_record), Some(inv)) =
            (self.file.cells.get(ci), self.file.inventories.get(ii))
        else {
            return Err(c.unknown(&at.key("cell"), "cell in orders.json", cell));
        };
        c.same_name(
            &at.key("cell"),
            cell,
            &inv.cell,
            "the cell of the inventory in orders.json",
        )?;
        Ok((cell_record, inv))
    }

    /// The order a record names at `at` (if any): one for `inventory`.
    pub(super) fn order(
        &self,
        c: &Check,
        at: &Field,
        order: Option<&str>,
        inventory: &str,
    ) -> Result<()> {
        let Some(name) = order else {
            return Ok(());
        };
        let found = self.orders.get(name).and_then(|&i| self.file.orders.get(i));
        let Some(o) = found else {
            return Err(c.unknown(at, "order in orders.json", name));
        };
        if o.inventory == inventory {
            Ok(())
        } else {
            Err(c.differs(
                at,
                format!("`{name}`, an order for `{}`", o.inventory),
                format!("an order for `{inventory}`"),
            ))
        }
    }
}

fn cell_record(c: &Check, at: &Field, cell: &CellRecord) -> Result<()> {
    c.point(&at.key("base"), &cell.base)?;
    c.length_in(&at.key("suction"), cell.suction, SUCTION_RANGE)?;
    c.length_in(&at.key("lift"), cell.lift, LIFT_RANGE)?;
    c.share_in(&at.key("speed"), cell.speed, SPEED_RANGE)?;
    c.time_in(&at.key("grip_settle"), cell.grip_settle, SETTLE_RANGE)?;
    c.time_in(&at.key("release_settle"), cell.release_settle, SETTLE_RANGE)?;
    c.share_in(&at.key("descent"), cell.descent, DESCENT_RANGE)?;
    for (key, values, range) in [
        ("acceleration", &cell.acceleration, ACCELERATION_RANGE),
        ("jerk", &cell.jerk, JERK_RANGE),
    ] {
        for (j, v) in values.iter().flatten().enumerate() {
            c.limit_in(&at.key(key).index(j), *v, range)?;
        }
    }
    let pending = at.key("pending");
    let (min, max) = (pending.key("min"), pending.key("max"));
    c.point(&min, &cell.pending.min)?;
    c.point(&max, &cell.pending.max)?;
    for k in 0..2 {
        c.above(&max.index(k), cell.pending.max[k], cell.pending.min[k])?;
    }
    let list = at.key("boxes");
    let boxes = c.unique(
        &list,
        "name",
        "box of the cell",
        cell.boxes.iter().map(|b| b.name.as_str()),
    )?;
    for (j, b) in cell.boxes.iter().enumerate() {
        let at = list.index(j);
        c.point(&at.key("centre"), &b.centre)?;
        c.size(&at.key("size"), &b.size)?;
    }
    let list = at.key("slots");
    c.unique(
        &list,
        "name",
        "slot of the cell",
        cell.slots.iter().map(|s| s.name.as_str()),
    )?;
    for (j, s) in cell.slots.iter().enumerate() {
        let at = list.index(j);
        let label = j as u64 + 1;
        if u64::from(s.label) != label {
            return Err(c.differs(
                &at.key("label"),
                s.label,
                format!("{label} (slot {j}'s label is its place + 1; 0 is `pick`)"),
            ));
        }
        if !boxes.contains_key(s.box_name.as_str()) {
            return Err(c.unknown(&at.key("box"), "box of the cell", &s.box_name));
        }
        c.point(&at.key("position"), &s.position)?;
    }
    Ok(())
}

/// An assignment (at `at`) of products of `inv` to slots of `cell`.
pub(super) fn assignment(
    c: &Check,
    at: &Field,
    list: &[Assignment],
    cell: &CellRecord,
    inv: &InventoryRecord,
) -> Result<()> {
    for (k, a) in list.iter().enumerate() {
        let at = at.index(k);
        let product = at.key("product");
        if !inv.products.iter().any(|p| p.product == a.product) {
            return Err(c.unknown(&product, "product of the inventory", &a.product));
        }
        if list[..k].iter().any(|b| b.product == a.product) {
            return Err(c.fail(
                &product,
                P::Duplicate {
                    what: "product of the assignment",
                    name: a.product.clone(),
                },
            ));
        }
        let slot = at.key("slot");
        let Some(s) = cell.slots.iter().position(|s| s.name == a.slot) else {
            return Err(c.unknown(&slot, "slot of the cell", &a.slot));
        };
        if list[..k].iter().any(|b| b.slot == a.slot) {
            return Err(c.fail(
                &slot,
                P::Duplicate {
                    what: "slot of the assignment",
                    name: a.slot.clone(),
                },
            ));
        }
        let label = s as u64 + 1;
        if u64::from(a.label) != label {
            return Err(c.differs(
                &at.key("label"),
                a.label,
                format!("{label} (the label of slot `{}`)", a.slot),
            ));
        }
        c.point(&at.key("goal"), &a.goal)?;
    }
    Ok(())
}

/// `start` (at `at`): the present products of `inv` (all but `missing`),
/// in listed order, where they stand.
pub(super) fn start(
    c: &Check,
    at: &Field,
    start: &[At],
    inv: &InventoryRecord,
    missing: &[String],
) -> Result<()> {
    let present: Vec<&str> = inv
        .products
        .iter()
        .map(|p| p.product.as_str())
        .filter(|p| !missing.iter().any(|m| m == p))
        .collect();
    for (j, s) in start.iter().enumerate() {
        let at = at.index(j);
        let product = at.key("product");
        if !inv.products.iter().any(|p| p.product == s.product) {
            return Err(c.unknown(&product, "product of the inventory", &s.product));
        }
        match present.get(j) {
            Some(&p) if p == s.product => {}
            Some(p) => {
                return Err(c.differs(
                    &product,
                    format!("`{}`", s.product),
                    format!("`{p}` (the present products in the inventory's order)"),
                ));
            }
            None => {
                return Err(c.differs(
                    &product,
                    format!("`{}`", s.product),
                    "no more products (the others are missing)",
                ));
            }
        }
        c.point(&at.key("at"), &s.at)?;
    }
    c.count(at, start.len(), present.len())
}
