//! The draw crate's one error type.

use thiserror::Error;

/// Why a picture or chart could not be drawn.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DrawError {
    /// An input number is NaN or infinite.
    #[error("{what} has a non-finite coordinate")]
    NonFinite { what: String },
    /// An assignment names a product or slot the picture does not hold.
    #[error("{what} refers to a product or slot that is not drawn")]
    BadIndex { what: String },
    /// plotters refused to draw a chart.
    #[error("chart `{chart}`: {reason}")]
    Chart { chart: &'static str, reason: String },
}
