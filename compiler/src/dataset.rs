//! Phase 5: the reasoner's graph samples. For each demonstration and each
//! product it handles, two samples:
//! - picking (stage 0): every present product where it is now (packed ones
//!   at their slot goal), target = the product's node, label 0 (`pick`);
//! - placing (stage 1): the held product raised by the cell's lift above
//!   where it stood, target = M (the box), label = its slot's label.
//!
//! Node features are (x, y, z, I): z is half the product's height at rest,
//! I = 1 for every product the order selects. Nodes follow the inventory's
//! listed order; missing products have no node, so the present ones are
//! packed to the front and the rest of the M columns are padding
//! (`node_mask` 0). Goal = the handled product's slot goal (slot x, slot y,
//! height / 2).

use crate::error::Error;
use crate::expand::{Demonstration, Expanded, Setup};
use crate::model::Model;

/// Tensors of a run of samples (row-major flattening, C order): all of
/// them ([`build`]) or a chunk ([`build_chunk`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Graphs {
    /// Samples.
    pub s: usize,
    /// Node columns (the largest present-product count).
    pub m: usize,
    pub nodes: Vec<f32>,
    pub node_mask: Vec<u8>,
    pub goal: Vec<f32>,
    pub target: Vec<i64>,
    pub label: Vec<i64>,
    pub stage: Vec<u8>,
    pub demo: Vec<i64>,
    /// [2, E]: row 0 sources, row 1 targets. Chain i -> i+1 for i in
    /// 0..M-1, then i+1 -> i.
    pub edge_index: Vec<i64>,
    /// Per demonstration: (first sample, number of samples).
    pub per_demo: Vec<(usize, usize)>,
}

impl Graphs {
    pub fn edges(&self) -> usize {
        self.edge_index.len() / 2
    }
}

/// Where the product of `entry` rests in its slot.
pub fn slot_goal(m: &Model, setup: &Setup, entry: usize) -> Option<[f64; 3]> {
    let inv = &m.inventories[setup.inventory];
    let slot = setup.slot_of(entry)?;
    let s = &m.cells[inv.cell].slots[slot];
    let h = m.products[inv.entries[entry].product].size[2];
    Some([s.at[0], s.at[1], h / 2.0])
}

/// The sizes of the whole dataset, known from the expansion's counts
/// before any sample is built.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Shape {
    /// Samples (S): two per product a demonstration handles.
    pub samples: usize,
    /// Node columns (M): the most products present in a demonstration.
    pub width: usize,
}

impl Shape {
    pub fn of(ex: &Expanded) -> Shape {
        Shape {
            samples: ex.blocks.iter().map(|b| 2 * b.handled).sum(),
            width: ex.blocks.iter().map(|b| b.most_present).max().unwrap_or(0),
        }
    }

    /// E: the chain's edges, both ways.
    pub fn edges(&self) -> usize {
        2 * self.width.saturating_sub(1)
    }
}

/// `[2, E]`: chain edges both ways, sources `[0..M-1, 1..M]`, targets
/// `[1..M, 0..M-1]`.
pub fn edge_index(width: usize) -> Vec<i64> {
    let low: Vec<i64> = (0..width.saturating_sub(1) as i64).collect();
    let high: Vec<i64> = low.iter().map(|i| i + 1).collect();
    [&low[..], &high[..], &high[..], &low[..]].concat()
}

/// Every sample of the expansion, in memory: for tests and small
/// datasets (`emit` builds them a chunk at a time with [`build_chunk`]).
pub fn build(m: &Model, ex: &Expanded) -> Result<Graphs, Error> {
    let shape = Shape::of(ex);
    let demos = ex.demonstrations(m).collect::<Result<Vec<_>, _>>()?;
    let mut g = build_chunk(m, demos.iter().enumerate(), shape.width, 0);
    g.edge_index = edge_index(shape.width);
    Ok(g)
}

/// The samples of `demos` (each with its index among all demonstrations),
/// numbered from `first_sample`, with `width` node columns; `edge_index`
/// is left empty.
pub fn build_chunk<'a>(
    m: &Model,
    demos: impl IntoIterator<Item = (usize, &'a Demonstration)>,
    width: usize,
    first_sample: usize,
) -> Graphs {
    let mut g = Graphs {
        m: width,
        ..Graphs::default()
    };
    for (di, d) in demos {
        let first = first_sample + g.s;
        let setup = &d.setup;
        let inv = &m.inventories[setup.inventory];
        let lift = m.cells[inv.cell].lift;
        let present: Vec<usize> = (0..inv.entries.len())
            .filter(|e| !setup.missing.contains(e))
            .collect();
        // Current (x, y, z) of each present node.
        let mut state: Vec<[f64; 3]> = present
            .iter()
            .map(|&e| {
                let h = m.products[inv.entries[e].product].size[2];
                let rest = [setup.positions[e][0], setup.positions[e][1], h / 2.0];
                if setup.human_packed.contains(&e) {
                    slot_goal(m, setup, e).unwrap_or(rest)
                } else {
                    rest
                }
            })
            .collect();
        let selected: Vec<bool> = present
            .iter()
            .map(|&e| setup.slot_of(e).is_some())
            .collect();
        for &e in &d.sequence {
            let (Some(node), Some(goal), Some(slot)) = (
                present.iter().position(|&p| p == e),
                slot_goal(m, setup, e),
                setup.slot_of(e),
            ) else {
                continue;
            };
            push(&mut g, &state, &selected, goal, node as i64, 0, 0, di);
            state[node][2] += lift;
            push(
                &mut g,
                &state,
                &selected,
                goal,
                width as i64,
                slot as i64 + 1,
                1,
                di,
            );
            state[node] = goal;
        }
        g.per_demo.push((first, first_sample + g.s - first));
    }
    g
}

#[allow(clippy::too_many_arguments)]
fn push(
    g: &mut Graphs,
    state: &[[f64; 3]],
    selected: &[bool],
    goal: [f64; 3],
    target: i64,
    label: i64,
    stage: u8,
    demo: usize,
) {
    for (col, p) in state.iter().enumerate() {
        g.nodes.extend([
            p[0] as f32,
            p[1] as f32,
            p[2] as f32,
            f32::from(u8::from(selected[col])),
        ]);
        g.node_mask.push(1);
    }
    for _ in state.len()..g.m {
        g.nodes.extend([0.0; 4]);
        g.node_mask.push(0);
    }
    g.goal.extend(goal.map(|v| v as f32));
    g.target.push(target);
    g.label.push(label);
    g.stage.push(stage);
    g.demo.push(demo as i64);
    g.s += 1;
}
