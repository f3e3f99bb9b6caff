//! `packwright execute`: pack an order in the simulator, or on a real
//! UR10 (`--robot`, `--dry-run`).

use crate::Exit;
use crate::cli::ExecuteArgs;
use crate::commands::draw::write_executed_svg;
use crate::fsio::FsLoader;
use packwright_interface::outcome::{Outcome, PlannerKind, Report};
use packwright_interface::{Graph, Policy, SequenceRule};
use packwright_motion::execute::{self, Planner};
use packwright_nets::Networks;
use packwright_nets::features::{node_rows, slot_rows};
use packwright_pipeline::episode::{Episode, episode, find_setup};
use packwright_pipeline::models::{
    CellRule, baseline_rule, choose_planner, follow_cell_rule, taught,
};
use packwright_pipeline::reach::RobotWorkspace;
use packwright_pipeline::robot::{self, Products};
use packwright_recording::{Journal, JournalPolicy, JournalWorld, Run, Scores};
use packwright_ur::RobotAddress;
use std::path::Path;

/// The report as JSON, with the task's name.
pub fn to_json(name: &str, r: &Report) -> serde_json::Value {
    let mut value = serde_json::to_value(r).unwrap_or_default();
    if let Some(obj) = value.as_object_mut() {
        obj.insert("task".into(), name.into());
    }
    value
}

/// Why `--record` is refused in a build without Rerun, and how to get it.
const NO_RERUN: &str = "--record needs Rerun, which this build leaves out: rebuild with \
`--features rerun` (cargo build --release --features rerun, or cargo install --path . \
--features rerun)";

/// `--record` in a build without Rerun: refused (exit 2) before anything
/// runs.
pub fn can_record(record: Option<&Path>) -> anyhow::Result<()> {
    if record.is_some() && !packwright_recording::ENABLED {
        anyhow::bail!(NO_RERUN);
    }
    Ok(())
}

/// Writes `runs` as one .rrd file (atomically), one recording each.
#[cfg(feature = "rerun")]
pub fn write_recording(path: &Path, runs: &[Run]) -> anyhow::Result<()> {
    let bytes = packwright_recording::rrd(runs)?;
    crate::fsio::write_file_atomically(path, &bytes)
}

#[cfg(not(feature = "rerun"))]
pub fn write_recording(_path: &Path, _runs: &[Run]) -> anyhow::Result<()> {
    anyhow::bail!(NO_RERUN)
}

/// The reasoner's own scores of a graph, as recordings show them.
pub fn scores(nets: &Networks, graph: &Graph) -> Scores {
    let r = &nets.weights().reasoner;
    Scores {
        nodes: r.scores(&node_rows(graph)),
        slots: r.slot_scores(&slot_rows(graph)),
    }
}

pub fn run(args: &ExecuteArgs) -> anyhow::Result<Exit> {
    can_record(args.record.as_deref())?;
    let compiled = match packwright_compiler::check(&FsLoader, &args.files, &RobotWorkspace::new())
    {
        Ok(c) => c,
        Err(failed) => return Ok(super::report_failure(&failed, false)),
    };
    super::report_warnings(&compiled.sources, &compiled.warnings, false);
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
    let (kind, mut model) = choose_planner(args.planner, args.model.as_deref())?;
    if let Some(nets) = &mut model {
        if !taught(nets, &ep.task.cell.name) {
            errln!(
                "note: the model was not taught cell `{}` ({}): it answers from this cell's geometry (see README, \"Learning\")",
                ep.task.cell.name,
                taught_cells(&nets.task.cells)
            );
        }
        let rule = follow_cell_rule(nets, &compiled, &ep.task.cell.name);
        note_cell_rule(&ep.task.cell.name, &rule, &nets.task.sequence);
    }
    // With --record, the policy's decisions are journalled too.
    let journal = Journal::new();
    let journalled = match (&model, &args.record) {
        (Some(nets), Some(_)) => Some(JournalPolicy::new(nets, &journal, &ep.task)),
        _ => None,
    };
    let policy: Option<&dyn Policy> = match (&journalled, &model) {
        (Some(p), _) => Some(p),
        (None, Some(nets)) => Some(nets),
        (None, None) => None,
    };
    let planner = match (policy, kind) {
        (Some(policy), _) => Planner::Learned {
            policy,
            seed: args.seed,
        },
        (None, PlannerKind::Rrt) => Planner::Rrt { seed: args.seed },
        (None, _) => Planner::Expert,
    };
    // The expert and RRT-Connect pack in the order the file's
    // demonstrations of the cell teach (the learned planner's reasoner
    // follows its own rule).
    let sequence = baseline_rule(model.as_ref(), &compiled, &ep.task.cell.name);
    if let Some(address) = address {
        if args.svg.is_some() {
            anyhow::bail!("--svg draws simulated runs only (no --robot)");
        }
        if args.record.is_some() {
            anyhow::bail!("--record records simulated runs only (no --robot)");
        }
        return on_robot(args, &address, &name, &ep, (&planner, &sequence));
    }
    let mut sim = ep.simulator(ep.home()?)?;
    // The journal records what `--svg` draws and `--record` writes.
    let report = execute::run_in_order(
        &mut JournalWorld::new(&mut sim, &journal),
        &ep.arm,
        &ep.task,
        &planner,
        &sequence,
    );
    let entries = journal.take();
    // The run's report first: a picture or recording that cannot be
    // written (a full disk, `--svg` naming a directory) loses nothing of
    // it, and exits 2 after it.
    let exit = print_outcome(args, &name, &report, "simulated")?;
    if let Some(path) = &args.svg {
        write_executed_svg(
            path,
            &compiled.model,
            &name,
            &setup,
            &ep.arm,
            &entries.cycles,
            &report,
        )
        .map_err(crate::AfterReport)?;
    }
    if let Some(path) = &args.record {
        let title = format!("{name} ({})", report.planner);
        let score = |g: &Graph| {
            model
                .as_ref()
                .map(|nets| scores(nets, g))
                .unwrap_or_default()
        };
        let run = Run {
            name: &title,
            arm: &ep.arm,
            task: &ep.task,
            entries: &entries,
            report: &report,
            scorer: model
                .as_ref()
                .map(|_| &score as packwright_recording::Scorer),
        };
        write_recording(path, &[run]).map_err(crate::AfterReport)?;
        errln!("wrote {}", path.display());
    }
    Ok(exit)
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
    (planner, sequence): (&Planner, &SequenceRule),
) -> anyhow::Result<Exit> {
    if args.dry_run {
        let d = robot::dry_run(ep, address, planner, sequence)?;
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
        world.controller().frequency()
    );
    let report = execute::run_in_order(&mut world, &ep.arm, &ep.task, planner, sequence);
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
        "{:>4} {:<12} {:<8} {:>11} {:>11} {:>9} {:>10}  outcome",
        "turn",
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
        let turn = p.turn.map_or("-".into(), |t| t.to_string());
        outln!(
            "{:>4} {:<12} {:<8} {:>11} {:>11} {:>9} {:>10}  {}",
            turn,
            p.product,
            p.slot,
            planning,
            exec,
            bound,
            error,
            p.outcome_text()
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
        outln!(
            "learned planner: {} to RRT-Connect, {}",
            super::counted(report.fallbacks.len(), "fallback", "fallbacks"),
            super::counted(report.violations.len(), "violation", "violations"),
        );
        for f in &report.fallbacks {
            outln!("  fallback: {f}");
        }
        for v in &report.violations {
            outln!("  the reasoner {v}: the arm stopped");
        }
    }
}

/// Says on stderr which order a model packs an untaught cell in, when
/// that cell's own demonstrations decided it ([`follow_cell_rule`]).
pub fn note_cell_rule(cell: &str, what: &CellRule, model_rule: &SequenceRule) {
    match what {
        CellRule::Taught(_) => {}
        CellRule::Undemonstrated => errln!(
            "note: no demonstration in the files orders cell `{cell}`: the learned planner packs it in the model's own order, {model_rule}"
        ),
        CellRule::Same(rule) => errln!(
            "note: the file's demonstrations of cell `{cell}` follow the order {rule}, the model's own: the learned planner packs it so"
        ),
        CellRule::Followed(rule) => errln!(
            "note: the file's demonstrations of cell `{cell}` follow the order {rule}: the learned planner packs it so"
        ),
        CellRule::NoRule => errln!(
            "note: the file's demonstrations of cell `{cell}` follow no one order: the model's own, {model_rule}, is kept"
        ),
    }
}

/// The cells a model was taught, for a note: all of them when few, else
/// the first three and how many more.
fn taught_cells(cells: &[String]) -> String {
    match cells {
        [] => "its config.json names no cell it was taught".to_owned(),
        [one] => format!("it was taught `{one}`"),
        _ if cells.len() <= 4 => format!("it was taught {}", cells.join(", ")),
        _ => format!(
            "it was taught {} cells: {} and {} more",
            cells.len(),
            cells[..3].join(", "),
            cells.len() - 3
        ),
    }
}
