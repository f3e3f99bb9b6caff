//! Geometric guards of the learned loop: bounded corrections tried only
//! after a learned motion failed (or, for the limits, would turn a joint
//! a whole turn), so that nothing that packs without them changes; but
//! for [`nearer_middle`], tried first where the base turns nearly half a
//! turn and either way round is about as short.
//!
//! - [`swing_via`]: a goal far round the base, through a via half way;
//! - [`descent_vias`]: down the vertical over a release or a top face,
//!   where the straight joint motion bows into a wall;
//! - [`level_vias`]: across at the higher end's height, where a swing
//!   out of or past a deep box comes down or rises over its rim;
//! - (the policy's steps or a descent's vias are routed by
//!   `Station::through`, as the expert's lift up the line is: the ones a
//!   straight joint motion skips left out, `fewer_vias`;)
//! - [`held_at_limits`] and [`with_room`]: the base and wrist 3 near their
//!   limits held there, or turned the other way round;
//! - [`nearer_middle`]: nearly half a turn round, the base the way that
//!   leaves it nearer the middle of its range (tried first, as the only
//!   guard that does not wait for a failure: at most 30 degrees more);
//! - [`Inside`]: a colliding release moved just inside the box's walls
//!   (the product's, the cup's and, deep in a box, the wrist's room);
//!   [`COLLIDING_RELEASE_RAISE`] bounds how far one is raised.
//!
//! Invariants: each guard is bounded (a 2 cm raise, a 6 mm move, a via
//! only for swings over 120 degrees, 10 mrad at a limit) and returns
//! points or joints for the loop to check: none of them sends anything
//! or skips a collision check.

use super::steps::{BACK_UP_REACHED, policy_steps};
use crate::execute::station::Route;
use crate::expert::Suction;
use nalgebra::{Isometry3, Point3, UnitQuaternion};
use packwright_interface::outcome::Shortfall;
use packwright_interface::record;
use packwright_interface::scene::CellScene;
use packwright_kinematics::body::{BOX_WALL, CUP_RADIUS, HELD_PADDING, PADDING};
use packwright_kinematics::{Arm, DOF, Joints, joint_distance};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_6, PI, TAU};

/// Segments of a learned descent down the vertical over its end, when the
/// straight joint motion would touch a wall ([`descent_vias`]).
const DESCENT_VIAS: usize = 5;

/// How far round the base (rad) a goal must be from the cup tip for the
/// policy's steps that fall short to be tried again through
/// [`swing_via`]: a third of a turn. Almost behind the arm, turning
/// either way is as short, the policy turns the base little and folds
/// the elbow instead (measured on a development cell: the elbow past its
/// limit, 0.9 m from the goal).
const WIDE_SWING: f64 = TAU / 3.0;

/// A via point half way round the base from cup tip `from` to `goal`
/// (world), at their mean distance from the base's axis and the higher
/// of their heights, turning the way that leaves base joint `q0` nearer
/// the middle of its range (0) at the end; `None` when `goal` is less
/// than [`WIDE_SWING`] round from `from`.
pub fn swing_via(
    base: &Isometry3<f64>,
    q0: f64,
    from: [f64; 3],
    goal: [f64; 3],
) -> Option<[f64; 3]> {
    let local = |p: [f64; 3]| base.inverse_transform_point(&Point3::from(p));
    let (a, b) = (local(from), local(goal));
    let turn = record::short_way(b.y.atan2(b.x) - a.y.atan2(a.x));
    if turn.abs() < WIDE_SWING {
        return None;
    }
    let other = turn - TAU.copysign(turn);
    let swing = if (q0 + turn).abs() <= (q0 + other).abs() {
        turn
    } else {
        other
    };
    let angle = a.y.atan2(a.x) + swing / 2.0;
    let radius = (a.x.hypot(a.y) + b.x.hypot(b.y)) / 2.0;
    let via = Point3::new(radius * angle.cos(), radius * angle.sin(), a.z.max(b.z));
    Some((base * via).coords.into())
}

/// Via points from `start` across to above `end`'s cup tip (at the
/// start's height; none when it is already within `tolerance`), then down
/// the vertical line to it, each reached by the policy's steps
/// ([`policy_steps`]) within `tolerance`, then `end`: at most
/// [`DESCENT_VIAS`] segments. A straight joint motion down into a slot
/// bows sideways (measured: 5-7 mm at the middle of a 14 cm descent),
/// and a learned "above the slot" is a few millimetres beside the learned
/// release, so that even the tip's straight line slants: either way a
/// held product enters a narrow box beside its slot and touches the
/// wall. Going down vertically over the learned release, it enters where
/// it is let go. `None` when the motion is not a descent (it goes
/// sideways at least half as far as it goes down), or the steps fall
/// short or leave the limits.
pub fn descent_vias(
    arm: &Arm,
    base: &Isometry3<f64>,
    suction: f64,
    start: Joints,
    end: Joints,
    tolerance: f64,
    action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
) -> Option<Vec<Joints>> {
    let tip = |q: &Joints| -> [f64; 3] { arm.tool_tip(base, q, suction).coords.into() };
    let (a, b) = (tip(&start), tip(&end));
    let drop = a[2] - b[2];
    if drop <= 0.0 || 2.0 * (b[0] - a[0]).hypot(b[1] - a[1]) >= drop {
        return None;
    }
    level_vias(arm, base, suction, start, end, tolerance, action)
}

/// A motion that goes across at the higher of its two ends' heights: one
/// that ends lower than it starts goes across to above the end, then
/// down, as [`descent_vias`]; one that ends higher goes up over its start
/// first (reached by the policy's steps within `tolerance`), then to
/// `end`. Swings past a deep box whose steps and straight joint motion
/// came down while still over it (a long cup out of a 300 mm box) or rose
/// only as they went over it (a product carried the long way round the
/// base, past the box's rim) cross at the height of the higher end
/// instead (both on wide development cells). `None` for a motion that
/// stays level (within `tolerance`), or steps that fall short or leave
/// the limits.
pub fn level_vias(
    arm: &Arm,
    base: &Isometry3<f64>,
    suction: f64,
    start: Joints,
    end: Joints,
    tolerance: f64,
    action: &mut dyn FnMut(&Joints, [f64; 3]) -> [f32; 3],
) -> Option<Vec<Joints>> {
    let tip = |q: &Joints| -> [f64; 3] { arm.tool_tip(base, q, suction).coords.into() };
    let (a, b) = (tip(&start), tip(&end));
    if (a[2] - b[2]).abs() <= tolerance {
        return None;
    }
    if a[2] < b[2] {
        let up = [a[0], a[1], b[2]];
        let steps = policy_steps(arm, base, suction, start, up, tolerance, action).ok()?;
        let near = steps.last().copied().unwrap_or(start);
        return arm.within_limits(&near).then(|| vec![near, end]);
    }
    let mut near = start;
    let mut vias = Vec::with_capacity(DESCENT_VIAS);
    for i in 1..DESCENT_VIAS {
        let f = (i - 1) as f64 / (DESCENT_VIAS - 1) as f64;
        let via = [b[0], b[1], a[2] + (b[2] - a[2]) * f];
        if i == 1 && (via[0] - a[0]).hypot(via[1] - a[1]) <= tolerance {
            continue;
        }
        let steps = policy_steps(arm, base, suction, near, via, tolerance, action).ok()?;
        near = steps.last().copied().unwrap_or(near);
        if !arm.within_limits(&near) {
            return None;
        }
        vias.push(near);
    }
    vias.push(end);
    Some(vias)
}

/// The joints that turn freely, the base and wrist 3: the policy's steps
/// turn them past their limits (`q` and `q` ± 2π are the same pose), and
/// the guards below bring a motion's end back.
const TURNING: [usize; 2] = [0, DOF - 1];

/// How far (rad) past its limit the base or wrist 3 may end a motion that
/// starts within it and be held at the limit instead: brought a whole turn
/// back, a release a few milliradians past would spin the arm a full turn
/// on its way down into the box (measured on a development cell: 6 mrad
/// past, the cup against the box's outside). Held, the cup tip ends at
/// most this angle times the reach from where the steps put it.
const LIMIT_SLACK: f64 = 0.01;

/// `q` with the base and wrist 3 held at their limits where they are at
/// most [`LIMIT_SLACK`] past them and `start` is within them.
pub(super) fn held_at_limits(arm: &Arm, start: &Joints, q: Joints) -> Joints {
    let mut held = q;
    for j in TURNING {
        let l = &arm.limits[j];
        let clamped = q[j].clamp(l.lower, l.upper);
        if l.contains(start[j]) && (q[j] - clamped).abs() <= LIMIT_SLACK {
            held[j] = clamped;
        }
    }
    held
}

/// Room (rad) a motion's end leaves to the limits of the base and wrist 3,
/// the joints that turn freely: the sub-goals after a swing move them a
/// few degrees further.
const TURN_ROOM: f64 = 0.1;

/// `end` with the base or wrist 3 a whole turn the other way where it ends
/// within [`TURN_ROOM`] of its limit, when the other turn has that room
/// and is at most a quarter turn farther from `start`: a swing of about
/// half a turn (either way round is as short) that ends at the base's
/// limit leaves the descent onto the product a few milliradians on only a
/// whole turn back, and that swing sweeps the arm through the cell
/// (probe cells 3063 and 3081: the cup into the box).
pub(super) fn with_room(arm: &Arm, start: &Joints, end: Joints) -> Joints {
    let mut out = end;
    for j in TURNING {
        let l = &arm.limits[j];
        let room = |v: f64| (v - l.lower).min(l.upper - v);
        if room(end[j]) >= TURN_ROOM {
            continue;
        }
        let other = if end[j] - l.lower < l.upper - end[j] {
            end[j] + TAU
        } else {
            end[j] - TAU
        };
        let farther = (other - start[j]).abs() - (end[j] - start[j]).abs();
        if room(other) >= TURN_ROOM && farther <= FRAC_PI_2 {
            out[j] = other;
        }
    }
    out
}

/// Where the policy's steps from `start` ended in another arm shape
/// (inverse-kinematics branch) than `start`'s: `end`'s pose in each other
/// shape that reaches it, with room to the base's and wrist 3's limits
/// ([`with_room`]), nearest `start` first; none where the steps kept the
/// shape, or on a non-UR arm. Steps towards a point behind the base can
/// swing the shoulder back over the top, the upper arm and forearm down
/// on the table (helper R's cell 6210 with a model trained with `--seed
/// 1`), where the expert's inverse kinematics takes the same cup pose
/// with the elbow and wrist the other way.
pub(super) fn other_shapes(
    arm: &Arm,
    base: &Isometry3<f64>,
    start: &Joints,
    end: &Joints,
) -> Vec<Joints> {
    let Some(own) = arm.ur_branch(base, end) else {
        return Vec::new();
    };
    if arm.ur_branch(base, start) == Some(own) {
        return Vec::new();
    }
    in_other_branches(arm, base, &arm.flange_pose(base, end), start, own, start)
}

/// Flange pose `pose`'s joints on every inverse-kinematics branch but
/// `except` (each joint at the whole turn nearest `near`), with room to
/// the base's and wrist 3's limits from `start` ([`with_room`]), nearest
/// `start` first.
pub(super) fn in_other_branches(
    arm: &Arm,
    base: &Isometry3<f64>,
    pose: &Isometry3<f64>,
    near: &Joints,
    except: usize,
    start: &Joints,
) -> Vec<Joints> {
    let mut others: Vec<Joints> = arm
        .ur_ik_branches(base, pose, near)
        .into_iter()
        .enumerate()
        .filter(|&(b, _)| b != except)
        .filter_map(|(_, q)| q)
        .map(|q| with_room(arm, start, q))
        .collect();
    others.sort_by(|a, b| joint_distance(a, start).total_cmp(&joint_distance(b, start)));
    others
}

/// The whole turn (±2π) that brings `to` nearer `from`, where `to` is
/// more than half a turn from it; `None` where it is not.
pub(super) fn shorter_turn(from: f64, to: f64) -> Option<f64> {
    ((to - from).abs() > PI).then(|| -TAU.copysign(to - from))
}

/// How much farther (rad) the base may turn the other way round to end
/// nearer the middle of its range ([`nearer_middle`]).
const OTHER_WAY: f64 = FRAC_PI_6;

/// `end` with the base a whole turn the other way, where the motion from
/// `start` turns the base nearly half a turn (the other way round is at
/// most [`OTHER_WAY`] longer) and the other way ends nearer the middle of
/// the base's range, with [`TURN_ROOM`] to its limit; `None` otherwise.
/// Near half a turn the policy's steps commit to either way round, and a
/// base turned ever further one way comes to its limit: a box behind the
/// base, whose products the policy reached turning clockwise, then carried
/// on clockwise, left the next release past the limit, reached only by
/// turning three quarters of the way back (a helper's probe cell: 1.2-1.7
/// s more for the product, in 5 of 45 scenarios).
pub(super) fn nearer_middle(arm: &Arm, start: &Joints, end: &Joints) -> Option<Joints> {
    let l = &arm.limits[0];
    let turn = (end[0] - start[0]).abs();
    let other = end[0] - TAU.copysign(end[0] - start[0]);
    let room = |v: f64| (v - l.lower).min(l.upper - v);
    let middle = (l.lower + l.upper) / 2.0;
    let nearer = (other - middle).abs() < (end[0] - middle).abs();
    (turn < PI
        && (other - start[0]).abs() - turn <= OTHER_WAY
        && nearer
        && room(other) >= TURN_ROOM)
        .then(|| {
            let mut q = *end;
            q[0] = other;
            q
        })
}

/// How far above the expert's release, or the learned release when that
/// is higher, (m) a learned release whose motion collides may be raised
/// (where the expert's own release from there is raised too, because the
/// arm cannot reach the floor of a deep box or the cup does not fit in a
/// narrow one: this far above where the expert lets go): a
/// learned release a little too low (the held product pressed into the
/// floor) is let go 1 or 2 cm up, as the expert lets go 5 mm up; one
/// beside a wall is not raised until it is clear of the wall (measured:
/// released 9 cm up, a product dropped 29 mm off its slot). A learned
/// release a little higher than the expert's may rise as many steps as
/// the expert's (a short cup in a deep box, where wrist 3 meets the rim
/// unless both are raised twice).
pub(super) const COLLIDING_RELEASE_RAISE: f64 = 0.02;

/// How far (m) above its box's rim a learned release may let the
/// product's bottom go (it falls the rest of the way): in a deep carton
/// the expert's own release rises to about the rim, where the arm cannot
/// go lower; a release reached only higher is the expert's instead
/// (helper R's cell 6210: the product let go 0.46 m over the rim fell
/// onto the arm).
pub(super) const MAX_ABOVE_RIM: f64 = 0.15;

/// How far (m) a colliding release may be moved to keep its product and
/// the cup inside the box's walls ([`Inside::keep`]; the policy then
/// reaches it within [`BACK_UP_REACHED`]): about twice the
/// sub-goal planner's error at a release on cells it was not taught, well
/// within [`SUCCESS_RADIUS`](crate::execute::station::SUCCESS_RADIUS).
pub(super) const KEEP_INSIDE: f64 = 0.006;

/// How far (m) a kept release ([`Inside`]) stays inside the padded
/// walls: it is reached within [`BACK_UP_REACHED`], and as far again is
/// left for rounding and the flange's small tilt.
const KEPT_MARGIN: f64 = 2.0 * BACK_UP_REACHED;
// A kept product stands as far inside the walls as the expert lets one go
// (`expert::release_at`): the two rooms are one.
const _: () = assert!(crate::expert::WALL_ROOM == HELD_PADDING + KEPT_MARGIN);
// A product lowered into a snug slot is padded as the room leaves less
// this (`Checker::lowering`): a release kept inside there fits.
const _: () = assert!(crate::collision::LOWER_ROOM == KEPT_MARGIN);

/// Whether `rolled` is a release (`switch`) whose motion would collide.
pub(super) fn release_collides(switch: Suction, rolled: &Result<Route, Shortfall>) -> bool {
    switch == Suction::Off && matches!(rolled, Err(Shortfall::Collides { .. }))
}

/// The cup-tip positions (x and y, m) from which a held product, let go,
/// stands clear of its box's inner walls by its padding and
/// [`KEPT_MARGIN`], with the cup clear of them too when the tip is
/// below the rim, and the wrist ([`Inside::with_wrist`]) when the tip is
/// so low that the wrist goes into the box: the box's inside shrunk by
/// the product's half-extents in the world (moved by where the product
/// hangs from the cup), by the cup's padded radius, by the wrist's. An
/// axis where they do not fit is left as it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Inside {
    /// For the product: lowest and highest x, then y.
    product: [(f64, f64); 2],
    /// For the cup.
    cup: [(f64, f64); 2],
    /// The box's rim height: the cup goes into the box below it.
    rim: f64,
    /// The box's inner walls: lowest and highest x, then y.
    walls: [(f64, f64); 2],
    /// For the wrist, where it goes into the box.
    wrist: Option<Wrist>,
}

/// The wrist's end round the tool axis as [`Inside`] keeps it from the
/// walls: a ball (the rounded end of a capsule round the axis, padded)
/// over the cup's tip.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Wrist {
    /// The padded ball's radius.
    radius: f64,
    /// Its centre's height over the cup's tip.
    above_tip: f64,
}

impl Wrist {
    /// How far from the walls the tool axis stays with the tip at height
    /// `tip` (the ball's width at the rim, all of it below): `None` when
    /// the ball is above the rim.
    fn clearance(&self, tip: f64, rim: f64) -> Option<f64> {
        let over = tip + self.above_tip - rim;
        (over < self.radius).then(|| {
            if over <= 0.0 {
                self.radius
            } else {
                (self.radius * self.radius - over * over).sqrt()
            }
        })
    }
}

impl Inside {
    /// For a product of `size` hanging `grip` (world x, y: its centre
    /// minus the cup tip) from a flange turned by `flange`, its sides
    /// padded by `side_pad` (no more than [`HELD_PADDING`]: the checker's
    /// padding going down into the slot, [`Checker::lowering`](crate::collision::Checker::lowering)), let go
    /// in `cell`'s box `b`.
    pub(super) fn new(
        cell: &CellScene,
        b: usize,
        size: [f64; 3],
        grip: [f64; 2],
        flange: &UnitQuaternion<f64>,
        side_pad: f64,
    ) -> Option<Inside> {
        let held = cell.boxes.get(b)?;
        let m = flange.to_rotation_matrix().into_inner();
        let half = [size[0] / 2.0, size[1] / 2.0, size[2] / 2.0];
        let extent = |row: usize| (0..3).map(|j| m[(row, j)].abs() * half[j]).sum::<f64>();
        // The inside's bounds on `axis` shrunk by `by`, for a tip `shift`
        // from the body kept inside.
        let bound = |axis: usize, by: f64, shift: f64| {
            let c = held.centre[axis];
            let w = held.size[axis] / 2.0 - BOX_WALL - by - KEPT_MARGIN;
            (c - w - shift, c + w - shift)
        };
        Some(Inside {
            product: [0, 1].map(|a| bound(a, extent(a) + side_pad.min(HELD_PADDING), grip[a])),
            cup: [0, 1].map(|a| bound(a, CUP_RADIUS + PADDING, 0.0)),
            rim: held.size[2],
            walls: [0, 1].map(|a| {
                let w = held.size[a] / 2.0 - BOX_WALL;
                (held.centre[a] - w, held.centre[a] + w)
            }),
            wrist: None,
        })
    }

    /// Keeping the wrist inside the walls too, where it goes into the box:
    /// a short cup in a deep box, where the expert's release stops just
    /// clear of a wall and a learned one a few millimetres off meets it
    /// (wrist 3 on the wall of a 270 mm box, 95 mm cup, on a wide
    /// development cell). `wrist` is the radius and reach past the flange of
    /// [`wrist_around_tool`](packwright_kinematics::body::wrist_around_tool);
    /// the cup is `suction` long, pointing down.
    pub(super) fn with_wrist(mut self, suction: f64, wrist: Option<(f64, f64)>) -> Inside {
        self.wrist = wrist.map(|(radius, past)| Wrist {
            radius: radius + PADDING,
            // The ball's centre is `radius` short of the lowest point.
            above_tip: suction - (past - radius),
        });
        self
    }

    /// `goal` moved into the inside on each axis where the product and the
    /// cup fit (the nearest such point; `goal` itself when it is inside
    /// already), and the wrist too on each axis where it fits as well,
    /// unless that moves the goal more than [`KEEP_INSIDE`] (where the
    /// wrist needs more, the expert's release is raised too: the
    /// product's walls are what a kept release at the learned height can
    /// still keep); `None` when nothing fits on either axis.
    pub(super) fn keep(&self, goal: [f64; 3]) -> Option<[f64; 3]> {
        let plain = self.kept(goal, false)?;
        let wrist = self
            .kept(goal, true)
            .filter(|k| (k[0] - goal[0]).hypot(k[1] - goal[1]) <= KEEP_INSIDE);
        Some(wrist.unwrap_or(plain))
    }

    /// For a release whose product drops (let go above the expert's): the
    /// product alone (not the cup or the wrist, which stay above it)
    /// moved inside the walls by its padding and [`KEPT_MARGIN`], on each
    /// axis where it fits, and how far (m) the product itself, unpadded,
    /// reaches over a wall from `goal` (0 where it does not): landing on
    /// the wall, it would tip off its slot.
    pub(super) fn keep_dropped(&self, goal: [f64; 3]) -> ([f64; 3], f64) {
        let mut kept = goal;
        let mut over: f64 = 0.0;
        for axis in 0..2 {
            let (lo, hi) = self.product[axis];
            if lo > hi {
                continue;
            }
            kept[axis] = goal[axis].clamp(lo, hi);
            let moved = (kept[axis] - goal[axis]).abs();
            over = over.max(moved - HELD_PADDING - KEPT_MARGIN);
        }
        (kept, over)
    }

    fn kept(&self, goal: [f64; 3], with_wrist: bool) -> Option<[f64; 3]> {
        let mut kept = goal;
        let mut fits = false;
        for axis in 0..2 {
            let (mut lo, mut hi) = self.product[axis];
            if goal[2] < self.rim {
                lo = lo.max(self.cup[axis].0);
                hi = hi.min(self.cup[axis].1);
            }
            // A product lowered into a snug slot is padded to fit it
            // exactly (`Checker::lowering`): bounds crossed by rounding
            // alone are its centre line.
            if lo > hi + 1e-9 {
                continue;
            }
            if lo > hi {
                (lo, hi) = ((lo + hi) / 2.0, (lo + hi) / 2.0);
            }
            if let Some(wrist) = self.wrist.filter(|_| with_wrist)
                && let Some(by) = wrist.clearance(goal[2], self.rim)
            {
                let (l, h) = (
                    lo.max(self.walls[axis].0 + by + KEPT_MARGIN),
                    hi.min(self.walls[axis].1 - by - KEPT_MARGIN),
                );
                if l <= h {
                    (lo, hi) = (l, h);
                }
            }
            kept[axis] = goal[axis].clamp(lo, hi);
            fits = true;
        }
        fits.then_some(kept)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::REACHED;
    use nalgebra::Point3;
    use nalgebra::Vector3;
    use packwright_interface::scene::BoxSpec;
    use packwright_kinematics::body::wrist_around_tool;
    /// A cell with one box, 350 mm wide and 80 mm deep, 80 mm high,
    /// centred at (-0.2, 0.65): 36 mm from its centre line to the inside
    /// of its long walls.
    fn narrow_box() -> CellScene {
        CellScene {
            name: "narrow".into(),
            base: [0.0, 0.0, 0.0],
            suction: 0.085,
            lift: 0.1,
            speed: 1.0,
            grip_settle: 0.1,
            release_settle: 0.5,
            descent: 1.0,
            pending: ([0.0, 0.0], [0.1, 0.1]),
            boxes: vec![BoxSpec {
                name: "carton".into(),
                centre: [-0.2, 0.65],
                size: [0.35, 0.08, 0.08],
            }],
            slots: Vec::new(),
        }
    }

    /// [`Inside`] for box `b` of `cell`, a product of `size` hanging `grip`
    /// off the cup turned by `yaw`, padded all round.
    fn padded(cell: &CellScene, b: usize, size: [f64; 3], grip: [f64; 2], yaw: f64) -> Inside {
        Inside::new(cell, b, size, grip, &down(yaw), HELD_PADDING).expect("the box exists")
    }

    /// The cup pointing down, turned by `yaw`.
    fn down(yaw: f64) -> UnitQuaternion<f64> {
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw)
            * UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0)
    }

    #[test]
    fn a_dropped_release_keeps_its_product_inside_and_says_how_far_it_was_over() {
        let cell = narrow_box();
        // A 60 mm deep product, 20 mm wide: its padded bounds leave 2 mm
        // either way of the centre line in y; the cup (20 mm, 10 mm
        // padding) would leave none, but a dropped product is kept alone.
        let inside = padded(&cell, 0, [0.02, 0.06, 0.05], [0.0, 0.0], 0.0);
        let at = |y: f64| [-0.2, 0.65 + y, 0.2];
        assert_eq!(inside.keep_dropped(at(0.001)), (at(0.001), 0.0), "inside");
        // 4 mm towards +y: moved back 2 mm, the product itself still 2 mm
        // inside the wall (36 - 30 - 4).
        let (kept, over) = inside.keep_dropped(at(0.004));
        assert!(
            (kept[1] - 0.652).abs() < 1e-9 && over == 0.0,
            "{kept:?} {over}"
        );
        // 9 mm: it would land 3 mm over the wall.
        let (kept, over) = inside.keep_dropped(at(-0.009));
        assert!((kept[1] - 0.648).abs() < 1e-9, "{kept:?}");
        assert!((over - 0.003).abs() < 1e-9, "{over}");
        assert_eq!((kept[0], kept[2]), (-0.2, 0.2), "x and z stay");
    }

    /// A product 68 mm deep in a box 72 mm deep inside, 2 mm either side:
    /// with the whole padding nothing fits across, and a release 1.5 mm
    /// off the centre line is left there (where it collides); padded as
    /// [`Checker::lowering`](crate::collision::Checker::lowering) pads it
    /// down into its slot (the room less `LOWER_ROOM`), it is moved onto
    /// the centre line.
    #[test]
    fn a_release_in_a_snug_slot_is_kept_on_its_centre_line() {
        let cell = narrow_box();
        let size = [0.04, 0.068, 0.05];
        let at = [-0.2, 0.65 + 0.0015, 0.06];
        let inside = |pad: f64| {
            Inside::new(&cell, 0, size, [0.0, 0.0], &down(0.0), pad).expect("the box exists")
        };
        let padded = inside(HELD_PADDING).keep(at).expect("x fits");
        assert_eq!(padded[1], at[1], "{padded:?}");
        let lowered = inside(0.002 - crate::collision::LOWER_ROOM)
            .keep(at)
            .expect("moved");
        assert!((lowered[1] - 0.65).abs() < 1e-9, "{lowered:?}");
        assert_eq!((lowered[0], lowered[2]), (at[0], at[2]), "x and z stay");
    }

    #[test]
    fn a_release_against_a_wall_is_kept_inside_the_box() {
        let cell = narrow_box();
        // A 60 mm deep product: 36 - 30 - 3 mm padding - 1 mm margin
        // leaves 2 mm either way of the centre line.
        let inside = padded(&cell, 0, [0.04, 0.06, 0.05], [0.0, 0.0], 0.0);
        let at = |y: f64| [-0.2, 0.65 + y, 0.06];
        assert_eq!(inside.keep(at(0.0015)), Some(at(0.0015)), "already inside");
        let kept = inside.keep(at(0.004)).expect("moved");
        assert!((kept[1] - 0.652).abs() < 1e-9, "{kept:?}");
        assert_eq!((kept[0], kept[2]), (-0.2, 0.06), "x and z stay");
        let kept = inside.keep(at(-0.004)).expect("moved");
        assert!((kept[1] - 0.648).abs() < 1e-9, "{kept:?}");
        // Hanging 2 mm off the cup towards +y, the cup lets go 2 mm further
        // towards -y.
        let off = padded(&cell, 0, [0.04, 0.06, 0.05], [0.0, 0.002], 0.0);
        let kept = off.keep(at(0.001)).expect("moved");
        assert!((kept[1] - 0.65).abs() < 1e-9, "{kept:?}");
        // Turned a quarter, the product's 60 mm lie along x: in y it is
        // 40 mm, and the cup (20 mm and 10 mm padding) is the bound.
        let turned = padded(&cell, 0, [0.04, 0.06, 0.05], [0.0, 0.0], FRAC_PI_2);
        let kept = turned.keep(at(0.007)).expect("moved");
        assert!((kept[1] - 0.655).abs() < 1e-9, "{kept:?}");
        // Above the rim, the cup is not in the box: the product's bound.
        let high = [-0.2, 0.665, 0.09];
        assert!((turned.keep(high).expect("moved")[1] - 0.662).abs() < 1e-9);
    }

    /// The narrow box's short walls are 171 mm from its centre inside;
    /// the UR10's wrist 3 ends in a ball of radius 45 mm (55 padded) 10
    /// mm above the flange, 95 mm above the tip of the 85 mm cup: it
    /// meets the 80 mm rim when the tip is below 80 - 95 + 55 = 40 mm,
    /// and all of it is in the box below -15 mm. The tool axis is kept
    /// 171 - 55 - 1 = 115 mm from the centre then, 171 - 44 - 1 = 126 mm
    /// with the tip at 18 mm (the ball 33 mm below the rim at its centre,
    /// 44 mm wide there); the cup (30 mm, 140) and the 40 mm wide product
    /// (147) have room to 130 mm. Across the box (y) the wrist does not
    /// fit, and the product is kept inside alone; a wrist that needs more
    /// than a 6 mm move is left out too.
    #[test]
    fn a_release_deep_in_a_box_keeps_the_wrist_inside_the_walls_too() {
        let cell = narrow_box();
        let inside = padded(&cell, 0, [0.04, 0.06, 0.05], [0.0, 0.0], 0.0);
        let wrist = wrist_around_tool(&Arm::ur10());
        let deep = inside.with_wrist(cell.suction, wrist);
        let at = |x: f64, y: f64, z: f64| [-0.2 + x, 0.65 + y, z];
        assert_eq!(
            inside.keep(at(0.13, 0.0, 0.018)),
            Some(at(0.13, 0.0, 0.018)),
            "no wrist: inside"
        );
        let kept = deep.keep(at(0.119, 0.004, -0.02)).expect("moved");
        assert!((kept[0] - (-0.2 + 0.115)).abs() < 1e-9, "{kept:?}");
        assert!(
            (kept[1] - 0.652).abs() < 1e-9,
            "the product alone: {kept:?}"
        );
        assert_eq!(kept[2], -0.02, "z stays");
        let kept = deep.keep(at(0.13, 0.0, 0.018)).expect("moved");
        assert!((kept[0] - (-0.2 + 0.126)).abs() < 1e-9, "{kept:?}");
        let far = at(0.13, 0.004, -0.02);
        assert_eq!(deep.keep(far), inside.keep(far), "15 mm for the wrist");
        let above = at(0.13, 0.0, 0.041);
        assert_eq!(deep.keep(above), Some(above), "the wrist above the rim");
        assert_eq!(
            inside.with_wrist(cell.suction, None),
            inside,
            "a last link without shapes"
        );
    }

    #[test]
    fn a_goal_behind_the_arm_is_reached_through_a_via_on_the_side_with_room() {
        // A base on a riser, turned a quarter: the tip along the base's
        // x is along the world's y.
        let base = Isometry3::new(Vector3::new(0.2, -0.3, 0.24), Vector3::z() * FRAC_PI_2);
        let world =
            |x: f64, y: f64, z: f64| -> [f64; 3] { (base * Point3::new(x, y, z)).coords.into() };
        let from = world(0.5, 0.0, 0.3);
        let behind = world(-0.6, 0.05, 0.1);
        let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|j| (a[j] - b[j]).abs() < 1e-9);
        // Behind and a little to the left: with the base turned right
        // (q0 < 0), the short way, to the left, ends nearer the middle of
        // the base's range; turned left, the other way round does.
        let left = swing_via(&base, -0.5, from, behind).expect("behind");
        let turn = record::short_way(0.05f64.atan2(-0.6));
        let r = (0.5 + 0.6f64.hypot(0.05)) / 2.0;
        assert!(
            near(
                left,
                world(r * (turn / 2.0).cos(), r * (turn / 2.0).sin(), 0.3)
            ),
            "{left:?}"
        );
        let right = swing_via(&base, 0.5, from, behind).expect("behind");
        let other = turn - TAU;
        assert!(
            near(
                right,
                world(r * (other / 2.0).cos(), r * (other / 2.0).sin(), 0.3)
            ),
            "{right:?}"
        );
        // A quarter turn round is not wide.
        assert_eq!(swing_via(&base, 0.0, from, world(0.0, 0.6, 0.1)), None);
    }

    #[test]
    fn a_base_a_little_past_its_limit_is_held_there_not_turned_back() {
        let arm = Arm::ur10();
        let upper = arm.limits[0].upper;
        let start = [upper - 0.003, -1.5, 2.0, -2.0, -1.571, 1.5];
        let mut past = start;
        past[0] = upper + 0.006;
        past[5] = arm.limits[5].lower - 0.004;
        let held = held_at_limits(&arm, &start, past);
        assert_eq!((held[0], held[5]), (upper, arm.limits[5].lower));
        assert_eq!(held[1..5], past[1..5], "the other joints stay");
        // Farther past: left to be brought a whole turn back.
        let mut far = start;
        far[0] = upper + 0.05;
        assert_eq!(held_at_limits(&arm, &start, far), far);
        // From outside the limits (a step's own turn past them): left.
        let outside = [upper + 0.002, -1.5, 2.0, -2.0, -1.571, 1.5];
        assert_eq!(held_at_limits(&arm, &outside, past)[0], past[0]);
    }

    #[test]
    fn a_product_wider_than_the_box_is_not_moved() {
        let cell = narrow_box();
        let inside = padded(&cell, 0, [0.04, 0.075, 0.05], [0.0, 0.0], 0.0);
        // Along the box's length it fits: only that axis is kept.
        assert_eq!(inside.keep([-0.2, 0.653, 0.06]), Some([-0.2, 0.653, 0.06]));
        assert_eq!(inside.keep([-0.4, 0.653, 0.06]).map(|k| k[1]), Some(0.653));
        assert_eq!(
            Inside::new(
                &cell,
                1,
                [0.04, 0.04, 0.05],
                [0.0, 0.0],
                &down(0.0),
                HELD_PADDING
            ),
            None
        );
    }

    /// Down into a slot, the straight joint motion's tip leaves the
    /// vertical line by millimetres; the descent's via points go across to
    /// it at the start's height (when the start is beside it) and keep to
    /// it on the way down, each within the tolerance, and end where the
    /// motion ends. A motion mostly sideways is no descent.
    #[test]
    fn a_descent_goes_down_the_vertical_over_the_release_where_the_joint_motion_bows() {
        let arm = Arm::ur10();
        let base = Isometry3::identity();
        let suction = 0.1;
        let (x, y, yaw) = (0.55, 0.25, 0.3);
        let tip = |q: &Joints| -> [f64; 3] { arm.tool_tip(&base, q, suction).coords.into() };
        let at = |p: [f64; 3], near: &Joints| {
            arm.tool_down_ik(&base, Point3::from(p), yaw, suction, near)
        };
        let home = [0.0, -1.5, 1.5, -1.6, -1.6, 0.0];
        let end = at([x, y, 0.11], &home).expect("reachable");
        // The expert's step towards the joints of the tip it is sent to.
        let mut act = |q: &Joints, delta: [f64; 3]| {
            let t = tip(q);
            let goal = at(std::array::from_fn(|j| t[j] + delta[j]), q).unwrap_or(*q);
            record::action(q, &goal).map(|v| v as f32)
        };
        let off_line = |q: &Joints| {
            let t = tip(q);
            (t[0] - x).hypot(t[1] - y)
        };
        let tolerance = REACHED;
        // Straight above the release, and 6 mm beside it (as a learned
        // "above the slot" may be): the vias go across first, then down.
        for (beside, across) in [(0.0, false), (0.006, true)] {
            let start = at([x + beside, y, 0.25], &end).expect("reachable");
            let middle: Joints = std::array::from_fn(|j| (start[j] + end[j]) / 2.0);
            assert!(off_line(&middle) > 0.003, "bows {} m", off_line(&middle));
            let vias = descent_vias(&arm, &base, suction, start, end, tolerance, &mut act)
                .expect("a descent");
            assert_eq!(vias.len(), DESCENT_VIAS - usize::from(!across));
            assert_eq!(vias.last(), Some(&end));
            let down = &vias[usize::from(across)..];
            if across {
                assert!(off_line(&vias[0]) <= tolerance, "{:?}", tip(&vias[0]));
                assert!((tip(&vias[0])[2] - 0.25).abs() <= tolerance);
            }
            for (i, q) in down.iter().enumerate() {
                let z = 0.25 - 0.14 * (i + 1) as f64 / (DESCENT_VIAS - 1) as f64;
                assert!(off_line(q) <= tolerance, "via {i} {} m off", off_line(q));
                assert!(
                    (tip(q)[2] - z).abs() <= tolerance,
                    "via {i} at {:?}",
                    tip(q)
                );
            }
        }
        let start = at([x, y, 0.25], &end).expect("reachable");
        let aside = at([x, y + 0.2, 0.11], &start).expect("reachable");
        assert_eq!(
            descent_vias(&arm, &base, suction, start, aside, tolerance, &mut act),
            None
        );
        // Mostly sideways, across at the higher end's height: down at the
        // end going one way, up at the start going back.
        let vias = level_vias(&arm, &base, suction, start, aside, tolerance, &mut act)
            .expect("lower at its end");
        assert_eq!(vias.last(), Some(&aside));
        let first = tip(&vias[0]);
        assert!(
            (first[0] - x).hypot(first[1] - (y + 0.2)) <= tolerance,
            "{first:?}"
        );
        assert!((first[2] - 0.25).abs() <= tolerance, "{first:?}");
        let back = level_vias(&arm, &base, suction, aside, start, tolerance, &mut act)
            .expect("higher at its end");
        assert_eq!(back.len(), 2);
        assert_eq!(back.last(), Some(&start));
        let up = tip(&back[0]);
        assert!((up[0] - x).hypot(up[1] - (y + 0.2)) <= tolerance, "{up:?}");
        assert!((up[2] - 0.25).abs() <= tolerance, "{up:?}");
        let level = at([x, y + 0.2, 0.25], &start).expect("reachable");
        assert_eq!(
            level_vias(&arm, &base, suction, start, level, tolerance, &mut act),
            None
        );
    }

    /// A half-turn swing that ends at the base's limit ends a whole turn
    /// the other way round instead; one ending at the limit a quarter turn
    /// on, or with room, or a short step past where the other turn is far,
    /// is left alone.
    #[test]
    fn a_swing_ending_at_the_base_limit_goes_the_other_way_round() {
        let arm = Arm::ur10();
        let q = |base: f64, wrist3: f64| [base, -1.2, 2.4, -2.8, -FRAC_PI_2, wrist3];
        let limit = arm.limits[0].lower;
        // About half a turn, to within 4 mrad of the limit (probe cell 3081).
        let start = q(-3.315, -1.744);
        let end = q(limit + 0.004, -4.708);
        let turned = with_room(&arm, &start, end);
        assert!((turned[0] - (limit + 0.004 + TAU)).abs() < 1e-12);
        assert_eq!(turned[1..], end[1..]);
        // A quarter turn to the limit: the other way is three quarters.
        let start = q(limit + FRAC_PI_2, 0.0);
        assert_eq!(with_room(&arm, &start, end), end);
        // With room: nothing to do.
        let roomy = q(limit + 0.2, 0.0);
        assert_eq!(with_room(&arm, &start, roomy), roomy);
        // A short step along the limit (a descent after such a swing):
        // the other turn is a whole turn farther.
        let start = q(limit + 0.004, 0.0);
        let step = q(limit + 0.002, 0.0);
        assert_eq!(with_room(&arm, &start, step), step);
        // Wrist 3 as well.
        let start = q(0.0, 3.2);
        let end = q(0.0, arm.limits[5].upper - 0.01);
        let turned = with_room(&arm, &start, end);
        assert!(turned[5] < 0.0, "{turned:?}");
    }

    /// Nearly half a turn round, the base goes the other way where that
    /// leaves it nearer the middle of its range and is at most 30 degrees
    /// longer (the helper's box behind the base: from -0.411 rad the
    /// steps turned clockwise to -3.363, 169 degrees; the other way ends
    /// at 2.920, 191 degrees); not where the other way is longer than
    /// that, nor where it ends farther from the middle.
    #[test]
    fn nearly_half_a_turn_goes_the_way_that_keeps_the_base_near_the_middle() {
        let arm = Arm::ur10();
        let q = |base: f64| [base, -1.2, 2.4, -2.8, -FRAC_PI_2, 0.3];
        let (start, end) = (q(-0.411), q(-3.363));
        let other = nearer_middle(&arm, &start, &end).map(|o| o[0]);
        assert!(
            other.is_some_and(|b| (b - (-3.363 + TAU)).abs() < 1e-12),
            "{other:?}"
        );
        assert_eq!(
            nearer_middle(&arm, &start, &end).map(|o| o[1..].to_vec()),
            Some(end[1..].to_vec())
        );
        // A third of a turn: the other way is two thirds.
        assert_eq!(nearer_middle(&arm, &q(0.0), &q(-2.0)), None);
        // Half a turn from near the middle towards it: the other way ends
        // farther out.
        assert_eq!(nearer_middle(&arm, &q(3.0), &q(-0.1)), None);
    }

    /// Another shape's base more than half a turn from where the arm
    /// stands is brought a whole turn nearer (probe cell 6003: from 2.283
    /// rad to another shape's -1.582, 221 degrees clockwise; +2π makes it
    /// 139 degrees the other way); within half a turn it is left alone.
    #[test]
    fn a_base_more_than_half_a_turn_away_is_brought_a_whole_turn_nearer() {
        assert_eq!(shorter_turn(2.283, -1.582), Some(TAU));
        assert_eq!(shorter_turn(-2.0, 2.0), Some(-TAU));
        assert_eq!(shorter_turn(0.0, 3.0), None);
        assert_eq!(shorter_turn(1.0, -2.0), None);
        for (from, to) in [(2.283, -1.582), (-2.0, 2.0), (0.3, -3.0), (-6.0, 0.5)] {
            let turn = shorter_turn(from, to).unwrap_or(0.0);
            assert!((to + turn - from).abs() <= PI, "{from} {to} {turn}");
        }
    }
    /// The other shapes of an end the policy's steps reached with the
    /// shoulder swung back over the top (R's cell 6210): each is the same
    /// flange pose on another branch, nearest the start first; the
    /// expert's elbow-and-wrist-flipped solution there is among them.
    #[test]
    fn other_shapes_reach_the_same_pose_in_another_shape_nearest_first() {
        let arm = Arm::ur10();
        let base = Isometry3::translation(-0.291, 0.103, 0.0);
        let start = [2.64, -2.05, 2.36, -1.88, -1.57, -2.07];
        let end = [1.76, -3.37, 1.76, 0.04, -1.57, -2.96];
        let own = arm.ur_branch(&base, &end).expect("a UR branch");
        let pose = arm.flange_pose(&base, &end);
        let others = other_shapes(&arm, &base, &start, &end);
        assert!(others.len() >= 3, "{others:?}");
        for q in &others {
            let p = arm.flange_pose(&base, q);
            assert!((p.translation.vector - pose.translation.vector).norm() < 1e-9);
            assert!(p.rotation.angle_to(&pose.rotation) < 1e-9);
            assert_ne!(arm.ur_branch(&base, q), Some(own), "{q:?}");
            assert!(arm.within_limits(q), "{q:?}");
        }
        let distances: Vec<f64> = others.iter().map(|q| joint_distance(q, &start)).collect();
        assert!(distances.is_sorted(), "{distances:?}");
        // The expert's shape there: the shoulder up, the elbow below.
        assert!(
            others.iter().any(|q| q[1] > -2.0 && q[2] < 0.0),
            "{others:?}"
        );
        // Steps that kept the start's shape, or joints on no branch (not
        // finite), have no other shape.
        assert!(other_shapes(&arm, &base, &start, &start).is_empty());
        assert!(other_shapes(&arm, &base, &start, &[f64::NAN; 6]).is_empty());
    }
}
