//! A trained model: the three networks on the CPU, called with plain
//! numbers; saved as `config.json` and three safetensors files.

use super::data::{ACTION_SCALE, graph_inputs, matrix, subgoal_input, subgoal_width};
use super::model::{DynamicsPolicy, ModelConfig, Reasoner, SubGoalPlanner};
use super::training::TrainConfig;
use crate::error::RuntimeError;
use burn::prelude::*;
use burn::store::{ModuleSnapshot, SafetensorsStore};
use serde::{Deserialize, Serialize};

/// What the model was taught on, for the runtime to check an order against.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Task {
    /// The cell of the demonstrations.
    pub cell: String,
    /// Label names: `pick`, then the cell's slots in order.
    pub labels: Vec<String>,
    /// The demonstration blocks taught.
    pub demos: Vec<String>,
}

/// `config.json`: enough to rebuild the modules and to know what they do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedConfig {
    pub schema: String,
    pub model: ModelConfig,
    pub training: TrainConfig,
    pub task: Task,
}

pub const SCHEMA: &str = "packwright.model/1";

/// The files of a model directory.
pub const FILES: [&str; 4] = [
    "config.json",
    "reasoner.safetensors",
    "subgoal.safetensors",
    "dynamics.safetensors",
];

/// The reasoner's decision at the start of a stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Choice {
    /// The node to pick, or `None` for the box.
    pub node: Option<usize>,
    /// 0 = pick, k = the k-th slot.
    pub label: usize,
}

#[derive(Debug, Clone)]
pub struct Networks {
    pub config: ModelConfig,
    pub training: TrainConfig,
    pub task: Task,
    reasoner: Reasoner,
    subgoal: SubGoalPlanner,
    dynamics: DynamicsPolicy,
    device: Device,
}

fn model_error(what: &str, e: impl std::fmt::Display) -> RuntimeError {
    RuntimeError::Model(format!("{what}: {e}"))
}

fn save<M: ModuleSnapshot>(m: &M) -> Result<Vec<u8>, RuntimeError> {
    let mut store = SafetensorsStore::from_bytes(None);
    m.save_into(&mut store)
        .map_err(|e| model_error("cannot serialise weights", e))?;
    store
        .get_bytes()
        .map_err(|e| model_error("cannot serialise weights", e))
}

fn load<M: ModuleSnapshot>(m: &mut M, name: &str, bytes: &[u8]) -> Result<(), RuntimeError> {
    let mut store = SafetensorsStore::from_bytes(Some(bytes.to_vec()));
    let result = m.load_from(&mut store).map_err(|e| model_error(name, e))?;
    if !result.is_success() || !result.missing.is_empty() {
        return Err(RuntimeError::Model(format!(
            "{name} does not fit the architecture in config.json: {} missing, {} errors",
            result.missing.len(),
            result.errors.len()
        )));
    }
    Ok(())
}

impl Networks {
    pub(crate) fn from_modules(
        config: ModelConfig,
        training: TrainConfig,
        reasoner: Reasoner,
        subgoal: SubGoalPlanner,
        dynamics: DynamicsPolicy,
    ) -> Networks {
        Networks {
            config,
            training,
            task: Task::default(),
            reasoner,
            subgoal,
            dynamics,
            device: Device::flex(),
        }
    }

    /// The model directory's files, in the order of [`FILES`].
    pub fn to_files(&self) -> Result<Vec<(&'static str, Vec<u8>)>, RuntimeError> {
        let config = SavedConfig {
            schema: SCHEMA.into(),
            model: self.config.clone(),
            training: self.training.clone(),
            task: self.task.clone(),
        };
        let json = serde_json::to_vec_pretty(&config)
            .map_err(|e| model_error("cannot write config.json", e))?;
        Ok(vec![
            (FILES[0], json),
            (FILES[1], save(&self.reasoner)?),
            (FILES[2], save(&self.subgoal)?),
            (FILES[3], save(&self.dynamics)?),
        ])
    }

    /// Rebuilds a model from the bytes of its files (see [`FILES`]).
    pub fn from_files(
        config: &[u8],
        reasoner: &[u8],
        subgoal: &[u8],
        dynamics: &[u8],
    ) -> Result<Networks, RuntimeError> {
        let saved: SavedConfig =
            serde_json::from_slice(config).map_err(|e| model_error("config.json", e))?;
        if saved.schema != SCHEMA {
            return Err(RuntimeError::Model(format!(
                "config.json has schema {:?}, this packwright reads {SCHEMA:?}",
                saved.schema
            )));
        }
        let c = &saved.model;
        if c.labels == 0 || c.graph_layers == 0 || c.labels > 4096 || c.graph_hidden > 4096 {
            return Err(RuntimeError::Model(
                "config.json describes an impossible architecture".into(),
            ));
        }
        let device = Device::flex();
        let mut r = Reasoner::new(c, &device);
        let mut s = SubGoalPlanner::new(c, &device);
        let mut d = DynamicsPolicy::new(c, &device);
        load(&mut r, "reasoner.safetensors", reasoner)?;
        load(&mut s, "subgoal.safetensors", subgoal)?;
        load(&mut d, "dynamics.safetensors", dynamics)?;
        let mut n = Networks::from_modules(saved.model, saved.training, r, s, d);
        n.task = saved.task;
        Ok(n)
    }

    /// The reasoner: which node to pick (or the box), then the label given
    /// the handled product's goal, `goal_of(node)` (`None`: the held
    /// product's).
    pub fn reason(
        &self,
        nodes: &[[f32; 4]],
        goal_of: impl FnOnce(Option<usize>) -> [f32; 3],
    ) -> Choice {
        let (n, adjacency, mask, score_mask) =
            graph_inputs(std::iter::once(nodes)).tensors(&self.device);
        let scores = self.reasoner.scores(n, adjacency, mask, score_mask);
        let values = scores
            .clone()
            .into_data()
            .try_to_vec::<f32>()
            .unwrap_or_default();
        let best = values
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i);
        let node = (best < nodes.len()).then_some(best);
        let goal = matrix(1, 3, goal_of(node).to_vec(), &self.device);
        let labels = self.reasoner.label(scores, goal);
        let values = labels.into_data().try_to_vec::<f32>().unwrap_or_default();
        let label = values
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i);
        Choice { node, label }
    }

    /// The sub-goal planner's mean: the next tool-tip position.
    pub fn subgoal(
        &self,
        feature: [f32; 3],
        tool: [f32; 3],
        label: usize,
        index: usize,
    ) -> [f32; 3] {
        let labels = self.config.labels;
        let mut x = Vec::with_capacity(subgoal_width(labels));
        subgoal_input(
            &mut x,
            feature,
            tool,
            label.min(labels - 1),
            index.min(2),
            labels,
        );
        let out = self
            .subgoal
            .forward(matrix(1, subgoal_width(labels), x, &self.device), None);
        let v = out.mean.into_data().try_to_vec::<f32>().unwrap_or_default();
        std::array::from_fn(|j| feature[j] + v.get(j).copied().unwrap_or(0.0))
    }

    /// The dynamics policy: base, shoulder and elbow steps (radians) for
    /// `delta` = sub-goal − tool tip at those joints.
    pub fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3] {
        let mut x = delta.to_vec();
        x.extend(joints);
        let out = self.dynamics.forward(matrix(1, 6, x, &self.device));
        let v = out.into_data().try_to_vec::<f32>().unwrap_or_default();
        std::array::from_fn(|j| v.get(j).copied().unwrap_or(0.0) * ACTION_SCALE)
    }
}
