//! Bad input at the file-system edge: sources too large (or endless) are
//! refused quickly, and temporary siblings left by killed runs are cleaned
//! up by the next run; a run killed at any point leaves the old output or
//! the new one whole; a model directory `eval` cannot use is refused
//! before anything runs.

mod common;
use common::{packwright, scratch};
use std::fs;
use std::path::Path;
use std::time::{Duration, Instant};

#[test]
fn oversized_and_endless_sources_are_refused_quickly() {
    let dir = scratch("reliability", "size");
    let big = dir.join("big.pack");
    // 17 MiB of comments: valid text, over the 16 MiB limit.
    let line = format!("# {}\n", "x".repeat(1021));
    fs::write(&big, line.repeat(17 * 1024)).expect("written");
    let mut files = vec![big.display().to_string()];
    if Path::new("/dev/zero").exists() {
        files.push("/dev/zero".into());
    }
    for f in &files {
        for command in ["check", "fmt"] {
            let started = Instant::now();
            let args: Vec<&str> = if command == "fmt" {
                vec!["fmt", "--stdout", f]
            } else {
                vec!["check", f]
            };
            let out = packwright(&args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(
                matches!(out.status.code(), Some(1 | 2)),
                "{command} {f}: {stderr}"
            );
            assert!(
                stderr.contains("larger than 16 MiB"),
                "{command} {f}: {stderr}"
            );
            assert!(
                started.elapsed() < Duration::from_secs(10),
                "{command} {f} took {:?}",
                started.elapsed()
            );
        }
    }
}

/// A file that `use`s a named pipe nobody writes to is refused at once
/// (opening the pipe would wait for a writer for ever), with the `use`'s
/// place (E010) and exit 1, as any error in the sources.
#[test]
fn a_used_named_pipe_is_refused_not_waited_on() {
    let dir = scratch("reliability", "fifo");
    let fifo = dir.join("fifo.pack");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs (coreutils)");
    assert!(made.success(), "mkfifo {}", fifo.display());
    let user = dir.join("user.pack");
    fs::write(&user, "use \"fifo.pack\"\n").expect("written");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_packwright"))
        .args(["check", &user.display().to_string()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("started");
    let started = Instant::now();
    while child.try_wait().expect("waited").is_none() {
        if started.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            panic!("check waited on the named pipe");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("output");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("not a file on disk"), "{stderr}");
    assert!(stderr.contains("user.pack:1:"), "{stderr}");
}

#[test]
fn a_killed_runs_temporary_directories_are_removed_by_the_next_run() {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let dir = scratch("reliability", "stale");
    let out = dir.join("out");
    // A process id above Linux's largest (4,194,304) is never alive; this
    // test's own process is.
    let stale = dir.join(".out.tmp-4194400");
    let stale_old = dir.join(".out.old-4194401");
    let live = dir.join(format!(".out.tmp-{}", std::process::id()));
    // As an earlier compile left them (`compile` replaces a directory
    // only when its manifest is packwright's).
    for d in [&stale, &stale_old, &live] {
        fs::create_dir_all(d).expect("created");
        fs::write(
            d.join("manifest.json"),
            r#"{"schema": "packwright.manifest"}"#,
        )
        .expect("written");
    }
    let target = out.display().to_string();
    let result = packwright(&["compile", "orders/customers/pine_gifts.pack", "-o", &target]);
    assert_eq!(result.status.code(), Some(0));
    assert!(out.join("manifest.json").is_file());
    assert!(
        !stale.exists() && !stale_old.exists(),
        "stale siblings removed"
    );
    assert!(live.exists(), "a live process's sibling is left alone");
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// The files of a directory, name and bytes, sorted by name.
type Files = Vec<(String, Vec<u8>)>;

/// The files of a directory.
fn contents(dir: &Path) -> Files {
    let mut files: Files = fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .map(|e| {
                    let bytes = fs::read(e.path()).unwrap_or_default();
                    (e.file_name().to_string_lossy().into_owned(), bytes)
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// Entries of `parent` that belong to the output `name` other than itself
/// (`.NAME.tmp-PID`, `.NAME.old-PID`).
fn siblings(parent: &Path, name: &str) -> Vec<String> {
    let prefix = format!(".{name}.");
    fs::read_dir(parent)
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|f| f.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default()
}

/// When to kill a run.
#[derive(Debug, Clone, Copy)]
enum Kill {
    /// This long after it starts.
    After(Duration),
    /// This long after its temporary output directory appears (while it
    /// writes or renames).
    Writing(Duration),
}

/// Runs packwright with `args` writing `out`, killed (SIGKILL) at `when`
/// if it is still running; its process id.
fn run_killed(args: &[&str], out: &Path, when: Kill) -> u32 {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_packwright"))
        .current_dir(common::root())
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("packwright starts");
    let pid = child.id();
    match when {
        Kill::After(delay) => std::thread::sleep(delay),
        Kill::Writing(delay) => {
            let name = out.file_name().map(|n| n.to_string_lossy().into_owned());
            let tmp = out.with_file_name(format!(".{}.tmp-{pid}", name.unwrap_or_default()));
            let started = Instant::now();
            while !tmp.exists()
                && started.elapsed() < Duration::from_secs(60)
                && child.try_wait().ok().flatten().is_none()
            {
                std::thread::sleep(Duration::from_micros(200));
            }
            std::thread::sleep(delay);
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    pid
}

/// Kill points spread over a run of `span`, from a fifth of it to past its
/// end (the writing is at the end): fixed, so every run of the test kills
/// at the same places.
/// Half of them from the moment its temporary output appears, 0-300 ms
/// into the writing and renaming.
fn kill_points(span: Duration, count: u32) -> Vec<Kill> {
    // A small linear congruential sequence: seeded, no dependency.
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    (0..count)
        .map(|i| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            if i % 2 == 0 {
                Kill::After(span.mul_f64(0.2 + u * 0.9))
            } else {
                Kill::Writing(Duration::from_secs_f64(u * 0.300))
            }
        })
        .collect()
}

/// `out` after a kill: the old output intact, the new one complete
/// (`complete` says what that means), or, killed between its two renames,
/// no `out` and the old one whole beside it under the killed run's name.
fn assert_old_or_new(
    out: &Path,
    old: &Files,
    pid: u32,
    complete: &dyn Fn(&Files) -> bool,
    what: &str,
) {
    let name = out.file_name().map(|n| n.to_string_lossy().into_owned());
    let name = name.unwrap_or_default();
    if out.exists() {
        let now = contents(out);
        assert!(
            now == *old || complete(&now),
            "{what}: {} is neither the old output nor a complete new one: {:?}",
            out.display(),
            now.iter().map(|(n, b)| (n, b.len())).collect::<Vec<_>>()
        );
    } else {
        let parent = out.parent().expect("a parent");
        let aside = parent.join(format!(".{name}.old-{pid}"));
        assert_eq!(
            contents(&aside),
            *old,
            "{what}: {} is gone and the old output is not whole beside it",
            out.display()
        );
    }
}

/// A scratch directory `name` holding a copy of the line2 cell.
fn beside_line2(name: &str) -> common::Scratch {
    let dir = scratch("reliability", name);
    fs::copy(
        common::root().join("orders/cells/line2.pack"),
        dir.join("line2.pack"),
    )
    .expect("copied");
    dir
}

/// A file beside line2 (`beside_line2`) whose `demos` block makes 600
/// demonstrations per `repeat`.
fn many_demonstrations(repeat: u32, seed: u32) -> String {
    format!(
        "use \"line2.pack\"\ndemos many for pantry5 {{\n  \
         choose 3 of jam, tea, honey, soap, candle into k1, k2, k3, k4, k5\n  \
         jitter 20 mm\n  repeat {repeat}\n  seed {seed}\n}}\n"
    )
}

/// `compile` killed at fixed points over its run (about 12,000
/// demonstrations of the line2 cell): `out` is always the old output or the new one
/// whole, never a mix; the next run leaves no debris.
#[test]
fn a_killed_compile_leaves_the_old_output_or_the_new_one() {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let dir = beside_line2("killed-compile");
    let source = |seed: u32| many_demonstrations(20, seed);
    let (old_file, new_file) = (dir.join("old.pack"), dir.join("new.pack"));
    fs::write(&old_file, source(1)).expect("written");
    fs::write(&new_file, source(2)).expect("written");
    let (old_file, new_file) = (
        old_file.display().to_string(),
        new_file.display().to_string(),
    );
    let out = dir.join("out");
    let out_s = out.display().to_string();
    let reference = dir.join("reference");
    let started = Instant::now();
    let made = packwright(&["compile", &new_file, "-o", &reference.display().to_string()]);
    let span = started.elapsed();
    assert_eq!(made.status.code(), Some(0));
    let new = contents(&reference);
    let is_new = |c: &Files| *c == new;
    for delay in kill_points(span, 12) {
        let made = packwright(&["compile", &old_file, "-o", &out_s]);
        assert_eq!(made.status.code(), Some(0));
        assert!(siblings(&dir, "out").is_empty(), "no debris after a run");
        let old = contents(&out);
        let pid = run_killed(&["compile", &new_file, "-o", &out_s], &out, delay);
        assert_old_or_new(&out, &old, pid, &is_new, &format!("killed at {delay:?}"));
        eprintln!(
            "killed at {delay:?}: {}, left {:?}",
            if contents(&out) == old { "old" } else { "new" },
            siblings(&dir, "out")
        );
    }
    let made = packwright(&["compile", &old_file, "-o", &out_s]);
    assert_eq!(made.status.code(), Some(0));
    assert!(siblings(&dir, "out").is_empty(), "no debris after a run");
}

/// `compile` interrupted with Ctrl-C (SIGINT) while it writes its output
/// (helper G found up to 0.9 GB left behind by one until a later compile
/// to the same place): exit 130, the old output intact, and no temporary
/// directory left. The demonstrations are many, so that the writing lasts
/// long past the moment the signal is sent.
#[test]
fn an_interrupted_compile_removes_what_it_was_writing_and_keeps_the_old_output() {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let dir = beside_line2("interrupted-compile");
    let source = |repeat: u32| many_demonstrations(repeat, 1);
    let (old_file, new_file) = (dir.join("old.pack"), dir.join("new.pack"));
    fs::write(&old_file, source(1)).expect("written");
    fs::write(&new_file, source(100)).expect("written");
    let out = dir.join("out");
    let out_s = out.display().to_string();
    let made = packwright(&["compile", &old_file.display().to_string(), "-o", &out_s]);
    assert_eq!(made.status.code(), Some(0));
    let old = contents(&out);
    // Ctrl-C, and a service manager's stop (helper W: SIGTERM left a
    // 339 MB temporary behind).
    for signal in ["-INT", "-TERM"] {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_packwright"))
            .current_dir(common::root())
            .args(["compile", &new_file.display().to_string(), "-o", &out_s])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("packwright starts");
        let pid = child.id();
        let tmp = dir.join(format!(".out.tmp-{pid}"));
        let started = Instant::now();
        while !tmp.exists()
            && started.elapsed() < Duration::from_secs(60)
            && child.try_wait().ok().flatten().is_none()
        {
            std::thread::sleep(Duration::from_micros(200));
        }
        std::thread::sleep(Duration::from_millis(20));
        let sent = std::process::Command::new("kill")
            .args([signal, &pid.to_string()])
            .status()
            .expect("kill runs");
        assert!(sent.success());
        let status = child.wait().expect("the run ends");
        assert_eq!(
            status.code(),
            Some(130),
            "interrupted while writing ({signal})"
        );
        assert!(!tmp.exists(), "{} left behind", tmp.display());
        assert!(
            siblings(&dir, "out").is_empty(),
            "{:?}",
            siblings(&dir, "out")
        );
        assert_eq!(contents(&out), old, "the old output intact");
    }
}

/// `train` killed at fixed points over its run: the model directory is
/// always the old model or a complete new one (every file, the JSON files
/// whole), and the next run leaves no debris.
#[test]
fn a_killed_train_leaves_the_old_model_or_the_new_one() {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let dir = scratch("reliability", "killed-train");
    let compiled = dir.join("pine").display().to_string();
    let made = packwright(&[
        "compile",
        "orders/customers/pine_gifts.pack",
        "-o",
        &compiled,
    ]);
    assert_eq!(made.status.code(), Some(0));
    let model = dir.join("model");
    let model_s = model.display().to_string();
    let train = |epochs: &'static str, target: &str| {
        vec![
            "train".to_owned(),
            compiled.clone(),
            "-o".to_owned(),
            target.to_owned(),
            "--demos".to_owned(),
            "pine_seen".to_owned(),
            "--epochs".to_owned(),
            epochs.to_owned(),
            "--dagger-rounds".to_owned(),
            "1".to_owned(),
            "--quiet".to_owned(),
        ]
    };
    let complete = |c: &Files| {
        let names: Vec<&str> = c.iter().map(|(n, _)| n.as_str()).collect();
        names
            == [
                "config.json",
                "dynamics.safetensors",
                "metrics.json",
                "reasoner.safetensors",
                "subgoal.safetensors",
            ]
            && c.iter()
                .filter(|(n, _)| n.ends_with(".json"))
                .all(|(_, b)| serde_json::from_slice::<serde_json::Value>(b).is_ok())
    };
    let reference = dir.join("reference").display().to_string();
    let started = Instant::now();
    let long = train("20", &reference);
    let made = packwright(&strs(&long));
    let span = started.elapsed();
    assert_eq!(made.status.code(), Some(0));
    let long = train("20", &model_s);
    let short = train("2", &model_s);
    for delay in kill_points(span, 6) {
        let made = packwright(&strs(&short));
        assert_eq!(made.status.code(), Some(0));
        assert!(siblings(&dir, "model").is_empty(), "no debris after a run");
        let old = contents(&model);
        assert!(complete(&old));
        let pid = run_killed(&strs(&long), &model, delay);
        assert_old_or_new(
            &model,
            &old,
            pid,
            &complete,
            &format!("killed at {delay:?}"),
        );
    }
    let made = packwright(&strs(&short));
    assert_eq!(made.status.code(), Some(0));
    assert!(siblings(&dir, "model").is_empty(), "no debris after a run");
}

/// A model named with `--model` that cannot be used (another schema, or
/// no model there) is refused with exit 2 before a scenario runs, saying
/// why; measuring only the baselines would answer another question.
#[test]
fn eval_refuses_a_model_it_cannot_use_before_running_anything() {
    let dir = scratch("reliability", "eval-model");
    let model = dir.join("old");
    fs::create_dir_all(&model).expect("model dir");
    for f in fs::read_dir("models/default").expect("the bundled model") {
        let f = f.expect("entry").path();
        let name = f.file_name().expect("a file name");
        fs::copy(&f, model.join(name)).expect("copied");
    }
    let config = model.join("config.json");
    let text = fs::read_to_string(&config).expect("config");
    let old = text.replacen("\"packwright.model/", "\"packwright.model/0", 1);
    assert_ne!(old, text);
    fs::write(&config, old).expect("written");
    let missing = dir.join("missing").display().to_string();
    for bad in [model.display().to_string(), missing] {
        let out = packwright(&[
            "eval",
            "orders/suites/measure.pack",
            "--model",
            &bad,
            "--limit",
            "1",
            "--json",
        ]);
        assert_eq!(out.status.code(), Some(2), "{bad}");
        // Nothing measured: with `--json`, the error alone, as JSON.
        let stdout = String::from_utf8_lossy(&out.stdout);
        let error: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON object");
        assert_eq!(error["type"], "error", "{bad}: {stdout}");
        assert!(
            error["message"].as_str().is_some_and(|m| m.contains(&bad)),
            "{stdout}"
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(&bad), "{bad}: {err}");
    }
}

/// What `eval` measured is printed before its files are written: a
/// `--markdown` path whose directory is missing gets it made (as
/// `compile` makes its output's), and a path that cannot be written
/// fails after the tables are out (a helper's probe: a run's results
/// lost to a typo in the path). A suite the files do not define, with
/// `--json`, is a JSON error on stdout as well as the message on stderr.
#[test]
fn eval_prints_what_it_measured_before_writing_its_files() {
    let dir = scratch("reliability", "eval-markdown");
    let md = dir.join("not").join("yet").join("table.md");
    let args = |md: &str, json: bool| {
        let mut args = vec![
            "eval",
            "orders/suites/measure.pack",
            "--suite",
            "m_case1_2of3",
            "--limit",
            "1",
            "--markdown",
            md,
        ];
        if json {
            args.push("--json");
        }
        packwright(&args)
    };
    let out = args(&md.display().to_string(), false);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = fs::read_to_string(&md).expect("written where its directory was missing");
    assert_eq!(String::from_utf8_lossy(&out.stdout), table);
    // A file where the directory should be: the write fails, the table
    // is out.
    let blocked = dir.join("file");
    fs::write(&blocked, "a file").expect("written");
    let unwritable = blocked.join("table.md").display().to_string();
    let out = args(&unwritable, false);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stdout).contains("m_case1_2of3"));
    // With `--json`, stdout stays the one report; the write's error is on
    // stderr.
    let out = args(&unwritable, true);
    assert_eq!(out.status.code(), Some(2));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    assert_eq!(report["rows"][0]["suite"], "m_case1_2of3");
    assert!(String::from_utf8_lossy(&out.stderr).contains("error:"));
    let out = packwright(&[
        "eval",
        "orders/suites/measure.pack",
        "--suite",
        "nosuch",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let error: serde_json::Value = serde_json::from_slice(&out.stdout).expect("a JSON error");
    assert_eq!(error["type"], "error");
    assert!(
        error["message"]
            .as_str()
            .is_some_and(|m| m.contains("nosuch"))
    );
}

/// Outputs never destroy inputs (helper W's probe): `draw -o` naming the
/// file drawn, or a file it `use`s, wrote the picture over it (exit 0);
/// compiling an empty file replaced an earlier dataset with nothing.
/// Both are refused now, the files as they were.
#[test]
fn no_output_replaces_a_source_read_or_a_dataset_with_nothing() {
    let dir = scratch("reliability", "inputs-kept");
    let cell = dir.join("cell.pack");
    let order = dir.join("order.pack");
    fs::copy("orders/cells/line2.pack", &cell).expect("the cell copied");
    let text = fs::read_to_string("orders/customers/pine_gifts.pack")
        .expect("the order")
        .replace("../cells/line2.pack", "cell.pack");
    fs::write(&order, &text).expect("the order written");
    let (order_s, cell_s) = (order.display().to_string(), cell.display().to_string());
    let cell_text = fs::read(&cell).expect("the cell");
    for out in [&order_s, &cell_s] {
        let o = packwright(&["draw", &order_s, "-o", out]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("would destroy it"),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    assert_eq!(fs::read_to_string(&order).expect("the order"), text);
    assert_eq!(fs::read(&cell).expect("the cell"), cell_text);
    // Elsewhere, the picture is written.
    let svg = dir.join("order.svg").display().to_string();
    let o = packwright(&["draw", &order_s, "-o", &svg]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );

    let out = dir.join("compiled");
    let o = packwright(&["compile", &order_s, "-o", &out.display().to_string()]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let before = contents(&out);
    let empty = dir.join("empty.pack");
    fs::write(&empty, "# nothing yet\n").expect("written");
    let o = packwright(&[
        "compile",
        &empty.display().to_string(),
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("define nothing to compile"));
    assert!(contents(&out) == before, "the dataset changed");
}

/// Counts that would make nothing or more than a run can hold are
/// refused by the command line (exit 2): `generate --count` above
/// 10,000 aborted allocating; `train --epochs 0` trained anyway.
#[test]
fn counts_out_of_range_are_refused() {
    let dir = scratch("reliability", "counts");
    let out = dir.join("gen").display().to_string();
    for count in ["10001", "18446744073709551615"] {
        let o = packwright(&["generate", "--seed", "1", "--count", count, "-o", &out]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    assert!(!dir.join("gen").exists(), "nothing made");
    let o = packwright(&["train", "nowhere", "-o", &out, "--epochs", "0"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("--epochs"));
}
