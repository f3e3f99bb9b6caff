//! The planning bench's "blend a product's 7 sub-goals and check them",
//! a fixed number of times, for instruction counts under callgrind
//! (repeatable where wall times on a shared machine are not):
//!
//! `cargo build --release -p packwright-motion --example profile_blend`
//! `valgrind --tool=callgrind target/release/examples/profile_blend 20`
//!
//! The argument is the number of checked blends (default 20); `blend`
//! as a second argument times the blend alone, `one` the checked
//! straight motion of one sub-goal (the hover to the approach, a long
//! one), as a planner joins a sub-goal; `held` the checked blend with
//! each leg's load, as the bench's "the product held" variant.

#[path = "../tests/common/mod.rs"]
mod common;
use common::{bench_cell, product_motion};

use nalgebra::{Point3, Vector3};
use packwright_kinematics::Arm;
use packwright_motion::blend::blend;
use packwright_motion::collision::{Checker, Held, ProductBody};
use packwright_motion::execute::{Load, checked_blend, checked_blend_by, reach};
use std::f64::consts::FRAC_PI_2;
use std::hint::black_box;

fn main() {
    let mut args = std::env::args().skip(1);
    let runs: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(20);
    let mode = args.next();
    let alone = mode.as_deref() == Some("blend");
    // One sub-goal: the straight checked motion from the hover to the
    // approach, as a planner joins a sub-goal.
    let one = mode.as_deref() == Some("one");
    let held = mode.as_deref() == Some("held");
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
    let product = product_motion::SUBGOALS.map(|[x, y, z]| at(x, y, z));
    let stops = product_motion::STOPS;
    let [x, y, z] = product_motion::START;
    let start = at(x, y, z);
    // The bench's loads: down onto P1, lift it, carry it, leave it.
    let p1 = Held::under_cup("P1", [0.05; 3], cell.suction, Vector3::zeros());
    let lifting = p1.clone().leaving_support();
    let load_of = |k: usize| match k {
        0 | 1 => Load::picking("P1"),
        2 => Load::holding(&lifting),
        3..=5 => Load::holding(&p1),
        _ => Load::released("P1"),
    };
    let mut commands = 0;
    // A digest of the commands' bits (FNV-1a), to compare builds.
    let mut digest: u64 = 0xcbf2_9ce4_8422_2325;
    for _ in 0..runs {
        let b = if one {
            checked_blend(
                &arm,
                &checker,
                black_box(product[0]),
                &product[3..4],
                &[],
                cup_on_p1,
            )
            .expect("free")
        } else if held {
            checked_blend_by(&arm, &checker, black_box(start), &product, &stops, load_of)
                .expect("free")
        } else if alone {
            blend(arm.limits, black_box(start), &product, &stops).expect("blends")
        } else {
            checked_blend(
                &arm,
                &checker,
                black_box(start),
                &product,
                &stops,
                cup_on_p1,
            )
            .expect("free")
        };
        commands += b.samples.len();
        for q in &b.samples {
            for v in q {
                digest = (digest ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    println!("{runs} runs, {commands} commands, digest {digest:016x}");
}
