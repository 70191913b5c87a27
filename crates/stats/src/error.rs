//! The error type of the crate: every variant names the invariant the input broke.

use thiserror::Error;

/// Invalid input to a statistical routine.
///
/// A sampler that *fails* a test is not an error: it yields a result whose p-value is small
/// or whose `passed` flag is false. Errors are reserved for inputs that make a test
/// meaningless (mismatched lengths, negative expected counts, empty samples, bad options).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum StatsError {
    /// `observed` and `expected` must have one entry per cell.
    #[error("observed has {observed} cells but expected has {expected}")]
    LengthMismatch {
        /// Number of observed cells.
        observed: usize,
        /// Number of expected cells.
        expected: usize,
    },
    /// Expected counts must be finite and non-negative.
    #[error("expected count of cell {index} is {value}; it must be finite and >= 0")]
    InvalidExpected {
        /// Index of the offending cell.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The pooling threshold must be finite and > 0.
    #[error("min_expected must be finite and > 0, got {0}")]
    InvalidMinExpected(f64),
    /// A goodness-of-fit test needs at least two cells (one degree of freedom) after pooling.
    #[error("only {cells} cell(s) with positive expected count remain after pooling; need >= 2")]
    TooFewCells {
        /// Number of cells left.
        cells: usize,
    },
    /// The test needs more samples than it was given.
    #[error("need at least {needed} samples, got {got}")]
    TooFewSamples {
        /// Minimum number of samples.
        needed: usize,
        /// Number given.
        got: usize,
    },
    /// A sample value (or a value derived from it) is NaN or infinite.
    #[error("sample {index} is not finite")]
    NonFiniteSample {
        /// Index of the offending sample.
        index: usize,
    },
    /// A cumulative distribution function returned a value outside `[0, 1]` or NaN.
    #[error("the CDF returned {value} at x = {x}; it must lie in [0, 1]")]
    InvalidCdfValue {
        /// Argument.
        x: f64,
        /// Returned value.
        value: f64,
    },
    /// A tabulated CDF must have strictly increasing knots and non-decreasing values.
    #[error("tabulated CDF is not monotone at knot {index}")]
    NonMonotoneCdf {
        /// Index of the first knot that breaks monotonicity.
        index: usize,
    },
    /// A density integrated to a negative, zero or non-finite mass where a positive one is needed.
    #[error("the density has mass {mass} over the domain; it must be finite and > 0")]
    InvalidMass {
        /// The integrated mass.
        mass: f64,
    },
    /// A significance level must lie in `(0, 1)`.
    #[error("significance level must lie in (0, 1), got {0}")]
    InvalidAlpha(f64),
    /// A tolerance must be finite and > 0.
    #[error("tolerance must be finite and > 0, got {0}")]
    InvalidTolerance(f64),
    /// A binning's geometry is invalid (empty grid, degenerate or non-finite range).
    #[error("invalid binning: {0}")]
    InvalidBinning(String),
    /// Quadrature options are out of range.
    #[error("invalid quadrature options: {0}")]
    InvalidQuadrature(String),
}
