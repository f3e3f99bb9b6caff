//! The trained networks' forward passes on plain `f32` slices, for run
//! time.
//!
//! burn/flex costs microseconds per tensor operation at batch 1, and a
//! reasoner call is some sixty operations; these loops do the same
//! arithmetic without that overhead (ARCHITECTURE.md, "Decisions"; the
//! figures are in the README). The weights are read from a model's
//! safetensors files (`networks.rs`) or copied from the burn modules after
//! training (`packwright-train`), and a test there checks these passes
//! against burn's on random inputs.
//!
//! A dense layer is a loop over its inputs adding a weight column times
//! the input (contiguous, so it vectorises), inputs that are 0 included:
//! after a ReLU about half are, but which ones changes with every policy
//! step, and a branch to skip them, mispredicted, cost more than the
//! arithmetic it saved (measured in the learned loop: a policy action took
//! 0.46 us with the branch, 0.33 without; a warm benchmark with the same
//! input every call predicts the branch perfectly and says the opposite).
//! A head narrower than [`NARROW`] outputs (the sub-goal's 3, the latent's
//! 4, a score's 1) is stored padded with zero columns, so that its block
//! is one register per row instead of a scalar loop over 3 outputs (that
//! loop cost as much as the 32 × 32 layer before it). `cargo bench -p
//! packwright-nets --bench learning` measures these passes.

use crate::features::{
    ACTION_INPUTS, NODE_FEATURES, OWN_FEATURES, PLACE, SLOT_FEATURES, action_input, own_row,
};

/// A dense layer: `y = W x + b`.
#[derive(Debug, Clone)]
pub struct Dense {
    inputs: usize,
    outputs: usize,
    /// Columns per input in `w` and `b`: `outputs`, or [`NARROW`] for a
    /// narrower layer (a head of 1 to 4 outputs), padded with zeros, so
    /// that its one block is whole registers rather than a scalar loop.
    stride: usize,
    /// burn's layout, row-major [in, out] (padded to `stride`): the
    /// weights from input `j` are `w[j * stride..(j + 1) * stride]`.
    w: Vec<f32>,
    b: Vec<f32>,
}

/// The width a layer with fewer outputs is padded to ([`Dense`]).
const NARROW: usize = 8;

impl Dense {
    /// From burn's `weight` (row-major [in, out]) and `bias` ([out];
    /// `None`: zeros). `None` when the lengths do not fit.
    pub fn new(
        inputs: usize,
        outputs: usize,
        weight: Vec<f32>,
        bias: Option<Vec<f32>>,
    ) -> Option<Dense> {
        let b = match bias {
            Some(b) if b.len() == outputs => b,
            Some(_) => return None,
            None => vec![0.0; outputs],
        };
        if weight.len() != inputs * outputs {
            return None;
        }
        if outputs >= NARROW || outputs == 0 {
            return Some(Dense {
                inputs,
                outputs,
                stride: outputs,
                w: weight,
                b,
            });
        }
        let pad = |row: &[f32]| {
            let mut padded = [0.0; NARROW];
            padded[..outputs].copy_from_slice(row);
            padded
        };
        Some(Dense {
            inputs,
            outputs,
            stride: NARROW,
            w: weight.chunks_exact(outputs).flat_map(pad).collect(),
            b: pad(&b).to_vec(),
        })
    }

    /// `W x + b` for each of the `n` rows of `x` (rows of `self.inputs`)
    /// into the first `n` rows of `y` (rows of `self.outputs`).
    fn apply_into(&self, x: &[f32], n: usize, y: &mut [f32]) {
        let rows = x
            .chunks_exact(self.inputs)
            .zip(y.chunks_exact_mut(self.outputs));
        for (row, out) in rows.take(n) {
            out.copy_from_slice(&self.b[..self.outputs]);
            for (&xj, column) in row.iter().zip(self.w.chunks_exact(self.stride)) {
                axpy(out, &column[..self.outputs], xj);
            }
        }
    }

    /// `W x + b` for `R` rows at once (`x[r]` of `self.inputs` values into
    /// `y[r]` of `self.outputs`), bit for bit what [`Dense::apply_into`]
    /// gives each row: every output gets the same products added in the
    /// same order. A block of outputs of
    /// every row stays in registers while the inputs pass, so no output is
    /// stored until its block is done and the rows share one walk over the
    /// weights; with AVX2 the blocks are twice as wide.
    fn apply_rows<const R: usize>(&self, x: [&[f32]; R], y: [&mut [f32]; R]) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.apply_rows_avx2(x, y) };
        }
        if self.stride == NARROW {
            self.apply_blocks::<R, NARROW>(x, y);
        } else {
            self.apply_blocks::<R, BLOCK>(x, y);
        }
    }

    /// [`Dense::apply_rows`] in 256-bit registers. AVX2 only, not FMA: a
    /// fused multiply-add rounds once where `axpy` rounds twice, and the
    /// results must not depend on the CPU.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn apply_rows_avx2<const R: usize>(&self, x: [&[f32]; R], y: [&mut [f32]; R]) {
        if self.stride == NARROW {
            self.apply_blocks::<R, NARROW>(x, y);
        } else {
            self.apply_blocks::<R, { 2 * BLOCK }>(x, y);
        }
    }

    /// [`Dense::apply_rows`] in blocks of `B` outputs, the last one
    /// shorter; inlined into the callers above, so that it is compiled for
    /// their instruction sets.
    #[inline(always)]
    fn apply_blocks<const R: usize, const B: usize>(&self, x: [&[f32]; R], mut y: [&mut [f32]; R]) {
        let whole = self.stride - self.stride % B;
        for start in (0..whole).step_by(B) {
            self.apply_columns::<R, B>(start..start + B, x, &mut y);
        }
        if whole < self.stride {
            self.apply_columns::<R, B>(whole..self.stride, x, &mut y);
        }
    }

    /// [`Dense::apply_blocks`] for the outputs in `columns` (at most `B`);
    /// inlined, so that for a whole block the accumulators' size is known
    /// and they live in registers.
    #[inline(always)]
    fn apply_columns<const R: usize, const B: usize>(
        &self,
        columns: std::ops::Range<usize>,
        x: [&[f32]; R],
        y: &mut [&mut [f32]; R],
    ) {
        let n = columns.len();
        // Rows shorter than the layer's inputs (never with loaded weights,
        // whose widths are checked) end the sum rather than panic.
        let inputs = x.iter().map(|row| row.len()).fold(self.inputs, usize::min);
        let mut acc = [[0.0f32; B]; R];
        for a in &mut acc {
            a[..n].copy_from_slice(&self.b[columns.clone()]);
        }
        for (j, column) in self.w.chunks_exact(self.stride).enumerate().take(inputs) {
            let w = &column[columns.clone()];
            for (a, row) in acc.iter_mut().zip(x) {
                axpy(&mut a[..n], w, row[j]);
            }
        }
        for (a, out) in acc.iter().zip(y.iter_mut()) {
            if columns.end <= self.outputs {
                out[columns.clone()].copy_from_slice(&a[..n]);
            } else {
                // A narrow layer's padding is not an output.
                let done: [f32; B] = *a;
                out[columns.start..self.outputs]
                    .copy_from_slice(&done[..self.outputs - columns.start]);
            }
        }
    }
}

/// `y += a x` (vectorised: contiguous, no bounds checks in the loop).
fn axpy(y: &mut [f32], x: &[f32], a: f32) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += a * x;
    }
}

fn argmax(v: impl Iterator<Item = f32>) -> usize {
    v.enumerate()
        .fold((0, f32::NEG_INFINITY), |best, (i, x)| {
            if x > best.1 { (i, x) } else { best }
        })
        .0
}

/// `tanh` of every value, within 4e-7 of the exact one (the sub-goal
/// planner's activation). Lambert's continued fraction for tanh cut after
/// 12 terms is one ratio of two polynomials in x² (integer coefficients,
/// both divided by the constant term); beyond |x| = 9 tanh is 1 in `f32`.
/// Only multiplications, additions and one division, so the loop
/// vectorises (libm's `tanhf` is a call per value: it took two thirds of a
/// sub-goal query) and gives the same bits on every CPU.
fn tanh(values: &mut [f32]) {
    const S: f64 = 7_905_853_580_625.0;
    const P: [f32; 7] = [
        1.0,
        (1_159_525_191_825.0 / S) as f32,
        (41_247_931_725.0 / S) as f32,
        (523_783_260.0 / S) as f32,
        (2_552_550.0 / S) as f32,
        (4_095.0 / S) as f32,
        (1.0 / S) as f32,
    ];
    const Q: [f32; 7] = [
        1.0,
        (3_794_809_718_700.0 / S) as f32,
        (252_070_693_875.0 / S) as f32,
        (5_237_832_600.0 / S) as f32,
        (41_351_310.0 / S) as f32,
        (120_120.0 / S) as f32,
        (91.0 / S) as f32,
    ];
    for v in values {
        let x = v.clamp(-9.0, 9.0);
        let y = x * x;
        let p = P.iter().rev().fold(0.0, |acc, c| acc * y + c);
        let q = Q.iter().rev().fold(0.0, |acc, c| acc * y + c);
        *v = x * p / q;
    }
}

/// Outputs per register block of [`Dense::apply_rows`] (twice as many
/// with AVX2): two rows of 16 accumulators take 8 of the 16 SSE (AVX)
/// registers, leaving room for the weights.
const BLOCK: usize = 16;

/// Cache-line aligned values.
#[repr(align(64))]
struct Aligned<const N: usize>([f32; N]);

/// `f` on `len` zeroed values: on the stack in a block of `N`, aligned to a
/// cache line, when they fit; else on the heap.
fn with_scratch<const N: usize, R>(len: usize, f: impl FnOnce(&mut [f32]) -> R) -> R {
    if len <= N {
        let mut stack = Aligned([0.0; N]);
        f(&mut stack.0[..len])
    } else {
        let mut heap = vec![0.0; len];
        f(&mut heap)
    }
}

/// The reasoner's scratch on the stack (8 KiB): 5 products need 1,280
/// values, 20 products 4,928 (heap).
const REASONER_SCRATCH: usize = 2048;
/// A multilayer perceptron's scratch on the stack: two layers of up to 128.
const MLP_SCRATCH: usize = 256;

/// `layers` in turn on `input`, a ReLU between two layers (none after the
/// last), in stack scratch.
fn relu_mlp(layers: &[Dense], input: &[f32]) -> Vec<f32> {
    let width = layers
        .iter()
        .map(|l| l.outputs)
        .chain([input.len()])
        .max()
        .unwrap_or(input.len())
        .next_multiple_of(16);
    let mut out = Vec::new();
    with_scratch::<MLP_SCRATCH, _>(2 * width, |scratch| {
        let (mut a, mut b) = scratch.split_at_mut(width);
        a[..input.len()].copy_from_slice(input);
        let mut n = input.len();
        let last = layers.len().saturating_sub(1);
        for (i, layer) in layers.iter().enumerate() {
            layer.apply_into(&a[..n], 1, b);
            n = layer.outputs;
            if i < last {
                b[..n].iter_mut().for_each(|v| *v = v.max(0.0));
            }
            std::mem::swap(&mut a, &mut b);
        }
        out.extend_from_slice(&a[..n]);
    });
    out
}

/// A GraphSAGE layer's two dense maps.
#[derive(Debug, Clone)]
pub struct SageWeights {
    pub own: Dense,
    pub neighbours: Dense,
}

#[derive(Debug, Clone)]
pub struct ReasonerWeights {
    pub layers: Vec<SageWeights>,
    /// A node's score network, on its row without the place.
    pub node_hidden: Dense,
    pub node_score: Dense,
    /// The chain slope (>= 0): a node's score falls by this much per unit
    /// of place along the chain.
    pub chain: f32,
    pub box_hidden: Dense,
    pub box_score: Dense,
    /// The slot pointer: a score per slot from its row.
    pub pointer: Vec<Dense>,
}

impl ReasonerWeights {
    /// Node and box logits for one graph's node rows
    /// ([`node_rows`](crate::features::node_rows)); the box last. A node's
    /// neighbours are the chain's.
    ///
    /// Works in one cache-aligned scratch on the stack: inside a run the
    /// allocator is as cold as the weights, and a fresh heap block can
    /// cost page faults.
    pub fn scores(&self, nodes: &[[f32; NODE_FEATURES]]) -> Vec<f32> {
        let m = nodes.len();
        let width = self
            .layers
            .iter()
            .map(|l| l.own.outputs)
            .chain([
                NODE_FEATURES,
                self.node_hidden.outputs,
                self.box_hidden.inputs,
                self.box_hidden.outputs,
            ])
            .max()
            .unwrap_or(NODE_FEATURES)
            // Whole cache lines: every part of the scratch starts aligned.
            .next_multiple_of(16);
        let mut scores = vec![0.0f32; m + 1];
        with_scratch::<REASONER_SCRATCH, _>(5 * m * width + 2 * width, |scratch| {
            let (x, rest) = scratch.split_at_mut(m * width);
            let (h, rest) = rest.split_at_mut(m * width);
            let (mean, rest) = rest.split_at_mut(m * width);
            let (out, rest) = rest.split_at_mut(m * width);
            let (neighbours, rest) = rest.split_at_mut(m * width);
            let (pooled, hidden) = rest.split_at_mut(width);
            let x = &mut x[..m * NODE_FEATURES];
            for (row, node) in x.chunks_exact_mut(NODE_FEATURES).zip(nodes) {
                row.copy_from_slice(node);
            }
            h[..x.len()].copy_from_slice(x);
            let mut w = NODE_FEATURES;
            for layer in &self.layers {
                // The mean of each node's chain neighbours.
                let mean = &mut mean[..m * w];
                let rows = &h[..m * w];
                for (i, row) in mean.chunks_exact_mut(w).enumerate() {
                    let before = i.checked_sub(1);
                    let after = (i + 1 < m).then_some(i + 1);
                    let degree = [before, after].iter().flatten().count();
                    row.fill(0.0);
                    for j in [before, after].into_iter().flatten() {
                        axpy(row, &rows[j * w..(j + 1) * w], 1.0 / degree as f32);
                    }
                }
                let o = layer.own.outputs;
                layer.own.apply_into(rows, m, out);
                layer.neighbours.apply_into(mean, m, neighbours);
                let rows = out.chunks_exact_mut(o).zip(neighbours.chunks_exact(o));
                for (row, n) in rows.take(m) {
                    for (v, n) in row.iter_mut().zip(n) {
                        *v = (*v + n).max(0.0);
                    }
                    let norm = (row.iter().map(|v| v * v).sum::<f32>() + 1e-12).sqrt();
                    row.iter_mut().for_each(|v| *v /= norm);
                }
                h[..m * o].copy_from_slice(&out[..m * o]);
                w = o;
            }
            // Node scores from the nodes' own inputs, less the chain
            // slope times the place.
            let own = &mut mean[..m * OWN_FEATURES];
            for (row, node) in own.chunks_exact_mut(OWN_FEATURES).zip(nodes) {
                row.copy_from_slice(&own_row(node));
            }
            let k = self.node_hidden.outputs;
            self.node_hidden.apply_into(own, m, out);
            out[..m * k].iter_mut().for_each(|v| *v = v.max(0.0));
            self.node_score.apply_into(&out[..m * k], m, &mut scores);
            for (score, node) in scores.iter_mut().zip(nodes) {
                *score -= self.chain * node[PLACE];
            }
            // The box: max of the embeddings (>= 0; when there are
            // GraphSAGE layers) and of the raw inputs.
            let e = if self.layers.is_empty() { 0 } else { w };
            let pooled = &mut pooled[..e + NODE_FEATURES];
            pooled.fill(f32::NEG_INFINITY);
            if e > 0 {
                for row in h[..m * w].chunks_exact(w) {
                    for (p, v) in pooled.iter_mut().zip(row) {
                        *p = p.max(*v);
                    }
                }
            }
            for row in x.chunks_exact(NODE_FEATURES) {
                for (p, v) in pooled[e..].iter_mut().zip(row) {
                    *p = p.max(*v);
                }
            }
            if m == 0 {
                pooled[..e].fill(0.0);
                pooled[e..].fill(-1e3);
            }
            let hidden = &mut hidden[..self.box_hidden.outputs];
            self.box_hidden.apply_into(pooled, 1, hidden);
            hidden.iter_mut().for_each(|v| *v = v.max(0.0));
            self.box_score.apply_into(hidden, 1, &mut scores[m..]);
        });
        scores
    }

    /// The best output of `scores` (`scores.len() - 1` is the box).
    pub fn best(scores: &[f32]) -> usize {
        argmax(scores.iter().copied())
    }

    /// The slot pointer's logits, one per slot row
    /// ([`slot_rows`](crate::features::slot_rows)).
    pub fn slot_scores(&self, slots: &[[f32; SLOT_FEATURES]]) -> Vec<f32> {
        slots
            .iter()
            .map(|row| relu_mlp(&self.pointer, row).first().copied().unwrap_or(0.0))
            .collect()
    }

    /// The best slot (`None` when there are none).
    pub fn slot(&self, slots: &[[f32; SLOT_FEATURES]]) -> Option<usize> {
        (!slots.is_empty()).then(|| argmax(self.slot_scores(slots).into_iter()))
    }
}

#[derive(Debug, Clone)]
pub struct SubGoalWeights {
    pub hidden: Vec<Dense>,
    pub latent_mean: Dense,
    pub decoder: Dense,
    pub mean: Dense,
}

impl SubGoalWeights {
    /// The Gaussian head's mean with the latent at its mean (run time).
    ///
    /// In stack scratch, as the policy's steps: the first call of a
    /// sub-goal comes after the simulator ran, with the allocator cold.
    pub fn mean(&self, input: &[f32]) -> [f32; 3] {
        let hidden = self.hidden.last().map_or(input.len(), |l| l.outputs);
        let width = self
            .hidden
            .iter()
            .chain([&self.decoder, &self.mean])
            .map(|l| l.outputs)
            .chain([input.len(), hidden + self.latent_mean.outputs])
            .max()
            .unwrap_or(input.len())
            .next_multiple_of(16);
        with_scratch::<MLP_SCRATCH, _>(2 * width, |scratch| {
            let (mut a, mut b) = scratch.split_at_mut(width);
            a[..input.len()].copy_from_slice(input);
            let mut n = input.len();
            for layer in &self.hidden {
                layer.apply_rows([&a[..n]], [&mut *b]);
                n = layer.outputs;
                tanh(&mut b[..n]);
                std::mem::swap(&mut a, &mut b);
            }
            // The decoder's input: the hidden values, then the latent mean.
            let (h, z) = a.split_at_mut(n);
            self.latent_mean
                .apply_rows([&*h], [&mut z[..self.latent_mean.outputs]]);
            n += self.latent_mean.outputs;
            self.decoder.apply_rows([&a[..n]], [&mut *b]);
            let d = &mut b[..self.decoder.outputs];
            tanh(d);
            self.mean.apply_rows([&*d], [&mut *a]);
            std::array::from_fn(|j| if j < self.mean.outputs { a[j] } else { 0.0 })
        })
    }
}

#[derive(Debug, Clone)]
pub struct DynamicsWeights {
    pub layers: Vec<Dense>,
}

impl DynamicsWeights {
    /// Fractions of the largest step for (delta, joints)
    /// ([`action_input`]), minus the output at delta 0.
    ///
    /// Both rows go through the layers together ([`Dense::apply_rows`]):
    /// a policy step is two passes over the same weights, and this is the
    /// learned planner's inner loop (up to 30 steps per sub-goal).
    pub fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3] {
        let moved = action_input(delta, joints);
        let mut still = moved;
        still[..3].fill(0.0);
        let width = self
            .layers
            .iter()
            .map(|l| l.outputs)
            .chain([ACTION_INPUTS])
            .max()
            .unwrap_or(ACTION_INPUTS)
            .next_multiple_of(16);
        with_scratch::<{ 2 * MLP_SCRATCH }, _>(4 * width, |scratch| {
            let (a, b) = scratch.split_at_mut(2 * width);
            let (mut a0, mut a1) = a.split_at_mut(width);
            let (mut b0, mut b1) = b.split_at_mut(width);
            a0[..ACTION_INPUTS].copy_from_slice(&moved);
            a1[..ACTION_INPUTS].copy_from_slice(&still);
            let mut n = ACTION_INPUTS;
            let last = self.layers.len().saturating_sub(1);
            for (i, layer) in self.layers.iter().enumerate() {
                layer.apply_rows([&a0[..n], &a1[..n]], [&mut *b0, &mut *b1]);
                n = layer.outputs;
                if i < last {
                    for v in b0[..n].iter_mut().chain(&mut b1[..n]) {
                        *v = v.max(0.0);
                    }
                }
                std::mem::swap(&mut a0, &mut b0);
                std::mem::swap(&mut a1, &mut b1);
            }
            std::array::from_fn(|j| if j < n { a0[j] - a1[j] } else { 0.0 })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic stream of numbers in [-1, 1).
    fn numbers(seed: u64) -> impl FnMut() -> f32 {
        let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
        move || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        }
    }

    fn dense(inputs: usize, outputs: usize, next: &mut impl FnMut() -> f32) -> Dense {
        let w = (0..inputs * outputs).map(|_| 2.0 * next()).collect();
        let b = (0..outputs).map(|_| next()).collect();
        Dense::new(inputs, outputs, w, Some(b)).expect("shapes")
    }

    /// The vectorised `tanh` is within 4e-7 of the exact one on a grid
    /// over [-12, 12] and at the extremes, odd, and NaN for NaN.
    #[test]
    fn tanh_is_within_4e_7_of_the_exact_one() {
        let xs: Vec<f32> = (-120_000..=120_000)
            .map(|i| i as f32 * 1e-4)
            .chain([-1e30, -30.0, 30.0, 1e30, f32::INFINITY, f32::NEG_INFINITY])
            .collect();
        let mut ys = xs.clone();
        tanh(&mut ys);
        for (x, y) in xs.iter().zip(&ys) {
            let exact = f64::from(*x).tanh();
            assert!(
                (f64::from(*y) - exact).abs() < 4e-7,
                "tanh({x}) = {y}, exactly {exact}"
            );
        }
        // Odd, and 0 at 0.
        assert!(xs.iter().zip(&ys).all(|(x, y)| {
            let mut minus = [-x];
            tanh(&mut minus);
            minus[0] == -y
        }));
        let mut nan = [f32::NAN];
        tanh(&mut nan);
        assert!(nan[0].is_nan());
    }

    /// Both block widths (SSE's and AVX2's, whichever this CPU would
    /// take) and the narrow one, one row or two, give the bits of one row
    /// at a time and of the plain sum over burn's unpadded layout, on
    /// widths that leave part of a block, heads narrower than a register
    /// (padded), and inputs that are 0 or -0.
    #[test]
    fn blocked_rows_are_bit_identical_to_one_row_at_a_time() {
        let shapes = [(64, 64), (5, 37), (68, 3), (32, 1), (64, 4), (9, 8)];
        for (seed, &(inputs, outputs)) in (0..300).zip(shapes.iter().cycle()) {
            let mut next = numbers(seed);
            let w: Vec<f32> = (0..inputs * outputs).map(|_| 2.0 * next()).collect();
            let b: Vec<f32> = (0..outputs).map(|_| next()).collect();
            let layer = Dense::new(inputs, outputs, w.clone(), Some(b.clone())).expect("shapes");
            let mut row = || -> Vec<f32> {
                (0..inputs)
                    .map(|_| match next() {
                        v if v < -0.6 => 0.0,
                        v if v < -0.4 => -0.0,
                        _ => 3.0 * next(),
                    })
                    .collect()
            };
            let (x0, x1) = (row(), row());
            // burn's layout as given, unpadded, one product at a time.
            let plain = |x: &[f32]| -> Vec<u32> {
                (0..outputs)
                    .map(|o| {
                        let sum = (0..inputs).fold(b[o], |acc, j| acc + x[j] * w[j * outputs + o]);
                        sum.to_bits()
                    })
                    .collect()
            };
            let one_at_a_time = |x: &[f32]| {
                let mut y = vec![0.0; outputs];
                layer.apply_into(x, 1, &mut y);
                y.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            };
            let bits = |y: &[f32]| y.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let (mut y0, mut y1) = (vec![0.0; outputs], vec![0.0; outputs]);
            layer.apply_blocks::<2, BLOCK>([&x0, &x1], [&mut y0, &mut y1]);
            assert_eq!(
                (bits(&y0), bits(&y1)),
                (one_at_a_time(&x0), one_at_a_time(&x1))
            );
            layer.apply_blocks::<2, { 2 * BLOCK }>([&x0, &x1], [&mut y0, &mut y1]);
            assert_eq!(
                (bits(&y0), bits(&y1)),
                (one_at_a_time(&x0), one_at_a_time(&x1))
            );
            layer.apply_blocks::<1, BLOCK>([&x1], [&mut y1]);
            assert_eq!(bits(&y1), one_at_a_time(&x1));
            layer.apply_rows([&x0], [&mut y0]);
            assert_eq!(bits(&y0), one_at_a_time(&x0));
            layer.apply_blocks::<2, NARROW>([&x0, &x1], [&mut y0, &mut y1]);
            assert_eq!((bits(&y0), bits(&y1)), (plain(&x0), plain(&x1)));
        }
    }

    /// The dynamics action as it was computed before the two rows went
    /// through the layers together: two separate passes.
    fn action_in_two_passes(weights: &DynamicsWeights, delta: [f32; 3], q: [f32; 3]) -> [f32; 3] {
        let x = action_input(delta, q);
        let mut zero = x;
        zero[..3].fill(0.0);
        let moved = relu_mlp(&weights.layers, &x);
        let still = relu_mlp(&weights.layers, &zero);
        std::array::from_fn(|j| {
            moved.get(j).copied().unwrap_or(0.0) - still.get(j).copied().unwrap_or(0.0)
        })
    }

    /// The two-row pass gives the very bits of the two passes, on random
    /// weights of the model's shape and of widths that leave part of a
    /// register block, with inputs that are exactly 0 among them.
    #[test]
    fn the_paired_action_is_bit_identical_to_two_passes() {
        for (seed, widths) in (0..300).zip([[64, 64, 3], [20, 37, 3], [16, 1, 5]].iter().cycle()) {
            let mut next = numbers(seed);
            let mut inputs = ACTION_INPUTS;
            let layers = widths
                .iter()
                .map(|&outputs| {
                    let layer = dense(inputs, outputs, &mut next);
                    inputs = outputs;
                    layer
                })
                .collect();
            let weights = DynamicsWeights { layers };
            for _ in 0..20 {
                let mut value = || if next() < -0.8 { 0.0 } else { 2.0 * next() };
                let delta = [value(), value(), value()];
                let q = [value(), value(), value()];
                let bits = |a: [f32; 3]| a.map(f32::to_bits);
                assert_eq!(
                    bits(weights.action(delta, q)),
                    bits(action_in_two_passes(&weights, delta, q)),
                    "seed {seed}, widths {widths:?}, delta {delta:?}, joints {q:?}"
                );
            }
        }
    }

    /// The sub-goal planner's mean as it was computed before it ran in
    /// stack scratch: a vector per layer.
    fn mean_in_vectors(weights: &SubGoalWeights, input: &[f32]) -> [f32; 3] {
        let apply = |layer: &Dense, x: &[f32]| {
            let mut y = vec![0.0; layer.outputs];
            layer.apply_into(x, 1, &mut y);
            y
        };
        let activated = |mut x: Vec<f32>| {
            tanh(&mut x);
            x
        };
        let mut h = input.to_vec();
        for layer in &weights.hidden {
            h = activated(apply(layer, &h));
        }
        let z = apply(&weights.latent_mean, &h);
        h.extend(z);
        let d = activated(apply(&weights.decoder, &h));
        let out = apply(&weights.mean, &d);
        std::array::from_fn(|j| out.get(j).copied().unwrap_or(0.0))
    }

    /// The sub-goal mean in scratch gives the very bits of the vectors, on
    /// random weights of the model's shape and of other widths.
    #[test]
    fn the_sub_goal_mean_in_scratch_is_bit_identical_to_vectors() {
        let shapes = [(64, 4, 3), (20, 5, 3), (16, 1, 2)];
        for (seed, &(h, z, out)) in (0..300).zip(shapes.iter().cycle()) {
            let mut next = numbers(seed);
            let inputs = crate::features::SUBGOAL_INPUTS;
            let weights = SubGoalWeights {
                hidden: vec![dense(inputs, h, &mut next), dense(h, h, &mut next)],
                latent_mean: dense(h, z, &mut next),
                decoder: dense(h + z, h, &mut next),
                mean: dense(h, out, &mut next),
            };
            for _ in 0..20 {
                let input: Vec<f32> = (0..inputs)
                    .map(|_| if next() < -0.5 { 0.0 } else { next() })
                    .collect();
                let bits = |a: [f32; 3]| a.map(f32::to_bits);
                assert_eq!(
                    bits(weights.mean(&input)),
                    bits(mean_in_vectors(&weights, &input)),
                    "seed {seed}, input {input:?}"
                );
            }
        }
    }

    /// Whatever the weights, of two nodes alike but for their place along
    /// the chain the earlier scores at least as high: the chain order
    /// holds for every pair of places, taught together or not.
    #[test]
    fn an_earlier_node_never_scores_lower_than_a_later_one_like_it() {
        for seed in 0..200 {
            let mut next = numbers(seed);
            let h = 8;
            let weights = ReasonerWeights {
                layers: Vec::new(),
                node_hidden: dense(OWN_FEATURES, h, &mut next),
                node_score: dense(h, 1, &mut next),
                chain: crate::features::chain_slope(3.0 * next()),
                box_hidden: dense(NODE_FEATURES, h, &mut next),
                box_score: dense(h, 1, &mut next),
                pointer: Vec::new(),
            };
            let own = [1.0, 3.0 * next().abs(), 3.0 * next().abs()];
            let row = |place: f32| [own[0], place, own[1], own[2]];
            let (a, b) = (next().abs(), next().abs());
            let (early, late) = (a.min(b), a.max(b));
            let filler = [0.0, 0.5, 0.0, 0.0];
            let scores = weights.scores(&[row(late), filler, row(early)]);
            assert!(
                scores[2] >= scores[0],
                "seed {seed}: place {early} scores {} < place {late} scores {}",
                scores[2],
                scores[0]
            );
        }
    }
}
