//! Evaluation: one scenario run by each planner, and the success rates and
//! timings of a suite (one [`Row`] per suite and planner).

use crate::episode::episode;
use crate::error::Result;
use crate::stats::{Interval, mean, quantile, wilson};
use packwright_compiler::Compiled;
use packwright_compiler::expand::Setup;
use packwright_interface::outcome::{
    FallbackKind, Outcome, PlannerKind, Report, SubGoalKind, Timing,
};
use packwright_interface::{Policy, SequenceRule, World};
use packwright_motion::execute::{self, Planner};
use packwright_nets::Networks;
use serde::Serialize;
use std::collections::BTreeMap;

/// One planner's run of one scenario.
#[derive(Debug, Clone)]
pub struct Run {
    /// Every present selected product packed (missing ones reported as
    /// waiting), nothing collided, no order broken.
    pub success: bool,
    /// Why not, when not.
    pub failure: Option<String>,
    /// Stages handed to RRT-Connect.
    pub fallbacks: Vec<FallbackKind>,
    pub violations: usize,
    pub timing: Timing,
    /// Simulated seconds per product the robot packed.
    pub execution_s: Vec<f64>,
    /// The lower bound of each of those
    /// ([`ProductReport::bound_s`](packwright_interface::outcome::ProductReport)).
    pub bound_s: Vec<f64>,
}

impl Run {
    pub fn of(r: &Report) -> Run {
        let failure = r.first_problem();
        let (execution_s, bound_s) = r
            .products
            .iter()
            .filter(|p| p.outcome == Outcome::Packed)
            .map(|p| (p.execution_s, p.bound_s))
            .unzip();
        Run {
            success: failure.is_none(),
            failure,
            fallbacks: r.fallbacks.iter().map(|f| f.kind()).collect(),
            violations: r.violations.len(),
            timing: r.timing.clone(),
            execution_s,
            bound_s,
        }
    }
}

/// Every planner's run of one scenario.
#[derive(Debug, Clone, Default)]
pub struct CaseResult {
    pub name: String,
    /// Every reasoner decision right (with a learned model only).
    pub reasoner: Option<bool>,
    pub runs: Vec<(PlannerKind, Run)>,
}

/// Runs scenario `name` (`setup`) with each of `planners`; the learned
/// planner needs `nets`, and the expert and RRT-Connect handle the
/// products in `sequence`'s order (the learned planner's, so that the
/// three pack the same sequence). With `reasoner_only`, only the
/// reasoner's decisions are replayed.
#[allow(clippy::too_many_arguments)]
pub fn run_case(
    name: &str,
    compiled: &Compiled,
    setup: &Setup,
    nets: Option<&Networks>,
    planners: &[PlannerKind],
    sequence: &SequenceRule,
    seed: u64,
    reasoner_only: bool,
) -> Result<CaseResult> {
    let ep = episode(&compiled.model, setup)?;
    let start = ep.home()?;
    let mut result = CaseResult {
        name: name.to_owned(),
        ..CaseResult::default()
    };
    if let Some(nets) = nets {
        let seen = ep.simulator(start)?.observe().products;
        result.reasoner = Some(execute::reasoner_trial(nets, &ep.task, &seen).is_ok());
    }
    if reasoner_only {
        return Ok(result);
    }
    for &kind in planners {
        let Some(planner) = Planner::of(kind, nets.map(|n| n as &dyn Policy), seed) else {
            continue;
        };
        let mut sim = ep.simulator(start)?;
        let report = execute::run_in_order(&mut sim, &ep.arm, &ep.task, &planner, sequence);
        result.runs.push((kind, Run::of(&report)));
    }
    Ok(result)
}

/// Median, 99th percentile and count of some timings (µs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spread {
    pub median: Option<f64>,
    pub p99: Option<f64>,
    pub n: usize,
}

impl Spread {
    fn of(values: &[f64]) -> Spread {
        Spread {
            median: quantile(values, 0.5),
            p99: quantile(values, 0.99),
            n: values.len(),
        }
    }
}

/// A rate with its Wilson 95% interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rate {
    pub rate: f64,
    pub ci95: Interval,
}

impl Rate {
    fn of(k: usize, n: usize) -> Option<Rate> {
        (n > 0).then(|| Rate {
            rate: k as f64 / n as f64,
            ci95: wilson(k, n),
        })
    }
}

/// A failed scenario and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseFailure {
    pub scenario: String,
    pub why: String,
}

/// A scenario in which the learned planner fell back, and each fallback's
/// kind ("placing 2: limits"), whether it packed or not: where to look
/// with `execute --scenario`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseFallbacks {
    pub scenario: String,
    pub kinds: Vec<String>,
}

/// One suite × planner.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    pub suite: String,
    /// The suite's cell.
    pub cell: String,
    /// Learned only: whether the model was taught demonstrations in that
    /// cell (`false`: it answers from the cell's geometry alone).
    pub cell_taught: Option<bool>,
    pub planner: PlannerKind,
    pub scenarios: usize,
    /// The products each scenario's order selects (n of `choose n of`),
    /// when every scenario of the suite selects as many.
    pub products: Option<usize>,
    /// Learned only: every reasoner decision of a scenario right.
    pub reasoner_sr: Option<Rate>,
    pub reasoner_scenarios: usize,
    pub sr: Option<Rate>,
    /// Learned only: success with no fallback.
    pub sr_no_fallback: Option<Rate>,
    pub fallbacks_per_package: Option<f64>,
    /// Fallbacks by kind ("placing 3: short").
    pub fallback_kinds: BTreeMap<String, usize>,
    /// The scenarios with fallbacks (`--json` only).
    pub fallback_scenarios: Vec<CaseFallbacks>,
    pub violations: usize,
    pub decision_us: Spread,
    pub subgoal_us: Spread,
    /// `subgoal_us` by what the sub-goals are for (the hover, the lift,
    /// ...; `--json` only): where a planner's planning time goes.
    pub subgoal_us_by_kind: BTreeMap<SubGoalKind, Spread>,
    pub network_us: Spread,
    pub failures: Vec<CaseFailure>,
    pub execution_s_per_product: Option<f64>,
    /// The mean lower bound of those products' execution times (each
    /// joint alone, jerk-limited, between the same stops, plus settling).
    pub bound_s_per_product: Option<f64>,
    /// `execution_s_per_product / bound_s_per_product`.
    pub time_ratio: Option<f64>,
    /// Products packed per hour of execution (3600 /
    /// `execution_s_per_product`; planning not included).
    pub products_per_hour: Option<f64>,
}

impl Row {
    /// The row of `planner` over the results of one suite in `cell`;
    /// `cell_taught` for the learned planner; `products` the order size
    /// its scenarios share, if they do.
    pub fn of(
        suite: &str,
        cell: &str,
        cell_taught: Option<bool>,
        planner: PlannerKind,
        products: Option<usize>,
        cases: &[CaseResult],
    ) -> Row {
        let runs: Vec<(&str, &Run)> = cases
            .iter()
            .flat_map(|c| {
                c.runs
                    .iter()
                    .filter(|(p, _)| *p == planner)
                    .map(|(_, r)| (c.name.as_str(), r))
            })
            .collect();
        let n = runs.len();
        let ok = runs.iter().filter(|(_, r)| r.success).count();
        let clean = runs
            .iter()
            .filter(|(_, r)| r.success && r.fallbacks.is_empty())
            .count();
        let learned = planner == PlannerKind::Learned;
        let reasoner: Vec<bool> = if learned {
            cases.iter().filter_map(|c| c.reasoner).collect()
        } else {
            Vec::new()
        };
        let all = |f: fn(&Timing) -> &Vec<f64>| -> Vec<f64> {
            runs.iter()
                .flat_map(|(_, r)| f(&r.timing).iter().copied())
                .collect()
        };
        let per_product = |f: fn(&Run) -> &Vec<f64>| {
            mean(
                &runs
                    .iter()
                    .flat_map(|(_, r)| f(r).iter().copied())
                    .collect::<Vec<_>>(),
            )
        };
        let execution = per_product(|r| &r.execution_s);
        let bound = per_product(|r| &r.bound_s);
        let mut kinds = BTreeMap::new();
        for kind in runs.iter().flat_map(|(_, r)| r.fallbacks.iter()) {
            *kinds.entry(kind.to_string()).or_default() += 1;
        }
        let mut by_kind: BTreeMap<SubGoalKind, Vec<f64>> = BTreeMap::new();
        for (kind, us) in runs.iter().flat_map(|(_, r)| r.timing.subgoals()) {
            by_kind.entry(kind).or_default().push(us);
        }
        Row {
            suite: suite.to_owned(),
            cell: cell.to_owned(),
            cell_taught: cell_taught.filter(|_| learned),
            planner,
            scenarios: n.max(reasoner.len()),
            products,
            reasoner_sr: Rate::of(reasoner.iter().filter(|r| **r).count(), reasoner.len()),
            reasoner_scenarios: reasoner.len(),
            sr: Rate::of(ok, n),
            sr_no_fallback: if learned { Rate::of(clean, n) } else { None },
            fallbacks_per_package: (learned && n > 0).then(|| {
                runs.iter().map(|(_, r)| r.fallbacks.len()).sum::<usize>() as f64 / n as f64
            }),
            fallback_kinds: kinds,
            fallback_scenarios: runs
                .iter()
                .filter(|(_, r)| !r.fallbacks.is_empty())
                .map(|(name, r)| CaseFallbacks {
                    scenario: (*name).to_owned(),
                    kinds: r.fallbacks.iter().map(ToString::to_string).collect(),
                })
                .collect(),
            violations: runs.iter().map(|(_, r)| r.violations).sum(),
            decision_us: Spread::of(&all(|t| &t.decision_us)),
            subgoal_us: Spread::of(&all(|t| &t.subgoal_us)),
            subgoal_us_by_kind: by_kind
                .into_iter()
                .map(|(kind, us)| (kind, Spread::of(&us)))
                .collect(),
            network_us: Spread::of(&all(|t| &t.network_us)),
            failures: runs
                .iter()
                .filter_map(|(name, r)| {
                    r.failure.as_ref().map(|why| CaseFailure {
                        scenario: (*name).to_owned(),
                        why: why.clone(),
                    })
                })
                .collect(),
            execution_s_per_product: execution,
            bound_s_per_product: bound,
            time_ratio: execution
                .zip(bound)
                .filter(|(_, b)| *b > 0.0)
                .map(|(e, b)| e / b),
            products_per_hour: execution.filter(|e| *e > 0.0).map(|e| 3600.0 / e),
        }
    }
}

fn rate(r: &Option<Rate>) -> String {
    r.map_or("-".into(), |r| {
        format!("{:.3} [{:.3}, {:.3}]", r.rate, r.ci95.0, r.ci95.1)
    })
}

fn micros(s: &Spread) -> String {
    match (s.median, s.p99) {
        (Some(m), Some(p)) => format!("{m:.0} / {p:.0}"),
        _ => "-".into(),
    }
}

/// The Markdown table of `rows`.
pub fn markdown(rows: &[Row]) -> String {
    let mut out = String::from(
        "| suite | cell | planner | n | reasoner SR | SR [95% CI] | SR no fallback | fallbacks/package | decision us (median / p99) | sub-goal us (median / p99) | sub-goal + action us (median / p99) | execution s/product | bound s/product | ratio | products/hour |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {}{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.suite,
            r.cell,
            if r.cell_taught == Some(false) {
                " (untaught)"
            } else {
                ""
            },
            r.planner,
            r.scenarios,
            rate(&r.reasoner_sr),
            rate(&r.sr),
            rate(&r.sr_no_fallback),
            r.fallbacks_per_package
                .map_or("-".into(), |v| format!("{v:.2}")),
            micros(&r.decision_us),
            micros(&r.subgoal_us),
            micros(&r.network_us),
            r.execution_s_per_product
                .map_or("-".into(), |v| format!("{v:.2}")),
            r.bound_s_per_product
                .map_or("-".into(), |v| format!("{v:.2}")),
            r.time_ratio.map_or("-".into(), |v| format!("{v:.2}")),
            r.products_per_hour
                .map_or("-".into(), |v| format!("{v:.0}")),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(subgoals: &[(SubGoalKind, f64)]) -> Run {
        let mut timing = Timing::default();
        for &(kind, us) in subgoals {
            timing.subgoal(kind, us);
        }
        Run {
            success: true,
            failure: None,
            fallbacks: Vec::new(),
            violations: 0,
            timing,
            execution_s: Vec::new(),
            bound_s: Vec::new(),
        }
    }

    /// A row's sub-goal times by kind hold each planner's own sub-goals
    /// of that kind over every scenario, and together all of them.
    #[test]
    fn subgoal_times_are_spread_by_kind_per_planner() {
        use SubGoalKind::*;
        let case =
            |name: &str, learned: &[(SubGoalKind, f64)], rrt: &[(SubGoalKind, f64)]| CaseResult {
                name: name.to_owned(),
                reasoner: None,
                runs: vec![
                    (PlannerKind::Learned, run(learned)),
                    (PlannerKind::Rrt, run(rrt)),
                ],
            };
        let cases = [
            case("a", &[(Hover, 10.0), (Contact, 1.0)], &[(Hover, 50.0)]),
            case("b", &[(Hover, 30.0), (BackUp, 7.0)], &[(Release, 5.0)]),
        ];
        let row = Row::of("s", "c", None, PlannerKind::Learned, None, &cases);
        let kinds: Vec<_> = row.subgoal_us_by_kind.keys().copied().collect();
        assert_eq!(kinds, [Hover, Contact, BackUp]);
        let hover = &row.subgoal_us_by_kind[&Hover];
        assert_eq!(hover.n, 2);
        assert_eq!(hover.median, quantile(&[10.0, 30.0], 0.5));
        assert_eq!(row.subgoal_us.n, 4);
        let rrt = Row::of("s", "c", None, PlannerKind::Rrt, None, &cases);
        let kinds: Vec<_> = rrt.subgoal_us_by_kind.keys().copied().collect();
        assert_eq!(kinds, [Hover, Release]);
        assert_eq!(rrt.subgoal_us_by_kind[&Hover].median, Some(50.0));
    }

    use packwright_interface::Stage;

    /// The learned row names each scenario that fell back, with its
    /// fallbacks' kinds; one without fallbacks is not listed.
    #[test]
    fn scenarios_that_fell_back_are_named() {
        let short = FallbackKind {
            stage: Stage::Placing,
            subgoal: 2,
            why: "short",
        };
        let mut fell = run(&[]);
        fell.fallbacks = vec![short, short];
        let case = |name: &str, run: Run| CaseResult {
            name: name.to_owned(),
            reasoner: None,
            runs: vec![(PlannerKind::Learned, run)],
        };
        let cases = [case("s/01", run(&[])), case("s/02", fell)];
        let row = Row::of("s", "c", None, PlannerKind::Learned, None, &cases);
        assert_eq!(
            row.fallback_scenarios,
            [CaseFallbacks {
                scenario: "s/02".into(),
                kinds: vec!["placing 2: short".into(); 2],
            }]
        );
        assert_eq!(row.fallbacks_per_package, Some(1.0));
    }
}
