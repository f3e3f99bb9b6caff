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
/// error[E021]: unknown product `gren`
///   --> orders/acme.pack:12:3
///    |
/// 12 |   gren -> g1
///    |   ^^^^ not found in inventory `stock5`
///    |
///    = help: did you mean `green`?
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
    let full = file.lines.line_text(&file.text, line);
    let number = line.to_string();
    let pad = " ".repeat(number.len());
    let _ = writeln!(out, "{pad}--> {}:{line}:{col}", file.path.display());
    let _ = writeln!(out, "{pad} |");
    // A long line is shown as a window round the span, `...` where it is
    // cut: echoing a line of thousands of names once per error made the
    // output grow with the square of its length.
    let span_text = file.text.get(at.span.range()).unwrap_or("");
    let on_line = span_text.split('\n').next().unwrap_or("");
    let (text, start_char) = window(full, col - 1, on_line.chars().count());
    // Invisible characters (a NUL, a zero-width space) shown in their
    // place, one for one, so that the carets line up.
    let text: String = text.chars().map(packwright_grammar::shown).collect();
    let _ = writeln!(out, "{number} | {text}");
    // Carets under the span's part on this line (at least one, and no
    // more than the window shows), in terminal columns: a wide character
    // (CJK, most emoji) takes two, a combining mark none; tabs are copied
    // so that they line up.
    let width = on_line
        .chars()
        .take(SHOWN_CHARS)
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

/// The most characters of a source line a snippet shows.
const SHOWN_CHARS: usize = 100;

/// Characters shown before the span when a long line is cut.
const SHOWN_BEFORE: usize = 40;

/// The part of `line` a snippet shows for a span starting at character
/// `start` and `len` characters long: the whole line when it is short,
/// else [`SHOWN_CHARS`] characters from [`SHOWN_BEFORE`] before the span,
/// marked `...` where cut; and where the span starts in it (characters).
fn window(line: &str, start: usize, len: usize) -> (String, usize) {
    if line.len() <= SHOWN_CHARS {
        return (line.to_owned(), start);
    }
    let count = line.chars().count();
    if count <= SHOWN_CHARS {
        return (line.to_owned(), start);
    }
    let from = start.saturating_sub(SHOWN_BEFORE);
    let to = (from + SHOWN_CHARS)
        .max(start + len.min(SHOWN_CHARS))
        .min(count);
    let cut: String = line.chars().skip(from).take(to - from).collect();
    let (before, after) = (
        if from > 0 { "..." } else { "" },
        if to < count { "..." } else { "" },
    );
    (format!("{before}{cut}{after}"), start - from + before.len())
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
    /// The places the text form shows under `note:` (the first of two
    /// duplicates, a product standing in the way).
    pub notes: Vec<JsonNote>,
}

/// A note of a diagnostic: what is at another place.
#[derive(Debug, Clone, Serialize)]
pub struct JsonNote {
    pub message: String,
    pub file: String,
    pub line: usize,
    pub column: usize,
}

fn json_notes(sources: &SourceMap, notes: Vec<(Loc, String)>) -> Vec<JsonNote> {
    notes
        .into_iter()
        .map(|(loc, message)| {
            let (file, line, column) = sources.position(loc);
            JsonNote {
                message,
                file,
                line,
                column,
            }
        })
        .collect()
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
        notes: json_notes(sources, error.notes()),
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
        notes: json_notes(sources, warning.notes()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::source::MemoryLoader;
    use crate::{Anywhere, SHOWN_ERRORS, check};
    use std::path::PathBuf;

    /// A short line is shown whole; a long one as a window of
    /// [`SHOWN_CHARS`] characters from [`SHOWN_BEFORE`] before the span,
    /// `...` where cut, the span's start moved with it.
    #[test]
    fn a_long_line_is_shown_as_a_window_round_the_span() {
        assert_eq!(window("a b c", 2, 1), ("a b c".to_owned(), 2));
        let line: String = (0..300)
            .map(|i| char::from(b'a' + (i % 26) as u8))
            .collect();
        let (shown, at) = window(&line, 150, 3);
        assert!(
            shown.starts_with("...") && shown.ends_with("..."),
            "{shown}"
        );
        assert_eq!(shown.chars().count(), SHOWN_CHARS + 6);
        assert_eq!(
            shown.chars().skip(at).take(3).collect::<String>(),
            line[150..153]
        );
        // Near the start: cut at the end only.
        let (shown, at) = window(&line, 10, 3);
        assert!(!shown.starts_with("...") && shown.ends_with("..."));
        assert_eq!(at, 10);
        // Near the end: cut at the start only, the span in the window.
        let (shown, at) = window(&line, 298, 2);
        assert!(shown.starts_with("...") && !shown.ends_with("..."));
        assert_eq!(shown.chars().skip(at).collect::<String>(), line[298..]);
    }

    /// A `use` of a file that is missing is told that paths are relative
    /// to the using file; one that is there but unreadable (a helper's
    /// `use "/dev/zero"`, larger than 16 MiB) is told what a usable file
    /// is instead.
    #[test]
    fn a_use_of_an_unreadable_file_is_not_told_about_relative_paths() {
        use crate::source::{Loader, Unreadable};
        use std::path::Path;
        struct Files;
        impl Loader for Files {
            fn read(&self, path: &Path) -> Result<String, Unreadable> {
                match path.to_str() {
                    Some("main.pack") => Ok("use \"big.pack\"\nuse \"gone.pack\"\n".into()),
                    Some("big.pack") => Err(Unreadable::TooLarge { limit_mib: 16 }),
                    _ => Err(Unreadable::Missing),
                }
            }
        }
        let failed = check(&Files, &[PathBuf::from("main.pack")], &Anywhere)
            .map(|_| ())
            .expect_err("unreadable uses");
        let helps: Vec<Option<String>> = failed.errors.iter().map(Error::help).collect();
        assert_eq!(failed.errors.len(), 2, "{:?}", failed.errors);
        assert!(
            helps[0].as_deref().is_some_and(|h| h.contains("16 MiB")),
            "{helps:?}"
        );
        assert!(
            helps[1].as_deref().is_some_and(|h| h.contains("relative")),
            "{helps:?}"
        );
    }

    /// Thousands of errors: the first [`SHOWN_ERRORS`] are rendered, and a
    /// line says how many more there are; every one is still counted.
    #[test]
    fn a_failure_shows_its_first_errors_and_counts_the_rest() {
        let text = "x\n".repeat(SHOWN_ERRORS + 20);
        let loader = MemoryLoader::new().with("stray.pack", text);
        let failed = check(&loader, &[PathBuf::from("stray.pack")], &Anywhere)
            .map(|_| ())
            .expect_err("stray lines");
        assert_eq!(failed.errors.len(), SHOWN_ERRORS + 20);
        assert_eq!(failed.shown().len(), SHOWN_ERRORS);
        assert_eq!(failed.not_shown(), 20);
        let rendered = failed.render();
        assert_eq!(rendered.matches("error[E001]").count(), SHOWN_ERRORS);
        assert!(
            rendered.contains("... and 20 more errors not shown"),
            "{rendered}"
        );
    }
}
