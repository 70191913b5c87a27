//! Directions on the sphere or the upper hemisphere, binned in `(cos θ, φ)`.

use super::{Axis, Binning, Direction, Grid, Patch};
use crate::error::StatsError;
use std::f64::consts::TAU;

/// Directions with `z ≥ −1e-12 |d|` count as on the horizon (rounding of rotated directions).
const HORIZON_SLACK: f64 = 1e-12;

/// Equal-solid-angle bins of the sphere (`cos θ ∈ [−1, 1]`) or upper hemisphere
/// (`cos θ ∈ [0, 1]`, `z ≥ 0`), with parameters `(u, v) = (cos θ, φ)`, `φ ∈ [0, 2π)`.
///
/// Solid angle is `dω = d(cos θ) dφ`, so `J = 1` and uniform grid cells have equal solid angle;
/// pdfs are with respect to solid angle. A direction is `(sin θ cos φ, sin θ sin φ, cos θ)`;
/// inputs need not be exactly unit length (they are normalised before binning).
#[derive(Debug, Clone, PartialEq)]
pub struct SphereBinning {
    grid: Grid,
}

impl SphereBinning {
    /// Upper hemisphere `z ≥ 0` with `n_cos × n_phi` bins (10 × 20 or finer is typical).
    /// Directions with `z` below `−1e-12 |d|` are outside the domain.
    ///
    /// # Errors
    /// [`StatsError::InvalidBinning`] when a count is zero.
    pub fn hemisphere(n_cos: usize, n_phi: usize) -> Result<Self, StatsError> {
        Ok(Self {
            grid: Grid::new([0.0, 1.0], [0.0, TAU], n_cos, n_phi)?,
        })
    }

    /// Whole sphere with `n_cos × n_phi` bins.
    ///
    /// # Errors
    /// [`StatsError::InvalidBinning`] when a count is zero.
    pub fn sphere(n_cos: usize, n_phi: usize) -> Result<Self, StatsError> {
        Ok(Self {
            grid: Grid::new([-1.0, 1.0], [0.0, TAU], n_cos, n_phi)?,
        })
    }

    /// Whether this is the hemisphere variant.
    pub fn is_hemisphere(&self) -> bool {
        self.grid.u_range()[0] == 0.0
    }
}

impl Binning for SphereBinning {
    type Point = Direction;

    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn param_of(&self, d: &Direction) -> Option<[f64; 2]> {
        let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return None;
        }
        if self.is_hemisphere() && d[2] < -HORIZON_SLACK * norm {
            return None;
        }
        let u = (d[2] / norm).clamp(-1.0, 1.0);
        let mut phi = d[1].atan2(d[0]);
        if phi < 0.0 {
            phi += TAU;
        }
        Some([u.max(self.grid.u_range()[0]), phi.min(TAU)])
    }

    fn point_at(&self, uv: [f64; 2]) -> Direction {
        let s = (1.0 - uv[0] * uv[0]).max(0.0).sqrt();
        let (sp, cp) = uv[1].sin_cos();
        [s * cp, s * sp, uv[0]]
    }

    fn jacobian(&self, _uv: [f64; 2]) -> f64 {
        1.0
    }

    fn clip(&self, u: [f64; 2], v: [f64; 2]) -> Vec<Patch> {
        super::rect::clip_rect(&self.grid, u, v)
    }

    fn section(&self, axis: Axis, t: f64) -> Vec<[f64; 2]> {
        super::rect::section_rect(&self.grid, axis, t)
    }
}
