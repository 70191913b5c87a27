//! A rigorous upper bound of an RGL material's `f_r · cos θi` (luminance) over a box of
//! incident directions and a range of outgoing elevations (issue 29: the envelope trees' leaf
//! bounds of `adaptive-exact`).
//!
//! **The value** (module docs of [`super`]): `Y(ωo, ωi) = L(s; θo) · D(u_m) / (4 σ(u_o))` with
//! `s = vndf⁻¹(u_m; θo)`, clamped at 0. Every factor is an interpolant with non-negative
//! weights of non-negative grid values, affine in each coordinate on each grid cell (and in
//! the blend weight between two `θ` slices), so its extremes over a rectangle are at the
//! corners of the rectangle's part in each cell (and at the ends of the weight range):
//! * `D` is bilinear on the `u_m`-square: its largest value over the region of `u_m`;
//! * `L` is bilinear on the warped square and linear in `θo` between two slices: its largest
//!   value over the region of `s` and the weight range of each slice pair `θo` meets;
//! * `σ(u_o)` is bilinear: its smallest value over `u_o`'s range (every azimuth unless its rows
//!   are equal).
//!
//! The product of the three extremes bounds `Y` (taken separately: `max L · max D` exceeds
//! `max (L · D)` where the two vary over the region).
//!
//! **The region of `u_m`.** With `ωo = (sin θo, 0, cos θo)` (the frame of an isotropic set)
//! the half vector is `S/|S|`, `S = ωo + ωi`. Interval arithmetic on the box of `ωi` and the
//! range of `θo` gives a box of `S`; `θm = atan2(|S_xy|, S_z)` grows with `|S_xy|` and falls
//! with `S_z`, and the azimuth `atan2(S_y, S_x)` of a box not holding the origin takes its
//! extremes at the corners (two ranges when the box crosses the branch cut `S_y = 0, S_x < 0`,
//! the whole turn when it holds the origin).
//!
//! **The region of `s`.** The inverse warp is `(C(x, y; w) / T(y; w), F_Y(y; w))` (the
//! partial row integral over the row total, and the marginal CDF) where `w` is the blend
//! weight between two `θ` slices. `F_Y` grows with `y` and is affine in `w`; `C` grows with
//! `x`; within one row cell `C` and `T` are affine in `y` and, for fixed `y`, in `w`, so their
//! ratio (a Möbius function of each variable, `T > 0`) is monotone in each: over a rectangle of
//! `(y, w)` its extremes are at corners. So `s_x` over the box lies between the inverse at
//! `x_lo` and at `x_hi` taken at `y ∈ {y_lo, y_hi, the row nodes between}` and the two ends of
//! the weight range, and `s_y` between `F_Y(y_lo)` and `F_Y(y_hi)` at those weights. A blend
//! with an empty row (total 0 at some weight of the range, where the code sets the ratio to
//! 0) takes `s_x ∈ [0, 1]`.
//!
//! **Rounding.** The evaluation computes these quantities in `f64` with `libm`'s `asin` and
//! `atan2` (errors below 1 ulp); every interval is widened by [`PAD`] (absolute, in its own
//! units: ~10⁷ ulps of the unit square) and the product by the factor [`MARGIN`].

use std::f64::consts::{FRAC_PI_2, PI};

use super::super::warp::{BilinearTable, Warp2D};
use super::{RglBrdf, angles::theta_to_u};

/// Absolute widening of every interval the bound is made of (radians, unit-square and
/// direction units): covers the rounding of the evaluation path (≈ 10⁻¹⁵) many times over.
pub const PAD: f64 = 1e-9;

/// Relative margin of the bound: covers the rounding of the interpolants' convex combinations
/// (a few ulps of their largest grid value) and of the product.
pub const MARGIN: f64 = 1.0 + 1e-9;

/// A box of incident directions `ωi = (x, y, z)` (each component a closed interval `[lo,
/// hi]`), in the frame where the outgoing direction's azimuth is 0. Directions at or below the
/// horizon (`z ≤ 0`) count for nothing (the material is 0 there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionBox {
    /// Range of `x`.
    pub x: [f64; 2],
    /// Range of `y`.
    pub y: [f64; 2],
    /// Range of `z`.
    pub z: [f64; 2],
}

/// The extreme (`max` when `upper`, else `min`) over `[x0, x1] × [y0, y1]` (clamped to the
/// unit square) and over the blend weights `w ∈ [w0, w1]` of the interpolant `(1 − w) A + w B`
/// of `table`'s slices `A = a` and `B = b` (bilinear on the square's grid). A bilinear function
/// is affine in each coordinate, so on each grid cell its extremes over a sub-rectangle are at
/// the sub-rectangle's corners, and the blend is affine in `w`: the extreme is taken over the
/// corners of every cell's part of the rectangle and the two weights.
fn bilinear_extreme(
    table: &BilinearTable,
    (a, b): (usize, usize),
    w: [f64; 2],
    x: [f64; 2],
    y: [f64; 2],
    upper: bool,
) -> f64 {
    let (nx, ny, data) = table.parts();
    let n = nx * ny;
    let span = |r: [f64; 2], m: usize| {
        let top = (m - 1) as f64;
        let (lo, hi) = (r[0].clamp(0.0, 1.0) * top, r[1].clamp(0.0, 1.0) * top);
        let (lo, hi) = (lo.min(hi), hi);
        let c0 = (lo.floor() as usize).min(m - 2);
        let c1 = (hi.ceil() as usize).clamp(c0 + 1, m - 1) - 1;
        (lo, hi, c0, c1)
    };
    let (gx0, gx1, cx0, cx1) = span(x, nx);
    let (gy0, gy1, cy0, cy1) = span(y, ny);
    let mut acc = if upper { 0.0f64 } else { f64::INFINITY };
    for cy in cy0..=cy1 {
        let fy = [
            (gy0 - cy as f64).clamp(0.0, 1.0),
            (gy1 - cy as f64).clamp(0.0, 1.0),
        ];
        for cx in cx0..=cx1 {
            let fx = [
                (gx0 - cx as f64).clamp(0.0, 1.0),
                (gx1 - cx as f64).clamp(0.0, 1.0),
            ];
            let k = cy * nx + cx;
            let at = |s: usize, fx: f64, fy: f64| {
                let d = &data[s * n..(s + 1) * n];
                let (v00, v10, v01, v11) = (d[k], d[k + 1], d[k + nx], d[k + nx + 1]);
                (1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11)
            };
            for &ty in &fy {
                for &tx in &fx {
                    let (va, vb) = (at(a, tx, ty), at(b, tx, ty));
                    for &wk in &w {
                        let v = (1.0 - wk) * va + wk * vb;
                        acc = if upper { acc.max(v) } else { acc.min(v) };
                    }
                }
            }
        }
    }
    acc
}

/// The row nodes `r/(ny − 1)` strictly inside `(y0, y1)`.
fn row_nodes(ny: usize, y: [f64; 2]) -> impl Iterator<Item = f64> {
    let top = (ny - 1) as f64;
    let lo = (y[0].clamp(0.0, 1.0) * top).floor() as usize;
    let hi = ((y[1].clamp(0.0, 1.0) * top).ceil() as usize).min(ny - 1);
    (lo..=hi)
        .map(move |r| r as f64 / top)
        .filter(move |&v| v > y[0] && v < y[1])
}

/// The box of `s = vndf⁻¹(u; i, w)` over `u ∈ ux × uy` and `w ∈ [w0, w1]` on slice pair `i`
/// (see the module docs), widened by [`PAD`] and clamped to the unit square.
fn warped_box(warp: &Warp2D, i: usize, w: [f64; 2], ux: [f64; 2], uy: [f64; 2]) -> [[f64; 2]; 2] {
    let ny = warp.rows();
    let mut sx = [f64::INFINITY, f64::NEG_INFINITY];
    let mut sy = [f64::INFINITY, f64::NEG_INFINITY];
    let ys = [uy[0], uy[1]].into_iter().chain(row_nodes(ny, uy));
    for y in ys {
        for &wk in &w {
            let (lo, _) = warp.invert_located([ux[0], y], i, wk);
            let (hi, _) = warp.invert_located([ux[1], y], i, wk);
            sx = [sx[0].min(lo[0]).min(hi[0]), sx[1].max(lo[0]).max(hi[0])];
            sy = [sy[0].min(lo[1]).min(hi[1]), sy[1].max(lo[1]).max(hi[1])];
        }
    }
    if warp.has_empty_row(i, w) || !(sx[0] <= sx[1]) {
        sx = [0.0, 1.0];
    }
    if !(sy[0] <= sy[1]) {
        sy = [0.0, 1.0];
    }
    let pad = |r: [f64; 2]| [(r[0] - PAD).max(0.0), (r[1] + PAD).min(1.0)];
    [pad(sx), pad(sy)]
}

/// The ranges of `u_m.y = frac((atan2(S_y, S_x) + π)/(2π))` over the box `sx × sy` of `S`
/// (one range, two across the branch cut, or `[0, 1]` when the box holds the origin).
fn azimuth_ranges(sx: [f64; 2], sy: [f64; 2]) -> ([[f64; 2]; 2], usize) {
    let u = |y: f64, x: f64| (y.atan2(x) + PI) / (2.0 * PI);
    let corners = |y: [f64; 2], x: [f64; 2]| {
        let v = [u(y[0], x[0]), u(y[0], x[1]), u(y[1], x[0]), u(y[1], x[1])];
        [
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        ]
    };
    let holds_origin = sx[0] <= 0.0 && sx[1] >= 0.0 && sy[0] <= 0.0 && sy[1] >= 0.0;
    if holds_origin {
        return ([[0.0, 1.0], [0.0, 0.0]], 1);
    }
    if sx[1] < 0.0 && sy[0] <= 0.0 && sy[1] >= 0.0 {
        // Across the cut: the lower half ends at u = 0 (angle −π), the upper at u = 1 (π).
        let lower = corners([sy[0], -0.0], sx);
        let upper = corners([0.0, sy[1]], sx);
        return ([[0.0, lower[1]], [upper[0], 1.0]], 2);
    }
    ([corners(sy, sx), [0.0, 0.0]], 1)
}

impl RglBrdf {
    /// A rigorous upper bound `B ≥ Y(ωo, ωi)` of the luminance of `f_r(ωo, ωi) · cos θi` (the
    /// file's value, [`Brdf::eval`](crate::Brdf::eval) times `cos θi`) over every
    /// `ωo = (sin θo, 0, cos θo)` with `θo ∈ [theta[0], theta[1]]` and every `ωi` of `wi` above
    /// the horizon: `B = (1 + 10⁻⁹) · max L · max D / (4 min σ)` over the regions of the
    /// module docs (`max L` alone when the file has no Jacobian factor). Values are
    /// evaluated at `fast::elevation(ωo)`, which is within [`PAD`] of `θo`. `+∞` for
    /// non-finite or empty ranges (no bound known); 0 when the box lies below the horizon.
    pub fn f_cos_bound(&self, theta: [f64; 2], wi: &DirectionBox) -> f64 {
        let finite = theta.iter().chain(&wi.x).chain(&wi.y).chain(&wi.z);
        if !finite.into_iter().all(|v| v.is_finite()) || !(theta[0] <= theta[1]) {
            return f64::INFINITY;
        }
        if !(wi.z[1] > 0.0) {
            return 0.0;
        }
        let t = &self.tables;
        let (ta, tb) = ((theta[0] - PAD).max(0.0), (theta[1] + PAD).min(FRAC_PI_2));
        let (ta, tb) = (ta.min(tb), tb);
        // ωo's components over the range (θo ∈ [0, π/2]: sin grows, cos falls).
        let (so, co) = (
            [ta.sin() - PAD, tb.sin() + PAD],
            [tb.cos() - PAD, ta.cos() + PAD],
        );
        let z = [wi.z[0].max(0.0), wi.z[1]];
        let sx = [so[0] + wi.x[0] - PAD, so[1] + wi.x[1] + PAD];
        let sy = [wi.y[0] - PAD, wi.y[1] + PAD];
        let sz = [(co[0] + z[0] - PAD).max(0.0), co[1] + z[1] + PAD];
        let near = |r: [f64; 2]| {
            if r[0] <= 0.0 && r[1] >= 0.0 {
                0.0
            } else {
                r[0].abs().min(r[1].abs())
            }
        };
        let far = |r: [f64; 2]| r[0].abs().max(r[1].abs());
        let (h_lo, h_hi) = (near(sx).hypot(near(sy)), far(sx).hypot(far(sy)));
        let theta_m = [h_lo.atan2(sz[1]), h_hi.atan2(sz[0])];
        let umx = [
            (theta_to_u(theta_m[0] - PAD) - PAD).max(0.0),
            (theta_to_u(theta_m[1] + PAD) + PAD).min(1.0),
        ];
        let (ranges, n_ranges) = azimuth_ranges(sx, sy);
        // σ(u_o) at u_o = (√(2θo/π), any azimuth): the smallest value of every row.
        let four_sigma_min = if t.jacobian {
            let uo = [theta_to_u(ta) - PAD, theta_to_u(tb) + PAD];
            let rows = if t.sigma_y_constant {
                [0.5, 0.5]
            } else {
                [0.0, 1.0]
            };
            4.0 * bilinear_extreme(&t.sigma, (0, 0), [0.0, 0.0], uo, rows, false)
        } else {
            1.0
        };
        if !(four_sigma_min > 0.0) {
            return f64::INFINITY;
        }
        // The θ slice pairs the range meets, with their weight ranges.
        let (ia, wa) = t.theta.locate(ta);
        let (ib, wb) = t.theta.locate(tb);
        let one = t.theta.values().len() < 2;
        let mut best = 0.0f64;
        for range in &ranges[..n_ranges] {
            let umy = [(range[0] - PAD).max(0.0), (range[1] + PAD).min(1.0)];
            let d_max = if t.jacobian {
                bilinear_extreme(&t.ndf, (0, 0), [0.0, 0.0], umx, umy, true)
            } else {
                1.0
            };
            let mut l_max = 0.0f64;
            for i in ia..=ib {
                let w = [
                    if i == ia { wa } else { 0.0 },
                    if i == ib { wb } else { 1.0 },
                ];
                let [bx, by] = warped_box(&t.vndf, i, w, umx, umy);
                let pair = if one { (0, 0) } else { (i, i + 1) };
                let w = if one { [0.0, 0.0] } else { w };
                l_max = l_max.max(bilinear_extreme(&t.rgb_luminance, pair, w, bx, by, true));
            }
            best = best.max(l_max * d_max);
        }
        MARGIN * best / four_sigma_min
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Brdf;
    use crate::geometry::Vec3;
    use std::path::{Path, PathBuf};

    /// The repository's fixture, and the RGL files of `$RGL_DIR` when set.
    fn materials() -> Vec<(PathBuf, RglBrdf)> {
        let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        let mut paths = vec![fixture];
        if let Ok(dir) = std::env::var("RGL_DIR") {
            let mut more: Vec<PathBuf> = std::fs::read_dir(dir)
                .expect("RGL_DIR is a directory")
                .map(|e| e.expect("entry").path())
                .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
                .collect();
            more.sort();
            paths.extend(more);
        }
        paths
            .into_iter()
            .map(|p| {
                let m = RglBrdf::load(&p).expect("an RGL file");
                (p, m)
            })
            .collect()
    }

    /// The largest `Y / B` over a dense sampling of boxes of `ωi` (`h` wide, 9 × 9 directions
    /// each, 5 outgoing elevations of the range) against `f_cos_bound · scale`, and whether any
    /// sample exceeded its bound.
    fn worst_ratio(rgl: &RglBrdf, theta: [f64; 2], h: f64, scale: f64) -> (f64, usize) {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut worst, mut over) = (0.0f64, 0);
        for _ in 0..120 {
            let (cx, cy) = (-1.0 + 2.0 * next(), -1.0 + 2.0 * next());
            let points: Vec<(f64, f64, f64)> = (0..81)
                .map(|k| (cx + h * (k % 9) as f64 / 8.0, cy + h * (k / 9) as f64 / 8.0))
                .filter(|(x, y)| x * x + y * y < 1.0)
                .map(|(x, y)| (x, y, (1.0 - x * x - y * y).sqrt()))
                .collect();
            if points.is_empty() {
                continue;
            }
            let z = points.iter().fold([f64::INFINITY, 0.0f64], |z, p| {
                [z[0].min(p.2), z[1].max(p.2)]
            });
            let wi_box = DirectionBox {
                x: [cx, cx + h],
                y: [cy, cy + h],
                z,
            };
            let bound = rgl.f_cos_bound(theta, &wi_box) * scale;
            assert!(bound.is_finite(), "{wi_box:?}");
            for k in 0..5 {
                let t = theta[0] + (theta[1] - theta[0]) * k as f64 / 4.0;
                let wo = Vec3::new(t.sin(), 0.0, t.cos());
                let q = rgl.prepare(&wo);
                for &(x, y, z) in &points {
                    let y_cos = rgl.eval_prepared(&q, &Vec3::new(x, y, z)) * z;
                    if y_cos > bound {
                        over += 1;
                    }
                    if bound > 0.0 {
                        worst = worst.max(y_cos / bound);
                    }
                }
            }
        }
        (worst, over)
    }

    const RANGES_DEG: [[f64; 2]; 5] = [
        [0.0, 2.0],
        [29.0, 30.5],
        [59.5, 61.0],
        [79.0, 80.5],
        [88.0, 89.99],
    ];

    /// `f_cos_bound` is never exceeded by the material's value (the evaluation path of
    /// `eval_prepared`) on boxes of two sizes and five ranges of θo, and it is tight: on some
    /// box the value reaches 97 % of it (so the test fails when the bound is shrunk by 3 %,
    /// checked, docs/benchmarks.md §29.2). `RGL_DIR=…/rgl` adds the files there.
    #[test]
    fn f_cos_bound_holds_and_is_tight() {
        let scale = std::env::var("RGL_BOUND_SCALE")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1.0);
        for (path, rgl) in materials() {
            let mut worst = 0.0f64;
            for range in RANGES_DEG {
                let theta = range.map(f64::to_radians);
                for h in [0.004, 0.03] {
                    let (w, over) = worst_ratio(&rgl, theta, h, scale);
                    eprintln!("{} θo {range:?}° h {h}: largest Y/B {w:.4}", path.display());
                    assert_eq!(over, 0, "{}: {over} values above the bound", path.display());
                    worst = worst.max(w);
                }
            }
            assert!(
                worst > 0.97,
                "{}: loose bound, largest Y/B {worst}",
                path.display()
            );
        }
    }

    /// Degenerate input: non-finite or reversed ranges give no bound, a box below the horizon
    /// gives 0.
    #[test]
    fn f_cos_bound_degenerate_input() {
        let (_, rgl) = materials().swap_remove(0);
        let b = DirectionBox {
            x: [0.0, 0.1],
            y: [0.0, 0.1],
            z: [0.9, 1.0],
        };
        assert_eq!(rgl.f_cos_bound([0.2, 0.1], &b), f64::INFINITY);
        assert_eq!(rgl.f_cos_bound([f64::NAN, 0.1], &b), f64::INFINITY);
        let below = DirectionBox {
            z: [-0.5, 0.0],
            ..b
        };
        assert_eq!(rgl.f_cos_bound([0.1, 0.2], &below), 0.0);
        assert!(rgl.f_cos_bound([0.1, 0.2], &b) > 0.0);
    }
}
