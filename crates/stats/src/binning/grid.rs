//! A uniform grid over a rectangle of the parameter plane.

use crate::error::StatsError;
use crate::quadrature::split;

/// Uniform `n_u × n_v` grid over `[u₀, u₁] × [v₀, v₁]`; cell `b = i_v · n_u + i_u`.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    u: [f64; 2],
    v: [f64; 2],
    nu: usize,
    nv: usize,
}

impl Grid {
    /// A grid with `nu × nv ≥ 1` cells over finite, non-degenerate ranges.
    ///
    /// # Errors
    /// [`StatsError::InvalidBinning`] for zero cells, a range with `u₀ ≥ u₁` or non-finite bounds.
    pub fn new(u: [f64; 2], v: [f64; 2], nu: usize, nv: usize) -> Result<Self, StatsError> {
        if nu == 0 || nv == 0 {
            return Err(StatsError::InvalidBinning(format!(
                "grid needs at least one cell per axis, got {nu} x {nv}"
            )));
        }
        if nu.checked_mul(nv).is_none() {
            return Err(StatsError::InvalidBinning("too many cells".into()));
        }
        for r in [u, v] {
            if !(r[0].is_finite() && r[1].is_finite() && r[0] < r[1]) {
                return Err(StatsError::InvalidBinning(format!(
                    "range [{}, {}] must be finite with lower < upper",
                    r[0], r[1]
                )));
            }
        }
        Ok(Self { u, v, nu, nv })
    }

    /// Range of `u`.
    pub fn u_range(&self) -> [f64; 2] {
        self.u
    }

    /// Range of `v`.
    pub fn v_range(&self) -> [f64; 2] {
        self.v
    }

    /// Range of the given axis.
    pub fn range(&self, axis: super::Axis) -> [f64; 2] {
        match axis {
            super::Axis::U => self.u,
            super::Axis::V => self.v,
        }
    }

    /// Number of cells along `u`.
    pub fn nu(&self) -> usize {
        self.nu
    }

    /// Number of cells along `v`.
    pub fn nv(&self) -> usize {
        self.nv
    }

    /// Total number of cells.
    pub fn n_cells(&self) -> usize {
        self.nu * self.nv
    }

    /// The cell containing `(u, v)` (closed ranges; the upper boundary belongs to the last cell),
    /// or `None` outside the grid or for NaN.
    pub fn index_of(&self, uv: [f64; 2]) -> Option<usize> {
        let iu = axis_index(uv[0], self.u, self.nu)?;
        let iv = axis_index(uv[1], self.v, self.nv)?;
        Some(iv * self.nu + iu)
    }

    /// The `u` and `v` ranges of cell `b`, or `None` when `b` is out of range.
    pub fn cell(&self, b: usize) -> Option<([f64; 2], [f64; 2])> {
        if b >= self.n_cells() {
            return None;
        }
        let (iu, iv) = (b % self.nu, b / self.nu);
        Some((split(self.u, self.nu, iu), split(self.v, self.nv, iv)))
    }
}

fn axis_index(x: f64, r: [f64; 2], n: usize) -> Option<usize> {
    if !(x >= r[0] && x <= r[1]) {
        return None;
    }
    let t = (x - r[0]) / (r[1] - r[0]) * n as f64;
    Some((t as usize).min(n - 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_and_cell_agree() {
        let g = Grid::new([0.0, 1.0], [-1.0, 3.0], 7, 5).unwrap();
        for b in 0..g.n_cells() {
            let (u, v) = g.cell(b).unwrap();
            let mid = [0.5 * (u[0] + u[1]), 0.5 * (v[0] + v[1])];
            assert_eq!(g.index_of(mid), Some(b));
        }
        assert_eq!(g.index_of([1.0, 3.0]), Some(g.n_cells() - 1));
        assert_eq!(g.index_of([1.0 + 1e-12, 0.0]), None);
        assert_eq!(g.index_of([f64::NAN, 0.0]), None);
        assert!(g.cell(g.n_cells()).is_none());
    }

    #[test]
    fn rejects_bad_grids() {
        assert!(Grid::new([0.0, 1.0], [0.0, 1.0], 0, 3).is_err());
        assert!(Grid::new([1.0, 1.0], [0.0, 1.0], 2, 3).is_err());
        assert!(Grid::new([0.0, f64::NAN], [0.0, 1.0], 2, 3).is_err());
    }
}
