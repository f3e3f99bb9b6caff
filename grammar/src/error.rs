//! Syntax diagnostics: what the parser and the value checks can say about
//! one text. Each carries the span to point at; `code`, `label` and `help`
//! give the rest of a rendered diagnostic.

use crate::place::Place;
use crate::span::Span;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum SyntaxError {
    /// The text does not fit the grammar at `span`.
    #[error("expected {expected} {context}, found {found}")]
    Unexpected {
        span: Span,
        /// Readable alternatives ("a length such as `50 mm`", "`->`").
        expected: String,
        found: String,
        /// Where the parser was: at the top level, in a cell.
        context: Place,
        /// A keyword close to what was written.
        suggestion: Option<String>,
        /// The first word of the statement the error stands in (`slot`),
        /// whose form the help shows.
        statement: Option<String>,
        /// What was found is an invisible character ([`crate::is_invisible`]).
        invisible: bool,
    },
    #[error("unknown unit `{unit}`")]
    UnknownUnit {
        span: Span,
        unit: String,
        allowed: &'static str,
    },
    #[error("missing unit: `{number}` would mean {number} metres")]
    MissingUnit { span: Span, number: String },
    #[error("{what} takes a plain number, without a unit")]
    UnexpectedUnit { span: Span, what: &'static str },
    #[error("{what} must be a whole number (no sign, no decimals), found `{found}`")]
    NotWholeNumber {
        span: Span,
        what: &'static str,
        found: String,
    },
    #[error(
        "{what} is too large: a whole number is at most {}, found `{found}`",
        u64::MAX
    )]
    WholeNumberTooLarge {
        span: Span,
        what: &'static str,
        found: String,
    },
    #[error("`{found}` is not a number")]
    BadNumber { span: Span, found: String },
    /// A number written with an exponent (`5e-2`), which the language
    /// does not read.
    #[error("`{written}` is written with an exponent")]
    Exponent {
        span: Span,
        written: String,
        /// The number without one (`0.05`); `None` when that is no
        /// number a cell could use (`1e400`, `1e308`, `1e-400`).
        plain: Option<String>,
    },
    #[error("this `{{` is never closed")]
    Unclosed { span: Span },
    /// So many syntax errors that the rest of the file is not read
    /// ([`MAX_SYNTAX_ERRORS`]): not a text worth reading line by line.
    #[error("too many syntax errors: the file is not read past here")]
    TooMany { span: Span },
}

/// The syntax errors a file's parse collects before it stops
/// ([`SyntaxError::TooMany`]).
pub const MAX_SYNTAX_ERRORS: usize = 1000;

/// A bare length longer than this is taken for a forgotten unit.
pub const MAX_BARE_METRES: f64 = 3.0;

impl SyntaxError {
    pub fn span(&self) -> Span {
        match self {
            SyntaxError::Unexpected { span, .. }
            | SyntaxError::UnknownUnit { span, .. }
            | SyntaxError::MissingUnit { span, .. }
            | SyntaxError::UnexpectedUnit { span, .. }
            | SyntaxError::NotWholeNumber { span, .. }
            | SyntaxError::WholeNumberTooLarge { span, .. }
            | SyntaxError::BadNumber { span, .. }
            | SyntaxError::Exponent { span, .. }
            | SyntaxError::Unclosed { span }
            | SyntaxError::TooMany { span } => *span,
        }
    }

    /// A stable code, documented in the README.
    pub fn code(&self) -> &'static str {
        match self {
            SyntaxError::Unexpected { .. } => "E001",
            SyntaxError::UnknownUnit { .. } => "E002",
            SyntaxError::MissingUnit { .. } => "E003",
            SyntaxError::UnexpectedUnit { .. } => "E004",
            SyntaxError::NotWholeNumber { .. } | SyntaxError::WholeNumberTooLarge { .. } => "E005",
            SyntaxError::BadNumber { .. } | SyntaxError::Exponent { .. } => "E006",
            SyntaxError::Unclosed { .. } => "E007",
            SyntaxError::TooMany { .. } => "E001",
        }
    }

    /// The short text under the caret.
    pub fn label(&self) -> String {
        match self {
            SyntaxError::Unexpected { expected, .. } => format!("expected {expected} here"),
            SyntaxError::UnknownUnit { .. } => "not a unit".into(),
            SyntaxError::MissingUnit { .. } => "no unit".into(),
            SyntaxError::UnexpectedUnit { .. } => "unit not allowed here".into(),
            SyntaxError::NotWholeNumber { .. } => "not a whole number".into(),
            SyntaxError::WholeNumberTooLarge { .. } => "too large".into(),
            SyntaxError::BadNumber { .. } => "not a number".into(),
            SyntaxError::Exponent { .. } => "an exponent".into(),
            SyntaxError::Unclosed { .. } => "opened here".into(),
            SyntaxError::TooMany { .. } => "stopped here".into(),
        }
    }

    /// How to fix it.
    pub fn help(&self) -> Option<String> {
        match self {
            SyntaxError::Unexpected {
                suggestion: Some(s),
                ..
            } => Some(format!("did you mean `{s}`?")),
            SyntaxError::Unexpected {
                expected, found, ..
            } if expected == "`to`" && found.starts_with("`-") => Some(
                "a range is written with `to`, as in `human packs 1 to 2` (`-2` reads as minus two)"
                    .into(),
            ),
            SyntaxError::Unexpected {
                expected, found, ..
            } if found == "end of file" && expected == "`{`" => Some(
                "the file ends before the block opens: add `{`, the block's statements, and `}`"
                    .into(),
            ),
            SyntaxError::Unexpected { found, .. } if found == "end of file" => Some(
                "the file ends in the middle of a statement or block; close every `{` with `}`"
                    .into(),
            ),
            SyntaxError::Unexpected {
                invisible: true, ..
            } => Some(
                "delete it: an invisible character, often pasted in with the text, is part of no statement"
                    .into(),
            ),
            // A name written with a letter outside ASCII (`bänch`, `苹果`):
            // the name stops before it.
            SyntaxError::Unexpected { found, .. } if non_ascii_letter(found).is_some() => {
                let c = non_ascii_letter(found).unwrap_or('?');
                Some(format!(
                    "names are written with ASCII letters, digits and `_` only (`bench_2`, `apple`): `{c}` is not one of them"
                ))
            }
            // A turn written on a box or a product (`yaw 30 deg`): the
            // help's form alone would silently drop it.
            SyntaxError::Unexpected {
                found,
                context,
                statement,
                ..
            } if is_turn(found) => Some(format!(
                "the language has no yaw: boxes and products stand square to the cell's x and y axes (slots may stand anywhere in their box); {}",
                context.help(statement.as_deref())
            )),
            SyntaxError::Unexpected {
                context, statement, ..
            } => Some(context.help(statement.as_deref())),
            SyntaxError::UnknownUnit { allowed, .. } => Some(format!("write one of {allowed}")),
            SyntaxError::MissingUnit { number, .. } => Some(format!(
                "a bare number is metres; write `{number} mm` or `{number} cm`, or `{number} m` if you really mean metres"
            )),
            SyntaxError::UnexpectedUnit { .. } => Some("remove the unit".into()),
            SyntaxError::NotWholeNumber { .. } => Some("write a whole number such as `3`".into()),
            SyntaxError::WholeNumberTooLarge { .. } => Some("write a smaller number".into()),
            SyntaxError::BadNumber { .. } => Some("write a number such as `0.25` or `-12`".into()),
            SyntaxError::Exponent {
                plain: Some(plain), ..
            } => Some(format!(
                "write `{plain}`: numbers are written without an exponent"
            )),
            SyntaxError::Exponent { plain: None, .. } => Some(
                "numbers are written without an exponent, and this one is far beyond any length, mass or time a cell uses: check it".into(),
            ),
            SyntaxError::Unclosed { .. } => {
                Some("close the block with `}` after its last statement".into())
            }
            SyntaxError::TooMany { .. } => Some(format!(
                "is this a `.pack` file? fix the first errors and check again (a parse stops after {MAX_SYNTAX_ERRORS})"
            )),
        }
    }
}

/// Whether a found text (`` `yaw` ``) is a word for a turn about the
/// vertical, which the language does not have.
fn is_turn(found: &str) -> bool {
    const TURNS: [&str; 8] = [
        "yaw",
        "rotated",
        "rotate",
        "rotation",
        "angle",
        "turned",
        "heading",
        "orientation",
    ];
    found
        .strip_prefix('`')
        .and_then(|w| w.strip_suffix('`'))
        .is_some_and(|w| TURNS.iter().any(|t| t.eq_ignore_ascii_case(w)))
}

/// The letter outside ASCII that a found text (`` `änch` ``) starts with.
fn non_ascii_letter(found: &str) -> Option<char> {
    let c = found.strip_prefix('`')?.chars().next()?;
    (c.is_alphabetic() && !c.is_ascii()).then_some(c)
}
