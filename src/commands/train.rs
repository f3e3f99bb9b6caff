//! `packwright train`: learn the three networks from compiled
//! demonstrations (the lesson is `packwright_pipeline::teach`, the run
//! `packwright_train::job`).

use crate::Exit;
use crate::cli::TrainArgs;
use crate::fsio::{check_replaceable, write_dir_atomically};
use anyhow::bail;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use packwright_compiler::emit::Artifact;
use packwright_motion::execute::MAX_POLICY_STEPS;
use packwright_nets::TrainConfig;
use packwright_pipeline::teach::Lesson;
use packwright_train::{Network, Progress, job};

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

/// What `train` writes into its output directory.
fn model_files() -> Vec<&'static str> {
    let mut names = packwright_nets::FILES.to_vec();
    names.push(METRICS);
    names
}

/// The training report beside the weights.
const METRICS: &str = "metrics.json";

pub fn run(args: &TrainArgs) -> anyhow::Result<Exit> {
    let lesson = Lesson::read(&args.dir, &args.demos)?;
    // Before the replay and the training: an output that would be
    // refused is said at once, not after minutes of work.
    check_replaceable(&args.output, packwright_nets::FILES[0], &model_files())?;
    let replaying = bar(
        (lesson.chosen.len() + lesson.rehearsals.len()) as u64,
        args.quiet,
        "replaying demonstrations [{bar:30}] {pos}/{len} {elapsed}",
    );
    let replayed = lesson.replay(&|| replaying.inc(1))?;
    replaying.finish_and_clear();
    // Not one demonstration replayed: nothing to learn from. Each is
    // named, as when only some were not, before the command stops.
    let failed = replayed.failures().len();
    if failed > 0 && failed == lesson.chosen.len() {
        for p in replayed.problems.iter().filter(|p| !p.rehearsal) {
            errln!("error: {p}");
        }
        bail!(
            "the expert could not replay any of the {failed} demonstrations (each named in its own `error:` line), so there is nothing to learn from and no model was written: `packwright check` the file, and `packwright demonstrate` shows each run"
        );
    }

    let mut config = TrainConfig {
        seed: args.seed,
        ..TrainConfig::default()
    };
    if let Some(e) = args.epochs {
        config.epochs = e;
        config.dagger_epochs = config.dagger_epochs.min(config.epochs);
    }
    if let Some(r) = args.dagger_rounds {
        config.dagger_rounds = r;
    }
    let bars = MultiProgress::with_draw_target(if args.quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    });
    let template = "{prefix:>9} [{bar:30}] {pos}/{len} {msg}";
    // The dynamics bar runs on through the DAgger rounds.
    let dagger_len = config.dagger_rounds * config.dagger_epochs;
    let named: Vec<(Network, ProgressBar)> = [
        (Network::Reasoner, 0),
        (Network::SubGoal, 0),
        (Network::Dynamics, dagger_len),
    ]
    .into_iter()
    .map(|(network, extra)| {
        let b = bars.add(bar((config.epochs + extra) as u64, args.quiet, template));
        b.set_prefix(network.to_string());
        (network, b)
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
        let position = (before + p.epoch) as u64;
        if b.length().is_some_and(|l| position > l) {
            b.set_length(position);
        }
        b.set_position(position);
        let metric = match p.network {
            Network::Reasoner => format!("accuracy {:.3}", p.valid_metric),
            Network::SubGoal => format!("error {:.1} mm", p.valid_metric * 1000.0),
            Network::Dynamics => format!("error {:.3} deg", p.valid_metric),
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
    let (trained, report) = job::run(&lesson, &replayed, &config, &progress)?;
    for (_, b) in &named {
        b.finish();
    }
    let mut artifacts: Vec<Artifact> = trained
        .to_files()?
        .into_iter()
        .map(|(name, bytes)| Artifact { name, bytes })
        .collect();
    let metrics_json = serde_json::to_vec_pretty(&report)?;
    artifacts.push(Artifact {
        name: METRICS,
        bytes: metrics_json,
    });
    write_dir_atomically(&args.output, &artifacts, packwright_nets::FILES[0])?;
    if args.json {
        outln!("{}", serde_json::to_string(&report)?);
    } else {
        outln!(
            "wrote {}: {} demonstration{} of {} {} ({} replayed in {:.1} s), trained in {:.1} s",
            args.output.display(),
            report.demonstrations,
            if report.demonstrations == 1 { "" } else { "s" },
            if report.cells.len() == 1 {
                "cell"
            } else {
                "cells"
            },
            report.cells.join(", "),
            report.replayed,
            report.replay_s,
            report.training_s
        );
        outln!("  sequence rule taught: {}", report.sequence);
        for (cell, rule) in &report.cell_rules {
            outln!("    in cell `{cell}`: {rule} (its own demonstrations' order)");
        }
        if report.any_order > 0 {
            outln!(
                "  any order: {} of {} demonstrations come from blocks with `sequence random`; taught in the rule's order{}",
                report.any_order,
                report.demonstrations,
                if report.any_order == report.demonstrations {
                    " (the inventory's: no demonstration shows an order)"
                } else {
                    ", inferred from the others"
                }
            );
        }
        if report.rehearsals > 0 {
            outln!(
                "  rehearsed by the expert: {} of {} orders of the products and slots no demonstration moved (motion examples only)",
                report.rehearsed,
                report.rehearsals
            );
        }
        outln!(
            "  reasoner: {} accuracy {:.3} ({} samples, best epoch {}/{})",
            report.reasoner.figures_on(),
            report.reasoner.valid_metric,
            report.samples.graphs,
            report.reasoner.best_epoch,
            report.reasoner.epochs_run
        );
        outln!(
            "  sub-goal planner: {} mean error {:.1} mm ({} samples, best epoch {}/{})",
            report.subgoal.figures_on(),
            report.subgoal.valid_metric * 1000.0,
            report.samples.subgoals,
            report.subgoal.best_epoch,
            report.subgoal.epochs_run
        );
        outln!(
            "  dynamics policy: {} mean error {:.3} deg ({} samples, best epoch {}/{})",
            report.dynamics.figures_on(),
            report.dynamics.valid_metric,
            report.dynamics.train_samples + report.dynamics.valid_samples,
            report.dynamics.best_epoch,
            report.dynamics.epochs_run
        );
        for r in &report.dagger {
            outln!(
                "  {}: the policy reaches {}/{} demonstrated sub-goals in {MAX_POLICY_STEPS} steps{}",
                if r.round == 0 {
                    "before DAgger".to_string()
                } else {
                    format!("after DAgger round {}", r.round)
                },
                r.reached,
                r.rollouts,
                if r.added > 0 {
                    format!(" ({} states labelled and added)", r.added)
                } else {
                    String::new()
                }
            );
        }
    }
    for w in &report.warnings {
        errln!("warning: {w}");
    }
    // A demonstration not replayed leaves its motion out of the model
    // (exit 1); a rehearsal not completed only teaches less.
    for p in &report.replay_problems {
        errln!("{}: {p}", if p.rehearsal { "warning" } else { "error" });
    }
    Ok(if report.replay_failures.is_empty() {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}
