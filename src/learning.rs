//! The CLI's side of learning: training samples from compiled artifacts and
//! expert replays, and model directories on disk (the bundled default model
//! is compiled into the binary).

use crate::bridge::demonstration_episode;
use anyhow::{Context, bail};
use packwright_compiler::artifact::{DemonstrationRecord, WorldFile};
use packwright_runtime::execute::{self, PlannerKind};
use packwright_runtime::learn::{ActionExample, GraphExample, Networks, SubGoalExample};
use packwright_runtime::record::MotionLog;
use packwright_runtime::sim::Simulator;
use rayon::prelude::*;
use safetensors::SafeTensors;
use std::path::Path;

pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> anyhow::Result<T> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_slice(&bytes)
        .with_context(|| format!("{} is not a packwright artifact", path.display()))
}

fn tensor<'a>(st: &'a SafeTensors, name: &str) -> anyhow::Result<(Vec<usize>, &'a [u8])> {
    let t = st
        .tensor(name)
        .with_context(|| format!("graphs.safetensors has no tensor `{name}`"))?;
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
pub fn graph_examples(bytes: &[u8], keep: &[bool]) -> anyhow::Result<Vec<GraphExample>> {
    let st = SafeTensors::deserialize(bytes).context("graphs.safetensors is not safetensors")?;
    let (shape, nodes) = tensor(&st, "nodes")?;
    let (_, mask) = tensor(&st, "node_mask")?;
    let (_, goal) = tensor(&st, "goal")?;
    let (_, target) = tensor(&st, "target")?;
    let (_, label) = tensor(&st, "label")?;
    let (_, demo) = tensor(&st, "demo")?;
    let [s, m, 4] = shape[..] else {
        bail!("graphs.safetensors: nodes has shape {shape:?}, expected [S, M, 4]");
    };
    let (nodes, goal) = (f32s(nodes), f32s(goal));
    let (target, label, demo) = (i64s(target), i64s(label), i64s(demo));
    if nodes.len() != s * m * 4
        || mask.len() != s * m
        || goal.len() != s * 3
        || [target.len(), label.len(), demo.len()] != [s, s, s]
    {
        bail!("graphs.safetensors: tensors of inconsistent sizes");
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

/// One demonstration replayed by the expert: its motion log, or `None` if
/// the expert could not complete it.
pub fn replay(world: &WorldFile, demo: &DemonstrationRecord) -> anyhow::Result<Option<MotionLog>> {
    let ep = demonstration_episode(world, demo)?;
    let start = execute::home(&ep.arm, &ep.task.cell)
        .context("the arm cannot reach a start pose over the pending area")?;
    let mut sim = Simulator::new(ep.arm.clone(), &ep.task.cell, &ep.placements, start)?;
    let mut log = MotionLog::default();
    let report = execute::run_recorded(
        &mut sim,
        &ep.arm,
        &ep.task,
        PlannerKind::Expert,
        Some(&mut log),
    );
    Ok(report.complete.then_some(log))
}

/// Replays `demos` in parallel (rayon); `tick` is called after each. The
/// logs come back in the order of `demos`.
pub fn replay_all(
    world: &WorldFile,
    demos: &[&DemonstrationRecord],
    tick: &(dyn Fn() + Sync),
) -> anyhow::Result<Vec<Option<MotionLog>>> {
    demos
        .par_iter()
        .map(|d| {
            let r = replay(world, d);
            tick();
            r
        })
        .collect()
}

/// The sub-goal planner's and the dynamics policy's samples of one log.
pub fn motion_examples(log: &MotionLog) -> (Vec<SubGoalExample>, Vec<ActionExample>) {
    let f = |v: [f64; 3]| v.map(|x| x as f32);
    let subgoals = log
        .subgoals
        .iter()
        .map(|s| SubGoalExample {
            feature: f(s.feature),
            tool: f(s.tool),
            label: s.label as usize,
            index: usize::from(s.index),
            target: f(s.target),
        })
        .collect();
    let actions = log
        .actions
        .iter()
        .map(|a| ActionExample {
            delta: f(a.delta),
            joints: f(a.joints),
            action: f(a.action),
        })
        .collect();
    (subgoals, actions)
}

/// The bundled model (`models/default/`), trained by `packwright train` on
/// `orders/`.
const DEFAULT: [&[u8]; 4] = [
    include_bytes!("../models/default/config.json"),
    include_bytes!("../models/default/reasoner.safetensors"),
    include_bytes!("../models/default/subgoal.safetensors"),
    include_bytes!("../models/default/dynamics.safetensors"),
];

pub fn default_model() -> anyhow::Result<Networks> {
    Networks::from_files(DEFAULT[0], DEFAULT[1], DEFAULT[2], DEFAULT[3])
        .context("the bundled default model does not load")
}

/// A model directory written by `packwright train`.
pub fn load_model(dir: &Path) -> anyhow::Result<Networks> {
    let read = |name: &str| {
        let path = dir.join(name);
        std::fs::read(&path).with_context(|| {
            format!(
                "cannot read {} (a model directory holds the files `packwright train` writes)",
                path.display()
            )
        })
    };
    let files = packwright_runtime::learn::inference::FILES;
    Networks::from_files(
        &read(files[0])?,
        &read(files[1])?,
        &read(files[2])?,
        &read(files[3])?,
    )
    .with_context(|| format!("{} is not a usable model", dir.display()))
}
