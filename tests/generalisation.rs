//! Generalisation, end to end on two generated cells (`packwright
//! generate`): a short training on each cell's sparse demonstrations, then
//! the learned planner on scenarios the demonstrations never showed: a
//! slot no demonstration used, and one product more than taught. gen_103
//! has its box behind a robot on a 280 mm riser and was taught in
//! descending order; gen_101 has its box on the left and was taught a
//! listed priority; gen_5 has its box and products on opposite sides (the
//! swing back from the box is 180 degrees). The learned planner must pack
//! them without falling back to RRT-Connect too. These seeds are
//! development seeds, not the README's reported family. The rest run the
//! bundled model on development cells where it once fell back (standard
//! and wide, `generate --family wide`), and on hand-written cells unlike
//! every generated one (tests/cells/).

mod common;
use common::{packwright, scratch};
use packwright_pipeline::generate::{Family, Generated, SuiteKind, family_cell, generated_cell};
use std::fs;
use std::path::Path;
use std::process::Output;

fn text(out: &Output) -> String {
    format!(
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

fn json(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("JSON ({e}): {}", text(out)))
}

/// `pack` compiled into `dir/out` (exit 0), then `train` on it with
/// `dagger_rounds` into `dir/model`, quiet, with JSON metrics: the model
/// directory and `train`'s output (its exit code the caller's to judge).
fn compiled_and_trained(pack: &str, dir: &Path, dagger_rounds: u32) -> (String, Output) {
    let compiled = dir.join("out").display().to_string();
    let model = dir.join("model").display().to_string();
    let out = packwright(&["compile", pack, "-o", &compiled]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let rounds = dagger_rounds.to_string();
    let out = packwright(&[
        "train",
        &compiled,
        "-o",
        &model,
        "--dagger-rounds",
        &rounds,
        "--quiet",
        "--json",
    ]);
    (model, out)
}

/// Scenarios of each suite run by the learned planner.
const SCENARIOS: usize = 6;

fn learns_cell(seed: u64) {
    let cell = family_cell(seed);
    let dir = scratch("generalisation", &cell.name);
    let pack = dir.join(cell.file_name());
    fs::write(&pack, &cell.text).expect("generated file written");
    let pack = pack.display().to_string();
    let (model, out) = compiled_and_trained(&pack, &dir, 1);
    // Exit 1: a demonstration the expert could not replay (reported).
    assert!(matches!(out.status.code(), Some(0 | 1)), "{}", text(&out));
    let report = json(&out);
    let rule = &report["sequence"];
    let taught = format!("{:?}", cell.sequence).to_lowercase();
    assert!(
        rule.as_str() == Some(taught.as_str()) || rule.get(&taught).is_some(),
        "{}: taught {taught}, inferred {rule}",
        cell.name
    );
    let reasoner = report["reasoner"]["valid_metric"].as_f64().unwrap_or(0.0);
    assert!(
        reasoner >= 0.97,
        "{}: held-out reasoner {reasoner}",
        cell.name
    );
    let subgoal = report["subgoal"]["valid_metric"].as_f64().unwrap_or(1.0);
    assert!(
        subgoal <= 0.015,
        "{}: held-out sub-goal error {subgoal} m",
        cell.name
    );

    let untaught = cell.suite(SuiteKind::Untaught).name.clone();
    let more = cell.suite(SuiteKind::Case1N1).name.clone();
    let limit = SCENARIOS.to_string();
    let out = packwright(&[
        "eval", &pack, "--model", &model, "--suite", &untaught, &more, "--limit", &limit,
        "--quiet", "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let eval = json(&out);
    let rows = eval["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 2, "{eval}");
    for row in rows {
        assert_eq!(row["planner"], "learned");
        assert_eq!(row["cell_taught"], true);
        let name = &row["suite"];
        let reasoner = row["reasoner_sr"]["rate"].as_f64().unwrap_or(0.0);
        assert_eq!(reasoner, 1.0, "{name}: reasoner SR {reasoner}: {row}");
        let sr = row["sr"]["rate"].as_f64().unwrap_or(0.0);
        assert!(sr >= 5.0 / 6.0, "{name}: SR {sr}: {row}");
        let alone = row["sr_no_fallback"]["rate"].as_f64().unwrap_or(0.0);
        assert!(
            alone >= 5.0 / 6.0,
            "{name}: SR without fallback {alone}: {row}"
        );
    }
}

#[test]
fn a_model_generalises_on_a_cell_with_its_box_behind_the_robot() {
    learns_cell(103);
}

#[test]
fn a_model_generalises_on_a_cell_taught_a_priority_list() {
    learns_cell(101);
}

#[test]
fn a_model_generalises_on_a_cell_with_box_and_products_on_opposite_sides() {
    learns_cell(5);
}

/// Three hand-written demonstrations (tests/cells/handful.pack): orders
/// of two and four products, one priority list. A model trained on them
/// alone (seed 0) must keep the rule on packages of five products into
/// slots no demonstration used, and where a worker packed some first: a
/// product packed at the chain's head is skipped, as one outside the
/// order is. Before each picking decision was also taught with the
/// products the rule skips swapped (outside the order and packed), this
/// model chose a packed product again in 19 of the 30 packages of five.
#[test]
fn a_model_taught_three_hand_written_demonstrations_keeps_its_rule_on_larger_orders() {
    let dir = scratch("generalisation", "handful");
    let pack = "tests/cells/handful.pack";
    let (model, out) = compiled_and_trained(pack, &dir, 0);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let report = json(&out);
    assert_eq!(report["demonstrations"], 3, "{report}");
    let listed = &report["sequence"]["listed"];
    let place = |name: &str| {
        listed
            .as_array()
            .and_then(|l| l.iter().position(|n| n == name))
            .unwrap_or_else(|| panic!("{name} in the listed rule {listed}"))
    };
    assert!(place("jar") < place("card"), "{listed}");
    assert!(
        place("mug") < place("tea") && place("tea") < place("tin"),
        "{listed}"
    );
    assert!(place("tin") < place("soap"), "{listed}");
    // The demonstrations never show jar or card with the other four:
    // those 8 pairs are named as ordered by the inventory, not taught.
    let guessed = report["warnings"]
        .as_array()
        .and_then(|w| w.iter().find(|w| w["kind"] == "pairs_guessed"))
        .unwrap_or_else(|| panic!("a pairs_guessed warning: {report}"));
    assert_eq!(
        (&guessed["ordered"], &guessed["pairs"]),
        (&7.into(), &15.into()),
        "{guessed}"
    );
    let untaught = guessed["untaught"].as_array().expect("untaught pairs");
    assert_eq!(untaught.len(), 8, "{guessed}");
    assert!(
        untaught.contains(&serde_json::json!(["jar", "mug"])),
        "{guessed}"
    );

    let out = packwright(&[
        "eval",
        pack,
        "--model",
        &model,
        "--reasoner-only",
        "--quiet",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let eval = json(&out);
    let rows = eval["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 3, "{eval}");
    for row in rows {
        let reasoner = row["reasoner_sr"]["rate"].as_f64().unwrap_or(0.0);
        assert_eq!(reasoner, 1.0, "{}: reasoner SR {reasoner}", row["suite"]);
    }
}

/// One hand-written demonstration of two of six products
/// (tests/cells/one_demo.pack, a wide cell with the products behind the
/// robot). The model taught it packs four products, none of them shown
/// in the demonstration but one, without falling back: the expert's
/// rehearsals taught the motion networks the products and slots the
/// demonstration did not move. Taught the demonstration's motions alone,
/// this model hovered beside the unseen products and came down onto them
/// through their neighbours: RRT-Connect took over in each of these four
/// packages.
#[test]
fn a_model_taught_one_demonstration_moves_the_products_it_never_saw() {
    let dir = scratch("generalisation", "one_demo");
    let pack = "tests/cells/one_demo.pack";
    let (model, out) = compiled_and_trained(pack, &dir, 2);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let report = json(&out);
    assert_eq!(report["demonstrations"], 1, "{report}");
    assert_eq!(report["rehearsals"], 2, "{report}");
    assert_eq!(report["rehearsed"], 2, "{report}");
    let out = packwright(&[
        "eval",
        pack,
        "--model",
        &model,
        "--suite",
        "wide_9812_case1_n2",
        "--limit",
        "4",
        "--quiet",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let eval = json(&out);
    let row = &eval["rows"][0];
    for rate in ["reasoner_sr", "sr", "sr_no_fallback"] {
        assert_eq!(row[rate]["rate"].as_f64(), Some(1.0), "{rate}: {row}");
    }
}

/// One hand-written demonstration, taught in reverse inventory order
/// (tests/cells/flat_beside_crate.pack, helper I's probe cell). The model
/// taught it was taught the arm's one shape: from above the crate, its
/// steps to the hover over a flat tray behind the robot kept that shape,
/// and the straight motion there put the upper arm into the crate at
/// every height; its steps from the arm's other shapes fell short, so
/// RRT-Connect took the stage over (both scenarios). The end its steps
/// reach is now also tried in the arm's other shapes, as the expert's
/// hover is in the elbow's other one: no fallback.
#[test]
fn a_model_taught_one_shape_hovers_in_another_where_its_own_meets_a_crate() {
    let dir = scratch("generalisation", "flat_beside_crate");
    let pack = "tests/cells/flat_beside_crate.pack";
    let (model, out) = compiled_and_trained(pack, &dir, 2);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let out = packwright(&[
        "eval", pack, "--model", &model, "--suite", "c1_6of7", "--limit", "2", "--quiet", "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let eval = json(&out);
    let row = &eval["rows"][0];
    for rate in ["reasoner_sr", "sr", "sr_no_fallback"] {
        assert_eq!(row[rate]["rate"].as_f64(), Some(1.0), "{rate}: {row}");
    }
}

/// A model taught one cell runs another of the line (helper AA's
/// tests/cells/turned/): taught with the box in front of its products,
/// every carry turned counter-clockwise, and in a cell whose short way to
/// the box is clockwise the sub-goal planner put the approach on the far
/// side (its turn input clamped to the turns taught): the base swung 241
/// degrees instead of 119, the package 25% longer than the expert's. Each
/// sub-goal is now also taught the other way round (mirrored).
#[test]
fn a_model_taught_turning_one_way_turns_the_short_way_in_another_cell() {
    let dir = scratch("generalisation", "turned");
    let (model, out) = compiled_and_trained("tests/cells/turned/taught_cell.pack", &dir, 0);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let time = |planner: &[&str]| {
        let mut args = vec![
            "execute",
            "tests/cells/turned/other_cell.pack",
            "--scenario",
            "side_plain",
            "--json",
        ];
        args.extend(planner);
        let out = packwright(&args);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out));
        let report = json(&out);
        assert_eq!(report["complete"], true, "{report}");
        report["time_s"].as_f64().unwrap_or(f64::INFINITY)
    };
    let learned = time(&["--model", &model]);
    let expert = time(&["--planner", "expert"]);
    assert!(
        learned <= 1.1 * expert,
        "learned {learned} s against the expert's {expert} s"
    );
}

/// Found by a probe of 100 cells no one had looked at (seeds 3000-3099,
/// the bundled model, which was not taught them): in gen_3078 a learned
/// release whose motion collides is handed to RRT-Connect at the expert's
/// release, whose straight descent from the learned "above the slot" (a
/// few millimetres off) slanted into the box's wall: "unreachable", the
/// product not placed. It now goes through the expert's "above the slot".
#[test]
fn a_release_handed_to_rrt_connect_goes_down_from_the_experts_above_the_slot() {
    let report = executes_with_the_bundled_model(&family_cell(3078), SuiteKind::Case1N, "02");
    assert_eq!(report["complete"], true, "{report}");
}

/// Found by helper Y's probe of other arms (a UR16e, the bundled model
/// taught the UR10): a learned release whose motion collides went to
/// RRT-Connect, whose releases nearest the arm shape the policy left all
/// fold the upper arm into wrist 1, and the package stopped ("every arm
/// pose there collides") where the expert and RRT-Connect pack it. The
/// fallback now tries the release's other arm shapes, as the expert's
/// own placing does.
#[test]
fn a_release_handed_to_rrt_connect_tries_the_releases_other_arm_shapes() {
    let out = packwright(&[
        "execute",
        "tests/cells/ur16e/release_shape.pack",
        "--scenario",
        "more6727/1",
        "--json",
    ]);
    let report = json(&out);
    assert_eq!(report["complete"], true, "{}", text(&out));
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
}

/// Found by helper Y's probe of other arms: a UR3e cannot hold its cup
/// 0.35 m over a pending area 0.37 m out (the UR10's start height), and
/// `check` refused the cell for the start alone (E039), though every pose
/// the packing needs is reached. The start is now the highest of 0.35,
/// 0.30, 0.25 and 0.20 m the arm reaches free.
#[test]
fn a_small_arm_starts_lower_where_the_ur10s_start_is_out_of_its_reach() {
    let pack = "tests/cells/ur3e/start_low.pack";
    let out = packwright(&["check", pack]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let out = packwright(&[
        "execute",
        pack,
        "--order",
        "o80",
        "--planner",
        "expert",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert_eq!(json(&out)["complete"], true, "{}", text(&out));
}

/// Found by the same probe (cells 3063 and 3081): a learned hover swung
/// about half a turn (either way round as short) and ended 4 mrad inside
/// the base's limit; the descent onto the product, a few milliradians on,
/// was reachable only a whole turn back, and that swing swept the cup
/// into the box (RRT-Connect took it over). The swing now ends the other
/// way round, with room: no fallback.
#[test]
fn a_half_turn_swing_ending_at_the_base_limit_goes_the_other_way_round() {
    packs_without_fallback(3081, SuiteKind::Case1N1, "02");
}

/// Development cell 2005 (`packwright generate --seed 2005`): a learned
/// release a few millimetres off in a narrow box, where the held product
/// touched the wall, went to RRT-Connect and the expert's release. It is
/// now moved just inside the walls: no fallback.
#[test]
fn a_release_against_the_wall_of_a_narrow_box_is_moved_inside() {
    packs_without_fallback(2005, SuiteKind::Case1N1, "01");
}

/// Development cell 2173: the same with the cup itself against the wall
/// of a deep box, above a small product (two fallbacks before).
#[test]
fn a_release_whose_cup_touches_the_wall_of_a_deep_box_is_moved_inside() {
    packs_without_fallback(2173, SuiteKind::Case1N, "01");
}

/// Development cell 2002: a 60 mm cube in a box 80 mm wide, where the
/// padded product has 4 mm to spare. The learned release was inside by
/// 0.3 mm, but the policy reaches a release within 2 mm: it ended 1.3 mm
/// beyond and the product touched the wall (a fallback). A colliding
/// release already inside is now reached within 0.5 mm too: none.
#[test]
fn a_release_just_inside_a_tight_box_is_reached_closely() {
    packs_without_fallback(2002, SuiteKind::Case1N2, "01");
}

/// Development cell 2144: a learned release 2.7 mm low and 4 mm towards
/// the wall of a box 80 mm wide. Raised, it still touched the wall; moved
/// inside at its own height, the product touched the floor (a fallback).
/// It is now moved inside at the expert's height (5 mm up): none.
#[test]
fn a_low_release_against_a_wall_is_moved_inside_at_the_experts_height() {
    packs_without_fallback(2144, SuiteKind::Case1N1, "02");
}

/// Development cell 2172: a short cup (80 mm) releasing a low product in
/// a deep box (100 mm), where wrist 3 meets the rim unless the release is
/// about 13 mm higher; the expert raises its own release twice (20 mm).
/// The learned release, half a millimetre above the expert's, was capped
/// at 20 mm above the expert's, so that it could rise only once: two
/// fallbacks before, none now.
#[test]
fn a_release_whose_wrist_meets_the_rim_of_a_deep_box_is_raised_as_far_as_the_experts() {
    packs_without_fallback(2172, SuiteKind::Case1N1, "01");
}

/// Development cell 2255: products behind a robot on a riser, the box in
/// front. From a release at the far end of the box, the next product was
/// almost straight behind: the policy turned the base little and folded
/// the elbow past its limit (a fallback). The steps now go through a via
/// point half way round: none.
#[test]
fn a_product_straight_behind_the_arm_is_reached_by_turning_half_way_first() {
    packs_without_fallback(2255, SuiteKind::Case1N, "01");
}

/// Development cell 2251: the learned "above the slot" ended with the
/// base 3 mrad inside its limit, and the release's steps took it 6 mrad
/// past: brought a whole turn back, the descent spun the arm round into
/// the box's outside (a fallback). Held at the limit: none.
#[test]
fn a_release_a_little_past_the_base_limit_is_held_at_the_limit() {
    packs_without_fallback(2251, SuiteKind::Case1N1, "01");
}

/// Development cell 2382: a 30 mm product let go in a box 80 mm wide and
/// 90 mm deep with an 80 mm cup. The learned release, 1.3 mm outside the
/// band where the cup clears the walls, had wrist 3 against the rim;
/// raised, the cup met the wall; moved inside the band, wrist 3 still met
/// the rim at the band's edge (a fallback). The kept release is now
/// raised as the learned one is: none.
#[test]
fn a_release_kept_inside_a_narrow_deep_box_is_raised_clear_of_the_rim() {
    packs_without_fallback(2382, SuiteKind::Case1N1, "03");
}

/// Development cell 2612: a 30 mm cube let go in a box 70 mm wide with
/// an 80 mm cup, where the cup's padded radius leaves it 1 mm either side
/// of the centre line. The learned release, raised, left the cup 0.05 mm
/// inside that band; the way back up, through five via points, bowed
/// into the wall and the package stopped. Through twenty where five
/// touch: packed.
#[test]
fn the_way_up_from_a_release_near_a_narrow_boxs_wall_takes_finer_via_points() {
    packs_without_fallback(2612, SuiteKind::Case1N, "05");
}

/// Development cell 2616: a box 66 mm wide, whose inside (58 mm) is
/// narrower than the cup's padded diameter (60 mm). No release inside it
/// is free: the expert lets go above the rim (its release raised until
/// free), while a colliding learned release could rise only 2 cm above
/// the expert's nominal one (a fallback at every release). The cap is
/// now 2 cm above where the expert lets go from there: none.
#[test]
fn a_release_into_a_box_narrower_than_the_cup_rises_as_the_experts_does() {
    packs_without_fallback(2616, SuiteKind::Case1N1, "01");
}

/// A cell unlike every generated one (tests/cells/deep_carton.pack): a
/// carton 200 mm deep and products up to 120 mm tall, where the bundled
/// model learned from boxes 60 to 100 mm deep and products up to 60 mm.
/// With the rim's height and the product's height as inputs, the sub-goal
/// planner put releases 3 cm off their slots there (fallbacks); its
/// heights are now over surfaces. Near the base the forearm then met the
/// carton's wall at the bottom of the carton, where the expert lets go
/// higher up: the learned release now may too.
#[test]
fn a_deeper_box_and_taller_products_than_any_taught_are_packed_without_fallback() {
    for scenario in ["deep_case1/01", "deep_case2/02"] {
        file_packs_without_fallback("tests/cells/deep_carton.pack", scenario);
    }
}

/// A small product let go at the bottom of a deep tote
/// (tests/cells/deep_tote.pack, helper AA's cell): in the arm's shape
/// it was carried in, the forearm met the tote's near wall at every
/// height the release was raised to, and the release went to
/// RRT-Connect. It is now tried in the arm's other shapes, as the
/// expert's inverse kinematics takes its nearest free solution.
#[test]
fn a_release_deep_in_a_tote_changes_the_arms_shape_as_the_experts_does() {
    file_packs_without_fallback("tests/cells/deep_tote.pack", "same_as_taught");
}

/// Boxes close to the robot's base (tests/cells/near_base.pack, after a
/// helper's probe cells 7102 and 7111). A 300 mm deep tote beside the
/// base: from the usual "ready" shape the arm started in, the upper arm
/// met the tote's wall at every height on the way to it, and every
/// scenario fell back (two or three times per package); the expert goes
/// there in another shape. The policy's steps are now taken from the
/// same pose in the arm's other shapes, the arm changing its shape on
/// the way to the nearest end that is free.
#[test]
fn a_deep_tote_beside_the_base_is_reached_in_another_arm_shape() {
    for scenario in ["beside_four/01", "beside_four/02"] {
        file_packs_without_fallback("tests/cells/near_base.pack", scenario);
    }
}

/// The same file's tray close behind the base: above the slot, the
/// upper arm of the shape the arm carried the product in lay across the
/// tray (a fallback in 8 of 10 scenarios). The arm now changes its shape
/// on the way to the approach. In `behind_four/08` the next product's
/// lift, in that shape, then folded the forearm into wrist 2, and the
/// first free grip shape's hover was not reached from there (a fallback):
/// the regrip now goes on to the next free shape.
#[test]
fn a_tray_close_behind_the_base_is_reached_in_another_arm_shape() {
    for scenario in ["behind_four/01", "behind_four/08"] {
        file_packs_without_fallback("tests/cells/near_base.pack", scenario);
    }
}

/// A tote close behind the base, and a tall product standing beside the
/// flat ones in front (tests/cells/tote_behind_tall.pack, a helper's probe
/// cell). Carrying a product to the tote, the arm changes its shape on the
/// way, as the expert's does; another shape's joints came with the base
/// more than half a turn from where it stood, and the swing there took
/// the upper arm the long way round the base, into the tall product: a
/// fallback in 3 of the 10 scenarios of the file's suite (20 of the
/// probe's 61). That shape's base is now also tried a whole turn nearer.
#[test]
fn another_arm_shape_is_reached_the_short_way_round_the_base() {
    for scenario in ["c1_n2/04", "c1_n2/08"] {
        file_packs_without_fallback("tests/cells/tote_behind_tall.pack", scenario);
    }
}

/// Helper R's probe cell 6210 (tests/cells/heavy_carafe_behind.pack),
/// with its own model trained with seed 1: a tote behind the base, tall
/// products waiting near it.
///
/// - The policy's steps on the carry to the tote swung the shoulder back
///   over the top (-2.0 to -3.4 rad), the forearm on the table. The
///   approach was raised until free in that shape, the point above the
///   slot after it to 0.78 m, and the release from there came down only
///   to 0.77 m: 39 of 42 packages fell back. Steps that end in another
///   arm shape than they started in, at a pose that collides, now take
///   the same pose in the nearest other shape that stands free
///   (`other_shapes`, the elbow and wrist the other way, as the expert's
///   inverse kinematics takes it): `c1_n6/02` packs without fallback.
/// - A release still reached only far above the expert's (`c1_n6/09`):
///   the carafe, let go 0.65 m above the expert's release, fell onto the
///   upper arm (a collision in the simulator, the package stopped). Such
///   a release is now the expert's, reached by RRT-Connect (a fallback):
///   the package is complete.
#[test]
fn a_seed_one_model_behind_the_base_keeps_a_free_arm_shape_and_never_drops_from_high() {
    let pack = "tests/cells/heavy_carafe_behind.pack";
    let dir = scratch("generalisation", "heavy_carafe");
    let compiled = dir.join("out").display().to_string();
    let model = dir.join("model").display().to_string();
    let out = packwright(&["compile", pack, "-o", &compiled]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let out = packwright(&["train", &compiled, "-o", &model, "--seed", "1", "--quiet"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let run = |scenario: &str| {
        json(&packwright(&[
            "execute",
            pack,
            "--scenario",
            scenario,
            "--model",
            &model,
            "--json",
        ]))
    };
    let report = run("c1_n6/02");
    assert_eq!(report["complete"], true, "{report}");
    assert_eq!(report["fallbacks"], serde_json::json!([]), "{report}");
    let report = run("c1_n6/09");
    assert_eq!(report["collisions"], serde_json::json!([]), "{report}");
    assert_eq!(report["complete"], true, "{report}");
    let dropped = report["fallbacks"]
        .as_array()
        .is_some_and(|f| f.iter().any(|f| f["why"]["kind"] == "drops_from"));
    assert!(dropped, "{report}");
}

/// Products waiting close to the base, the box behind it
/// (tests/cells/near_pending.pack, a helper's probe cell): after the last
/// release of `n2_8010/01` and `n1_8010/07` every way up the policy's
/// steps or inverse kinematics took folded the forearm into wrist 2, and
/// the package was reported incomplete with the product in its slot. The
/// back-up now goes as RRT-Connect's does there (a fallback, sub-goal 4
/// of placing).
#[test]
fn a_back_up_with_no_learned_way_up_falls_back_instead_of_failing() {
    for scenario in ["n2_8010/01", "n1_8010/07"] {
        let report = executes_file("tests/cells/near_pending.pack", scenario);
        assert_eq!(report["complete"], true, "{report}");
        let backed_up = report["fallbacks"]
            .as_array()
            .into_iter()
            .flatten()
            .any(|f| f["stage"] == "placing" && f["subgoal"] == 4);
        assert!(backed_up, "{report}");
    }
}

/// A product let go off its slot and handled again (tests/cells/
/// tall_narrow.pack, a helper's probe cell: a tall narrow product fell
/// off its slot and was picked again from inside the box) kept only its
/// last attempt's row: its first turn was missing from the table and
/// the rows added up to 5.63 s of a 9.78 s run. It now keeps its first
/// turn, and its times are the sums of both: the rows add up to the
/// package's time.
#[test]
fn a_product_handled_twice_keeps_its_first_turn_and_both_attempts_times() {
    let out = packwright(&[
        "execute",
        "tests/cells/tall_narrow.pack",
        "--scenario",
        "n2_8015/04",
        "--json",
    ]);
    let report = json(&out);
    let rows = report["products"].as_array().expect("rows");
    let sum: f64 = rows.iter().filter_map(|r| r["execution_s"].as_f64()).sum();
    let total = report["time_s"].as_f64().expect("time_s");
    assert!((sum - total).abs() < 1e-6, "{sum} of {total}\n{report}");
    let turns: Vec<u64> = rows.iter().filter_map(|r| r["turn"].as_u64()).collect();
    assert!(turns.contains(&1), "{report}");
}

/// A florist's box behind the robot (tests/cells/florist.pack): vases
/// of 250 and 280 mm stand in the pending area beside flat packets. The
/// learned hover over a packet, back from the box, swept the wrist past
/// a standing vase with the arm's shape kept from the start (the expert
/// goes there with another shape, which the policy's steps cannot
/// reach): a fallback at the hover in 3 of the cell's 20 scenarios with
/// the bundled model. The hover is now raised over the way, as a carried
/// point is; no fallback in these two.
#[test]
fn a_hover_whose_wrist_would_sweep_past_a_tall_product_is_raised_over_it() {
    for scenario in ["f_5/09", "f_5/11"] {
        file_packs_without_fallback("tests/cells/florist.pack", scenario);
    }
}

/// A cell that lifts its products 50 mm (tests/cells/low_lift.pack),
/// where every cell the bundled model learned from lifts 100 to 200 mm.
/// With the height of a product's bottom in decimetres as its input, the
/// reasoner chose the held product again instead of the box (SR 0.05 and
/// 0.25 on the two suites); a node now reads only whether it is raised.
#[test]
fn a_cell_that_lifts_its_products_less_than_any_taught_is_packed() {
    for scenario in ["low_case1/01", "low_case2/01"] {
        file_packs_without_fallback("tests/cells/low_lift.pack", scenario);
    }
}

/// A compact cell (tests/cells/compact.pack): the products wait beside
/// the box, 10 to 30 cm from their slots, where every cell the bundled
/// model learned from keeps them a whole side away. A node read its
/// distance from its goal in decimetres, and the reasoner took products
/// waiting this near as packed: it chose the box with nothing in the cup
/// (7 % of the decisions over 86 such development cells). A node now
/// reads only whether its product is in its slot.
#[test]
fn a_compact_cell_with_the_products_beside_the_box_is_packed() {
    for scenario in ["compact_case1_n/01", "compact_case1_n1/01"] {
        file_packs_without_fallback("tests/cells/compact.pack", scenario);
    }
}

/// A cell whose products wait far out (tests/cells/far_out.pack, the
/// farthest 1.065 m from the base axis, where generated cells keep them
/// within 0.95 m). A product let go from there came to rest tilted on
/// its slot's edge, 16 mm up and packed by the rule; a node read it as
/// raised, so held, and the reasoner chose the box with nothing in the
/// cup. A node now reads as held only out of its slot.
#[test]
fn a_product_packed_tilted_in_its_slot_is_not_read_as_held() {
    file_packs_without_fallback("tests/cells/far_out.pack", "far_out_case1_n/05");
}

/// A cell whose products wait 1.1-1.2 m out, for a box 80 mm wide
/// (tests/cells/far_narrow.pack). The bundled model's sub-goal planner
/// was taught "above the slot" from cup tips at most 0.15 m farther out
/// than the slot; from 0.3 m out it answered 2 cm off, and the release
/// after it 1 cm off, so that a 60 mm cube let go over the wall rested on
/// it. A query beyond the taught ones is now answered as at their edge.
#[test]
fn a_query_farther_out_than_any_taught_is_answered_as_the_nearest_taught() {
    for scenario in ["far_narrow_case1_n1/01", "far_narrow_untaught/02"] {
        file_packs_without_fallback("tests/cells/far_narrow.pack", scenario);
    }
}

/// A cell whose products wait 0.30 m from the base axis, below it
/// (tests/cells/near_fold.pack). The policy kept the arm's shape from the
/// stage's start down to the product, and no way up from that contact
/// was free (the forearm folded into the base or the upper arm): the
/// product was not packed. Then the stage was planned again from its
/// start by the expert's sub-goals (a fallback). The grip is now made
/// with a shape the lift leaves freely at the learned sub-goals, the arm
/// changing its shape on the way to the hover: no fallback.
#[test]
fn a_grip_with_no_free_way_up_is_made_again_with_another_arm_shape() {
    for scenario in ["near_fold_case1_n1/02", "near_fold_untaught/01"] {
        file_packs_without_fallback("tests/cells/near_fold.pack", scenario);
    }
}

/// A bakery's hamper (tests/cells/bakery.pack) and a cosmetics display
/// (tests/cells/display.pack, written by a helper from the language
/// docs): small or flat items wait behind tins, a bottle or cartons
/// 210-270 mm tall. The learned contact on one, in the arm's shape the
/// policy's steps kept from the stage's start, puts wrist 1 or the
/// forearm against a tall product. RRT-Connect from the learned hover
/// then changed the arm's shape down among the products (bakery_four/09
/// stopped); later the stage was planned again by the expert's
/// sub-goals (a fallback), and the next approach, from the shape it
/// gripped with, folded the forearm into wrist 2 (a second one). The
/// contact is now made with a free shape at the learned sub-goals, the
/// arm changing its shape on the way to the hover (`grip_learned`), and
/// the approach follows the policy's steps from the taught shape
/// (`reshaped`): no fallback.
#[test]
fn a_contact_beside_a_taller_product_is_made_with_a_free_shape_at_the_learned_subgoals() {
    for (file, scenario) in [
        ("tests/cells/bakery.pack", "bakery_four/01"),
        ("tests/cells/bakery.pack", "bakery_four/09"),
        ("tests/cells/display.pack", "mixed_4of5/01"),
    ] {
        file_packs_without_fallback(file, scenario);
    }
}

/// A sauce line's feed row of 240 mm bottles and 40 mm tins
/// (tests/cells/sauce_row.pack). In row_3of6/04 the learned contact on
/// the mustard tin between two bottles collides and no grip shape is
/// free at the learned sub-goals: the picking stage is planned again by
/// the expert's sub-goals, gripping with a free shape (a fallback from
/// sub-goal 1), and the package is complete.
#[test]
fn where_no_shape_is_free_at_the_learned_contact_the_expert_grips_again() {
    let report = executes_file("tests/cells/sauce_row.pack", "row_3of6/04");
    assert_eq!(report["complete"], true, "{report}");
    let regripped = report["fallbacks"]
        .as_array()
        .into_iter()
        .flatten()
        .any(|f| f["stage"] == "picking" && f["subgoal"] == 2 && f["expert_from"] == 1);
    assert!(regripped, "{report}");
}

/// A spirits gift box behind a row of 260 mm bottle cartons
/// (tests/cells/spirits.pack). In smalls_only_2of3/03 the pourer's
/// learned release beside the gin collides, and RRT-Connect goes to the
/// expert's release, in an arm shape the policy was not taught in (a
/// fallback). The back-up from there followed the policy's steps up,
/// which folded the forearm into wrist 2 at every height, and searched
/// ever higher for a free end: it rose half a metre (11.07 s of
/// execution for the product, 0.9 s of planning). It now goes up to the
/// inverse-kinematics solution in the arm's own shape (9.32 s).
#[test]
fn the_back_up_from_a_shape_the_policy_was_not_taught_in_goes_straight_up() {
    packs_within(
        "tests/cells/spirits.pack",
        "smalls_only_2of3/03",
        "pourer",
        10.0,
    );
}

/// A breakfast line (tests/cells/breakfast.pack): the small goods wait in
/// a 180 mm channel between two 220 mm cereal cartons. In across_3of4/01
/// the straight joint motion to the biscuits' hover, the last in the
/// channel, sweeps the arm into a carton, and the hover went through
/// every one of the policy's 13 steps: short legs the blend could not
/// speed up on (13.91 s for the product; the expert's 10.65 s). The
/// steps a straight motion can skip are now left out (`fewer_vias`):
/// 8.50 s.
#[test]
fn a_hover_through_the_policys_steps_leaves_out_the_steps_a_straight_motion_skips() {
    let report = packs_within(
        "tests/cells/breakfast.pack",
        "across_3of4/01",
        "biscuits",
        10.0,
    );
    assert_eq!(report["fallbacks"], serde_json::json!([]), "{report}");
}

/// The scenario W003 names in tests/cases/warn/drawn_pick_blocked.pack
/// (a helper's small-parts tray: the sachet and the vial drawn nearer each
/// other than W001 allows for) fails with the learned planner and the
/// expert alike, at the sachet. The products after it are not attempted,
/// and neither planner gives them a final distance from their slots (the
/// learned planner reported their distance at the start, 1.0 m).
#[test]
fn the_scenario_w003_names_fails_with_every_planner_and_leaves_the_rest_unmeasured() {
    for planner in ["learned", "expert"] {
        let out = packwright(&[
            "execute",
            "tests/cases/warn/drawn_pick_blocked.pack",
            "--scenario",
            "smalls_4of8/15",
            "--planner",
            planner,
            "--json",
        ]);
        assert_eq!(out.status.code(), Some(1), "{planner}: {}", text(&out));
        let report = json(&out);
        let products = report["products"].as_array().cloned().unwrap_or_default();
        let sachet = products.iter().find(|p| p["product"] == "sachet");
        assert_eq!(
            sachet.map(|p| p["outcome"] == "failed"),
            Some(true),
            "{planner}: {report}"
        );
        let rest: Vec<_> = products
            .iter()
            .filter(|p| p["outcome"] == "not_attempted")
            .collect();
        assert!(!rest.is_empty(), "{planner}: {report}");
        assert!(
            rest.iter()
                .all(|p| p["error_m"].is_null() && p["turn"].is_null()),
            "{planner}: {report}"
        );
        // The products handled, by their turns: the sachet first.
        let turns: Vec<(&str, u64)> = products
            .iter()
            .filter_map(|p| Some((p["product"].as_str()?, p["turn"].as_u64()?)))
            .collect();
        assert_eq!(turns, [("sachet", 1)], "{planner}: {report}");
    }
}

/// Helper T's cell 6311 (tests/cells/turned_tray.pack): a 2 x 8 tray
/// turned 60 degrees behind the waiting products. The first carry meets
/// the tray in the arm's taught shape, the arm changes to the other one
/// on the way and stays in it; above two slots of c1_n9/01 the bundled
/// policy's steps turned the shoulder past -2 pi there (two fallbacks).
/// The taught shape's steps are now brought back to the arm's own shape
/// (`in_own_shape`): none.
#[test]
fn steps_in_a_shape_the_policy_was_not_taught_are_the_taught_shapes_brought_back() {
    let report = executes_file("tests/cells/turned_tray.pack", "c1_n9/01");
    assert_eq!(report["complete"], true, "{report}");
    assert_eq!(report["fallbacks"], serde_json::json!([]), "{report}");
}

/// A box right behind the robot's base (tests/cells/rear_box.pack): each
/// product needs about half a turn of the base, and the policy's steps
/// commit to either way round. In rear_3of5/03 they turned clockwise to
/// the first product and on to the box, then clockwise again to the
/// next product (169 degrees; the other way, 191), and the release after
/// it was past the base's limit that way: the arm turned three quarters
/// of the way back (P4: 9.26 s, the expert's 7.89 s). Nearly half a turn
/// round, the base now goes the way that leaves it nearer the middle of
/// its range (`nearer_middle`): 7.09 s.
#[test]
fn nearly_half_a_turn_round_the_base_goes_the_way_that_leaves_it_room() {
    packs_within("tests/cells/rear_box.pack", "rear_3of5/03", "P4", 8.0);
}

/// A tight gift box, 65 mm slots for 58-60 mm products
/// (tests/cells/tight_box.pack). The straight joint motion from the
/// learned point above a slot down to the release bows sideways into a
/// neighbour, and the descent went down the vertical through five vias,
/// stopping short of each (tight_4of7/13, p4: 7.76 s, the expert's 5.73).
/// The vias a straight motion can skip are now left out (`fewer_vias`):
/// 6.36 s.
#[test]
fn a_descent_down_the_vertical_leaves_out_the_vias_a_straight_motion_skips() {
    packs_within("tests/cells/tight_box.pack", "tight_4of7/13", "p4", 7.0);
}

/// The same cell's products wait 6 mm apart, jittered up to 2 mm each:
/// some stand 2-3 mm from a neighbour, inside the 3 mm padding round a
/// held product. The lift then collided before it moved, and every
/// planner failed (tight_6of7/04: p4 beside p5, 2.4 mm; /05: p1 beside
/// p2), or lowered the lift until the product hung among its neighbours
/// and the carry from there collided. A lifted product's sides are now
/// padded by the room it has (`Checker::lifting`), a lowered lift must
/// leave it free once padded all round, and a lift whose straight joint
/// motion bows into a neighbour goes up the cup tip's line.
#[test]
fn a_product_standing_close_to_its_neighbours_is_lifted_out_from_between_them() {
    for scenario in ["tight_6of7/04", "tight_6of7/05"] {
        for planner in ["expert", "rrt", "learned"] {
            let out = packwright(&[
                "execute",
                "tests/cells/tight_box.pack",
                "--scenario",
                scenario,
                "--planner",
                planner,
                "--json",
            ]);
            assert_eq!(
                out.status.code(),
                Some(0),
                "{scenario} {planner}: {}",
                text(&out)
            );
        }
    }
}

/// Two products 0.3 mm apart (tests/cells/touching.pack): no lift takes
/// the first out, and the failure says why: the lift's pose is free, its
/// straight motion meets the neighbour (it said only "unreachable").
#[test]
fn a_lift_that_cannot_leave_its_neighbour_says_what_it_meets() {
    let out = packwright(&[
        "execute",
        "tests/cells/touching.pack",
        "--order",
        "pair",
        "--planner",
        "expert",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let report = json(&out);
    let reason = &report["products"][0]["reason"];
    assert_eq!(reason["kind"], "unreachable", "{report}");
    assert_eq!(reason["subgoal"], 3, "{report}");
    assert_eq!(reason["way"]["a"], "held:p1", "{report}");
    assert_eq!(reason["way"]["b"], "product:p4", "{report}");
}

/// A kiosk's mailer beside the robot base (tests/cells/kiosk.pack, slots
/// 0.33-0.37 m from its axis). The bundled model's steps towards the
/// point above a slot spiral in there, each turning the tip's way a few
/// degrees off, and ended 2.0-2.3 mm away after 30 steps where 2 mm is
/// needed (a fallback in 19 of the cell's 30 scenarios). Steps that end
/// within 1 cm now take up to 15 more: no fallback.
#[test]
fn steps_that_spiral_in_on_a_slot_near_the_base_are_let_take_a_few_more() {
    for scenario in ["kiosk_four/04", "kiosk_four/06"] {
        file_packs_without_fallback("tests/cells/kiosk.pack", scenario);
    }
}

/// A cell whose products wait 0.29 m from the base axis
/// (tests/cells/near_flip.pack). The expert solved each sub-goal nearest
/// the one before: over one product the contact nearest the hover had
/// the wrist flipped, and the straight descent to it swung the cup into
/// the neighbouring product (93 of the cell's 150 demonstrations could
/// not be replayed). The stage is now solved again from the contact's
/// shape.
#[test]
fn the_expert_grips_a_product_near_the_base_with_a_shape_it_can_reach_straight_down() {
    for scenario in ["near_flip_case1_n/03", "near_flip_untaught/05"] {
        let out = packwright(&[
            "execute",
            "tests/cells/near_flip.pack",
            "--scenario",
            scenario,
            "--planner",
            "expert",
            "--json",
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out));
        let report = json(&out);
        assert_eq!(report["complete"], true, "{report}");
    }
}

/// A wide development cell (`generate --family wide --seed 109`): a 270
/// mm deep carton and a 95 mm cup, where the expert lets go 10 cm up with
/// wrist 3 a few millimetres from a wall, and the learned release 3 mm
/// beside it put the wrist on the wall (the expert's release by
/// RRT-Connect, at 455 of 6,000 wide scenarios). The release is now kept
/// inside the walls by the wrist's radius too.
#[test]
fn a_release_whose_wrist_would_meet_a_deep_boxs_wall_is_kept_inside_it() {
    wide_packs_without_fallback(109, SuiteKind::Case1N1, "01");
}

/// A wide development cell (`generate --family wide --seed 165`): a
/// carton 120 mm across and 300 mm deep, narrower than the wrist, where
/// the expert lets go 12 cm up with wrist 3 just over the middle. The
/// kept release 2 mm beside it put the wrist on the wall at every height
/// it was raised to; it is now kept inside again at each height.
#[test]
fn a_release_raised_out_of_a_box_narrower_than_the_wrist_is_kept_in_its_middle() {
    wide_packs_without_fallback(165, SuiteKind::Case1N2, "01");
}

/// A wide development cell (`generate --family wide --seed 181`): a 300
/// mm deep carton, a 165 mm cup. The swing from above a slot to the next
/// product came down while still over the carton, the cup on its rim;
/// it now crosses at the height it left from, then goes down.
#[test]
fn a_swing_out_of_a_deep_box_crosses_the_rim_before_it_comes_down() {
    wide_packs_without_fallback(181, SuiteKind::Case1N1, "02");
}

/// A wide development cell (`generate --family wide --seed 123`): a 270
/// mm deep carton beside the products, the base near its limit, so that
/// a product is carried the long way round, past the carton. Its carry
/// rose only as it went and met the rim; it now rises first.
#[test]
fn a_product_carried_the_long_way_round_rises_before_it_passes_the_box() {
    wide_packs_without_fallback(123, SuiteKind::Case1N1, "02");
}

/// A wide development cell (`generate --family wide --seed 258`): a 200
/// mm cup over a 115 mm product waiting right under the start pose. The
/// start was chosen without the products and leaned the upper arm
/// through it, so every planner's first motion collided (no package of
/// the cell packed); it is now chosen clear of what stands there.
#[test]
fn the_start_pose_over_a_tall_product_is_clear_of_it() {
    wide_packs_without_fallback(258, SuiteKind::Case1N, "01");
}

/// Scenario `scenario` of the cell file `pack`, executed with the bundled
/// model: the package complete, with no fallback.
fn file_packs_without_fallback(pack: &str, scenario: &str) {
    complete_without_fallback(&executes_file(pack, scenario));
}

/// Scenario `number` of suite `kind` of generated cell `seed`, executed
/// with the bundled model: the package complete, with no fallback.
fn packs_without_fallback(seed: u64, kind: SuiteKind, number: &str) {
    let cell = family_cell(seed);
    complete_without_fallback(&executes_with_the_bundled_model(&cell, kind, number));
}

/// As [`packs_without_fallback`], on a cell of the wide family.
fn wide_packs_without_fallback(seed: u64, kind: SuiteKind, number: &str) {
    let cell = generated_cell(Family::Wide, seed, None);
    complete_without_fallback(&executes_with_the_bundled_model(&cell, kind, number));
}

fn complete_without_fallback(report: &serde_json::Value) {
    assert_eq!(report["complete"], true, "{report}");
    assert_eq!(report["fallbacks"], serde_json::json!([]), "{report}");
}

/// Scenario `number` of suite `kind` of generated `cell`, executed with
/// the bundled model (exit 0): the JSON report.
fn executes_with_the_bundled_model(
    cell: &Generated,
    kind: SuiteKind,
    number: &str,
) -> serde_json::Value {
    let dir = scratch("generalisation", &cell.name);
    let pack = dir.join(cell.file_name());
    fs::write(&pack, &cell.text).expect("generated file written");
    let scenario = format!("{}/{number}", cell.suite(kind).name);
    executes_file(&pack.display().to_string(), &scenario)
}

/// Scenario `scenario` of the cell file `pack`, executed with the bundled
/// model (exit 0): the JSON report.
/// The learned planner's report on `scenario` of `pack`, checked
/// complete, with `product` packed in under `seconds` of simulated time.
fn packs_within(pack: &str, scenario: &str, product: &str, seconds: f64) -> serde_json::Value {
    let report = executes_file(pack, scenario);
    assert_eq!(report["complete"], true, "{report}");
    let took = report["products"]
        .as_array()
        .into_iter()
        .flatten()
        .find(|p| p["product"] == product)
        .and_then(|p| p["execution_s"].as_f64())
        .unwrap_or(f64::INFINITY);
    assert!(took < seconds, "{product}: {took} s\n{report}");
    report
}

fn executes_file(pack: &str, scenario: &str) -> serde_json::Value {
    let out = packwright(&["execute", pack, "--scenario", scenario, "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    json(&out)
}
