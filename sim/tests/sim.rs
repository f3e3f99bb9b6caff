//! The physical simulator: resting products, a pick and place with the
//! suction cup, dropping into a box, determinism, collision reporting.

use std::f64::consts::{FRAC_PI_2, PI};
use std::time::Instant;

use nalgebra::{Isometry3, Point3};
use packwright_interface::scene::{
    BoxSpec, CellScene, DEFAULT_MASS, Placement, ProductSpec, SlotSpec,
};
use packwright_interface::world::{Body, Contact, Observation, World};
use packwright_kinematics::{Arm, Joints};
use packwright_sim::Simulator;

fn link(name: &str) -> Body {
    Body::Link(name.into())
}

const SUCTION: f64 = 0.1;
/// A tool-down configuration with the elbow up, the IK seed.
const HOME: Joints = [0.0, -2.0, -1.6, 2.0, -FRAC_PI_2, 0.0];

fn cell() -> CellScene {
    CellScene {
        name: "test".into(),
        base: [0.0, 0.0, 0.0],
        suction: SUCTION,
        lift: 0.15,
        speed: 1.0,
        grip_settle: 0.1,
        release_settle: 0.5,
        descent: 1.0,
        pending: ([0.45, -0.5], [0.85, -0.1]),
        boxes: vec![BoxSpec {
            name: "tray".into(),
            centre: [0.0, 0.65],
            size: [0.40, 0.30, 0.08],
        }],
        slots: vec![SlotSpec {
            name: "s1".into(),
            position: [0.0, 0.6],
            box_index: 0,
        }],
    }
}

fn product(name: &str, size: [f64; 3], centre: [f64; 3]) -> Placement {
    Placement {
        product: ProductSpec {
            name: name.into(),
            size,
            mass: DEFAULT_MASS,
        },
        centre,
    }
}

fn cube(centre: [f64; 3]) -> Placement {
    product("A", [0.05; 3], centre)
}

fn base() -> Isometry3<f64> {
    Isometry3::identity()
}

/// Tool-down joints putting the tip at `tip`, nearest `near`.
fn ik(arm: &Arm, tip: [f64; 3], near: &Joints) -> Joints {
    arm.tool_down_ik(&base(), Point3::from(tip), 0.0, SUCTION, near)
        .unwrap_or_else(|| panic!("no IK for {tip:?}"))
}

fn run(sim: &mut Simulator, cycles: usize) {
    for _ in 0..cycles {
        sim.step().unwrap();
    }
}

/// Moves the tip along the straight line from `from` to `to` in `seconds`:
/// IK every centimetre, linear joint interpolation in between. Returns the
/// final joints.
fn move_tip(
    sim: &mut Simulator,
    arm: &Arm,
    q: Joints,
    from: [f64; 3],
    to: [f64; 3],
    seconds: f64,
) -> Joints {
    let length = (0..3)
        .map(|k| (to[k] - from[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    let pieces = ((length / 0.01).ceil() as usize).max(1);
    let mut waypoints = vec![q];
    for i in 1..=pieces {
        let t = i as f64 / pieces as f64;
        let tip = std::array::from_fn(|k| from[k] + (to[k] - from[k]) * t);
        let last = *waypoints.last().unwrap();
        waypoints.push(ik(arm, tip, &last));
    }
    let cycles = (seconds / sim.control_period()).round() as usize;
    for c in 1..=cycles {
        let s = c as f64 / cycles as f64 * pieces as f64;
        let i = (s.floor() as usize).min(pieces - 1);
        let f = s - i as f64;
        let target: Joints =
            std::array::from_fn(|j| waypoints[i][j] + (waypoints[i + 1][j] - waypoints[i][j]) * f);
        sim.command(&target).unwrap();
        sim.step().unwrap();
    }
    *waypoints.last().unwrap()
}

fn centre(obs: &Observation, name: &str) -> [f64; 3] {
    obs.products.iter().find(|p| p.name == name).unwrap().centre
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Picks the cube at (0.6, -0.3) and places it at slot (0, 0.6); returns
/// the final observation and every contact reported.
fn pick_and_place() -> (Observation, Vec<Contact>) {
    let arm = Arm::ur10();
    let above = [0.6, -0.3, 0.15];
    let start = ik(&arm, above, &HOME);
    let mut sim = Simulator::new(arm.clone(), &cell(), &[cube([0.6, -0.3, 0.025])], start).unwrap();
    let mut contacts = Vec::new();
    run(&mut sim, 100);

    let top = [0.6, -0.3, 0.05];
    let q = move_tip(&mut sim, &arm, start, above, top, 1.5);
    sim.set_suction(true).unwrap();
    assert_eq!(sim.held(), Some("A"), "the suction grips the cube");
    run(&mut sim, 50);
    contacts.extend(sim.take_collisions());

    let lifted = [0.6, -0.3, 0.2];
    let q = move_tip(&mut sim, &arm, q, top, lifted, 1.5);
    let carried = sim.observe();
    assert!(
        (centre(&carried, "A")[2] - 0.175).abs() < 0.003,
        "the cube is lifted with the cup: {:?}",
        centre(&carried, "A")
    );
    let over_slot = [0.0, 0.6, 0.2];
    let q = move_tip(&mut sim, &arm, q, lifted, over_slot, 2.0);
    let down = [0.0, 0.6, 0.055];
    move_tip(&mut sim, &arm, q, over_slot, down, 1.5);
    run(&mut sim, 50);
    contacts.extend(sim.take_collisions());

    sim.set_suction(false).unwrap();
    assert_eq!(sim.held(), None);
    run(&mut sim, 500);
    contacts.extend(sim.take_collisions());
    (sim.observe(), contacts)
}

#[test]
fn a_product_left_alone_rests() {
    let arm = Arm::ur10();
    let start = ik(&arm, [0.6, -0.3, 0.3], &HOME);
    let products = [
        cube([0.6, -0.3, 0.025]),
        product("B", [0.08, 0.06, 0.12], [0.5, -0.2, 0.06]),
    ];
    let mut sim = Simulator::new(arm, &cell(), &products, start).unwrap();
    let before = sim.observe();
    run(&mut sim, 1000);
    let after = sim.observe();
    assert!((after.time - 2.0).abs() < 1e-9);
    for (b, a) in before.products.iter().zip(&after.products) {
        let moved = distance(b.centre, a.centre);
        assert!(moved < 0.001, "{} moved {moved} m", a.name);
        assert!(a.yaw.abs() < 1e-3);
    }
    assert_eq!(sim.take_collisions(), vec![]);
}

#[test]
fn suction_picks_a_product_and_drops_it_in_the_box() {
    let (obs, contacts) = pick_and_place();
    let c = centre(&obs, "A");
    assert!(distance(c, [0.0, 0.6, 0.025]) < 0.02, "placed at {c:?}");
    let inner = |v: f64, centre: f64, size: f64| (v - centre).abs() < size / 2.0 - 0.004 - 0.025;
    assert!(
        inner(c[0], 0.0, 0.40) && inner(c[1], 0.65, 0.30),
        "inside the box: {c:?}"
    );
    assert!(!obs.suction);
    assert_eq!(
        contacts,
        vec![],
        "no collision during a clean pick and place"
    );
}

#[test]
fn a_product_released_above_the_box_ends_inside() {
    let arm = Arm::ur10();
    let start = ik(&arm, [0.6, -0.3, 0.3], &HOME);
    // Bottom 5 cm above the floor, over the slot.
    let mut sim = Simulator::new(arm, &cell(), &[cube([0.0, 0.6, 0.075])], start).unwrap();
    run(&mut sim, 500);
    let c = centre(&sim.observe(), "A");
    assert!((c[2] - 0.025).abs() < 0.002, "resting on the floor: {c:?}");
    assert!(
        c[0].abs() < 0.2 - 0.004 - 0.025 && (c[1] - 0.65).abs() < 0.15 - 0.004 - 0.025,
        "inside: {c:?}"
    );
    assert_eq!(sim.take_collisions(), vec![]);
}

#[test]
fn identical_runs_are_identical() {
    let (a, ca) = pick_and_place();
    let (b, cb) = pick_and_place();
    let bits = |o: &Observation| -> Vec<u64> {
        o.products
            .iter()
            .flat_map(|p| p.centre.iter().chain([&p.yaw]).map(|v| v.to_bits()))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a, b);
    assert_eq!(ca, cb);
}

#[test]
fn driving_the_forearm_through_a_product_is_a_collision() {
    let arm = Arm::ur10();
    let start = ik(&arm, [0.6, -0.3, 0.15], &HOME);
    // A tall post where the forearm's middle will be after turning the base
    // by 30 degrees.
    let forearm = arm.link_poses(&base(), &start)[3];
    let middle = forearm * Point3::new(-0.286, 0.0, 0.049);
    let turn = nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), PI / 6.0);
    let at = turn * middle;
    let height = middle.z + 0.1;
    let post = product("post", [0.06, 0.06, height], [at.x, at.y, height / 2.0]);
    let mut sim = Simulator::new(arm, &cell(), &[post], start).unwrap();
    run(&mut sim, 50);
    assert_eq!(sim.take_collisions(), vec![]);
    let cycles = 1000;
    for c in 1..=cycles {
        let mut q = start;
        q[0] += PI / 3.0 * c as f64 / cycles as f64;
        sim.command(&q).unwrap();
        sim.step().unwrap();
    }
    let contacts = sim.take_collisions();
    assert!(
        contacts
            .iter()
            .any(|c| c.a == link("forearm_link") && c.b == Body::Product("post".into())),
        "forearm through the post: {contacts:?}"
    );
    let first = contacts
        .iter()
        .find(|c| c.a == link("forearm_link"))
        .unwrap();
    assert!(first.time > 0.1 && first.time < 2.2, "{first:?}");
}

#[test]
fn suction_with_nothing_in_reach_grips_nothing() {
    let arm = Arm::ur10();
    let start = ik(&arm, [0.6, -0.3, 0.1], &HOME);
    let mut sim = Simulator::new(arm, &cell(), &[cube([0.6, -0.3, 0.025])], start).unwrap();
    sim.set_suction(true).unwrap();
    run(&mut sim, 100);
    assert_eq!(sim.held(), None);
    assert!(sim.observe().suction);
    let c = centre(&sim.observe(), "A");
    assert!(distance(c, [0.6, -0.3, 0.025]) < 0.001);
}

#[test]
fn a_cup_reaching_the_top_with_the_suction_on_grips() {
    let arm = Arm::ur10();
    let above = [0.6, -0.3, 0.15];
    let start = ik(&arm, above, &HOME);
    let mut sim = Simulator::new(arm.clone(), &cell(), &[cube([0.6, -0.3, 0.025])], start).unwrap();
    sim.set_suction(true).unwrap();
    assert_eq!(sim.held(), None);
    let q = move_tip(&mut sim, &arm, start, above, [0.6, -0.3, 0.05], 1.0);
    assert_eq!(sim.held(), Some("A"));
    move_tip(&mut sim, &arm, q, [0.6, -0.3, 0.05], [0.6, -0.3, 0.2], 1.0);
    let c = centre(&sim.observe(), "A");
    // Gripped when the tip came within 1 mm of the top: it hangs about
    // 1 mm below the tip.
    assert!((c[2] - 0.174).abs() < 0.002, "lifted: {c:?}");
    assert_eq!(sim.take_collisions(), vec![]);
}

#[test]
fn pressing_a_held_product_into_the_box_floor_is_a_collision() {
    let arm = Arm::ur10();
    let above = [0.0, 0.6, 0.07];
    let start = ik(&arm, above, &HOME);
    // The cube hangs under the cup, 2 cm above the floor.
    let mut sim = Simulator::new(arm.clone(), &cell(), &[cube([0.0, 0.6, 0.045])], start).unwrap();
    sim.set_suction(true).unwrap();
    assert_eq!(sim.held(), Some("A"));
    run(&mut sim, 50);
    // Down 1.5 cm: the cube touches the floor, no collision.
    let q = move_tip(&mut sim, &arm, start, above, [0.0, 0.6, 0.055], 1.0);
    run(&mut sim, 50);
    assert_eq!(sim.take_collisions(), vec![]);
    // Down 1 cm more: into the floor.
    move_tip(&mut sim, &arm, q, [0.0, 0.6, 0.055], [0.0, 0.6, 0.045], 1.0);
    let contacts = sim.take_collisions();
    assert!(
        contacts
            .iter()
            .any(|c| c.a == Body::Held("A".into()) && c.b == Body::Box("tray".into())),
        "{contacts:?}"
    );
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let arm = Arm::ur10();
    let start = ik(&arm, [0.6, -0.3, 0.3], &HOME);
    let mut sim = Simulator::new(arm.clone(), &cell(), &[cube([0.6, -0.3, 0.025])], start).unwrap();
    assert!(sim.command(&[f64::NAN; 6]).is_err());
    assert!(sim.command(&[100.0; 6]).is_err());
    assert!(sim.step().is_ok());
    assert_eq!(sim.observe().joints, start);
    let mut bad = cube([0.6, -0.3, 0.025]);
    bad.product.size[0] = -1.0;
    assert!(Simulator::new(arm.clone(), &cell(), &[bad], start).is_err());
    let mut bad = cube([0.6, -0.3, 0.025]);
    bad.product.mass = 0.0;
    assert!(Simulator::new(arm.clone(), &cell(), &[bad], start).is_err());
    let mut bad = cube([0.6, -0.3, 0.025]);
    bad.centre[2] = f64::INFINITY;
    assert!(Simulator::new(arm.clone(), &cell(), &[bad], start).is_err());
    assert!(Simulator::new(arm.clone(), &cell(), &[], [f64::NAN; 6]).is_err());
    let mut c = cell();
    c.suction = -0.1;
    assert!(Simulator::new(arm, &c, &[], start).is_err());
}

/// The cost of one step with five products and a moving arm. Run with
/// `cargo test --release -p packwright-runtime --test sim -- --ignored --nocapture`.
#[test]
#[ignore]
fn step_cost() {
    let arm = Arm::ur10();
    let start = ik(&arm, [0.6, -0.3, 0.3], &HOME);
    let products: Vec<Placement> = (0..5)
        .map(|k| {
            product(
                &format!("P{k}"),
                [0.05, 0.05, 0.05],
                [0.5 + 0.08 * k as f64, -0.3, 0.025],
            )
        })
        .collect();
    let mut sim = Simulator::new(arm, &cell(), &products, start).unwrap();
    let cycles = 5000;
    let begin = Instant::now();
    for c in 0..cycles {
        let mut q = start;
        q[0] += 0.3 * (c as f64 * 0.002).sin();
        sim.command(&q).unwrap();
        sim.step().unwrap();
    }
    let per_step = begin.elapsed().as_secs_f64() / cycles as f64 * 1e6;
    println!("one step with 5 products: {per_step:.1} µs");
}
