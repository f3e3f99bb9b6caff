//! An order to pack, in the robot half's terms.

use crate::scene::{CellScene, ProductSpec};

/// The order to pack: the cell, the inventory's products and which slot
/// each selected product goes to.
#[derive(Debug, Clone, PartialEq)]
pub struct OrderTask {
    pub cell: CellScene,
    /// The inventory's products, in listed order.
    pub products: Vec<ProductSpec>,
    /// (index into `products`, index into `cell.slots`) per selected
    /// product, in inventory order.
    pub assignment: Vec<(usize, usize)>,
}

impl OrderTask {
    /// Where product `p` rests in slot `s`.
    pub fn goal(&self, p: usize, s: usize) -> [f64; 3] {
        let slot = &self.cell.slots[s];
        [
            slot.position[0],
            slot.position[1],
            self.products[p].size[2] / 2.0,
        ]
    }

    /// The slot the order gives product `p`, if it selects it.
    pub fn slot_of(&self, p: usize) -> Option<usize> {
        self.assignment
            .iter()
            .find(|&&(q, _)| q == p)
            .map(|&(_, s)| s)
    }

    /// Slot `s`'s centre at the height of its box's rim: the feature the
    /// placing stage's sub-goals are planned from.
    pub fn slot_rim(&self, s: usize) -> [f64; 3] {
        let cell = &self.cell;
        let slot = cell.slots[s].position;
        let rim = cell
            .boxes
            .get(cell.slots[s].box_index)
            .map_or(0.0, |b| b.size[2]);
        [slot[0], slot[1], rim]
    }
}
