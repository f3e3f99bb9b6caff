//! `packwright train`: learn the three networks from compiled demonstrations.

use crate::Exit;
use crate::bridge::demonstration_episode;
use crate::cli::TrainArgs;
use crate::fsio::write_dir_atomically;
use crate::learning::{graph_examples, motion_examples, read_json, replay_all};
use anyhow::{Context, bail};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use packwright_compiler::artifact::{LabelsFile, Manifest, WorldFile};
use packwright_compiler::emit::Artifact;
use packwright_runtime::learn::{self, Progress, Task, TrainConfig, TrainingSet};
use packwright_runtime::relabel::ExpertCoach;
use std::collections::BTreeSet;
use std::time::Instant;

fn bar(len: u64, quiet: bool, template: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(
        Some(len),
        if quiet {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        },
    );
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

pub fn run(args: &TrainArgs) -> anyhow::Result<Exit> {
    let manifest: Manifest = read_json(&args.dir.join("manifest.json"))?;
    let world: WorldFile = read_json(&args.dir.join("orders.json"))?;
    let labels_file: LabelsFile = read_json(&args.dir.join("labels.json"))?;
    let graphs_path = args.dir.join("graphs.safetensors");
    let graphs = std::fs::read(&graphs_path)
        .with_context(|| format!("cannot read {}", graphs_path.display()))?;

    // Which demonstrations.
    let known: BTreeSet<&str> = manifest
        .demo_blocks
        .iter()
        .map(|b| b.name.as_str())
        .collect();
    if let Some(unknown) = args.demos.iter().find(|d| !known.contains(d.as_str())) {
        bail!(
            "{} has no demonstration block `{unknown}` (it has: {})",
            args.dir.display(),
            known.iter().copied().collect::<Vec<_>>().join(", ")
        );
    }
    let keep: Vec<bool> = manifest
        .demonstrations
        .iter()
        .map(|d| args.demos.is_empty() || args.demos.contains(&d.block))
        .collect();
    let chosen: Vec<_> = manifest
        .demonstrations
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(d, _)| d)
        .collect();
    if chosen.is_empty() {
        bail!(
            "{} holds no demonstrations to learn from: compile files with `demo` or `demos` blocks",
            args.dir.display()
        );
    }
    let cells: BTreeSet<&str> = chosen.iter().map(|d| d.cell.as_str()).collect();
    if cells.len() > 1 {
        bail!(
            "the demonstrations are in {} cells ({}): a model learns one cell's slots; choose blocks with --demos",
            cells.len(),
            cells.iter().copied().collect::<Vec<_>>().join(", ")
        );
    }
    let cell = chosen[0].cell.clone();
    let cell_labels = labels_file
        .cells
        .iter()
        .find(|c| c.cell == cell)
        .with_context(|| format!("labels.json has no labels for cell `{cell}`"))?;
    let count = cell_labels
        .labels
        .iter()
        .map(|l| l.label as usize + 1)
        .max()
        .unwrap_or(1);
    let mut names = vec![String::new(); count];
    for l in &cell_labels.labels {
        names[l.label as usize] = l.name.clone();
    }
    let blocks: Vec<String> = chosen
        .iter()
        .map(|d| d.block.clone())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();

    // Motion demonstrations.
    let started = Instant::now();
    let replaying = bar(
        chosen.len() as u64,
        args.quiet,
        "replaying demonstrations [{bar:30}] {pos}/{len} {elapsed}",
    );
    let logs = replay_all(&world, &chosen, &|| replaying.inc(1))?;
    replaying.finish_and_clear();
    let replay_s = started.elapsed().as_secs_f64();
    let failed: Vec<usize> = logs
        .iter()
        .enumerate()
        .filter(|(_, l)| l.is_none())
        .map(|(i, _)| i)
        .collect();
    let mut set = TrainingSet {
        graphs: graph_examples(&graphs, &keep)?,
        labels: count,
        ..TrainingSet::default()
    };
    for log in logs.iter().flatten() {
        let (s, a) = motion_examples(log);
        set.subgoals.extend(s);
        set.actions.extend(a);
    }

    // Training.
    let mut config = TrainConfig {
        seed: args.seed,
        ..TrainConfig::default()
    };
    if let Some(e) = args.epochs {
        config.epochs = e.max(1);
        config.dagger_epochs = config.dagger_epochs.min(config.epochs);
    }
    if let Some(r) = args.dagger_rounds {
        config.dagger_rounds = r;
    }
    // DAgger's expert: the policy's rollouts from the demonstrated starts,
    // on this cell's arm.
    let ep = demonstration_episode(&world, chosen[0])?;
    let replayed: Vec<_> = logs.iter().flatten().collect();
    let coach = ExpertCoach::new(&ep.arm, ep.task.cell.base, ep.task.cell.suction, &replayed);
    let bars = MultiProgress::with_draw_target(if args.quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    });
    let template = "{prefix:>9} [{bar:30}] {pos}/{len} {msg}";
    // The dynamics bar runs on through the DAgger rounds.
    let dagger_len = config.dagger_rounds * config.dagger_epochs;
    let named: Vec<(&str, ProgressBar)> =
        [("reasoner", 0), ("sub-goal", 0), ("dynamics", dagger_len)]
            .into_iter()
            .map(|(name, extra)| {
                let b = bars.add(bar((config.epochs + extra) as u64, args.quiet, template));
                b.set_prefix(name);
                (name, b)
            })
            .collect();
    let progress = |p: Progress| {
        let Some((_, b)) = named.iter().find(|(n, _)| *n == p.network) else {
            return;
        };
        let before = match p.round {
            0 => 0,
            r => config.epochs + (r - 1) * config.dagger_epochs,
        };
        b.set_position((before + p.epoch) as u64);
        let metric = match p.network {
            "reasoner" => format!("accuracy {:.3}", p.valid_metric),
            "sub-goal" => format!("error {:.1} mm", p.valid_metric * 1000.0),
            _ => format!("error {:.3} deg", p.valid_metric),
        };
        let round = match p.round {
            0 => String::new(),
            r => format!("DAgger round {r}: "),
        };
        b.set_message(format!(
            "{round}loss {:.4} / held-out {:.4}, {metric}",
            p.train_loss, p.valid_loss
        ));
    };
    let (mut networks, metrics) = learn::train(&set, &config, Some(&coach), &progress)?;
    for (_, b) in &named {
        b.finish();
    }
    networks.task = Task {
        cell: cell.clone(),
        labels: names,
        demos: blocks.clone(),
    };
    let report = serde_json::json!({
        "schema": "packwright.metrics/1",
        "cell": cell,
        "demos": blocks,
        "demonstrations": chosen.len(),
        "replayed": chosen.len() - failed.len(),
        "replay_failures": failed,
        "replay_s": replay_s,
        "samples": {
            "graphs": set.graphs.len(),
            "subgoals": set.subgoals.len(),
            "actions": set.actions.len(),
        },
        "training_s": metrics.seconds,
        "reasoner": metrics.reasoner,
        "subgoal": metrics.subgoal,
        "dynamics": metrics.dynamics,
        "dagger": metrics.dagger,
    });
    let mut artifacts: Vec<Artifact> = networks
        .to_files()?
        .into_iter()
        .map(|(name, bytes)| Artifact { name, bytes })
        .collect();
    artifacts.push(Artifact {
        name: "metrics.json",
        bytes: serde_json::to_vec_pretty(&report)?,
    });
    write_dir_atomically(&args.output, &artifacts, "config.json")?;
    if args.json {
        outln!("{report}");
    } else {
        outln!(
            "wrote {}: {} demonstrations of cell {cell} ({} replayed in {replay_s:.1} s), trained in {:.1} s",
            args.output.display(),
            chosen.len(),
            chosen.len() - failed.len(),
            metrics.seconds
        );
        outln!(
            "  reasoner: held-out accuracy {:.3} ({} samples, best epoch {}/{})",
            metrics.reasoner.valid_metric,
            set.graphs.len(),
            metrics.reasoner.best_epoch,
            metrics.reasoner.epochs_run
        );
        outln!(
            "  sub-goal planner: held-out mean error {:.1} mm ({} samples, best epoch {}/{})",
            metrics.subgoal.valid_metric * 1000.0,
            set.subgoals.len(),
            metrics.subgoal.best_epoch,
            metrics.subgoal.epochs_run
        );
        outln!(
            "  dynamics policy: held-out mean error {:.3} deg ({} samples, best epoch {}/{})",
            metrics.dynamics.valid_metric,
            metrics.dynamics.train_samples + metrics.dynamics.valid_samples,
            metrics.dynamics.best_epoch,
            metrics.dynamics.epochs_run
        );
        for r in &metrics.dagger {
            outln!(
                "  {}: the policy reaches {}/{} demonstrated sub-goals in {} steps{}",
                if r.round == 0 {
                    "before DAgger".to_string()
                } else {
                    format!("after DAgger round {}", r.round)
                },
                r.reached,
                r.rollouts,
                packwright_runtime::execute::MAX_POLICY_STEPS,
                if r.added > 0 {
                    format!(" ({} states labelled and added)", r.added)
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(if failed.is_empty() {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}
