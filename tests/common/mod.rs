//! What the CLI tests share: the repository root, running the binary, and
//! a fresh scratch directory per test.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `packwright` with `args` from the repository root.
pub fn packwright(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_packwright"))
        .current_dir(root())
        .args(args)
        .output()
        .expect("the packwright binary runs")
}

/// An empty directory for one test (`suite` and `name` keep tests apart).
pub fn scratch(suite: &str, name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("packwright-{suite}-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("scratch dir");
    dir
}
