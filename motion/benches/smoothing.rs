//! The smoother's cost per control cycle: one online update (`step`) while a
//! 6-DoF move is under way, the first step after a new target (calculation
//! plus sample), and one full offline calculation of a 6-DoF trajectory
//! (through `duration_of`, and bare rsruckig for reference).
//! The 2 ms cycle is the budget.
//!
//! `cargo bench -p packwright-runtime --bench smoothing`

use std::f64::consts::{PI, TAU};
use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use packwright_kinematics::{DOF, Joints, Limits};
use packwright_motion::smoothing::{CONTROL_PERIOD, Smoother, duration_of};
use rsruckig::prelude::*;

/// UR10-like limits (as in the tests).
fn ur10() -> [Limits; DOF] {
    let deg = PI / 180.0;
    let mut limits = [Limits {
        lower: -TAU,
        upper: TAU,
        velocity: 180.0 * deg,
        acceleration: 2.5,
        jerk: 15.0,
    }; DOF];
    limits[0].velocity = 120.0 * deg;
    limits[1].velocity = 120.0 * deg;
    limits
}

const START: Joints = [0.0, -1.57, 1.2, -1.2, -1.57, 0.0];
const TARGET: Joints = [1.3, -0.8, 2.0, -2.5, -1.0, 3.0];

fn bench(c: &mut Criterion) {
    let limits = ur10();

    // Mid-move: the trajectory is computed; a step only samples it. Each
    // batch starts from a clone (untimed) 200 cycles into a ~1180-cycle move
    // and takes at most 500 steps, so every timed step is mid-move. (The
    // smoother is ~33 KB: `iter_batched` would time moving it around.)
    let mut moving = Smoother::new(limits, START).unwrap();
    moving.set_target(TARGET).unwrap();
    for _ in 0..200 {
        moving.step().unwrap();
    }
    c.bench_function("smoother step (online update, mid-move)", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut left = iters;
            while left > 0 {
                let mut s = moving.clone();
                let n = left.min(500);
                let t = Instant::now();
                for _ in 0..n {
                    black_box(s.step().unwrap());
                }
                total += t.elapsed();
                left -= n;
            }
            total
        })
    });

    // A new target while moving: Ruckig recalculates from the current state.
    let mut retargeted = moving.clone();
    retargeted
        .set_target([0.2, -1.0, 0.5, -0.5, 0.5, -1.0])
        .unwrap();
    c.bench_function(
        "smoother step after set_target (calculation + sample)",
        |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let mut s = retargeted.clone();
                    let t = Instant::now();
                    black_box(s.step().unwrap());
                    total += t.elapsed();
                }
                total
            })
        },
    );

    // Offline: construction of a smoother plus one Ruckig calculation.
    c.bench_function("duration_of (one offline 6-DoF calculation)", |b| {
        b.iter(|| duration_of(black_box(limits), black_box(START), black_box(&[TARGET])).unwrap())
    });

    // The bare calculation, for reference: rsruckig's offline `calculate`
    // on the same input (with position limits, as the smoother sets them).
    let mut otg = Ruckig::<DOF, ThrowErrorHandler>::new(None, CONTROL_PERIOD);
    let mut input = InputParameter::<DOF>::new(None);
    for (j, l) in limits.iter().enumerate() {
        input.current_position[j] = START[j];
        input.target_position[j] = TARGET[j];
        input.max_velocity[j] = l.velocity;
        input.max_acceleration[j] = l.acceleration;
        input.max_jerk[j] = l.jerk;
    }
    input.max_position = Some(DataArrayOrVec::Stack(limits.map(|l| l.upper)));
    input.min_position = Some(DataArrayOrVec::Stack(limits.map(|l| l.lower)));
    let mut trajectory = Trajectory::<DOF>::new(None);
    c.bench_function("rsruckig calculate (6 DoF, position limits)", |b| {
        b.iter(|| otg.calculate(black_box(&input), &mut trajectory).unwrap())
    });
    input.max_position = None;
    input.min_position = None;
    c.bench_function("rsruckig calculate (6 DoF, no position limits)", |b| {
        b.iter(|| otg.calculate(black_box(&input), &mut trajectory).unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
