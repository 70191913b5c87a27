//! The fine grid of one outgoing slice: cell values of `g = f_r · cos θi` over
//! `(z = cos θi, φi) ∈ [0,1] × [0, 2π)`, supersampled, with a defensive floor.

use std::f64::consts::TAU;

use brdf::{Brdf, Vec3};

/// The fine grid of every slice: `n_z × n_φ` equal cells over `[0,1] × [0, 2π)`.
///
/// Row `a` covers `z ∈ [a Δz, (a+1) Δz)`, column `b` covers `φ ∈ [b Δφ, (b+1) Δφ)`, with
/// `Δz = 1/n_z` and `Δφ = 2π/n_φ`. Because `dz dφ = dω` (solid angle), a density that is
/// piecewise constant in `(z, φ)` is directly a solid-angle density.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GridShape {
    /// Cells along `z = cos θi`.
    pub n_z: usize,
    /// Cells along `φi`.
    pub n_phi: usize,
}

impl GridShape {
    /// Number of cells `n_z · n_φ`.
    pub fn cells(&self) -> usize {
        self.n_z * self.n_phi
    }

    /// Points of the uncompressed cascade: the marginal's `n_z + 1` plus `n_z` conditionals
    /// of `n_φ + 1` each.
    pub fn cdf_points(&self) -> usize {
        self.n_z + 1 + self.n_z * (self.n_phi + 1)
    }

    /// `z` of grid coordinate `t ∈ [0, n_z]`.
    #[inline]
    pub(crate) fn z_of(&self, t: f64) -> f64 {
        t / self.n_z as f64
    }

    /// Grid coordinate `t ∈ [0, n_z]` of `z`.
    #[inline]
    pub(crate) fn t_of_z(&self, z: f64) -> f64 {
        z * self.n_z as f64
    }

    /// `φ` of grid coordinate `s ∈ [0, n_φ]`.
    #[inline]
    pub(crate) fn phi_of(&self, s: f64) -> f64 {
        s * (TAU / self.n_phi as f64)
    }

    /// Grid coordinate `s ∈ [0, n_φ]` of `φ`.
    #[inline]
    pub(crate) fn s_of_phi(&self, phi: f64) -> f64 {
        phi * (self.n_phi as f64 / TAU)
    }

    /// Row of `z` (clamped to the grid).
    #[inline]
    pub(crate) fn row_of(&self, z: f64) -> usize {
        (self.t_of_z(z).max(0.0) as usize).min(self.n_z - 1)
    }
}

/// Cell values of `g(ωi) = f_r(ωo, ωi) · cos θi` on `shape`, row-major (`n_φ` values per row).
///
/// Each cell is the mean of `ss²` evaluations at the centres of an `ss × ss` sub-grid (a
/// midpoint estimate of the cell's mean value); negative or non-finite BRDF values count as 0.
/// Then the **defensive floor** `floor · mean` (mean over all cells) is added to every cell, so
/// that every cell has positive mass: a narrow peak the sub-grid missed costs variance, never
/// bias (baselines.md §B.5). A slice whose values are all 0 becomes uniform.
///
/// Returns the values and the number of BRDF evaluations spent.
pub(crate) fn slice_values(
    brdf: &dyn Brdf,
    wo: &Vec3,
    shape: GridShape,
    ss: usize,
    floor: f64,
) -> (Vec<f64>, u64) {
    let n_phi = shape.n_phi;
    let sub = |i: usize, k: usize| (i * ss + k) as f64 + 0.5;
    let inv_ss = 1.0 / ss as f64;
    // Azimuths of every sub-column (n_φ · ss), as (cos, sin).
    let azimuths: Vec<(f64, f64)> = (0..n_phi * ss)
        .map(|j| {
            let phi = shape.phi_of(sub(0, j) * inv_ss);
            let (s, c) = phi.sin_cos();
            (c, s)
        })
        .collect();
    let mut values = vec![0.0; shape.cells()];
    let mut row_acc = vec![0.0; n_phi];
    for (a, row) in values.chunks_exact_mut(n_phi).enumerate() {
        row_acc.iter_mut().for_each(|v| *v = 0.0);
        for k in 0..ss {
            let z = shape.z_of(sub(a, k) * inv_ss);
            let r = (1.0 - z * z).max(0.0).sqrt();
            for (b, acc) in row_acc.iter_mut().enumerate() {
                let mut sum = 0.0;
                for &(c, s) in &azimuths[b * ss..(b + 1) * ss] {
                    let wi = Vec3::new(r * c, r * s, z);
                    let f = brdf.eval(wo, &wi);
                    if f.is_finite() && f > 0.0 {
                        sum += f;
                    }
                }
                *acc += sum * z;
            }
        }
        let scale = inv_ss * inv_ss;
        for (v, acc) in row.iter_mut().zip(&row_acc) {
            *v = acc * scale;
        }
    }
    let evaluations = (shape.cells() * ss * ss) as u64;
    let mean = values.iter().sum::<f64>() / shape.cells() as f64;
    if mean.is_finite() && mean > 0.0 {
        let add = floor * mean;
        values.iter_mut().for_each(|v| *v += add);
    } else {
        values.iter_mut().for_each(|v| *v = 1.0);
    }
    (values, evaluations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::parse_spec;

    #[test]
    fn lambert_cells_are_the_cell_mean_of_cos_and_floor_is_added() {
        // g = (ρ/π) z: the midpoint mean over a cell is exact for a linear function.
        let brdf = parse_spec("lambert:rho=1").unwrap();
        let shape = GridShape { n_z: 4, n_phi: 3 };
        let wo = Vec3::new(0.0, 0.0, 1.0);
        let floor = 1e-3;
        let (v, evals) = slice_values(brdf.as_ref(), &wo, shape, 2, floor);
        assert_eq!(evals, 4 * 3 * 4);
        // Mean over all cells of (1/π) z is 1/(2π).
        let add = floor / (2.0 * std::f64::consts::PI);
        for a in 0..4 {
            let expected = (a as f64 + 0.5) / 4.0 / std::f64::consts::PI + add;
            for b in 0..3 {
                approx::assert_relative_eq!(v[a * 3 + b], expected, max_relative = 1e-12);
            }
        }
    }

    #[test]
    fn an_all_zero_slice_becomes_uniform() {
        let brdf = parse_spec("lambert:rho=0").unwrap();
        let shape = GridShape { n_z: 2, n_phi: 2 };
        let (v, _) = slice_values(brdf.as_ref(), &Vec3::new(0.0, 0.0, 1.0), shape, 1, 1e-4);
        assert_eq!(v, vec![1.0; 4]);
    }
}
