//! `packwright eval`: success rates and planning times over scenario suites.

use crate::Exit;
use crate::bridge::episode;
use crate::cli::EvalArgs;
use crate::cli::PlannerArg;
use crate::commands::execute::choose_planner;
use crate::fsio::{FsLoader, write_file_atomically};
use crate::stats::{mean, quantile, wilson};
use anyhow::bail;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use packwright_runtime::execute::{self, Outcome, PlannerKind, Report, Timing};
use packwright_runtime::learn::Networks;
use packwright_runtime::sim::Simulator;
use rayon::prelude::*;
use serde_json::json;

/// One planner's run of one scenario.
#[derive(Debug, Clone)]
struct Run {
    /// Every present selected product packed (missing ones reported as
    /// waiting), nothing collided, no order broken.
    success: bool,
    /// Why not, when not.
    failure: Option<String>,
    /// Stages handed to RRT-Connect, by kind ("placing 3: short").
    fallbacks: Vec<String>,
    violations: usize,
    timing: Timing,
    /// Simulated seconds per product the robot packed.
    execution_s: Vec<f64>,
}

impl Run {
    fn of(r: &Report) -> Run {
        let failed = r.products.iter().find_map(|p| match &p.outcome {
            Outcome::Failed(why) => Some(format!("{}: {why}", p.product)),
            Outcome::NotAttempted => Some(format!("{}: not attempted", p.product)),
            _ => None,
        });
        let failure = r
            .violations
            .first()
            .map(|v| format!("the reasoner {v}"))
            .or(failed)
            .or_else(|| r.collisions.first().cloned());
        Run {
            success: failure.is_none(),
            failure,
            fallbacks: r.fallbacks.iter().map(|f| f.kind()).collect(),
            violations: r.violations.len(),
            timing: r.timing.clone(),
            execution_s: r
                .products
                .iter()
                .filter(|p| p.outcome == Outcome::Packed)
                .map(|p| p.execution_s)
                .collect(),
        }
    }
}

#[derive(Debug, Clone, Default)]
struct CaseResult {
    name: String,
    /// Every reasoner decision right (learned only).
    reasoner: Option<bool>,
    runs: Vec<(&'static str, Run)>,
}

fn one_case(
    name: &str,
    compiled: &packwright_compiler::Compiled,
    setup: &packwright_compiler::expand::Setup,
    nets: Option<&Networks>,
    planners: &[&'static str],
    seed: u64,
    reasoner_only: bool,
) -> anyhow::Result<CaseResult> {
    let ep = episode(&compiled.model, setup)?;
    let cell = &ep.task.cell;
    let Some(start) = execute::home(&ep.arm, cell) else {
        bail!("the arm cannot reach a start pose over the pending area");
    };
    let mut result = CaseResult {
        name: name.to_owned(),
        ..CaseResult::default()
    };
    if let Some(nets) = nets {
        let sim = Simulator::new(ep.arm.clone(), cell, &ep.placements, start)?;
        let seen = packwright_runtime::world::World::observe(&sim).products;
        result.reasoner = Some(execute::reasoner_trial(nets, &ep.task, &seen).is_ok());
    }
    if reasoner_only {
        return Ok(result);
    }
    for &planner in planners {
        let mut sim = Simulator::new(ep.arm.clone(), cell, &ep.placements, start)?;
        let report = match (planner, nets) {
            ("learned", Some(nets)) => {
                execute::run_learned(&mut sim, &ep.arm, &ep.task, nets, seed)
            }
            ("rrt", _) => execute::run(&mut sim, &ep.arm, &ep.task, PlannerKind::Rrt { seed }),
            ("expert", _) => execute::run(&mut sim, &ep.arm, &ep.task, PlannerKind::Expert),
            _ => continue,
        };
        result.runs.push((planner, Run::of(&report)));
    }
    Ok(result)
}

fn stat(values: &[f64]) -> serde_json::Value {
    json!({
        "median": quantile(values, 0.5),
        "p99": quantile(values, 0.99),
        "n": values.len(),
    })
}

/// One suite × planner row.
fn row(suite: &str, planner: &str, cases: &[CaseResult]) -> serde_json::Value {
    let runs: Vec<&Run> = cases
        .iter()
        .flat_map(|c| c.runs.iter().filter(|(p, _)| *p == planner).map(|(_, r)| r))
        .collect();
    let n = runs.len();
    let ok = runs.iter().filter(|r| r.success).count();
    let clean = runs
        .iter()
        .filter(|r| r.success && r.fallbacks.is_empty())
        .count();
    let reasoner: Vec<bool> = cases.iter().filter_map(|c| c.reasoner).collect();
    let reasoner_ok = reasoner.iter().filter(|r| **r).count();
    let all = |f: fn(&Timing) -> &Vec<f64>| -> Vec<f64> {
        runs.iter()
            .flat_map(|r| f(&r.timing).iter().copied())
            .collect()
    };
    let learned = planner == "learned";
    let mut kinds = std::collections::BTreeMap::<&str, usize>::new();
    for kind in runs.iter().flat_map(|r| r.fallbacks.iter()) {
        *kinds.entry(kind).or_default() += 1;
    }
    json!({
        "suite": suite,
        "planner": planner,
        "scenarios": n.max(if learned { reasoner.len() } else { 0 }),
        "reasoner_sr": (learned && !reasoner.is_empty()).then(|| reasoner_ok as f64 / reasoner.len() as f64),
        "reasoner_ci95": (learned && !reasoner.is_empty()).then(|| wilson(reasoner_ok, reasoner.len())),
        "reasoner_scenarios": if learned { reasoner.len() } else { 0 },
        "sr": (n > 0).then(|| ok as f64 / n as f64),
        "sr_ci95": (n > 0).then(|| wilson(ok, n)),
        "sr_no_fallback": (learned && n > 0).then(|| clean as f64 / n as f64),
        "sr_no_fallback_ci95": (learned && n > 0).then(|| wilson(clean, n)),
        "fallbacks_per_package": (learned && n > 0).then(|| runs.iter().map(|r| r.fallbacks.len()).sum::<usize>() as f64 / n as f64),
        "fallback_kinds": kinds,
        "violations": runs.iter().map(|r| r.violations).sum::<usize>(),
        "decision_us": stat(&all(|t| &t.decision_us)),
        "subgoal_us": stat(&all(|t| &t.subgoal_us)),
        "network_us": stat(&all(|t| &t.network_us)),
        "failures": cases.iter().flat_map(|c| c.runs.iter().filter(|(p, _)| *p == planner).filter_map(|(_, r)| r.failure.as_ref().map(|f| json!({"scenario": c.name, "why": f})))).collect::<Vec<_>>(),
        "execution_s_per_product": mean(&runs.iter().flat_map(|r| r.execution_s.iter().copied()).collect::<Vec<_>>()),
    })
}

fn fmt_rate(v: &serde_json::Value, rate: &str, ci: &str) -> String {
    match (v[rate].as_f64(), v[ci].as_array()) {
        (Some(r), Some(c)) => format!(
            "{r:.3} [{:.3}, {:.3}]",
            c.first().and_then(serde_json::Value::as_f64).unwrap_or(0.0),
            c.get(1).and_then(serde_json::Value::as_f64).unwrap_or(1.0)
        ),
        _ => "-".into(),
    }
}

fn fmt_us(v: &serde_json::Value) -> String {
    match (v["median"].as_f64(), v["p99"].as_f64()) {
        (Some(m), Some(p)) => format!("{m:.0} / {p:.0}"),
        _ => "-".into(),
    }
}

/// The Markdown table of `rows`.
fn markdown(rows: &[serde_json::Value]) -> String {
    let mut out = String::from(
        "| suite | planner | n | reasoner SR | SR [95% CI] | SR no fallback | fallbacks/package | decision us (median / p99) | sub-goal us (median / p99) | sub-goal + action us (median / p99) | execution s/product |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r["suite"].as_str().unwrap_or(""),
            r["planner"].as_str().unwrap_or(""),
            r["scenarios"],
            fmt_rate(r, "reasoner_sr", "reasoner_ci95"),
            fmt_rate(r, "sr", "sr_ci95"),
            fmt_rate(r, "sr_no_fallback", "sr_no_fallback_ci95"),
            r["fallbacks_per_package"]
                .as_f64()
                .map_or("-".into(), |v| format!("{v:.2}")),
            fmt_us(&r["decision_us"]),
            fmt_us(&r["subgoal_us"]),
            fmt_us(&r["network_us"]),
            r["execution_s_per_product"]
                .as_f64()
                .map_or("-".into(), |v| format!("{v:.2}")),
        ));
    }
    out
}

pub fn run(args: &EvalArgs) -> anyhow::Result<Exit> {
    let compiled = match packwright_compiler::check(&FsLoader, &args.files) {
        Ok(c) => c,
        Err(failed) => return Ok(super::report_failure(&failed, args.json)),
    };
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
    let mut skipped = Vec::new();
    for suite in suites {
        let Some(first) = suite.cases.first() else {
            continue;
        };
        let cell = super::execute::cell_of(&compiled, &first.setup);
        let learned = choose_planner(Some(PlannerArg::Learned), args.model.as_deref(), &cell);
        let nets = match learned {
            Ok((_, nets)) => nets,
            Err(e) => {
                errln!("{}: no learned planner ({e:#})", suite.name);
                skipped.push(json!({"suite": suite.name, "reason": format!("{e:#}")}));
                None
            }
        };
        let mut planners: Vec<&'static str> = Vec::new();
        if nets.is_some() {
            planners.push("learned");
        }
        if args.baselines || nets.is_none() {
            planners.extend(["rrt", "expert"]);
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
                    let r = one_case(
                        &case.name,
                        &compiled,
                        &case.setup,
                        nets.as_ref(),
                        &planners,
                        args.seed.wrapping_add(i as u64),
                        args.reasoner_only,
                    );
                    bar.inc(1);
                    r
                },
            )
            .collect::<anyhow::Result<_>>()?;
        bar.finish_and_clear();
        if args.reasoner_only {
            planners.retain(|p| *p == "learned");
        }
        for p in &planners {
            rows.push(row(&suite.name, p, &results));
        }
    }
    let table = markdown(&rows);
    if let Some(path) = &args.markdown {
        write_file_atomically(path, table.as_bytes())?;
    }
    let machine = json!({
        "cpus": std::thread::available_parallelism().map(usize::from).unwrap_or(1),
        "os": std::env::consts::OS,
        "arch": std::env::consts::ARCH,
    });
    if args.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&json!({
                "schema": "packwright.eval/1",
                "seed": args.seed,
                "machine": machine,
                "rows": rows,
                "skipped": skipped,
            }))?
        );
    } else {
        out!("{table}");
    }
    Ok(Exit::Success)
}
