//! `Station::send_legs` against the simulator.

use super::*;
use packwright_interface::scene::ProductSpec;
use packwright_interface::world::{Body, WorldError};
use packwright_sim::Simulator;

// The bench cell the crate's integration tests use.
#[path = "../../tests/common/mod.rs"]
mod common;

/// The simulator, remembering each command and where each suction
/// switch happened.
struct Recording {
    sim: Simulator,
    commands: Vec<Joints>,
    switches: Vec<(bool, Option<Joints>)>,
}

impl World for Recording {
    fn control_period(&self) -> f64 {
        self.sim.control_period()
    }
    fn observe(&self) -> Observation {
        self.sim.observe()
    }
    fn command(&mut self, joints: &Joints) -> Result<(), WorldError> {
        self.commands.push(*joints);
        self.sim.command(joints)
    }
    fn set_suction(&mut self, on: bool) -> Result<(), WorldError> {
        self.switches.push((on, self.commands.last().copied()));
        self.sim.set_suction(on)
    }
    fn step(&mut self) -> Result<(), WorldError> {
        self.sim.step()
    }
    fn take_collisions(&mut self) -> Vec<Contact> {
        self.sim.take_collisions()
    }
}

/// The bench cell with no products, the arm at home there, and its
/// simulation recording commands and switches.
fn empty_bench_cell(arm: &Arm) -> (OrderTask, Joints, Recording) {
    let task = OrderTask {
        cell: common::bench_cell(),
        products: Vec::new(),
        assignment: Vec::new(),
    };
    let start = home(arm, &task.cell).expect("a start pose");
    let sim = Simulator::new(arm.clone(), &task.cell, &[], start).expect("a simulation");
    let world = Recording {
        sim,
        commands: Vec::new(),
        switches: Vec::new(),
    };
    (task, start, world)
}

/// A leg that does not move but switches the suction (its sub-goal
/// already reached) switches where the leg before it ends, at rest:
/// the blend must stop there, not pass through it.
#[test]
fn a_switch_on_a_leg_that_does_not_move_happens_at_rest() {
    let arm = Arm::ur10();
    let (task, start, mut world) = empty_bench_cell(&arm);
    let mut station = Station::new(&mut world, &arm, &task);
    let at = |x: f64, y: f64, z: f64| {
        reach(
            &station.checker,
            Point3::new(x, y, z),
            0.0,
            &start,
            Load::FREE,
        )
        .expect("reachable")
    };
    // Out and back: the joints turn round at `a`, where two legs can
    // overlap.
    let (a, b) = (at(0.45, -0.15, 0.2), at(0.75, -0.4, 0.35));
    let route = |station: &Station<Recording>, from: Joints, to: Joints| {
        station.checked(1, from, &[to], Load::FREE).expect("free")
    };
    let legs = vec![
        Leg::new(route(&station, start, a), Suction::Keep, Load::FREE),
        Leg::new(
            Route {
                waypoints: Vec::new(),
                samples: Vec::new(),
            },
            Suction::On,
            Load::FREE,
        ),
        Leg::new(route(&station, a, b), Suction::Keep, Load::FREE),
    ];
    let tail = station.send_legs(legs, false).expect("sent");
    assert!(tail.is_empty());
    assert_eq!(world.switches, [(true, Some(a))]);
    assert_eq!(world.commands.last(), Some(&b));
}

#[test]
fn settle_times_are_whole_control_cycles() {
    assert_eq!(settle_cycles(0.1, 0.002), 50);
    assert_eq!(settle_cycles(0.5, 0.002), 250);
    assert_eq!(settle_cycles(0.0, 0.002), 0);
    assert_eq!(settle_cycles(0.0031, 0.002), 2);
    assert_eq!(settle_cycles(-1.0, 0.002), 0);
    assert_eq!(settle_cycles(f64::NAN, 0.002), 0);
    assert_eq!(settle_cycles(0.1, 0.0), 0);
}

/// A product's pick, carry and release on the bench cell, blended through
/// the corners with the loads `send_legs` gives (the product ignored on
/// the way down onto it and back up from the slot, held in between): the
/// commands a transition shaped are free with nothing ignored, and next
/// to each stop the cup tip moves [`STOP_CLEARANCE`] on the straight
/// segment before any transition shapes the commands.
#[test]
fn transitions_ignore_nothing_and_stops_keep_their_clearance() {
    let arm = Arm::ur10();
    let cell = common::bench_cell();
    let mut checker = Checker::new(&arm, &cell);
    let size = [0.05; 3];
    checker.set_products(&[
        ProductBody {
            name: "P".into(),
            centre: [0.62, -0.2, 0.025],
            size,
            yaw: 0.0,
        },
        ProductBody {
            name: "Q".into(),
            centre: [0.74, -0.2, 0.025],
            size,
            yaw: 0.0,
        },
    ]);
    let held = Held::under_cup("P", size, cell.suction, nalgebra::Vector3::zeros());
    let lifting = held.clone().leaving_support();
    let load_of = |k: usize| match k {
        0 | 1 => Load::picking("P"),
        6 => Load::released("P"),
        2 => Load::holding(&lifting),
        _ => Load::holding(&held),
    };
    let ready = READY;
    // Each sub-goal reached with its leg's load (the cup on P's top face
    // ignores P).
    let at = |[x, y, z]: [f64; 3], load: Load| {
        reach(&checker, Point3::new(x, y, z), 0.0, &ready, load).expect("reachable")
    };
    let start = at(common::product_motion::START, Load::FREE);
    let subgoals = common::product_motion::SUBGOALS;
    let waypoints: [Joints; 7] = std::array::from_fn(|k| at(subgoals[k], load_of(k)));
    let stops = common::product_motion::STOPS;
    let b = checked_blend_by(&arm, &checker, start, &waypoints, &stops, load_of).expect("free");
    assert!(b.corners.iter().filter(|c| c.saved > 0.0).count() >= 3);
    let tip = |q: &Joints| arm.tool_tip(checker.base(), q, checker.suction());
    for (i, q) in b.samples.iter().enumerate() {
        if b.shaped(i) {
            let load = load_of(b.leg_at(i));
            assert_eq!(checker.check(q, load.held, None), None, "sample {i}");
            // No shaped command within the clearance of a stop, but for
            // the two commands a corner's samples reach past its
            // transition: the tip's moves over the three commands after.
            let moves: f64 = (i..(i + 3).min(b.samples.len() - 1))
                .map(|n| (tip(&b.samples[n + 1]) - tip(&b.samples[n])).norm())
                .sum();
            for (k, w) in waypoints.iter().enumerate().filter(|(k, _)| stops[*k]) {
                let d = (tip(q) - tip(w)).norm();
                assert!(
                    d + moves >= STOP_CLEARANCE,
                    "sample {i}: {d} m from stop {k}"
                );
            }
        }
    }
}

/// The straight shares found by skipping the grid points the tip's
/// speed bound proves far are those of testing every grid point, on
/// random legs, long and short (a few centimetres, as a descent).
#[test]
fn straight_shares_skip_only_points_proved_far() {
    use rand::{Rng, SeedableRng};
    let arm = Arm::ur10();
    let checker = Checker::new(&arm, &common::bench_cell());
    let tip = |q: &Joints| arm.tool_tip(checker.base(), q, checker.suction());
    // Every grid point tested, as before the bound.
    let exhaustive = |stop: &Joints, other: &Joints| -> f64 {
        let at = tip(stop);
        let last_near = (1..=64)
            .filter(|&i| {
                let s = i as f64 / 64.0;
                let q: Joints = std::array::from_fn(|j| stop[j] + s * (other[j] - stop[j]));
                (tip(&q) - at).norm() < STOP_CLEARANCE
            })
            .max()
            .unwrap_or(0);
        ((last_near + 1) as f64 / 64.0).min(1.0)
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut partial = 0;
    for k in 0..400 {
        let start: Joints = std::array::from_fn(|j| {
            rng.random_range(arm.limits[j].lower / 2.0..arm.limits[j].upper / 2.0)
        });
        // Long legs, and short ones of up to a few degrees.
        let reach = if k % 2 == 0 { 1.5 } else { 0.05 };
        let to: Joints = std::array::from_fn(|j| start[j] + rng.random_range(-reach..reach));
        let shares = straight_shares(&checker, start, &[to], &[1.0]);
        let [leaving, reaching] = shares[0].expect("a full-speed leg has shares");
        assert_eq!(leaving, exhaustive(&start, &to), "leg {k} leaving");
        assert_eq!(reaching, exhaustive(&to, &start), "leg {k} reaching");
        partial += usize::from(leaving < 1.0);
    }
    assert!(partial > 150, "{partial} legs left the clearance");
}

/// A release solved from `from` is routed from there with the straight
/// motion its solve checked, the same route `route_any` finds by checking
/// it again; from anywhere else it is routed anew. A hover (no switch)
/// keeps no motion.
#[test]
fn a_solved_release_is_routed_with_the_motion_its_solve_checked() {
    let arm = Arm::ur10();
    let (task, start, mut world) = empty_bench_cell(&arm);
    let station = Station::new(&mut world, &arm, &task);
    let above = SubGoal {
        tip: [0.6, -0.3, 0.3],
        suction: Suction::Keep,
    };
    let hover = station
        .solve(&above, 1, &start, 0.0, Load::FREE, 0.3)
        .expect("reachable");
    assert!(hover.straight.is_none(), "a hover keeps no motion");
    let release = SubGoal {
        tip: [0.6, -0.3, 0.1],
        suction: Suction::Off,
    };
    let solved = station
        .solve(&release, 2, &hover.joints, 0.0, Load::FREE, 0.3)
        .expect("reachable");
    assert!(
        solved.straight.is_some(),
        "a release keeps its checked motion"
    );
    let how = Connect::Straight;
    let anew = station
        .route_any(how, 2, hover.joints, solved.joints, 0.0, Load::FREE)
        .expect("free");
    let kept = station
        .route_solved(how, 2, hover.joints, solved.clone(), 0.0, Load::FREE)
        .expect("free");
    assert_eq!(kept, anew);
    // From elsewhere: routed anew, to the same joints.
    let (to, route) = station
        .route_solved(how, 2, start, solved.clone(), 0.0, Load::FREE)
        .expect("free");
    assert_eq!(to, solved.joints);
    let (first, last) = (route.samples.first(), route.samples.last());
    assert!(first.is_some_and(|q| joint_distance(q, &start) < 1e-6));
    assert!(last.is_some_and(|q| joint_distance(q, &solved.joints) < 1e-6));
}

/// Wide development cell 258: a 200 mm cup over a 115 mm product waiting
/// right under the start, 0.43 m from the base. The branch nearest
/// "ready" that can go down leans the upper arm forward through that
/// product (the elbow 8 cm over the table), so the first motion of every
/// package collided, for every planner. Told what stands there, the start
/// is on a branch clear of it; where the nearest branch is clear anyway,
/// it is unchanged.
#[test]
fn the_start_pose_keeps_clear_of_the_products_waiting_under_it() {
    let arm = Arm::ur10();
    let mut cell = common::bench_cell();
    cell.base = [-0.19, 0.04, 0.0];
    cell.suction = 0.2;
    cell.pending = ([0.18, -0.27], [0.30, 0.41]);
    cell.boxes[0].centre = [-0.66, 0.07];
    cell.boxes[0].size = [0.13, 0.63, 0.14];
    for (i, slot) in cell.slots.iter_mut().enumerate() {
        slot.position = [-0.66, 0.32 - 0.1 * i as f64];
    }
    let under_start = ProductBody {
        name: "tall".into(),
        centre: [0.24, 0.07, 0.0575],
        size: [0.08, 0.06, 0.115],
        yaw: 0.0,
    };
    let standing = [under_start];
    let mut among = Checker::new(&arm, &cell);
    among.set_products(&standing);

    let blind = home(&arm, &cell).expect("a start pose");
    assert!(
        among.check(&blind, None, None).is_some(),
        "the cell no longer shows the case: {blind:?}"
    );
    let start = home_among(&arm, &cell, &standing).expect("a start pose");
    assert_eq!(among.check(&start, None, None), None, "{start:?}");
    let tip = arm.tool_tip(among.base(), &start, cell.suction);
    let want = home_tip(&cell);
    assert!((tip - Point3::from(want)).norm() < 1e-6, "{tip:?}");

    // A product off to the side leaves the start where it was.
    let aside = ProductBody {
        name: "aside".into(),
        centre: [0.65, -0.45, 0.04],
        size: [0.05, 0.05, 0.08],
        yaw: 0.0,
    };
    let bench = common::bench_cell();
    assert_eq!(
        home_among(&arm, &bench, &[aside]),
        home(&arm, &bench),
        "a clear start changed"
    );
}

/// The motion an independent probe found (a UR10 on a 400 mm riser
/// carrying a 70 x 70 x 150 mm vase 80 mm above the table past a 140 mm
/// lamp): its smoothed commands, checked as they will be sent with the
/// vase held, meet the lamp, whose corner the vase grazes between
/// commands a degree apart (`collision::tests` has the geometry).
#[test]
fn a_carried_product_grazing_a_neighbour_between_full_checks_is_found() {
    use crate::collision::graze::{self, along};
    let arm = Arm::ur10();
    let cell = graze::cell();
    let mut checker = Checker::new(&arm, &cell);
    checker.set_products(&[graze::lamp()]);
    let mut exact = Checker::with_padding(&arm, &cell, 0.0, 0.0);
    exact.set_products(&[graze::lamp()]);
    let vase = graze::vase();
    // Motions of a degree and a half across the graze, from each of 160
    // starts: the commands' full checks fall a degree apart, anywhere
    // along it.
    let mut tried = 0;
    for k in 0..160 {
        let s0 = -0.04 + 0.00025 * k as f64;
        let (from, to) = (along(s0), along(s0 + 0.026));
        if [from, to]
            .iter()
            .any(|q| checker.check(q, Some(&vase), None).is_some())
        {
            continue;
        }
        // Only motions whose straight way the vase itself meets the lamp
        // on (400 steps, no padding).
        let grazes = (0..=400).any(|t| {
            let q: Joints = std::array::from_fn(|j| from[j] + (to[j] - from[j]) * t as f64 / 400.0);
            exact.check(&q, Some(&vase), None).is_some()
        });
        if !grazes {
            continue;
        }
        tried += 1;
        let checked = checked_samples(&arm, &checker, from, &[to], Load::holding(&vase));
        assert!(
            matches!(
                checked,
                Err(Unchecked::Collides(Hit::Bodies { b: packwright_interface::world::Body::Product(ref n), .. })) if n == "lamp"
            ),
            "from {s0} rad on: {:?}",
            checked.map(|s| s.len())
        );
    }
    assert!(tried >= 8, "{tried} grazing motions with both ends free");
}

/// A world that is nowhere but where it says its products are: each
/// observation shows `products`, which the test moves.
struct Shown {
    products: Vec<Seen>,
}

impl World for Shown {
    fn control_period(&self) -> f64 {
        0.002
    }
    fn observe(&self) -> Observation {
        Observation {
            time: 0.0,
            joints: [0.0; DOF],
            suction: false,
            products: self.products.clone(),
        }
    }
    fn command(&mut self, _: &Joints) -> Result<(), WorldError> {
        Ok(())
    }
    fn set_suction(&mut self, _: bool) -> Result<(), WorldError> {
        Ok(())
    }
    fn step(&mut self) -> Result<(), WorldError> {
        Ok(())
    }
    fn take_collisions(&mut self) -> Vec<Contact> {
        Vec::new()
    }
}

/// A product the run never picked that ends more than the success radius
/// from where it stood (knocked over by a touch the world did not count)
/// is reported and the package is not complete; one nudged less is not,
/// nor one the run handled (its own outcome says what became of it).
#[test]
fn a_product_never_picked_that_moved_is_reported_as_disturbed() {
    let arm = Arm::ur10();
    let product = |name: &str| ProductSpec {
        name: name.into(),
        size: [0.05; 3],
        mass: 0.2,
    };
    let task = OrderTask {
        cell: common::bench_cell(),
        products: ["picked", "unattempted", "unselected", "nudged"]
            .map(product)
            .to_vec(),
        assignment: vec![(0, 0), (1, 1)],
    };
    let seen = |name: &str, x: f64| Seen {
        name: name.into(),
        centre: [x, -0.3, 0.025],
        yaw: 0.0,
    };
    let standing = vec![
        seen("picked", 0.5),
        seen("unattempted", 0.6),
        seen("unselected", 0.7),
        seen("nudged", 0.8),
    ];
    let mut world = Shown {
        products: standing.clone(),
    };
    let mut station = Station::new(&mut world, &arm, &task);
    let mut rows = vec![station.row(0, 0), station.row(1, 1)];
    rows[0].outcome = Outcome::Failed(Failure::MovedLater);
    station.world.products = vec![
        seen("picked", 0.3),
        seen("unattempted", 0.63),
        seen("unselected", 0.75),
        seen("nudged", 0.81),
    ];
    let report = station.finish(PlannerKind::Expert, rows, Vec::new());
    let moved: Vec<(&str, i64)> = report
        .disturbed
        .iter()
        .map(|d| (d.product.as_str(), (d.moved_m * 1000.0).round() as i64))
        .collect();
    assert_eq!(moved, [("unattempted", 30), ("unselected", 50)]);
    assert!(!report.complete);
    assert_eq!(
        report.disturbed[1].to_string(),
        "`unselected`, never picked, moved 50 mm from where it stood"
    );
}

/// A sub-goal whose every arm pose collides (a carried product over a
/// product standing taller than raising it could clear) is unreachable,
/// and says what the nearest pose meets: the carried product, not the
/// arm's reach.
#[test]
fn an_unreachable_sub_goal_says_what_its_nearest_pose_meets() {
    let arm = Arm::ur10();
    let (task, start, mut world) = empty_bench_cell(&arm);
    let mut station = Station::new(&mut world, &arm, &task);
    // Its top 0.9 m up: the syrup's bottom, 0.18 m under the tip, stays
    // below it up to 0.5 m over the sub-goal.
    station.checker.set_products(&[ProductBody {
        name: "pillar".into(),
        centre: [0.6, -0.3, 0.45],
        size: [0.06, 0.06, 0.9],
        yaw: 0.0,
    }]);
    let syrup = Held::under_cup(
        "syrup",
        [0.045, 0.045, 0.18],
        task.cell.suction,
        nalgebra::Vector3::zeros(),
    );
    let goal = SubGoal {
        tip: [0.6, -0.3, 0.33],
        suction: Suction::Keep,
    };
    let failed = station.solve(&goal, 1, &start, 0.0, Load::holding(&syrup), 0.33);
    let Err(Failure::Unreachable { met: Some(hit), .. }) = failed else {
        panic!("unreachable with what it meets: {failed:?}");
    };
    // The nearest pose meets the pillar (with the held syrup or the wrist
    // above it, whichever the check finds first).
    assert!(
        matches!(&hit, Hit::Bodies { b: Body::Product(p), .. } if p == "pillar"),
        "{hit:?}"
    );
    // With nothing in the way, the same sub-goal is reached.
    station.checker.set_products(&[]);
    assert!(
        station
            .solve(&goal, 1, &start, 0.0, Load::holding(&syrup), 0.33)
            .is_ok()
    );
}

/// A point the held product is carried through, over a product standing
/// taller than the carrying height (a 180 mm syrup over a 220 mm
/// bottle), is raised until every part clears it; the point above
/// nothing stays where it was.
#[test]
fn a_carried_point_over_a_taller_product_is_raised_until_clear() {
    let arm = Arm::ur10();
    let (task, start, mut world) = empty_bench_cell(&arm);
    let mut station = Station::new(&mut world, &arm, &task);
    let bottle = ProductBody {
        name: "bottle".into(),
        centre: [0.6, -0.3, 0.11],
        size: [0.06, 0.06, 0.22],
        yaw: 0.0,
    };
    station.checker.set_products(std::slice::from_ref(&bottle));
    let syrup = Held::under_cup(
        "syrup",
        [0.045, 0.045, 0.18],
        task.cell.suction,
        nalgebra::Vector3::zeros(),
    );
    let load = Load::holding(&syrup);
    let over = SubGoal {
        tip: [0.6, -0.3, 0.33],
        suction: Suction::Keep,
    };
    let solved = station
        .solve(&over, 1, &start, 0.0, load, 0.33)
        .expect("raised until clear");
    let tip = station.tip(&solved.joints);
    assert!((tip[0] - 0.6).hypot(tip[1] + 0.3) < 1e-6, "{tip:?}");
    // The syrup's bottom over the bottle's top, in whole raise steps.
    assert!(tip[2] - 0.18 > 0.22, "{tip:?}");
    assert!(tip[2] < 0.33 + RAISE_STEP * f64::from(MAX_CARRY_RAISES));
    let steps = (tip[2] - 0.33) / RAISE_STEP;
    assert!((steps - steps.round()).abs() < 1e-6, "{tip:?}");
    assert!(
        station
            .checker
            .check(&solved.joints, Some(&syrup), None)
            .is_none()
    );
    // One step lower, every arm pose meets the bottle.
    let lower = nalgebra::Point3::new(0.6, -0.3, tip[2] - RAISE_STEP);
    assert!(reach(&station.checker, lower, 0.0, &start, load).is_none());
    // Beside the bottle, nothing is raised.
    let beside = SubGoal {
        tip: [0.6, 0.0, 0.33],
        suction: Suction::Keep,
    };
    let solved = station
        .solve(&beside, 1, &start, 0.0, load, 0.33)
        .expect("reached");
    assert!((station.tip(&solved.joints)[2] - 0.33).abs() < 1e-6);
}

/// `grips` gives every free grip shape, nearest the arm first, and
/// `grip` is its first: a caller that cannot reach one shape's hover
/// goes on to the next (the learned regrip after a change of shape).
#[test]
fn grips_offers_every_free_shape_nearest_first_and_grip_is_the_first() {
    let arm = Arm::ur10();
    let (task, start, mut world) = empty_bench_cell(&arm);
    let station = Station::new(&mut world, &arm, &task);
    let goals = crate::expert::picking([0.6, -0.2, 0.025], 0.05, 0.15);
    let cube = Held::under_cup(
        "cube",
        [0.05; 3],
        task.cell.suction,
        nalgebra::Vector3::zeros(),
    );
    let lifted = station.checker.lifting(cube, None);
    let held = |_: &Joints| lifted.clone();
    let loads = [Load::FREE, Load::FREE.guarded(task.cell.descent)];
    let shapes: Vec<[Solved; 3]> = station.grips(&goals, &start, 0.0, loads, &held).collect();
    assert!(shapes.len() >= 2, "{} free shapes", shapes.len());
    let first = station
        .grip(&goals, &start, 0.0, loads, &held)
        .expect("a free shape");
    assert_eq!(first[1].joints, shapes[0][1].joints);
    let contacts: Vec<Joints> = shapes.iter().map(|s| s[1].joints).collect();
    for pair in contacts.windows(2) {
        assert_ne!(pair[0], pair[1]);
        assert!(joint_distance(&pair[0], &start) <= joint_distance(&pair[1], &start));
    }
    for [over, at, up] in &shapes {
        for q in [over.joints, at.joints, up.joints] {
            assert!(arm.within_limits(&q));
        }
        // The descent ends at the contact; the lift starts there.
        assert_eq!(
            at.straight.as_ref().map(|(from, _)| *from),
            Some(over.joints)
        );
        assert_eq!(up.straight.as_ref().map(|(from, _)| *from), Some(at.joints));
    }
}

/// A product the handling left more than the success radius from its
/// goal is misplaced, or not gripped when it still stands where it was
/// picked from (a learned grip beside a small product's face was
/// reported as "released 1.399 m from its goal"). Neither is a failure
/// at a sub-goal: no stage is named for them.
#[test]
fn a_product_left_where_it_stood_was_not_gripped() {
    let row = |error_m| ProductReport {
        product: "cube".into(),
        slot: "s".into(),
        planning_s: 0.0,
        execution_s: 0.0,
        bound_s: 0.0,
        error_m: Some(error_m),
        turn: Some(1),
        outcome: Outcome::NotAttempted,
        failed_in: None,
    };
    let placing = Some(Stage::Placing);
    let mut r = row(1.399);
    assert_eq!(
        judge(&mut r, Ok(()), true, placing),
        Err(Failure::NotGripped { error_m: 1.399 })
    );
    assert_eq!(r.failed_in, None);
    let mut r = row(1.399);
    assert_eq!(
        judge(&mut r, Ok(()), false, placing),
        Err(Failure::Misplaced { error_m: 1.399 })
    );
    let mut r = row(0.001);
    assert_eq!(judge(&mut r, Ok(()), true, placing), Ok(()));
    assert_eq!(r.outcome, Outcome::Packed);
    assert_eq!(r.failed_in, None);
}

/// A failure at a sub-goal names its stage: "sub-goal 1" alone reads the
/// same for the hover over a product and for the approach to the box (a
/// helper read a placing approach as a pick's).
#[test]
fn a_failure_at_a_sub_goal_names_its_stage() {
    let mut r = ProductReport {
        product: "tea".into(),
        slot: "s".into(),
        planning_s: 0.0,
        execution_s: 0.0,
        bound_s: 0.0,
        error_m: None,
        turn: Some(1),
        outcome: Outcome::NotAttempted,
        failed_in: None,
    };
    let why = Failure::NoPath { subgoal: 1 };
    assert_eq!(
        judge(&mut r, Err(why.clone()), false, Some(Stage::Placing)),
        Err(why)
    );
    assert_eq!(r.failed_in, Some(Stage::Placing));
    assert_eq!(
        r.outcome_text(),
        "failed while placing: RRT-Connect found no path to sub-goal 1"
    );
    // The way back up from a release is no stage.
    judge(&mut r, Err(Failure::NoPath { subgoal: 1 }), false, None).ok();
    assert_eq!(r.failed_in, None);
}
