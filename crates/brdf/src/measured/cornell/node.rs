//! A quadrature evaluator of the kNN interpolant (issue 29, docs/benchmarks.md §27.3): the
//! value of [`Brdf::eval`](crate::Brdf::eval) to within [`QUADRATURE_REL_BOUND`] relative,
//! not bit for bit, at a fraction of its instructions. The set table's normaliser nodes
//! integrate the interpolant to ≈ 10⁻⁵–10⁻⁴ relative; an evaluation off by at most `ε`
//! relative moves such an integral of the non-negative `f` by at most `ε · ∫ f`, which the
//! caller adds to its declared error.
//!
//! What differs from `eval` (the same math, other rounding):
//!
//! 1. **Remap.** `p = (√(|ωi,xy|² |ωo,xy|²), Δφ/π, cos θi cos θo)` as `eval` computes it, but
//!    `Δφ = atan2(|sin Δφ|, cos Δφ)` by [`atan2_upper`] (Cephes' rational `atan` on `[0, 1]`
//!    after the octant swap, a few ulp; `libm`'s `atan2` was 143 of `eval`'s ≈ 2 082
//!    instructions per node evaluation, §23.7).
//! 2. **Search.** The squared distances to every candidate of `p`'s grid cell are computed
//!    in vector lanes from the cell's structure-of-arrays copy (`search::CellList`, the same
//!    formula, so the same bits), then the `K` = 9 smallest *values* are kept by insertion
//!    (no file-index tie order). The interpolant only needs those values: with `c` the 9-th
//!    smallest squared distance (with multiplicity), sample `k`'s cut weight
//!    `max(0, expm1((c − d_k²)/2h²))` is positive exactly for the samples strictly nearer
//!    than `c` — at most 8, the same ones whichever tied samples a search keeps — and 0 for
//!    every other sample, so the blended value does not depend on the tie order.
//! 3. **Weights.** The 8 `expm1` in lanes by [`expm1_nonneg`] (Cody–Waite reduction by
//!    `ln 2`, the degree-13 Taylor polynomial of `expm1` on `|r| ≤ ln 2 / 2`, then
//!    `2^k · expm1(r) + (2^k − 1)`; a few ulp).
//!
//! The one discontinuous branch of `eval` (every blended sample as far as the cut one: equal
//! weights), points outside the grid (none from directions), cells of fewer than `K`
//! candidates and directions on the pole take `eval` itself. The bound is checked against `eval` on
//! every shared file (test `quadrature_eval_is_eval_within_its_bound`).
//!
//! The lanes are plain loops over fixed arrays compiled for AVX-512 / AVX2 + FMA / the
//! baseline by `pulp`'s runtime dispatch (as `measured/rgl/lanes.rs`); Rust never contracts
//! `a·b + c` into a fused multiply-add, so every level gives the same bits.

// Cephes' and fdlibm's constants as published.
#![allow(clippy::excessive_precision, clippy::approx_constant)]

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use super::search::{self, K, SOA_PAD};
use super::{BANDWIDTH, CornellBrdf, Interpolation};
use crate::brdf::Brdf;
use crate::geometry::Vec3;

/// Largest relative difference between [`QuadratureEval::eval`] and `eval` that a caller must
/// allow for (measured: docs/benchmarks.md §27.3; asserted by the tests on every shared file).
/// An integral of `f ≥ 0` computed from these values is within `QUADRATURE_REL_BOUND · ∫ f`
/// of the same rule on `eval`.
pub const QUADRATURE_REL_BOUND: f64 = 1e-10;

/// The quadrature evaluator of a [`CornellBrdf`] (see the [module docs](self)): `f_r(ωo, ωi)`
/// within [`QUADRATURE_REL_BOUND`] relative of [`Brdf::eval`]. Made by
/// [`CornellBrdf::quadrature_eval`]; cheap to copy, `Sync`.
#[derive(Clone, Copy)]
pub struct QuadratureEval<'a> {
    brdf: &'a CornellBrdf,
    arch: pulp::Arch,
}

impl std::fmt::Debug for QuadratureEval<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("QuadratureEval")
            .field("brdf", self.brdf)
            .finish()
    }
}

impl CornellBrdf {
    /// This material's quadrature evaluator: `f_r` within [`QUADRATURE_REL_BOUND`] relative of
    /// [`Brdf::eval`], for rules whose own error is far larger (the set table's nodes). With
    /// [`Interpolation::Grid`] it is `eval` itself.
    pub fn quadrature_eval(&self) -> QuadratureEval<'_> {
        QuadratureEval {
            brdf: self,
            arch: preferred_arch(),
        }
    }
}

/// AVX2 + FMA when the host has it (AVX-512 measured slower here: 217 against 158 ns per
/// evaluation, `timing::quadrature_eval_timing`), else `pulp`'s choice.
fn preferred_arch() -> pulp::Arch {
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        return pulp::Arch::V3(v3);
    }
    pulp::Arch::new()
}

impl QuadratureEval<'_> {
    /// `f_r(ωo, ωi)` (the luminance) within [`QUADRATURE_REL_BOUND`] relative of
    /// [`Brdf::eval`]: 0 below either horizon, else the kNN interpolant at the remapped point
    /// with the lanes search and weights of the [module docs](self).
    #[inline]
    pub fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wo.z > 0.0 && wi.z > 0.0) || self.brdf.interp != Interpolation::Knn {
            return self.brdf.eval(wo, wi);
        }
        let (ri, ro) = (wi.x * wi.x + wi.y * wi.y, wo.x * wo.x + wo.y * wo.y);
        if !(ri > 0.0 && ro > 0.0) {
            return self.brdf.eval(wo, wi);
        }
        let cross = wo.x * wi.y - wo.y * wi.x;
        let dot = wo.x * wi.x + wo.y * wi.y;
        let p = [
            (ri * ro).sqrt(),
            atan2_upper(cross.abs(), dot) / PI,
            wi.z * wo.z,
        ];
        let data = &*self.brdf.data;
        self.arch
            .dispatch(Blend {
                tree: &data.tree,
                lum: &data.lum,
                p,
            })
            .unwrap_or_else(|| self.brdf.eval(wo, wi))
    }
}

/// One point's blend as a `pulp` operation.
struct Blend<'a> {
    tree: &'a search::Tree,
    lum: &'a [f64],
    p: [f64; 3],
}

impl pulp::WithSimd for Blend<'_> {
    type Output = Option<f64>;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> Option<f64> {
        blend(self.tree, self.lum, &self.p)
    }
}

/// The kNN interpolant's luminance at `p` by the lanes path; `None` where `eval` must decide.
#[inline(always)]
fn blend(tree: &search::Tree, lum: &[f64], p: &[f64; 3]) -> Option<f64> {
    let cell = tree.cell_list_of(p)?;
    let (n, s) = (cell.index.len(), cell.stride());
    if n < K {
        return None;
    }
    let (xs, rest) = cell.xyz.split_at(s);
    let (ys, zs) = rest.split_at(s);
    // The K smallest squared distances (in no order; ties in any order: see the module docs)
    // and where they are in the list: the first K candidates, then each nearer one replaces
    // the farthest kept. The distances by blocks of `SOA_PAD` lanes with the search's `dist2`
    // formula (so the same bits); a block whose smallest is not below the farthest kept is
    // passed over whole (the list is ordered by distance to the cell's centre, so after the
    // first blocks most are). Padding points are never kept: the `n ≥ K` real candidates come
    // first and every one is nearer.
    let mut kept = [0.0f64; K];
    let mut at = [0usize; K];
    let (mut len, mut far, mut far_at) = (0usize, f64::INFINITY, 0usize);
    let blocks = xs
        .chunks_exact(SOA_PAD)
        .zip(ys.chunks_exact(SOA_PAD))
        .zip(zs.chunks_exact(SOA_PAD));
    for (b, ((xb, yb), zb)) in blocks.enumerate() {
        let mut d = [0.0f64; SOA_PAD];
        for l in 0..SOA_PAD {
            let (a, bb, c) = (xb[l] - p[0], yb[l] - p[1], zb[l] - p[2]);
            d[l] = a * a + bb * bb + c * c;
        }
        let m = d.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        if !(m < far) {
            continue;
        }
        for (l, &dl) in d.iter().enumerate() {
            if len < K {
                kept[len] = dl;
                at[len] = b * SOA_PAD + l;
                len += 1;
                if len < K {
                    continue;
                }
            } else if dl < far {
                kept[far_at] = dl;
                at[far_at] = b * SOA_PAD + l;
            } else {
                continue;
            }
            // The farthest kept (the last of equals), by selects rather than branches.
            far = kept.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x));
            far_at = 0;
            for (j, &x) in kept.iter().enumerate() {
                far_at = if x == far { j } else { far_at };
            }
        }
    }
    if len < K {
        return None;
    }
    // The cut: the K-th smallest squared distance. Every kept sample at it (the farthest,
    // and any tied with it) gets weight `expm1(0) = 0`, every other kept one is strictly
    // nearer: `eval`'s blended samples with positive weight, the same weights.
    let cut = far;
    let inv = 1.0 / (2.0 * BANDWIDTH * BANDWIDTH);
    let mut x = [0.0f64; K];
    for (x, &d) in x.iter_mut().zip(&kept) {
        *x = (cut - d) * inv;
    }
    let mut w = [0.0f64; K];
    for (w, &x) in w.iter_mut().zip(&x) {
        *w = expm1_nonneg(x);
    }
    let (mut sum, mut total) = (0.0, 0.0);
    for (&w, &k) in w.iter().zip(&at) {
        sum += w * lum[cell.index[k] as usize];
        total += w;
    }
    // Every blended sample as far as the cut one: `eval`'s equal weights.
    (total > 0.0).then(|| sum / total)
}

/// `1.5 · 2⁵²`: adding it rounds a double of magnitude below 2⁵¹ to an integer.
const ROUND_SHIFT: f64 = 6_755_399_441_055_744.0;
const LOG2_E: f64 = 1.442_695_040_888_963_387_00e+00;
// fdlibm's split of ln 2 (`ln2_hi` has 21 trailing zero bits: `k · LN2_HI` is exact for
// |k| < 2¹¹).
const LN2_HI: f64 = 6.931_471_803_691_238_164_90e-01;
const LN2_LO: f64 = 1.908_214_929_270_587_700_02e-10;

/// `expm1(x)` for `0 ≤ x ≤ 700` (the weights' arguments are at most `3/(2h²)` = 600), a few ulp:
/// `x = k ln 2 + r` with `k = round(x / ln 2)`, `|r| ≤ ln 2 / 2` (Cody–Waite), `expm1(r)` by
/// its Taylor polynomial to `r¹³` (remainder `< r¹⁴/14! ≤ 5·10⁻¹⁸`), and
/// `expm1(x) = 2^k · expm1(r) + (2^k − 1)` (exact at `k = 0`). Branch-free, so it vectorises.
#[inline(always)]
pub(super) fn expm1_nonneg(x: f64) -> f64 {
    let x = x.min(700.0);
    let t = x * LOG2_E + ROUND_SHIFT;
    let k = t - ROUND_SHIFT;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    // 1/n! for n = 2..=13.
    const C: [f64; 12] = [
        1.0 / 2.0,
        1.0 / 6.0,
        1.0 / 24.0,
        1.0 / 120.0,
        1.0 / 720.0,
        1.0 / 5_040.0,
        1.0 / 40_320.0,
        1.0 / 362_880.0,
        1.0 / 3_628_800.0,
        1.0 / 39_916_800.0,
        1.0 / 479_001_600.0,
        1.0 / 6_227_020_800.0,
    ];
    let mut q = C[11];
    for &c in C[..11].iter().rev() {
        q = q * r + c;
    }
    let p = r + r * r * q;
    // 2^k from the bits of `t` (its low bits hold k; 0 ≤ k ≤ 1 010).
    let k_bits = t.to_bits().wrapping_sub(ROUND_SHIFT.to_bits());
    let two_k = f64::from_bits(k_bits.wrapping_add(1023) << 52);
    two_k * p + (two_k - 1.0)
}

// Cephes' `atan` (atan.c): `atan(x) = x + x³ P(x²)/Q(x²)` on `|x| ≤ 0.66`.
const ATAN_P: [f64; 5] = [
    -8.750_608_600_031_904_122_785e-1,
    -1.615_753_718_733_365_076_637e1,
    -7.500_855_792_314_704_667_340e1,
    -1.228_866_684_490_136_173_410e2,
    -6.485_021_904_942_025_371_773e1,
];
const ATAN_Q: [f64; 5] = [
    2.485_846_490_142_306_297_962e1,
    1.650_270_098_316_988_542_046e2,
    4.328_810_604_912_902_668_951e2,
    4.853_903_996_359_136_964_868e2,
    1.945_506_571_482_613_964_425e2,
];
/// Cephes' `MOREBITS`: `π/4`'s rounding error, added back with the reduction by `π/4`.
const MOREBITS: f64 = 6.123_233_995_736_765_886_130e-17;

/// `atan(t)` for `0 ≤ t ≤ 1` (Cephes: above 0.66, `π/4 + atan((t − 1)/(t + 1))`).
#[inline(always)]
fn atan_unit(t: f64) -> f64 {
    let (base, x, more) = if t > 0.66 {
        (FRAC_PI_4, (t - 1.0) / (t + 1.0), 0.5 * MOREBITS)
    } else {
        (0.0, t, 0.0)
    };
    let z = x * x;
    let num = (((ATAN_P[0] * z + ATAN_P[1]) * z + ATAN_P[2]) * z + ATAN_P[3]) * z + ATAN_P[4];
    let den = ((((z + ATAN_Q[0]) * z + ATAN_Q[1]) * z + ATAN_Q[2]) * z + ATAN_Q[3]) * z + ATAN_Q[4];
    base + (x * (z * num / den) + x + more)
}

/// `atan2(y, x)` for `y ≥ 0`, `(x, y) ≠ (0, 0)`, in `[0, π]`, a few ulp: `atan` of the smaller
/// over the larger magnitude ([`atan_unit`]), reflected into the right octant.
#[inline(always)]
pub(super) fn atan2_upper(y: f64, x: f64) -> f64 {
    let ax = x.abs();
    let a = if y > ax {
        FRAC_PI_2 - atan_unit(ax / y)
    } else {
        atan_unit(y / ax)
    };
    if x < 0.0 { PI - a } else { a }
}

#[cfg(test)]
mod tests {
    use super::super::search::tests::xorshift;
    use super::*;

    /// The team's Cornell files when the data repository sits beside this one, and the
    /// synthetic grid file (many equidistant samples).
    /// The kNN materials the evaluator serves (the default interpolation is the grid).
    fn files() -> Vec<(String, CornellBrdf)> {
        let knn = |b: CornellBrdf| b.with_interpolation(Interpolation::Knn);
        let mut out = vec![(
            "synthetic".to_string(),
            knn(
                CornellBrdf::parse(&super::super::lobe_grid_text(|f| [0.7 * f, f, 0.2 + f]))
                    .unwrap(),
            ),
        )];
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/measured/cornell");
        for name in ["acryl_blue", "cayman", "krylon_blue"] {
            match CornellBrdf::load(&dir.join(format!("{name}.brdf"))) {
                Ok(b) => out.push((name.to_string(), knn(b))),
                Err(_) => eprintln!("skipped {name}: {} is absent", dir.display()),
            }
        }
        out
    }

    /// The direction of the equal-area disc point `(x, y)` (the reference rule's map).
    fn equal_area(x: f64, y: f64) -> Vec3 {
        let r2 = x * x + y * y;
        let s = (2.0 - r2).sqrt();
        Vec3::new(x * s, y * s, 1.0 - r2)
    }

    /// Largest relative difference of the quadrature evaluator from `eval` on `b`: random
    /// direction pairs (uniform on the hemisphere, poles and shared azimuths now and then) and,
    /// at 12 outgoing angles (φo = 0, as the set table's nodes), the points of a 300 × 300 grid
    /// on the equal-area half disc `y ≤ 0` and of a fine 60 × 60 patch around the mirror
    /// direction. Also counts the points where the value is the one of `eval` bit for bit.
    fn worst(b: &CornellBrdf, random: usize) -> (f64, usize, usize) {
        let q = b.quadrature_eval();
        let (mut worst, mut same, mut n) = (0.0f64, 0usize, 0usize);
        let mut check = |wo: &Vec3, wi: &Vec3| {
            let (e, v) = (b.eval(wo, wi), q.eval(wo, wi));
            n += 1;
            if e == v {
                same += 1;
                return;
            }
            assert!(e > 0.0 && v.is_finite(), "{wo:?} {wi:?}: {v} vs {e}");
            worst = worst.max((v - e).abs() / e);
        };
        let mut u = xorshift(0x9e37_79b9_7f4a_7c15);
        let mut dir = |k: usize| {
            if k.is_multiple_of(991) {
                return Vec3::new(0.0, 0.0, 1.0);
            }
            let (z, phi) = (u(), std::f64::consts::TAU * u());
            let s = (1.0 - z * z).sqrt();
            Vec3::new(s * phi.cos(), s * phi.sin(), z)
        };
        for k in 0..random {
            let wo = dir(k);
            let wi = if k.is_multiple_of(13) {
                let t = dir(k + 1);
                // A shared azimuth: Δφ = 0 exactly.
                let (r, ro) = (
                    (t.x * t.x + t.y * t.y).sqrt(),
                    (wo.x * wo.x + wo.y * wo.y).sqrt(),
                );
                if ro > 0.0 {
                    Vec3::new(wo.x / ro * r, wo.y / ro * r, t.z)
                } else {
                    t
                }
            } else {
                dir(k + 1)
            };
            check(&wo, &wi);
        }
        for deg in [
            0.3, 2.8, 11.0, 17.3, 30.5, 45.1, 55.0, 62.4, 75.7, 84.2, 89.5, 89.99,
        ] {
            let wo = crate::direction_from_radians(f64::to_radians(deg), 0.0);
            let m = 300;
            for i in 0..m {
                for j in 0..m / 2 {
                    let (x, y) = (
                        -1.0 + 2.0 * (i as f64 + 0.37) / m as f64,
                        -1.0 + 2.0 * (j as f64 + 0.61) / m as f64,
                    );
                    if x * x + y * y < 1.0 {
                        check(&wo, &equal_area(x, y));
                    }
                }
            }
            // Around the mirror direction (x = −|disc point of ωo|, y ≤ 0).
            let c = -(1.0 - wo.z).sqrt();
            for i in 0..60 {
                for j in 0..60 {
                    let (x, y) = (c + (i as f64 - 30.0) * 1e-3, -(j as f64) * 1e-3);
                    if x * x + y * y < 1.0 {
                        check(&wo, &equal_area(x, y));
                    }
                }
            }
        }
        (worst, same, n)
    }

    /// The quadrature evaluator is `eval` within [`QUADRATURE_REL_BOUND`] on every file: on
    /// 10⁵ random pairs and ≈ 4·10⁵ node-rule-like points per file (see `worst`); measured
    /// 1.4·10⁻¹³ (synthetic) to 2.6·10⁻¹² (`cayman`), all from the `atan2` (with `libm`'s
    /// `atan2` the evaluator is within 8.2·10⁻¹⁶). Fails when the weights' reduction drops
    /// `LN2_LO` (synthetic file 3.5·10⁻¹⁰; docs/benchmarks.md §27.3).
    #[test]
    fn quadrature_eval_is_eval_within_its_bound() {
        for (name, b) in files() {
            let (w, same, n) = worst(&b, 100_000);
            eprintln!("{name}: max relative difference {w:.2e} on {n} points ({same} bit for bit)");
            assert!(w <= QUADRATURE_REL_BOUND, "{name}: {w:e}");
            // Not `eval` itself: most values differ in their last bits.
            assert!(same < n, "{name}");
        }
        // Grid interpolation: `eval` itself.
        let (_, b) = &files()[0];
        let g = b.with_interpolation(Interpolation::Grid);
        let (w, same, n) = worst(&g, 2_000);
        assert!(w == 0.0 && same == n);
    }

    /// The two elementary functions against `std`'s on their whole ranges: `expm1_nonneg` within
    /// 4 ulp-scale (4·2⁻⁵² relative) on `[0, 600]`, `atan2_upper` within 4·2⁻⁵² absolute on
    /// the upper half plane (measured 1.2 and 2.0). Fails with `LN2_LO` dropped (7·10⁸);
    /// dropping Cephes' `MOREBITS` does not fail it (still 2.0).
    #[test]
    fn elementary_functions_are_within_a_few_ulp() {
        let eps = 4.0 * f64::EPSILON;
        let mut u = xorshift(0x2545_f491_4f6c_dd1d);
        let mut worst_e = 0.0f64;
        for k in 0..400_000 {
            let x = match k % 4 {
                0 => 600.0 * u(),
                1 => u(),
                2 => 1e-3 * u(),
                _ => (k / 4) as f64 * std::f64::consts::LN_2 * 0.5 * (1.0 + 1e-12 * (u() - 0.5)),
            }
            .min(600.0);
            let (a, b) = (expm1_nonneg(x), x.exp_m1());
            let rel = if b == 0.0 { a.abs() } else { (a - b).abs() / b };
            worst_e = worst_e.max(rel);
        }
        assert_eq!(expm1_nonneg(0.0), 0.0);
        let mut worst_a = 0.0f64;
        for k in 0..400_000 {
            let (y, x) = match k % 4 {
                0 => (u(), 2.0 * u() - 1.0),
                1 => (1e-6 * u(), 2.0 * u() - 1.0),
                2 => (u(), 1e-6 * (2.0 * u() - 1.0)),
                _ => {
                    let t = std::f64::consts::PI * u();
                    (t.sin().abs(), t.cos())
                }
            };
            if y == 0.0 && x == 0.0 {
                continue;
            }
            worst_a = worst_a.max((atan2_upper(y, x) - y.atan2(x)).abs());
        }
        for (y, x) in [(0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (1.0, 1.0), (1.0, -1.0)] {
            worst_a = worst_a.max((atan2_upper(y, x) - f64::atan2(y, x)).abs());
        }
        eprintln!(
            "expm1: {:.2} ulp-scale; atan2: {:.2} ulp-scale",
            worst_e / f64::EPSILON,
            worst_a / f64::EPSILON
        );
        assert!(worst_e <= eps, "expm1 {worst_e:e}");
        assert!(worst_a <= eps, "atan2 {worst_a:e}");
    }
}

#[cfg(test)]
mod timing {
    use super::*;

    /// Wall time per evaluation of `eval` and of the quadrature evaluator (each instruction
    /// set) on the points of a 600 × 300 half-disc grid at θo = 30.5° on the team's `cayman`,
    /// for the record (docs/benchmarks.md §27.3): `cargo test --release -p brdf --lib
    /// quadrature_eval_timing -- --ignored --nocapture`.
    #[test]
    #[ignore = "a timing for the record"]
    fn quadrature_eval_timing() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/measured/cornell/cayman.brdf");
        let Ok(b) = CornellBrdf::load(&path) else {
            return;
        };
        let wo = crate::direction_from_radians(30.5f64.to_radians(), 0.0);
        let mut wis = Vec::new();
        for i in 0..600 {
            for j in 0..300 {
                let (x, y) = (
                    -1.0 + (i as f64 + 0.5) / 300.0,
                    -1.0 + (j as f64 + 0.5) / 300.0,
                );
                let r2 = x * x + y * y;
                if r2 < 1.0 {
                    let s = (2.0 - r2).sqrt();
                    wis.push(Vec3::new(x * s, y * s, 1.0 - r2));
                }
            }
        }
        let time = |name: &str, f: &dyn Fn(&Vec3) -> f64| {
            let mut best = f64::INFINITY;
            let mut sum = 0.0;
            for _ in 0..5 {
                let t = std::time::Instant::now();
                sum = wis.iter().map(f).sum::<f64>();
                best = best.min(t.elapsed().as_secs_f64());
            }
            eprintln!(
                "{name}: {:.1} ns per evaluation (sum {sum})",
                best * 1e9 / wis.len() as f64
            );
        };
        time("eval", &|wi| b.eval(&wo, wi));
        let mut levels = vec![pulp::Arch::Scalar];
        #[cfg(target_arch = "x86_64")]
        {
            levels.extend(pulp::x86::V3::try_new().map(pulp::Arch::V3));
            levels.extend(pulp::x86::V4::try_new().map(pulp::Arch::V4));
        }
        for arch in levels {
            let q = QuadratureEval { brdf: &b, arch };
            time(&format!("quadrature {arch:?}"), &|wi| q.eval(&wo, wi));
        }
    }
}
