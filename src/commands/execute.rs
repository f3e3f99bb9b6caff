//! `packwright execute`: pack an order in the simulator, or on a real
//! UR10 (`--robot`, `--dry-run`).

use crate::Exit;
use crate::cli::ExecuteArgs;
use crate::commands::draw::{Recorder, write_executed_svg};
use crate::fsio::FsLoader;
use packwright_interface::outcome::{Outcome, PlannerKind, Report};
use packwright_interface::world::World;
use packwright_motion::execute::{self, Planner};
use packwright_pipeline::episode::{Episode, episode, find_setup};
use packwright_pipeline::models::{choose_planner, taught};
use packwright_pipeline::reach::RobotWorkspace;
use packwright_pipeline::robot::{self, Products};
use packwright_ur::RobotAddress;

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
    // A bad robot address is bad input, found before anything else.
    // `sim` (the specification's spelling of the default) is the simulator.
    let address = match args.robot.as_deref() {
        None | Some("sim") => None,
        Some(url) => Some(RobotAddress::parse(url)?),
    };
    if args.dry_run && address.is_none() {
        anyhow::bail!("--dry-run needs a real robot: --robot ur10://HOST");
    }
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
    if let Some(address) = address {
        if args.svg.is_some() {
            anyhow::bail!("--svg draws simulated runs only (no --robot)");
        }
        return on_robot(args, &address, &name, &ep, &planner);
    }
    let mut sim = ep.simulator(ep.home()?)?;
    let mut recorder = Recorder::new(&mut sim);
    let report = execute::run(&mut recorder, &ep.arm, &ep.task, &planner);
    if let Some(path) = &args.svg {
        let cycles = &recorder.cycles;
        write_executed_svg(
            path,
            &compiled.model,
            &name,
            &setup,
            &ep.arm,
            cycles,
            &report,
        )?;
    }
    print_outcome(args, &name, &report, "simulated")
}

/// Prints the report and picks the exit code.
fn print_outcome(
    args: &ExecuteArgs,
    name: &str,
    report: &Report,
    clock: &str,
) -> anyhow::Result<Exit> {
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&to_json(name, report))?);
    } else {
        print_report(name, report, clock);
    }
    Ok(if report.complete {
        Exit::Success
    } else {
        Exit::Diagnostics
    })
}

/// `--robot`: the package on the real UR10 (or, with `--dry-run`, planned
/// from its measured joints with nothing moving). Connection problems are
/// errors (exit 2); a stop during the run stops the arm, names the reason
/// and exits 1.
fn on_robot(
    args: &ExecuteArgs,
    address: &RobotAddress,
    name: &str,
    ep: &Episode,
    planner: &Planner,
) -> anyhow::Result<Exit> {
    if args.dry_run {
        let d = robot::dry_run(ep, address, planner)?;
        let verdict = match &d.first {
            Some((_, Ok(()))) => "ok".to_string(),
            Some((_, Err(problem))) => problem.to_string(),
            None => "no command".to_string(),
        };
        if args.json {
            let mut value = to_json(name, &d.report);
            if let Some(obj) = value.as_object_mut() {
                obj.insert("dry_run".into(), true.into());
                obj.insert("robot".into(), address.to_string().into());
                obj.insert("controller".into(), d.controller.to_string().into());
                obj.insert("measured".into(), d.state.actual_q.to_vec().into());
                obj.insert("commands".into(), d.commands.into());
                obj.insert("first_command".into(), verdict.clone().into());
            }
            outln!("{}", serde_json::to_string_pretty(&value)?);
        } else {
            outln!(
                "dry run on {address} (controller {}, {:.0} Hz): nothing moved",
                d.controller,
                d.controller.frequency()
            );
            let q = d.state.actual_q.map(|v| format!("{v:.4}")).join(", ");
            outln!("measured joints: [{q}] rad");
            outln!(
                "first command against the measured joints: {verdict}; {} commands planned",
                d.commands
            );
            print_report(name, &d.report, "simulated from the measured joints");
        }
        let first_ok = !matches!(d.first, Some((_, Err(_))));
        if !first_ok {
            errln!("error: the first command would be refused: {verdict}");
        }
        return Ok(if first_ok && d.report.complete {
            Exit::Success
        } else {
            Exit::Diagnostics
        });
    }
    let products = match &args.products_feed {
        Some(at) => Products::Feed(at.clone()),
        None => Products::Nominal,
    };
    let mut world = robot::connect(ep, address, &products)?;
    errln!(
        "connected to {address} (controller {}, {:.0} Hz); streaming",
        world.controller(),
        1.0 / world.control_period()
    );
    let report = execute::run(&mut world, &ep.arm, &ep.task, planner);
    let fault = world.close();
    let exit = print_outcome(args, name, &report, "on the robot")?;
    if let Some(f) = fault {
        errln!("the robot stopped: {f}");
        return Ok(Exit::Diagnostics);
    }
    Ok(exit)
}

fn print_report(name: &str, report: &Report, clock: &str) {
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
        "{}: {} packed, {} already packed, {} waiting, {} failed; {:.2} s {clock}",
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
