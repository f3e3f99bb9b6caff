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

/// An empty directory for one test (`suite` and `name` keep tests apart),
/// removed when the test passes and kept for a look when it fails.
pub fn scratch(suite: &str, name: &str) -> Scratch {
    let dir =
        std::env::temp_dir().join(format!("packwright-{suite}-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("scratch dir");
    Scratch(dir)
}

/// A test's scratch directory ([`scratch`]): a path, removed on drop
/// unless the test is failing.
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = fs::remove_dir_all(&self.0);
        }
    }
}
