//! The scripted expert's geometry: the three sub-goals of each stage
//! (README, "The robot world"), as tool-tip positions in the world
//! frame.
//!
//! Picking: above the product at hover height; on its top face (suction
//! on); lifted by the cell's lift height. Placing: an approach point at
//! carrying height between the lift point and the slot; above the slot,
//! clear of the box's rim; down into the slot, the product's bottom
//! [`RELEASE_GAP`] above the box floor (suction off).

use packwright_interface::outcome::Stage;
use packwright_interface::scene::{CellScene, SlotSpec};
use packwright_kinematics::body::{BOX_WALL, HELD_PADDING};

/// Height of the hover point above a product's top face.
pub const HOVER: f64 = 0.10;
/// The approach point is kept at least this far from the base axis.
pub const MIN_APPROACH_RADIUS: f64 = 0.35;
/// Clearance of a held product's bottom over the box rim, above the slot.
pub const RIM_CLEARANCE: f64 = 0.05;
/// Height of a held product's bottom over the box floor when released.
pub const RELEASE_GAP: f64 = 0.005;
/// How far (m) a released product is kept from its box's inner walls
/// where the box has room ([`release_at`]): the planner's padding round a
/// held product, and a millimetre for the grip's and the reach's error;
/// the learned planner keeps a moved release's product as far in (its
/// guards assert that the two agree).
pub const WALL_ROOM: f64 = HELD_PADDING + 0.001;

/// What the suction does when a sub-goal is reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Suction {
    Keep,
    On,
    Off,
}

/// The suction schedule of a stage: what happens at each of its three
/// sub-goals (picking: on at the top face; placing: off at the release).
/// The expert and the learned loop both follow it.
pub fn schedule(stage: Stage) -> [Suction; 3] {
    match stage {
        Stage::Picking => [Suction::Keep, Suction::On, Suction::Keep],
        Stage::Placing => [Suction::Keep, Suction::Keep, Suction::Off],
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubGoal {
    /// Tool-tip position.
    pub tip: [f64; 3],
    pub suction: Suction,
}

/// The picking sub-goals for a product whose centre is `centre` and height
/// `height`, carried `lift` above where it stood.
pub fn picking(centre: [f64; 3], height: f64, lift: f64) -> [SubGoal; 3] {
    let top = centre[2] + height / 2.0;
    let [s0, s1, s2] = schedule(Stage::Picking);
    [
        SubGoal {
            tip: [centre[0], centre[1], top + HOVER],
            suction: s0,
        },
        SubGoal {
            tip: [centre[0], centre[1], top],
            suction: s1,
        },
        SubGoal {
            tip: [centre[0], centre[1], top + lift],
            suction: s2,
        },
    ]
}

/// The placing sub-goals for a held product of `height` whose tip is at
/// `from` (the lift point), going to the slot at `slot` in a box
/// `box_height` tall, for a robot whose base axis stands at `base`.
pub fn placing(
    from: [f64; 3],
    slot: [f64; 2],
    height: f64,
    box_height: f64,
    base: [f64; 2],
) -> [SubGoal; 3] {
    let above = box_height + height + RIM_CLEARANCE;
    let carry = from[2].max(above);
    let polar = |p: [f64; 2]| {
        let (dx, dy) = (p[0] - base[0], p[1] - base[1]);
        (dy.atan2(dx), dx.hypot(dy))
    };
    let (a0, r0) = polar([from[0], from[1]]);
    let (a1, r1) = polar(slot);
    // The shorter way around.
    let mut turn = a1 - a0;
    while turn > std::f64::consts::PI {
        turn -= std::f64::consts::TAU;
    }
    while turn < -std::f64::consts::PI {
        turn += std::f64::consts::TAU;
    }
    let angle = a0 + turn / 2.0;
    let radius = ((r0 + r1) / 2.0).max(MIN_APPROACH_RADIUS);
    let [s0, s1, s2] = schedule(Stage::Placing);
    [
        SubGoal {
            tip: [
                base[0] + radius * angle.cos(),
                base[1] + radius * angle.sin(),
                carry,
            ],
            suction: s0,
        },
        SubGoal {
            tip: [slot[0], slot[1], above],
            suction: s1,
        },
        SubGoal {
            tip: [slot[0], slot[1], height + RELEASE_GAP],
            suction: s2,
        },
    ]
}

/// Where the centre of a product of `size` is let go in `slot` of
/// `cell`: the slot, moved on each axis just far enough that the product
/// keeps [`WALL_ROOM`] from its box's inner walls, where the box is wide
/// enough for that (else not moved on that axis). Lowered past a wall any
/// closer, the planner's padded product meets the wall at every height:
/// the release is raised until the product clears the rim, and dropped
/// from there it catches the wall and lands tilted (a 110 mm card 1 mm
/// from the wall of a 200 mm deep shipper landed 28 mm off its slot).
/// Moved at most [`WALL_ROOM`] for a product inside the walls, well
/// within the success radius.
pub fn release_at(cell: &CellScene, slot: &SlotSpec, size: [f64; 3]) -> [f64; 2] {
    let Some(b) = cell.boxes.get(slot.box_index) else {
        return slot.position;
    };
    std::array::from_fn(|axis| {
        let at = slot.position[axis];
        // How far the product's centre may go from the box's centre.
        let room = b.size[axis] / 2.0 - BOX_WALL - WALL_ROOM - size[axis] / 2.0;
        if room < 0.0 {
            return at;
        }
        at.clamp(b.centre[axis] - room, b.centre[axis] + room)
    })
}

/// Where a product `height` tall stands (its centre) as the expert lets it
/// go over `slot` ([`release_at`]): [`RELEASE_GAP`] over the floor.
pub fn released_centre(slot: [f64; 2], height: f64) -> [f64; 3] {
    [slot[0], slot[1], RELEASE_GAP + height / 2.0]
}

/// The box a slot belongs to, and its height.
pub fn box_height(cell: &CellScene, slot: usize) -> f64 {
    cell.slots
        .get(slot)
        .and_then(|s| cell.boxes.get(s.box_index))
        .map_or(0.0, |b| b.size[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sub_goals_follow_the_geometry() {
        let p = picking([0.6, -0.3, 0.025], 0.05, 0.15);
        assert_eq!(p[1].tip, [0.6, -0.3, 0.05]);
        assert_eq!(p[1].suction, Suction::On);
        assert!((p[0].tip[2] - 0.15).abs() < 1e-12);
        assert!((p[2].tip[2] - 0.20).abs() < 1e-12);
        let q = placing(p[2].tip, [0.0, 0.6], 0.05, 0.08, [0.0, 0.0]);
        assert!((q[1].tip[2] - 0.18).abs() < 1e-12);
        assert!((q[0].tip[2] - 0.20).abs() < 1e-12);
        assert!((q[2].tip[2] - 0.055).abs() < 1e-12);
        assert_eq!(q[2].suction, Suction::Off);
        // The approach point goes around the base, not over it.
        let behind = placing([0.55, -0.2, 0.2], [-0.55, 0.0], 0.05, 0.08, [0.1, 0.05]);
        let [x, y, _] = behind[0].tip;
        assert!((x - 0.1).hypot(y - 0.05) >= MIN_APPROACH_RADIUS - 1e-9);
    }

    /// A 100 mm box 200 mm wide at (0, 0.6): its inside runs 96 mm either
    /// way in x, 46 mm in y.
    fn boxed(slot: [f64; 2]) -> (CellScene, SlotSpec) {
        let slot = SlotSpec {
            name: "s".into(),
            position: slot,
            box_index: 0,
        };
        let cell = CellScene {
            boxes: vec![packwright_interface::scene::BoxSpec {
                name: "b".into(),
                centre: [0.0, 0.6],
                size: [0.2, 0.1, 0.1],
            }],
            slots: vec![slot.clone()],
            ..crate::collision::graze::cell()
        };
        (cell, slot)
    }

    #[test]
    fn a_release_keeps_its_product_off_the_walls_where_the_box_has_room() {
        let close =
            |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12;
        // Far from the walls: the slot itself.
        let (cell, slot) = boxed([0.02, 0.61]);
        assert!(close(release_at(&cell, &slot, [0.05; 3]), [0.02, 0.61]));
        // 1 mm from the inside of the +x wall (96 - 25 - 70 mm): moved in
        // to WALL_ROOM (4 mm), y unchanged.
        let (cell, slot) = boxed([0.07, 0.61]);
        let at = release_at(&cell, &slot, [0.05; 3]);
        assert!(close(at, [0.096 - WALL_ROOM - 0.025, 0.61]), "{at:?}");
        // Against the -y wall too, and a product sticking into the wall.
        let (cell, slot) = boxed([-0.07, 0.58]);
        let at = release_at(&cell, &slot, [0.05, 0.06, 0.05]);
        assert!(close(at, [-0.067, 0.554 + WALL_ROOM + 0.03]), "{at:?}");
        // 90 mm deep in a 92 mm inside: no room for 4 mm either side, y
        // stays where the slot is; x still moves.
        let (cell, slot) = boxed([0.07, 0.601]);
        let at = release_at(&cell, &slot, [0.05, 0.09, 0.05]);
        assert!(close(at, [0.067, 0.601]), "{at:?}");
    }
}
