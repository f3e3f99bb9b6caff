//! What a training run learns from: the demonstrations chosen from a
//! compiled directory, their cell's labels, the reasoner's samples, and
//! the expert's replays of them (motion demonstrations).

use crate::artifacts::{graph_examples, read_json};
use crate::episode::{Episode, demonstration_episode};
use crate::error::{PipelineError, Result};
use crate::replay::{motion_examples, replay_all};
use packwright_compiler::artifact::{DemonstrationRecord, LabelsFile, Manifest, WorldFile};
use packwright_interface::record::MotionLog;
use packwright_nets::{Task, TrainingSet};
use std::collections::BTreeSet;
use std::path::Path;
use std::time::Instant;

/// The chosen demonstrations of one compiled directory.
pub struct Lesson {
    world: WorldFile,
    graphs: Vec<u8>,
    /// Per demonstration of `manifest.json`: chosen or not.
    keep: Vec<bool>,
    /// The chosen demonstrations, in manifest order.
    pub chosen: Vec<DemonstrationRecord>,
    /// The cell they are in.
    pub cell: String,
    /// Label names: `pick`, then the cell's slots in label order.
    pub labels: Vec<String>,
    /// The demonstration blocks chosen, sorted.
    pub blocks: Vec<String>,
}

/// The expert's replays of a lesson's demonstrations.
pub struct Replayed {
    /// Per chosen demonstration: its motion log, `None` if the expert
    /// could not complete it.
    pub logs: Vec<Option<MotionLog>>,
    pub seconds: f64,
}

impl Replayed {
    /// Indices (into the chosen demonstrations) of the failed replays.
    pub fn failures(&self) -> Vec<usize> {
        self.logs
            .iter()
            .enumerate()
            .filter(|(_, l)| l.is_none())
            .map(|(i, _)| i)
            .collect()
    }

    pub fn complete(&self) -> Vec<&MotionLog> {
        self.logs.iter().flatten().collect()
    }
}

impl Lesson {
    /// The demonstrations of the blocks `demos` (all when empty) in the
    /// compiled directory `dir`. They must all be in one cell.
    pub fn read(dir: &Path, demos: &[String]) -> Result<Lesson> {
        let manifest: Manifest = read_json(&dir.join("manifest.json"))?;
        let world: WorldFile = read_json(&dir.join("orders.json"))?;
        let labels_file: LabelsFile = read_json(&dir.join("labels.json"))?;
        let graphs_path = dir.join("graphs.safetensors");
        let graphs = std::fs::read(&graphs_path).map_err(|e| PipelineError::Read {
            path: graphs_path,
            reason: e.to_string(),
        })?;
        let known: BTreeSet<&str> = manifest
            .demo_blocks
            .iter()
            .map(|b| b.name.as_str())
            .collect();
        if let Some(unknown) = demos.iter().find(|d| !known.contains(d.as_str())) {
            return Err(PipelineError::NoSuch {
                what: "demonstration block",
                name: unknown.clone(),
                known: format!(
                    "{} has: {}",
                    dir.display(),
                    known.iter().copied().collect::<Vec<_>>().join(", ")
                ),
            });
        }
        let keep: Vec<bool> = manifest
            .demonstrations
            .iter()
            .map(|d| demos.is_empty() || demos.contains(&d.block))
            .collect();
        let chosen: Vec<DemonstrationRecord> = manifest
            .demonstrations
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(d, _)| d.clone())
            .collect();
        let Some(first) = chosen.first() else {
            return Err(PipelineError::Selection(format!(
                "{} holds no demonstrations to learn from: compile files with `demo` or `demos` blocks",
                dir.display()
            )));
        };
        let cells: BTreeSet<&str> = chosen.iter().map(|d| d.cell.as_str()).collect();
        if cells.len() > 1 {
            return Err(PipelineError::Selection(format!(
                "the demonstrations are in {} cells ({}): a model learns one cell's slots; choose blocks with --demos",
                cells.len(),
                cells.iter().copied().collect::<Vec<_>>().join(", ")
            )));
        }
        let cell = first.cell.clone();
        let cell_labels = labels_file
            .cells
            .iter()
            .find(|c| c.cell == cell)
            .ok_or_else(|| PipelineError::Unknown {
                file: "labels.json",
                what: "labels for cell",
                name: cell.clone(),
            })?;
        let count = cell_labels
            .labels
            .iter()
            .map(|l| l.label as usize + 1)
            .max()
            .unwrap_or(1);
        let mut labels = vec![String::new(); count];
        for l in &cell_labels.labels {
            labels[l.label as usize] = l.name.clone();
        }
        let blocks = chosen
            .iter()
            .map(|d| d.block.clone())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        Ok(Lesson {
            world,
            graphs,
            keep,
            chosen,
            cell,
            labels,
            blocks,
        })
    }

    /// Replays the chosen demonstrations with the expert in the simulator
    /// (in parallel); `tick` after each.
    pub fn replay(&self, tick: &(dyn Fn() + Sync)) -> Result<Replayed> {
        let started = Instant::now();
        let demos: Vec<&DemonstrationRecord> = self.chosen.iter().collect();
        let logs = replay_all(&self.world, &demos, tick)?;
        Ok(Replayed {
            logs,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// The three networks' examples: the reasoner's from the compiled
    /// graphs, the others from the completed replays.
    pub fn training_set(&self, replayed: &Replayed) -> Result<TrainingSet> {
        let mut set = TrainingSet {
            graphs: graph_examples(&self.graphs, &self.keep)?,
            labels: self.labels.len(),
            ..TrainingSet::default()
        };
        for log in replayed.complete() {
            let (s, a) = motion_examples(log);
            set.subgoals.extend(s);
            set.actions.extend(a);
        }
        Ok(set)
    }

    /// The episode of the first chosen demonstration (its arm and cell).
    pub fn first_episode(&self) -> Result<Episode> {
        demonstration_episode(&self.world, &self.chosen[0])
    }

    /// What a model trained on this lesson was taught.
    pub fn task(&self) -> Task {
        Task {
            cell: self.cell.clone(),
            labels: self.labels.clone(),
            demos: self.blocks.clone(),
        }
    }
}
