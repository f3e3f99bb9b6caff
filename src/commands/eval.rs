//! `packwright eval`: success rates and planning times over scenario suites
//! (the rows and their statistics are `packwright_pipeline::evaluate`).

use crate::Exit;
use crate::cli::EvalArgs;
use crate::fsio::{FsLoader, write_file_atomically};
use anyhow::bail;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use packwright_compiler::Compiled;
use packwright_compiler::expand::Setup;
use packwright_interface::{PlannerKind, Policy, SequenceRule};
use packwright_motion::execute::{self, Planner};
use packwright_nets::Networks;
use packwright_pipeline::episode::{cell_of, episode};
use packwright_pipeline::evaluate::{CaseResult, Row, Run, markdown, run_case};
use packwright_pipeline::models::{
    CellRule, baseline_rule, choose_planner, follow_cell_rule, taught,
};
use packwright_pipeline::reach::RobotWorkspace;
use packwright_recording::{Journal, JournalPolicy, JournalWorld};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The schema of `eval --json`, which `chart` reads back.
pub const SCHEMA: &str = "packwright.eval/3";

/// The schema before it, which `chart` still reads: the same rows, and a
/// list of suites measured without the learned planner (always empty
/// now: a model that cannot be used is refused).
pub const PREVIOUS_SCHEMA: &str = "packwright.eval/2";

/// The machine the figures were measured on.
#[derive(Debug, Serialize)]
struct Machine {
    cpus: usize,
    os: &'static str,
    arch: &'static str,
}

/// `eval --json` (schema [`SCHEMA`]).
#[derive(Debug, Serialize)]
struct EvalReport<'a> {
    schema: &'static str,
    seed: u64,
    machine: Machine,
    rows: &'a [Row],
    /// With more than one suite, one row per planner over every scenario
    /// of the run (suite `all suites`, cell `-`): the pooled success rates,
    /// planning times and execution times.
    totals: &'a [Row],
}

/// The suite name of the pooled rows ([`EvalReport::totals`]).
const ALL_SUITES: &str = "all suites";

pub fn run(args: &EvalArgs) -> anyhow::Result<Exit> {
    super::execute::can_record(args.record.as_deref())?;
    let compiled = match packwright_compiler::check(&FsLoader, &args.files, &RobotWorkspace::new())
    {
        Ok(c) => c,
        Err(failed) => return Ok(super::report_failure(&failed, args.json)),
    };
    super::report_warnings(&compiled.sources, &compiled.warnings, false);
    let suites: Vec<_> = compiled
        .expanded
        .suites
        .iter()
        .filter(|s| args.suites.is_empty() || args.suites.contains(&s.name))
        .collect();
    if let Some(missing) = args
        .suites
        .iter()
        .find(|n| !compiled.expanded.suites.iter().any(|s| &s.name == *n))
    {
        let known: Vec<&str> = compiled
            .expanded
            .suites
            .iter()
            .map(|s| s.name.as_str())
            .collect();
        bail!(
            "no suite `{missing}`; the files define: {}",
            known.join(", ")
        );
    }
    if suites.is_empty() {
        bail!("the files define no `scenarios` suite to evaluate");
    }
    let mut rows = Vec::new();
    // The order each cell's own demonstrations teach a model that was not
    // taught the cell, or the one the model was taught there
    // (`follow_cell_rule`).
    let mut cell_rules = std::collections::BTreeMap::new();
    let mut all_results = Vec::new();
    // Loaded once. A model that cannot be used (files missing, another
    // schema, weights not finite; the bundled one too) is refused before
    // anything runs: measuring only the baselines would answer another
    // question than the one asked.
    let (_, learned) = choose_planner(Some(PlannerKind::Learned), args.model.as_deref())?;
    let several = suites.len() > 1;
    for suite in suites {
        let Some(first) = suite.cases.first() else {
            continue;
        };
        let cell = cell_of(&compiled, &first.setup);
        let mut nets = learned.clone();
        if let Some(n) = &mut nets {
            // Read once per cell (and said once), applied to every suite
            // of the cell.
            match cell_rules.get(&cell) {
                Some(CellRule::Followed(rule) | CellRule::Taught(rule)) => {
                    n.task.sequence = rule.clone()
                }
                Some(_) => {}
                None => {
                    let rule = follow_cell_rule(n, &compiled, &cell);
                    super::execute::note_cell_rule(&cell, &rule, &n.task.sequence);
                    cell_rules.insert(cell.clone(), rule);
                }
            }
        }
        let sequence = baseline_rule(nets.as_ref(), &compiled, &cell);
        let mut planners = Vec::new();
        if nets.is_some() {
            planners.push(PlannerKind::Learned);
        }
        if args.baselines || nets.is_none() {
            planners.extend([PlannerKind::Rrt, PlannerKind::Expert]);
        }
        let cases: Vec<_> = suite
            .cases
            .iter()
            .take(args.limit.unwrap_or(usize::MAX))
            .collect();
        let bar = ProgressBar::with_draw_target(
            Some(cases.len() as u64),
            if args.quiet {
                ProgressDrawTarget::hidden()
            } else {
                ProgressDrawTarget::stderr()
            },
        );
        if let Ok(style) =
            ProgressStyle::with_template("{prefix:>12} [{bar:30}] {pos}/{len} {elapsed}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(suite.name.clone());
        let results: Vec<CaseResult> = cases
            .par_iter()
            .enumerate()
            .map_init(
                || nets.clone(),
                |nets, (i, case)| {
                    let seed = args.seed.wrapping_add(i as u64);
                    let r = match &args.record {
                        Some(dir) => recorded_case(
                            &recording_path(dir, &case.name),
                            &case.name,
                            &compiled,
                            &case.setup,
                            nets.as_ref(),
                            &planners,
                            &sequence,
                            seed,
                        ),
                        None => run_case(
                            &case.name,
                            &compiled,
                            &case.setup,
                            nets.as_ref(),
                            &planners,
                            &sequence,
                            seed,
                            args.reasoner_only,
                        )
                        .map_err(anyhow::Error::from),
                    };
                    bar.inc(1);
                    r
                },
            )
            .collect::<anyhow::Result<_>>()?;
        bar.finish_and_clear();
        if args.reasoner_only {
            planners.retain(|p| *p == PlannerKind::Learned);
        }
        let products = suite
            .cases
            .first()
            .map(|c| c.setup.assignment.len())
            .filter(|n| suite.cases.iter().all(|c| c.setup.assignment.len() == *n));
        for &p in &planners {
            let taught = nets.as_ref().map(|n| taught(n, &cell));
            rows.push(Row::of(&suite.name, &cell, taught, p, products, &results));
        }
        all_results.extend(results);
    }
    if let Some(dir) = &args.record {
        errln!(
            "wrote {} .rrd files (one per scenario) under {}",
            all_results.len(),
            dir.display()
        );
    }
    // Pooled over the run: a percentile from thousands of sub-goals
    // rather than a suite's hundreds.
    let totals: Vec<Row> = if several {
        let mut planners: Vec<PlannerKind> = Vec::new();
        for r in &rows {
            if !planners.contains(&r.planner) {
                planners.push(r.planner);
            }
        }
        planners
            .iter()
            .map(|&p| Row::of(ALL_SUITES, "-", None, p, None, &all_results))
            .collect()
    } else {
        Vec::new()
    };
    let mut table = markdown(&rows);
    if !totals.is_empty() {
        table.push_str("\nOver every suite of the run:\n\n");
        table.push_str(&markdown(&totals));
    }
    let machine = Machine {
        cpus: std::thread::available_parallelism()
            .map(usize::from)
            .unwrap_or(1),
        os: std::env::consts::OS,
        arch: std::env::consts::ARCH,
    };
    if args.json {
        let report = EvalReport {
            schema: SCHEMA,
            seed: args.seed,
            machine,
            rows: &rows,
            totals: &totals,
        };
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        out!("{table}");
    }
    // Written after the results are printed: a path that cannot be
    // written loses nothing the run measured.
    let written = || -> anyhow::Result<()> {
        if let Some(dir) = &args.plots {
            write_plots(dir, &rows, &all_results)?;
        }
        if let Some(path) = &args.markdown {
            write_file_atomically(path, table.as_bytes())?;
        }
        Ok(())
    };
    written().map_err(crate::AfterReport)?;
    Ok(Exit::Success)
}

/// Where `--record DIR` writes scenario `case` (`SUITE/NNN`):
/// DIR/SUITE/NNN.rrd. Names are the compiler's identifiers; any other
/// character is replaced, so that a name never leaves DIR.
fn recording_path(dir: &Path, case: &str) -> PathBuf {
    let mut path = dir.to_path_buf();
    for part in case.split('/') {
        let safe: String = part
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        path.push(safe);
    }
    path.set_extension("rrd");
    path
}

/// `--record`: scenario `name` as [`run_case`] runs it (the reasoner's
/// trial there, then each planner from the start pose), every run
/// journalled, and the file `path` written with one recording per
/// planner.
#[allow(clippy::too_many_arguments)]
fn recorded_case(
    path: &Path,
    name: &str,
    compiled: &Compiled,
    setup: &Setup,
    nets: Option<&Networks>,
    planners: &[PlannerKind],
    sequence: &SequenceRule,
    seed: u64,
) -> anyhow::Result<CaseResult> {
    let mut result = run_case(name, compiled, setup, nets, &[], sequence, seed, false)?;
    let ep = episode(&compiled.model, setup)?;
    let start = ep.home()?;
    let mut journalled = Vec::new();
    for &kind in planners {
        let journal = Journal::new();
        let policy = nets.map(|n| JournalPolicy::new(n, &journal, &ep.task));
        let Some(planner) = Planner::of(kind, policy.as_ref().map(|p| p as &dyn Policy), seed)
        else {
            continue;
        };
        let mut sim = ep.simulator(start)?;
        let mut world = JournalWorld::new(&mut sim, &journal);
        let report = execute::run_in_order(&mut world, &ep.arm, &ep.task, &planner, sequence);
        result.runs.push((kind, Run::of(&report)));
        journalled.push((format!("{name} ({kind})"), journal.take(), report));
    }
    let score = |g: &packwright_interface::Graph| {
        nets.map(|n| super::execute::scores(n, g))
            .unwrap_or_default()
    };
    let runs: Vec<packwright_recording::Run> = journalled
        .iter()
        .map(|(title, entries, report)| packwright_recording::Run {
            name: title,
            arm: &ep.arm,
            task: &ep.task,
            entries,
            report,
            scorer: (report.planner == PlannerKind::Learned)
                .then_some(&score as packwright_recording::Scorer),
        })
        .collect();
    if let Some(dir) = path.parent() {
        crate::fsio::make_dir(dir)?;
    }
    super::execute::write_recording(path, &runs)?;
    Ok(result)
}

/// `--plots DIR`: the charts of this run (`packwright_draw::charts`),
/// each file written atomically; planners in the rows' order.
fn write_plots(dir: &Path, rows: &[Row], results: &[CaseResult]) -> anyhow::Result<()> {
    use packwright_draw::charts::{self, Latencies, ProductTimes, SuccessRate};
    let rates: Vec<SuccessRate> = rows
        .iter()
        .filter_map(|r| {
            let sr = r.sr?;
            Some(SuccessRate {
                suite: r.suite.clone(),
                planner: r.planner.to_string(),
                rate: sr.rate,
                low: sr.ci95.0,
                high: sr.ci95.1,
                n: r.scenarios,
            })
        })
        .collect();
    let mut planners: Vec<PlannerKind> = Vec::new();
    for r in rows {
        if !planners.contains(&r.planner) {
            planners.push(r.planner);
        }
    }
    let runs = |p: PlannerKind| {
        results
            .iter()
            .flat_map(move |c| c.runs.iter().filter(move |(k, _)| *k == p))
            .map(|(_, run)| run)
    };
    let latencies: Vec<Latencies> = planners
        .iter()
        .map(|&p| Latencies {
            planner: p.to_string(),
            decision_us: runs(p).flat_map(|r| r.timing.decision_us.clone()).collect(),
            subgoal_us: runs(p).flat_map(|r| r.timing.subgoal_us.clone()).collect(),
            network_us: runs(p).flat_map(|r| r.timing.network_us.clone()).collect(),
        })
        .collect();
    let times: Vec<ProductTimes> = planners
        .iter()
        .map(|&p| ProductTimes {
            planner: p.to_string(),
            execution_s: runs(p).flat_map(|r| r.execution_s.clone()).collect(),
            bound_s: runs(p).flat_map(|r| r.bound_s.clone()).collect(),
        })
        .collect();
    crate::fsio::make_dir(dir)?;
    for (name, svg) in [
        ("success_rate.svg", charts::success_rates(&rates)?),
        ("latency.svg", charts::latencies(&latencies)?),
        ("execution_time.svg", charts::execution_times(&times)?),
    ] {
        let path = dir.join(name);
        write_file_atomically(&path, svg.as_bytes())?;
        errln!("wrote {}", path.display());
    }
    Ok(())
}
