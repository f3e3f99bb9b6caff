//! One module per subcommand.

pub mod chart;
pub mod check;
pub mod compile;
pub mod demonstrate;
pub mod draw;
pub mod eval;
pub mod execute;
pub mod fmt;
pub mod generate;
pub mod show;
pub mod train;

use crate::Exit;
use packwright_compiler::{Compiled, Failed, SourceMap, Warning, diagnostic};

/// Prints a failed compilation's diagnostics (text on stderr, or JSON Lines
/// on stdout) and picks the exit code.
pub fn report_failure(failed: &Failed, json: bool) -> Exit {
    if json {
        for e in failed.shown() {
            let mut value =
                serde_json::to_value(diagnostic::to_json(&failed.sources, e)).unwrap_or_default();
            if let Some(obj) = value.as_object_mut() {
                obj.insert("type".into(), "diagnostic".into());
            }
            outln!("{value}");
        }
        outln!(
            "{}",
            serde_json::json!({"type": "summary", "errors": failed.errors.len(), "not_shown": failed.not_shown(), "files": failed.sources.files().count()})
        );
    } else {
        err!("{}", failed.render());
        let n = failed.errors.len();
        errln!("\n{} found", counted(n, "error", "errors"));
    }
    if failed.is_io() {
        Exit::Failure
    } else {
        Exit::Diagnostics
    }
}

/// `files` checked as `check` and `compile` check them: the compiler's
/// diagnostics with the robot's workspace, and W005 for demonstrations
/// `train` would refuse ([`packwright_pipeline::teach::rule_warnings`]).
pub fn checked(
    files: &[std::path::PathBuf],
) -> Result<packwright_compiler::Compiled, packwright_compiler::Failed> {
    let mut compiled = packwright_compiler::check(
        &crate::fsio::FsLoader,
        files,
        &packwright_pipeline::reach::RobotWorkspace::new(),
    )?;
    let rules = packwright_pipeline::teach::rule_warnings(&compiled);
    compiled.warnings.extend(rules);
    Ok(compiled)
}

/// Prints a compilation's warnings: text on stderr, or (`json`) JSON
/// Lines on stdout, `"type": "diagnostic"` with `"severity": "warning"`.
pub fn report_warnings(sources: &SourceMap, warnings: &[Warning], json: bool) {
    for w in warnings {
        if json {
            let mut value =
                serde_json::to_value(diagnostic::warning_to_json(sources, w)).unwrap_or_default();
            if let Some(obj) = value.as_object_mut() {
                obj.insert("type".into(), "diagnostic".into());
            }
            outln!("{value}");
        } else {
            errln!("{}", diagnostic::render_warning(sources, w));
        }
    }
}

/// `n` and the noun counted, in the singular where `n` is 1 ("1 file",
/// "2 files").
pub fn counted(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// One line that says what a clean compilation holds ("1 file: 1 cell,
/// 5 products, ...").
pub fn summary_line(c: &Compiled) -> String {
    let m = &c.model;
    let x = &c.expanded;
    format!(
        "{}: {}, {}, {}, {}, {} ({}), {} in {}",
        counted(c.sources.files().count(), "file", "files"),
        counted(m.cells.len(), "cell", "cells"),
        counted(m.products.len(), "product", "products"),
        counted(m.inventories.len(), "inventory", "inventories"),
        counted(m.orders.len(), "order", "orders"),
        counted(x.demonstration_count(), "demonstration", "demonstrations"),
        counted(c.shape.samples, "sample", "samples"),
        counted(
            x.suites.iter().map(|s| s.cases.len()).sum::<usize>(),
            "scenario",
            "scenarios"
        ),
        counted(x.suites.len(), "suite", "suites"),
    )
}
