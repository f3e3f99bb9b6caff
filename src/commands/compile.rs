//! `packwright compile`: check, then write the artifacts atomically.

use super::{report_failure, summary_line};
use crate::Exit;
use crate::cli::CompileArgs;
use crate::fsio::{FsLoader, write_dir_atomically};
use packwright_pipeline::reach::RobotWorkspace;

pub fn run(args: &CompileArgs) -> anyhow::Result<Exit> {
    let (compiled, artifacts) =
        match packwright_compiler::compile(&FsLoader, &args.files, &RobotWorkspace::new()) {
            Ok(ok) => ok,
            Err(failed) => return Ok(report_failure(&failed, args.json)),
        };
    write_dir_atomically(&args.output, &artifacts, "manifest.json")?;
    if args.json {
        let files: Vec<_> = artifacts
            .iter()
            .map(|a| serde_json::json!({"name": a.name, "bytes": a.bytes.len()}))
            .collect();
        outln!(
            "{}",
            serde_json::json!({
                "output": args.output.display().to_string(),
                "files": files,
                "demonstrations": compiled.expanded.demonstrations.len(),
                "samples": compiled.graphs.s,
                "nodes": compiled.graphs.m,
                "scenarios": compiled.expanded.suites.iter().map(|s| s.cases.len()).sum::<usize>(),
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
