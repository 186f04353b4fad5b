//! Errors of the contour-parallel toolpath piece.

/// Everything that can go wrong when planning, verifying or posting a 2.5D tool-centre path.
///
/// Every variant names the input (`part`, `stock`, `path`, an option) and what is wrong with it,
/// so a caller can show the message as is.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ContourError {
    /// A numeric option is out of its documented range.
    #[error("option `{name}` = {value} is invalid: {reason}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// An input shape has no contours at all.
    #[error("{what}: the shape has no contours")]
    EmptyShape { what: &'static str },
    /// A contour of an input shape is unusable.
    #[error("{what}: contour {index} {reason}")]
    BadContour {
        what: &'static str,
        index: usize,
        reason: String,
    },
    /// A tool-centre path violates its own invariants (links not joining consecutive passes, …).
    #[error("path: {0}")]
    BadPath(String),
    /// The offset engine (cavalier_contours) failed on this input.
    #[error("{what}: offsetting by {distance} mm failed inside cavalier_contours")]
    OffsetFailed { what: &'static str, distance: f64 },
    /// The offset loop did not terminate within the level budget.
    #[error(
        "contour-parallel: stopped after {levels} offset levels (limit); the stock is farther \
         than {reached} mm from the part"
    )]
    TooManyLevels { levels: usize, reached: f64 },
}

/// Result alias of this piece.
pub type Result<T> = std::result::Result<T, ContourError>;

/// `Ok` when `value` is a positive finite number, else the [`ContourError::InvalidOption`]
/// naming option `name` with `reason`.
pub(crate) fn require_positive(name: &'static str, value: f64, reason: &'static str) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ContourError::InvalidOption {
            name,
            value,
            reason,
        })
    }
}
