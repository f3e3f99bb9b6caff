//! The `packwright` command line: argument parsing, file IO and output.
//! The language and compiler live in `packwright-grammar` and
//! `packwright-compiler`, the robot half in its crates, the glue between
//! them in `packwright-pipeline`; this crate is the edge where files are
//! read and written and results printed.

/// Like `print!`/`println!`/`eprint!`/`eprintln!`, but a closed pipe
/// (`packwright show out | head`) is not a panic: output just stops.
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => {{ use std::io::Write as _; let _ = write!(std::io::stdout().lock(), $($t)*); }};
}
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => {{ use std::io::Write as _; let _ = writeln!(std::io::stdout().lock(), $($t)*); }};
}
#[macro_export]
macro_rules! err {
    ($($t:tt)*) => {{ use std::io::Write as _; let _ = write!(std::io::stderr().lock(), $($t)*); }};
}
#[macro_export]
macro_rules! errln {
    ($($t:tt)*) => {{ use std::io::Write as _; let _ = writeln!(std::io::stderr().lock(), $($t)*); }};
}

pub mod cli;
pub mod commands;
pub mod fsio;

use std::process::ExitCode;

/// Documented exit codes (as ripgrep: 0 success, 1 "found something", 2
/// trouble).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// Everything is fine.
    Success = 0,
    /// The input has diagnostics, or `fmt --check` found files to format.
    Diagnostics = 1,
    /// Bad usage, unreadable input, a failed write, or an internal error.
    Failure = 2,
}

impl From<Exit> for ExitCode {
    fn from(e: Exit) -> ExitCode {
        ExitCode::from(e as u8)
    }
}

/// An error after a command printed its `--json` report on stdout (a
/// picture or table that could not be written): said on stderr only, so
/// that stdout stays one JSON document.
#[derive(Debug)]
pub struct AfterReport(pub anyhow::Error);

impl std::fmt::Display for AfterReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:#}", self.0)
    }
}

impl std::error::Error for AfterReport {}

pub fn run(cli: cli::Cli) -> anyhow::Result<Exit> {
    match cli.command {
        cli::Command::Check(args) => commands::check::run(&args),
        cli::Command::Compile(args) => commands::compile::run(&args),
        cli::Command::Show(args) => commands::show::run(&args),
        cli::Command::Draw(args) => commands::draw::run(&args),
        cli::Command::Execute(args) => commands::execute::run(&args),
        cli::Command::Demonstrate(args) => commands::demonstrate::run(&args),
        cli::Command::Train(args) => commands::train::run(&args),
        cli::Command::Eval(args) => commands::eval::run(&args),
        cli::Command::Fmt(args) => commands::fmt::run(&args),
        cli::Command::Generate(args) => commands::generate::run(&args),
        cli::Command::Chart(args) => commands::chart::run(&args),
    }
}
