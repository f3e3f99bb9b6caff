//! A freshly trained model: the burn modules (whose safetensors files
//! `packwright-nets` reads) and the same weights as run-time networks.

use crate::model::{DynamicsPolicy, Reasoner, SubGoalPlanner};
use burn::store::{ModuleSnapshot, SafetensorsStore};
use packwright_nets::config::FILES;
use packwright_nets::{
    ModelConfig, ModelError, Networks, Task, TaughtQueries, TrainConfig, Weights,
};

/// The three trained modules and their run-time twin.
#[derive(Debug, Clone)]
pub struct Trained {
    reasoner: Reasoner,
    subgoal: SubGoalPlanner,
    dynamics: DynamicsPolicy,
    /// The run-time networks (the same weights as plain numbers).
    pub networks: Networks,
}

/// Why a trained model could not be turned into files or networks.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SaveError {
    #[error("cannot read the trained weights' values")]
    Values,
    #[error("cannot serialise the weights of {file}: {reason}")]
    Serialise { file: &'static str, reason: String },
    #[error(transparent)]
    Model(#[from] ModelError),
}

fn save<M: ModuleSnapshot>(m: &M, file: &'static str) -> Result<Vec<u8>, SaveError> {
    let mut store = SafetensorsStore::from_bytes(None);
    let fail = |e: &dyn std::fmt::Display| SaveError::Serialise {
        file,
        reason: e.to_string(),
    };
    m.save_into(&mut store).map_err(|e| fail(&e))?;
    let bytes = store.get_bytes().map_err(|e| fail(&e))?;
    canonical(&bytes).ok_or_else(|| fail(&"its header is not a safetensors header"))
}

/// A safetensors file with its header's keys sorted (tensors and
/// metadata), padded with spaces to 8 bytes as `safetensors` writes it:
/// burn's store writes its metadata in a hash map's order, so that two
/// identical trainings gave files differing in those bytes alone. The
/// tensors' bytes and offsets (from the end of the header) are kept.
fn canonical(bytes: &[u8]) -> Option<Vec<u8>> {
    let n = u64::from_le_bytes(bytes.get(..8)?.try_into().ok()?);
    let end = 8usize.checked_add(usize::try_from(n).ok()?)?;
    let header: std::collections::BTreeMap<String, serde_json::Value> =
        serde_json::from_slice(bytes.get(8..end)?).ok()?;
    let mut json = serde_json::to_vec(&sorted(serde_json::to_value(header).ok()?)).ok()?;
    while json.len() % 8 != 0 {
        json.push(b' ');
    }
    let mut out = Vec::with_capacity(8 + json.len() + bytes.len() - end);
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(bytes.get(end..)?);
    Some(out)
}

/// `v` with every object's keys in sorted order.
fn sorted(v: serde_json::Value) -> serde_json::Value {
    match v {
        serde_json::Value::Object(map) => {
            let sorted: std::collections::BTreeMap<String, serde_json::Value> =
                map.into_iter().map(|(k, v)| (k, sorted(v))).collect();
            serde_json::Value::Object(sorted.into_iter().collect())
        }
        serde_json::Value::Array(items) => {
            serde_json::Value::Array(items.into_iter().map(sorted).collect())
        }
        other => other,
    }
}

impl Trained {
    pub(crate) fn new(
        config: ModelConfig,
        training: TrainConfig,
        taught_queries: TaughtQueries,
        reasoner: Reasoner,
        subgoal: SubGoalPlanner,
        dynamics: DynamicsPolicy,
    ) -> Result<Trained, SaveError> {
        let weights = (|| {
            Some(Weights {
                reasoner: reasoner.weights()?,
                subgoal: subgoal.weights()?,
                dynamics: dynamics.weights()?,
            })
        })()
        .ok_or(SaveError::Values)?;
        Ok(Trained {
            networks: Networks::new(config, training, Task::default(), taught_queries, weights),
            reasoner,
            subgoal,
            dynamics,
        })
    }

    /// Records what the model was taught (saved in `config.json`).
    pub fn set_task(&mut self, task: Task) {
        self.networks.task = task;
    }

    /// The model directory's files, in the order of
    /// [`FILES`](packwright_nets::FILES).
    pub fn to_files(&self) -> Result<Vec<(&'static str, Vec<u8>)>, SaveError> {
        Ok(vec![
            (FILES[0], self.networks.config_json()?),
            (FILES[1], save(&self.reasoner, FILES[1])?),
            (FILES[2], save(&self.subgoal, FILES[2])?),
            (FILES[3], save(&self.dynamics, FILES[3])?),
        ])
    }

    #[cfg(test)]
    pub(crate) fn modules(&self) -> (&Reasoner, &SubGoalPlanner, &DynamicsPolicy) {
        (&self.reasoner, &self.subgoal, &self.dynamics)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{graph_inputs, matrix, slot_inputs};
    use crate::training::SEEDED_DEVICE;
    use burn::prelude::*;
    use packwright_interface::{Graph, Node, Stage, SubGoalQuery};
    use packwright_nets::features::{
        ACTION_INPUTS, SUBGOAL_INPUTS, action_input, node_rows, slot_rows, subgoal_input,
    };
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
    /// products; and the files burn writes load into the same networks.
    #[test]
    fn plain_passes_match_burn() {
        // Random weights come from the process-wide device stream: not
        // while a seeded training test runs.
        let _turn = SEEDED_DEVICE
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let device = Device::flex();
        // The default (no GraphSAGE layers) and three layers.
        for layers in [0, 3] {
            same_answers(
                &ModelConfig {
                    graph_layers: layers,
                    ..ModelConfig::new()
                },
                &device,
            );
        }
    }

    fn same_answers(c: &ModelConfig, device: &Device) {
        let device = device.clone();
        let c = c.clone();
        let trained = Trained::new(
            c.clone(),
            TrainConfig::default(),
            TaughtQueries::default(),
            Reasoner::new(&c, &device),
            SubGoalPlanner::new(&c, &device),
            DynamicsPolicy::new(&c, &device),
        )
        .expect("weights readable");
        let files = trained.to_files().expect("saves");
        let loaded = Networks::from_files(&files[0].1, &files[1].1, &files[2].1, &files[3].1)
            .expect("loads without burn");
        let (reasoner, subgoal, dynamics) = trained.modules();
        let plain = trained.networks.weights();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for m in 1..=20 {
            let nodes: Vec<Node> = (0..m)
                .map(|_| Node {
                    centre: [
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(0.0..0.5),
                    ],
                    height: rng.random_range(0.02..0.1),
                    selected: rng.random_bool(0.5),
                    goal: [rng.random_range(-1.0..1.0), 0.6, 0.03],
                })
                .collect();
            let graph = Graph {
                nodes,
                slots: (0..1 + m % 7)
                    .map(|i| [0.1 * i as f32 - 0.2, rng.random_range(0.5..0.7), 0.0])
                    .collect(),
                held_goal: [rng.random_range(-0.3..0.3), 0.6, 0.03],
            };
            let rows = node_rows(&graph);
            let (n, a, mask, score_mask) =
                graph_inputs(std::slice::from_ref(&rows)).tensors(&device);
            let scores = reasoner.scores(n, a, mask, score_mask);
            let plain_scores = plain.reasoner.scores(&rows);
            assert!(close(&values(scores), &plain_scores), "scores, m = {m}");
            assert_eq!(plain_scores, loaded.weights().reasoner.scores(&rows));
            let slot_rows = slot_rows(&graph);
            let (slots, slot_mask) = slot_inputs(std::slice::from_ref(&slot_rows), &device);
            let burn_slots = reasoner.slot_scores(slots, slot_mask);
            assert!(
                close(&values(burn_slots), &plain.reasoner.slot_scores(&slot_rows)),
                "slots, m = {m}"
            );

            let query = SubGoalQuery {
                stage: if m % 2 == 0 {
                    Stage::Picking
                } else {
                    Stage::Placing
                },
                index: m % 3,
                feature: [0.5, -0.2, 0.1],
                tool: [rng.random_range(-1.0..1.0), 0.3, 0.6],
                height: 0.05,
                base: [0.1, 0.0, 0.2],
            };
            let x = subgoal_input(&query);
            let burn = subgoal.forward(matrix(1, SUBGOAL_INPUTS, x.to_vec(), &device), None);
            assert!(close(&values(burn.mean), &plain.subgoal.mean(&x)));
            assert_eq!(plain.subgoal.mean(&x), loaded.weights().subgoal.mean(&x));

            let delta = [rng.random_range(-0.5..0.5), 0.1, -0.2];
            let joints = [rng.random_range(-3.0..3.0), -1.0, 1.5];
            let input = action_input(delta, joints);
            let burn = dynamics.forward(matrix(1, ACTION_INPUTS, input.to_vec(), &device));
            assert!(close(&values(burn), &plain.dynamics.action(delta, joints)));
            assert_eq!(
                plain.dynamics.action(delta, joints),
                loaded.weights().dynamics.action(delta, joints)
            );
        }
    }
}
