//! The unit disc `x² + y² ≤ 1` with area measure, binned by a Cartesian grid clipped to the disc.

use super::{Axis, Binning, Edge, Grid, Patch, Point2};
use crate::error::StatsError;

/// Slack on `x² + y² ≤ 1` for points produced by samplers (rounding of `r cos φ`, `r sin φ`).
const RADIUS_SLACK: f64 = 1e-12;

/// `n × n` (or `nx × ny`) grid over `[−1, 1]²` with cells clipped exactly to the unit disc.
///
/// Parameters are `(u, v) = (x, y)`, the measure is area (`J = 1`). Cells straddling the circle
/// are split into patches bounded by circle arcs, integrated without approximation of the
/// boundary; cells outside the disc have zero mass.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscBinning {
    grid: Grid,
}

impl DiscBinning {
    /// `nx × ny` grid over `[−1, 1]²`.
    ///
    /// # Errors
    /// [`StatsError::InvalidBinning`] when a count is zero.
    pub fn new(nx: usize, ny: usize) -> Result<Self, StatsError> {
        Ok(Self {
            grid: Grid::new([-1.0, 1.0], [-1.0, 1.0], nx, ny)?,
        })
    }
}

impl Binning for DiscBinning {
    type Point = Point2;

    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn param_of(&self, p: &Point2) -> Option<[f64; 2]> {
        let r2 = p[0] * p[0] + p[1] * p[1];
        (r2 <= 1.0 + RADIUS_SLACK).then(|| [p[0].clamp(-1.0, 1.0), p[1].clamp(-1.0, 1.0)])
    }

    fn point_at(&self, uv: [f64; 2]) -> Point2 {
        uv
    }

    fn jacobian(&self, _uv: [f64; 2]) -> f64 {
        1.0
    }

    fn clip(&self, u: [f64; 2], v: [f64; 2]) -> Vec<Patch> {
        clip_to_disc(u, v)
    }

    /// The chord `[−√(1 − t²), √(1 − t²)]` (the disc is symmetric, so both axes agree).
    fn section(&self, _axis: Axis, t: f64) -> Vec<[f64; 2]> {
        if t.abs() < 1.0 {
            let c = (1.0 - t * t).sqrt();
            vec![[-c, c]]
        } else {
            Vec::new()
        }
    }
}

/// `{x ∈ u, y ∈ v, x² + y² ≤ 1}` as patches whose edges are constants or circle arcs.
///
/// The `x` range is cut where a horizontal side `y = c` meets the circle (`x = ±√(1 − c²)`);
/// between cuts, each edge is either the side or the arc throughout (at a tangency, `|c| = 1`,
/// the arc is the binding edge).
pub(crate) fn clip_to_disc(u: [f64; 2], v: [f64; 2]) -> Vec<Patch> {
    let a = u[0].max(-1.0);
    let b = u[1].min(1.0);
    if !(a < b && v[0] < v[1]) {
        return Vec::new();
    }
    let mut cuts = vec![a, b];
    for y in v {
        if y.abs() < 1.0 {
            let x = (1.0 - y * y).sqrt();
            for c in [-x, x] {
                if c > a && c < b {
                    cuts.push(c);
                }
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let mut patches = Vec::new();
    for w in cuts.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        let xm = 0.5 * (x0 + x1);
        let c = (1.0 - xm * xm).max(0.0).sqrt();
        let lo = if v[0] > -c {
            Edge::Const(v[0])
        } else {
            Edge::CircleLower
        };
        let hi = if v[1] < c {
            Edge::Const(v[1])
        } else {
            Edge::CircleUpper
        };
        if lo.at(xm) < hi.at(xm) {
            patches.push(Patch {
                u: [x0, x1],
                lo,
                hi,
            });
        }
    }
    patches
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ √(1 − x²) dx`.
    fn arc_antiderivative(x: f64) -> f64 {
        0.5 * (x * (1.0 - x * x).sqrt() + x.asin())
    }

    fn patch_area(p: &Patch) -> f64 {
        // Edges are constants or ±√(1 − x²): integrate each analytically.
        let int = |e: &Edge| match *e {
            Edge::Const(c) => c * (p.u[1] - p.u[0]),
            Edge::CircleUpper => arc_antiderivative(p.u[1]) - arc_antiderivative(p.u[0]),
            Edge::CircleLower => -(arc_antiderivative(p.u[1]) - arc_antiderivative(p.u[0])),
        };
        int(&p.hi) - int(&p.lo)
    }

    #[test]
    fn clipped_cells_tile_the_disc() {
        for n in [1usize, 2, 3, 7, 10] {
            let b = DiscBinning::new(n, n).unwrap();
            let total: f64 = (0..b.n_bins())
                .flat_map(|i| b.bin_patches(i))
                .map(|p| patch_area(&p))
                .sum();
            assert!(
                (total - std::f64::consts::PI).abs() < 1e-12,
                "n={n}: {total}"
            );
        }
    }

    #[test]
    fn points_land_in_the_patch_of_their_bin() {
        let b = DiscBinning::new(9, 9).unwrap();
        for i in 0..b.n_bins() {
            for p in b.bin_patches(i) {
                let x = 0.5 * (p.u[0] + p.u[1]);
                let y = 0.5 * (p.lo.at(x) + p.hi.at(x));
                assert_eq!(b.bin_of(&[x, y]), Some(i));
            }
        }
        assert_eq!(b.bin_of(&[0.8, 0.8]), None);
    }
}
