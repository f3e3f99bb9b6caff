//! `packwright compile`: check, then write the artifacts atomically.

use super::{report_failure, summary_line};
use crate::Exit;
use crate::cli::CompileArgs;
use crate::fsio::AtomicDir;

pub fn run(args: &CompileArgs) -> anyhow::Result<Exit> {
    let compiled = match super::checked(&args.files) {
        Ok(ok) => ok,
        Err(failed) => return Ok(report_failure(&failed, args.json)),
    };
    if !args.json {
        super::report_warnings(&compiled.sources, &compiled.warnings, false);
    }
    // An empty file (a truncated copy, the wrong file, `/dev/null`) would
    // replace an earlier dataset with nothing: refused, that kept.
    if defines_nothing(&compiled.model) {
        let why = format!(
            "the files define nothing to compile (no cell, product, inventory, order, demonstration or scenario): {} was left as it was",
            args.output.display()
        );
        if args.json {
            outln!(
                "{}",
                serde_json::json!({"type": "nothing_to_compile", "error": why})
            );
        } else {
            errln!("error: {why}");
        }
        return Ok(Exit::Diagnostics);
    }
    // Checked before anything is written; then the artifacts are streamed
    // into a temporary sibling of the output, swapped in when complete.
    let file = &packwright_compiler::file::ALL;
    let out = AtomicDir::begin(&args.output, file[0], file)?;
    let written = match packwright_compiler::emit::emit(
        &compiled.sources,
        &compiled.model,
        &compiled.expanded,
        compiled.shape,
        &out,
    ) {
        Ok(written) => written,
        Err(e) => {
            let failed = packwright_compiler::Failed {
                sources: compiled.sources,
                errors: vec![e],
            };
            return Ok(report_failure(&failed, args.json));
        }
    };
    out.commit()?;
    if args.json {
        let files: Vec<_> = written
            .iter()
            .map(|w| serde_json::json!({"name": w.name, "bytes": w.bytes}))
            .collect();
        outln!(
            "{}",
            serde_json::json!({
                "type": "compiled",
                "output": args.output.display().to_string(),
                "files": files,
                "demonstrations": compiled.expanded.demonstration_count(),
                "samples": compiled.shape.samples,
                "nodes": compiled.shape.width,
                "scenarios": compiled.expanded.suites.iter().map(|s| s.cases.len()).sum::<usize>(),
                "warnings": compiled.warnings.iter().map(|w| packwright_compiler::diagnostic::warning_to_json(&compiled.sources, w)).collect::<Vec<_>>(),
            })
        );
    } else {
        outln!(
            "wrote {}: {}",
            args.output.display(),
            summary_line(&compiled)
        );
    }
    Ok(Exit::Success)
}

/// Whether a model holds no item at all.
fn defines_nothing(m: &packwright_compiler::model::Model) -> bool {
    m.cells.is_empty()
        && m.products.is_empty()
        && m.inventories.is_empty()
        && m.orders.is_empty()
        && m.demos.is_empty()
        && m.demo_sets.is_empty()
        && m.scenarios.is_empty()
        && m.scenario_sets.is_empty()
}
