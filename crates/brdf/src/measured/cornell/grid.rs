//! The tabulated Cornell interpolant (issue 29): the k-nearest-neighbour interpolant sampled
//! once on a regular grid of the remapped cube and interpolated multilinearly.
//!
//! [`super::Interpolation::Grid`] defines `f` at a remapped point `p ∈ [0, 1]³` as the trilinear
//! interpolant of the kNN interpolant's values at the vertices `(i, j, k)/N`,
//! `N` = [`GRID_CELLS`]. Its kinks lie on the grid's planes only (the kNN interpolant has them
//! on the bisector planes of sample pairs, everywhere), so the albedo at `θo` is an exact sum:
//! along `y` (`Δφ/π`) the interpolant is piecewise linear, so `∫₀¹ f dy` is the bilinear
//! interpolant of the vertex columns' trapezoid sums, and the remaining integral over `θi` is
//! smooth between the known angles where `sin θi sin θo` or `cos θi cos θo` crosses a grid
//! plane ([`CornellBrdf::grid_albedo`]). Vertex values are computed when a query first needs
//! their block (8³ vertices), so a file read for a few evaluations pays for a few blocks.

use std::sync::OnceLock;

use super::{CornellBrdf, GRID_CELLS, VertexGrid};

/// Vertices per axis.
const V: usize = GRID_CELLS + 1;
/// Vertices per block edge.
const B: usize = 8;
/// Blocks per axis.
const NB: usize = V.div_ceil(B);

/// One vertex: luminance and RGB.
type Vertex = [f64; 4];

impl VertexGrid {
    /// No vertex made yet.
    pub(super) fn new() -> Self {
        Self {
            blocks: (0..NB * NB * NB).map(|_| OnceLock::new()).collect(),
            columns: (0..V * V).map(|_| OnceLock::new()).collect(),
        }
    }
}

impl CornellBrdf {
    /// The value of vertex `(i, j, k)` (each `< V`).
    #[inline]
    fn vertex(&self, i: usize, j: usize, k: usize) -> &Vertex {
        let grid = &self.data.vertices;
        let (bi, bj, bk) = (i / B, j / B, k / B);
        let block = grid.blocks[bi + NB * (bj + NB * bk)].get_or_init(|| {
            let mut out = Vec::with_capacity(B * B * B);
            for dk in 0..B {
                for dj in 0..B {
                    for di in 0..B {
                        let (vi, vj, vk) = (bi * B + di, bj * B + dj, bk * B + dk);
                        if vi >= V || vj >= V || vk >= V {
                            out.push([0.0; 4]);
                            continue;
                        }
                        let h = 1.0 / GRID_CELLS as f64;
                        let p = [vi as f64 * h, vj as f64 * h, vk as f64 * h];
                        // One search for the four channels: each channel's sum is the one
                        // `knn_luminance_at` / `knn_rgb_at` make (same weights, same order),
                        // so the same bits as two blends.
                        let (lum, rgb) = (&self.data.lum, &self.data.rgb);
                        out.push(self.blend(&p, |i| [lum[i], rgb[i][0], rgb[i][1], rgb[i][2]]));
                    }
                }
            }
            out.into_boxed_slice()
        });
        &block[(i % B) + B * ((j % B) + B * (k % B))]
    }

    /// The trilinear interpolant of channels `C` (0: luminance, 1–3: RGB) at `p` (clamped to
    /// the cube).
    #[inline]
    pub(super) fn grid_at<const C: usize>(&self, p: &[f64; 3], first: usize) -> [f64; C] {
        let n = GRID_CELLS as f64;
        let mut idx = [0usize; 3];
        let mut frac = [0.0; 3];
        for d in 0..3 {
            let s = (p[d].clamp(0.0, 1.0)) * n;
            let i = (s as usize).min(GRID_CELLS - 1);
            idx[d] = i;
            frac[d] = s - i as f64;
        }
        let mut out = [0.0; C];
        for corner in 0..8 {
            let (a, b, c) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if a == 1 { frac[0] } else { 1.0 - frac[0] })
                * (if b == 1 { frac[1] } else { 1.0 - frac[1] })
                * (if c == 1 { frac[2] } else { 1.0 - frac[2] });
            let v = self.vertex(idx[0] + a, idx[1] + b, idx[2] + c);
            for ch in 0..C {
                out[ch] += w * v[first + ch];
            }
        }
        out
    }

    /// `∫₀¹ L dy` of the grid interpolant on the vertex column `(i, k)`: the trapezoid sum of
    /// its luminances (exact: the interpolant is linear in `y` between vertices).
    fn column_integral(&self, i: usize, k: usize) -> f64 {
        *self.data.vertices.columns[i + V * k].get_or_init(|| {
            let inner: f64 = (1..GRID_CELLS).map(|j| self.vertex(i, j, k)[0]).sum();
            (inner + 0.5 * (self.vertex(i, 0, k)[0] + self.vertex(i, GRID_CELLS, k)[0]))
                / GRID_CELLS as f64
        })
    }

    /// The directional albedo `∫ f cos θi dωi` of the luminance of [`super::Interpolation::Grid`]
    /// at the polar angle `theta_o` (radians, in `[0, π/2]`) whatever this material's own
    /// interpolation, with an error estimate: `(value, abs_err)`; `None` outside that range.
    ///
    /// `A = 2π ∫₀^{π/2} sin θi cos θi J(sin θi sin θo, cos θi cos θo) dθi` with `J` the bilinear
    /// interpolant of the vertex columns' integrals over `y` (exact). `J` along the path is
    /// smooth between the angles where a coordinate crosses a grid plane; there each piece is
    /// integrated by 8 Gauss–Legendre points, the estimate the difference from 4 points.
    pub fn grid_albedo(&self, theta_o: f64) -> Option<(f64, f64)> {
        if !(theta_o.is_finite() && (0.0..=std::f64::consts::FRAC_PI_2).contains(&theta_o)) {
            return None;
        }
        let (so, co) = theta_o.sin_cos();
        let n = GRID_CELLS as f64;
        let breaks = grid_break_angles(GRID_CELLS, so, co);
        let j_at = |t: f64| {
            let (si, ci) = t.sin_cos();
            let (x, z) = ((si * so).clamp(0.0, 1.0) * n, (ci * co).clamp(0.0, 1.0) * n);
            let (i, k) = (
                (x as usize).min(GRID_CELLS - 1),
                (z as usize).min(GRID_CELLS - 1),
            );
            let (fx, fz) = (x - i as f64, z - k as f64);
            let c = |a: usize, b: usize| self.column_integral(i + a, k + b);
            let j = (1.0 - fx) * ((1.0 - fz) * c(0, 0) + fz * c(0, 1))
                + fx * ((1.0 - fz) * c(1, 0) + fz * c(1, 1));
            std::f64::consts::TAU * si * ci * j
        };
        let (g8, g4) = (
            crate::quadrature::GaussLegendre::new(8),
            crate::quadrature::GaussLegendre::new(4),
        );
        let (mut value, mut err) = (0.0, 0.0);
        for w in breaks.windows(2) {
            let hi = g8.integrate(w[0], w[1], j_at);
            let lo = g4.integrate(w[0], w[1], j_at);
            value += hi;
            err += (hi - lo).abs();
        }
        Some((value, err))
    }
}

/// The polar angles `θi ∈ [0, π/2]` (sorted, without repeats, both ends included) where the
/// path `x = sin θi sin θo`, `z = cos θi cos θo` (`so`, `co` = `sin θo`, `cos θo`) crosses a plane
/// `x = i/n` or `z = k/n` of a regular `n³` grid of the remapped cube: between them the grid's
/// trilinear interpolant integrated over `y` is smooth along the path.
pub(super) fn grid_break_angles(n: usize, so: f64, co: f64) -> Vec<f64> {
    let mut breaks = vec![0.0, std::f64::consts::FRAC_PI_2];
    for i in 1..n {
        let v = i as f64 / n as f64;
        if v < so {
            breaks.push((v / so).asin());
        }
        if v < co {
            breaks.push((v / co).acos());
        }
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup();
    breaks
}
