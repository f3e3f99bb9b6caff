//! Batching training examples (`packwright_nets::features`) into tensors.

use burn::prelude::*;
use packwright_nets::features::{
    ACTION_SCALE, ActionExample, GraphExample, NODE_FEATURES, SubGoalExample, one_hot,
    subgoal_input, subgoal_width,
};

pub(crate) fn matrix(rows: usize, cols: usize, data: Vec<f32>, device: &Device) -> Tensor<2> {
    Tensor::from_data(TensorData::new(data, [rows, cols]), device)
}

fn cube(shape: [usize; 3], data: Vec<f32>, device: &Device) -> Tensor<3> {
    Tensor::from_data(TensorData::new(data, shape), device)
}

/// A batch of graphs padded to the largest node count `m`.
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
    /// [B, 3].
    pub goal: Tensor<2>,
    /// [B, m + 1] one-hot of the chosen output (the box is column m).
    pub target: Tensor<2>,
    /// [B, labels] one-hot.
    pub label: Tensor<2>,
}

/// The graph inputs of `graphs` (nodes, adjacency, masks) as flat vectors:
/// shared by training batches and single inference calls.
pub(crate) struct GraphInputs {
    pub b: usize,
    pub m: usize,
    pub nodes: Vec<f32>,
    pub adjacency: Vec<f32>,
    pub mask: Vec<f32>,
    pub score_mask: Vec<f32>,
}

pub(crate) fn graph_inputs<'a>(
    graphs: impl ExactSizeIterator<Item = &'a [[f32; 4]]> + Clone,
) -> GraphInputs {
    let b = graphs.len();
    let m = graphs.clone().map(<[_]>::len).max().unwrap_or(0).max(1);
    let mut g = GraphInputs {
        b,
        m,
        nodes: Vec::with_capacity(b * m * NODE_FEATURES),
        adjacency: vec![0.0; b * m * m],
        mask: Vec::with_capacity(b * m),
        score_mask: Vec::with_capacity(b * (m + 1)),
    };
    for (k, nodes) in graphs.enumerate() {
        let n = nodes.len();
        let last = n.saturating_sub(1).max(1) as f32;
        for i in 0..m {
            g.nodes.extend(nodes.get(i).copied().unwrap_or([0.0; 4]));
            g.nodes.push(if i < n { i as f32 / last } else { 0.0 });
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

pub fn graph_batch(examples: &[&GraphExample], labels: usize, device: &Device) -> GraphBatch {
    let inputs = graph_inputs(examples.iter().map(|e| e.nodes.as_slice()));
    let (b, m) = (inputs.b, inputs.m);
    let (nodes, adjacency, mask, score_mask) = inputs.tensors(device);
    let mut goal = Vec::with_capacity(b * 3);
    let mut target = Vec::with_capacity(b * (m + 1));
    let mut label = Vec::with_capacity(b * labels);
    for e in examples {
        goal.extend(e.goal);
        let column = if e.target >= e.nodes.len() {
            m
        } else {
            e.target
        };
        one_hot(&mut target, column, m + 1);
        one_hot(&mut label, e.label, labels);
    }
    GraphBatch {
        nodes,
        adjacency,
        mask,
        score_mask,
        goal: matrix(b, 3, goal, device),
        target: matrix(b, m + 1, target, device),
        label: matrix(b, labels, label, device),
    }
}

/// Inputs [B, width] and targets (sub-goal − feature) [B, 3].
pub fn subgoal_batch(
    examples: &[&SubGoalExample],
    labels: usize,
    device: &Device,
) -> (Tensor<2>, Tensor<2>) {
    let mut x = Vec::new();
    let mut y = Vec::new();
    for e in examples {
        subgoal_input(&mut x, e.feature, e.tool, e.label, e.index, labels);
        y.extend((0..3).map(|j| e.target[j] - e.feature[j]));
    }
    let b = examples.len();
    (
        matrix(b, subgoal_width(labels), x, device),
        matrix(b, 3, y, device),
    )
}

/// Inputs [B, 6] (delta, joints) and targets (action / 5 degrees) [B, 3].
pub fn action_batch(examples: &[&ActionExample], device: &Device) -> (Tensor<2>, Tensor<2>) {
    let mut x = Vec::new();
    let mut y = Vec::new();
    for e in examples {
        x.extend(e.delta);
        x.extend(e.joints);
        y.extend(e.action.map(|a| a / ACTION_SCALE));
    }
    let b = examples.len();
    (matrix(b, 6, x, device), matrix(b, 3, y, device))
}
