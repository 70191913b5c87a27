//! Typed errors of the crate; each variant names the invariant that failed.

use crate::rect::Rect;

/// A density provider could not be constructed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DensityError {
    /// The grid has no cells.
    #[error("empty grid: {width} × {height}")]
    EmptyGrid {
        /// Requested width.
        width: usize,
        /// Requested height.
        height: usize,
    },
    /// `width · height` does not fit in memory indices (or is too large for 32-bit cell ids).
    #[error("grid too large: {width} × {height}")]
    GridTooLarge {
        /// Requested width.
        width: usize,
        /// Requested height.
        height: usize,
    },
    /// `values.len() != width · height`.
    #[error("expected {expected} values (width · height), got {got}")]
    LengthMismatch {
        /// `width · height`.
        expected: usize,
        /// `values.len()`.
        got: usize,
    },
    /// A value is NaN, negative or infinite.
    #[error("value {value} at column {column}, row {row} (index {index}) is not finite and ≥ 0")]
    InvalidValue {
        /// Row-major index of the first bad value.
        index: usize,
        /// Its column.
        column: usize,
        /// Its row (row 0 is the `y0` side).
        row: usize,
        /// The value.
        value: f64,
    },
    /// A density evaluated at a point returned NaN, a negative or an infinite value.
    #[error("f({x}, {y}) = {value} is not finite and ≥ 0")]
    InvalidSample {
        /// x of the point.
        x: f64,
        /// y of the point.
        y: f64,
        /// The value.
        value: f64,
    },
    /// The density integrates to zero (all values zero).
    #[error("the density is zero everywhere on its domain")]
    ZeroTotal,
    /// The domain rectangle is not finite with `x0 < x1`, `y0 < y1`.
    #[error("invalid domain rectangle {0:?}")]
    InvalidDomain(Rect),
    /// A row factor returned a non-finite or negative maximum or integral for a row.
    #[error("row factor gives an invalid {what} ({value}) on row {row}")]
    InvalidRowFactor {
        /// The row.
        row: usize,
        /// `"max"` or `"integral"`.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// The grid resolution of a sampled density is out of range.
    #[error("grid resolution {0} out of range (1 ..= 8192)")]
    InvalidResolution(usize),
    /// The safety factor must be finite and ≥ 1.
    #[error("safety factor {0} must be finite and ≥ 1")]
    InvalidSafetyFactor(f64),
    /// A refinement needs power-of-two `n` and `coarsest ≥ 2` and a finite tolerance `≥ 0`.
    #[error(
        "invalid grid refinement: resolution {n}, coarsest {coarsest}, tolerance {tolerance} (need powers of two, coarsest ≥ 2, and a finite tolerance ≥ 0)"
    )]
    InvalidRefinement {
        /// Grid resolution.
        n: usize,
        /// Requested coarsest resolution.
        coarsest: usize,
        /// Requested tolerance.
        tolerance: f64,
    },
    /// Mirroring needs an even resolution and a domain symmetric about `y = 0`.
    #[error(
        "mirror symmetry y ↦ −y needs an even resolution ({n}) and a domain symmetric about y = 0 ({domain:?})"
    )]
    InvalidMirror {
        /// Grid resolution.
        n: usize,
        /// The domain's bounding rectangle.
        domain: Rect,
    },
    /// The quadrature resolution must be even and in `2 ..= 1024`.
    #[error("quadrature resolution {0} must be even and in 2 ..= 1024")]
    InvalidQuadrature(usize),
}

/// The quadtree could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// `n_max` must be finite and ≥ 1.
    #[error("n_max = {0} must be finite and ≥ 1")]
    InvalidNMax(f64),
    /// `max_depth` exceeds the supported limit.
    #[error("max_depth = {0} exceeds the limit {max}", max = crate::limits::MAX_DEPTH_LIMIT)]
    MaxDepthTooLarge(u32),
    /// `min_leaf_size` must be finite and ≥ 0.
    #[error("min_leaf_size = {0} must be finite and ≥ 0")]
    InvalidMinLeafSize(f64),
    /// `volume_tolerance` must be finite and ≥ 0.
    #[error("volume_tolerance = {0} must be finite and ≥ 0")]
    InvalidVolumeTolerance(f64),
    /// The provider's domain is not a valid rectangle.
    #[error("invalid domain {0:?}")]
    InvalidDomain(crate::rect::Domain),
    /// The provider returned a NaN / negative / infinite bound or integral.
    #[error("invalid region estimate on {cell:?}: max_bound = {max_bound}, integral = {integral}")]
    InvalidRegionEstimate {
        /// The cell.
        cell: Rect,
        /// The returned bound.
        max_bound: f64,
        /// The returned integral.
        integral: f64,
    },
    /// No leaf can be sampled (all bounds or integrals are zero).
    #[error("the density has no mass the sampler can reach (all leaf weights are zero)")]
    ZeroMass,
    /// More nodes than 32-bit indices allow.
    #[error("the tree has too many nodes")]
    TooManyNodes,
    /// Replacement leaf integrals ([`crate::QuadTree::with_leaf_integrals`]) of the wrong
    /// length, not finite and `≥ 0`, or summing to zero.
    #[error("replacement leaf integrals: {0}")]
    InvalidLeafIntegrals(&'static str),
}

/// [`crate::allocate()`] was given invalid input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AllocationError {
    /// A probability (weight) is NaN, negative or infinite.
    #[error("weight {value} at index {index} is not finite and ≥ 0")]
    InvalidWeight {
        /// Index of the first bad weight.
        index: usize,
        /// The weight.
        value: f64,
    },
    /// `n > 0` but the weights sum to zero (or there are none).
    #[error("cannot allocate {n} samples: the weights sum to zero")]
    ZeroTotal {
        /// The requested count.
        n: usize,
    },
}

/// Stored bytes could not be decoded into a tree.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PersistError {
    /// Fewer bytes than the header or the payload needs.
    #[error("truncated input")]
    Truncated,
    /// The bytes do not start with the format's magic.
    #[error("not a partition-sampler tree (bad magic)")]
    BadMagic,
    /// The format version differs from [`crate::FORMAT_VERSION`].
    #[error("format version {found} is not supported (expected {expected})")]
    UnsupportedVersion {
        /// Version in the bytes.
        found: u32,
        /// Version this build reads.
        expected: u32,
    },
    /// The payload could not be decoded.
    #[error("decode error: {0}")]
    Decode(String),
    /// The payload decoded but violates a structural invariant.
    #[error("corrupt tree: {0}")]
    Corrupt(&'static str),
}

/// A stored tree does not fit the density it is attached to.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AttachError {
    /// The density's shape differs from the one the tree was built for.
    #[error("density shape {found:?} differs from the tree's {expected:?}")]
    ShapeMismatch {
        /// The tree's shape.
        expected: Box<crate::shape::DensityShape>,
        /// The density's shape.
        found: Box<crate::shape::DensityShape>,
    },
    /// The tree violates a structural invariant.
    #[error("corrupt tree: {0}")]
    Corrupt(&'static str),
}
