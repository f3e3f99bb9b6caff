//! What the networks read: the training examples, and the input encodings
//! that training and run time share.
//!
//! Every encoding is in terms that mean the same in any cell, so that one
//! set of weights serves cells it was not taught (README, "Learning"):
//!
//! - a **node** (a product) is (selected, place along the taught chain,
//!   in its slot or not, raised over the table or not), never its
//!   position;
//! - a **slot** is where it lies relative to the held product's goal, so
//!   the placing decision points at a slot by its geometry: any slot of any
//!   cell, demonstrated or not;
//! - a **sub-goal** is in cylindrical coordinates about the robot base's
//!   vertical axis, relative to the feature (the product, or the slot at
//!   its box's rim), its height over a surface (the product's top face,
//!   the rim, the box's floor), with the turn from the cup tip to the
//!   feature as an input and no height by itself: the expert's
//!   approach point, half-way round between the pick and place azimuths,
//!   is then one smooth function of the inputs whichever side the box is
//!   on (in Cartesian coordinates the two ways round a box behind the
//!   robot average to a point inside the base);
//! - an **action** sees the sub-goal's direction in the frame that turns
//!   with the base joint, and the shoulder and elbow, not the base angle:
//!   the arm's motion is the same wherever it points.

use packwright_interface::outcome::SUCCESS_RADIUS;
use packwright_interface::{Graph, Stage, SubGoalQuery};

/// Scale of the dynamics policy's outputs: actions are learnt as fractions
/// of the largest joint step (15 degrees).
pub const ACTION_SCALE: f32 = packwright_interface::record::MAX_ACTION as f32;

/// Inputs per node: selected (0/1), place along the chain (0 for the first
/// product seen to 1 for the last), whether it is out of its slot ([`out_of_slot`]:
/// 0 within [`SUCCESS_RADIUS`] of its goal, as the rule judges a packed
/// product, 1 from [`PACKED_RAMP`] beyond), and whether it is held:
/// raised, the height of its bottom over the table in units of
/// [`RAISED`], at most 1, times its "out of its slot" (a product let go
/// tilted, resting on its slot's edge 16 mm up and packed by the rule,
/// read as held, and the reasoner chose the box with nothing in the cup).
pub const NODE_FEATURES: usize = 4;
/// How far beyond [`SUCCESS_RADIUS`] (m) a product's "out of its slot"
/// input rises from 0 to 1. In decimetres up to 3, as it was, the
/// reasoner learned "packed" from the distances of the cells it was
/// taught (products waiting 0.3 m or more from their slots) and, in a
/// compact cell with products waiting 12 cm from their slots, read them
/// as packed and chose the box with nothing in the cup; in units of 5 cm
/// (tried next) it learned "packed" from the expert's releases, a few
/// millimetres off, and took products the learned planner had let go 1
/// cm off, packed by the rule, as still to pick.
pub const PACKED_RAMP: f32 = 0.005;

/// A selected product's "out of its slot" input from its distance (m)
/// from its goal: 0 up to [`SUCCESS_RADIUS`], 1 from [`PACKED_RAMP`]
/// beyond, linear between.
pub fn out_of_slot(away: f32) -> f32 {
    ((away - SUCCESS_RADIUS as f32) / PACKED_RAMP).clamp(0.0, 1.0)
}
/// A product whose bottom is this high (m) over the table reads as raised
/// (held): products stand on the table or on a box's floor, which is at
/// table height, and a held one is carried the cell's `lift` up, at
/// least 20 mm (the language's shortest lift). In decimetres, as it was,
/// the reasoner learned where "held" begins from the lifts it was taught
/// (100-200 mm) and, with `lift 60 mm`, chose the held product again
/// instead of the box.
pub const RAISED: f32 = 0.02;
/// The column of a node row holding its place along the chain.
pub const PLACE: usize = 1;
/// The node row without its place ([`own_row`]): what a node's score
/// network reads. The place enters the score only through one learned
/// non-negative slope (later along the chain, lower), so among products
/// that are otherwise alike the earlier one always scores higher, for
/// any pair of places, taught together or not.
pub const OWN_FEATURES: usize = NODE_FEATURES - 1;

/// A node row without its place column.
pub fn own_row(row: &[f32; NODE_FEATURES]) -> [f32; OWN_FEATURES] {
    std::array::from_fn(|i| if i < PLACE { row[i] } else { row[i + 1] })
}

/// How much the chain slope moves per unit of its parameter: one scalar
/// learnt at the networks' learning rate would take tens of thousands of
/// steps to separate places a quarter apart by a confident margin.
pub const CHAIN_SCALE: f32 = 30.0;

/// The chain slope from its stored parameter: `CHAIN_SCALE *
/// softplus(raw)`, so that it is never negative.
pub fn chain_slope(raw: f32) -> f32 {
    let softplus = if raw > 20.0 { raw } else { raw.exp().ln_1p() };
    CHAIN_SCALE * softplus
}

/// Inputs per slot: (dx, dy) from the held product's goal to the slot, and
/// their length (decimetres).
pub const SLOT_FEATURES: usize = 3;
/// The sub-goal planner's inputs ([`subgoal_input`]).
pub const SUBGOAL_INPUTS: usize = 8;
/// The dynamics policy's inputs ([`action_input`]).
pub const ACTION_INPUTS: usize = 5;
/// Metres per radian of sub-goal azimuth in the planner's outputs: a
/// typical reach, so that an azimuth error weighs like the distance it
/// moves the cup.
pub const ARC_SCALE: f32 = 0.7;
/// Scale of the release's height in the planner's outputs: the held
/// product is let go 5 mm over the floor with 3 mm of padding, so a
/// release 2 mm low touches it (and is raised and planned again), and
/// the release's height must be fitted to the millimetre. At the scale
/// of the other outputs the planner left it 1.4 mm low.
pub const RELEASE_HEIGHT_SCALE: f32 = 10.0;

/// One reasoner decision: the graph at the start of a stage and what the
/// demonstrator did.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphExample {
    pub graph: Graph,
    /// The chosen node, or `graph.nodes.len()` for the box.
    pub target: usize,
    /// Placing: the chosen slot (index into `graph.slots`).
    pub slot: Option<usize>,
}

/// One sub-goal issued by the demonstrator.
#[derive(Debug, Clone, PartialEq)]
pub struct SubGoalExample {
    pub query: SubGoalQuery,
    /// The cup tip reached.
    pub target: [f32; 3],
}

impl SubGoalExample {
    /// The example reflected in the vertical plane through the robot's
    /// base and the feature: the cup tip and the sub-goal on the other
    /// side, at the same radius and height, so the turn to the feature
    /// and the sub-goal's azimuth from it go the other way round
    /// ([`subgoal_input`], [`subgoal_output`]). The expert's sub-goals are
    /// symmetric so (over a product or a slot, or half way round on the
    /// way there), and a model taught turning one way only (a cell's box
    /// on one side of its products) put the approach on the far side
    /// where the short way round turned the other: the arm swung 241
    /// degrees instead of 119. Unchanged where the feature stands over
    /// the base.
    pub fn mirrored(&self) -> SubGoalExample {
        let q = &self.query;
        let (ux, uy) = (q.feature[0] - q.base[0], q.feature[1] - q.base[1]);
        let length = ux.hypot(uy);
        if length < 1e-6 {
            return self.clone();
        }
        let (ux, uy) = (ux / length, uy / length);
        let reflect = |p: [f32; 3]| {
            let (dx, dy) = (p[0] - q.base[0], p[1] - q.base[1]);
            let along = dx * ux + dy * uy;
            [
                q.base[0] + 2.0 * along * ux - dx,
                q.base[1] + 2.0 * along * uy - dy,
                p[2],
            ]
        };
        SubGoalExample {
            query: SubGoalQuery {
                tool: reflect(q.tool),
                ..*q
            },
            target: reflect(self.target),
        }
    }
}

/// One joint action of the demonstrator.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionExample {
    /// Sub-goal minus tool tip.
    pub delta: [f32; 3],
    /// Base, shoulder and elbow positions when the action was taken.
    pub joints: [f32; 3],
    /// Base, shoulder and elbow steps (radians, at most 15 degrees each).
    pub action: [f32; 3],
}

/// Everything the three networks learn from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrainingSet {
    pub graphs: Vec<GraphExample>,
    pub subgoals: Vec<SubGoalExample>,
    pub actions: Vec<ActionExample>,
}

fn norm2(v: [f32; 2]) -> f32 {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

fn distance(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The nodes' input rows, in chain order.
pub fn node_rows(graph: &Graph) -> Vec<[f32; NODE_FEATURES]> {
    let last = graph.nodes.len().saturating_sub(1).max(1) as f32;
    graph
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let away = if n.selected {
                distance(n.centre, n.goal)
            } else {
                0.0
            };
            let bottom = n.centre[2] - n.height / 2.0;
            let out = out_of_slot(away);
            [
                if n.selected { 1.0 } else { 0.0 },
                i as f32 / last,
                out,
                // Held: raised, and not in its slot (a product let go
                // tilted on its slot's edge is raised too, and packed).
                out * (bottom / RAISED).clamp(0.0, 1.0),
            ]
        })
        .collect()
}

/// The slots' input rows, in the cell's slot order.
pub fn slot_rows(graph: &Graph) -> Vec<[f32; SLOT_FEATURES]> {
    let g = graph.held_goal;
    graph
        .slots
        .iter()
        .map(|s| {
            let d = [10.0 * (s[0] - g[0]), 10.0 * (s[1] - g[1])];
            [d[0], d[1], norm2(d)]
        })
        .collect()
}

/// `a` in (-pi, pi].
fn wrap(mut a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    while a > PI {
        a -= TAU;
    }
    while a <= -PI {
        a += TAU;
    }
    a
}

/// (radius, azimuth) of `p` about the vertical axis through `base`.
fn polar(p: [f32; 3], base: [f32; 3]) -> (f32, f32) {
    let (dx, dy) = (p[0] - base[0], p[1] - base[1]);
    (dx.hypot(dy), dy.atan2(dx))
}

/// How far the cup tip is above what the sub-goal's heights measure: the
/// held product's bottom when placing (the product's height), the tip
/// itself when picking.
fn carried(q: &SubGoalQuery) -> f32 {
    match q.stage {
        Stage::Picking => 0.0,
        Stage::Placing => q.height,
    }
}

/// The height of the surface a stage's heights are measured from: the
/// handled product's top face (picking; the feature is its centre), the
/// box's rim (placing).
fn stage_surface(q: &SubGoalQuery) -> f32 {
    match q.stage {
        Stage::Picking => q.feature[2] + q.height / 2.0,
        Stage::Placing => q.feature[2],
    }
}

/// Whether `q` asks for the release: the placing stage's last sub-goal,
/// where the suction lets go.
fn release(q: &SubGoalQuery) -> bool {
    q.stage == Stage::Placing && q.index >= 2
}

/// The height of the surface sub-goal `q.index` is measured from: the
/// stage's ([`stage_surface`]), except for the release, which is measured
/// from the box's floor: the table, z = 0, which every box stands on.
fn target_surface(q: &SubGoalQuery) -> f32 {
    if release(q) { 0.0 } else { stage_surface(q) }
}

/// The scale of sub-goal `q.index`'s height in the planner's outputs
/// ([`RELEASE_HEIGHT_SCALE`] at the release, else 1).
fn height_scale(q: &SubGoalQuery) -> f32 {
    if release(q) {
        RELEASE_HEIGHT_SCALE
    } else {
        1.0
    }
}

/// The sub-goal planner's input row: the cup tip's radius relative to the
/// feature's, the tip's height over the stage's surface (the product's
/// top face when picking; when placing, the held product's bottom over
/// the box's rim), the turn from the tip's azimuth to the feature's (the
/// shorter way), the stage and the sub-goal index one-hot.
///
/// No height is an input by itself. The expert's hover, pick, "above the
/// slot" and release are each a fixed distance over a surface
/// ([`subgoal_output`]), its approach the higher of the tip and a fixed
/// distance over the rim, so a box deeper or a product taller than any
/// taught is planned for like the others: with the box's rim and the
/// product's height as inputs, the planner had to extrapolate to heights
/// no cell taught, and beyond them it missed sideways as well (a box
/// 160 mm deep, taught 60 to 100 mm: releases 3 cm off the slot).
///
/// Nothing says where the feature is around or away from the base: the
/// expert's sub-goals do not depend on it, and a model that could not see
/// it cannot learn to depend on it (a slot at a radius no demonstration
/// used is planned for like the others).
pub fn subgoal_input(q: &SubGoalQuery) -> [f32; SUBGOAL_INPUTS] {
    let (rf, af) = polar(q.feature, q.base);
    let (rt, at) = polar(q.tool, q.base);
    let stage = match q.stage {
        Stage::Picking => 0,
        Stage::Placing => 1,
    };
    let mut x = [0.0; SUBGOAL_INPUTS];
    x[..3].copy_from_slice(&[
        rt - rf,
        q.tool[2] - carried(q) - stage_surface(q),
        wrap(af - at),
    ]);
    x[3 + stage] = 1.0;
    x[5 + q.index.min(2)] = 1.0;
    x
}

/// The planner's target for `target`, relative to the feature: its
/// radius minus the feature's; its height over the sub-goal's surface
/// ([`target_surface`]: the product's top face when picking; when
/// placing, the held product's bottom over the rim, or over the floor at
/// the release, times [`RELEASE_HEIGHT_SCALE`]); and its azimuth from
/// the feature's (times [`ARC_SCALE`]). Above a product or a slot, and
/// at the release, these are constants; the approach point's are half
/// the cup tip's offsets.
pub fn subgoal_output(q: &SubGoalQuery, target: [f32; 3]) -> [f32; 3] {
    let (r, a) = polar(target, q.base);
    let (rf, af) = polar(q.feature, q.base);
    [
        r - rf,
        height_scale(q) * (target[2] - carried(q) - target_surface(q)),
        ARC_SCALE * wrap(a - af),
    ]
}

/// The cup-tip position an output of the planner stands for.
pub fn subgoal_position(q: &SubGoalQuery, out: [f32; 3]) -> [f32; 3] {
    let (rf, af) = polar(q.feature, q.base);
    let (r, a) = (rf + out[0], af + out[2] / ARC_SCALE);
    [
        q.base[0] + r * a.cos(),
        q.base[1] + r * a.sin(),
        target_surface(q) + carried(q) + out[1] / height_scale(q),
    ]
}

/// The dynamics policy's input row: delta turned into the frame of the
/// base joint (so the base angle itself is not an input), then the
/// shoulder and elbow.
pub fn action_input(delta: [f32; 3], joints: [f32; 3]) -> [f32; ACTION_INPUTS] {
    let (s, c) = joints[0].sin_cos();
    [
        c * delta[0] + s * delta[1],
        -s * delta[0] + c * delta[1],
        delta[2],
        joints[1],
        joints[2],
    ]
}

/// Appends a one-hot row of `n` with a 1 at `k` (none when `k >= n`).
pub fn one_hot(out: &mut Vec<f32>, k: usize, n: usize) {
    out.extend((0..n).map(|i| if i == k { 1.0 } else { 0.0 }));
}

#[cfg(test)]
mod tests {
    use super::*;
    use packwright_interface::Node;

    /// A mirrored example turns the other way round to its feature, and
    /// its sub-goal lies as far round the other way: the same radii and
    /// heights, the turn and the arc negated.
    #[test]
    fn a_mirrored_sub_goal_turns_the_other_way_round() {
        let e = SubGoalExample {
            query: SubGoalQuery {
                stage: Stage::Placing,
                index: 0,
                feature: [0.7, 0.3, 0.08],
                tool: [-0.2, 0.6, 0.25],
                height: 0.05,
                base: [0.1, -0.1, 0.0],
            },
            target: [0.5, 0.6, 0.3],
        };
        let m = e.mirrored();
        let (x, mx) = (subgoal_input(&e.query), subgoal_input(&m.query));
        let (y, my) = (
            subgoal_output(&e.query, e.target),
            subgoal_output(&m.query, m.target),
        );
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        assert!(x[2].abs() > 0.5 && close(mx[2], -x[2]), "{x:?} {mx:?}");
        assert!(y[2].abs() > 0.1 && close(my[2], -y[2]), "{y:?} {my:?}");
        for i in [0, 1] {
            assert!(
                close(mx[i], x[i]) && close(my[i], y[i]),
                "{x:?} {mx:?} {y:?} {my:?}"
            );
        }
        assert_eq!(mx[3..], x[3..]);
        // Mirrored twice: the example itself.
        let back = m.mirrored();
        for (a, b) in back
            .query
            .tool
            .iter()
            .chain(&back.target)
            .zip(e.query.tool.iter().chain(&e.target))
        {
            assert!(close(*a, *b));
        }
    }

    /// Whether a product is packed reads the same in any cell, as the
    /// rule judges it: one waiting 12 cm from its slot (a compact cell,
    /// the products beside the box) reads exactly as one waiting a metre
    /// away, and one let go 1 cm or 2 cm off its goal (packed) exactly as
    /// one on it.
    #[test]
    fn a_node_reads_packed_or_not_whatever_the_cells_distances() {
        let node = |x: f32| Node {
            centre: [x, 0.0, 0.03],
            height: 0.06,
            selected: true,
            goal: [0.0, 0.0, 0.03],
        };
        let rows = node_rows(&Graph {
            nodes: vec![node(1.0), node(0.12), node(0.0199), node(0.01), node(0.0)],
            slots: Vec::new(),
            held_goal: [0.0; 3],
        });
        let packed: Vec<f32> = rows.iter().map(|r| r[2]).collect();
        assert_eq!(packed, [1.0, 1.0, 0.0, 0.0, 0.0]);
        assert_eq!(out_of_slot(0.026), 1.0);
        // Standing on the table: not raised.
        assert!(rows.iter().all(|r| r[3] == 0.0));
        // Lifted 20 mm where it stood: held. Let go tilted in its slot,
        // its bottom 16 mm up and its centre 16 mm off its goal: packed,
        // not held.
        let lifted = Node {
            centre: [0.3, 0.0, 0.05],
            ..node(0.3)
        };
        let tilted = Node {
            centre: [0.0, 0.0, 0.046],
            ..node(0.0)
        };
        let rows = node_rows(&Graph {
            nodes: vec![lifted, tilted],
            slots: Vec::new(),
            held_goal: [0.0; 3],
        });
        assert_eq!((rows[0][2], rows[0][3]), (1.0, 1.0));
        assert_eq!((rows[1][2], rows[1][3]), (0.0, 0.0));
    }

    #[test]
    fn sub_goal_outputs_round_trip() {
        for base in [[0.0, 0.0, 0.0], [0.2, -0.1, 0.3]] {
            for (stage, index) in [Stage::Picking, Stage::Placing]
                .into_iter()
                .flat_map(|s| (0..3).map(move |i| (s, i)))
            {
                let q = SubGoalQuery {
                    stage,
                    index,
                    feature: [-0.5, 0.1, 0.08],
                    tool: [0.6, -0.3, 0.2],
                    height: 0.05,
                    base,
                };
                let target = [-0.2, -0.45, 0.2];
                let back = subgoal_position(&q, subgoal_output(&q, target));
                for j in 0..3 {
                    assert!((back[j] - target[j]).abs() < 1e-5, "{back:?}");
                }
            }
        }
    }

    /// "Above the slot" (the held product 50 mm over the rim) and the
    /// release (5 mm over the floor), asked from the same place over the
    /// rim, read and write the same numbers whatever the box's depth and
    /// the product's height: nothing for the planner to extrapolate in a
    /// box deeper or for a product taller than any taught.
    #[test]
    fn a_box_of_any_depth_and_a_product_of_any_height_read_the_same() {
        let encoded = |rim: f32, height: f32| {
            let query = |index| SubGoalQuery {
                stage: Stage::Placing,
                index,
                feature: [0.1, 0.6, rim],
                tool: [0.15, 0.55, rim + height + 0.07],
                height,
                base: [0.0, 0.0, 0.2],
            };
            let above = subgoal_output(&query(1), [0.1, 0.6, rim + height + 0.05]);
            let release = subgoal_output(&query(2), [0.1, 0.6, height + 0.005]);
            let mut all = subgoal_input(&query(2)).to_vec();
            all.extend(above);
            all.extend(release);
            all
        };
        let taught = encoded(0.08, 0.04);
        for (rim, height) in [(0.06, 0.025), (0.1, 0.06), (0.25, 0.12), (0.4, 0.15)] {
            for (a, b) in taught.iter().zip(encoded(rim, height)) {
                assert!((a - b).abs() < 1e-5, "{rim} {height}: {a} against {b}");
            }
        }
    }

    /// A held product reads as raised whatever the cell's lift (20 mm to
    /// 500 mm, the language's range), one on the table or on a box's floor (at table height) as
    /// not: the reasoner tells them apart the same way in every cell.
    #[test]
    fn a_held_product_reads_as_raised_at_any_lift() {
        let node = |bottom: f32| Node {
            centre: [0.5, 0.1, bottom + 0.03],
            height: 0.06,
            selected: true,
            goal: [0.0, 0.6, 0.03],
        };
        let raised = |bottom| {
            node_rows(&Graph {
                nodes: vec![node(bottom)],
                ..Graph::default()
            })[0][NODE_FEATURES - 1]
        };
        for lift in [0.02, 0.05, 0.1, 0.15, 0.5] {
            assert!(raised(lift) > 0.999, "lift {lift}");
        }
        assert_eq!(raised(0.0), 0.0);
    }

    /// Turning the whole arm (base joint and delta together) leaves the
    /// action input unchanged.
    #[test]
    fn action_inputs_turn_with_the_base() {
        let delta = [0.1f32, -0.05, 0.02];
        let a = action_input(delta, [0.3, -1.2, 1.5]);
        let t = 1.1f32;
        let turned = [
            t.cos() * delta[0] - t.sin() * delta[1],
            t.sin() * delta[0] + t.cos() * delta[1],
            delta[2],
        ];
        let b = action_input(turned, [0.3 + t, -1.2, 1.5]);
        for j in 0..ACTION_INPUTS {
            assert!((a[j] - b[j]).abs() < 1e-5);
        }
    }
}
