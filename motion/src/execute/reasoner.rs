//! The reasoner's view of a cell: the graph of the products seen (where
//! they are, their goals, whether the order selects each; never whether
//! one is packed, held or missing), chained in the taught sequence order;
//! the cell's slots; the decisions a demonstration implies; and the trial
//! `eval` judges a reasoner by.

use super::station::{SUCCESS_RADIUS, distance};
use packwright_interface::outcome::{Stage, Violation};
use packwright_interface::world::Seen;
use packwright_interface::{Choice, Graph, Node, OrderTask, Policy, SequenceRule};

pub(crate) fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

/// The reasoner's graph of the products `seen`, chained in `rule`'s order,
/// with the goal of `held` (a product index) if one is in the cup; and the
/// product index of each node.
pub fn graph(
    task: &OrderTask,
    seen: &[Seen],
    rule: &SequenceRule,
    held: Option<usize>,
) -> (Graph, Vec<usize>) {
    let names: Vec<&str> = task.products.iter().map(|p| p.name.as_str()).collect();
    let mut g = Graph::default();
    let mut which = Vec::new();
    for p in rule.chain(&names) {
        if let Some(s) = seen.iter().find(|s| s.name == names[p]) {
            let centre = f32s(s.centre);
            let slot = task.slot_of(p);
            g.nodes.push(Node {
                centre,
                height: task.products[p].size[2] as f32,
                selected: slot.is_some(),
                goal: slot.map_or(centre, |s| f32s(task.goal(p, s))),
            });
            which.push(p);
        }
    }
    g.slots = (0..task.cell.slots.len())
        .map(|s| {
            let [x, y, _] = task.slot_rim(s);
            [x as f32, y as f32, 0.0]
        })
        .collect();
    g.held_goal = held
        .and_then(|p| task.slot_of(p).map(|s| f32s(task.goal(p, s))))
        .unwrap_or_default();
    (g, which)
}

/// Whether product `p` already sits in its slot.
pub(crate) fn in_slot(task: &OrderTask, seen: &[Seen], p: usize) -> bool {
    let Some(s) = task.slot_of(p) else {
        return false;
    };
    seen.iter()
        .find(|x| x.name == task.products[p].name)
        .is_some_and(|x| distance(x.centre, task.goal(p, s)) <= SUCCESS_RADIUS)
}

/// The product the taught rule handles next: the first selected, present
/// product in the rule's order that is not yet in its slot.
pub fn expected_next(task: &OrderTask, seen: &[Seen], rule: &SequenceRule) -> Option<usize> {
    let names: Vec<&str> = task.products.iter().map(|p| p.name.as_str()).collect();
    rule.chain(&names).into_iter().find(|&p| {
        task.slot_of(p).is_some()
            && seen.iter().any(|x| x.name == names[p])
            && !in_slot(task, seen, p)
    })
}

/// `seen` with product `p` lifted by the cell's lift (in the cup).
pub(crate) fn lifted(task: &OrderTask, seen: &mut [Seen], p: usize) {
    if let Some(x) = seen.iter_mut().find(|x| x.name == task.products[p].name) {
        x.centre[2] += task.cell.lift;
    }
}

/// `seen` with product `p` in slot `s`.
fn placed(task: &OrderTask, seen: &mut [Seen], p: usize, s: usize) {
    if let Some(x) = seen.iter_mut().find(|x| x.name == task.products[p].name) {
        x.centre = task.goal(p, s);
    }
}

/// The decisions a demonstration implies: from the products `seen` at the
/// start, the demonstrator handles `sequence` (product indices, each
/// selected) in turn; before each pick the graph and the node chosen,
/// then, with the product lifted, the graph and the box with its slot.
/// The products move as the demonstrator moves them.
pub fn demonstrated_decisions(
    task: &OrderTask,
    seen: &[Seen],
    sequence: &[usize],
    rule: &SequenceRule,
) -> Vec<(Graph, Choice)> {
    let mut seen = seen.to_vec();
    let mut out = Vec::new();
    for &p in sequence {
        let Some(s) = task.slot_of(p) else {
            continue;
        };
        let (g, which) = graph(task, &seen, rule, None);
        let Some(node) = which.iter().position(|&q| q == p) else {
            continue;
        };
        out.push((
            g,
            Choice {
                node: Some(node),
                label: 0,
            },
        ));
        lifted(task, &mut seen, p);
        let (g, _) = graph(task, &seen, rule, Some(p));
        out.push((
            g,
            Choice {
                node: None,
                label: s + 1,
            },
        ));
        placed(task, &mut seen, p, s);
    }
    out
}

/// Runs the reasoner alone over a whole episode from the products `seen`
/// at the start, moving products as the demonstrator would (lifted by the
/// cell's lift, then into their slot), and compares every decision with
/// the policy's taught rule: the first wrong decision.
pub fn reasoner_trial(
    policy: &dyn Policy,
    task: &OrderTask,
    seen: &[Seen],
) -> Result<(), Violation> {
    let rule = policy.sequence();
    let mut seen = seen.to_vec();
    let name = |p: usize| task.products[p].name.clone();
    for _ in 0..=task.assignment.len() {
        let Some(want) = expected_next(task, &seen, &rule) else {
            return Ok(());
        };
        let (g, which) = graph(task, &seen, &rule, None);
        let choice = policy.reason(&g);
        let got = choice.node.map(|n| which[n]);
        if got != Some(want) || choice.label != 0 {
            return Err(Violation::OutOfSequence {
                stage: Stage::Picking,
                chosen: got.map(name),
                label: choice.label,
                expected: name(want),
                expected_label: 0,
            });
        }
        let s = task.slot_of(want).unwrap_or(0);
        lifted(task, &mut seen, want);
        let (g, which) = graph(task, &seen, &rule, Some(want));
        let choice = policy.reason(&g);
        if choice.node.is_some() || choice.label != s + 1 {
            return Err(Violation::OutOfSequence {
                stage: Stage::Placing,
                chosen: choice.node.map(|n| name(which[n])),
                label: choice.label,
                expected: name(want),
                expected_label: s + 1,
            });
        }
        placed(task, &mut seen, want, s);
    }
    Err(Violation::DidNotFinish)
}
