//! `packwright execute`: pack an order in the simulator.

use crate::Exit;
use crate::bridge::{episode, find_setup};
use crate::cli::{ExecuteArgs, PlannerArg};
use crate::fsio::FsLoader;
use crate::learning::{default_model, load_model};
use anyhow::{Context, bail};
use packwright_compiler::expand::Setup;
use packwright_runtime::execute::{self, Outcome, PlannerKind, Report};
use packwright_runtime::learn::Networks;
use packwright_runtime::sim::Simulator;
use std::path::Path;

fn outcome(o: &Outcome) -> String {
    match o {
        Outcome::Packed => "packed".into(),
        Outcome::AlreadyPacked => "already packed".into(),
        Outcome::Waiting => "waiting (missing)".into(),
        Outcome::Failed(why) => format!("failed: {why}"),
        Outcome::NotAttempted => "not attempted".into(),
    }
}

pub fn to_json(name: &str, r: &Report) -> serde_json::Value {
    serde_json::json!({
        "task": name,
        "planner": r.planner,
        "complete": r.complete,
        "simulated_s": r.time_s,
        "collisions": r.collisions,
        "fallbacks": r.fallbacks.iter().map(ToString::to_string).collect::<Vec<_>>(),
        "violations": r.violations,
        "products": r.products.iter().map(|p| serde_json::json!({
            "product": p.product,
            "slot": p.slot,
            "planning_ms": p.planning_s * 1000.0,
            "execution_s": p.execution_s,
            "error_m": p.error_m,
            "outcome": match &p.outcome {
                Outcome::Packed => "packed",
                Outcome::AlreadyPacked => "already_packed",
                Outcome::Waiting => "waiting",
                Outcome::Failed(_) => "failed",
                Outcome::NotAttempted => "not_attempted",
            },
            "reason": match &p.outcome { Outcome::Failed(w) => Some(w.as_str()), _ => None },
        })).collect::<Vec<_>>(),
    })
}

/// The name of the cell a setup packs in.
pub fn cell_of(compiled: &packwright_compiler::Compiled, setup: &Setup) -> String {
    let m = &compiled.model;
    m.inventories
        .get(setup.inventory)
        .and_then(|inv| m.cells.get(inv.cell))
        .map(|c| c.name.clone())
        .unwrap_or_default()
}

/// The planner to use and, for `learned`, its networks: `--model`, or the
/// bundled model when it was trained on `cell`.
pub fn choose_planner(
    asked: Option<PlannerArg>,
    model: Option<&Path>,
    cell: &str,
) -> anyhow::Result<(PlannerArg, Option<Networks>)> {
    let nets = match (asked, model) {
        (Some(PlannerArg::Expert | PlannerArg::Rrt), _) => None,
        (_, Some(dir)) => Some(load_model(dir)?),
        (Some(PlannerArg::Learned), None) => Some(default_model()?),
        (None, None) => default_model().ok().filter(|n| n.task.cell == cell),
    };
    if let Some(n) = &nets
        && n.task.cell != cell
    {
        bail!(
            "the model was trained on cell `{}`, this order packs in cell `{cell}`: train a model on its demonstrations (`packwright train`)",
            n.task.cell
        );
    }
    let planner = match (asked, &nets) {
        (Some(p), _) => p,
        (None, Some(_)) => PlannerArg::Learned,
        (None, None) => PlannerArg::Expert,
    };
    Ok((planner, nets))
}

pub fn run(args: &ExecuteArgs) -> anyhow::Result<Exit> {
    let compiled = match packwright_compiler::check(&FsLoader, &args.files) {
        Ok(c) => c,
        Err(failed) => return Ok(super::report_failure(&failed, false)),
    };
    let (name, setup) = find_setup(&compiled, args.order.as_deref(), args.scenario.as_deref())?;
    let ep = episode(&compiled.model, &setup)?;
    let cell = &ep.task.cell;
    let start = execute::home(&ep.arm, cell)
        .context("the arm cannot reach a start pose over the pending area")?;
    let mut sim = Simulator::new(ep.arm.clone(), cell, &ep.placements, start)?;
    let cell_name = cell_of(&compiled, &setup);
    let (planner, model) = choose_planner(args.planner, args.model.as_deref(), &cell_name)?;
    let report = match (&model, planner) {
        (Some(nets), _) => execute::run_learned(&mut sim, &ep.arm, &ep.task, nets, args.seed),
        (None, PlannerArg::Rrt) => execute::run(
            &mut sim,
            &ep.arm,
            &ep.task,
            PlannerKind::Rrt { seed: args.seed },
        ),
        (None, _) => execute::run(&mut sim, &ep.arm, &ep.task, PlannerKind::Expert),
    };
    if args.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&to_json(&name, &report))?
        );
    } else {
        outln!("{name}: planner {}", report.planner);
        outln!(
            "{:<12} {:<8} {:>11} {:>11} {:>10}  outcome",
            "product",
            "slot",
            "planning",
            "execution",
            "error"
        );
        for p in &report.products {
            let error = p
                .error_m
                .map_or("-".into(), |e| format!("{:.1} mm", e * 1000.0));
            let planning = if p.execution_s > 0.0 {
                format!("{:.1} ms", p.planning_s * 1000.0)
            } else {
                "-".into()
            };
            let exec = if p.execution_s > 0.0 {
                format!("{:.2} s", p.execution_s)
            } else {
                "-".into()
            };
            outln!(
                "{:<12} {:<8} {:>11} {:>11} {:>10}  {}",
                p.product,
                p.slot,
                planning,
                exec,
                error,
                outcome(&p.outcome)
            );
        }
        let count =
            |f: fn(&Outcome) -> bool| report.products.iter().filter(|p| f(&p.outcome)).count();
        outln!(
            "{}: {} packed, {} already packed, {} waiting, {} failed; {:.2} s simulated",
            if report.complete {
                "package complete"
            } else {
                "package NOT complete"
            },
            count(|o| *o == Outcome::Packed),
            count(|o| *o == Outcome::AlreadyPacked),
            count(|o| *o == Outcome::Waiting),
            count(|o| matches!(o, Outcome::Failed(_))),
            report.time_s
        );
        if report.planner == "learned" {
            outln!(
                "learned planner: {} fallback{} to RRT-Connect, {} violation{}",
                report.fallbacks.len(),
                if report.fallbacks.len() == 1 { "" } else { "s" },
                report.violations.len(),
                if report.violations.len() == 1 {
                    ""
                } else {
                    "s"
                },
            );
            for f in &report.fallbacks {
                outln!("  fallback: {f}");
            }
            for v in &report.violations {
                outln!("  the reasoner {v}: the arm stopped");
            }
        }
    }
    Ok(if report.complete {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}
