//! The parameters of curvature-driven refinement ([`Refinement`]), read by the fill
//! (`fill.rs`) and validated by [`super::SampledGridDensity`]'s constructor.

/// Default coarsest resolution of [`Refinement`].
pub const DEFAULT_REFINEMENT_COARSEST: usize = 32;

/// Default tolerance of [`Refinement`]: a block is kept coarse when its estimated excess over
/// the interpolated maximum is at most 3 % of its largest value.
pub const DEFAULT_REFINEMENT_TOLERANCE: f64 = 0.03;

/// Curvature-driven refinement of the image map (see [`super::GridOptions::refinement`]).
///
/// Blocks of fine cells at resolution `coarsest` are judged on a 3 × 3 stencil of point
/// values (spacing `d` = half the block). With `Δx`, `Δy` the largest second differences
/// along rows and columns, a quadratic exceeds its bilinear interpolant on a stencil square by
/// at most `e = (|Δx| + |Δy|)/8`. A block inside the domain with `e ≤ tolerance · max` keeps
/// its 9 values: its fine cells get `max(bilinear at the cell's corners) + e` as maximum and
/// their share (by the interpolant at their centres) of the block's 2-D Simpson integral.
/// Any other block, and every block crossing the disc boundary, is split in four and judged
/// again, down to single fine cells, which use the dense rule. Smooth regions therefore cost
/// 9 evaluations per block instead of `2 s²`; sharp lobes are resolved as densely as before.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Refinement {
    /// Resolution of the coarsest blocks (a power of two `≥ 2`; clamped to the grid's `n`).
    pub coarsest: usize,
    /// Largest accepted excess `e / max` of a block kept coarse (finite, `≥ 0`).
    pub tolerance: f64,
}

impl Default for Refinement {
    fn default() -> Self {
        Self {
            coarsest: DEFAULT_REFINEMENT_COARSEST,
            tolerance: DEFAULT_REFINEMENT_TOLERANCE,
        }
    }
}
