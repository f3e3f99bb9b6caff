//! `packwright`: teach a UR10 cobot to pack customer orders from a few
//! demonstrations. See `packwright --help`.

use clap::Parser;
use packwright::cli::Cli;
use packwright::errln;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match packwright::run(cli) {
        Ok(code) => code.into(),
        Err(e) => {
            errln!("error: {e:#}");
            packwright::Exit::Failure.into()
        }
    }
}
