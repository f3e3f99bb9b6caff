//! The reasoner's view of a cell: the graph of the products seen (x, y, z
//! and whether the order selects each, never whether it is packed, held or
//! missing), the goal input of a chosen node, and the demonstrations'
//! sequence rule that `eval` judges decisions against.

use super::station::{SUCCESS_RADIUS, distance};
use packwright_interface::outcome::{Stage, Violation};
use packwright_interface::world::Seen;
use packwright_interface::{OrderTask, Policy};

pub(crate) fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

/// The reasoner's graph: (x, y, z, I) of every product seen, in inventory
/// order, and the product index of each node.
pub(crate) fn graph(task: &OrderTask, seen: &[Seen]) -> (Vec<[f32; 4]>, Vec<usize>) {
    let mut nodes = Vec::new();
    let mut which = Vec::new();
    for (p, spec) in task.products.iter().enumerate() {
        if let Some(s) = seen.iter().find(|s| s.name == spec.name) {
            let selected = task.slot_of(p).is_some();
            let c = f32s(s.centre);
            nodes.push([c[0], c[1], c[2], if selected { 1.0 } else { 0.0 }]);
            which.push(p);
        }
    }
    (nodes, which)
}

/// The goal the reasoner's classifier is given for node `node`: the goal of
/// the product there (its own centre when the order does not select it).
pub(crate) fn goal_input(
    task: &OrderTask,
    which: &[usize],
    seen: &[Seen],
    node: usize,
) -> [f32; 3] {
    let p = which[node];
    match task.slot_of(p) {
        Some(s) => f32s(task.goal(p, s)),
        None => seen
            .iter()
            .find(|x| x.name == task.products[p].name)
            .map_or([0.0; 3], |x| f32s(x.centre)),
    }
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

/// The product the demonstrations' rule handles next: the first selected,
/// present product (inventory order) not yet in its slot.
pub fn expected_next(task: &OrderTask, seen: &[Seen]) -> Option<usize> {
    task.assignment
        .iter()
        .map(|&(p, _)| p)
        .find(|&p| seen.iter().any(|x| x.name == task.products[p].name) && !in_slot(task, seen, p))
}

/// Runs the reasoner alone over a whole episode from the products `seen`
/// at the start, moving products as the demonstrator would (lifted by the
/// cell's lift, then into their slot), and compares every decision with
/// the demonstrated rule (inventory order): the first wrong decision.
pub fn reasoner_trial(
    policy: &dyn Policy,
    task: &OrderTask,
    seen: &[Seen],
) -> Result<(), Violation> {
    let mut seen = seen.to_vec();
    let name = |p: usize| task.products[p].name.clone();
    for _ in 0..=task.assignment.len() {
        let Some(want) = expected_next(task, &seen) else {
            return Ok(());
        };
        let (nodes, which) = graph(task, &seen);
        let choice = policy.reason(&nodes, &|n| {
            n.map_or([0.0; 3], |n| goal_input(task, &which, &seen, n))
        });
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
        let held = name(want);
        if let Some(x) = seen.iter_mut().find(|x| x.name == held) {
            x.centre[2] += task.cell.lift;
        }
        let (nodes, which) = graph(task, &seen);
        let goal = f32s(task.goal(want, s));
        let choice = policy.reason(&nodes, &|_| goal);
        if choice.node.is_some() || choice.label != s + 1 {
            return Err(Violation::OutOfSequence {
                stage: Stage::Placing,
                chosen: choice.node.map(|n| name(which[n])),
                label: choice.label,
                expected: held,
                expected_label: s + 1,
            });
        }
        if let Some(x) = seen.iter_mut().find(|x| x.name == held) {
            x.centre = task.goal(want, s);
        }
    }
    Err(Violation::DidNotFinish)
}
