//! The bench cell shared by the runtime's tests and benches: a UR10 at the
//! origin, products waiting on its right, a tray with five slots on its
//! left (the canonical example's layout).

use packwright_interface::scene::{BoxSpec, CellScene, SlotSpec};

pub fn bench_cell() -> CellScene {
    let slot = |name: &str, x: f64, y: f64| SlotSpec {
        name: name.into(),
        position: [x, y],
        box_index: 0,
    };
    CellScene {
        name: "bench".into(),
        base: [0.0, 0.0, 0.0],
        suction: 0.1,
        lift: 0.15,
        speed: 1.0,
        grip_settle: 0.1,
        release_settle: 0.5,
        descent: 1.0,
        pending: ([0.45, -0.5], [0.85, -0.1]),
        boxes: vec![BoxSpec {
            name: "tray".into(),
            centre: [0.0, 0.65],
            size: [0.4, 0.3, 0.08],
        }],
        slots: vec![
            slot("g1", -0.12, 0.58),
            slot("g2", 0.0, 0.58),
            slot("g3", 0.12, 0.58),
            slot("g4", -0.06, 0.72),
            slot("g5", 0.06, 0.72),
        ],
    }
}

/// One product's motion on the bench cell, in tool positions (x, y, z):
/// from above the pending area, its seven sub-goals (hover, top face,
/// lift, approach, above the slot, release, back up), stopping only at
/// the contact and the release. The bench, the callgrind example and the
/// station's tests blend it.
#[allow(dead_code)] // not every file that includes this module blends it
pub mod product_motion {
    pub const START: [f64; 3] = [0.5, -0.2, 0.3];
    pub const SUBGOALS: [[f64; 3]; 7] = [
        [0.62, -0.2, 0.15],
        [0.62, -0.2, 0.05],
        [0.62, -0.2, 0.15],
        [0.35, 0.25, 0.25],
        [0.0, 0.6, 0.15],
        [0.0, 0.6, 0.08],
        [0.0, 0.6, 0.15],
    ];
    pub const STOPS: [bool; 7] = [false, true, false, false, false, true, false];
}
