//! `packwright draw` on the example cells, with diagnostics drawn where
//! they are; `eval --plots`; and the recorded tool path that `execute
//! --svg` draws.

mod common;

use common::{packwright, scratch};
use packwright::commands::draw::executed_picture;
use packwright::fsio::FsLoader;
use packwright_motion::execute::{self, Planner};
use packwright_pipeline::episode::{episode, find_setup};
use packwright_pipeline::reach::RobotWorkspace;
use packwright_recording::{Journal, JournalWorld};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

/// Elements whose `class` attribute starts with `class` followed by a
/// space or the closing quote.
fn count(svg: &str, class: &str) -> usize {
    svg.matches(&format!("class=\"{class}\"")).count()
        + svg.matches(&format!("class=\"{class} ")).count()
}

/// The run exited 0 (else its stderr is shown).
fn succeeded(o: &Output) {
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A plotters chart: one SVG document.
fn is_chart(svg: &str) -> bool {
    svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>")
}

fn is_svg(svg: &str) {
    assert!(
        svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""),
        "{svg:.200}"
    );
    assert!(svg.trim_end().ends_with("</svg>"));
}

#[test]
fn every_example_cell_is_drawn_with_its_slots() {
    let dir = scratch("draw", "cells");
    for (file, slots) in [
        ("orders/cells/line2.pack", 5),
        ("orders/cells/twin_row.pack", 6),
    ] {
        let out = dir.join("cell.svg");
        let o = packwright(&["draw", file, "-o", out.to_str().unwrap()]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(
            String::from_utf8_lossy(&o.stdout).trim(),
            out.to_str().unwrap()
        );
        let svg = fs::read_to_string(&out).expect("written");
        is_svg(&svg);
        assert_eq!(count(&svg, "slot"), slots, "{file}");
        assert_eq!(count(&svg, "product"), 0, "{file}");
        assert_eq!(count(&svg, "reach"), 1, "{file}");
        // The note says how to draw the products.
        assert!(String::from_utf8_lossy(&o.stderr).contains("--inventory"));
    }
}

#[test]
fn an_order_has_its_products_slots_and_arrows() {
    let o = packwright(&[
        "draw",
        "orders/customers/hampton_deli.pack",
        "--order",
        "deli_crate",
    ]);
    succeeded(&o);
    let svg = String::from_utf8(o.stdout).expect("UTF-8");
    is_svg(&svg);
    assert_eq!(count(&svg, "product"), 5);
    assert_eq!(count(&svg, "product-side"), 5);
    assert_eq!(count(&svg, "slot"), 5);
    assert_eq!(count(&svg, "assignment"), 4);
    assert_eq!(count(&svg, "diagnostic"), 0);
    assert!(svg.contains("id=\"product-candle\"") && svg.contains("id=\"slot-k5\""));
    assert!(svg.contains("order deli_crate (cell line2)"));
}

#[test]
fn a_scenario_marks_worker_packed_and_missing_products() {
    let o = packwright(&[
        "draw",
        "orders/customers/hampton_deli.pack",
        "--scenario",
        "deli_mixed",
    ]);
    succeeded(&o);
    let svg = String::from_utf8(o.stdout).expect("UTF-8");
    assert_eq!(count(&svg, "product waiting"), 3);
    assert_eq!(count(&svg, "product worker-packed"), 1);
    assert_eq!(count(&svg, "product missing"), 1);
    assert!(svg.contains("id=\"product-jam\"") && svg.contains("jam (worker)"));
    assert!(svg.contains("honey (missing)"));
    // No arrow for jam, packed already; honey's is dashed.
    assert_eq!(count(&svg, "assignment"), 3);
}

#[test]
fn diagnostics_are_drawn_where_they_are() {
    let dir = scratch("draw", "diagnostics");
    let out = dir.join("stray.svg");
    let o = packwright(&[
        "draw",
        "tests/cases/err/slot_outside_box.pack",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("E030") && stderr.contains("1 drawn where it is"),
        "{stderr}"
    );
    let svg = fs::read_to_string(&out).expect("the picture is written anyway");
    assert_eq!(count(&svg, "diagnostic"), 1);
    assert!(svg.contains("E030: slot `so2` is outside box `so_box`"));
    // The red circle is on slot so2 at (-0.50, 0.25): the same centre as
    // the slot's own circle.
    let slot = svg.split("id=\"slot-so2\"").nth(1).expect("slot so2");
    let cx = slot
        .split("cx=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .expect("cx");
    let mark = svg.split("class=\"diagnostic\"").nth(1).expect("mark");
    assert!(mark.contains(&format!("cx=\"{cx}\"")), "{mark:.300}");

    let o = packwright(&[
        "draw",
        "tests/cases/err/product_outside_pending.pack",
        "--inventory",
        "edge_shelf",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let svg = String::from_utf8_lossy(&o.stdout);
    assert_eq!(count(&svg, "diagnostic"), 1);
    assert!(svg.contains("E034"));

    // An unreachable pose is crossed at its tool tip; the file's other
    // orders' and cells' diagnostics stay out of this order's picture.
    let o = packwright(&[
        "draw",
        "tests/cases/err/unreachable_poses.pack",
        "--order",
        "far_one",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let svg = String::from_utf8_lossy(&o.stdout);
    assert_eq!(count(&svg, "diagnostic"), 1);
    assert_eq!(svg.matches("E039").count(), 3, "{svg}");
    assert!(svg.contains("in slot `far`") && !svg.contains("slot `top`"));
    assert!(!svg.contains("cell `edge`"));
}

#[test]
fn bad_requests_name_what_exists() {
    let o = packwright(&["draw", "orders/suites/teach.pack"]);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("line2") && stderr.contains("twin_row"),
        "{stderr}"
    );
    let o = packwright(&["draw", "orders/cells/line2.pack", "--cell", "line3"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("known cells: line2"));
    let o = packwright(&["draw", "tests/cases/err/syntax_missing_paren.pack"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stdout.is_empty());
    // Said, not silent: a helper's probe found no word of the missing
    // picture.
    assert!(String::from_utf8_lossy(&o.stderr).contains("no picture written"));
    // A file with no cell: said so, not "0 cells: name one".
    let dir = scratch("draw", "no-cell");
    let empty = dir.join("empty.pack");
    fs::write(&empty, "").expect("written");
    let o = packwright(&["draw", &empty.display().to_string()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no cell to draw"));
    // A generator check's error (E045, jitter that cannot place a
    // product): the picture is drawn and the exit code is check's.
    let o = packwright(&["draw", "tests/cases/err/jitter_impossible.pack"]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    is_svg(&String::from_utf8_lossy(&o.stdout));
    assert!(String::from_utf8_lossy(&o.stderr).contains("E045"));
}

#[test]
fn eval_writes_its_charts() {
    let dir = scratch("draw", "plots");
    let plots = dir.join("charts");
    let o = packwright(&[
        "eval",
        "orders/suites/measure.pack",
        "--suite",
        "m_case1_2of3",
        "--limit",
        "2",
        "--quiet",
        "--plots",
        plots.to_str().unwrap(),
    ]);
    succeeded(&o);
    for name in ["success_rate.svg", "latency.svg", "execution_time.svg"] {
        let svg = fs::read_to_string(plots.join(name)).expect(name);
        assert!(is_chart(&svg), "{name}");
        assert!(svg.contains("learned"), "{name} names the planner");
    }
    let rates = fs::read_to_string(plots.join("success_rate.svg")).expect("rates");
    assert!(rates.contains("m_case1_2of3"));
}

/// `chart` reads `eval --json` reports back: two runs of the reasoner on
/// two suites give one line per suite against the run's value, and one
/// per value against n; a file that is no report, or a value that is no
/// number, is refused with exit 2 and writes nothing.
#[test]
fn chart_draws_a_study_from_eval_reports() {
    let dir = scratch("draw", "study");
    let report = dir.join("run.json");
    let o = packwright(&[
        "eval",
        "orders/suites/measure.pack",
        "--suite",
        "m_case1_2of3",
        "m_case1_3of5",
        "--limit",
        "3",
        "--reasoner-only",
        "--quiet",
        "--json",
    ]);
    succeeded(&o);
    fs::write(&report, &o.stdout).expect("report written");
    let out = dir.join("charts");
    let run = |value: &str| format!("{value}={}", report.display());
    let o = packwright(&[
        "chart",
        &run("0.5"),
        &run("1"),
        "--x",
        "training ratio",
        "-o",
        out.to_str().unwrap(),
    ]);
    succeeded(&o);
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 2);
    let vs_x = fs::read_to_string(out.join("success_vs_x.svg")).expect("vs x");
    assert!(is_chart(&vs_x));
    for name in ["m_case1_2of3", "m_case1_3of5", "training ratio"] {
        assert!(vs_x.contains(name), "{name}");
    }
    assert_eq!(vs_x.matches("<circle").count(), 4, "2 suites x 2 runs");
    let vs_n = fs::read_to_string(out.join("success_vs_n.svg")).expect("vs n");
    assert!(is_chart(&vs_n));
    assert!(vs_n.contains("training ratio 0.5") && vs_n.contains("training ratio 1"));
    assert_eq!(vs_n.matches("<circle").count(), 4, "n = 2, 3 for each run");

    let not_a_report = dir.join("not.json");
    fs::write(&not_a_report, "{\"rows\": 3}").expect("written");
    let refused = dir.join("refused");
    for bad in [
        format!("0.5={}", not_a_report.display()),
        format!("half={}", report.display()),
        format!("0.5={}", dir.join("missing.json").display()),
    ] {
        let o = packwright(&["chart", &bad, "-o", refused.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(!o.stderr.is_empty(), "{bad}: says why");
        assert!(!refused.exists(), "{bad}: nothing written");
    }
    // Two runs at one value (helper W: drawn silently).
    let o = packwright(&[
        "chart",
        &run("0.5"),
        &run("0.5"),
        "-o",
        refused.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("two runs at"));
    assert!(!refused.exists(), "nothing written");
}

/// What `execute --svg` draws: the expert packing deli_crate, recorded
/// through the `World`, has every stage and its rests.
#[test]
fn the_executed_path_is_recorded_and_drawn() {
    let files = [PathBuf::from("orders/customers/hampton_deli.pack")];
    let files: Vec<PathBuf> = files.iter().map(|f| common::root().join(f)).collect();
    let compiled =
        packwright_compiler::check(&FsLoader, &files, &RobotWorkspace::new()).expect("compiles");
    let (name, setup) = find_setup(&compiled, Some("deli_crate"), None).expect("the order");
    let ep = episode(&compiled.model, &setup).expect("an episode");
    let mut sim = ep
        .simulator(ep.home().expect("home"))
        .expect("a simulation");
    let journal = Journal::new();
    let report = execute::run(
        &mut JournalWorld::new(&mut sim, &journal),
        &ep.arm,
        &ep.task,
        &Planner::Expert,
    );
    assert!(report.complete);
    let cycles = journal.take().cycles;
    assert!(cycles.len() > 1000, "{}", cycles.len());
    let picture = executed_picture(&compiled.model, &name, &setup, &ep.arm, &cycles, &report);
    let path = picture.path.as_ref().expect("a path");
    let picks = path
        .events
        .iter()
        .filter(|e| e.kind == packwright_draw::EventKind::Pick)
        .count();
    assert_eq!(picks, 4);
    let svg = packwright_draw::picture(&picture).expect("draws");
    for stage in ["approach", "carry", "retreat"] {
        assert!(count(&svg, stage) >= 2, "{stage}");
    }
    assert_eq!(count(&svg, "pick"), 2 * 4);
    assert_eq!(count(&svg, "release"), 2 * 4);
    // Per product the expert reaches seven sub-goals (hover, top face,
    // lift, approach, above the slot, release, back up), most passed
    // without stopping: each is numbered where the path passes it.
    let subgoals: Vec<[f64; 3]> = path
        .events
        .iter()
        .filter(|e| matches!(e.kind, packwright_draw::EventKind::SubGoal(_)))
        .map(|e| e.at)
        .collect();
    assert_eq!(count(&svg, "subgoal"), 2 * subgoals.len());
    assert_eq!(report.subgoals.len(), 7 * 4);
    assert_eq!(subgoals.len(), report.subgoals.len());
    // The path passes each within the blend's corner deviation: up to
    // about 7 cm at the lift's top (an 18 cm lift left straight for its
    // first 2 cm only, `execute::STOP_CLEARANCE`), under 5 cm elsewhere.
    for (marked, planned) in subgoals.iter().zip(&report.subgoals) {
        let off = (0..3)
            .map(|k| (marked[k] - planned[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(off < 0.08, "sub-goal {planned:?} passed {off} m away");
    }
    for e in &path.events {
        if matches!(
            e.kind,
            packwright_draw::EventKind::Pick | packwright_draw::EventKind::Release
        ) {
            let near = |p: &[f64; 3]| (0..3).all(|k| (p[k] - e.at[k]).abs() < 1e-3);
            assert!(
                subgoals.iter().any(near),
                "a switch at {:?} is a sub-goal",
                e.at
            );
        }
    }
    assert_eq!(count(&svg, "failure"), 0);
    // Each pick is on top of its product: within 1 cm of a product's
    // centre in x and y.
    for e in path
        .events
        .iter()
        .filter(|e| e.kind == packwright_draw::EventKind::Pick)
    {
        assert!(
            picture
                .products
                .iter()
                .any(|p| (p.centre[0] - e.at[0]).hypot(p.centre[1] - e.at[1]) < 0.01),
            "pick at {:?}",
            e.at
        );
    }
}

#[test]
fn execute_draws_its_path() {
    let dir = scratch("draw", "execute");
    let out = dir.join("path.svg");
    let o = packwright(&[
        "execute",
        "orders/customers/hampton_deli.pack",
        "--order",
        "deli_crate",
        "--planner",
        "expert",
        "--svg",
        out.to_str().unwrap(),
    ]);
    succeeded(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("package complete"));
    let svg = fs::read_to_string(&out).expect("written");
    is_svg(&svg);
    assert_eq!(count(&svg, "product"), 5);
    for stage in ["approach", "carry", "retreat"] {
        assert!(count(&svg, stage) >= 2, "{stage}");
    }
    assert_eq!(count(&svg, "pick"), 2 * 4);
    assert_eq!(count(&svg, "subgoal"), 2 * 7 * 4);
    assert_eq!(count(&svg, "failure"), 0);
    assert!(svg.contains("deli_crate, planner expert"));
}

/// Diagnostics about what the picture does not show (here, the file's
/// other two cells) are counted apart, so that the count adds up.
#[test]
fn diagnostics_about_what_the_picture_does_not_show_are_counted() {
    let dir = scratch("draw", "elsewhere");
    let out = dir.join("two_boxes.svg");
    let o = packwright(&[
        "draw",
        "tests/cases/err/boxes_and_base.pack",
        "--cell",
        "two_boxes",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("4 diagnostics (1 drawn where it is, 0 more listed under the picture, 3 about what this picture does not show)"),
        "{stderr}"
    );
}

/// `-o /dev/stdout` into a pipe (`draw … -o /dev/stdout | less`): the
/// picture goes down the pipe, not into a temporary file beside a path
/// that is no file (`/proc/self/fd/pipe:[…]`).
#[test]
fn a_picture_written_to_stdout_goes_down_its_pipe() {
    let o = packwright(&["draw", "orders/cells/line2.pack", "-o", "/dev/stdout"]);
    if !Path::new("/dev/stdout").exists() {
        return;
    }
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    is_svg(
        String::from_utf8_lossy(&o.stdout)
            .split("</svg>")
            .next()
            .map(|s| format!("{s}</svg>"))
            .as_deref()
            .unwrap_or_default(),
    );
}
