//! Errors of the piecewise-constant CDF samplers.

use thiserror::Error;

/// Why a piecewise-constant table could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PiecewiseConstantError {
    /// The grid has no cell (`width == 0` or `height == 0`).
    #[error("empty table: {width}×{height} cells")]
    Empty {
        /// Number of columns requested.
        width: usize,
        /// Number of rows requested.
        height: usize,
    },
    /// `values.len()` differs from `width · height`.
    #[error("size mismatch: expected {expected} values ({width}×{height}), got {got}")]
    SizeMismatch {
        /// Number of columns.
        width: usize,
        /// Number of rows.
        height: usize,
        /// `width · height` (saturated).
        expected: usize,
        /// Length of the given vector.
        got: usize,
    },
    /// A cell holds NaN or ±∞.
    #[error("value {value} of cell (column {column}, row {row}) is not finite")]
    NonFinite {
        /// Column of the cell (0 = first).
        column: usize,
        /// Row of the cell (0 = first, at the domain's `y0`).
        row: usize,
        /// The offending value.
        value: f64,
    },
    /// A cell holds a negative value.
    #[error("value {value} of cell (column {column}, row {row}) is negative")]
    Negative {
        /// Column of the cell.
        column: usize,
        /// Row of the cell.
        row: usize,
        /// The offending value.
        value: f64,
    },
    /// Every cell is zero: there is no density to normalise.
    #[error("every value is zero: the table has no mass")]
    AllZero,
    /// The sum of the values overflows to +∞.
    #[error("the sum of the values is not finite")]
    TotalNotFinite,
    /// The domain rectangle is degenerate or not finite (`!(x0 < x1 && y0 < y1)`).
    #[error("invalid domain [{x0}, {x1}]×[{y0}, {y1}]: need finite x0 < x1 and y0 < y1")]
    InvalidDomain {
        /// Lower x bound.
        x0: f64,
        /// Lower y bound.
        y0: f64,
        /// Upper x bound.
        x1: f64,
        /// Upper y bound.
        y1: f64,
    },
    /// A 1D table was given no value.
    #[error("empty 1D table: no cell")]
    EmptyInterval,
    /// A 1D table's interval is degenerate or not finite (`!(min < max)`).
    #[error("invalid interval [{min}, {max}]: need finite min < max")]
    InvalidInterval {
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// A value of a 1D table is NaN or ±∞.
    #[error("value {value} of cell {index} is not finite")]
    NonFiniteValue {
        /// Index of the cell (0 = first, at `min`).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A value of a 1D table is negative.
    #[error("value {value} of cell {index} is negative")]
    NegativeValue {
        /// Index of the cell.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A serialised table carries an unknown format version.
    #[error("unsupported format version {found} (this build reads version {expected})")]
    FormatVersion {
        /// Version found in the data.
        found: u32,
        /// Version this build writes and reads.
        expected: u32,
    },
}

/// The serialised tables' format version (1D and 2D alike: both store their inputs).
pub(crate) const FORMAT_VERSION: u32 = 1;

/// `Ok` when a serialised table's `version` is [`FORMAT_VERSION`].
pub(crate) fn check_version(version: u32) -> Result<(), PiecewiseConstantError> {
    if version == FORMAT_VERSION {
        Ok(())
    } else {
        Err(PiecewiseConstantError::FormatVersion {
            found: version,
            expected: FORMAT_VERSION,
        })
    }
}

/// A table's integral over its domain: `integral` when finite and positive, else
/// [`PiecewiseConstantError::TotalNotFinite`] (the cell sizes times the sum overflowed or
/// underflowed).
pub(super) fn finite_integral(integral: f64) -> Result<f64, PiecewiseConstantError> {
    if integral.is_finite() && integral > 0.0 {
        Ok(integral)
    } else {
        Err(PiecewiseConstantError::TotalNotFinite)
    }
}
