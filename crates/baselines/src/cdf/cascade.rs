//! The cascade of Douglas–Peucker-compressed 1D CDFs of one slice (Lawrence et al. 2005,
//! baselines.md §B.3–B.4).

use super::douglas_peucker::douglas_peucker;
use super::grid::GridShape;
use super::linear::{density, draw_settled};
use super::tabulated::{TabulatedSlice, density_scale};
use super::{SliceCdf, SlicePoint};
use crate::CdfOptions;

/// The slice's marginal CDF over `z` and its `n_z` conditional CDFs over `φ` (one per **fine**
/// row), each simplified by [`douglas_peucker`] with tolerance `ε` and stored as its kept
/// points `(x_m, C_m)` (grid coordinate as `u32`, CDF value as `f64`).
///
/// Sampling inverts the piecewise-linear compressed marginal to get `z`, takes the fine row
/// `a(z)` containing it, and inverts that row's compressed conditional to get `φ`. The density
/// w.r.t. solid angle (`dz dφ = dω`) is the product of the two segment slopes,
/// `p(ωi) = p̃_z(z) · p̃_φ(φ | a(z))` (baselines.md §B.4): the samples follow the *compressed*
/// CDFs, and so does the pdf (never the uncompressed table's, §B.5). Compression cannot create
/// support holes: the fine CDFs are strictly increasing (every cell has positive mass, see
/// [`CdfOptions::floor`]), so every compressed segment has positive slope.
#[derive(Debug, Clone, PartialEq)]
pub struct CascadeSlice {
    marginal_xs: Vec<u32>,
    marginal_cs: Vec<f64>,
    /// Row `a`'s kept points are `xs[offsets[a]..offsets[a + 1]]` (and the same in `cs`).
    offsets: Vec<u32>,
    xs: Vec<u32>,
    cs: Vec<f64>,
}

impl CascadeSlice {
    /// Compresses every CDF of `fine` with tolerance `epsilon`.
    pub(crate) fn compress(fine: &TabulatedSlice, n_z: usize, epsilon: f64) -> Self {
        let marginal_xs = douglas_peucker(fine.marginal(), epsilon);
        let marginal_cs = marginal_xs
            .iter()
            .map(|&x| fine.marginal()[x as usize])
            .collect();
        let mut offsets = Vec::with_capacity(n_z + 1);
        let (mut xs, mut cs) = (Vec::new(), Vec::new());
        offsets.push(0);
        for a in 0..n_z {
            let row = fine.conditional(a);
            let kept = douglas_peucker(row, epsilon);
            cs.extend(kept.iter().map(|&x| row[x as usize]));
            xs.extend(kept);
            offsets.push(xs.len() as u32);
        }
        xs.shrink_to_fit();
        cs.shrink_to_fit();
        Self {
            marginal_xs,
            marginal_cs,
            offsets,
            xs,
            cs,
        }
    }

    /// The kept points `(x_m, C_m)` of the marginal (x in rows).
    pub fn marginal(&self) -> (&[u32], &[f64]) {
        (&self.marginal_xs, &self.marginal_cs)
    }

    /// The kept points of fine row `a`'s conditional (x in columns).
    #[inline]
    pub fn conditional(&self, a: usize) -> (&[u32], &[f64]) {
        let (lo, hi) = (self.offsets[a] as usize, self.offsets[a + 1] as usize);
        (&self.xs[lo..hi], &self.cs[lo..hi])
    }
}

impl SliceCdf for CascadeSlice {
    const COMPRESSED: bool = true;
    const NAME: &'static str = "cascade-cdf";

    fn build(values: &[f64], shape: GridShape, options: &CdfOptions) -> Self {
        let fine = TabulatedSlice::from_values(values, shape);
        Self::compress(&fine, shape.n_z, options.epsilon)
    }

    #[inline]
    fn sample(&self, shape: GridShape, u: [f64; 2]) -> SlicePoint {
        let (mxs, mcs) = self.marginal();
        let (z, dz) = draw_settled(mxs, mcs, u[0], |t| shape.z_of(t), |z| shape.t_of_z(z));
        let (xs, cs) = self.conditional(shape.row_of(z));
        let (phi, dp) = draw_settled(xs, cs, u[1], |s| shape.phi_of(s), |p| shape.s_of_phi(p));
        SlicePoint {
            z,
            phi,
            pdf: dz * dp * density_scale(shape),
        }
    }

    #[inline]
    fn pdf(&self, shape: GridShape, z: f64, phi: f64) -> f64 {
        let (mxs, mcs) = self.marginal();
        let (xs, cs) = self.conditional(shape.row_of(z));
        density(mxs, mcs, shape.t_of_z(z))
            * density(xs, cs, shape.s_of_phi(phi))
            * density_scale(shape)
    }

    /// The marginal's kept points are row edges, so the `z` density is constant on each fine
    /// row; the row's conditional is linear between its kept points.
    fn phi_edges(&self, shape: GridShape, row: usize) -> Vec<f64> {
        let (xs, _) = self.conditional(row);
        xs.iter().map(|&x| shape.phi_of(f64::from(x))).collect()
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + 12 * (self.marginal_xs.len() + self.xs.len())
            + 4 * self.offsets.len()
    }

    fn stored_points(&self) -> usize {
        self.marginal_xs.len() + self.xs.len()
    }
}
