//! The `.pack` language: grammar, typed AST with byte spans, syntax
//! diagnostics and the canonical formatter. This crate does no IO: it turns
//! text into trees and trees back into text.

pub mod ast;
mod error;
mod format;
mod parser;
mod place;
mod span;
mod suggest;
mod visible;

pub use error::{MAX_BARE_METRES, SyntaxError};
pub use format::{format, format_file};
pub use parser::parse;
pub use place::Place;
pub use span::{LineIndex, Span};
pub use suggest::{closest, edit_distance};
pub use visible::{is_invisible, named, shown};
