//! The executed tool path: where the cup tip went, in which stage, and the
//! events along it (sub-goals, the suction's switches, fallbacks, the
//! point of a failure).
//!
//! The path is built from what a `World` sees (commanded joints through
//! forward kinematics, their speed, and the suction), so it is the same
//! for any planner and any world. A sub-goal is where the arm stops or,
//! blending through a via point, slows below [`ToolPath::SLOW`] of its top
//! speed: on the expert's packages these are exactly its sub-goals but the
//! approach point, which it passes at speed.

use crate::svg::{Attrs, Svg, num, points};
use crate::view::View;

const RED: &str = "#d62728";

/// What the arm is doing, from the suction's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Suction off, going to a product (or from the start).
    Approach,
    /// Suction on: carrying a product.
    Carry,
    /// Suction off after a release, until the first sub-goal after it.
    Retreat,
}

impl Stage {
    /// The CSS class and legend name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Approach => "approach",
            Stage::Carry => "carry",
            Stage::Retreat => "retreat",
        }
    }

    /// The stroke colour.
    pub fn colour(self) -> &'static str {
        match self {
            Stage::Approach => "#1f77b4",
            Stage::Carry => "#2ca02c",
            Stage::Retreat => "#9467bd",
        }
    }
}

/// One control cycle as the world saw it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The cup tip (world frame, m).
    pub tip: [f64; 3],
    /// Whether the suction is on.
    pub suction: bool,
    /// The commanded joints' largest change since the cycle before (rad):
    /// 0 at rest.
    pub speed: f64,
}

/// Something that happened at a point of the path.
#[derive(Debug, Clone, PartialEq)]
pub enum EventKind {
    /// The n-th sub-goal (from 1): the arm stopped or slowed there.
    SubGoal(usize),
    /// The suction switched on.
    Pick,
    /// The suction switched off.
    Release,
    /// A stage handed to RRT-Connect, and why (for people).
    Fallback(String),
    /// Where the arm stopped on a failure, and why.
    Failure(String),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    pub at: [f64; 3],
    pub kind: EventKind,
}

/// A path to draw: points with their stage (thinned: consecutive points at
/// least [`ToolPath::STEP`] apart, stage changes and the end kept) and
/// events.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ToolPath {
    pub points: Vec<([f64; 3], Stage)>,
    pub events: Vec<Event>,
}

impl ToolPath {
    /// The thinning distance (m).
    pub const STEP: f64 = 0.002;

    /// A sample is slow below this share of the path's top speed.
    pub const SLOW: f64 = 0.1;

    /// The path of `samples` (one per control cycle, in order): stages from
    /// the suction, a `Pick`/`Release` where it switches, a numbered
    /// `SubGoal` at the slowest sample of every slow stretch after the arm
    /// first moved.
    pub fn from_samples(samples: &[Sample]) -> ToolPath {
        let mut subgoals = slow_points(samples).into_iter().peekable();
        let mut path = ToolPath::default();
        let mut stage = Stage::Approach;
        let mut moved_since_release = false;
        let mut suction = false;
        let mut n = 0;
        for (i, s) in samples.iter().enumerate() {
            if s.suction != suction {
                suction = s.suction;
                path.events.push(Event {
                    at: s.tip,
                    kind: if suction {
                        EventKind::Pick
                    } else {
                        EventKind::Release
                    },
                });
                stage = if suction {
                    Stage::Carry
                } else {
                    moved_since_release = false;
                    Stage::Retreat
                };
            }
            if s.speed > 0.0 {
                moved_since_release = true;
            }
            let last = path.points.last().copied();
            let keep = match last {
                None => true,
                Some((p, st)) => {
                    st != stage || distance(p, s.tip) >= Self::STEP || i + 1 == samples.len()
                }
            };
            if keep {
                path.points.push((s.tip, stage));
            }
            if subgoals.next_if_eq(&i).is_some() {
                n += 1;
                path.events.push(Event {
                    at: s.tip,
                    kind: EventKind::SubGoal(n),
                });
                // The sub-goal that ends a retreat still belongs to it.
                if stage == Stage::Retreat && moved_since_release {
                    stage = Stage::Approach;
                }
            }
        }
        path
    }

    /// Where the path ends (the arm's last commanded tip).
    pub fn end(&self) -> Option<[f64; 3]> {
        self.points.last().map(|(p, _)| *p)
    }
}

/// Draws `path` in `view` (`which`: `top` or `side`, its class): one
/// polyline per run of a stage, the start, and every event.
pub(crate) fn draw(svg: &mut Svg, path: &ToolPath, view: &View, which: &str) {
    svg.group(Attrs::new().s("class", &format!("path path-{which}")));
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut stage: Option<Stage> = None;
    let flush = |svg: &mut Svg, run: &[(f64, f64)], stage: Stage| {
        if run.len() > 1 {
            svg.el(
                "polyline",
                Attrs::new()
                    .s("class", stage.name())
                    .s("points", &points(run))
                    .s("fill", "none")
                    .s("stroke", stage.colour())
                    .n("stroke-width", 1.6),
            );
        }
    };
    for (p, st) in &path.points {
        let xy = view.px(*p);
        match stage {
            Some(s) if s == *st => run.push(xy),
            Some(s) => {
                flush(svg, &run, s);
                // Join the runs at the point where the stage changed.
                let joint = run.last().copied();
                run.clear();
                run.extend(joint);
                run.push(xy);
                stage = Some(*st);
            }
            None => {
                run.push(xy);
                stage = Some(*st);
            }
        }
    }
    if let Some(s) = stage {
        flush(svg, &run, s);
    }
    if let Some((start, _)) = path.points.first() {
        let (x, y) = view.px(*start);
        svg.el(
            "rect",
            Attrs::new()
                .s("class", "start")
                .n("x", x - 4.0)
                .n("y", y - 4.0)
                .n("width", 8.0)
                .n("height", 8.0)
                .s("fill", "black"),
        );
    }
    for e in &path.events {
        let (x, y) = view.px(e.at);
        match &e.kind {
            EventKind::SubGoal(n) => {
                svg.el(
                    "circle",
                    Attrs::new()
                        .s("class", "subgoal")
                        .n("cx", x)
                        .n("cy", y)
                        .n("r", 3.0)
                        .s("fill", "white")
                        .s("stroke", "black"),
                );
                svg.text(
                    Attrs::new()
                        .n("x", x + 4.0)
                        .n("y", y - 4.0)
                        .n("font-size", 9.0),
                    &n.to_string(),
                );
            }
            EventKind::Pick | EventKind::Release => {
                let (class, fill) = if e.kind == EventKind::Pick {
                    ("pick", "#2ca02c")
                } else {
                    ("release", "#9467bd")
                };
                svg.el(
                    "circle",
                    Attrs::new()
                        .s("class", class)
                        .n("cx", x)
                        .n("cy", y)
                        .n("r", 2.0)
                        .s("fill", fill),
                );
            }
            EventKind::Fallback(why) => {
                svg.group(Attrs::new().s("class", "fallback"));
                svg.title(&format!("fallback: {why}"));
                svg.el(
                    "path",
                    Attrs::new()
                        .s(
                            "d",
                            &format!(
                                "M {} {} L {} {} L {} {} L {} {} Z",
                                num(x),
                                num(y - 7.0),
                                num(x + 7.0),
                                num(y),
                                num(x),
                                num(y + 7.0),
                                num(x - 7.0),
                                num(y)
                            ),
                        )
                        .s("fill", "none")
                        .s("stroke", "#ff7f0e")
                        .n("stroke-width", 2.0),
                );
                svg.end();
            }
            EventKind::Failure(why) => {
                svg.group(Attrs::new().s("class", "failure"));
                svg.title(&format!("failure: {why}"));
                svg.el(
                    "path",
                    Attrs::new()
                        .s(
                            "d",
                            &format!(
                                "M {} {} L {} {} M {} {} L {} {}",
                                num(x - 8.0),
                                num(y - 8.0),
                                num(x + 8.0),
                                num(y + 8.0),
                                num(x - 8.0),
                                num(y + 8.0),
                                num(x + 8.0),
                                num(y - 8.0)
                            ),
                        )
                        .s("stroke", RED)
                        .n("stroke-width", 3.0),
                );
                svg.end();
            }
        }
    }
    svg.end();
}

/// The slowest sample of every stretch of samples slower than
/// [`ToolPath::SLOW`] of the top speed, after the first fast one.
fn slow_points(samples: &[Sample]) -> Vec<usize> {
    let peak = samples.iter().map(|s| s.speed).fold(0.0, f64::max);
    let slow = |i: usize| samples[i].speed <= peak * ToolPath::SLOW;
    let mut out = Vec::new();
    let mut i = (0..samples.len())
        .find(|&i| !slow(i))
        .unwrap_or(samples.len());
    while i < samples.len() {
        if !slow(i) {
            i += 1;
            continue;
        }
        let start = i;
        while i < samples.len() && slow(i) {
            i += 1;
        }
        // The first of the slowest.
        let k = (start..i)
            .min_by(|&a, &b| samples[a].speed.total_cmp(&samples[b].speed))
            .unwrap_or(start);
        out.push(k);
    }
    out
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(x: f64, suction: bool, resting: bool) -> Sample {
        Sample {
            tip: [x, 0.0, 0.5],
            suction,
            speed: if resting { 0.0 } else { 0.01 },
        }
    }

    #[test]
    fn stages_follow_the_suction_and_stops_are_numbered() {
        let samples = [
            s(0.0, false, true),
            s(0.1, false, false),
            s(0.2, false, true), // rest 1
            s(0.2, true, true),  // pick
            s(0.3, true, false),
            s(0.4, true, true),  // rest 2
            s(0.4, false, true), // release
            s(0.5, false, false),
            s(0.6, false, true), // rest 3: retreat ends
            s(0.7, false, false),
        ];
        let path = ToolPath::from_samples(&samples);
        let stages: Vec<Stage> = path.points.iter().map(|(_, st)| *st).collect();
        use Stage::*;
        assert_eq!(
            stages,
            [
                Approach, Approach, Approach, Carry, Carry, Carry, Retreat, Retreat, Retreat,
                Approach
            ]
        );
        let kinds: Vec<&EventKind> = path.events.iter().map(|e| &e.kind).collect();
        assert_eq!(
            kinds,
            [
                &EventKind::SubGoal(1),
                &EventKind::Pick,
                &EventKind::SubGoal(2),
                &EventKind::Release,
                &EventKind::SubGoal(3),
            ]
        );
        assert_eq!(path.end(), Some([0.7, 0.0, 0.5]));
    }

    #[test]
    fn a_via_point_passed_slowly_is_a_sub_goal() {
        // Fast, slowing to a tenth at sample 3, fast again, a stop at the end.
        let speeds = [0.0, 1.0, 0.5, 0.05, 0.08, 0.5, 1.0, 0.3, 0.0];
        let samples: Vec<Sample> = speeds
            .iter()
            .enumerate()
            .map(|(i, &speed)| Sample {
                tip: [i as f64 * 0.01, 0.0, 0.5],
                suction: false,
                speed,
            })
            .collect();
        let path = ToolPath::from_samples(&samples);
        let at: Vec<f64> = path.events.iter().map(|e| e.at[0]).collect();
        assert_eq!(at, [0.03, 0.08]);
        // Nothing moves: no sub-goal.
        let still = vec![samples[0]; 5];
        assert!(ToolPath::from_samples(&still).events.is_empty());
    }

    #[test]
    fn close_points_are_thinned_but_the_end_is_kept() {
        let samples: Vec<Sample> = (0..=100)
            .map(|i| s(f64::from(i) * 0.0001, false, false))
            .collect();
        let path = ToolPath::from_samples(&samples);
        assert!(path.points.len() < 10, "{}", path.points.len());
        assert_eq!(path.end(), Some([0.01, 0.0, 0.5]));
    }
}
