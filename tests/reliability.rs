//! Bad input at the file-system edge: sources too large (or endless) are
//! refused quickly, and temporary siblings left by killed runs are cleaned
//! up by the next run.

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
    let _ = fs::remove_dir_all(&dir);
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
    for d in [&stale, &stale_old, &live] {
        fs::create_dir_all(d).expect("created");
        fs::write(d.join("manifest.json"), "{}").expect("written");
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
    let _ = fs::remove_dir_all(&dir);
}
