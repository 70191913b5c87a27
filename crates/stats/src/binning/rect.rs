//! Rectangle (image) domain `[x₀, x₁] × [y₀, y₁]` with area measure.

use super::{Axis, Binning, Grid, Patch, Point2};
use crate::error::StatsError;

/// `n_x × n_y` grid over the rectangle `[x₀, x₁] × [y₀, y₁]`; parameters are `(u, v) = (x, y)`,
/// the measure is area (`J = 1`), and bins are in row-major order (`b = i_y · n_x + i_x`).
#[derive(Debug, Clone, PartialEq)]
pub struct RectBinning {
    grid: Grid,
}

impl RectBinning {
    /// Bins for the rectangle `x × y` with `nx × ny` cells.
    ///
    /// # Errors
    /// [`StatsError::InvalidBinning`] for empty grids or degenerate/non-finite ranges.
    pub fn new(x: [f64; 2], y: [f64; 2], nx: usize, ny: usize) -> Result<Self, StatsError> {
        Ok(Self {
            grid: Grid::new(x, y, nx, ny)?,
        })
    }

    /// Bins for the unit square `[0, 1]²`.
    ///
    /// # Errors
    /// [`StatsError::InvalidBinning`] when `nx` or `ny` is zero.
    pub fn unit_square(nx: usize, ny: usize) -> Result<Self, StatsError> {
        Self::new([0.0, 1.0], [0.0, 1.0], nx, ny)
    }
}

impl Binning for RectBinning {
    type Point = Point2;

    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn param_of(&self, p: &Point2) -> Option<[f64; 2]> {
        let (x, y) = (self.grid.u_range(), self.grid.v_range());
        (p[0] >= x[0] && p[0] <= x[1] && p[1] >= y[0] && p[1] <= y[1]).then_some(*p)
    }

    fn point_at(&self, uv: [f64; 2]) -> Point2 {
        uv
    }

    fn jacobian(&self, _uv: [f64; 2]) -> f64 {
        1.0
    }

    fn clip(&self, u: [f64; 2], v: [f64; 2]) -> Vec<Patch> {
        clip_rect(&self.grid, u, v)
    }

    fn section(&self, axis: Axis, t: f64) -> Vec<[f64; 2]> {
        section_rect(&self.grid, axis, t)
    }
}

/// The section of the grid's rectangle on the line `axis = t`.
pub(super) fn section_rect(grid: &Grid, axis: Axis, t: f64) -> Vec<[f64; 2]> {
    let (along, other) = match axis {
        Axis::U => (grid.u_range(), grid.v_range()),
        Axis::V => (grid.v_range(), grid.u_range()),
    };
    if t >= along[0] && t <= along[1] {
        vec![other]
    } else {
        Vec::new()
    }
}

/// Intersection of `u × v` with the grid's rectangle, as at most one patch.
pub(super) fn clip_rect(grid: &Grid, u: [f64; 2], v: [f64; 2]) -> Vec<Patch> {
    let (gu, gv) = (grid.u_range(), grid.v_range());
    let u = [u[0].max(gu[0]), u[1].min(gu[1])];
    let v = [v[0].max(gv[0]), v[1].min(gv[1])];
    if u[0] < u[1] && v[0] < v[1] {
        vec![Patch::rect(u, v)]
    } else {
        Vec::new()
    }
}
