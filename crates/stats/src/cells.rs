//! Densities that are constant on known cells of the parameter plane, integrated exactly.
//!
//! Adaptive quadrature of a density with thousands of jumps refines at every jump (a tabulated
//! CDF's pdf jumps at each of its cell edges). When the jumps are known, no quadrature is
//! needed: a [`PiecewiseConstant`] density is constant on each cell of a *row layout* — rows
//! `[u₀, u₁)` of the parameter `u`, each cut along `v` at its own edges — so its mass over a
//! grid cell, and its projection CDF onto either axis, are sums of exact overlap-area products.
//! Densities are with respect to `du dv` (= solid angle for [`crate::SphereBinning`], area for
//! [`crate::RectBinning`], whose bins are grid cells with Jacobian 1).

use serde::{Deserialize, Serialize};

use crate::binning::{Axis, Grid};
use crate::cdf::TabulatedCdf;
use crate::error::StatsError;

/// One row of a [`PiecewiseConstant`] density: `u ∈ [u₀, u₁)`, cut along `v` at `v_edges`
/// (strictly increasing), with density `densities[k]` on `[v_edges[k], v_edges[k+1])`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellRow {
    /// `[u₀, u₁]`, `u₀ < u₁`.
    pub u: [f64; 2],
    /// Cell edges along `v` (at least two, strictly increasing).
    pub v_edges: Vec<f64>,
    /// Density of each cell w.r.t. `du dv` (`v_edges.len() − 1` finite values `≥ 0`).
    pub densities: Vec<f64>,
}

impl CellRow {
    /// The row's mass `∫ p du dv = (u₁ − u₀) Σ_k d_k (v_{k+1} − v_k)`.
    pub fn mass(&self) -> f64 {
        self.mass_per_u() * (self.u[1] - self.u[0])
    }

    /// The row's mass per unit `u`, `Σ_k d_k (v_{k+1} − v_k)` (its marginal rate along `u`).
    fn mass_per_u(&self) -> f64 {
        self.densities
            .iter()
            .zip(self.v_edges.windows(2))
            .map(|(d, e)| d * (e[1] - e[0]))
            .sum()
    }
}

/// A density `p(u, v) = Σ_cells d_c 1[(u, v) ∈ c]` on the cells of a row layout (see the
/// module docs), zero outside the rows. Rows may leave gaps; they must not overlap for the
/// masses to mean "the density's integral" (overlapping rows add up).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PiecewiseConstant {
    rows: Vec<CellRow>,
}

impl PiecewiseConstant {
    /// A density from its rows.
    ///
    /// # Errors
    /// [`StatsError::InvalidBinning`] for a row with `u₀ ≥ u₁`, non-finite or non-increasing
    /// edges, fewer than two `v` edges, or a density count that does not match; and
    /// [`StatsError::InvalidMass`] for a negative or non-finite density.
    pub fn new(rows: Vec<CellRow>) -> Result<Self, StatsError> {
        for (i, r) in rows.iter().enumerate() {
            let bad = |what: &str| {
                Err(StatsError::InvalidBinning(format!(
                    "piecewise-constant row {i}: {what}"
                )))
            };
            if !(r.u[0].is_finite() && r.u[1].is_finite() && r.u[0] < r.u[1]) {
                return bad("u range must be finite and increasing");
            }
            if r.v_edges.len() < 2 || r.densities.len() + 1 != r.v_edges.len() {
                return bad("needs >= 2 v edges and one density per cell");
            }
            if r.v_edges.iter().any(|e| !e.is_finite())
                || r.v_edges.windows(2).any(|w| w[0] >= w[1])
            {
                return bad("v edges must be finite and strictly increasing");
            }
            if let Some(&d) = r.densities.iter().find(|d| !(**d >= 0.0 && d.is_finite())) {
                return Err(StatsError::InvalidMass { mass: d });
            }
        }
        Ok(Self { rows })
    }

    /// The rows.
    pub fn rows(&self) -> &[CellRow] {
        &self.rows
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.rows.iter().map(|r| r.densities.len()).sum()
    }

    /// `∫ p du dv = Σ_c d_c |c|`.
    pub fn total_mass(&self) -> f64 {
        self.rows.iter().map(CellRow::mass).sum()
    }

    /// Mass of every cell of `grid` (index `i_v · n_u + i_u`, as [`Grid::cell`]):
    /// `Σ_c d_c |c ∩ cell|`, exact up to rounding; the parts of cells outside the grid are
    /// dropped. Cost `O(cells + overlaps)`.
    pub fn grid_masses(&self, grid: &Grid) -> Vec<f64> {
        let mut masses = vec![0.0; grid.n_cells()];
        let (gu, gv) = (grid.u_range(), grid.v_range());
        for r in &self.rows {
            let u_parts = overlaps(r.u, gu, grid.nu());
            if u_parts.is_empty() {
                continue;
            }
            for (d, e) in r.densities.iter().zip(r.v_edges.windows(2)) {
                if *d == 0.0 {
                    continue;
                }
                for (iv, lv) in overlaps([e[0], e[1]], gv, grid.nv()) {
                    for &(iu, lu) in &u_parts {
                        masses[iv * grid.nu() + iu] += d * lu * lv;
                    }
                }
            }
        }
        masses
    }

    /// The CDF of the projection onto `axis`, `F(t) = ∫_{axis ≤ t} p du dv / ∫ p du dv`,
    /// exact: the marginal density is constant between consecutive cell edges along `axis`, so
    /// `F` is linear there and is tabulated at every edge.
    ///
    /// # Errors
    /// [`StatsError::InvalidMass`] when the total mass is not positive.
    pub fn projection_cdf(&self, axis: Axis) -> Result<TabulatedCdf, StatsError> {
        // Intervals of the axis with their marginal rate (mass per unit length).
        let mut pieces: Vec<([f64; 2], f64)> = Vec::new();
        for r in &self.rows {
            let du = r.u[1] - r.u[0];
            match axis {
                Axis::U => pieces.push((r.u, r.mass_per_u())),
                Axis::V => pieces.extend(
                    r.densities
                        .iter()
                        .zip(r.v_edges.windows(2))
                        .map(|(d, e)| ([e[0], e[1]], d * du)),
                ),
            }
        }
        let mut knots: Vec<f64> = pieces.iter().flat_map(|(i, _)| *i).collect();
        knots.sort_by(f64::total_cmp);
        knots.dedup();
        // Difference array of rates over the knot intervals.
        let mut rate = vec![0.0; knots.len()];
        for ([a, b], r) in &pieces {
            rate[knots.partition_point(|k| k < a)] += r;
            rate[knots.partition_point(|k| k < b)] -= r;
        }
        let mut values = Vec::with_capacity(knots.len());
        let (mut acc, mut current) = (0.0_f64, 0.0_f64);
        for (i, k) in knots.iter().enumerate() {
            if i > 0 {
                acc += current.max(0.0) * (k - knots[i - 1]);
            }
            values.push(acc);
            current += rate[i];
        }
        TabulatedCdf::new(knots, values)
    }
}

/// The grid cells `i` (of `n` equal cells over `range`) that `[a, b]` overlaps, with the
/// overlap lengths (zero-length overlaps dropped).
fn overlaps(ab: [f64; 2], range: [f64; 2], n: usize) -> Vec<(usize, f64)> {
    let (lo, hi) = (ab[0].max(range[0]), ab[1].min(range[1]));
    if !(lo < hi) {
        return Vec::new();
    }
    let w = (range[1] - range[0]) / n as f64;
    let edge = |k: usize| {
        if k == n {
            range[1]
        } else {
            range[0] + (range[1] - range[0]) * (k as f64 / n as f64)
        }
    };
    let first = (((lo - range[0]) / w) as usize).min(n - 1);
    let mut out = Vec::new();
    let mut i = first;
    while i < n {
        let (c0, c1) = (edge(i), edge(i + 1));
        if c0 >= hi {
            break;
        }
        let l = c1.min(hi) - c0.max(lo);
        if l > 0.0 {
            out.push((i, l));
        }
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binning::{Binning, SphereBinning};
    use crate::quadrature::expected_masses;

    /// Two rows of the hemisphere with different φ cuts, normalised to 1 over `dz dφ`.
    fn two_rows() -> PiecewiseConstant {
        let tau = std::f64::consts::TAU;
        let rows = vec![
            CellRow {
                u: [0.0, 0.3],
                v_edges: vec![0.0, 1.0, 4.0, tau],
                densities: vec![0.5, 0.1, 0.2],
            },
            CellRow {
                u: [0.3, 1.0],
                v_edges: vec![0.0, 2.5, tau],
                densities: vec![0.05, 0.3],
            },
        ];
        let p = PiecewiseConstant::new(rows).unwrap();
        let m = p.total_mass();
        let rows = p
            .rows
            .iter()
            .map(|r| CellRow {
                densities: r.densities.iter().map(|d| d / m).collect(),
                ..r.clone()
            })
            .collect();
        PiecewiseConstant::new(rows).unwrap()
    }

    fn pdf_of(p: &PiecewiseConstant) -> impl Fn([f64; 3]) -> f64 + Sync + '_ {
        let bins = SphereBinning::hemisphere(1, 1).unwrap();
        move |d| {
            let Some([u, v]) = bins.param_of(&d) else {
                return 0.0;
            };
            for r in &p.rows {
                if u >= r.u[0] && u < r.u[1] {
                    let k = r
                        .v_edges
                        .partition_point(|e| *e <= v)
                        .clamp(1, r.densities.len());
                    return r.densities[k - 1];
                }
            }
            0.0
        }
    }

    #[test]
    fn grid_masses_agree_with_adaptive_quadrature_and_sum_to_the_total() {
        let p = two_rows();
        approx::assert_relative_eq!(p.total_mass(), 1.0, max_relative = 1e-14);
        let bins = SphereBinning::hemisphere(7, 9).unwrap();
        let exact = p.grid_masses(bins.grid());
        approx::assert_relative_eq!(exact.iter().sum::<f64>(), 1.0, max_relative = 1e-13);
        let pdf = pdf_of(&p);
        let quad = expected_masses(&pdf, &bins, 1_000_000);
        for (e, q) in exact.iter().zip(&quad) {
            assert!((e - q).abs() < 1e-4, "{e} vs {q}");
        }
        // A density off by 50 % in one cell changes the masses beyond the quadrature agreement.
        let mut rows = p.rows.clone();
        rows[1].densities[0] *= 1.5;
        let off = PiecewiseConstant::new(rows)
            .unwrap()
            .grid_masses(bins.grid());
        assert!(off.iter().zip(&exact).any(|(a, b)| (a - b).abs() > 1e-3));
    }

    #[test]
    fn projection_cdfs_are_exact_at_and_between_edges() {
        let p = two_rows();
        let fu = p.projection_cdf(Axis::U).unwrap();
        let row0: f64 = 0.3 * (0.5 + 0.1 * 3.0 + 0.2 * (std::f64::consts::TAU - 4.0));
        let m = {
            let row1 = 0.7 * (0.05 * 2.5 + 0.3 * (std::f64::consts::TAU - 2.5));
            row0 + row1
        };
        approx::assert_relative_eq!(fu.eval(0.3), row0 / m, max_relative = 1e-13);
        approx::assert_relative_eq!(fu.eval(0.15), 0.5 * row0 / m, max_relative = 1e-13);
        assert_eq!(fu.eval(1.0), 1.0);
        let fv = p.projection_cdf(Axis::V).unwrap();
        // F_v(1) = 0.3·0.5·1 + 0.7·0.05·1 (normalised), linear below.
        let at1 = (0.3 * 0.5 + 0.7 * 0.05) / m;
        approx::assert_relative_eq!(fv.eval(1.0), at1, max_relative = 1e-13);
        approx::assert_relative_eq!(fv.eval(0.5), 0.5 * at1, max_relative = 1e-13);
        assert!(
            PiecewiseConstant::new(vec![])
                .unwrap()
                .projection_cdf(Axis::U)
                .is_err()
        );
    }

    #[test]
    fn bad_rows_are_rejected() {
        let row = |u: [f64; 2], e: Vec<f64>, d: Vec<f64>| CellRow {
            u,
            v_edges: e,
            densities: d,
        };
        assert!(PiecewiseConstant::new(vec![row([0.5, 0.5], vec![0.0, 1.0], vec![1.0])]).is_err());
        assert!(PiecewiseConstant::new(vec![row([0.0, 1.0], vec![1.0, 0.0], vec![1.0])]).is_err());
        assert!(PiecewiseConstant::new(vec![row([0.0, 1.0], vec![0.0, 1.0], vec![])]).is_err());
        assert!(PiecewiseConstant::new(vec![row([0.0, 1.0], vec![0.0, 1.0], vec![-1.0])]).is_err());
    }
}
