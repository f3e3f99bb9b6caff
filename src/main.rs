//! `packwright`: teach a UR10 cobot to pack customer orders from a few
//! demonstrations. See `packwright --help`.

use clap::Parser;
use packwright::cli::Cli;
use packwright::{errln, outln};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(&e),
    };
    packwright::fsio::remove_temporaries_on_interrupt();
    let json = cli.wants_json();
    match packwright::run(cli) {
        Ok(code) => code.into(),
        Err(e) => {
            errln!("error: {e:#}");
            if json && e.downcast_ref::<packwright::AfterReport>().is_none() {
                let error = serde_json::json!({"type": "error", "message": format!("{e:#}")});
                outln!("{error}");
            }
            packwright::Exit::Failure.into()
        }
    }
}

/// A command line clap refuses: its message on stderr and exit 2 (help
/// and `--version` print on stdout and exit 0); with `--json`, the error
/// also on stdout as JSON, as for any error that stops a command.
fn usage_error(e: &clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion)
        || !std::env::args().any(|a| a == "--json")
    {
        // clap prints where it should (help on stdout, errors on
        // stderr) and says which exit code.
        let _ = e.print();
        return ExitCode::from(e.exit_code().clamp(0, 255) as u8);
    }
    let _ = e.print();
    let rendered = e.render().to_string();
    let message = rendered
        .lines()
        .next()
        .unwrap_or_default()
        .trim_start_matches("error: ");
    outln!(
        "{}",
        serde_json::json!({"type": "error", "message": message})
    );
    packwright::Exit::Failure.into()
}
