//! The draw crate's one error type.

use thiserror::Error;

/// Why a picture or chart could not be drawn.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DrawError {
    /// An input number is NaN or infinite.
    #[error("{what} has a non-finite coordinate")]
    NonFinite { what: String },
    /// The picture, drawn at true scale, would be larger than
    /// [`MAX_SPAN`](crate::cell::MAX_SPAN) along an axis.
    #[error(
        "the picture would span {metres:.1e} m along {axis}, more than the {max} m drawn at true scale: a position or size in the cell is far out (its diagnostics say which)"
    )]
    TooLarge { axis: char, metres: f64, max: f64 },
    /// An assignment names a product or slot the picture does not hold.
    #[error("{what} refers to a product or slot that is not drawn")]
    BadIndex { what: String },
    /// plotters refused to draw a chart.
    #[error("chart `{chart}`: {reason}")]
    Chart { chart: &'static str, reason: String },
}
