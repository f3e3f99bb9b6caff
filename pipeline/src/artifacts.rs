//! Reading compiled artifacts: the JSON files, and the reasoner's samples
//! from `graphs.safetensors` (tensor names from the compiler's
//! `artifact::tensor`).

use crate::error::{PipelineError, Result};
use packwright_compiler::artifact::tensor;
use packwright_nets::GraphExample;
use safetensors::SafeTensors;
use std::path::Path;

/// A compiled JSON artifact at `path`.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let bytes = std::fs::read(path).map_err(|e| PipelineError::Read {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    serde_json::from_slice(&bytes).map_err(|e| PipelineError::Artifact {
        file: path.display().to_string(),
        problem: format!("not a packwright artifact ({e})"),
    })
}

fn problem(what: impl Into<String>) -> PipelineError {
    PipelineError::Artifact {
        file: "graphs.safetensors".into(),
        problem: what.into(),
    }
}

fn tensor<'a>(st: &'a SafeTensors, name: &str) -> Result<(Vec<usize>, &'a [u8])> {
    let t = st
        .tensor(name)
        .map_err(|_| problem(format!("no tensor `{name}`")))?;
    Ok((t.shape().to_vec(), t.data()))
}

fn f32s(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn i64s(bytes: &[u8]) -> Vec<i64> {
    bytes
        .chunks_exact(8)
        .map(|c| i64::from_le_bytes(std::array::from_fn(|i| c[i])))
        .collect()
}

/// The reasoner's samples of the demonstrations `keep` (indices into
/// `manifest.json`'s list) from `graphs.safetensors`.
pub fn graph_examples(bytes: &[u8], keep: &[bool]) -> Result<Vec<GraphExample>> {
    let st =
        SafeTensors::deserialize(bytes).map_err(|e| problem(format!("not safetensors ({e})")))?;
    let (shape, nodes) = tensor(&st, tensor::NODES)?;
    let (_, mask) = tensor(&st, tensor::NODE_MASK)?;
    let (_, goal) = tensor(&st, tensor::GOAL)?;
    let (_, target) = tensor(&st, tensor::TARGET)?;
    let (_, label) = tensor(&st, tensor::LABEL)?;
    let (_, demo) = tensor(&st, tensor::DEMO)?;
    let [s, m, 4] = shape[..] else {
        return Err(problem(format!(
            "nodes has shape {shape:?}, expected [S, M, 4]"
        )));
    };
    let (nodes, goal) = (f32s(nodes), f32s(goal));
    let (target, label, demo) = (i64s(target), i64s(label), i64s(demo));
    if nodes.len() != s * m * 4
        || mask.len() != s * m
        || goal.len() != s * 3
        || [target.len(), label.len(), demo.len()] != [s, s, s]
    {
        return Err(problem("tensors of inconsistent sizes"));
    }
    let mut out = Vec::new();
    for i in 0..s {
        let d = usize::try_from(demo[i]).unwrap_or(usize::MAX);
        if !keep.get(d).copied().unwrap_or(false) {
            continue;
        }
        let present: Vec<[f32; 4]> = (0..m)
            .filter(|&j| mask[i * m + j] != 0)
            .map(|j| std::array::from_fn(|k| nodes[(i * m + j) * 4 + k]))
            .collect();
        let t = usize::try_from(target[i]).unwrap_or(usize::MAX);
        out.push(GraphExample {
            target: t.min(present.len()),
            nodes: present,
            goal: [goal[i * 3], goal[i * 3 + 1], goal[i * 3 + 2]],
            label: usize::try_from(label[i]).unwrap_or(0),
        });
    }
    Ok(out)
}
