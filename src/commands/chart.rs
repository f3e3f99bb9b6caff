//! `packwright chart`: the charts of a study, from several `eval --json`
//! reports each run at one value of a studied quantity (the paper's
//! generalisation studies: success against the training ratio, and
//! against the number of products in the order).

use crate::cli::{ChartArgs, StudyMetric};
use crate::fsio::write_file_atomically;
use anyhow::{Context, bail};
use packwright_draw::charts::{self, StudyPoint};
use packwright_interface::PlannerKind;
use packwright_pipeline::stats::wilson;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use crate::Exit;

/// The largest report read (64 MiB): an eval report is a few kB per suite.
const MAX_REPORT_BYTES: u64 = 64 << 20;

/// What a study needs of an `eval --json` report.
#[derive(Debug, Deserialize)]
struct Report {
    schema: String,
    rows: Vec<ReportRow>,
}

#[derive(Debug, Deserialize)]
struct ReportRow {
    suite: String,
    planner: PlannerKind,
    scenarios: usize,
    #[serde(default)]
    products: Option<usize>,
    reasoner_sr: Option<ReportRate>,
    reasoner_scenarios: usize,
    sr: Option<ReportRate>,
    sr_no_fallback: Option<ReportRate>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
struct ReportRate {
    rate: f64,
}

/// A row's successes and trials under `metric`, if it has that rate.
fn outcome(row: &ReportRow, metric: StudyMetric) -> Option<(usize, usize)> {
    let (rate, n) = match metric {
        StudyMetric::Reasoner => (row.reasoner_sr?, row.reasoner_scenarios),
        StudyMetric::System => (row.sr?, row.scenarios),
        StudyMetric::NoFallback => (row.sr_no_fallback?, row.scenarios),
    };
    if !(0.0..=1.0).contains(&rate.rate) || n == 0 {
        return None;
    }
    Some(((rate.rate * n as f64).round() as usize, n))
}

fn read_report(path: &Path) -> anyhow::Result<Report> {
    let file =
        std::fs::File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut text = String::new();
    file.take(MAX_REPORT_BYTES + 1)
        .read_to_string(&mut text)
        .with_context(|| format!("cannot read {} as UTF-8 text", path.display()))?;
    if text.len() as u64 > MAX_REPORT_BYTES {
        bail!(
            "{} is larger than {} MiB: not an eval report",
            path.display(),
            MAX_REPORT_BYTES >> 20
        );
    }
    let report: Report = serde_json::from_str(&text).with_context(|| {
        format!(
            "{} is not an `eval --json` report (write one with `packwright eval ... --json > FILE`)",
            path.display()
        )
    })?;
    if ![super::eval::SCHEMA, super::eval::PREVIOUS_SCHEMA].contains(&report.schema.as_str()) {
        bail!(
            "{} has schema `{}`; this packwright reads `{}` (run eval again)",
            path.display(),
            report.schema,
            super::eval::SCHEMA
        );
    }
    Ok(report)
}

/// The points of both charts: per suite at each value, and per value at
/// each n (suites with the same n pooled).
fn points(
    reports: &[(f64, Report)],
    metric: StudyMetric,
    planner: PlannerKind,
    x_name: &str,
) -> (Vec<StudyPoint>, Vec<StudyPoint>) {
    let point = |series: String, x: f64, (k, n): (usize, usize)| {
        let (low, high) = wilson(k, n);
        StudyPoint {
            series,
            x,
            rate: k as f64 / n as f64,
            low,
            high,
            n,
        }
    };
    let mut by_x = Vec::new();
    let mut by_n = Vec::new();
    for (x, report) in reports {
        let mut pooled: BTreeMap<usize, (usize, usize)> = BTreeMap::new();
        for row in report.rows.iter().filter(|r| r.planner == planner) {
            let Some(kn) = outcome(row, metric) else {
                continue;
            };
            by_x.push(point(row.suite.clone(), *x, kn));
            if let Some(products) = row.products {
                let e = pooled.entry(products).or_default();
                e.0 += kn.0;
                e.1 += kn.1;
            }
        }
        for (n, kn) in pooled {
            by_n.push(point(format!("{x_name} {x}"), n as f64, kn));
        }
    }
    (by_x, by_n)
}

pub fn run(args: &ChartArgs) -> anyhow::Result<Exit> {
    // Two runs at one x would be drawn as one point of either: refused.
    let mut seen: Vec<f64> = Vec::new();
    for (x, path) in &args.runs {
        if seen.contains(x) {
            bail!(
                "two runs at {} = {x} ({} is the second): give each run its own value",
                args.x,
                path.display()
            );
        }
        seen.push(*x);
    }
    let reports = args
        .runs
        .iter()
        .map(|(x, path)| Ok((*x, read_report(path)?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let (by_x, by_n) = points(&reports, args.metric, args.planner, &args.x);
    if by_x.is_empty() {
        bail!(
            "the reports hold no {} success rate of the {} planner (was it evaluated? `--metric reasoner` needs the learned planner)",
            metric_name(args.metric),
            args.planner
        );
    }
    let what = metric_name(args.metric);
    let vs_x = charts::study(
        &by_x,
        &format!("{what} against {} ({})", args.x, args.planner),
        &args.x,
    )?;
    let vs_n = charts::study(
        &by_n,
        &format!(
            "{what} against n, the products in the order ({})",
            args.planner
        ),
        "n: products in the order",
    )?;
    crate::fsio::make_dir(&args.output)?;
    for (name, svg) in [("success_vs_x.svg", vs_x), ("success_vs_n.svg", vs_n)] {
        let path = args.output.join(name);
        write_file_atomically(&path, svg.as_bytes())?;
        outln!("{}", path.display());
    }
    Ok(Exit::Success)
}

fn metric_name(metric: StudyMetric) -> &'static str {
    match metric {
        StudyMetric::Reasoner => "Reasoner success",
        StudyMetric::System => "Success",
        StudyMetric::NoFallback => "Success without fallback",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(rows: &str) -> Report {
        serde_json::from_str(&format!(
            r#"{{"schema": "packwright.eval/2", "rows": [{rows}]}}"#
        ))
        .expect("parses")
    }

    fn row(suite: &str, planner: &str, products: usize, reasoner: f64) -> String {
        format!(
            r#"{{"suite": "{suite}", "planner": "{planner}", "scenarios": 10, "products": {products},
               "reasoner_sr": {{"rate": {reasoner}}}, "reasoner_scenarios": 10,
               "sr": {{"rate": 1.0}}, "sr_no_fallback": {{"rate": 0.9}}}}"#
        )
    }

    #[test]
    fn suites_of_the_same_n_are_pooled_and_other_planners_left_out() {
        let runs = vec![
            (
                0.25,
                report(
                    &[
                        row("case1_3of5", "learned", 3, 0.8),
                        row("case2_3of5", "learned", 3, 0.6),
                        row("case1_4of5", "learned", 4, 0.5),
                        row("case1_4of5", "rrt", 4, 0.1),
                    ]
                    .join(","),
                ),
            ),
            (1.0, report(&row("case1_3of5", "learned", 3, 1.0))),
        ];
        let (by_x, by_n) = points(&runs, StudyMetric::Reasoner, PlannerKind::Learned, "ratio");
        assert_eq!(by_x.len(), 4);
        assert_eq!(by_n.len(), 3);
        let pooled = &by_n[0];
        assert_eq!((pooled.series.as_str(), pooled.x), ("ratio 0.25", 3.0));
        assert_eq!(pooled.n, 20);
        assert!((pooled.rate - 0.7).abs() < 1e-12);
        assert!(pooled.low < 0.7 && pooled.high > 0.7);
        let (clean, _) = points(&runs, StudyMetric::NoFallback, PlannerKind::Learned, "r");
        assert!(clean.iter().all(|p| (p.rate - 0.9).abs() < 1e-12));
    }

    #[test]
    fn a_row_without_the_rate_is_skipped() {
        let mut r = report(&row("a", "expert", 3, 1.0));
        r.rows[0].reasoner_sr = None;
        assert_eq!(outcome(&r.rows[0], StudyMetric::Reasoner), None);
        assert_eq!(outcome(&r.rows[0], StudyMetric::System), Some((10, 10)));
    }
}
