//! `packwright train` and `packwright eval` end to end, on small inputs:
//! a short training of the pine-gifts demonstrations whose model loads and
//! drives `execute`, and an evaluation of a few scenarios with the bundled
//! model beside the baselines.

mod common;
use common::{packwright, scratch};
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

#[test]
fn train_writes_a_model_that_execute_loads() {
    let dir = scratch("learning", "train");
    let compiled = dir.join("pine").display().to_string();
    let model = dir.join("model").display().to_string();
    let out = packwright(&[
        "compile",
        "orders/customers/pine_gifts.pack",
        "-o",
        &compiled,
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));

    // An unknown demonstration block is trouble: exit 2, nothing written.
    let out = packwright(&[
        "train", &compiled, "-o", &model, "--demos", "nope", "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no demonstration block `nope`"));
    assert!(!Path::new(&model).exists());

    // The two demonstrations handle their products in opposite orders:
    // no sequence rule to learn, exit 2, nothing written.
    let out = packwright(&["train", &compiled, "-o", &model, "--quiet"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("follow no one sequence rule") && stderr.contains("pine_duo_seen"),
        "{stderr}"
    );
    assert!(!Path::new(&model).exists());

    let out = packwright(&[
        "train",
        &compiled,
        "-o",
        &model,
        "--demos",
        "pine_seen",
        "--epochs",
        "5",
        "--dagger-rounds",
        "1",
        "--quiet",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(report["schema"], "packwright.metrics/2");
    assert_eq!(report["cells"], serde_json::json!(["line2"]));
    assert_eq!(report["sequence"], "ascending");
    // Five epochs do not converge: said.
    let warnings = report["warnings"].as_array().expect("warnings");
    assert!(
        warnings.iter().any(|w| w["kind"] == "not_converged"),
        "{warnings:?}"
    );
    assert_eq!(report["demonstrations"], 1);
    assert_eq!(report["replayed"], 1);
    // The demonstration moved every product of pantry3 but used three of
    // line2's five slots, and line2's other inventory, pantry5, has two
    // products more (its other three wait where pantry3's do): the expert
    // rehearses an order of two products into k3 and k5, and one of soap
    // and candle.
    assert_eq!(report["rehearsals"], 2);
    assert_eq!(report["rehearsed"], 2);
    // pine_trio's demo handles 3 products: 3 × 2 stages × 3 sub-goals, 20
    // actions each, and the rehearsals' 4 products as many again; 3 × 2
    // reasoner decisions (none from the rehearsal), the 2 picks with
    // products after them along the chain again without those, and the
    // second of those once more with the packed product before it made
    // one outside the order.
    assert_eq!(report["samples"]["graphs"], 9);
    assert_eq!(report["samples"]["subgoals"], 18 + 24);
    assert_eq!(report["samples"]["actions"], 360 + 480);
    assert_eq!(report["dagger"].as_array().map(Vec::len), Some(2));
    for file in [
        "config.json",
        "reasoner.safetensors",
        "subgoal.safetensors",
        "dynamics.safetensors",
        "metrics.json",
    ] {
        assert!(Path::new(&model).join(file).is_file(), "{file} written");
    }
    let config: serde_json::Value =
        serde_json::from_slice(&fs::read(Path::new(&model).join("config.json")).expect("config"))
            .expect("JSON");
    assert_eq!(config["task"]["cells"], serde_json::json!(["line2"]));
    assert_eq!(config["task"]["sequence"], "ascending");
    assert_eq!(config["training"]["epochs"], 5);

    // The model loads and packs (or fails, typed) with the learned planner.
    let out = packwright(&[
        "execute",
        "orders/customers/pine_gifts.pack",
        "--order",
        "pine_duo",
        "--model",
        &model,
        "--json",
    ]);
    assert!(matches!(out.status.code(), Some(0 | 1)), "{}", text(&out));
    let run: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(run["planner"], "learned");
    assert_eq!(run["task"], "pine_duo");
    assert_eq!(run["products"].as_array().map(Vec::len), Some(2));
}

#[test]
fn eval_reports_every_planner_of_a_suite() {
    let dir = scratch("learning", "eval");
    let table = dir.join("eval.md").display().to_string();
    let out = packwright(&[
        "eval",
        "orders/suites/measure.pack",
        "--suite",
        "m_case1_2of3",
        "m_short_3of5",
        "--limit",
        "2",
        "--baselines",
        "--quiet",
        "--json",
        "--markdown",
        &table,
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(report["schema"], "packwright.eval/3");
    let rows = report["rows"].as_array().expect("rows");
    let planners: Vec<&str> = rows.iter().filter_map(|r| r["planner"].as_str()).collect();
    assert_eq!(
        planners,
        ["learned", "rrt", "expert", "learned", "rrt", "expert"]
    );
    for (r, suite) in rows
        .iter()
        .zip(["m_case1_2of3"; 3].iter().chain(&["m_short_3of5"; 3]))
    {
        assert_eq!(r["suite"], *suite);
        assert_eq!(r["scenarios"], 2);
        // The bundled model and both baselines pack these scenarios.
        assert_eq!(r["sr"]["rate"], 1.0, "{r}");
        assert_eq!(r["decision_us"]["n"].as_u64().map(|n| n > 0), Some(true));
    }
    assert_eq!(rows[0]["reasoner_sr"]["rate"], 1.0);
    assert!(rows[1]["reasoner_sr"].is_null());
    // Pooled per planner over both suites: every sub-goal of both.
    let totals = report["totals"].as_array().expect("totals");
    assert_eq!(totals.len(), 3);
    for (t, planner) in totals.iter().zip(["learned", "rrt", "expert"]) {
        assert_eq!(t["suite"], "all suites");
        assert_eq!(t["planner"], planner);
        assert_eq!(t["scenarios"], 4);
        let per_suite: Vec<u64> = rows
            .iter()
            .filter(|r| r["planner"] == planner)
            .filter_map(|r| r["subgoal_us"]["n"].as_u64())
            .collect();
        assert_eq!(t["subgoal_us"]["n"].as_u64(), Some(per_suite.iter().sum()));
    }
    let md = fs::read_to_string(&table).expect("markdown written");
    assert_eq!(md.lines().count(), 2 + 6 + 3 + 2 + 3, "{md}");
    assert!(
        md.contains("| m_case1_2of3 | line2 | learned | 2 | 1.000"),
        "{md}"
    );
    assert!(md.contains("| all suites | - | rrt | 4 | -"), "{md}");
}

/// The bundled model serves cells it was not taught: `execute` on a
/// generated cell (seed 1003, one of the family's reporting seeds; the
/// bundled model learned from seeds 5000 to 5015 and line2) uses it by
/// default, says so on stderr, follows the order the cell's own
/// demonstrations show, and packs the order.
#[test]
fn the_bundled_model_packs_a_cell_it_was_not_taught() {
    let dir = scratch("learning", "untaught");
    let out = packwright(&[
        "generate",
        "--seed",
        "1003",
        "-o",
        &dir.display().to_string(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let pack = dir.join("gen_1003.pack").display().to_string();
    let out = packwright(&[
        "execute",
        &pack,
        "--scenario",
        "gen_1003_case1_n1/01",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the model was not taught cell `gen_1003`"),
        "{stderr}"
    );
    // gen_1003 is taught in descending order in its file; the bundled
    // model was taught ascending, and follows the file.
    assert!(
        stderr.contains("demonstrations of cell `gen_1003` follow the order descending"),
        "{stderr}"
    );
    let run: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(run["planner"], "learned");
    assert_eq!(run["complete"], true, "{}", text(&out));
}

/// A `demos` block with `sequence random` shows that any order is right:
/// `train` teaches the inventory's order (before, it refused: the
/// demonstrations followed no one rule), and `execute` with a model not
/// taught the cell keeps the model's own order without calling the
/// demonstrations contradictory.
#[test]
fn demonstrations_in_random_order_teach_the_inventorys_order() {
    let dir = scratch("learning", "random");
    let cell = packwright_pipeline::generate::family_cell(9950);
    let shuffled = cell
        .text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("sequence ") {
                "  sequence random".to_owned()
            } else {
                l.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(shuffled.contains("sequence random"), "{shuffled}");
    let pack = dir.join(cell.file_name());
    fs::write(&pack, shuffled).expect("written");
    let pack = pack.display().to_string();
    let compiled = dir.join("out").display().to_string();
    let out = packwright(&["compile", &pack, "-o", &compiled]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let model = dir.join("model").display().to_string();
    let out = packwright(&[
        "train",
        &compiled,
        "-o",
        &model,
        "--epochs",
        "5",
        "--dagger-rounds",
        "0",
        "--quiet",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(report["sequence"], "ascending", "{report}");
    assert_eq!(report["any_order"], report["demonstrations"], "{report}");
    assert!(report["any_order"].as_u64() > Some(1), "{report}");
    let out = packwright(&[
        "execute",
        &pack,
        "--scenario",
        &format!(
            "{}/01",
            cell.suite(packwright_pipeline::generate::SuiteKind::Case1N)
                .name
        ),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("follow no one order"), "{stderr}");
    // Said all the same: the model's own order is followed.
    assert!(
        stderr.contains("no demonstration in the files orders cell"),
        "{stderr}"
    );
}

/// `source` written into `dir`, compiled (exit 0): the compiled directory.
fn compiled_text(dir: &Path, source: &str) -> String {
    let pack = dir.join("cells.pack");
    fs::write(&pack, source).expect("write the cells");
    let compiled = dir.join("compiled").display().to_string();
    let out = packwright(&["compile", &pack.display().to_string(), "-o", &compiled]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    compiled
}

/// A short training of `compiled` into `to` (JSON metrics): what the
/// demonstrations decide (rules, warnings) does not need a good model.
fn short_train(compiled: &str, to: &str) -> Output {
    packwright(&[
        "train",
        compiled,
        "-o",
        to,
        "--epochs",
        "2",
        "--dagger-rounds",
        "0",
        "--quiet",
        "--json",
    ])
}

/// A model taught two cells keeps each cell's own order where the cells
/// stock different products: `right`'s one demonstration reads as
/// descending, where the order taught over both cells (a listed one)
/// puts b2 first; `left`, which that order chains as its own ascending
/// one, needs none. Before, the model followed the joint order in both
/// and `train` only warned.
#[test]
fn two_cells_with_their_own_products_keep_their_own_orders() {
    let dir = scratch("learning", "two-cells");
    let compiled = compiled_text(&dir, &format!("{TWO_LINES}{APART}"));
    let model = dir.join("model").display().to_string();
    // The bytes compared below come from the same seed.
    let train = |to: &str| short_train(&compiled, to);
    let out = train(&model);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    // The cells stock no product in common: `right` keeps the order its
    // own demonstration follows, in the report and in the model.
    assert_eq!(
        report["cell_rules"],
        serde_json::json!({ "right": "descending" }),
        "{}",
        text(&out)
    );
    assert!(
        report["warnings"]
            .as_array()
            .expect("warnings")
            .iter()
            .all(|w| w["kind"] != "cell_reads_otherwise"),
        "{}",
        text(&out)
    );
    let config: serde_json::Value =
        serde_json::from_slice(&fs::read(Path::new(&model).join("config.json")).expect("config"))
            .expect("config JSON");
    assert_eq!(
        config["task"]["cell_rules"],
        serde_json::json!({ "right": "descending" })
    );
    // The same training again writes the same bytes (burn's store wrote
    // its header's metadata in a hash map's order).
    let again = dir.join("again").display().to_string();
    let out = train(&again);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    for file in [
        "reasoner.safetensors",
        "subgoal.safetensors",
        "dynamics.safetensors",
    ] {
        let read = |d: &str| fs::read(Path::new(d).join(file)).expect("a model file");
        assert!(read(&model) == read(&again), "{file} differs");
    }
}

/// Two lines stocking the same products, one taught in inventory order
/// and the other in reverse (helper L's shared-catalogue uses): no one
/// rule explains their demonstrations together, and `train` refused them
/// (exit 2). Each cell's own demonstrations follow one, so each keeps
/// it.
#[test]
fn two_cells_sharing_products_in_opposite_orders_each_keep_their_own() {
    let dir = scratch("learning", "shared-opposite");
    let compiled = compiled_text(&dir, &format!("{TWO_LINES}{SHARED_OPPOSITE}"));
    let model = dir.join("model").display().to_string();
    let out = short_train(&compiled, &model);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let rule_of = |cell: &str| {
        report["cell_rules"]
            .get(cell)
            .cloned()
            .unwrap_or_else(|| report["sequence"].clone())
    };
    assert_eq!(rule_of("left"), "ascending", "{report}");
    assert_eq!(rule_of("right"), "descending", "{report}");
}

/// Demonstrations the expert replays none of (a helper's probe cell: a
/// carafe 177 mm tall stands 0.36 m from the base, and the upper arm
/// meets it on the way to every pick of `soap` beside it): `train` named
/// none of them and said only "no sub-goal samples to learn from". Each
/// is now named in an `error:` line, as when only some fail, and the
/// command stops (exit 2) with nothing written.
#[test]
fn train_names_every_demonstration_when_none_replays() {
    let dir = scratch("learning", "none-replayed");
    let compiled = compiled_text(&dir, CARAFE_IN_THE_WAY);
    let model = dir.join("model");
    let out = short_train(&compiled, &model.display().to_string());
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    for demo in ["o_d1", "o_d2"] {
        assert!(
            stderr.lines().any(|l| l
                .starts_with("error: the expert could not replay demonstration")
                && l.contains(&format!("`{demo}`"))),
            "{demo}: {}",
            text(&out)
        );
    }
    assert!(
        stderr.contains("could not replay any of the 2 demonstrations"),
        "{}",
        text(&out)
    );
    assert!(!model.exists(), "a model was written");
}

/// A carafe standing in the arm's way to `soap`.
const CARAFE_IN_THE_WAY: &str = r#"cell crowded {
  robot ur10
  base (0.046, 0.152, 0.000)
  suction 180 mm
  pending (-0.124, 0.342) to (0.365, 1.192)
  box tote (0.549, -0.212) size (674 mm, 356 mm, 77 mm)
  slot s1 (0.310, -0.290)
  slot s2 (0.469, -0.290)
  lift 250 mm
}
product carafe box (114 mm, 94 mm, 177 mm)
product kelp box (65 mm, 59 mm, 62 mm)
product soap cube 54 mm mass 0.93
inventory shelf for crowded {
  carafe (-0.052, 0.498)
  kelp (0.105, 1.090)
  soap (0.314, 0.436)
}
order o for shelf {
  kelp -> s2
  soap -> s1
}
demo o_d1 for o {
  sequence soap, kelp
}
demo o_d2 for o {
  sequence soap, kelp
}
"#;

/// Two lines, each with a tray of three slots.
const TWO_LINES: &str = r#"cell left {
  robot ur10
  base (0, 0, 0)
  suction 100 mm
  pending (0.45, -0.50) to (0.85, -0.10)
  box tray (0.00, 0.65) size (0.40, 0.30, 0.08)
  slot g1 (-0.12, 0.58)
  slot g2 ( 0.00, 0.58)
  slot g3 ( 0.12, 0.58)
}
cell right {
  robot ur10
  base (0, 0, 0)
  suction 100 mm
  pending (0.45, 0.10) to (0.85, 0.50)
  box tray (0.00, -0.65) size (0.40, 0.30, 0.08)
  slot h1 (-0.12, -0.58)
  slot h2 ( 0.00, -0.58)
  slot h3 ( 0.12, -0.58)
}
"#;

/// Products stocked on one line each; `right` demonstrated in reverse.
const APART: &str = r#"product a1 cube 50 mm
product a2 cube 50 mm
product a3 cube 50 mm
product b1 cube 50 mm
product b2 cube 50 mm
product b3 cube 50 mm
inventory la for left {
  a1 (0.50, -0.20)
  a2 (0.62, -0.20)
  a3 (0.74, -0.20)
}
inventory rb for right {
  b1 (0.50, 0.20)
  b2 (0.62, 0.20)
  b3 (0.74, 0.20)
}
order lo for la {
  a1 -> g1
  a2 -> g2
}
order ro for rb {
  b1 -> h1
  b3 -> h3
}
demo left_seen for lo {
  sequence a1, a2
}
demo right_seen for ro {
  sequence b3, b1
}
"#;

/// The same three products on both lines, taught in opposite orders.
const SHARED_OPPOSITE: &str = r#"product a1 cube 50 mm
product a2 cube 50 mm
product a3 cube 50 mm
inventory la for left {
  a1 (0.50, -0.20)
  a2 (0.62, -0.20)
  a3 (0.74, -0.20)
}
inventory ra for right {
  a1 (0.50, 0.20)
  a2 (0.62, 0.20)
  a3 (0.74, 0.20)
}
order lo for la {
  a1 -> g1
  a2 -> g2
  a3 -> g3
}
order ro for ra {
  a1 -> h1
  a2 -> h2
  a3 -> h3
}
demo left_seen for lo {
  sequence a1, a2, a3
}
demo left_again for lo {
  sequence a1, a2, a3
}
demo right_seen for ro {
  sequence a3, a2, a1
}
demo right_again for ro {
  sequence a3, a2, a1
}
"#;

/// Helper X's cells taught together (tests/cells/multi/): what one model
/// keeps for each. `silent.pack`: a cell's two hand-written pairs read
/// as the other cell's declared list when read alone, and the cell was
/// packed in that list without a word; its own reading is descending
/// now, and the shared products keep the joint list, said
/// (`cell_reads_otherwise`). `borrowed.pack`: `down` keeps descending;
/// the rule for `up` came from both cells' demonstrations (D and E
/// first), not up's own ascending. `few_pairs.pack`: `solo` keeps its
/// own rule read from one pair, said as when taught alone.
/// `guessed.pack`: each cell's guessed pairs, over its own products.
#[test]
fn cells_taught_together_keep_their_own_orders_and_say_so() {
    let dir = scratch("learning", "multi");
    let train = |name: &str| -> serde_json::Value {
        let source =
            fs::read_to_string(format!("tests/cells/multi/{name}.pack")).expect("the cells");
        fs::create_dir_all(dir.join(name)).expect("a directory");
        let compiled = compiled_text(&dir.join(name), &source);
        let model = dir.join(name).join("model").display().to_string();
        let out = short_train(&compiled, &model);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out));
        serde_json::from_slice(&out.stdout).expect("JSON")
    };
    let kinds = |report: &serde_json::Value| -> Vec<String> {
        report["warnings"]
            .as_array()
            .map(|w| {
                w.iter()
                    .map(|w| w["kind"].as_str().unwrap_or("").to_owned())
                    .collect()
            })
            .unwrap_or_default()
    };
    let silent = train("silent");
    assert!(
        silent["warnings"].as_array().is_some_and(|w| w
            .iter()
            .any(|w| w["kind"] == "cell_reads_otherwise" && w["cell"] == "right")),
        "{silent}"
    );
    let borrowed = train("borrowed");
    assert_eq!(borrowed["sequence"], "ascending", "{borrowed}");
    assert_eq!(
        borrowed["cell_rules"],
        serde_json::json!({"down": "descending"}),
        "{borrowed}"
    );
    assert!(
        !kinds(&borrowed).contains(&"cell_reads_otherwise".to_owned()),
        "{borrowed}"
    );
    // Two cells on one rule read from one demonstration each: the pairs
    // guessed are named per cell, over its own products.
    let guessed = train("guessed");
    for cell in ["left", "right"] {
        let found = guessed["warnings"].as_array().and_then(|w| {
            w.iter()
                .find(|w| w["kind"] == "pairs_guessed" && w["cell"] == cell)
        });
        let found = found.unwrap_or_else(|| panic!("{cell}: {guessed}"));
        assert_eq!(
            (&found["ordered"], &found["pairs"]),
            (&3.into(), &15.into()),
            "{found}"
        );
    }
    let few = train("few_pairs");
    assert_eq!(few["cell_rules"]["solo"], "descending", "{few}");
    assert!(
        few["warnings"].as_array().is_some_and(|w| w
            .iter()
            .any(|w| w["kind"] == "rule_from_few_pairs" && w["cell"] == "solo")),
        "{few}"
    );
}
