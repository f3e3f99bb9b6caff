//! `packwright check`: diagnostics only.

use super::{report_failure, report_warnings, summary_line};
use crate::Exit;
use crate::cli::CheckArgs;
use crate::fsio::FsLoader;
use packwright_pipeline::reach::RobotWorkspace;

pub fn run(args: &CheckArgs) -> anyhow::Result<Exit> {
    match packwright_compiler::check(&FsLoader, &args.files, &RobotWorkspace::new()) {
        Ok(mut compiled) => {
            // W005: demonstrations `train` would refuse.
            let rules = packwright_pipeline::teach::rule_warnings(&compiled);
            compiled.warnings.extend(rules);
            report_warnings(&compiled.sources, &compiled.warnings, args.json);
            if args.json {
                outln!(
                    "{}",
                    serde_json::json!({"type": "summary", "errors": 0, "warnings": compiled.warnings.len(), "files": compiled.sources.files().count()})
                );
            } else {
                errln!("ok: {}", summary_line(&compiled));
            }
            Ok(Exit::Success)
        }
        Err(failed) => Ok(report_failure(&failed, args.json)),
    }
}
