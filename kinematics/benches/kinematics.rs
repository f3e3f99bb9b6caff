//! Kinematics of the built-in UR10: forward kinematics of every link, of the
//! flange only, the cup tip in closed form along cup-down steps, and the
//! closed-form and numeric tool-down inverse kinematics.

use std::f64::consts::FRAC_PI_2;
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Isometry3, Point3, Vector3};
use packwright_kinematics::{Arm, UR10_URDF, from_urdf};

fn kinematics(c: &mut Criterion) {
    let arm = Arm::ur10();
    let base = Isometry3::new(Vector3::new(0.4, -0.3, 0.75), Vector3::z() * 0.7);
    let q = [0.3, -1.2, 1.4, -1.77, -FRAC_PI_2, 0.4];
    let near = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];
    let suction = 0.12;
    let tip = arm.tool_tip(&base, &q, suction);
    let tip = Point3::new(tip.x + 0.05, tip.y - 0.03, tip.z);

    assert!(arm.tool_down_ik(&base, tip, 0.3, suction, &near).is_some());
    c.bench_function("fk_all_links", |b| {
        b.iter(|| arm.link_poses(black_box(&base), black_box(&q)))
    });
    c.bench_function("fk_flange", |b| {
        b.iter(|| arm.flange_pose(black_box(&base), black_box(&q)))
    });
    // The cup tip along the learned loop's cup-down steps, in closed form.
    let down = arm
        .tool_down_ik(&base, tip, 0.3, suction, &near)
        .expect("reachable");
    let at_tip = arm.tool_tip(&base, &down, suction);
    let closed = arm.cup_down_tip(&base, &down, &at_tip).expect("a UR10");
    c.bench_function("cup_down_tip_closed_form", |b| {
        b.iter(|| closed.at(black_box(&down)))
    });
    c.bench_function("ik_closed_form_tool_down", |b| {
        b.iter(|| {
            arm.tool_down_ik(
                black_box(&base),
                black_box(tip),
                0.3,
                suction,
                black_box(&near),
            )
        })
    });
    c.bench_function("ik_closed_form_yaw_free", |b| {
        b.iter(|| {
            arm.yaw_free_tool_down_ik(black_box(&base), black_box(tip), suction, black_box(&near))
        })
    });

    // The same arm with wrist 2 moved 1 cm: no closed form.
    let numeric =
        from_urdf(&UR10_URDF.replacen(r#"xyz="0 -0.1157 0""#, r#"xyz="0.01 -0.1157 0""#, 1));
    if let Ok(numeric) = numeric {
        let near = arm
            .tool_down_ik(&base, tip, 0.3, suction, &near)
            .unwrap_or(near);
        assert!(
            numeric
                .tool_down_ik(&base, tip, 0.3, suction, &near)
                .is_some()
        );
        c.bench_function("ik_numeric_tool_down", |b| {
            b.iter(|| {
                numeric.tool_down_ik(
                    black_box(&base),
                    black_box(tip),
                    0.3,
                    suction,
                    black_box(&near),
                )
            })
        });
    }
}

criterion_group!(benches, kinematics);
criterion_main!(benches);
