//! Rendering errors for people (file:line:col, the source line, a caret, a
//! fix) and for machines (one JSON object per error).

use crate::error::Error;
use crate::source::{Loc, SourceMap};
use crate::warning::Warning;
use serde::Serialize;
use std::fmt::Write;
use unicode_width::UnicodeWidthChar;

/// Renders one error as text, in the style of rustc:
///
/// ```text
/// error[E021]: unknown product `F`
///   --> orders/acme.pack:12:3
///    |
/// 12 |   F -> g1
///    |   ^ not found in inventory `stock5`
///    |
///    = help: did you mean `E`?
/// ```
pub fn render(sources: &SourceMap, error: &Error) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "error[{}]: {error}", error.code());
    let gutter = match error.at() {
        Some(at) => snippet(&mut out, sources, at, &error.label()),
        None => {
            if let Error::Read { path, .. } = error {
                let _ = writeln!(out, "  --> {}", path.display());
            }
            GUTTER
        }
    };
    for (loc, note) in error.notes() {
        let _ = writeln!(out, "note: {note}");
        snippet(&mut out, sources, loc, "");
    }
    if let Some(help) = error.help() {
        let _ = writeln!(out, "{} = help: {help}", " ".repeat(gutter));
    }
    out
}

/// Renders one warning as text, as [`render`] does an error:
///
/// ```text
/// warning[W001]: the robot cannot reach ...
///   --> cells/line.pack:30:3
/// ```
pub fn render_warning(sources: &SourceMap, warning: &Warning) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "warning[{}]: {warning}", warning.code());
    let gutter = snippet(&mut out, sources, warning.at(), &warning.label());
    for (loc, note) in warning.notes() {
        let _ = writeln!(out, "note: {note}");
        snippet(&mut out, sources, loc, "");
    }
    let _ = writeln!(out, "{} = help: {}", " ".repeat(gutter), warning.help());
    out
}

/// The gutter's width (the line number's digits) where no line is shown.
const GUTTER: usize = 2;

/// Writes the `-->` location, the line and the carets under `at`; returns
/// the gutter's width, for the `= help` line to line up under its `|`.
fn snippet(out: &mut String, sources: &SourceMap, at: Loc, label: &str) -> usize {
    let Some(file) = sources.get(at.file) else {
        return GUTTER;
    };
    let (line, col) = file.lines.line_col(&file.text, at.span.start as usize);
    let text = file.lines.line_text(&file.text, line);
    let number = line.to_string();
    let pad = " ".repeat(number.len());
    let _ = writeln!(out, "{pad}--> {}:{line}:{col}", file.path.display());
    let _ = writeln!(out, "{pad} |");
    let _ = writeln!(out, "{number} | {text}");
    // Carets under the span's part on this line (at least one), in
    // terminal columns: a wide character (CJK, most emoji) takes two, a
    // combining mark none; tabs are copied so that they line up.
    let start_char = col - 1;
    let span_text = file.text.get(at.span.range()).unwrap_or("");
    let on_line = span_text.split('\n').next().unwrap_or("");
    let width = on_line
        .chars()
        .map(|c| c.width().unwrap_or(0))
        .sum::<usize>()
        .max(1);
    let lead: String = text
        .chars()
        .take(start_char)
        .map(|c| match c {
            '\t' => "\t".to_owned(),
            c => " ".repeat(c.width().unwrap_or(0)),
        })
        .collect();
    let carets = "^".repeat(width);
    if label.is_empty() {
        let _ = writeln!(out, "{pad} | {lead}{carets}");
    } else {
        let _ = writeln!(out, "{pad} | {lead}{carets} {label}");
    }
    number.len()
}

/// The machine-readable form of an error or a warning (`--json`).
#[derive(Debug, Clone, Serialize)]
pub struct JsonDiagnostic {
    /// `error` or `warning`.
    pub severity: Severity,
    pub code: &'static str,
    pub message: String,
    pub file: Option<String>,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub label: String,
    pub help: Option<String>,
}

pub fn to_json(sources: &SourceMap, error: &Error) -> JsonDiagnostic {
    let (file, line, column) = match error.at() {
        Some(at) => {
            let (f, l, c) = sources.position(at);
            (Some(f), Some(l), Some(c))
        }
        None => match error {
            Error::Read { path, .. } => (Some(path.display().to_string()), None, None),
            _ => (None, None, None),
        },
    };
    JsonDiagnostic {
        severity: Severity::Error,
        code: error.code(),
        message: error.to_string(),
        file,
        line,
        column,
        label: error.label(),
        help: error.help(),
    }
}

/// Whether a diagnostic stops the compilation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    Error,
    Warning,
}

/// The machine-readable form of a warning (`--json`).
pub fn warning_to_json(sources: &SourceMap, warning: &Warning) -> JsonDiagnostic {
    let (file, line, column) = sources.position(warning.at());
    JsonDiagnostic {
        severity: Severity::Warning,
        code: warning.code(),
        message: warning.to_string(),
        file: Some(file),
        line: Some(line),
        column: Some(column),
        label: warning.label(),
        help: Some(warning.help()),
    }
}
