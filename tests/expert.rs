//! The scripted expert and RRT-Connect on generated cells whose box and
//! products stand on opposite sides of the robot: every feasible package is
//! packed. On development seed 1 (box behind the robot, products in front)
//! the inverse-kinematics solution nearest the arm at "above the slot" has
//! the wrist flipped, and the straight motion to it folds the wrist into the
//! forearm; the loop then joins another solution of the same cup pose
//! (`Station::route_any`). These scenarios failed before that.
//!
//! The lift carries the product: two cells where the arm's shape at the
//! full lift height collides with itself, so the nearest free solution is
//! another shape, and the joint motion to it dragged the just-gripped
//! product through the table while it was checked as if nothing were held.
//! The lift is now checked carrying the product and lowered until the arm
//! keeps its shape.

mod common;
use common::{packwright, scratch};
use std::fs;
use std::process::Output;

/// `packwright` with `args`, which must exit 0 (the package complete):
/// else the test fails with its report.
fn packs(args: &[&str]) -> Output {
    let out = packwright(args);
    assert!(
        out.status.success(),
        "{args:?}: exit {:?}\n{}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

#[test]
fn front_to_back_packages_are_packed_by_the_expert_and_rrt_connect() {
    let dir = scratch("expert", "front-to-back");
    let out = packwright(&[
        "generate",
        "--seed",
        "1",
        "-o",
        dir.to_str().expect("utf-8"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pack = dir.join("gen_1.pack");
    let pack = pack.to_str().expect("utf-8");
    for (scenario, planner) in [
        ("gen_1_case1_n1/04", "expert"),
        ("gen_1_case1_n2/06", "expert"),
        ("gen_1_case1_n2/15", "expert"),
        ("gen_1_case1_n1/05", "rrt"),
    ] {
        packs(&[
            "execute",
            pack,
            "--scenario",
            scenario,
            "--planner",
            planner,
            "--json",
        ]);
    }
}

/// A tote behind the robot (products in front, far out) and a robot on a
/// riser with a product near its axis: the held product touched the table
/// during the lift in the simulator ("held:tea with table"), on motions
/// the checker had passed.
#[test]
fn the_lift_carries_the_product_off_the_table() {
    let tote = r#"cell back {
  robot ur10
  base (0, 0, 0)
  suction 120 mm
  pending (0.55, -0.35) to (0.95, 0.35)
  box tote (-0.62, 0.05) size (0.36, 0.44, 0.12)
  slot t1 (-0.72, -0.09)
  slot t2 (-0.72, 0.05)
  slot t3 (-0.72, 0.19)
  slot t4 (-0.54, -0.09)
}
product soap cube 60 mm
product tea box (80 mm, 50 mm, 60 mm)
product nuts cube 50 mm
product honey box (60 mm, 60 mm, 100 mm) mass 0.5
inventory shelf for back {
  soap (0.62, -0.25)
  tea (0.62, 0.25)
  nuts (0.85, -0.25)
  honey (0.85, 0.00)
}
order four for shelf {
  soap -> t2
  tea -> t3
  nuts -> t4
  honey -> t1
}
"#;
    let riser = r#"cell riser {
  robot ur10
  base (0, 0, 0.269)
  suction 100 mm
  pending (0.10, 0.20) to (0.25, 0.32)
  box b (1.093, 0) size (0.12, 0.12, 0.06)
  slot s (1.093, 0)
}
product c cube 32 mm
inventory inv for riser {
  c (0.164, 0.256)
}
order one for inv {
  c -> s
}
"#;
    let dir = scratch("expert", "lift");
    for (name, text, order) in [("tote", tote, "four"), ("riser", riser, "one")] {
        let pack = dir.join(format!("{name}.pack"));
        fs::write(&pack, text).expect("write the cell");
        let pack = pack.to_str().expect("utf-8");
        for planner in ["expert", "rrt"] {
            let out = packwright(&[
                "execute",
                pack,
                "--order",
                order,
                "--planner",
                planner,
                "--json",
            ]);
            // Exit 0: every product packed and nothing collided.
            assert!(
                out.status.success(),
                "{name} with {planner}: exit {:?}\n{}",
                out.status.code(),
                String::from_utf8_lossy(&out.stdout)
            );
        }
    }
}

/// Where the straight motion and both swings collide, the expert searches
/// (RRT-Connect, seeded by the sub-goal) instead of ending the package: it
/// gave up on `tests/cells/deep_wall.pack`'s order before, which is the
/// cell's one demonstration, so `train` could not replay it.
#[test]
fn the_expert_searches_where_every_straight_way_collides() {
    let run = || {
        packwright(&[
            "execute",
            "tests/cells/deep_wall.pack",
            "--order",
            "wall_side",
            "--planner",
            "expert",
            "--json",
        ])
    };
    let out = run();
    assert!(
        out.status.success(),
        "exit {:?}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout)
    );
    // Seeded: the same motion every run (the simulated time to the
    // millisecond; planning times are wall-clock).
    let time = |stdout: &[u8]| {
        let report: serde_json::Value = serde_json::from_slice(stdout).expect("JSON");
        report["time_s"].as_f64().expect("time_s")
    };
    assert_eq!(time(&run().stdout), time(&out.stdout));
}

/// A path RRT-Connect finds whose commands, checked as they will be sent,
/// graze an obstacle the start stands close to is searched for again
/// with the next seeds: in `tests/cells/florist.pack`'s scenario f_5/08
/// the back-up beside a packed 250 mm vase left wrist 3 next to it, and
/// the expert gave up on the card's hover after the first path.
#[test]
fn a_searched_path_whose_commands_collide_is_searched_for_again() {
    packs(&[
        "execute",
        "tests/cells/florist.pack",
        "--scenario",
        "f_5/08",
        "--planner",
        "expert",
        "--json",
    ]);
}

/// The expert and RRT-Connect pack in the order the file's demonstrations
/// teach, as the learned planner's reasoner does: in a cell taught
/// descending they handled the products in inventory order before, so
/// the planners were compared on different sequences (a helper's probe
/// cell, c8030).
#[test]
fn the_baselines_pack_in_the_demonstrated_order() {
    let text = r#"cell line {
  robot ur10
  base (0, 0, 0)
  suction 100 mm
  pending (0.45, -0.35) to (0.85, 0.35)
  box tray (-0.1, 0.7) size (0.36, 0.2, 0.06)
  slot a (-0.2, 0.7)
  slot b (-0.1, 0.7)
  slot c (0.0, 0.7)
}
product soap cube 50 mm
product tea cube 50 mm
product nuts cube 50 mm
inventory shelf for line {
  soap (0.6, -0.2)
  tea (0.6, 0.0)
  nuts (0.6, 0.2)
}
demos taught for shelf {
  choose 2 of soap, tea, nuts into a, b, c
  jitter 5 mm
  sequence descending
  seed 3
}
order three for shelf {
  soap -> a
  tea -> b
  nuts -> c
}
"#;
    let dir = scratch("expert", "sequence");
    let pack = dir.join("line.pack");
    fs::write(&pack, text).expect("write the cell");
    let pack = pack.to_str().expect("utf-8");
    for planner in ["expert", "rrt"] {
        let out = packs(&[
            "execute",
            pack,
            "--order",
            "three",
            "--planner",
            planner,
            "--json",
        ]);
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("a JSON report");
        let turns: Vec<(String, u64)> = report["products"]
            .as_array()
            .expect("product rows")
            .iter()
            .map(|r| {
                (
                    r["product"].as_str().unwrap_or_default().to_owned(),
                    r["turn"].as_u64().unwrap_or_default(),
                )
            })
            .collect();
        // Rows stay in the order's assignment order; the turns say the
        // products were handled last to first.
        let expected = [("soap", 3), ("tea", 2), ("nuts", 1)].map(|(p, t)| (p.to_owned(), t));
        assert_eq!(turns, expected, "{planner}");
    }
}

/// A box far behind the robot (`tests/cells/far_behind.pack`, a helper's
/// probe cell): after the first product, the upper arm met the table at
/// every height of the second's release from the arm's shape above the
/// slot, and the expert and RRT-Connect stopped where `check` accepted
/// the cell. The point above the slot is now solved in the release's
/// shape.
#[test]
fn a_release_far_behind_the_robot_is_reached_in_its_own_arm_shape() {
    for planner in ["expert", "rrt"] {
        packs(&[
            "execute",
            "tests/cells/far_behind.pack",
            "--order",
            "two",
            "--planner",
            planner,
            "--json",
        ]);
    }
}

/// A crate in front and a tall product behind (`tests/cells/far_corner.pack`,
/// a helper's probe cell): after a release in the crate's far corner,
/// the only free hover over the product has wrist 1 3.1 rad away past
/// the forearm, which RRT-Connect's samples did not find a way to; the
/// expert and RRT-Connect stopped, and the cell's one demonstration could
/// not be replayed. The same pose with wrist 1 a whole turn round is
/// searched for too.
#[test]
fn a_hover_past_the_forearm_is_searched_for_a_whole_turn_round() {
    let pack = "tests/cells/far_corner.pack";
    for planner in ["expert", "rrt"] {
        packs(&[
            "execute",
            pack,
            "--order",
            "corner",
            "--planner",
            planner,
            "--json",
        ]);
    }
    let dir = scratch("expert", "far-corner");
    let compiled = dir.join("compiled");
    let motion = dir.join("motion.safetensors");
    let out = packwright(&["compile", pack, "-o", compiled.to_str().expect("utf-8")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = packwright(&[
        "demonstrate",
        compiled.to_str().expect("utf-8"),
        "-o",
        motion.to_str().expect("utf-8"),
    ]);
    assert!(
        out.status.success(),
        "the demonstration replays: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Helper X's demonstration the expert could not replay
/// (tests/cells/lift_beside_tall.pack): after the first product, the
/// second's lift in the arm's nearest shape meets a 206 mm product beside
/// it. The stage was solved again in the contact's shape, but the way to
/// its hover went to another solution (another shape), where the descent
/// and the lift were solved again nearest it and failed as before. The
/// hover is now reached in the shape the stage was solved in.
#[test]
fn a_stage_solved_in_the_contacts_shape_is_reached_in_it() {
    for planner in ["expert", "rrt"] {
        let out = packwright(&[
            "execute",
            "tests/cells/lift_beside_tall.pack",
            "--order",
            "d9",
            "--planner",
            planner,
        ]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{planner}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}
