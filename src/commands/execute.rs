//! `packwright execute`: pack an order in the simulator.

use crate::Exit;
use crate::bridge::{episode, find_setup};
use crate::cli::{ExecuteArgs, PlannerArg};
use crate::fsio::FsLoader;
use anyhow::Context;
use packwright_runtime::execute::{self, Outcome, PlannerKind, Report};
use packwright_runtime::sim::Simulator;

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
    let planner = match args.planner {
        PlannerArg::Expert => PlannerKind::Expert,
        PlannerArg::Rrt => PlannerKind::Rrt { seed: args.seed },
    };
    let report = execute::run(&mut sim, &ep.arm, &ep.task, planner);
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
    }
    Ok(if report.complete {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}
