//! `packwright`: teach a UR10 cobot to pack customer orders from a few
//! demonstrations. See `packwright --help`.

use clap::Parser;
use packwright::cli::Cli;
use packwright::{errln, outln};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    packwright::fsio::remove_temporaries_on_interrupt();
    let json = cli.wants_json();
    match packwright::run(cli) {
        Ok(code) => code.into(),
        Err(e) => {
            errln!("error: {e:#}");
            if json {
                let error = serde_json::json!({"type": "error", "message": format!("{e:#}")});
                outln!("{error}");
            }
            packwright::Exit::Failure.into()
        }
    }
}
