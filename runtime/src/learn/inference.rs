//! A trained model: the three networks on the CPU, called with plain
//! numbers; saved as `config.json` and three safetensors files.

use super::data::{ACTION_SCALE, subgoal_input, subgoal_width};
use super::forward::{DynamicsWeights, ReasonerWeights, SubGoalWeights};
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
    /// The same weights as plain matrices: what run-time calls use.
    plain: Plain,
}

#[derive(Debug, Clone)]
struct Plain {
    reasoner: ReasonerWeights,
    subgoal: SubGoalWeights,
    dynamics: DynamicsWeights,
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
    ) -> Result<Networks, RuntimeError> {
        let plain = (|| {
            Some(Plain {
                reasoner: reasoner.weights()?,
                subgoal: subgoal.weights()?,
                dynamics: dynamics.weights()?,
            })
        })()
        .ok_or_else(|| RuntimeError::Model("cannot read the weights' values".into()))?;
        Ok(Networks {
            config,
            training,
            task: Task::default(),
            reasoner,
            subgoal,
            dynamics,
            plain,
        })
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
        let widths = [
            c.labels,
            c.graph_hidden,
            c.classifier_hidden,
            c.subgoal_hidden,
            c.subgoal_latent,
            c.dynamics_hidden,
        ];
        if widths.iter().any(|&w| w == 0 || w > 4096) || !(1..=64).contains(&c.graph_layers) {
            return Err(RuntimeError::Model(
                "config.json describes an impossible architecture".into(),
            ));
        }
        // Building the modules draws their (then replaced) initial weights
        // from the process-wide device stream: not while a seeded training
        // runs.
        let _turn = super::training::SEEDED_DEVICE
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let device = Device::flex();
        let mut r = Reasoner::new(c, &device);
        let mut s = SubGoalPlanner::new(c, &device);
        let mut d = DynamicsPolicy::new(c, &device);
        load(&mut r, "reasoner.safetensors", reasoner)?;
        load(&mut s, "subgoal.safetensors", subgoal)?;
        load(&mut d, "dynamics.safetensors", dynamics)?;
        let mut n = Networks::from_modules(saved.model, saved.training, r, s, d)?;
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
        let scores = self.plain.reasoner.scores(nodes);
        let best = ReasonerWeights::best(&scores);
        let node = (best < nodes.len()).then_some(best);
        let label = self.plain.reasoner.label(&scores, goal_of(node));
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
        let v = self.plain.subgoal.mean(&x);
        std::array::from_fn(|j| feature[j] + v[j])
    }

    /// The dynamics policy: base, shoulder and elbow steps (radians) for
    /// `delta` = sub-goal − tool tip at those joints.
    pub fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3] {
        self.plain
            .dynamics
            .action(delta, joints)
            .map(|a| a * ACTION_SCALE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learn::data::{graph_inputs, matrix};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn close(a: &[f32], b: &[f32]) -> bool {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= 1e-4 * (1.0 + x.abs().max(y.abs())))
    }

    fn values(t: Tensor<2>) -> Vec<f32> {
        t.into_data().try_to_vec::<f32>().unwrap_or_default()
    }

    /// The plain run-time passes compute what burn's forward passes do,
    /// on randomly initialised networks and random inputs of 1 to 20
    /// products.
    #[test]
    fn plain_passes_match_burn() {
        // Random weights come from the process-wide device stream: not
        // while a seeded training test runs.
        let _turn = crate::learn::training::SEEDED_DEVICE
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let device = Device::flex();
        let c = ModelConfig::new(6);
        let nets = Networks::from_modules(
            c.clone(),
            TrainConfig::default(),
            Reasoner::new(&c, &device),
            SubGoalPlanner::new(&c, &device),
            DynamicsPolicy::new(&c, &device),
        )
        .expect("weights readable");
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for m in 1..=20 {
            let nodes: Vec<[f32; 4]> = (0..m)
                .map(|_| {
                    [
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(0.0..0.5),
                        f32::from(u8::from(rng.random_bool(0.5))),
                    ]
                })
                .collect();
            let (n, a, mask, score_mask) =
                graph_inputs(std::iter::once(nodes.as_slice())).tensors(&device);
            let scores = nets.reasoner.scores(n, a, mask, score_mask);
            let plain = nets.plain.reasoner.scores(&nodes);
            assert!(close(&values(scores.clone()), &plain), "scores, m = {m}");
            let goal = [rng.random_range(-1.0..1.0), 0.5, 0.1];
            let labels = nets
                .reasoner
                .label(scores, matrix(1, 3, goal.to_vec(), &device));
            assert!(
                close(&values(labels), &nets.plain.reasoner.labels(&plain, goal)),
                "labels, m = {m}"
            );

            let mut x = Vec::new();
            let feature = [0.5, -0.2, 0.1];
            let tool = [rng.random_range(-1.0..1.0), 0.3, 0.6];
            subgoal_input(&mut x, feature, tool, m % 6, m % 3, 6);
            let burn = nets
                .subgoal
                .forward(matrix(1, subgoal_width(6), x.clone(), &device), None);
            assert!(close(&values(burn.mean), &nets.plain.subgoal.mean(&x)));

            let delta = [rng.random_range(-0.5..0.5), 0.1, -0.2];
            let joints = [rng.random_range(-3.0..3.0), -1.0, 1.5];
            let input: Vec<f32> = delta.into_iter().chain(joints).collect();
            let burn = nets.dynamics.forward(matrix(1, 6, input, &device));
            assert!(close(
                &values(burn),
                &nets.plain.dynamics.action(delta, joints)
            ));
        }
    }
}
