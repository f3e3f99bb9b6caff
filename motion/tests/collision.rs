//! Hand-made cases that must and must not collide, and RRT-Connect plans
//! that must be valid when re-checked and reproducible from a seed.

mod common;
use common::bench_cell;

use nalgebra::{Isometry3, Point3, Vector3};
use packwright_interface::outcome::Hit;
use packwright_interface::world::Body;
use packwright_kinematics::{Arm, Joints};
use packwright_motion::collision::{Checker, Held, ProductBody, Touch};
use packwright_motion::rrt::{self, Query, RrtConfig};
use std::f64::consts::FRAC_PI_2;

/// A point at `radius` from the base axis, `degrees` around it, at height `z`.
fn polar(radius: f64, degrees: f64, z: f64) -> [f64; 3] {
    let a = degrees.to_radians();
    [radius * a.cos(), radius * a.sin(), z]
}

/// A 5 x 5 x 30 cm post standing at (x, y).
fn post(at: [f64; 3]) -> ProductBody {
    ProductBody {
        name: "wall".into(),
        centre: at,
        size: [0.05, 0.05, 0.3],
        yaw: 0.0,
    }
}

const UPRIGHT: Joints = [0.0, -FRAC_PI_2, 0.0, -FRAC_PI_2, 0.0, 0.0];

fn ik(arm: &Arm, tip: [f64; 3]) -> Joints {
    arm.tool_down_ik(
        &Isometry3::identity(),
        Point3::from(tip),
        0.0,
        0.1,
        &UPRIGHT,
    )
    .unwrap_or_else(|| panic!("{tip:?} is reachable"))
}

fn cube(name: &str, centre: [f64; 3], edge: f64) -> ProductBody {
    ProductBody {
        name: name.into(),
        centre,
        size: [edge; 3],
        yaw: 0.0,
    }
}

#[test]
fn free_configurations_are_free() {
    let arm = Arm::ur10();
    let checker = Checker::new(&arm, &bench_cell());
    assert_eq!(checker.check(&UPRIGHT, None, None), None);
    let above_pending = ik(&arm, [0.6, -0.3, 0.3]);
    assert_eq!(checker.check(&above_pending, None, None), None);
    let above_box = ik(&arm, [0.0, 0.6, 0.25]);
    assert_eq!(checker.check(&above_box, None, None), None);
}

#[test]
fn the_arm_in_the_table_collides() {
    let arm = Arm::ur10();
    let checker = Checker::new(&arm, &bench_cell());
    // Shoulder tipped forward past horizontal: the arm goes down through the table.
    let q = [0.0, 0.6, 0.0, -FRAC_PI_2, 0.0, 0.0];
    let hit = checker.check(&q, None, None).expect("a collision");
    assert!(
        matches!(&hit, Hit::Bodies { b: Body::Table, .. }),
        "{hit:?}"
    );
}

#[test]
fn products_are_obstacles_except_the_one_being_picked() {
    let arm = Arm::ur10();
    let mut checker = Checker::new(&arm, &bench_cell());
    checker.set_products(&[cube("A", [0.6, -0.3, 0.025], 0.05)]);
    // The cup's tip on A's top face: touching A is fine when picking A.
    let on_top = ik(&arm, [0.6, -0.3, 0.05]);
    assert_eq!(
        checker.check(&on_top, None, Some(Touch::Picking("A"))),
        None
    );
    // The cup pushed 2 cm into A hits A when A is not being picked (the
    // cup's model ends 5 mm short of its tip).
    let inside = ik(&arm, [0.6, -0.3, 0.03]);
    let hit = checker.check(&inside, None, None).expect("a collision");
    assert!(
        matches!(&hit, Hit::Bodies { b: Body::Product(n), .. } if n == "A"),
        "{hit:?}"
    );
    // A neighbour 12 cm away is not touched.
    checker.set_products(&[
        cube("A", [0.6, -0.3, 0.025], 0.05),
        cube("B", [0.72, -0.3, 0.025], 0.05),
    ]);
    assert_eq!(
        checker.check(&on_top, None, Some(Touch::Picking("A"))),
        None
    );
}

/// The cup may meet the product it picks from above only: swept into its
/// side (as a fallback's RRT-Connect path to a pick did, on a cell whose
/// products stand near the base), it collides, as in the simulator. The
/// product just released it may touch anywhere.
#[test]
fn the_cup_meets_the_product_it_picks_from_above_only() {
    let arm = Arm::ur10();
    let mut checker = Checker::new(&arm, &bench_cell());
    checker.set_products(&[cube("A", [0.6, -0.3, 0.025], 0.05)]);
    // The tip 1.5 mm under the top face (the cup's body ends 5 mm above
    // the tip, and keeps TOUCH_CLEARANCE over the face): still on it.
    let pressed = ik(&arm, [0.6, -0.3, 0.0485]);
    let deeper = ik(&arm, [0.6, -0.3, 0.044]);
    assert!(
        checker
            .check(&deeper, None, Some(Touch::Picking("A")))
            .is_some()
    );
    assert_eq!(
        checker.check(&pressed, None, Some(Touch::Picking("A"))),
        None
    );
    // Beside A at half its height, the cup overlapping its side.
    let beside = ik(&arm, [0.635, -0.3, 0.025]);
    let hit = checker
        .check(&beside, None, Some(Touch::Picking("A")))
        .expect("a collision");
    assert!(
        matches!(&hit, Hit::Bodies { a: Body::Cup, b: Body::Product(n) } if n == "A"),
        "{hit:?}"
    );
    assert_eq!(
        checker.check(&beside, None, Some(Touch::Released("A"))),
        None
    );
    // A motion from above A down its side collides when picking it.
    let above = ik(&arm, [0.635, -0.3, 0.15]);
    assert!(
        checker
            .check_motion(&above, &beside, None, Some(Touch::Picking("A")))
            .is_some()
    );
}

#[test]
fn a_motion_through_an_obstacle_collides_between_free_ends() {
    let arm = Arm::ur10();
    let mut checker = Checker::new(&arm, &bench_cell());
    // Two ends 50 degrees apart around the base, a tall product between.
    let a = ik(&arm, polar(0.6, -60.0, 0.15));
    let b = ik(&arm, polar(0.6, -10.0, 0.15));
    checker.set_products(&[post(polar(0.6, -35.0, 0.15))]);
    assert_eq!(checker.check(&a, None, None), None);
    assert_eq!(checker.check(&b, None, None), None);
    let hit = checker
        .check_motion(&a, &b, None, None)
        .expect("the motion collides");
    assert!(
        matches!(&hit, Hit::Bodies { b: Body::Product(n), .. } if n == "wall"),
        "{hit:?}"
    );
}

#[test]
fn a_held_product_collides_with_the_box_wall() {
    let arm = Arm::ur10();
    let checker = Checker::new(&arm, &bench_cell());
    // Hanging under a 0.1 m cup: centre half a height below the tip.
    let held = Held::under_cup("A", [0.05; 3], 0.1, Vector3::zeros());
    assert_eq!(
        held.in_flange,
        Isometry3::translation(0.0, 0.0, 0.1 + 0.025)
    );
    // Above the slot: free.
    let above = ik(&arm, [0.0, 0.6, 0.25]);
    assert_eq!(checker.check(&above, Some(&held), None), None);
    // Down at the slot: the product's bottom 5 mm over the floor, free.
    let down = ik(&arm, [0.0, 0.6, 0.055]);
    assert_eq!(checker.check(&down, Some(&held), None), None);
    // Lowered onto the tray's front wall (y = 0.5), the cup still above
    // it: the held product collides.
    let on_wall = ik(&arm, [0.0, 0.5, 0.13]);
    let hit = checker
        .check(&on_wall, Some(&held), None)
        .expect("a collision");
    assert_eq!(
        hit,
        Hit::Bodies {
            a: Body::Held("A".into()),
            b: Body::Box("tray".into())
        }
    );
}

#[test]
fn rrt_connect_plans_valid_and_reproducible_paths() {
    let arm = Arm::ur10();
    let mut checker = Checker::new(&arm, &bench_cell());
    let a = ik(&arm, polar(0.6, -60.0, 0.15));
    let b = ik(&arm, polar(0.6, -10.0, 0.15));
    checker.set_products(&[post(polar(0.6, -35.0, 0.15))]);
    assert!(
        checker.check_motion(&a, &b, None, None).is_some(),
        "the direct motion is blocked"
    );
    let query = Query {
        checker: &checker,
        limits: &arm.limits,
        held: None,
        ignore: None,
    };
    let config = RrtConfig {
        seed: 3,
        ..RrtConfig::default()
    };
    let path = rrt::plan(&query, a, b, &config).expect("a path around the wall");
    assert_eq!(path.first(), Some(&a));
    assert_eq!(path.last(), Some(&b));
    for w in path.windows(2) {
        assert_eq!(checker.check_motion(&w[0], &w[1], None, None), None);
    }
    let again = rrt::plan(&query, a, b, &config).expect("same plan");
    assert_eq!(path, again, "same seed, same path");
    // A search whose deadline has passed gives up at once.
    let late = RrtConfig {
        deadline: Some(std::time::Instant::now()),
        ..config.clone()
    };
    assert!(rrt::plan(&query, a, b, &late).is_none());
    // A goal inside an obstacle has no plan.
    let inside = ik(&arm, polar(0.6, -35.0, 0.2));
    assert!(rrt::plan(&query, a, inside, &config).is_none());
}
