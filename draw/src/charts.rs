//! The charts of an evaluation (plotters, SVG backend). plotters runs here
//! without a font backend: its naive font estimates text widths for the
//! layout and the SVG holds `<text>` elements that the viewer renders, so
//! no font file ships and the output is the same on every machine.
//!
//! Inputs are plain numbers named by strings (suites, planners), so that
//! this crate needs nothing of the pipeline. Planners keep the order in
//! which they first appear, and each has one colour in every chart.

use crate::error::DrawError;
use plotters::prelude::*;

/// One suite × planner's success rate and its Wilson 95% interval.
#[derive(Debug, Clone, PartialEq)]
pub struct SuccessRate {
    pub suite: String,
    pub planner: String,
    pub rate: f64,
    pub low: f64,
    pub high: f64,
    /// Scenarios run.
    pub n: usize,
}

/// One planner's planning times (µs) over a run: every reasoner
/// decision, every sub-goal, every sub-goal-planner-plus-one-action call.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Latencies {
    pub planner: String,
    pub decision_us: Vec<f64>,
    pub subgoal_us: Vec<f64>,
    pub network_us: Vec<f64>,
}

/// One planner's packed products: each one's simulated execution time
/// and its lower bound (s), pairwise.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProductTimes {
    pub planner: String,
    pub execution_s: Vec<f64>,
    pub bound_s: Vec<f64>,
}

const PALETTE: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// A planner's colour: fixed for the three planners packwright has, the
/// rest of the palette for others.
fn colour(planner: &str, others: &[&str]) -> RGBColor {
    match planner {
        "learned" => PALETTE[0],
        "rrt" => PALETTE[1],
        "expert" => PALETTE[2],
        _ => {
            let i = others.iter().position(|p| *p == planner).unwrap_or(0);
            PALETTE[3 + i % 2]
        }
    }
}

fn planners<'a>(names: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for n in names {
        if !out.contains(&n) {
            out.push(n);
        }
    }
    out
}

fn fail<E: std::fmt::Display>(chart: &'static str) -> impl Fn(E) -> DrawError {
    move |e| DrawError::Chart {
        chart,
        reason: e.to_string(),
    }
}

fn finite(chart: &'static str, values: impl IntoIterator<Item = f64>) -> Result<(), DrawError> {
    if values.into_iter().all(f64::is_finite) {
        Ok(())
    } else {
        Err(DrawError::NonFinite {
            what: format!("the data of chart `{chart}`"),
        })
    }
}

/// Success rate with its Wilson interval, per suite (x) and planner
/// (colour, side by side).
pub fn success_rates(rates: &[SuccessRate]) -> Result<String, DrawError> {
    const NAME: &str = "success rate";
    finite(NAME, rates.iter().flat_map(|r| [r.rate, r.low, r.high]))?;
    let err = fail(NAME);
    let suites = planners(rates.iter().map(|r| r.suite.as_str()));
    let kinds = planners(rates.iter().map(|r| r.planner.as_str()));
    let n = suites.len().max(1);
    let width = (160 + 110 * n).max(640) as u32;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (width, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Success rate per suite and planner (Wilson 95% interval)",
                ("sans-serif", 18),
            )
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), 0f64..1.05)
            .map_err(&err)?;
        let names = suites.clone();
        let label = move |v: &f64| {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 {
                names
                    .get(i as usize)
                    .map_or(String::new(), |s| (*s).to_owned())
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n + 1)
            .x_label_formatter(&label)
            .y_desc("success rate")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(&err)?;
        let k = kinds.len().max(1) as f64;
        for (j, planner) in kinds.iter().enumerate() {
            let c = colour(planner, &kinds);
            let offset = (j as f64 - (k - 1.0) / 2.0) * 0.7 / k;
            let mine: Vec<(f64, &SuccessRate)> = rates
                .iter()
                .filter(|r| r.planner == *planner)
                .filter_map(|r| {
                    let i = suites.iter().position(|s| *s == r.suite)?;
                    Some((i as f64 + offset, r))
                })
                .collect();
            chart
                .draw_series(mine.iter().map(|(x, r)| {
                    ErrorBar::new_vertical(*x, r.low, r.rate, r.high, c.stroke_width(2), 10)
                }))
                .map_err(&err)?
                .label(planner.to_string())
                .legend(move |(x, y)| Circle::new((x, y), 5, c.filled()));
            chart
                .draw_series(
                    mine.iter()
                        .map(|(x, r)| Circle::new((*x, r.rate), 5, c.filled())),
                )
                .map_err(&err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .label_font(("sans-serif", 13))
            .draw()
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(out)
}

/// At most `max` points of the empirical distribution of `values`:
/// (value, share of values at or below it), by quantiles when there are
/// more.
fn ecdf(values: &[f64], max: usize) -> Vec<(f64, f64)> {
    let mut v: Vec<f64> = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return Vec::new();
    }
    let idx: Vec<usize> = if n <= max {
        (0..n).collect()
    } else {
        (0..max).map(|k| k * (n - 1) / (max - 1)).collect()
    };
    idx.into_iter()
        .map(|i| (v[i], (i + 1) as f64 / n as f64))
        .collect()
}

/// Which timings of a planner a panel shows.
type Pick = fn(&Latencies) -> &Vec<f64>;

/// Latency distributions per planner (empirical distribution functions
/// on a log time axis): decision, sub-goal, sub-goal planner + one
/// action, side by side.
pub fn latencies(sets: &[Latencies]) -> Result<String, DrawError> {
    const NAME: &str = "latency";
    finite(
        NAME,
        sets.iter().flat_map(|s| {
            s.decision_us
                .iter()
                .chain(&s.subgoal_us)
                .chain(&s.network_us)
                .copied()
        }),
    )?;
    let err = fail(NAME);
    let kinds = planners(sets.iter().map(|s| s.planner.as_str()));
    let panels: [(&str, Pick); 3] = [
        ("decision", |s| &s.decision_us),
        ("sub-goal", |s| &s.subgoal_us),
        ("sub-goal + action", |s| &s.network_us),
    ];
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (1200, 400)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let root = root
            .titled(
                "Planning time per call (share of calls at or below; log time axis)",
                ("sans-serif", 18),
            )
            .map_err(&err)?;
        let areas = root.split_evenly((1, 3));
        for (area, (title, pick)) in areas.iter().zip(panels) {
            let all: Vec<f64> = sets
                .iter()
                .flat_map(|s| pick(s).iter().copied())
                .filter(|v| *v > 0.0)
                .collect();
            let lo = all.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = all.iter().copied().fold(0.0, f64::max);
            let (lo, hi) = if all.is_empty() {
                (1.0, 10.0)
            } else {
                (
                    10f64.powf(lo.log10().floor()),
                    10f64.powf(hi.log10().ceil()).max(10.0 * lo),
                )
            };
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 15))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(44)
                .build_cartesian_2d((lo..hi).log_scale(), 0f64..1.0)
                .map_err(&err)?;
            chart
                .configure_mesh()
                .x_desc("µs")
                .x_label_formatter(&|v: &f64| {
                    if *v >= 1.0 {
                        format!("{v:.0}")
                    } else {
                        format!("{v}")
                    }
                })
                .label_style(("sans-serif", 11))
                .draw()
                .map_err(&err)?;
            for planner in &kinds {
                let values: Vec<f64> = sets
                    .iter()
                    .filter(|s| s.planner == *planner)
                    .flat_map(|s| pick(s).iter().copied())
                    .map(|v| v.max(lo))
                    .collect();
                if values.is_empty() {
                    continue;
                }
                let c = colour(planner, &kinds);
                let n = values.len();
                chart
                    .draw_series(LineSeries::new(ecdf(&values, 400), c.stroke_width(2)))
                    .map_err(&err)?
                    .label(format!("{planner} ({n})"))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c));
            }
            if all.is_empty() {
                chart
                    .draw_series([Text::new("no calls", (lo * 2.0, 0.5), ("sans-serif", 14))])
                    .map_err(&err)?;
            } else {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .position(SeriesLabelPosition::LowerRight)
                    .label_font(("sans-serif", 12))
                    .draw()
                    .map_err(&err)?;
            }
        }
        root.present().map_err(&err)?;
    }
    Ok(out)
}

/// Each packed product's simulated execution time (y) against its lower
/// bound (x), per planner, with the line where the two are equal.
pub fn execution_times(sets: &[ProductTimes]) -> Result<String, DrawError> {
    const NAME: &str = "execution time";
    finite(
        NAME,
        sets.iter()
            .flat_map(|s| s.execution_s.iter().chain(&s.bound_s).copied()),
    )?;
    let err = fail(NAME);
    let kinds = planners(sets.iter().map(|s| s.planner.as_str()));
    let top = sets
        .iter()
        .flat_map(|s| s.execution_s.iter().chain(&s.bound_s).copied())
        .fold(1.0, f64::max)
        * 1.05;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (640, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Execution time per product beside its lower bound",
                ("sans-serif", 18),
            )
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(56)
            .build_cartesian_2d(0f64..top, 0f64..top)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc("lower bound (s): each joint alone, jerk-limited, same stops")
            .y_desc("simulated execution (s)")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(&err)?;
        chart
            .draw_series(LineSeries::new(
                [(0.0, 0.0), (top, top)],
                BLACK.mix(0.5).stroke_width(1),
            ))
            .map_err(&err)?
            .label("at the bound")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.mix(0.5)));
        for planner in &kinds {
            let c = colour(planner, &kinds);
            let pairs: Vec<(f64, f64)> = sets
                .iter()
                .filter(|s| s.planner == *planner)
                .flat_map(|s| s.bound_s.iter().copied().zip(s.execution_s.iter().copied()))
                .collect();
            if pairs.is_empty() {
                continue;
            }
            let n = pairs.len();
            chart
                .draw_series(
                    pairs
                        .into_iter()
                        .map(|p| Circle::new(p, 3, c.mix(0.7).filled())),
                )
                .map_err(&err)?
                .label(format!("{planner} ({n} products)"))
                .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 13))
            .draw()
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(out)
}

/// One point of a study: a series' success rate with its Wilson 95%
/// interval at one value of the studied quantity (a training ratio, the
/// number of products in the order).
#[derive(Debug, Clone, PartialEq)]
pub struct StudyPoint {
    /// The line the point belongs to (a suite, a training ratio).
    pub series: String,
    pub x: f64,
    pub rate: f64,
    pub low: f64,
    pub high: f64,
    /// Scenarios behind the rate.
    pub n: usize,
}

/// Success (y, with its interval as a bar) against a studied quantity (x):
/// one line per series, points in order of x; `title` is the caption and
/// `x_desc` names the x axis.
pub fn study(points: &[StudyPoint], title: &str, x_desc: &str) -> Result<String, DrawError> {
    const NAME: &str = "study";
    finite(
        NAME,
        points.iter().flat_map(|p| [p.x, p.rate, p.low, p.high]),
    )?;
    let err = fail(NAME);
    let series = planners(points.iter().map(|p| p.series.as_str()));
    let (lo, hi) = points
        .iter()
        .map(|p| p.x)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
    let pad = ((hi - lo) * 0.08).max(0.05 * hi.abs().max(1.0));
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (720, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(56)
            .build_cartesian_2d((lo - pad)..(hi + pad), 0f64..1.05)
            .map_err(&err)?;
        // Whole numbers (n, products) are labelled as such, nothing between.
        let whole = points.iter().all(|p| p.x.fract() == 0.0);
        let ticks = if whole {
            ((hi - lo) as usize + 1).clamp(2, 20)
        } else {
            10
        };
        let x_label = move |v: &f64| {
            if !whole {
                // At most three decimals, no trailing zeros (0.3, not
                // 0.30000000000000004).
                let text = format!("{v:.3}");
                text.trim_end_matches('0').trim_end_matches('.').to_owned()
            } else if (v - v.round()).abs() < 1e-6 {
                format!("{:.0}", v.round())
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_labels(ticks)
            .x_label_formatter(&x_label)
            .x_desc(x_desc)
            .y_desc("success rate (Wilson 95% interval)")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(&err)?;
        for (i, name) in series.iter().enumerate() {
            let c = PALETTE[i % PALETTE.len()];
            let mut line: Vec<&StudyPoint> = points.iter().filter(|p| p.series == *name).collect();
            line.sort_by(|a, b| a.x.total_cmp(&b.x));
            let nudge = (i as f64 - (series.len() as f64 - 1.0) / 2.0) * pad * 0.08;
            chart
                .draw_series(LineSeries::new(
                    line.iter().map(|p| (p.x + nudge, p.rate)),
                    c.stroke_width(2),
                ))
                .map_err(&err)?
                .label(name.to_string())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                });
            // The bar's own marker is the point.
            chart
                .draw_series(line.iter().map(|p| {
                    ErrorBar::new_vertical(p.x + nudge, p.low, p.rate, p.high, c.stroke_width(2), 8)
                }))
                .map_err(&err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .label_font(("sans-serif", 13))
            .draw()
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(out)
}
