//! Packing orders end to end in the simulator, with the scripted expert,
//! with RRT-Connect, and with the learned loop driven by scripted policies
//! (its fallbacks and its violations).

mod common;
use common::bench_cell;

use packwright_interface::OrderTask;
use packwright_interface::Policy;
use packwright_interface::outcome::{Outcome, Report, Shortfall, Stage, Violation};
use packwright_interface::record;
use packwright_interface::scene::{BoxSpec, CellScene, Placement, ProductSpec, SlotSpec};
use packwright_interface::{Choice, Graph, Node, SequenceRule, SubGoalQuery};
use packwright_kinematics::{Arm, Joints};
use packwright_motion::execute::{self, Planner};
use packwright_motion::expert;
use packwright_sim::Simulator;

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

/// An order ready to run: `assign` maps product names to slot names;
/// `packed` products start in their slots, `missing` ones are absent.
fn episode(
    assign: &[(&str, &str)],
    packed: &[&str],
    missing: &[&str],
) -> (Arm, OrderTask, Simulator) {
    episode_in(bench_cell(), assign, packed, missing)
}

/// [`episode`] in `cell` (the bench cell's products).
fn episode_in(
    cell: CellScene,
    assign: &[(&str, &str)],
    packed: &[&str],
    missing: &[&str],
) -> (Arm, OrderTask, Simulator) {
    episode_of(cell, products(), assign, packed, missing)
}

/// [`episode_in`] with `inventory`'s products where it puts them.
fn episode_of(
    cell: CellScene,
    inventory: Vec<(ProductSpec, [f64; 2])>,
    assign: &[(&str, &str)],
    packed: &[&str],
    missing: &[&str],
) -> (Arm, OrderTask, Simulator) {
    let arm = Arm::ur10();
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
    let sim = Simulator::new(arm.clone(), &cell, &placements, start).expect("a valid simulation");
    (arm, task, sim)
}

fn run(assign: &[(&str, &str)], packed: &[&str], missing: &[&str], planner: Planner) -> Report {
    let (arm, task, mut sim) = episode(assign, packed, missing);
    execute::run(&mut sim, &arm, &task, &planner)
}

/// The learned loop with `policy`, RRT-Connect seeded with 3.
fn run_learned(sim: &mut Simulator, arm: &Arm, task: &OrderTask, policy: &dyn Policy) -> Report {
    execute::run(sim, arm, task, &Planner::Learned { policy, seed: 3 })
}

fn assert_packed(report: &Report) {
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
        Planner::Expert,
    );
    assert_packed(&report);
    for p in &report.products {
        assert!(p.error_m.is_some_and(|e| e < 0.02));
        assert!(p.execution_s > 1.0, "moving takes simulated time");
    }
}

/// A planning budget that has run out stops the arm with its own
/// failure, for each planner; the first product is not moved.
#[test]
fn planning_past_its_budget_stops_the_arm() {
    use packwright_interface::outcome::{Budget, Failure};
    use packwright_motion::execute::PlanningBudget;
    use std::time::Duration;
    let assign = [("C", "g1"), ("A", "g3")];
    let cases = [
        (Duration::ZERO, Duration::from_secs(60), Budget::SubGoal),
        (Duration::from_secs(60), Duration::ZERO, Budget::Package),
    ];
    for (subgoal, package, which) in cases {
        let (_, task, _) = episode(&assign, &[], &[]);
        let policy = Scripted::new(task);
        let learned = Planner::Learned {
            policy: &policy,
            seed: 3,
        };
        for planner in [Planner::Expert, Planner::Rrt { seed: 1 }, learned] {
            let (arm, task, mut sim) = episode(&assign, &[], &[]);
            let budget = PlanningBudget { subgoal, package };
            let report = execute::run_within(&mut sim, &arm, &task, &planner, budget);
            assert!(!report.complete);
            match &report.products[0].outcome {
                Outcome::Failed(Failure::OutOfTime {
                    subgoal: 1, budget, ..
                }) => assert_eq!(*budget, which),
                other => panic!("{other:?}"),
            }
            assert_eq!(report.products[1].outcome, Outcome::NotAttempted);
            assert_eq!(report.products[0].execution_s, 0.0, "the arm did not move");
        }
    }
    // The default budget is far from any plan: the same order packs.
    let (arm, task, mut sim) = episode(&assign, &[], &[]);
    let budget = PlanningBudget::default();
    assert_packed(&execute::run_within(
        &mut sim,
        &arm,
        &task,
        &Planner::Expert,
        budget,
    ));
}

#[test]
fn execution_is_above_its_lower_bound_and_a_slower_arm_takes_longer() {
    let assign = [("C", "g1"), ("A", "g3")];
    let full = run(&assign, &[], &[], Planner::Expert);
    let (arm, task, _) = episode(&assign, &[], &[]);
    let slow_arm = arm.at_speed(0.5);
    let start = execute::home(&slow_arm, &task.cell).expect("a start pose");
    let placements: Vec<Placement> = products()
        .into_iter()
        .map(|(s, at)| Placement {
            centre: [at[0], at[1], s.size[2] / 2.0],
            product: s,
        })
        .collect();
    let mut sim = Simulator::new(slow_arm.clone(), &task.cell, &placements, start).expect("sim");
    let slow = execute::run(&mut sim, &slow_arm, &task, &Planner::Expert);
    assert_packed(&full);
    assert_packed(&slow);
    for (f, s) in full.products.iter().zip(&slow.products) {
        // No planner beats the bound; settling (0.6 s) does not scale.
        assert!(f.bound_s > 1.0 && f.execution_s >= f.bound_s, "{f:?}");
        assert!(s.execution_s >= s.bound_s, "{s:?}");
        let (fm, sm) = (f.execution_s - 0.6, s.execution_s - 0.6);
        assert!(
            sm > 1.8 * fm && sm < 2.2 * fm,
            "half speed: {sm:.2} s of motion against {fm:.2} s"
        );
    }
}

#[test]
fn settle_times_are_the_cells() {
    // The same order with the default settle times (0.1 s after a grip,
    // 0.5 s after a release) and with 0.3 s and 0.1 s: each product waits
    // 0.2 s longer after its grip and 0.4 s less after its release, in its
    // motion and in its lower bound alike; the paths are the same.
    let assign = [("C", "g1"), ("A", "g3")];
    let default = run(&assign, &[], &[], Planner::Expert);
    let (arm, mut task, mut sim) = episode(&assign, &[], &[]);
    task.cell.grip_settle = 0.3;
    task.cell.release_settle = 0.1;
    let changed = execute::run(&mut sim, &arm, &task, &Planner::Expert);
    assert_packed(&default);
    assert_packed(&changed);
    for (d, c) in default.products.iter().zip(&changed.products) {
        let moved = (c.execution_s - d.execution_s) + 0.2;
        assert!(moved.abs() < 1e-9, "{d:?} against {c:?}");
        let bound = (c.bound_s - d.bound_s) + 0.2;
        assert!(bound.abs() < 1e-9, "{d:?} against {c:?}");
    }
    // No wait at all: the product still drops into its slot.
    let (arm, mut task, mut sim) = episode(&assign, &[], &[]);
    task.cell.grip_settle = 0.0;
    task.cell.release_settle = 0.0;
    let none = execute::run(&mut sim, &arm, &task, &Planner::Expert);
    assert_packed(&none);
}

#[test]
fn a_guarded_descent_is_slower_and_packs() {
    // The descent onto each top face at a quarter of the arm's speed: the
    // same stops (so the same lower bound), more time, still packed, with
    // the expert and with RRT-Connect.
    let assign = [("C", "g1"), ("A", "g3")];
    for planner in [Planner::Expert, Planner::Rrt { seed: 1 }] {
        let default = run(&assign, &[], &[], planner);
        let (arm, mut task, mut sim) = episode(&assign, &[], &[]);
        task.cell.descent = 0.25;
        let guarded = execute::run(&mut sim, &arm, &task, &planner);
        assert_packed(&default);
        assert_packed(&guarded);
        for (d, g) in default.products.iter().zip(&guarded.products) {
            assert!(g.execution_s > d.execution_s + 0.1, "{d:?} against {g:?}");
            assert!((g.bound_s - d.bound_s).abs() < 1e-9, "{d:?} against {g:?}");
        }
    }
}

#[test]
fn rrt_connect_packs_an_order() {
    let report = run(
        &[("B", "g4"), ("D", "g2")],
        &[],
        &[],
        Planner::Rrt { seed: 1 },
    );
    assert_packed(&report);
}

#[test]
fn a_worker_started_package_is_finished_and_missing_stock_waits() {
    let report = run(
        &[("A", "g1"), ("C", "g2"), ("E", "g3")],
        &["C"],
        &[],
        Planner::Expert,
    );
    assert_packed(&report);
    assert_eq!(report.products[1].outcome, Outcome::AlreadyPacked);
    let short = run(&[("A", "g1"), ("C", "g2")], &[], &["A"], Planner::Expert);
    assert_eq!(short.products[0].outcome, Outcome::Waiting);
    assert_eq!(short.products[1].outcome, Outcome::Packed);
    assert!(
        !short.complete,
        "a package with a missing product is not complete"
    );
}

/// A scripted stand-in for trained networks on the bench cell (products
/// 5 cm tall): the demonstrated rule as the reasoner, the expert's
/// geometry as the sub-goal planner, and a dynamics policy that never
/// moves the arm (or, with `reaching`, the expert's steps).
struct Scripted {
    task: OrderTask,
    /// The dynamics policy takes the expert's steps (what it is trained
    /// on): the cup-down joints at the base, shoulder and elbow given
    /// (the wrist as the learned loop turns it from the start pose),
    /// towards the inverse kinematics of the sub-goal nearest them.
    reaching: Option<(Arm, Joints)>,
    /// Move the proposed release by this much (m).
    release_offset: [f64; 3],
    /// Pick this product first, whatever the order says.
    wrong_pick: Option<usize>,
    /// Propose every sub-goal 3 m off, out of the arm's reach.
    lost: bool,
}

impl Policy for Scripted {
    fn reason(&self, graph: &Graph) -> Choice {
        if let Some(node) = self.wrong_pick {
            return Choice {
                node: Some(node),
                label: 0,
            };
        }
        // A product more than 5 cm above the table is held: place it.
        let raised = |n: &Node| n.centre[2] - n.height / 2.0 > 0.05;
        if graph.nodes.iter().any(raised) {
            let goal = graph.held_goal;
            let slot = graph
                .slots
                .iter()
                .position(|s| (s[0] - goal[0]).hypot(s[1] - goal[1]) < 1e-3);
            return Choice {
                node: None,
                label: slot.map_or(0, |s| s + 1),
            };
        }
        let next = graph.nodes.iter().position(|n| {
            let away = (0..3)
                .map(|j| (n.centre[j] - n.goal[j]).powi(2))
                .sum::<f32>()
                .sqrt();
            n.selected && away > 0.02
        });
        Choice {
            node: next,
            label: 0,
        }
    }

    fn subgoal(&self, q: &SubGoalQuery) -> [f32; 3] {
        let f = |v: [f32; 3]| v.map(f64::from);
        let cell = &self.task.cell;
        let goals = match q.stage {
            Stage::Picking => expert::picking(f(q.feature), f64::from(q.height), cell.lift),
            Stage::Placing => {
                let s = cell
                    .slots
                    .iter()
                    .position(|s| {
                        (s.position[0] - f64::from(q.feature[0]))
                            .hypot(s.position[1] - f64::from(q.feature[1]))
                            < 1e-3
                    })
                    .unwrap_or(0);
                // The product the order puts there (its size keeps the
                // release inside the walls, as the expert's is).
                let size = self
                    .task
                    .assignment
                    .iter()
                    .find(|(_, slot)| *slot == s)
                    .map_or([0.0; 3], |(p, _)| self.task.products[*p].size);
                expert::placing(
                    f(q.tool),
                    expert::release_at(cell, &cell.slots[s], size),
                    f64::from(q.height),
                    expert::box_height(cell, s),
                    [cell.base[0], cell.base[1]],
                )
            }
        };
        let mut tip = goals[q.index.min(2)].tip;
        if self.lost {
            tip[0] += 3.0;
        }
        if q.stage == Stage::Placing && q.index == 2 {
            (0..3).for_each(|j| tip[j] += self.release_offset[j]);
        }
        tip.map(|v| v as f32)
    }

    fn sequence(&self) -> SequenceRule {
        SequenceRule::Ascending
    }

    fn action(&self, delta: [f32; 3], joints: [f32; 3]) -> [f32; 3] {
        let Some((arm, start)) = &self.reaching else {
            return [0.0; 3];
        };
        // The learned loop keeps q1 + q2 + q3, q4 and q5 - q0 as at the
        // start (`execute::cup_down`).
        let [q0, q1, q2] = joints.map(f64::from);
        let q = [
            q0,
            q1,
            q2,
            start[1] + start[2] + start[3] - q1 - q2,
            start[4],
            start[5] - start[0] + q0,
        ];
        let [x, y, z] = self.task.cell.base;
        let base = nalgebra::Isometry3::translation(x, y, z);
        let suction = self.task.cell.suction;
        let tip = arm.tool_tip(&base, &q, suction);
        let goal = tip + nalgebra::Vector3::from(delta.map(f64::from));
        arm.yaw_free_tool_down_ik(&base, goal, suction, &q)
            .map_or([0.0; 3], |g| record::action(&q, &g).map(|v| v as f32))
    }
}

impl Scripted {
    /// The demonstrated rule and the expert's geometry, nothing changed.
    fn new(task: OrderTask) -> Scripted {
        Scripted {
            task,
            wrong_pick: None,
            lost: false,
            reaching: None,
            release_offset: [0.0; 3],
        }
    }

    /// [`Scripted::new`] with the expert's steps as its dynamics policy.
    fn reaching(task: OrderTask) -> Scripted {
        let arm = Arm::ur10();
        let start = execute::home(&arm, &task.cell).expect("a start pose");
        Scripted {
            reaching: Some((arm, start)),
            ..Scripted::new(task)
        }
    }
}

/// `assign` packed on the bench cell by the learned loop with the policy
/// `make` builds for the task.
fn learned_with(assign: &[(&str, &str)], make: impl FnOnce(OrderTask) -> Scripted) -> Report {
    learned_in(bench_cell(), assign, make)
}

/// [`learned_with`] in `cell`.
fn learned_in(
    cell: CellScene,
    assign: &[(&str, &str)],
    make: impl FnOnce(OrderTask) -> Scripted,
) -> Report {
    let (arm, task, mut sim) = episode_in(cell, assign, &[], &[]);
    let policy = make(task.clone());
    run_learned(&mut sim, &arm, &task, &policy)
}

/// A dynamics policy that does not move reaches no sub-goal: every stage
/// is handed to RRT-Connect at its first sub-goal, counted with the
/// distance left, and the package is still packed.
#[test]
fn the_learned_loop_falls_back_to_rrt_connect_and_says_why() {
    let assign = [("A", "g1"), ("D", "g5")];
    let report = learned_with(&assign, Scripted::new);
    assert_packed(&report);
    assert!(report.violations.is_empty(), "{:?}", report.violations);
    // Two stages per product, each falling back at its first sub-goal.
    assert_eq!(
        report.fallbacks.len(),
        2 * assign.len(),
        "{:#?}",
        report.fallbacks
    );
    for (i, f) in report.fallbacks.iter().enumerate() {
        let stage = if i % 2 == 1 {
            Stage::Placing
        } else {
            Stage::Picking
        };
        assert_eq!((f.stage, f.subgoal), (stage, 1), "{f}");
        assert!(
            matches!(f.why, Shortfall::Short { distance_m, .. } if distance_m > execute::REACHED_VIA),
            "{f}"
        );
    }
    assert_eq!(report.fallbacks[0].product, "A");
    assert!(report.fallbacks[3].to_string().starts_with(&format!(
        "placing D, sub-goal 1: {} policy steps ended",
        execute::MAX_POLICY_STEPS
    )));
}

/// A sub-goal planner whose sub-goals are out of reach (a model on a cell
/// unlike any it learned from): RRT-Connect cannot reach them either and
/// goes to the expert's sub-goals instead; the package is packed and the
/// fallbacks say so.
#[test]
fn a_fallback_goes_to_the_experts_sub_goal_when_the_learned_one_is_out_of_reach() {
    let assign = [("A", "g1"), ("D", "g5")];
    let report = learned_with(&assign, |task| Scripted {
        lost: true,
        ..Scripted::new(task)
    });
    assert_packed(&report);
    assert!(report.violations.is_empty(), "{:?}", report.violations);
    assert_eq!(
        report.fallbacks.len(),
        2 * assign.len(),
        "{:#?}",
        report.fallbacks
    );
    for f in &report.fallbacks {
        assert_eq!((f.subgoal, f.expert_from), (1, Some(1)), "{f}");
        assert!(
            f.to_string()
                .ends_with("RRT-Connect went to the expert's sub-goal 1"),
            "{f}"
        );
    }
    // With sub-goals in reach, no fallback goes to the expert's.
    let report = learned_with(&assign, Scripted::new);
    assert!(report.fallbacks.iter().all(|f| f.expert_from.is_none()));
}

/// A learned release 5 cm beside the slot is reachable but would put the
/// product outside it: it is not tried, RRT-Connect goes to the expert's
/// release, and the fallback says why.
#[test]
fn a_release_off_the_slot_is_not_tried() {
    let assign = [("A", "g1"), ("D", "g5")];
    let report = learned_with(&assign, |task| Scripted {
        release_offset: [0.0, 0.05, 0.0],
        ..Scripted::new(task)
    });
    assert_packed(&report);
    let releases: Vec<_> = report
        .fallbacks
        .iter()
        .filter(|f| f.stage == Stage::Placing)
        .collect();
    assert_eq!(releases.len(), assign.len(), "{:#?}", report.fallbacks);
    for f in releases {
        // The policy does not move, so placing falls back at sub-goal 1;
        // the release (3) is then the expert's.
        assert_eq!((f.subgoal, f.expert_from), (1, Some(3)), "{f}");
    }
}

/// With the expert's steps as its dynamics policy, the learned loop packs
/// without a fallback, and a learned release 15 mm too low, whose motion
/// would push the product into the tray's floor, is raised (1 cm at a time)
/// until it is free: still no fallback. In a slot 8 mm from the tray's wall
/// (the product's padded box to the wall), a learned release 15 mm towards
/// the wall (within the success radius) collides with the wall at any height
/// up to 2 cm above the expert's release, and is not raised higher (let go
/// from there, the product would drop off its slot), nor moved the 8 mm
/// back inside the walls (at most 6 mm): RRT-Connect goes to the
/// expert's release, and the fallback says why. One 9 mm towards the wall
/// is moved back inside it: no fallback.
#[test]
fn a_colliding_release_is_raised_a_little_then_goes_to_the_experts() {
    let assign = [("A", "g1"), ("D", "g5")];
    let moved = |cell: CellScene, by: [f64; 3]| {
        learned_in(cell, &assign, |task| Scripted {
            release_offset: by,
            ..Scripted::reaching(task)
        })
    };
    for by in [[0.0; 3], [0.0, 0.0, -0.015]] {
        let report = moved(bench_cell(), by);
        assert_packed(&report);
        assert!(
            report.fallbacks.is_empty(),
            "{by:?}: {:#?}",
            report.fallbacks
        );
    }
    // g1 near the tray's wall at y = 0.5 (4 mm thick): product A is 50 mm.
    let mut cell = bench_cell();
    cell.slots[0].position = [-0.12, 0.54];
    let report = moved(cell.clone(), [0.0; 3]);
    assert_packed(&report);
    assert!(report.fallbacks.is_empty(), "{:#?}", report.fallbacks);
    // 9 mm towards the wall, 1 mm into it: moved back inside the walls
    // (2 mm, to 1 mm inside them), no fallback.
    let report = moved(cell.clone(), [0.0, -0.009, 0.0]);
    assert_packed(&report);
    assert!(report.fallbacks.is_empty(), "{:#?}", report.fallbacks);
    // 15 mm: more than a small move from where it was learned.
    let report = moved(cell, [0.0, -0.015, 0.0]);
    assert_packed(&report);
    let [f] = report.fallbacks.as_slice() else {
        panic!("one fallback: {:#?}", report.fallbacks);
    };
    assert_eq!(
        (f.product.as_str(), f.stage, f.subgoal),
        ("A", Stage::Placing, 3),
        "{f}"
    );
    assert_eq!(f.expert_from, Some(3), "{f}");
    assert!(matches!(f.why, Shortfall::Collides { .. }), "{f}");
}

/// A cell with one box, 100 mm deep, in front of the products (0.32 m by
/// 0.20 m, its near wall at y = -0.35), with one slot `slot` at `at`.
fn case_cell(slot: &str, at: [f64; 2]) -> CellScene {
    CellScene {
        name: "case".into(),
        pending: ([0.40, -0.30], [0.85, 0.05]),
        boxes: vec![BoxSpec {
            name: "case".into(),
            centre: [0.60, -0.45],
            size: [0.32, 0.20, 0.10],
        }],
        slots: vec![SlotSpec {
            name: slot.into(),
            position: at,
            box_index: 0,
        }],
        ..bench_cell()
    }
}

/// A release near a box's wall: a 10 mm tray in a slot 1 mm from the
/// inside of a 100 mm box's wall. The expert lets go 4 mm further in
/// (`expert::release_at`), where the padded tray goes down into the box;
/// learned releases up to 5 mm towards the wall from there collide and
/// are kept inside the walls, packed without a fallback; 8 mm off, kept
/// inside it would move more than a learned release is moved, and the
/// expert's release is used.
#[test]
fn a_release_near_a_wall_keeps_its_product_inside() {
    let cell = case_cell("h5", [0.60, -0.40]);
    let tray = ProductSpec {
        name: "tray".into(),
        size: [0.09, 0.09, 0.01],
        mass: 0.15,
    };
    let run = |by: [f64; 3]| {
        let (arm, task, mut sim) = episode_of(
            cell.clone(),
            vec![(tray.clone(), [0.50, -0.07])],
            &[("tray", "h5")],
            &[],
            &[],
        );
        let policy = Scripted {
            release_offset: by,
            ..Scripted::reaching(task.clone())
        };
        run_learned(&mut sim, &arm, &task, &policy)
    };
    for by in [0.0, 0.001, 0.003, 0.005] {
        let report = run([0.0, by, 0.0]);
        assert_packed(&report);
        assert!(report.fallbacks.is_empty(), "{by}: {:#?}", report.fallbacks);
        let error = report.products[0].error_m.expect("released");
        assert!(error < 0.005, "{by}: {error}");
    }
    let report = run([0.0, 0.008, 0.0]);
    assert_packed(&report);
    let [f] = report.fallbacks.as_slice() else {
        panic!("one fallback: {:#?}", report.fallbacks);
    };
    assert_eq!(
        (f.stage, f.subgoal, f.expert_from),
        (Stage::Placing, 3, Some(3)),
        "{f}"
    );
    assert!(matches!(f.why, Shortfall::Collides { .. }), "{f}");
}

/// A 110 mm card in a slot 1 mm from the inside of a 200 mm deep
/// shipper's wall, by every planner: let go where the padded card goes
/// down past the wall (4 mm in from the slot), not raised until it
/// clears the rim and dropped 20 cm onto the wall's edge (28 mm off its
/// slot, tilted, before `expert::release_at`).
#[test]
fn a_product_close_to_a_deep_boxs_wall_is_let_go_inside_it() {
    let mut cell = case_cell("c1", [0.60, -0.41]);
    cell.boxes[0].size[2] = 0.20;
    cell.lift = 0.20;
    let card = ProductSpec {
        name: "card".into(),
        size: [0.07, 0.11, 0.008],
        mass: 0.02,
    };
    let episode = || {
        episode_of(
            cell.clone(),
            vec![(card.clone(), [0.50, -0.07])],
            &[("card", "c1")],
            &[],
            &[],
        )
    };
    for planner in [Planner::Expert, Planner::Rrt { seed: 1 }] {
        let (arm, task, mut sim) = episode();
        let report = execute::run(&mut sim, &arm, &task, &planner);
        assert_packed(&report);
        let error = report.products[0].error_m.expect("released");
        assert!(error < 0.005, "{:?}: {error}", report.planner);
        assert_let_go_inside(&report);
    }
    let (arm, task, mut sim) = episode();
    let report = run_learned(&mut sim, &arm, &task, &Scripted::reaching(task.clone()));
    assert_packed(&report);
    assert!(report.fallbacks.is_empty(), "{:#?}", report.fallbacks);
    assert_let_go_inside(&report);
}

/// The release (the sixth sub-goal reached) is in the lower half of the
/// 200 mm box: the card goes down into it (7 cm up, where the wrist
/// clears the walls), not over its rim (21 cm up before).
fn assert_let_go_inside(report: &Report) {
    let release = report.subgoals.get(5).expect("a release");
    assert!(release[2] < 0.10, "{:?}: {release:?}", report.planner);
}

/// A product carried over one standing taller than the carrying height
/// (a 180 mm syrup over a 220 mm bottle, lift 150 mm): every planner
/// raises the approach until the syrup clears the bottle; the learned
/// planner by its own steps, without a fallback.
#[test]
fn a_carry_over_a_taller_product_is_raised_by_every_planner() {
    let cell = case_cell("h3", [0.70, -0.50]);
    let product = |name: &str, size: [f64; 3], at: [f64; 2]| {
        (
            ProductSpec {
                name: name.into(),
                size,
                mass: 0.5,
            },
            at,
        )
    };
    let episode = || {
        episode_of(
            cell.clone(),
            vec![
                product("bottle", [0.06, 0.06, 0.22], [0.77, -0.26]),
                product("syrup", [0.045, 0.045, 0.18], [0.78, -0.05]),
            ],
            &[("syrup", "h3")],
            &[],
            &[],
        )
    };
    // The approach the expert's geometry gives: the syrup's bottom would
    // meet the bottle there.
    let (arm, task, mut sim) = episode();
    let lift = expert::picking([0.78, -0.05, 0.09], 0.18, task.cell.lift)[2].tip;
    let approach = expert::placing(lift, [0.70, -0.50], 0.18, 0.10, [0.0, 0.0])[0].tip;
    assert!(
        (approach[0] - 0.77).abs() < 0.0525 && (approach[1] + 0.26).abs() < 0.0525,
        "{approach:?}"
    );
    assert!(approach[2] - 0.18 < 0.22, "{approach:?}");
    for planner in [Planner::Expert, Planner::Rrt { seed: 1 }] {
        let (_, _, mut sim) = episode();
        let report = execute::run(&mut sim, &arm, &task, &planner);
        assert_packed(&report);
        assert!(report.collisions.is_empty(), "{:?}", report.collisions);
    }
    let policy = Scripted::reaching(task.clone());
    let report = run_learned(&mut sim, &arm, &task, &policy);
    assert_packed(&report);
    assert!(report.collisions.is_empty(), "{:?}", report.collisions);
    assert!(report.fallbacks.is_empty(), "{:#?}", report.fallbacks);
}

/// A reasoner that picks a product the order does not select breaks the
/// order: the violation is reported and the arm stops before moving.
#[test]
fn a_decision_against_the_order_stops_the_arm() {
    let report = learned_with(&[("A", "g1"), ("D", "g5")], |task| Scripted {
        wrong_pick: Some(1),
        ..Scripted::new(task)
    });
    assert!(!report.complete);
    assert_eq!(
        report.violations,
        [Violation::NotSelected {
            product: "B".into()
        }]
    );
    assert!(report.fallbacks.is_empty());
    assert!(
        report
            .products
            .iter()
            .all(|p| p.outcome == Outcome::NotAttempted)
    );
}
