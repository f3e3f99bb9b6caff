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
