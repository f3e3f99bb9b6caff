//! Packing orders end to end in the simulator, with the scripted expert and
//! with RRT-Connect.

mod common;
use common::bench_cell;

use packwright_runtime::execute::{self, OrderTask, Outcome, PlannerKind};
use packwright_runtime::robot::Arm;
use packwright_runtime::scene::{Placement, ProductSpec};
use packwright_runtime::sim::Simulator;

fn products() -> Vec<(ProductSpec, [f64; 2])> {
    let p = |name: &str, size: [f64; 3], at: [f64; 2]| {
        (
            ProductSpec {
                name: name.into(),
                size,
                mass: 0.2,
            },
            at,
        )
    };
    vec![
        p("A", [0.05; 3], [0.50, -0.20]),
        p("B", [0.05; 3], [0.62, -0.20]),
        p("C", [0.05; 3], [0.74, -0.20]),
        p("D", [0.05; 3], [0.56, -0.38]),
        p("E", [0.06, 0.04, 0.05], [0.68, -0.38]),
    ]
}

/// Runs an order: `assign` maps product names to slot names; `packed`
/// products start in their slots, `missing` ones are absent.
fn run(
    assign: &[(&str, &str)],
    packed: &[&str],
    missing: &[&str],
    planner: PlannerKind,
) -> execute::Report {
    let arm = Arm::ur10();
    let cell = bench_cell();
    let inventory = products();
    let specs: Vec<ProductSpec> = inventory.iter().map(|(s, _)| s.clone()).collect();
    let mut assignment: Vec<(usize, usize)> = assign
        .iter()
        .map(|(p, s)| {
            let pi = specs.iter().position(|x| x.name == *p).expect("product");
            let si = cell.slots.iter().position(|x| x.name == *s).expect("slot");
            (pi, si)
        })
        .collect();
    assignment.sort_unstable();
    let task = OrderTask {
        cell: cell.clone(),
        products: specs,
        assignment,
    };
    let placements: Vec<Placement> = inventory
        .iter()
        .enumerate()
        .filter(|(_, (s, _))| !missing.contains(&s.name.as_str()))
        .map(|(i, (s, at))| {
            let centre = match task.assignment.iter().find(|(p, _)| *p == i) {
                Some(&(p, slot)) if packed.contains(&s.name.as_str()) => task.goal(p, slot),
                _ => [at[0], at[1], s.size[2] / 2.0],
            };
            Placement {
                product: s.clone(),
                centre,
            }
        })
        .collect();
    let start = execute::home(&arm, &cell).expect("a start pose");
    let mut sim =
        Simulator::new(arm.clone(), &cell, &placements, start).expect("a valid simulation");
    execute::run(&mut sim, &arm, &task, planner)
}

fn assert_packed(report: &execute::Report) {
    for p in &report.products {
        assert!(
            matches!(p.outcome, Outcome::Packed | Outcome::AlreadyPacked),
            "{} -> {}: {:?} (error {:?})",
            p.product,
            p.slot,
            p.outcome,
            p.error_m
        );
    }
    assert!(report.complete, "{report:#?}");
}

#[test]
fn the_expert_packs_an_order() {
    let report = run(
        &[("C", "g1"), ("A", "g3"), ("E", "g2")],
        &[],
        &[],
        PlannerKind::Expert,
    );
    assert_packed(&report);
    for p in &report.products {
        assert!(p.error_m.is_some_and(|e| e < 0.02));
        assert!(p.execution_s > 1.0, "moving takes simulated time");
    }
}

#[test]
fn rrt_connect_packs_an_order() {
    let report = run(
        &[("B", "g4"), ("D", "g2")],
        &[],
        &[],
        PlannerKind::Rrt { seed: 1 },
    );
    assert_packed(&report);
}

#[test]
fn a_worker_started_package_is_finished_and_missing_stock_waits() {
    let report = run(
        &[("A", "g1"), ("C", "g2"), ("E", "g3")],
        &["C"],
        &[],
        PlannerKind::Expert,
    );
    assert_packed(&report);
    assert_eq!(report.products[1].outcome, Outcome::AlreadyPacked);
    let short = run(
        &[("A", "g1"), ("C", "g2")],
        &[],
        &["A"],
        PlannerKind::Expert,
    );
    assert_eq!(short.products[0].outcome, Outcome::Waiting);
    assert_eq!(short.products[1].outcome, Outcome::Packed);
    assert!(
        !short.complete,
        "a package with a missing product is not complete"
    );
}
