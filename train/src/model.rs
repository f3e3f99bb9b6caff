//! The three networks (README, "Learning") as burn modules, their forward
//! passes for training, and their weights as run-time layers.

use crate::data::GraphBatch;
use burn::nn::{Linear, LinearConfig};
use burn::prelude::*;
use burn::tensor::activation::{relu, softplus, tanh};
use packwright_nets::ModelConfig;
use packwright_nets::features::{
    ACTION_INPUTS, CHAIN_SCALE, NODE_FEATURES, OWN_FEATURES, PLACE, SLOT_FEATURES, SUBGOAL_INPUTS,
    chain_slope,
};
use packwright_nets::forward::{
    Dense, DynamicsWeights, ReasonerWeights, SageWeights, SubGoalWeights,
};
use packwright_nets::networks::box_inputs;

fn linear(i: usize, o: usize, device: &Device) -> Linear {
    LinearConfig::new(i, o).init(device)
}

/// A layer's weights as plain numbers (`None` if burn's data does not
/// have the layer's shape).
fn dense(l: &Linear) -> Option<Dense> {
    let w = l.weight.val();
    let [inputs, outputs] = w.dims();
    let weight = w.into_data().try_to_vec::<f32>().ok()?;
    let bias = match &l.bias {
        Some(b) => Some(b.val().into_data().try_to_vec::<f32>().ok()?),
        None => None,
    };
    Dense::new(inputs, outputs, weight, bias)
}

fn denses(layers: &[Linear]) -> Option<Vec<Dense>> {
    layers.iter().map(dense).collect()
}

/// One GraphSAGE layer: h' = normalise(relu(W_self h + W_neigh mean(h_N))).
#[derive(Module, Debug)]
pub struct Sage {
    own: Linear,
    neighbours: Linear,
}

impl Sage {
    fn forward(&self, h: Tensor<3>, adjacency: Tensor<3>, mask: Tensor<3>) -> Tensor<3> {
        let mean = adjacency.matmul(h.clone());
        let out = relu(self.own.forward(h) + self.neighbours.forward(mean));
        let norm = out
            .clone()
            .powf_scalar(2.0)
            .sum_dim(2)
            .add_scalar(1e-12)
            .sqrt();
        out.div(norm) * mask
    }
}

/// The task-level reasoner: node and box scores; for the box, a pointer
/// over the cell's slots.
///
/// Three GraphSAGE layers embed the graph; the box's score reads the max
/// of the embeddings and the max of the raw node inputs (a max tells a
/// held product apart however many nodes there are; a mean changes with
/// every missing product, and picked the box with nothing held in 10% of
/// missing-stock scenarios). A node's score reads the node's own inputs:
/// when it also read its embedding, the network learnt from CASE 1
/// demonstrations the shortcut "my chain neighbour was just packed, so I
/// am next", right in CASE 1 and wrong when a worker packed products out
/// of order (ARCHITECTURE.md, "Decisions", has the measurements). The
/// slot pointer scores each slot from where it lies relative to the held
/// product's goal, with the same weights for every slot: a slot no
/// demonstration used, or another cell's, is scored like any other.
#[derive(Module, Debug)]
pub struct Reasoner {
    layers: Vec<Sage>,
    node_hidden: Linear,
    node_score: Linear,
    /// The chain slope's parameter (one weight, no bias): the score falls
    /// by `CHAIN_SCALE * softplus(weight)` per unit of place along the
    /// chain.
    chain: Linear,
    box_hidden: Linear,
    box_score: Linear,
    pointer: Vec<Linear>,
}

/// The reasoner's outputs for a batch.
pub struct ReasonerOutput {
    /// [B, m + 1] logits over the nodes and the box (padding at -1e9).
    pub scores: Tensor<2>,
    /// [B, k] logits over the slots (padding at -1e9).
    pub slots: Tensor<2>,
}

impl Reasoner {
    pub fn new(c: &ModelConfig, device: &Device) -> Reasoner {
        let h = c.graph_hidden;
        let layers = (0..c.graph_layers)
            .map(|i| Sage {
                own: linear(if i == 0 { NODE_FEATURES } else { h }, h, device),
                neighbours: linear(if i == 0 { NODE_FEATURES } else { h }, h, device),
            })
            .collect();
        let k = c.pointer_hidden;
        Reasoner {
            layers,
            node_hidden: linear(OWN_FEATURES, h, device),
            node_score: linear(h, 1, device),
            chain: LinearConfig::new(1, 1).with_bias(false).init(device),
            box_hidden: linear(box_inputs(c), h, device),
            box_score: linear(h, 1, device),
            pointer: vec![
                linear(SLOT_FEATURES, k, device),
                linear(k, k, device),
                linear(k, 1, device),
            ],
        }
    }

    /// Node and box logits: [B, m + 1].
    pub fn scores(
        &self,
        nodes: Tensor<3>,
        adjacency: Tensor<3>,
        mask: Tensor<3>,
        score_mask: Tensor<2>,
    ) -> Tensor<2> {
        let mut h = nodes.clone();
        for layer in &self.layers {
            h = layer.forward(h, adjacency.clone(), mask.clone());
        }
        let [b, m, _] = h.dims();
        let own = Tensor::cat(
            vec![
                nodes.clone().slice([0..b, 0..m, 0..PLACE]),
                nodes.clone().slice([0..b, 0..m, PLACE + 1..NODE_FEATURES]),
            ],
            2,
        );
        let place = nodes.clone().slice([0..b, 0..m, PLACE..PLACE + 1]);
        let slope = softplus(self.chain.weight.val().reshape([1, 1, 1]), 1.0) * CHAIN_SCALE;
        let node = (self.node_score.forward(relu(self.node_hidden.forward(own))) - place * slope)
            .reshape([b, m]);
        let width = h.dims()[2];
        let raw_max = (nodes + (mask - 1.0) * 1e3)
            .max_dim(1)
            .reshape([b, NODE_FEATURES]);
        let pooled = if self.layers.is_empty() {
            raw_max
        } else {
            // Embeddings are >= 0 (ReLU) and padding is 0, so the max over
            // all columns is the max over the present nodes.
            let max = h.max_dim(1).reshape([b, width]);
            Tensor::cat(vec![max, raw_max], 1)
        };
        let boxed = self
            .box_score
            .forward(relu(self.box_hidden.forward(pooled)));
        Tensor::cat(vec![node, boxed], 1) + score_mask
    }

    /// Slot logits [B, k] from slot rows [B, k, SLOT_FEATURES] and their
    /// mask.
    pub fn slot_scores(&self, slots: Tensor<3>, slot_mask: Tensor<2>) -> Tensor<2> {
        let [b, k, _] = slots.dims();
        let mut x = slots;
        let last = self.pointer.len() - 1;
        for (i, layer) in self.pointer.iter().enumerate() {
            x = layer.forward(x);
            if i < last {
                x = relu(x);
            }
        }
        x.reshape([b, k]) + slot_mask
    }

    /// The weights for the plain forward pass used at run time.
    pub(crate) fn weights(&self) -> Option<ReasonerWeights> {
        Some(ReasonerWeights {
            layers: self
                .layers
                .iter()
                .map(|l| {
                    Some(SageWeights {
                        own: dense(&l.own)?,
                        neighbours: dense(&l.neighbours)?,
                    })
                })
                .collect::<Option<_>>()?,
            node_hidden: dense(&self.node_hidden)?,
            node_score: dense(&self.node_score)?,
            chain: chain_slope(
                *self
                    .chain
                    .weight
                    .val()
                    .into_data()
                    .try_to_vec::<f32>()
                    .ok()?
                    .first()?,
            ),
            box_hidden: dense(&self.box_hidden)?,
            box_score: dense(&self.box_score)?,
            pointer: denses(&self.pointer)?,
        })
    }

    pub fn forward(&self, batch: &GraphBatch) -> ReasonerOutput {
        let scores = self.scores(
            batch.nodes.clone(),
            batch.adjacency.clone(),
            batch.mask.clone(),
            batch.score_mask.clone(),
        );
        let slots = self.slot_scores(batch.slots.clone(), batch.slot_mask.clone());
        ReasonerOutput { scores, slots }
    }
}

/// The variational sub-goal planner: tanh encoder to a Gaussian latent
/// (KL to a unit prior, reparameterised), a Gaussian head over the
/// sub-goal (cylindrical, `features::subgoal_output`).
#[derive(Module, Debug)]
pub struct SubGoalPlanner {
    hidden: Vec<Linear>,
    latent_mean: Linear,
    latent_log_std: Linear,
    decoder: Linear,
    mean: Linear,
    log_std: Linear,
}

pub struct SubGoalOutput {
    pub mean: Tensor<2>,
    pub log_std: Tensor<2>,
    pub latent_mean: Tensor<2>,
    pub latent_log_std: Tensor<2>,
}

impl SubGoalPlanner {
    pub fn new(c: &ModelConfig, device: &Device) -> SubGoalPlanner {
        let (h, z) = (c.subgoal_hidden, c.subgoal_latent);
        SubGoalPlanner {
            hidden: vec![linear(SUBGOAL_INPUTS, h, device), linear(h, h, device)],
            latent_mean: linear(h, z, device),
            latent_log_std: linear(h, z, device),
            decoder: linear(h + z, h, device),
            mean: linear(h, 3, device),
            log_std: linear(h, 3, device),
        }
    }

    /// The weights of the run-time pass (the latent at its mean).
    pub(crate) fn weights(&self) -> Option<SubGoalWeights> {
        Some(SubGoalWeights {
            hidden: denses(&self.hidden)?,
            latent_mean: dense(&self.latent_mean)?,
            decoder: dense(&self.decoder)?,
            mean: dense(&self.mean)?,
        })
    }

    /// `noise`: standard normal [B, latent] while training, `None` at run
    /// time (the latent's mean).
    pub fn forward(&self, x: Tensor<2>, noise: Option<Tensor<2>>) -> SubGoalOutput {
        let mut h = x;
        for layer in &self.hidden {
            h = tanh(layer.forward(h));
        }
        let latent_mean = self.latent_mean.forward(h.clone());
        let latent_log_std = self.latent_log_std.forward(h.clone()).clamp(-6.0, 2.0);
        let z = match noise {
            Some(eps) => latent_mean.clone() + latent_log_std.clone().exp() * eps,
            None => latent_mean.clone(),
        };
        let d = tanh(self.decoder.forward(Tensor::cat(vec![h, z], 1)));
        SubGoalOutput {
            mean: self.mean.forward(d.clone()),
            log_std: self.log_std.forward(d).clamp(-9.0, 2.0),
            latent_mean,
            latent_log_std,
        }
    }
}

/// The dynamics policy: (delta, shoulder, elbow) -> joint steps, as
/// fractions of the largest step (15 degrees). The output at delta = 0 is
/// subtracted, so a reached sub-goal asks for no motion.
#[derive(Module, Debug)]
pub struct DynamicsPolicy {
    layers: Vec<Linear>,
}

impl DynamicsPolicy {
    pub fn new(c: &ModelConfig, device: &Device) -> DynamicsPolicy {
        let h = c.dynamics_hidden;
        DynamicsPolicy {
            layers: vec![
                linear(ACTION_INPUTS, h, device),
                linear(h, h, device),
                linear(h, 3, device),
            ],
        }
    }

    pub(crate) fn weights(&self) -> Option<DynamicsWeights> {
        Some(DynamicsWeights {
            layers: denses(&self.layers)?,
        })
    }

    fn raw(&self, x: Tensor<2>) -> Tensor<2> {
        let last = self.layers.len() - 1;
        let mut x = x;
        for (i, layer) in self.layers.iter().enumerate() {
            x = layer.forward(x);
            if i < last {
                x = relu(x);
            }
        }
        x
    }

    /// `x`: [B, ACTION_INPUTS] (`features::action_input`: delta in the
    /// base joint's frame, then shoulder and elbow).
    pub fn forward(&self, x: Tensor<2>) -> Tensor<2> {
        let [b, w] = x.dims();
        let still = Tensor::cat(
            vec![
                Tensor::zeros([b, 3], &x.device()),
                x.clone().narrow(1, 3, w - 3),
            ],
            1,
        );
        self.raw(x) - self.raw(still)
    }
}
