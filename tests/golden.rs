//! Golden-file tests of the `packwright` command over the example orders and
//! the test cases: every diagnostic in `tests/cases/err/` and the `show`
//! summary of every file in `orders/` and `tests/cases/ok/` are insta
//! snapshots (`tests/snapshots/`). Review changes with `cargo insta review`
//! or by reading the `.snap.new` files.

mod common;
use common::{packwright, root, scratch};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `.pack` files below `dir` (relative to the repository), sorted.
fn pack_files(dir: &str) -> Vec<String> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "pack") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(&root().join(dir), &mut out);
    let mut names: Vec<String> = out
        .iter()
        .filter_map(|p| p.strip_prefix(root()).ok())
        .map(|p| p.display().to_string())
        .collect();
    names.sort();
    names
}

fn snapshot_name(path: &str) -> String {
    path.trim_end_matches(".pack").replace(['/', '\\'], "__")
}

fn show_of(files: &[&str], scratch_name: &str) -> String {
    let dir = scratch("golden", scratch_name);
    let out = dir.join("out");
    let out_s = out.display().to_string();
    let mut args = vec!["compile"];
    args.extend_from_slice(files);
    args.extend_from_slice(&["-o", &out_s]);
    let compiled = packwright(&args);
    assert_eq!(
        compiled.status.code(),
        Some(0),
        "compile {files:?} failed:\n{}",
        text(&compiled.stderr)
    );
    let shown = packwright(&["show", &out_s]);
    assert_eq!(
        shown.status.code(),
        Some(0),
        "show failed:\n{}",
        text(&shown.stderr)
    );
    text(&shown.stdout)
}

#[test]
fn every_error_case_reports_its_diagnostics() {
    let cases = pack_files("tests/cases/err");
    assert!(
        cases.len() >= 25,
        "expected the error cases, found {}",
        cases.len()
    );
    for case in &cases {
        let out = packwright(&["check", case]);
        assert_eq!(
            out.status.code(),
            Some(1),
            "{case} should fail with diagnostics (exit 1)"
        );
        assert!(out.stdout.is_empty(), "{case}: diagnostics go to stderr");
        insta::assert_snapshot!(format!("err__{}", snapshot_name(case)), text(&out.stderr));
    }
}

/// A warning is printed with the file's summary, and `check` still exits
/// 0: the input compiles, and may fail on the robot depending on what
/// happens first. With `--json`, each warning is a diagnostic line of
/// severity `warning`, counted in the summary.
#[test]
fn every_warning_case_checks_with_its_warnings() {
    let cases = pack_files("tests/cases/warn");
    assert!(!cases.is_empty(), "expected the warning cases");
    for case in &cases {
        let out = packwright(&["check", case]);
        assert_eq!(out.status.code(), Some(0), "{case}: {}", text(&out.stderr));
        assert!(out.stdout.is_empty(), "{case}: warnings go to stderr");
        let stderr = text(&out.stderr);
        assert!(stderr.contains("warning["), "{case}: no warning:\n{stderr}");
        insta::assert_snapshot!(format!("warn__{}", snapshot_name(case)), stderr);

        let json = packwright(&["check", "--json", case]);
        assert_eq!(json.status.code(), Some(0));
        let lines: Vec<serde_json::Value> = text(&json.stdout)
            .lines()
            .map(|l| serde_json::from_str(l).expect("each line is JSON"))
            .collect();
        let warnings: Vec<_> = lines.iter().filter(|v| v["type"] == "diagnostic").collect();
        assert!(!warnings.is_empty());
        for w in &warnings {
            assert_eq!(w["severity"], "warning", "{w}");
            assert!(w["code"].as_str().is_some_and(|c| c.starts_with('W')));
            assert!(w["help"].is_string(), "{w}");
        }
        let summary = lines.last().expect("a summary line");
        assert_eq!(summary["errors"], 0);
        assert_eq!(summary["warnings"], warnings.len());
    }
}

#[test]
fn every_valid_case_compiles_and_shows() {
    let cases = pack_files("tests/cases/ok");
    assert!(cases.len() >= 10);
    for case in &cases {
        let shown = show_of(&[case], &snapshot_name(case));
        insta::assert_snapshot!(format!("ok__{}", snapshot_name(case)), shown);
    }
}

#[test]
fn every_example_order_compiles_and_shows() {
    let files = pack_files("orders");
    assert!(!files.is_empty());
    for file in &files {
        let shown = show_of(&[file], &snapshot_name(file));
        insta::assert_snapshot!(snapshot_name(file), shown);
    }
    let all: Vec<&str> = files.iter().map(String::as_str).collect();
    insta::assert_snapshot!("orders__all", show_of(&all, "all-orders"));
}

#[test]
fn compiling_twice_gives_the_same_bytes() {
    let files = pack_files("orders");
    let dir = scratch("golden", "determinism");
    let mut outputs = Vec::new();
    for run in ["a", "b"] {
        let out = dir.join(run).display().to_string();
        let mut args = vec!["compile"];
        args.extend(files.iter().map(String::as_str));
        args.extend(["-o", out.as_str()]);
        assert_eq!(packwright(&args).status.code(), Some(0));
        outputs.push(out);
    }
    for name in [
        "manifest.json",
        "labels.json",
        "orders.json",
        "scenarios.json",
        "graphs.safetensors",
    ] {
        let a = fs::read(Path::new(&outputs[0]).join(name)).expect("artifact");
        let b = fs::read(Path::new(&outputs[1]).join(name)).expect("artifact");
        assert!(!a.is_empty(), "{name} is empty");
        assert!(
            a == b,
            "{name} differs between two compiles of the same input"
        );
    }
}

#[test]
fn compile_replaces_artifacts_but_never_other_directories() {
    let dir = scratch("golden", "atomic");
    let precious = dir.join("precious");
    fs::create_dir_all(&precious).expect("dir");
    fs::write(precious.join("notes.txt"), "keep me").expect("write");
    let target = precious.display().to_string();
    let refused = packwright(&["compile", "orders/cells/line2.pack", "-o", &target]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(text(&refused.stderr).contains("refusing to replace"));
    assert_eq!(
        fs::read_to_string(precious.join("notes.txt")).expect("kept"),
        "keep me"
    );

    let out = dir.join("out").display().to_string();
    assert_eq!(
        packwright(&["compile", "orders/cells/line2.pack", "-o", &out])
            .status
            .code(),
        Some(0)
    );
    let first = fs::read(dir.join("out/manifest.json")).expect("manifest");
    // Replacing earlier artifacts works; a failed compile leaves them alone.
    assert_eq!(
        packwright(&["compile", "orders/suites/teach.pack", "-o", &out])
            .status
            .code(),
        Some(0)
    );
    let second = fs::read(dir.join("out/manifest.json")).expect("manifest");
    assert_ne!(first, second);
    let failed = packwright(&["compile", "tests/cases/err/duplicate_name.pack", "-o", &out]);
    assert_eq!(failed.status.code(), Some(1));
    assert_eq!(
        fs::read(dir.join("out/manifest.json")).expect("manifest"),
        second
    );
    // A model trained into the compiled directory (`train out -o
    // out/model`) would go with it: refused, everything kept.
    fs::create_dir_all(dir.join("out/model")).expect("dir");
    fs::write(dir.join("out/model/config.json"), "{}").expect("write");
    let refused = packwright(&["compile", "orders/cells/line2.pack", "-o", &out]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(
        text(&refused.stderr).contains("holds `model`"),
        "{}",
        text(&refused.stderr)
    );
    assert!(dir.join("out/model/config.json").is_file());
    assert_eq!(
        fs::read(dir.join("out/manifest.json")).expect("manifest"),
        second
    );
    let leftovers: Vec<_> = fs::read_dir(&dir)
        .expect("dir")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(
        leftovers.is_empty(),
        "temporary directories left behind: {leftovers:?}"
    );
}

/// A file named by its absolute path and `use`d by a relative one (or
/// reached through a link) is one file, loaded once: not its cells and
/// products defined twice (E020).
#[test]
fn a_file_reached_by_two_paths_is_loaded_once() {
    let cell = fs::canonicalize("orders/cells/line2.pack").expect("the cell file");
    let cell = cell.display().to_string();
    let both = packwright(&["check", &cell, "orders/suites/teach.pack"]);
    assert_eq!(both.status.code(), Some(0), "{}", text_of(&both));
}

#[test]
fn exit_codes_and_json_lines() {
    let ok = packwright(&["check", "orders/suites/teach.pack"]);
    assert_eq!(ok.status.code(), Some(0));
    let missing = packwright(&["check", "no/such/file.pack"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(text(&missing.stderr).contains("no such file"));
    let usage = packwright(&["check"]);
    assert_eq!(usage.status.code(), Some(2));
    assert!(usage.stdout.is_empty());
    // With `--json`, a usage error is JSON on stdout too.
    let usage = packwright(&["eval", "orders/suites/teach.pack", "--limit", "0", "--json"]);
    assert_eq!(usage.status.code(), Some(2));
    let said: serde_json::Value =
        serde_json::from_slice(&usage.stdout).expect("one JSON document on stdout");
    assert_eq!(said["type"], "error");
    assert!(
        said["message"]
            .as_str()
            .is_some_and(|m| m.contains("--limit")),
        "{said}"
    );
    let help = packwright(&["check", "--help"]);
    assert_eq!(help.status.code(), Some(0));
    assert!(text(&help.stdout).contains("Usage"));

    // A .pack file where a compiled directory is read, and the other way
    // round: exit 2 and what to give instead.
    for command in ["train", "show"] {
        let mut args = vec![command, "orders/suites/teach.pack"];
        if command == "train" {
            args.extend(["-o", "no/such/out"]);
        }
        let out = packwright(&args);
        assert_eq!(out.status.code(), Some(2), "{command}");
        let said = text(&out.stderr);
        assert!(
            said.contains("not a compiled directory: compile it first"),
            "{said}"
        );
    }
    let dir = scratch("golden", "compiled_as_source");
    let out = dir.join("out");
    let compiled = packwright(&[
        "compile",
        "orders/suites/teach.pack",
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(
        compiled.status.code(),
        Some(0),
        "{}",
        text(&compiled.stderr)
    );
    let given = packwright(&["eval", &out.display().to_string()]);
    assert_eq!(given.status.code(), Some(2));
    let said = text(&given.stderr);
    assert!(
        said.contains("a compiled directory, not a .pack file"),
        "{said}"
    );

    let json = packwright(&["check", "--json", "tests/cases/err/many_errors.pack"]);
    assert_eq!(json.status.code(), Some(1));
    let lines: Vec<serde_json::Value> = text(&json.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("each line is JSON"))
        .collect();
    let diagnostics = lines.iter().filter(|v| v["type"] == "diagnostic").count();
    assert!(
        diagnostics >= 5,
        "many_errors.pack reports every error, got {diagnostics}"
    );
    let summary = lines.last().expect("a summary line");
    assert_eq!(summary["type"], "summary");
    assert_eq!(summary["errors"], diagnostics);
    for d in lines.iter().filter(|v| v["type"] == "diagnostic") {
        assert_eq!(d["severity"], "error");
        assert!(d["code"].as_str().is_some_and(|c| c.starts_with('E')));
        assert!(d["line"].as_u64().is_some_and(|l| l > 0));
        assert!(
            d["help"].is_string(),
            "every diagnostic says how to fix it: {d}"
        );
    }
    assert_eq!(summary["not_shown"], 0);
    // The notes the text form shows are in the JSON too (a helper's
    // probe: they were left out).
    let twice = packwright(&[
        "check",
        "--json",
        "tests/cases/err/product_listed_twice.pack",
    ]);
    let first: serde_json::Value =
        serde_json::from_str(text(&twice.stdout).lines().next().unwrap_or("")).expect("JSON");
    assert_eq!(first["notes"][0]["line"], 6, "{first}");
    assert_eq!(first["notes"][0]["message"], "first listed here", "{first}");

    // compile --json: one line, typed like check's, so that a JSON Lines
    // reader dispatches on `type` either way.
    let json_out = dir.join("json_out");
    let compiled = packwright(&[
        "compile",
        "--json",
        "orders/suites/teach.pack",
        "-o",
        &json_out.display().to_string(),
    ]);
    assert_eq!(compiled.status.code(), Some(0));
    let stdout = text(&compiled.stdout);
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    let report: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(report["type"], "compiled", "{report}");
}

#[test]
fn fmt_check_then_fmt_then_clean() {
    let dir = scratch("golden", "fmt");
    let file = dir.join("messy.pack");
    fs::write(
        &file,
        "product  A cube 50mm   # a cube\nproduct B box (60 mm,40 mm , 50 mm) mass 0.3\n",
    )
    .expect("write");
    let f = file.display().to_string();
    let check = packwright(&["fmt", "--check", &f]);
    assert_eq!(check.status.code(), Some(1));
    assert!(text(&check.stdout).contains("messy.pack"));
    assert_eq!(packwright(&["fmt", &f]).status.code(), Some(0));
    assert_eq!(
        fs::read_to_string(&file).expect("read"),
        "product A cube 50 mm  # a cube\nproduct B box (60 mm, 40 mm, 50 mm) mass 0.3\n"
    );
    assert_eq!(packwright(&["fmt", "--check", &f]).status.code(), Some(0));
    let broken = dir.join("broken.pack");
    fs::write(&broken, "product A cube (\n").expect("write");
    let b = broken.display().to_string();
    assert_eq!(packwright(&["fmt", &b]).status.code(), Some(1));
    assert_eq!(
        fs::read_to_string(&broken).expect("read"),
        "product A cube (\n"
    );
}

/// The canonical examples in `../shared/examples/` (beside the
/// repository in CI, where their absence is a failure) must be accepted
/// verbatim.
#[test]
fn shared_examples_compile_when_present() {
    let shared = root().join("../shared/examples");
    if !shared.is_dir() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but ../shared/examples is missing"
        );
        eprintln!("../shared/examples not found; skipped");
        return;
    }
    let mut files: Vec<String> = Vec::new();
    for sub in ["cells", "orders", "suites"] {
        if let Ok(entries) = fs::read_dir(shared.join(sub)) {
            files.extend(entries.flatten().map(|e| e.path().display().to_string()));
        }
    }
    files.retain(|f| f.ends_with(".pack"));
    assert!(!files.is_empty());
    for f in &files {
        let out = packwright(&["check", f]);
        assert_eq!(out.status.code(), Some(0), "{f}:\n{}", text(&out.stderr));
    }
}

/// The README's language example is a valid file.
#[test]
fn the_readme_example_compiles() {
    let readme = fs::read_to_string(root().join("README.md")).expect("README");
    let start = readme.find("## The language by example").expect("section");
    let block = &readme[start..];
    let body = block
        .split("```text\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("code block");
    let dir = scratch("golden", "readme");
    let file = dir.join("readme.pack");
    fs::write(&file, body).expect("write");
    let out = packwright(&["check", &file.display().to_string()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

/// The per-product execution plan of every example order, with the expert
/// and with RRT-Connect, in the simulator (planning times are wall-clock
/// and left out; distances rounded to 0.1 mm, times to 10 ms).
#[test]
fn execution_plans_of_the_example_orders() {
    let mut text = String::new();
    for file in pack_files("orders/customers") {
        let src = fs::read_to_string(root().join(&file)).expect("order file");
        let orders: Vec<&str> = src
            .lines()
            .filter_map(|l| l.strip_prefix("order "))
            .filter_map(|l| l.split_whitespace().next())
            .collect();
        for order in orders {
            for planner in ["expert", "rrt"] {
                let out = packwright(&[
                    "execute",
                    &file,
                    "--order",
                    order,
                    "--planner",
                    planner,
                    "--json",
                ]);
                assert_eq!(
                    out.status.code(),
                    Some(0),
                    "{file} {order} {planner}:\n{}",
                    text_of(&out)
                );
                let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
                text.push_str(&format!(
                    "{order} ({planner}): complete {}\n",
                    report["complete"]
                ));
                text.push_str(&plan_rows(&report, 2, 1));
            }
        }
    }
    insta::assert_snapshot!("execution_plans", text);
}

/// The bundled model (models/default, trained on orders/) loads and packs
/// the example orders of its cell with the learned planner, which
/// `execute` picks by itself: the golden plan of each.
#[test]
fn the_default_model_packs_the_example_orders() {
    let mut text = String::new();
    for (file, order) in [
        ("orders/customers/hampton_deli.pack", "deli_crate"),
        ("orders/customers/pine_gifts.pack", "pine_trio"),
        ("orders/customers/pine_gifts.pack", "pine_duo"),
    ] {
        let out = packwright(&["execute", file, "--order", order, "--json"]);
        assert_eq!(out.status.code(), Some(0), "{order}:\n{}", text_of(&out));
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        assert_eq!(report["planner"], "learned", "the default planner");
        text.push_str(&format!(
            "{order} (learned): complete {}, fallbacks {}, violations {}\n",
            report["complete"], report["fallbacks"], report["violations"]
        ));
        // Coarser: network outputs are f32 and may differ in the last bits
        // between CPUs.
        text.push_str(&plan_rows(&report, 1, 0));
    }
    insta::assert_snapshot!("default_model_plans", text);
}

/// One line per product of an `execute --json` report: outcome, simulated
/// execution time and its lower bound, and final error, rounded as asked.
fn plan_rows(report: &serde_json::Value, time_digits: usize, error_digits: usize) -> String {
    let mut text = String::new();
    for p in report["products"].as_array().expect("products") {
        text.push_str(&format!(
            "  {} -> {}: {}, execution {:.t$} s (bound {:.t$} s), error {:.e$} mm\n",
            p["product"].as_str().unwrap_or("?"),
            p["slot"].as_str().unwrap_or("?"),
            p["outcome"].as_str().unwrap_or("?"),
            p["execution_s"].as_f64().unwrap_or(f64::NAN),
            p["bound_s"].as_f64().unwrap_or(f64::NAN),
            p["error_m"].as_f64().unwrap_or(f64::NAN) * 1000.0,
            t = time_digits,
            e = error_digits,
        ));
    }
    text
}

fn text_of(out: &Output) -> String {
    format!("{}{}", text(&out.stdout), text(&out.stderr))
}

/// `demonstrate` replays compiled demonstrations with the expert and
/// writes the motion tensors: 6 sub-goals per handled product, 20 action
/// samples per sub-goal, every action within ±15 degrees.
#[test]
fn demonstrate_writes_motion_demonstrations() {
    let dir = scratch("golden", "demonstrate");
    let compiled = dir.join("pine").display().to_string();
    let motion = dir.join("motion.safetensors").display().to_string();
    assert_eq!(
        packwright(&[
            "compile",
            "orders/customers/pine_gifts.pack",
            "-o",
            &compiled
        ])
        .status
        .code(),
        Some(0)
    );
    let out = packwright(&["demonstrate", &compiled, "-o", &motion, "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", text_of(&out));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    // pine_trio's demo handles 3 products, pine_duo's 2.
    assert_eq!(summary["subgoals"], 30);
    assert_eq!(summary["actions"], 600);
    let bytes = fs::read(&motion).expect("motion file");
    let st = safetensors::SafeTensors::deserialize(&bytes).expect("safetensors");
    let shape = |n: &str| st.tensor(n).expect(n).shape().to_vec();
    assert_eq!(shape("subgoal_feature"), [30, 3]);
    assert_eq!(shape("subgoal_label"), [30]);
    assert_eq!(shape("subgoal_start_joints"), [30, 6]);
    assert_eq!(shape("subgoal_goal_joints"), [30, 6]);
    assert_eq!(shape("action_delta"), [600, 3]);
    let joints = st.tensor("action_joints").expect("action_joints");
    let limit = 15f32.to_radians() + 1e-6;
    for c in joints.data().chunks_exact(4) {
        let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        assert!(v.abs() <= limit, "action {v} beyond 15 degrees");
    }
}
