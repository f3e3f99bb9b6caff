//! `graphs.safetensors`, read and checked against the JSON artifacts: the
//! layout `emit` writes (names, dtypes, shapes from the manifest's S, M
//! and E) and what each value may be (see [`GraphsFile`]).

use super::field::Field;
use super::{CompiledDir, invalid};
use crate::error::{ArtifactProblem as P, PipelineError, Result};
use packwright_compiler::artifact::{schema, tensor};
use packwright_compiler::dataset::Graphs;
use safetensors::{Dtype, SafeTensors};
use std::path::Path;

/// The metadata key `emit` writes (the file's only one).
const SCHEMA_KEY: &str = "schema";

/// Each tensor's name, dtype and shape for `s` samples, `m` node columns
/// and `e` edges, in documented order ([`tensor::ALL`]).
pub fn layout(s: usize, m: usize, e: usize) -> [(&'static str, Dtype, Vec<usize>); 8] {
    [
        (tensor::NODES, Dtype::F32, vec![s, m, 4]),
        (tensor::NODE_MASK, Dtype::U8, vec![s, m]),
        (tensor::GOAL, Dtype::F32, vec![s, 3]),
        (tensor::TARGET, Dtype::I64, vec![s]),
        (tensor::LABEL, Dtype::I64, vec![s]),
        (tensor::STAGE, Dtype::U8, vec![s]),
        (tensor::DEMO, Dtype::I64, vec![s]),
        (tensor::EDGE_INDEX, Dtype::I64, vec![2, e]),
    ]
}

/// `graphs.safetensors`, checked: its bytes (for a digest) and its
/// tensors as the compiler built them.
///
/// Invariants: the metadata's schema is [`schema::GRAPHS`]; every tensor
/// of [`layout`] is present with its dtype and shape (S, M and E from the
/// manifest's `tensors`); for each demonstration `d` of the manifest and
/// each sample `i` of its range: `demo[i] = d`, `stage[i]` alternates 0
/// (picking) and 1 (placing) from the range's start, `node_mask[i]` is 1
/// for the demonstration's present products and 0 for the padding, nodes
/// and goal are finite, `target[i]` is within `0..=M` (a present node when
/// picking, M, the box, when placing) and `label[i]` within the labels of
/// the demonstration's cell (`0..=slots`: 0 when picking, a slot when
/// placing); `edge_index` is the chain over `0..M` both ways
/// (`dataset::build`). `graphs.per_demo` comes from the manifest.
#[derive(Debug, Clone)]
pub struct GraphsFile {
    pub bytes: Vec<u8>,
    pub graphs: Graphs,
}

impl GraphsFile {
    /// Each tensor's name, dtype and shape (the file's, as checked).
    pub fn tensors(&self) -> [(&'static str, Dtype, Vec<usize>); 8] {
        let g = &self.graphs;
        layout(g.s, g.m, g.edges())
    }
}

/// Reads `bytes` (of `path`) against `c`.
pub(super) fn read(c: &CompiledDir, path: &Path, bytes: Vec<u8>) -> Result<GraphsFile> {
    let root = Field::ROOT;
    let fail = |at: &Field, problem| invalid(path, at, problem);
    let not_safetensors = |e: safetensors::SafeTensorError| {
        fail(
            &root,
            P::NotSafetensors {
                reason: e.to_string(),
            },
        )
    };
    let (_, metadata) = SafeTensors::read_metadata(&bytes).map_err(not_safetensors)?;
    let found = metadata
        .metadata()
        .as_ref()
        .and_then(|m| m.get(SCHEMA_KEY))
        .cloned();
    if found.as_deref() != Some(schema::GRAPHS) {
        return Err(fail(
            &root.key("__metadata__").key(SCHEMA_KEY),
            P::Schema {
                found: found.unwrap_or_else(|| "(none)".to_owned()),
                expected: schema::GRAPHS.to_owned(),
            },
        ));
    }
    let st = SafeTensors::deserialize(&bytes).map_err(not_safetensors)?;
    let shapes = &c.manifest.tensors;
    let (s, m, e) = (shapes.samples, shapes.nodes, shapes.edges);
    let mut f32s: Vec<Vec<f32>> = Vec::new();
    let mut i64s: Vec<Vec<i64>> = Vec::new();
    let mut u8s: Vec<Vec<u8>> = Vec::new();
    for (name, dtype, shape) in layout(s, m, e) {
        let at = root.key(name);
        let view = st.tensor(name).map_err(|_| fail(&at, P::MissingTensor))?;
        if view.dtype() != dtype {
            return Err(fail(
                &at,
                P::Dtype {
                    found: format!("{:?}", view.dtype()),
                    expected: format!("{dtype:?}"),
                },
            ));
        }
        let elements = shape.iter().product::<usize>();
        if view.shape() != shape.as_slice() || view.data().len() != elements * (dtype.bitsize() / 8)
        {
            return Err(fail(
                &at,
                P::Shape {
                    found: view.shape().to_vec(),
                    expected: shape,
                },
            ));
        }
        let data = view.data();
        match dtype {
            Dtype::F32 => f32s.push(
                data.chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect(),
            ),
            Dtype::I64 => i64s.push(
                data.chunks_exact(8)
                    .map(|b| i64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
                    .collect(),
            ),
            _ => u8s.push(data.to_vec()),
        }
    }
    // In layout order: F32 nodes, goal; I64 target, label, demo,
    // edge_index; U8 node_mask, stage.
    let ([nodes, goal], [target, label, demo, edge_index], [node_mask, stage]) = (
        <[Vec<f32>; 2]>::try_from(f32s).map_err(|_| fail(&root, P::MissingTensor))?,
        <[Vec<i64>; 4]>::try_from(i64s).map_err(|_| fail(&root, P::MissingTensor))?,
        <[Vec<u8>; 2]>::try_from(u8s).map_err(|_| fail(&root, P::MissingTensor))?,
    );
    let graphs = Graphs {
        s,
        m,
        nodes,
        node_mask,
        goal,
        target,
        label,
        stage,
        demo,
        edge_index,
        per_demo: c
            .demonstrations
            .iter()
            .map(|d| (d.first_sample, d.samples))
            .collect(),
    };
    check(c, path, &graphs)?;
    Ok(GraphsFile { bytes, graphs })
}

fn int(v: usize) -> i64 {
    i64::try_from(v).unwrap_or(i64::MAX)
}

/// The values of `g` (shapes already checked) against the manifest and
/// `orders.json`.
fn check(c: &CompiledDir, path: &Path, g: &Graphs) -> Result<()> {
    let root = Field::ROOT;
    let fail = |at: &Field, problem| invalid(path, at, problem);
    let range = |at: &Field, value: i64, min: i64, max: i64| -> Result<()> {
        if (min..=max).contains(&value) {
            Ok(())
        } else {
            Err(fail(at, P::OutOfRange { value, min, max }))
        }
    };
    let differs = |at: &Field, found: i64, expected: String| -> PipelineError {
        fail(
            at,
            P::Differs {
                expected,
                found: found.to_string(),
            },
        )
    };
    let finite = |at: &Field, v: f32| -> Result<()> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(fail(
                at,
                P::NotFinite {
                    value: f64::from(v),
                },
            ))
        }
    };
    let m = g.m;
    let demos = c.demonstrations.len();
    let (nodes, node_mask, goal) = (
        root.key(tensor::NODES),
        root.key(tensor::NODE_MASK),
        root.key(tensor::GOAL),
    );
    let (target, label, stage, demo) = (
        root.key(tensor::TARGET),
        root.key(tensor::LABEL),
        root.key(tensor::STAGE),
        root.key(tensor::DEMO),
    );
    for (d, record) in c.demonstrations.iter().enumerate() {
        let slots = c
            .world
            .cells
            .iter()
            .find(|cell| cell.name == record.cell)
            .map_or(0, |cell| cell.slots.len());
        let present = record.start.len();
        for (k, i) in (record.first_sample..record.first_sample + record.samples).enumerate() {
            let placing = k % 2 == 1;
            let at = stage.index(i);
            let value = g.stage.get(i).copied().unwrap_or_default();
            range(&at, i64::from(value), 0, 1)?;
            if (value == 1) != placing {
                return Err(differs(
                    &at,
                    i64::from(value),
                    format!(
                        "{} (each handled product has a picking sample, 0, then a placing one, 1)",
                        u8::from(placing)
                    ),
                ));
            }
            let at = demo.index(i);
            let value = g.demo.get(i).copied().unwrap_or(-1);
            range(&at, value, 0, int(demos) - 1)?;
            if value != int(d) {
                return Err(differs(
                    &at,
                    value,
                    format!("{d} (demonstrations.jsonl gives sample {i} to demonstration {d})"),
                ));
            }
            for j in 0..m {
                let at = node_mask.index(i);
                let at = at.index(j);
                let value = g.node_mask.get(i * m + j).copied().unwrap_or_default();
                range(&at, i64::from(value), 0, 1)?;
                let expected = u8::from(j < present);
                if value != expected {
                    return Err(differs(
                        &at,
                        i64::from(value),
                        format!(
                            "{expected} (demonstration {d} has {present} products present, then padding)"
                        ),
                    ));
                }
                let row = nodes.index(i);
                let row = row.index(j);
                for f in 0..4 {
                    let value = g
                        .nodes
                        .get((i * m + j) * 4 + f)
                        .copied()
                        .unwrap_or_default();
                    finite(&row.index(f), value)?;
                }
            }
            let row = goal.index(i);
            for f in 0..3 {
                finite(
                    &row.index(f),
                    g.goal.get(i * 3 + f).copied().unwrap_or_default(),
                )?;
            }
            let at = target.index(i);
            let value = g.target.get(i).copied().unwrap_or(-1);
            range(&at, value, 0, int(m))?;
            if placing {
                range(&at, value, int(m), int(m))?;
            } else {
                range(&at, value, 0, int(present) - 1)?;
            }
            let at = label.index(i);
            let value = g.label.get(i).copied().unwrap_or(-1);
            range(&at, value, 0, int(slots))?;
            if placing {
                range(&at, value, 1, int(slots))?;
            } else {
                range(&at, value, 0, 0)?;
            }
        }
    }
    // The chain: sources [0..M-1, 1..M], targets [1..M, 0..M-1].
    let edges = root.key(tensor::EDGE_INDEX);
    let e = g.edges();
    let half = m.saturating_sub(1);
    for r in 0..2 {
        let row = edges.index(r);
        for k in 0..e {
            let at = row.index(k);
            let value = g.edge_index.get(r * e + k).copied().unwrap_or(-1);
            range(&at, value, 0, int(m) - 1)?;
            let forward = k < half;
            let source = if forward { k } else { k - half + 1 };
            let expected = match (r, forward) {
                (0, _) => source,
                (_, true) => source + 1,
                (_, false) => source - 1,
            };
            if value != int(expected) {
                return Err(differs(
                    &at,
                    value,
                    format!("{expected} (the chain over the nodes, both ways)"),
                ));
            }
        }
    }
    Ok(())
}
