//! `packwright check`: diagnostics only.

use super::{checked, report_failure, report_warnings, summary_line};
use crate::Exit;
use crate::cli::CheckArgs;

pub fn run(args: &CheckArgs) -> anyhow::Result<Exit> {
    match checked(&args.files) {
        Ok(compiled) => {
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
