//! A trained model at run time: the three networks as plain `f32` layers,
//! read from a model directory's files (`config.json` and three
//! safetensors files, the layout `packwright-train` writes: a dense
//! layer's `weight` is [inputs, outputs] row-major and its `bias`
//! [outputs]). Every tensor is checked on load: present, F32, the shape
//! `config.json` implies, finite.

use crate::config::{ModelConfig, SCHEMA, SavedConfig, Task, TrainConfig};
use crate::error::ModelError;
use crate::features::{
    ACTION_INPUTS, ACTION_SCALE, NODE_FEATURES, OWN_FEATURES, SLOT_FEATURES, SUBGOAL_INPUTS,
    chain_slope, node_rows, slot_rows, subgoal_input, subgoal_position,
};
use crate::forward::{Dense, DynamicsWeights, ReasonerWeights, SageWeights, SubGoalWeights};
use crate::taught::TaughtQueries;
use packwright_interface::{Choice, Graph, Node, Policy, SequenceRule, Stage, SubGoalQuery};
use safetensors::{Dtype, SafeTensors};

/// The three networks' run-time weights.
#[derive(Debug, Clone)]
pub struct Weights {
    pub reasoner: ReasonerWeights,
    pub subgoal: SubGoalWeights,
    pub dynamics: DynamicsWeights,
}

/// A trained model: what it is, how it was trained, what it was taught,
/// and its weights.
#[derive(Debug, Clone)]
pub struct Networks {
    pub config: ModelConfig,
    pub training: TrainConfig,
    pub task: Task,
    /// The queries the sub-goal planner was taught: it answers others as
    /// at their edge.
    pub taught_queries: TaughtQueries,
    weights: Weights,
}

/// The box score's inputs: the max of the raw node inputs, after the max
/// of the GraphSAGE embeddings when there are layers.
pub fn box_inputs(c: &ModelConfig) -> usize {
    if c.graph_layers == 0 {
        NODE_FEATURES
    } else {
        c.graph_hidden + NODE_FEATURES
    }
}

/// One weights file, read tensor by tensor.
struct File<'a> {
    name: &'static str,
    tensors: SafeTensors<'a>,
}

impl File<'_> {
    /// The dense layer `prefix` (`prefix.weight`, `prefix.bias`) with
    /// `inputs` × `outputs` weights.
    fn dense(&self, prefix: &str, inputs: usize, outputs: usize) -> Result<Dense, ModelError> {
        let weight = self.tensor(&format!("{prefix}.weight"), &[inputs, outputs])?;
        let bias = self.tensor(&format!("{prefix}.bias"), &[outputs])?;
        Dense::new(inputs, outputs, weight, Some(bias)).ok_or(ModelError::Architecture)
    }

    fn tensor(&self, name: &str, shape: &[usize]) -> Result<Vec<f32>, ModelError> {
        let t = self.tensors.tensor(name).map_err(|_| ModelError::Missing {
            file: self.name,
            tensor: name.to_owned(),
        })?;
        if t.dtype() != Dtype::F32 || t.shape() != shape {
            return Err(ModelError::Shape {
                file: self.name,
                tensor: name.to_owned(),
                found: format!("{:?} of shape {:?}", t.dtype(), t.shape()),
                expected: shape.to_vec(),
            });
        }
        let values: Vec<f32> = t
            .data()
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if values.iter().any(|v| !v.is_finite()) {
            return Err(ModelError::NotFinite {
                file: self.name,
                tensor: name.to_owned(),
            });
        }
        Ok(values)
    }
}

fn open<'a>(name: &'static str, bytes: &'a [u8]) -> Result<File<'a>, ModelError> {
    let tensors = SafeTensors::deserialize(bytes).map_err(|e| ModelError::NotSafetensors {
        file: name,
        reason: e.to_string(),
    })?;
    Ok(File { name, tensors })
}

fn denses(file: &File, prefix: &str, sizes: &[(usize, usize)]) -> Result<Vec<Dense>, ModelError> {
    sizes
        .iter()
        .enumerate()
        .map(|(i, &(a, b))| file.dense(&format!("{prefix}.{i}"), a, b))
        .collect()
}

/// How far (m) from the product a loaded sub-goal planner's answer to the
/// load probe may lie: further than any arm reaches (a UR10 1.3 m, the
/// largest industrial arms about 4 m) means unusable weights.
pub const PROBE_REACH: f64 = 10.0;

impl Networks {
    /// A model from its parts (after training).
    pub fn new(
        config: ModelConfig,
        training: TrainConfig,
        task: Task,
        taught_queries: TaughtQueries,
        weights: Weights,
    ) -> Networks {
        Networks {
            config,
            training,
            task,
            taught_queries,
            weights,
        }
    }

    /// The run-time weights.
    pub fn weights(&self) -> &Weights {
        &self.weights
    }

    /// `config.json`'s bytes for this model.
    pub fn config_json(&self) -> Result<Vec<u8>, ModelError> {
        let saved = SavedConfig {
            schema: SCHEMA.into(),
            model: self.config.clone(),
            training: self.training.clone(),
            task: self.task.clone(),
            taught_queries: self.taught_queries.clone(),
        };
        serde_json::to_vec_pretty(&saved).map_err(|e| ModelError::Write {
            reason: e.to_string(),
        })
    }

    /// Reads a model from the bytes of its files (see
    /// [`FILES`](crate::config::FILES)), checking every tensor.
    pub fn from_files(
        config: &[u8],
        reasoner: &[u8],
        subgoal: &[u8],
        dynamics: &[u8],
    ) -> Result<Networks, ModelError> {
        let bad = |e: serde_json::Error| ModelError::Config {
            reason: e.to_string(),
        };
        // The schema first: a model of another schema lacks fields or has
        // others, and "train again" says more than the missing field.
        #[derive(serde::Deserialize)]
        struct Schema {
            schema: String,
        }
        let Schema { schema } = serde_json::from_slice(config).map_err(bad)?;
        if schema != SCHEMA {
            return Err(ModelError::Schema {
                found: schema,
                expected: SCHEMA,
            });
        }
        let saved: SavedConfig = serde_json::from_slice(config).map_err(bad)?;
        let c = &saved.model;
        let widths = [
            c.graph_hidden,
            c.pointer_hidden,
            c.subgoal_hidden,
            c.subgoal_latent,
            c.dynamics_hidden,
        ];
        if widths.iter().any(|&w| w == 0 || w > 4096) || c.graph_layers > 64 {
            return Err(ModelError::Architecture);
        }
        let (h, k) = (c.graph_hidden, c.pointer_hidden);
        let r = open("reasoner.safetensors", reasoner)?;
        let layers = (0..c.graph_layers)
            .map(|i| {
                let inputs = if i == 0 { NODE_FEATURES } else { h };
                Ok(SageWeights {
                    own: r.dense(&format!("layers.{i}.own"), inputs, h)?,
                    neighbours: r.dense(&format!("layers.{i}.neighbours"), inputs, h)?,
                })
            })
            .collect::<Result<_, ModelError>>()?;
        let reasoner = ReasonerWeights {
            layers,
            node_hidden: r.dense("node_hidden", OWN_FEATURES, h)?,
            node_score: r.dense("node_score", h, 1)?,
            chain: chain_slope(r.tensor("chain.weight", &[1, 1])?[0]),
            box_hidden: r.dense("box_hidden", box_inputs(c), h)?,
            box_score: r.dense("box_score", h, 1)?,
            pointer: denses(&r, "pointer", &[(SLOT_FEATURES, k), (k, k), (k, 1)])?,
        };
        let (h, z) = (c.subgoal_hidden, c.subgoal_latent);
        let s = open("subgoal.safetensors", subgoal)?;
        let subgoal = SubGoalWeights {
            hidden: denses(&s, "hidden", &[(SUBGOAL_INPUTS, h), (h, h)])?,
            latent_mean: s.dense("latent_mean", h, z)?,
            decoder: s.dense("decoder", h + z, h)?,
            mean: s.dense("mean", h, 3)?,
        };
        let h = c.dynamics_hidden;
        let d = open("dynamics.safetensors", dynamics)?;
        let dynamics = DynamicsWeights {
            layers: denses(&d, "layers", &[(ACTION_INPUTS, h), (h, h), (h, 3)])?,
        };
        let networks = Networks {
            config: saved.model,
            training: saved.training,
            task: saved.task,
            taught_queries: saved.taught_queries,
            weights: Weights {
                reasoner,
                subgoal,
                dynamics,
            },
        };
        networks.taught_queries.check()?;
        networks.probe()?;
        Ok(networks)
    }

    /// Checks that every network answers a typical input with finite
    /// numbers (finite weights can still overflow: weights times 1e20),
    /// and the sub-goal planner within [`PROBE_REACH`] of the product
    /// (every weight 1e20 saturates it: finite, kilometres away).
    fn probe(&self) -> Result<(), ModelError> {
        /// The probe's product.
        const FEATURE: [f32; 3] = [0.5, -0.2, 0.025];
        let node = |centre: [f32; 3], selected| Node {
            centre,
            height: 0.05,
            selected,
            goal: [0.0, 0.6, 0.025],
        };
        let graph = Graph {
            nodes: vec![
                node([0.5, -0.2, 0.025], true),
                node([0.62, -0.2, 0.025], false),
                node([0.0, 0.6, 0.2], true),
            ],
            slots: vec![[0.0, 0.6, 0.0], [0.1, 0.6, 0.0]],
            held_goal: [0.0, 0.6, 0.025],
        };
        let r = &self.weights.reasoner;
        let scores = r.scores(&node_rows(&graph));
        let slots = r.slot_scores(&slot_rows(&graph));
        if scores.iter().chain(&slots).any(|v| !v.is_finite()) {
            return Err(ModelError::NonFiniteOutput {
                network: "reasoner",
            });
        }
        for stage in [Stage::Picking, Stage::Placing] {
            for index in 0..3 {
                let g = self.subgoal(&SubGoalQuery {
                    stage,
                    index,
                    feature: FEATURE,
                    tool: [0.5, -0.2, 0.35],
                    height: 0.05,
                    base: [0.0; 3],
                });
                if g.iter().any(|v| !v.is_finite()) {
                    return Err(ModelError::NonFiniteOutput {
                        network: "sub-goal planner",
                    });
                }
                let distance_m = g
                    .iter()
                    .zip(FEATURE)
                    .map(|(a, b)| (f64::from(*a) - f64::from(b)).powi(2))
                    .sum::<f64>()
                    .sqrt();
                if distance_m > PROBE_REACH {
                    return Err(ModelError::SubGoalOutOfReach { distance_m });
                }
            }
        }
        let a = self.action([0.05, -0.02, 0.1], [0.0, -1.5, 1.5]);
        if a.iter().any(|v| !v.is_finite()) {
            return Err(ModelError::NonFiniteOutput {
                network: "dynamics policy",
            });
        }
        Ok(())
    }

    /// The reasoner: which node to pick, or the box and the slot the
    /// pointer chooses for the held product (label = slot + 1).
    pub fn reason(&self, graph: &Graph) -> Choice {
        let r = &self.weights.reasoner;
        let scores = r.scores(&node_rows(graph));
        let best = ReasonerWeights::best(&scores);
        if best < graph.nodes.len() {
            return Choice {
                node: Some(best),
                label: 0,
            };
        }
        Choice {
            node: None,
            label: r.slot(&slot_rows(graph)).map_or(0, |s| s + 1),
        }
    }

    /// The sub-goal planner's mean: the next cup-tip position; a query
    /// beyond those taught is answered as at their edge
    /// ([`TaughtQueries`]).
    pub fn subgoal(&self, query: &SubGoalQuery) -> [f32; 3] {
        let mut x = subgoal_input(query);
        self.taught_queries.clamp(query, &mut x);
        let v = self.weights.subgoal.mean(&x);
        subgoal_position(query, v)
    }

    /// The dynamics policy: base, shoulder and elbow steps (radians) for
    /// `delta` = sub-goal − tool tip at those joints.
    pub fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3] {
        self.weights
            .dynamics
            .action(delta, joints)
            .map(|a| a * ACTION_SCALE)
    }
}

impl Policy for Networks {
    fn reason(&self, graph: &Graph) -> Choice {
        Networks::reason(self, graph)
    }

    fn subgoal(&self, query: &SubGoalQuery) -> [f32; 3] {
        Networks::subgoal(self, query)
    }

    fn sequence(&self) -> SequenceRule {
        self.task.sequence.clone()
    }

    fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3] {
        Networks::action(self, delta, joints)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use safetensors::tensor::TensorView;

    const CONFIG: &[u8] = include_bytes!("../../models/default/config.json");
    const REASONER: &[u8] = include_bytes!("../../models/default/reasoner.safetensors");
    const SUBGOAL: &[u8] = include_bytes!("../../models/default/subgoal.safetensors");
    const DYNAMICS: &[u8] = include_bytes!("../../models/default/dynamics.safetensors");

    /// `bytes` with every value of every tensor passed through `f`.
    fn mapped(bytes: &[u8], f: impl Fn(f32) -> f32) -> Vec<u8> {
        let st = SafeTensors::deserialize(bytes).expect("safetensors");
        let tensors: Vec<(String, Vec<usize>, Vec<u8>)> = st
            .tensors()
            .into_iter()
            .map(|(name, t)| {
                let data = t
                    .data()
                    .chunks_exact(4)
                    .flat_map(|c| f(f32::from_le_bytes([c[0], c[1], c[2], c[3]])).to_le_bytes())
                    .collect();
                (name, t.shape().to_vec(), data)
            })
            .collect();
        let views: Vec<(String, TensorView)> = tensors
            .iter()
            .map(|(n, shape, data)| {
                (
                    n.clone(),
                    TensorView::new(Dtype::F32, shape.clone(), data).expect("view"),
                )
            })
            .collect();
        safetensors::serialize(views, None).expect("serialised")
    }

    #[test]
    fn the_bundled_model_loads() {
        let nets = Networks::from_files(CONFIG, REASONER, SUBGOAL, DYNAMICS).expect("loads");
        // Taught on the repo's line2 cell and 16 generated ones.
        assert_eq!(nets.task.cells.len(), 17);
        assert!(nets.task.cells.iter().any(|c| c == "line2"));
    }

    /// NaN, infinite and overflowing weights are refused at load, naming
    /// the file or the network.
    #[test]
    fn unusable_weights_are_refused() {
        let nan = mapped(SUBGOAL, |_| f32::NAN);
        assert!(matches!(
            Networks::from_files(CONFIG, REASONER, &nan, DYNAMICS),
            Err(ModelError::NotFinite {
                file: "subgoal.safetensors",
                ..
            })
        ));
        let inf = mapped(DYNAMICS, |v| v * f32::INFINITY);
        assert!(matches!(
            Networks::from_files(CONFIG, REASONER, SUBGOAL, &inf),
            Err(ModelError::NotFinite { .. })
        ));
        for scale in [1e20, 1e30] {
            let huge = mapped(SUBGOAL, |v| v * scale);
            assert_eq!(
                Networks::from_files(CONFIG, REASONER, &huge, DYNAMICS).err(),
                Some(ModelError::NonFiniteOutput {
                    network: "sub-goal planner"
                }),
                "scale {scale}"
            );
        }
        // Every weight 1e20 (helper W): tanh saturates, the answer is
        // finite and kilometres away.
        let saturated = mapped(SUBGOAL, |_| 1e20);
        assert!(matches!(
            Networks::from_files(CONFIG, REASONER, &saturated, DYNAMICS),
            Err(ModelError::SubGoalOutOfReach { distance_m }) if distance_m > 1e6
        ));
        let short = &REASONER[..REASONER.len() / 2];
        assert!(matches!(
            Networks::from_files(CONFIG, short, SUBGOAL, DYNAMICS),
            Err(ModelError::NotSafetensors { .. })
        ));
        assert!(matches!(
            Networks::from_files(CONFIG, SUBGOAL, SUBGOAL, DYNAMICS),
            Err(ModelError::Missing { .. })
        ));
    }

    /// `config.json` changed as `edit` says.
    fn config_with(edit: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
        let mut config: serde_json::Value = serde_json::from_slice(CONFIG).expect("json");
        edit(&mut config);
        serde_json::to_vec(&config).expect("serialised")
    }

    /// A model of an older schema is refused as such (it lacks
    /// `taught_queries`, and "train again" says more than the missing
    /// field); taught bounds that are inverted are refused.
    #[test]
    fn an_older_schema_and_inverted_taught_bounds_are_refused() {
        let older = config_with(|c| {
            c["schema"] = "packwright.model/9".into();
            if let Some(c) = c.as_object_mut() {
                c.remove("taught_queries");
            }
        });
        assert!(matches!(
            Networks::from_files(&older, REASONER, SUBGOAL, DYNAMICS),
            Err(ModelError::Schema { found, .. }) if found == "packwright.model/9"
        ));
        let inverted = config_with(|c| c["taught_queries"]["placing"][1]["low"][0] = 1.0.into());
        assert_eq!(
            Networks::from_files(&inverted, REASONER, SUBGOAL, DYNAMICS).err(),
            Some(ModelError::TaughtQueries)
        );
    }

    /// The bundled model answers "above the slot" from a cup tip 0.7 m
    /// farther out than the slot as from the farthest it was taught, and
    /// a taught query as its network does.
    #[test]
    fn the_bundled_model_answers_beyond_its_taught_queries_as_at_their_edge() {
        let nets = Networks::from_files(CONFIG, REASONER, SUBGOAL, DYNAMICS).expect("loads");
        let Some(taught) = nets.taught_queries.placing[1] else {
            panic!("the bundled model was taught \"above the slot\"");
        };
        let query = |out: f32| SubGoalQuery {
            stage: Stage::Placing,
            index: 1,
            feature: [0.5, 0.1, 0.07],
            tool: [0.5 + out, 0.1, 0.2],
            height: 0.04,
            base: [0.0, 0.1, 0.0],
        };
        let edge = taught.high[0];
        assert!(edge > 0.05 && edge < 0.5, "{edge}");
        assert_eq!(nets.subgoal(&query(0.7)), nets.subgoal(&query(edge)));
        let inside = query(edge / 2.0);
        let unclamped =
            subgoal_position(&inside, nets.weights.subgoal.mean(&subgoal_input(&inside)));
        assert_eq!(nets.subgoal(&inside), unclamped);
    }
}
