//! The executed tool path: where the cup tip went, in which stage, and the
//! events along it (sub-goals, the suction's switches, fallbacks, the
//! point of a failure).
//!
//! The path is built from what a `World` sees (commanded joints through
//! forward kinematics, their speed, and the suction), so it is the same
//! for any planner and any world. The sub-goals come from the plan (the
//! report's cup tip at each sub-goal reached), each marked at the sample
//! nearest it: the arm passes through most of them without stopping.

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

    /// The path of `samples` (one per control cycle, in order): stages from
    /// the suction, a `Pick`/`Release` where it switches, and a numbered
    /// `SubGoal` at the sample nearest each of `subgoals` (the cup tip at
    /// each sub-goal the planner reached, in order: the arm passes through
    /// most of them without stopping, so they are taken from the plan, not
    /// guessed from the motion).
    pub fn from_samples(samples: &[Sample], subgoals: &[[f64; 3]]) -> ToolPath {
        let mut subgoals = nearest_samples(samples, subgoals).into_iter().peekable();
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

/// The index of the sample nearest each sub-goal, in order. A sub-goal
/// never lies past the next switch of the suction (a pick's or a
/// release's sub-goal is reached before the suction switches there), so
/// each is looked for from the sample after the previous one's up to the
/// first switch after that (the switch sample included); the indices
/// increase.
fn nearest_samples(samples: &[Sample], subgoals: &[[f64; 3]]) -> Vec<usize> {
    let switches: Vec<usize> = (1..samples.len())
        .filter(|&i| samples[i].suction != samples[i - 1].suction)
        .collect();
    let mut out = Vec::new();
    let mut from = 0;
    for goal in subgoals {
        let end = switches
            .iter()
            .find(|&&s| s > from)
            .map_or(samples.len(), |&s| s + 1);
        let Some(k) = (from..end).min_by(|&a, &b| {
            distance(samples[a].tip, *goal).total_cmp(&distance(samples[b].tip, *goal))
        }) else {
            break;
        };
        out.push(k);
        from = k + 1;
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
        let subgoals = [[0.2, 0.0, 0.5], [0.4, 0.0, 0.5], [0.6, 0.0, 0.5]];
        let path = ToolPath::from_samples(&samples, &subgoals);
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
    fn a_sub_goal_passed_without_stopping_is_marked_where_the_path_is_nearest() {
        // A straight pass at full speed; the sub-goal 4 mm off the path
        // near sample 3, another at the end; nothing moves: none.
        let samples: Vec<Sample> = (0..9)
            .map(|i| Sample {
                tip: [f64::from(i) * 0.01, 0.0, 0.5],
                suction: false,
                speed: 1.0,
            })
            .collect();
        let path = ToolPath::from_samples(&samples, &[[0.031, 0.004, 0.5], [0.08, 0.0, 0.5]]);
        let at: Vec<f64> = path.events.iter().map(|e| e.at[0]).collect();
        assert_eq!(at, [0.03, 0.08]);
        assert!(ToolPath::from_samples(&samples, &[]).events.is_empty());
    }

    #[test]
    fn a_sub_goal_is_not_looked_for_past_the_next_switch() {
        // Carry from x = 0 to 0.4 then release; back to x = 0.1 after it.
        // The sub-goal at x = 0.1 before the release is on the carry, not
        // on the way back.
        let samples: Vec<Sample> = [0.0, 0.1, 0.2, 0.3, 0.4, 0.4, 0.3, 0.1]
            .iter()
            .enumerate()
            .map(|(i, &x)| Sample {
                tip: [x, 0.0, 0.5],
                suction: i < 5,
                speed: 0.01,
            })
            .collect();
        let path = ToolPath::from_samples(
            &samples,
            &[[0.1, 0.0, 0.5], [0.4, 0.0, 0.5], [0.1, 0.0, 0.5]],
        );
        let subgoals: Vec<usize> = path
            .events
            .iter()
            .filter_map(|e| match e.kind {
                EventKind::SubGoal(n) => Some(n),
                _ => None,
            })
            .collect();
        assert_eq!(subgoals, [1, 2, 3]);
        let release = path
            .events
            .iter()
            .position(|e| e.kind == EventKind::Release)
            .expect("a release");
        let third = path
            .events
            .iter()
            .position(|e| e.kind == EventKind::SubGoal(3))
            .expect("a third sub-goal");
        assert!(third > release);
    }

    #[test]
    fn close_points_are_thinned_but_the_end_is_kept() {
        let samples: Vec<Sample> = (0..=100)
            .map(|i| s(f64::from(i) * 0.0001, false, false))
            .collect();
        let path = ToolPath::from_samples(&samples, &[]);
        assert!(path.points.len() < 10, "{}", path.points.len());
        assert_eq!(path.end(), Some([0.01, 0.0, 0.5]));
    }
}
