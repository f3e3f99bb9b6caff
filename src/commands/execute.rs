//! `packwright execute`: pack an order in the simulator.

use crate::Exit;
use crate::cli::ExecuteArgs;
use crate::fsio::FsLoader;
use packwright_interface::outcome::{Outcome, PlannerKind, Report};
use packwright_motion::execute::{self, Planner};
use packwright_pipeline::episode::{episode, find_setup};
use packwright_pipeline::models::{choose_planner, taught};
use packwright_pipeline::reach::RobotWorkspace;

/// The report as JSON, with the task's name.
pub fn to_json(name: &str, r: &Report) -> serde_json::Value {
    let mut value = serde_json::to_value(r).unwrap_or_default();
    if let Some(obj) = value.as_object_mut() {
        obj.insert("task".into(), name.into());
    }
    value
}

pub fn run(args: &ExecuteArgs) -> anyhow::Result<Exit> {
    let compiled = match packwright_compiler::check(&FsLoader, &args.files, &RobotWorkspace::new())
    {
        Ok(c) => c,
        Err(failed) => return Ok(super::report_failure(&failed, false)),
    };
    let (name, setup) = find_setup(&compiled, args.order.as_deref(), args.scenario.as_deref())?;
    let ep = episode(&compiled.model, &setup)?;
    let mut sim = ep.simulator(ep.home()?)?;
    let (kind, model) = choose_planner(args.planner, args.model.as_deref(), &ep.task.cell.name)?;
    if let Some(nets) = &model
        && !taught(nets, &ep.task.cell.name)
    {
        errln!(
            "note: the model was taught cell(s) {}, not `{}`: it answers from this cell's geometry (see README, \"Learning\")",
            nets.task.cells.join(", "),
            ep.task.cell.name
        );
    }
    let planner = match (&model, kind) {
        (Some(nets), _) => Planner::Learned {
            policy: nets,
            seed: args.seed,
        },
        (None, PlannerKind::Rrt) => Planner::Rrt { seed: args.seed },
        (None, _) => Planner::Expert,
    };
    let report = execute::run(&mut sim, &ep.arm, &ep.task, &planner);
    if args.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&to_json(&name, &report))?
        );
    } else {
        print_report(&name, &report);
    }
    Ok(if report.complete {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}

fn print_report(name: &str, report: &Report) {
    outln!("{name}: planner {}", report.planner);
    outln!(
        "{:<12} {:<8} {:>11} {:>11} {:>9} {:>10}  outcome",
        "product",
        "slot",
        "planning",
        "execution",
        "bound",
        "error"
    );
    for p in &report.products {
        let error = p
            .error_m
            .map_or("-".into(), |e| format!("{:.1} mm", e * 1000.0));
        let (planning, exec, bound) = if p.execution_s > 0.0 {
            (
                format!("{:.1} ms", p.planning_s * 1000.0),
                format!("{:.2} s", p.execution_s),
                format!("{:.2} s", p.bound_s),
            )
        } else {
            ("-".into(), "-".into(), "-".into())
        };
        outln!(
            "{:<12} {:<8} {:>11} {:>11} {:>9} {:>10}  {}",
            p.product,
            p.slot,
            planning,
            exec,
            bound,
            error,
            p.outcome
        );
    }
    let count = |f: fn(&Outcome) -> bool| report.products.iter().filter(|p| f(&p.outcome)).count();
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
    if report.planner == PlannerKind::Learned {
        let plural = |n: usize| if n == 1 { "" } else { "s" };
        outln!(
            "learned planner: {} fallback{} to RRT-Connect, {} violation{}",
            report.fallbacks.len(),
            plural(report.fallbacks.len()),
            report.violations.len(),
            plural(report.violations.len()),
        );
        for f in &report.fallbacks {
            outln!("  fallback: {f}");
        }
        for v in &report.violations {
            outln!("  the reasoner {v}: the arm stopped");
        }
    }
}
