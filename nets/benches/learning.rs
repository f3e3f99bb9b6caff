//! The learned networks at run time (batch 1, the plain `nalgebra` passes
//! of `Networks`): a reasoner decision for 3, 5 and 20 products, a sub-goal
//! planner call and a dynamics-policy action, and the first calls of a
//! stage on cold caches; with the bundled model.

use std::hint::black_box;
use std::path::Path;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use packwright_interface::{Graph, Node, Stage, SubGoalQuery};
use packwright_nets::FILES;
use packwright_nets::Networks;

fn bundled() -> Networks {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/default");
    let read = |name: &str| std::fs::read(dir.join(name)).expect("models/default is in the repo");
    Networks::from_files(
        &read(FILES[0]),
        &read(FILES[1]),
        &read(FILES[2]),
        &read(FILES[3]),
    )
    .expect("the bundled model loads")
}

/// A graph of `m` products, every other one selected, none packed.
fn graph(m: usize) -> Graph {
    Graph {
        nodes: (0..m)
            .map(|i| Node {
                centre: [0.4 + 0.05 * i as f32, -0.4, 0.03],
                height: 0.06,
                selected: i % 2 == 0,
                goal: [0.1, 0.62, 0.03],
            })
            .collect(),
        slots: (0..5).map(|i| [0.1 * i as f32 - 0.2, 0.62, 0.0]).collect(),
        held_goal: [0.0; 3],
    }
}

/// Writes all of `sweep` (8 MiB): L1 and L2 hold none of what they held.
fn evict(sweep: &mut [u8]) -> u8 {
    for (i, v) in sweep.iter_mut().enumerate() {
        *v = v.wrapping_add(i as u8);
    }
    black_box(sweep[sweep.len() / 2])
}

fn learning(c: &mut Criterion) {
    let nets = bundled();
    for m in [3usize, 5, 20] {
        let g = graph(m);
        c.bench_function(&format!("reasoner_decision_{m}_products"), |b| {
            b.iter(|| nets.reason(black_box(&g)))
        });
    }
    // Cold caches, as inside a run: the simulator works between two
    // decisions. 8 MiB written before each call evicts L1 and L2.
    let mut sweep = vec![0u8; 8 << 20];
    let g = graph(5);
    c.bench_function("reasoner_decision_5_products_cold_cache", |b| {
        b.iter_batched(
            || evict(&mut sweep),
            |_| nets.reason(black_box(&g)),
            BatchSize::PerIteration,
        )
    });
    let query = SubGoalQuery {
        stage: Stage::Placing,
        index: 1,
        feature: [0.6, -0.4, 0.03],
        tool: [0.1, 0.6, 0.4],
        height: 0.06,
        base: [0.0; 3],
    };
    c.bench_function("subgoal_planner", |b| {
        b.iter(|| nets.subgoal(black_box(&query)))
    });
    c.bench_function("dynamics_action", |b| {
        b.iter(|| nets.action(black_box([0.1, -0.2, 0.05]), [1.0, -1.4, 2.0]))
    });
    // The first calls of a stage, after the simulator ran: a sub-goal
    // query, then eight policy actions (a long swing), on cold caches.
    c.bench_function("subgoal_and_8_actions_cold_cache", |b| {
        b.iter_batched(
            || evict(&mut sweep),
            |_| {
                let goal = nets.subgoal(black_box(&query));
                let mut q = [1.0f32, -1.4, 2.0];
                for _ in 0..8 {
                    let a = nets.action(black_box(goal), q);
                    q = [q[0] + a[0], q[1] + a[1], q[2] + a[2]];
                }
                q
            },
            BatchSize::PerIteration,
        )
    });
}

criterion_group!(benches, learning);
criterion_main!(benches);
