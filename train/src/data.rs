//! Batching training examples (`packwright_nets::features`) into tensors,
//! through the same encodings the run-time networks use.

use burn::prelude::*;
use packwright_nets::features::{
    ACTION_INPUTS, ACTION_SCALE, ActionExample, GraphExample, NODE_FEATURES, SLOT_FEATURES,
    SUBGOAL_INPUTS, SubGoalExample, action_input, node_rows, one_hot, slot_rows, subgoal_input,
    subgoal_output,
};

pub(crate) fn matrix(rows: usize, cols: usize, data: Vec<f32>, device: &Device) -> Tensor<2> {
    Tensor::from_data(TensorData::new(data, [rows, cols]), device)
}

fn cube(shape: [usize; 3], data: Vec<f32>, device: &Device) -> Tensor<3> {
    Tensor::from_data(TensorData::new(data, shape), device)
}

/// A batch of graphs padded to the largest node count `m` and slot count
/// `k`.
#[derive(Debug, Clone)]
pub struct GraphBatch {
    /// [B, m, NODE_FEATURES].
    pub nodes: Tensor<3>,
    /// [B, m, m]: chain neighbours, each row divided by its degree (mean
    /// aggregation).
    pub adjacency: Tensor<3>,
    /// [B, m, 1]: 1 for a present node, 0 for padding.
    pub mask: Tensor<3>,
    /// [B, m + 1]: 0 for a real output, -1e9 for padding.
    pub score_mask: Tensor<2>,
    /// [B, m + 1] one-hot of the chosen output (the box is column m).
    pub target: Tensor<2>,
    /// [B, k, SLOT_FEATURES].
    pub slots: Tensor<3>,
    /// [B, k]: 0 for a slot, -1e9 for padding.
    pub slot_mask: Tensor<2>,
    /// [B, k]: one-hot of the chosen slot when placing, zeros when picking.
    pub slot_target: Tensor<2>,
}

/// The graph inputs of node rows (nodes, adjacency, masks) as flat
/// vectors: shared by training batches and single inference calls.
pub(crate) struct GraphInputs {
    pub b: usize,
    pub m: usize,
    pub nodes: Vec<f32>,
    pub adjacency: Vec<f32>,
    pub mask: Vec<f32>,
    pub score_mask: Vec<f32>,
}

pub(crate) fn graph_inputs(rows: &[Vec<[f32; NODE_FEATURES]>]) -> GraphInputs {
    let b = rows.len();
    let m = rows.iter().map(Vec::len).max().unwrap_or(0).max(1);
    let mut g = GraphInputs {
        b,
        m,
        nodes: Vec::with_capacity(b * m * NODE_FEATURES),
        adjacency: vec![0.0; b * m * m],
        mask: Vec::with_capacity(b * m),
        score_mask: Vec::with_capacity(b * (m + 1)),
    };
    for (k, nodes) in rows.iter().enumerate() {
        let n = nodes.len();
        for i in 0..m {
            g.nodes
                .extend(nodes.get(i).copied().unwrap_or([0.0; NODE_FEATURES]));
            g.mask.push(if i < n { 1.0 } else { 0.0 });
            g.score_mask.push(if i < n { 0.0 } else { -1e9 });
        }
        g.score_mask.push(0.0);
        for i in 0..n {
            let neighbours = [i.checked_sub(1), (i + 1 < n).then_some(i + 1)];
            let degree = neighbours.iter().flatten().count() as f32;
            for &j in neighbours.iter().flatten() {
                g.adjacency[k * m * m + i * m + j] = 1.0 / degree;
            }
        }
    }
    g
}

impl GraphInputs {
    pub fn tensors(self, device: &Device) -> (Tensor<3>, Tensor<3>, Tensor<3>, Tensor<2>) {
        let (b, m) = (self.b, self.m);
        (
            cube([b, m, NODE_FEATURES], self.nodes, device),
            cube([b, m, m], self.adjacency, device),
            cube([b, m, 1], self.mask, device),
            matrix(b, m + 1, self.score_mask, device),
        )
    }
}

/// Slot rows padded to the most slots: ([B, k, SLOT_FEATURES], [B, k]
/// mask).
pub(crate) fn slot_inputs(
    rows: &[Vec<[f32; SLOT_FEATURES]>],
    device: &Device,
) -> (Tensor<3>, Tensor<2>) {
    let b = rows.len();
    let k = rows.iter().map(Vec::len).max().unwrap_or(0).max(1);
    let mut x = Vec::with_capacity(b * k * SLOT_FEATURES);
    let mut mask = Vec::with_capacity(b * k);
    for r in rows {
        for i in 0..k {
            x.extend(r.get(i).copied().unwrap_or([0.0; SLOT_FEATURES]));
            mask.push(if i < r.len() { 0.0 } else { -1e9 });
        }
    }
    (
        cube([b, k, SLOT_FEATURES], x, device),
        matrix(b, k, mask, device),
    )
}

pub fn graph_batch(examples: &[&GraphExample], device: &Device) -> GraphBatch {
    let rows: Vec<_> = examples.iter().map(|e| node_rows(&e.graph)).collect();
    let slot_rows: Vec<_> = examples.iter().map(|e| slot_rows(&e.graph)).collect();
    let inputs = graph_inputs(&rows);
    let (b, m) = (inputs.b, inputs.m);
    let (nodes, adjacency, mask, score_mask) = inputs.tensors(device);
    let (slots, slot_mask) = slot_inputs(&slot_rows, device);
    let k = slot_mask.dims()[1];
    let mut target = Vec::with_capacity(b * (m + 1));
    let mut slot_target = Vec::with_capacity(b * k);
    for e in examples {
        let column = if e.target >= e.graph.nodes.len() {
            m
        } else {
            e.target
        };
        one_hot(&mut target, column, m + 1);
        one_hot(&mut slot_target, e.slot.unwrap_or(usize::MAX), k);
    }
    GraphBatch {
        nodes,
        adjacency,
        mask,
        score_mask,
        target: matrix(b, m + 1, target, device),
        slots,
        slot_mask,
        slot_target: matrix(b, k, slot_target, device),
    }
}

/// Inputs [B, SUBGOAL_INPUTS] and encoded targets [B, 3].
pub fn subgoal_batch(examples: &[&SubGoalExample], device: &Device) -> (Tensor<2>, Tensor<2>) {
    let mut x = Vec::with_capacity(examples.len() * SUBGOAL_INPUTS);
    let mut y = Vec::with_capacity(examples.len() * 3);
    for e in examples {
        x.extend(subgoal_input(&e.query));
        y.extend(subgoal_output(&e.query, e.target));
    }
    let b = examples.len();
    (
        matrix(b, SUBGOAL_INPUTS, x, device),
        matrix(b, 3, y, device),
    )
}

/// Inputs [B, ACTION_INPUTS] and targets (action / 15 degrees) [B, 3].
pub fn action_batch(examples: &[&ActionExample], device: &Device) -> (Tensor<2>, Tensor<2>) {
    let mut x = Vec::with_capacity(examples.len() * ACTION_INPUTS);
    let mut y = Vec::with_capacity(examples.len() * 3);
    for e in examples {
        x.extend(action_input(e.delta, e.joints));
        y.extend(e.action.map(|a| a / ACTION_SCALE));
    }
    let b = examples.len();
    (matrix(b, ACTION_INPUTS, x, device), matrix(b, 3, y, device))
}
