//! What a recording shows besides the frames, each at its sim time: the
//! tool path with its sub-goals, picks and releases (the same path
//! `execute --svg` draws, `packwright_draw::ToolPath`, from the commanded
//! joints), the learned planner's fallbacks, and the reasoner's
//! decisions with their scores.

use crate::journal::{Cycle, Decision, Entries};
use nalgebra::Isometry3;
use packwright_draw::{EventKind, Sample, ToolPath};
use packwright_interface::outcome::{Fallback, Report};
use packwright_interface::{Graph, OrderTask, SlotSpec};
use packwright_kinematics::Arm;

/// The reasoner's scores for one graph: one per node then the box's
/// (`nodes`), and the slot pointer's, one per slot (`slots`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scores {
    pub nodes: Vec<f32>,
    pub slots: Vec<f32>,
}

/// Scores a reasoner graph (the model's own numbers).
pub type Scorer<'a> = &'a (dyn Fn(&Graph) -> Scores + Sync);

/// One run to record.
#[derive(Clone, Copy)]
pub struct Run<'a> {
    /// The recording's name in the viewer (the order or scenario, and the
    /// planner).
    pub name: &'a str,
    pub arm: &'a Arm,
    pub task: &'a OrderTask,
    pub entries: &'a Entries,
    pub report: &'a Report,
    /// The learned planner's scores, when there is a model.
    pub scorer: Option<Scorer<'a>>,
}

/// A point of the tool path where something happened.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedEvent {
    pub time: f64,
    pub at: [f64; 3],
    pub kind: EventKind,
}

/// The tool path of `cycles` (the cup tip of the commanded joints) and
/// its sub-goals (`subgoals`: the cup tip at each sub-goal reached, as
/// the report gives them, marked at the nearest cycle), picks and
/// releases, with the time of their cycle.
pub fn tool_path(
    arm: &Arm,
    task: &OrderTask,
    cycles: &[Cycle],
    subgoals: &[[f64; 3]],
) -> (ToolPath, Vec<TimedEvent>) {
    let b = task.cell.base;
    let base = Isometry3::translation(b[0], b[1], b[2]);
    let samples: Vec<Sample> = cycles
        .iter()
        .map(|c| {
            let tip = arm.tool_tip(&base, &c.commanded, task.cell.suction);
            Sample {
                tip: [tip.x, tip.y, tip.z],
                suction: c.suction,
                speed: c.speed,
            }
        })
        .collect();
    let path = ToolPath::from_samples(&samples, subgoals);
    // The path's events are in sample order, each at its sample's tip:
    // walking both finds each event's cycle.
    let mut timed = Vec::new();
    let mut i = 0;
    for e in &path.events {
        while i < samples.len() && samples[i].tip != e.at {
            i += 1;
        }
        let Some(cycle) = cycles.get(i) else {
            break;
        };
        timed.push(TimedEvent {
            time: cycle.time,
            at: e.at,
            kind: e.kind.clone(),
        });
    }
    (path, timed)
}

/// Each fallback of `report` with its time: when the sub-goal planner was
/// asked for the sub-goal whose rollout fell short, within the handling
/// of its product (from the decision that picked it to the next picking
/// decision); the picking decision's time when that question is not
/// found, the end of the run when the decision is not either.
pub fn fallback_times<'r>(entries: &Entries, report: &'r Report) -> Vec<(f64, &'r Fallback)> {
    let picks: Vec<(f64, &str)> = entries
        .decisions
        .iter()
        .filter_map(|d| Some((d.time, d.chosen()?)))
        .collect();
    let end = entries.frames.last().map_or(report.time_s, |f| f.time);
    report
        .fallbacks
        .iter()
        .map(|f| {
            let handled = picks.iter().position(|(_, p)| *p == f.product);
            let time = handled.map_or(end, |k| {
                let from = picks[k].0;
                let until = picks.get(k + 1).map_or(f64::INFINITY, |n| n.0);
                entries
                    .planned
                    .iter()
                    .find(|p| {
                        p.time >= from
                            && p.time < until
                            && p.stage == f.stage
                            && p.index + 1 == f.subgoal
                    })
                    .map_or(from, |p| p.time)
            });
            (time, f)
        })
        .collect()
}

impl Decision {
    /// The product a picking decision chose.
    pub fn chosen(&self) -> Option<&str> {
        self.choice
            .node
            .and_then(|n| self.nodes.get(n))
            .map(String::as_str)
    }

    /// The decision for people: what was chosen, then every option's
    /// score (`scores`, when there is a model); `slots` are the cell's.
    pub fn describe(&self, slots: &[SlotSpec], scores: Option<&Scores>) -> String {
        let slot = |label: usize| {
            label
                .checked_sub(1)
                .and_then(|s| slots.get(s))
                .map_or_else(|| format!("label {label}"), |s| format!("slot {}", s.name))
        };
        let mut text = match self.chosen() {
            Some(p) => format!("picking: chose {p}"),
            None => format!("placing: chose the box, {}", slot(self.choice.label)),
        };
        if let Some(s) = scores {
            let nodes: Vec<String> = self
                .nodes
                .iter()
                .map(String::as_str)
                .chain(["box"])
                .zip(&s.nodes)
                .map(|(n, v)| format!("{n} {v:.2}"))
                .collect();
            text.push_str(&format!("; scores: {}", nodes.join(", ")));
            if self.choice.node.is_none() && !s.slots.is_empty() {
                let slots: Vec<String> = slots
                    .iter()
                    .zip(&s.slots)
                    .map(|(slot, v)| format!("{} {v:.2}", slot.name))
                    .collect();
                text.push_str(&format!("; slot scores: {}", slots.join(", ")));
            }
        }
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::journal::{Decision, Planned};
    use packwright_interface::Choice;
    use packwright_interface::outcome::{PlannerKind, Shortfall, Stage, Timing};

    fn decision(time: f64, node: Option<usize>, label: usize) -> Decision {
        Decision {
            time,
            graph: Graph::default(),
            nodes: vec!["jam".into(), "tea".into()],
            choice: Choice { node, label },
        }
    }

    fn fallback(product: &str, stage: Stage, subgoal: usize) -> Fallback {
        Fallback {
            product: product.into(),
            stage,
            subgoal,
            why: Shortfall::Short {
                steps: 60,
                distance_m: 0.01,
            },
            expert_from: None,
        }
    }

    /// A fallback is at the question for its sub-goal within its
    /// product's handling; without one, at the product's pick; for a
    /// product never picked, at the end.
    #[test]
    fn fallbacks_are_at_the_question_for_their_sub_goal() {
        let planned = |time, stage, index| Planned {
            time,
            stage,
            index,
            tip: [0.0; 3],
        };
        let entries = Entries {
            decisions: vec![
                decision(1.0, Some(1), 0),
                decision(2.0, None, 3),
                decision(5.0, Some(0), 0),
            ],
            planned: vec![
                planned(1.0, Stage::Picking, 0),
                planned(2.0, Stage::Placing, 1),
                planned(5.0, Stage::Picking, 0),
                planned(6.0, Stage::Placing, 1),
            ],
            ..Entries::default()
        };
        let report = Report {
            planner: PlannerKind::Learned,
            products: Vec::new(),
            complete: true,
            collisions: Vec::new(),
            disturbed: Vec::new(),
            time_s: 9.0,
            fallbacks: vec![
                fallback("tea", Stage::Placing, 2),
                fallback("jam", Stage::Placing, 2),
                fallback("jam", Stage::Picking, 3),
                fallback("soap", Stage::Picking, 1),
            ],
            violations: Vec::new(),
            timing: Timing::default(),
            subgoals: Vec::new(),
        };
        let times: Vec<f64> = fallback_times(&entries, &report)
            .into_iter()
            .map(|(t, _)| t)
            .collect();
        assert_eq!(times, [2.0, 6.0, 5.0, 9.0]);
        let slots: Vec<SlotSpec> = ["k1", "k2", "k3"]
            .iter()
            .map(|n| SlotSpec {
                name: (*n).into(),
                position: [0.0; 2],
                box_index: 0,
            })
            .collect();
        let text = entries.decisions[1].describe(
            &slots,
            Some(&Scores {
                nodes: vec![1.0, 2.0, -3.0],
                slots: vec![0.5, 0.25, 4.0],
            }),
        );
        assert_eq!(
            text,
            "placing: chose the box, slot k3; scores: jam 1.00, tea 2.00, box -3.00; \
slot scores: k1 0.50, k2 0.25, k3 4.00"
        );
    }
}
