//! Collision checks, RRT-Connect and blending a product's motion on the
//! UR10 in a bench cell.
//!
//! `cargo bench -p packwright-motion --bench planning` (instruction
//! counts of the checked blend: `examples/profile_blend.rs` under callgrind)

#[path = "../tests/common/mod.rs"]
mod common;
use common::{bench_cell, product_motion};

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point3, Vector3};
use packwright_kinematics::Arm;
use packwright_motion::blend::blend;
use packwright_motion::collision::{Checker, Held, ProductBody};
use packwright_motion::execute::{Load, checked_blend, checked_blend_by, reach};
use packwright_motion::rrt::{self, Query, RrtConfig};
use std::f64::consts::FRAC_PI_2;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let arm = Arm::ur10();
    let cell = bench_cell();
    let mut checker = Checker::new(&arm, &cell);
    let cubes: Vec<ProductBody> = [
        [0.5, -0.2],
        [0.62, -0.2],
        [0.74, -0.2],
        [0.56, -0.38],
        [0.68, -0.38],
    ]
    .iter()
    .enumerate()
    .map(|(i, at)| ProductBody {
        name: format!("P{i}"),
        centre: [at[0], at[1], 0.025],
        size: [0.05; 3],
        yaw: 0.0,
    })
    .collect();
    checker.set_products(&cubes);
    let ready = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];
    // The product's motion comes down onto P1's top face: P1 is not an
    // obstacle for the cup (as a planner's load ignores it).
    let cup_on_p1 = Load::picking("P1");
    let at = |x: f64, y: f64, z: f64| {
        reach(&checker, Point3::new(x, y, z), 0.0, &ready, cup_on_p1).expect("reachable")
    };
    let pick = at(0.62, -0.2, 0.2);
    let place = at(0.0, 0.6, 0.2);
    c.bench_function("collision check (arm, 5 products, box)", |b| {
        b.iter(|| checker.check(black_box(&pick), None, None))
    });
    c.bench_function("swept check pick -> place (1 degree steps)", |b| {
        b.iter(|| checker.check_motion(black_box(&pick), black_box(&place), None, None))
    });
    let query = Query {
        checker: &checker,
        limits: &arm.limits,
        held: None,
        ignore: None,
    };
    // A post between two poses forces a real search.
    let mut blocked = checker.clone();
    let mut with_post = cubes.clone();
    with_post.push(ProductBody {
        name: "post".into(),
        centre: [0.49, -0.34, 0.15],
        size: [0.05, 0.05, 0.3],
        yaw: 0.0,
    });
    blocked.set_products(&with_post);
    let a = at(0.3, -0.52, 0.15);
    let b2 = at(0.59, -0.1, 0.15);
    let blocked_query = Query {
        checker: &blocked,
        limits: &arm.limits,
        held: None,
        ignore: None,
    };
    let mut group = c.benchmark_group("rrt-connect");
    group.sample_size(20);
    group.bench_function("pick -> place", |b| {
        b.iter(|| rrt::plan(&query, pick, place, &RrtConfig::default()))
    });
    group.bench_function("around a post", |b| {
        b.iter(|| rrt::plan(&blocked_query, a, b2, &RrtConfig::default()))
    });
    group.finish();

    // One product's seven sub-goals (hover, top face, lift, approach,
    // above the slot, release, back up), stopping only at the contact and
    // the release: the legs, the overlaps, the samples, and with their
    // collision checks.
    let product = product_motion::SUBGOALS.map(|[x, y, z]| at(x, y, z));
    let stops = product_motion::STOPS;
    let [x, y, z] = product_motion::START;
    let start = at(x, y, z);
    c.bench_function("blend a product's 7 sub-goals", |b| {
        b.iter(|| blend(arm.limits, black_box(start), &product, &stops))
    });
    c.bench_function("blend a product's 7 sub-goals and check them", |b| {
        b.iter(|| {
            checked_blend(
                &arm,
                &checker,
                black_box(start),
                &product,
                &stops,
                cup_on_p1,
            )
        })
    });
    // The same with each leg's load as a planner gives it: the cup comes
    // down onto P1, lifts it off the table, carries it to the slot and
    // leaves it; the held product is swept between checked commands.
    let p1 = Held::under_cup("P1", [0.05; 3], cell.suction, Vector3::zeros());
    let lifting = p1.clone().leaving_support();
    let load_of = |k: usize| match k {
        0 | 1 => Load::picking("P1"),
        2 => Load::holding(&lifting),
        3..=5 => Load::holding(&p1),
        _ => Load::released("P1"),
    };
    let checked = checked_blend_by(&arm, &checker, start, &product, &stops, load_of);
    assert!(
        checked.is_ok(),
        "the held product's motion passes its check"
    );
    c.bench_function(
        "blend a product's 7 sub-goals and check them, the product held",
        |b| {
            b.iter(|| checked_blend_by(&arm, &checker, black_box(start), &product, &stops, load_of))
        },
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
