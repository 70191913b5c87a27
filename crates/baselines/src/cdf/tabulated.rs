//! The uncompressed marginal/conditional piecewise-constant CDF of one slice (seed 000's
//! "uncompressed CDF", baselines.md §B.2).

use super::grid::GridShape;
use super::linear::{cell_of, draw_uniform, fill_cdf, settle};
use super::{SliceCdf, SlicePoint};
use crate::CdfOptions;

/// The marginal CDF over the `n_z` rows and one conditional CDF over the `n_φ` columns per
/// row, stored at the cell edges (`n_z + 1` and `n_z · (n_φ + 1)` values).
///
/// With cell values `g_ab`, row masses `M_a = Σ_b g_ab` (the common factor `Δz Δφ` cancels):
/// `C(z_a) = Σ_{a'<a} M_a' / Σ M`, `C_a(φ_b) = Σ_{b'<b} g_ab' / M_a`. The density is
/// piecewise constant, `p(z, φ) = (M_a / Σ M) / Δz · (g_ab / M_a) / Δφ = g_ab / (Σ g Δz Δφ)`,
/// which is a solid-angle density since `dz dφ = dω`.
///
/// Sampling starts each CDF search from a guide table ([`distributions::fill_guide`], one
/// `u32` per `GUIDE_CELLS` = 8 cells, +6 % of the table's memory) instead of a binary search
/// over the row: the same cell for every `u`, one or two cache lines read instead of ~9
/// dependent probes of a 4 KiB row.
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedSlice {
    marginal: Vec<f64>,
    conditional: Vec<f64>,
    marginal_guide: Vec<u32>,
    /// `guide_len(n_φ)` entries per row, concatenated.
    conditional_guide: Vec<u32>,
}

/// Cells per guide entry: a bucket of the guide spans about one cache line of CDF values.
const GUIDE_CELLS: usize = 8;

/// Guide entries for a CDF over `n` cells.
fn guide_len(n: usize) -> usize {
    n.div_ceil(GUIDE_CELLS).max(1)
}

impl TabulatedSlice {
    /// The CDFs of `values` (row-major `shape.n_z × shape.n_phi`, non-negative).
    pub(crate) fn from_values(values: &[f64], shape: GridShape) -> Self {
        let n_phi = shape.n_phi;
        let mut conditional = vec![0.0; shape.n_z * (n_phi + 1)];
        let row_sums: Vec<f64> = values
            .chunks_exact(n_phi)
            .zip(conditional.chunks_exact_mut(n_phi + 1))
            .map(|(row, cdf)| fill_cdf(row, cdf))
            .collect();
        let mut marginal = vec![0.0; shape.n_z + 1];
        fill_cdf(&row_sums, &mut marginal);
        let mut marginal_guide = vec![0; guide_len(shape.n_z)];
        distributions::fill_guide(&marginal, &mut marginal_guide);
        let g = guide_len(n_phi);
        let mut conditional_guide = vec![0; shape.n_z * g];
        for (cdf, guide) in conditional
            .chunks_exact(n_phi + 1)
            .zip(conditional_guide.chunks_exact_mut(g))
        {
            distributions::fill_guide(cdf, guide);
        }
        Self {
            marginal,
            conditional,
            marginal_guide,
            conditional_guide,
        }
    }

    /// The marginal CDF over rows at the `n_z + 1` row edges.
    pub fn marginal(&self) -> &[f64] {
        &self.marginal
    }

    /// The conditional CDF of row `a` at its `n_φ + 1` column edges.
    pub fn conditional(&self, a: usize) -> &[f64] {
        let w = self.conditional.len() / (self.marginal.len() - 1);
        &self.conditional[a * w..(a + 1) * w]
    }
}

impl SliceCdf for TabulatedSlice {
    const COMPRESSED: bool = false;
    const NAME: &'static str = "tabulated-cdf";

    fn build(values: &[f64], shape: GridShape, _options: &CdfOptions) -> Self {
        Self::from_values(values, shape)
    }

    #[inline]
    fn sample(&self, shape: GridShape, u: [f64; 2]) -> SlicePoint {
        let dz = draw_uniform(&self.marginal, &self.marginal_guide, u[0]);
        let a = dz.segment;
        let z = settle(
            dz.t,
            a,
            a as f64 + 0.5,
            |t| shape.z_of(t),
            |z| shape.row_of(z),
        );
        let cond = self.conditional(a);
        let g = guide_len(shape.n_phi);
        let dp = draw_uniform(cond, &self.conditional_guide[a * g..(a + 1) * g], u[1]);
        let b = dp.segment;
        let phi = settle(
            dp.t,
            b,
            b as f64 + 0.5,
            |s| shape.phi_of(s),
            |phi| cell_of(shape.s_of_phi(phi), shape.n_phi),
        );
        SlicePoint {
            z,
            phi,
            pdf: dz.slope * dp.slope * density_scale(shape),
        }
    }

    #[inline]
    fn pdf(&self, shape: GridShape, z: f64, phi: f64) -> f64 {
        let a = shape.row_of(z);
        let b = cell_of(shape.s_of_phi(phi), shape.n_phi);
        let cond = self.conditional(a);
        (self.marginal[a + 1] - self.marginal[a]) * (cond[b + 1] - cond[b]) * density_scale(shape)
    }

    fn phi_edges(&self, shape: GridShape, _row: usize) -> Vec<f64> {
        (0..=shape.n_phi).map(|b| shape.phi_of(b as f64)).collect()
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + 8 * (self.marginal.len() + self.conditional.len())
            + 4 * (self.marginal_guide.len() + self.conditional_guide.len())
    }

    fn stored_points(&self) -> usize {
        self.marginal.len() + self.conditional.len()
    }
}

/// `1 / (Δz Δφ) = n_z n_φ / (2π)`: turns the product of two grid-coordinate densities into a
/// density w.r.t. `dz dφ = dω`.
#[inline]
pub(crate) fn density_scale(shape: GridShape) -> f64 {
    shape.n_z as f64 * shape.n_phi as f64 / std::f64::consts::TAU
}
