//! The per-interval record of anisotropic queries ([`AnisoRecord`], issue 29: the per-query
//! cost of anisotropic Ward) and its normaliser patches ([`Patch`]).
//!
//! An anisotropic interval's normaliser table is a tensor Chebyshev series of 45–81
//! coefficients in `(θo, δ)`: a query paid two `atan` series for its variables and read ≈ 6.5
//! cache lines of coefficients (docs/benchmarks.md §23.2). Here the same interpolant is
//! **refitted** once per set (on construction and on loading; no quadrature, no file-format
//! change) on a uniform grid of small cells over the query's own search keys,
//! `w = √(1 − cos θo)` and the strip key `d` (`tan δ`, or `δ` for wide cells; see
//! [`Cell::by_tan`](super::layout::Cell::by_tan)): each cell a bicubic in the monomial basis
//! ([`Patch`], 16 coefficients on two cache lines). A query finds its patch by two
//! multiplications (no search), evaluates 16 coefficients by Horner's rule, and needs neither
//! `θo` nor `δ` (no `atan`).
//!
//! `w` is a smooth, monotone function of `θo` (`w = √2 sin(θo/2)`, with non-zero derivative
//! up to π/2), so the refit is as smooth as the table (whereas `1 − cos θo` would put a
//! square-root singularity at the normal for BRDFs without half-turn symmetry).
//!
//! **Accuracy.** Each axis is first refined alone (patches doubled along `w` until the
//! one-variable fits on 5 lines of `d` meet half of [`REFIT_REL`], and likewise along `d`),
//! then the grid is doubled along `w` or `d`, whichever lowers the error more, until the
//! patches agree with the interval's table to [`REFIT_REL`] (relative) at 8 × 8 points inside
//! every patch (between its nodes), up to [`MAX_PATCHES`] per interval; the largest
//! difference found is added to the interval's declared normaliser error
//! ([`Interval::norm_err`](super::interval::Interval::norm_err)). On anisotropic Ward's
//! default set (129 intervals) every interval meets the target, with 5 488 patches (686 KiB;
//! docs/benchmarks.md §24.2).

use super::chebyshev::{tensor_monomial, tensor_series};
use super::interval::Interval;
use crate::disc::DiscMap;

/// Coefficients per axis of a [`Patch`] (a bicubic).
pub(super) const P: usize = 4;

/// Largest relative difference between the patches and the interval's table that stops the
/// refinement: a tenth of the default normaliser tolerance
/// ([`ExactOptions::DEFAULT_NORMALISER_TOL`](super::ExactOptions::DEFAULT_NORMALISER_TOL)).
pub(super) const REFIT_REL: f64 = 1e-7;

/// Most patches per interval (128 KiB of coefficients).
pub(super) const MAX_PATCHES: usize = 1024;

/// Most patches along one axis when each axis is refined alone.
const MAX_PER_AXIS: u32 = 32;

/// Lines of the other variable along which each axis is refined alone.
const LINES: usize = 5;

/// Check points per axis and patch.
const CHECKS: usize = 8;

/// One cell of an interval's normaliser grid: `A · cos θo ≈ Σ_{i,j} a[i·P + j] xⁱ yʲ` for the
/// local coordinates `x, y ∈ [−1, 1]` of the cell. 128 bytes, aligned to a cache line: two
/// lines per query.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub(super) struct Patch(pub(super) [f64; P * P]);

impl Patch {
    /// The bicubic at local coordinates `(x, y)`: Horner's rule along `x` for the four `y`
    /// powers side by side, then along `y`.
    #[inline]
    pub(super) fn eval(&self, x: f64, y: f64) -> f64 {
        let a = &self.0;
        let mut acc = [a[12], a[13], a[14], a[15]];
        for i in (0..P - 1).rev() {
            for j in 0..P {
                acc[j] = acc[j] * x + a[i * P + j];
            }
        }
        ((acc[3] * y + acc[2]) * y + acc[1]) * y + acc[0]
    }
}

/// What an anisotropic query reads of its interval besides the sampling table (one cache
/// line): the normaliser grid's affine maps and size, its first patch, and the disc map.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub(super) struct AnisoRecord {
    /// `w` at the grid's lower edge and `nw / (w_hi − w_lo)`: `u = (w − w_lo) · w_scale ∈ [0, nw]`.
    w_lo: f64,
    w_scale: f64,
    /// The same for the strip key `d`.
    d_lo: f64,
    d_scale: f64,
    /// `1 − w²` at the grid's edges: `cos θo` of a query clamped to the grid.
    cos_range: [f64; 2],
    /// Patches along `w` and `d`.
    nw: u32,
    nd: u32,
    /// Index of the first patch in the cell's patch list; patch `(i, j)` is `first + i·nd + j`.
    first: u32,
    pub(super) map: DiscMap,
}

/// The grid variable of `θo`: `w = √(1 − cos θo) = √2 sin(θo/2)`.
pub(super) fn w_of_theta(theta: f64) -> f64 {
    std::f64::consts::SQRT_2 * (0.5 * theta).sin()
}

/// `θo` of the grid variable `w` (exact near the normal, unlike `acos(1 − w²)`).
fn theta_of_w(w: f64) -> f64 {
    2.0 * (w * std::f64::consts::FRAC_1_SQRT_2)
        .clamp(-1.0, 1.0)
        .asin()
}

/// The local coordinate and cell of `u ∈ [0, n]` (clamped).
#[inline]
fn cell_of(u: f64, n: u32) -> (usize, f64) {
    let u = u.clamp(0.0, n as f64);
    let i = (u as u32).min(n - 1);
    (i as usize, 2.0 * (u - i as f64) - 1.0)
}

/// A refitted grid before it is stored: its size, patches and largest relative difference.
struct Fit {
    nw: u32,
    nd: u32,
    patches: Vec<Patch>,
    err: f64,
}

impl AnisoRecord {
    /// The record of `iv` (an interval of an anisotropic cell whose strip key is `tan δ` when
    /// `by_tan`, otherwise `δ`), its patches appended to `patches`; returns the record and
    /// the largest relative difference between the patches and the interval's table.
    pub(super) fn of(iv: &Interval, by_tan: bool, patches: &mut Vec<Patch>) -> (Self, f64) {
        let t = &iv.table;
        let (th_lo, th_hi) = (t.theta[t.theta.len() - 1], t.theta[0]);
        let (de_lo, de_hi) = (t.delta[t.delta.len() - 1], t.delta[0]);
        let key = |d: f64| if by_tan { d.tan() } else { d };
        let unkey = |k: f64| if by_tan { k.atan() } else { k };
        let (w_lo, w_hi) = (w_of_theta(th_lo), w_of_theta(th_hi));
        let (d_lo, d_hi) = (key(de_lo), key(de_hi));
        let reference = |w: f64, d: f64| t.eval(theta_of_w(w), unkey(d));
        let fit = |nw: u32, nd: u32| fit_grid(&reference, [w_lo, w_hi], [d_lo, d_hi], nw, nd);
        // Each axis refined alone first, on lines of the other (a greedy choice from one
        // patch refined only the axis that was worse at the start), then both as needed.
        let lines = |lo: f64, hi: f64| {
            (0..LINES).map(move |k| lo + (hi - lo) * k as f64 / (LINES - 1) as f64)
        };
        let axis = |one: &dyn Fn(u32) -> f64| {
            let mut n = 1;
            while !(one(n) <= 0.5 * REFIT_REL) && n < MAX_PER_AXIS {
                n *= 2;
            }
            n
        };
        let nw = axis(&|n| {
            lines(d_lo, d_hi)
                .map(|d| fit_grid(&reference, [w_lo, w_hi], [d, d], n, 1).err)
                .fold(0.0, f64::max)
        });
        let nd = axis(&|n| {
            lines(w_lo, w_hi)
                .map(|w| fit_grid(&reference, [w, w], [d_lo, d_hi], 1, n).err)
                .fold(0.0, f64::max)
        });
        let mut best = fit(nw, nd);
        while !(best.err <= REFIT_REL) && (best.nw * best.nd) as usize * 2 <= MAX_PATCHES {
            let (a, b) = (fit(2 * best.nw, best.nd), fit(best.nw, 2 * best.nd));
            // Whichever axis lowers the error more (the other when one is not a number).
            best = if b.err < a.err || a.err.is_nan() {
                b
            } else {
                a
            };
        }
        let scale = |n: u32, lo: f64, hi: f64| if hi > lo { n as f64 / (hi - lo) } else { 0.0 };
        let rec = Self {
            w_lo,
            w_scale: scale(best.nw, w_lo, w_hi),
            d_lo,
            d_scale: scale(best.nd, d_lo, d_hi),
            cos_range: [1.0 - w_lo * w_lo, 1.0 - w_hi * w_hi],
            nw: best.nw,
            nd: best.nd,
            first: patches.len() as u32,
            map: iv.map,
        };
        patches.extend_from_slice(&best.patches);
        (rec, best.err)
    }

    /// Patches of this record (`[along w, along d]`).
    #[cfg(test)]
    pub(super) fn size(&self) -> [u32; 2] {
        [self.nw, self.nd]
    }

    /// `A(θo, δ)` at the grid keys `w = √(1 − cos θo)` and `d` (the strip key) of a query with
    /// `cos θo = cos`, from the cell's `patches`: the keys clamped to the grid, `A = (A cos
    /// θo) / cos θo` (the clamped `cos θo` when `w` was clamped).
    #[inline]
    pub(super) fn normaliser(&self, w: f64, d: f64, cos: f64, patches: &[Patch]) -> f64 {
        let (i, x) = cell_of((w - self.w_lo) * self.w_scale, self.nw);
        let (j, y) = cell_of((d - self.d_lo) * self.d_scale, self.nd);
        let p = &patches[self.first as usize + i * self.nd as usize + j];
        // Only queries within rounding of an edge, or served beyond the table's top, clamp.
        let cos = cos.clamp(self.cos_range[1], self.cos_range[0]);
        p.eval(x, y) / cos
    }
}

/// The grid of `nw × nd` bicubic patches over `w ∈ [w_lo, w_hi]`, `d ∈ [d_lo, d_hi]`
/// interpolating `reference` at the 4 × 4 Chebyshev–Lobatto nodes of each cell, and its
/// largest relative difference from `reference` at [`CHECKS`]² points inside each cell.
fn fit_grid(
    reference: &impl Fn(f64, f64) -> f64,
    [w_lo, w_hi]: [f64; 2],
    [d_lo, d_hi]: [f64; 2],
    nw: u32,
    nd: u32,
) -> Fit {
    // Local x ∈ [−1, 1] of cell i → w.
    let at = |lo: f64, hi: f64, n: u32, i: u32, x: f64| {
        lo + (hi - lo) * ((i as f64 + 0.5 * (x + 1.0)) / n as f64)
    };
    let nodes: Vec<f64> = (0..P)
        .map(|k| (std::f64::consts::PI * k as f64 / (P - 1) as f64).cos())
        .collect();
    let checks: Vec<f64> = (0..CHECKS)
        .map(|k| -1.0 + (2 * k + 1) as f64 / CHECKS as f64)
        .collect();
    let mut patches = Vec::with_capacity((nw * nd) as usize);
    let mut err = 0.0f64;
    for i in 0..nw {
        for j in 0..nd {
            let mut values = [0.0; P * P];
            for (a, &x) in nodes.iter().enumerate() {
                for (b, &y) in nodes.iter().enumerate() {
                    values[a * P + b] =
                        reference(at(w_lo, w_hi, nw, i, x), at(d_lo, d_hi, nd, j, y));
                }
            }
            let mono = tensor_monomial(&tensor_series(&values, P), P);
            let mut patch = Patch([0.0; P * P]);
            patch.0.copy_from_slice(&mono);
            for &x in &checks {
                for &y in &checks {
                    let want = reference(at(w_lo, w_hi, nw, i, x), at(d_lo, d_hi, nd, j, y));
                    let rel = (patch.eval(x, y) - want).abs() / want.abs();
                    // NaN (a zero or non-finite value) counts as failing.
                    err = if rel.is_nan() {
                        f64::INFINITY
                    } else {
                        err.max(rel)
                    };
                }
            }
            patches.push(patch);
        }
    }
    Fit {
        nw,
        nd,
        patches,
        err,
    }
}

#[cfg(test)]
pub(super) mod tests {
    use std::sync::Arc;

    use brdf::{Brdf, parse_spec};
    use partition_sampler::UniformSource;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    use super::*;
    use crate::ExactOptions;
    use crate::exact::ExactSet;

    /// A patch is the bicubic it was fitted to (to rounding), and a smooth non-polynomial
    /// function is met to [`REFIT_REL`] once the grid is fine enough, with the error the fit
    /// reports bounding the error at other points.
    #[test]
    fn patches_interpolate_bicubics_and_converge_on_smooth_functions() {
        let cubic = |w: f64, d: f64| 2.0 + w - 0.5 * w * w * d + 0.25 * d * d * d * w * w * w;
        let fit = fit_grid(&cubic, [0.1, 0.9], [-0.4, 0.4], 3, 2);
        assert!(fit.err < 1e-14, "{}", fit.err);
        let smooth = |w: f64, d: f64| (1.3 * w).exp() * (2.0 + (3.0 * d).sin());
        let (coarse, fine) = (
            fit_grid(&smooth, [0.0, 1.0], [-0.4, 0.4], 1, 1),
            fit_grid(&smooth, [0.0, 1.0], [-0.4, 0.4], 32, 32),
        );
        assert!(
            coarse.err > 1e-4 && fine.err < REFIT_REL,
            "{coarse:?} {fine:?}",
            coarse = coarse.err,
            fine = fine.err
        );
        // Between the check points too, through the record's own lookup.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        for _ in 0..2000 {
            let (w, d) = (rng.next_uniform(), 0.8 * rng.next_uniform() - 0.4);
            let (i, x) = cell_of(w * 32.0, 32);
            let (j, y) = cell_of((d + 0.4) * 32.0 / 0.8, 32);
            let got = fine.patches[i * 32 + j].eval(x, y);
            let want = smooth(w, d);
            assert!(
                (got / want - 1.0).abs() < 2.0 * fine.err,
                "({w}, {d}): {got} vs {want}"
            );
        }
    }

    /// The anisotropic query's normaliser (the record's patches over `√(1 − cos θo)` and the
    /// strip key, no `θo` or `δ`) is the interval's table at `(θo, δ)` to the refit error: at
    /// random directions, at the normal, next to every interval's corners and above the served
    /// top; `locate_keys` finds the query `locate` finds; the refit error is part of the
    /// declared one. Returns the largest `|grid/table − 1|`. (Called by this module's test,
    /// on wide cells, and by `tests.rs`'s anisotropic-cells test, on narrow ones.)
    pub(in crate::exact) fn assert_normaliser_is_the_table(set: &ExactSet) -> f64 {
        let mut refined = 0;
        for c in &set.cells {
            assert_eq!(c.aniso.len(), c.intervals.len());
            let total: usize = c
                .aniso
                .iter()
                .map(|r| r.size().iter().product::<u32>() as usize)
                .sum();
            assert_eq!(total, c.patches.len());
            refined += c.aniso.iter().filter(|r| r.size() != [1, 1]).count();
        }
        assert!(refined > 0, "some grids refined");
        // The intervals of the queries below come from the direct index
        // (`Cell::interval_direct`): the search's, exactly.
        assert!(crate::exact::layout::tests::assert_direct_is_the_search(&set.cells, 11) > 0);
        // Each interval's refit difference (the build's, again): below the target unless the
        // grid is at its largest size.
        let errs: Vec<Vec<f64>> = set
            .cells
            .iter()
            .map(|c| {
                c.intervals
                    .iter()
                    .zip(&c.aniso)
                    .map(|(iv, rec)| {
                        let (again, err) = AnisoRecord::of(iv, c.by_tan, &mut Vec::new());
                        assert_eq!(again.size(), rec.size());
                        let full = 2 * rec.size().iter().product::<u32>() as usize > MAX_PATCHES;
                        assert!(err <= REFIT_REL || full, "{rec:?}: {err:e}");
                        err
                    })
                    .collect()
            })
            .collect();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let mut queries: Vec<(f64, f64)> = (0..3000)
            .map(|_| (rng.next_uniform() * 89.999, rng.next_uniform() * 360.0))
            .collect();
        queries.extend([
            (0.0, 0.0),
            (1e-6, 10.0),
            (1e-3, 200.0),
            (89.995, 33.0),
            (89.9999, 300.0),
        ]);
        for cell in &set.cells {
            for iv in &cell.intervals {
                for t in iv.theta {
                    for d in iv.delta {
                        let (t, p) = (t.to_degrees(), (cell.phi + d).to_degrees());
                        for e in [-1e-7, 0.0, 1e-7] {
                            queries.push(((t + e).clamp(0.0, 89.9999), p + e));
                        }
                    }
                }
            }
        }
        let mut worst = 0.0f64;
        for (t, p) in queries {
            let wo = brdf::direction_from_angles(t, p);
            let (qa, qk) = (set.locate(&wo).unwrap(), set.locate_keys(&wo).unwrap());
            assert_eq!(
                (qa.cell, qa.interval, qa.turn, qa.cos),
                (qk.cell, qk.interval, qk.turn, qk.cos)
            );
            assert_eq!(qa.keys.map(f64::to_bits), qk.keys.map(f64::to_bits));
            // No angles computed for drawing (δ only on the `atan2` path: wide cells, or
            // a query exactly at a narrow cell's edge, which rounding puts out of both).
            assert!(qk.var.is_nan());
            if !set.cells[qk.cell].by_tan {
                assert_eq!(qk.delta.to_bits(), qa.delta.to_bits());
            }
            let iv = set.interval(&qa);
            let (table, grid) = (iv.normaliser(set.var, &qa), set.normaliser_of(&qk));
            let rel = (grid / table - 1.0).abs();
            worst = worst.max(rel);
            // The refit's checks sample each patch at 64 points: allow twice the target
            // between them.
            let refit = errs[qa.cell][qa.interval];
            assert!(
                rel <= 2.0 * refit.max(REFIT_REL),
                "θo {t}° φo {p}°: {grid} vs table {table}, {rel:e} (refit {refit:e})"
            );
            assert!(iv.norm_err >= iv.quad_err + iv.table.rel_tail());
        }
        worst
    }

    /// [`assert_normaliser_is_the_table`] on wide cells (3 over π: `tan h > 0.5`, so the
    /// strip key and the grid's variable are `δ` itself, from `atan2`), a quick build.
    #[test]
    fn anisotropic_normaliser_on_wide_cells_is_the_table() {
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec("ward:alpha_x=0.12,alpha_y=0.3").unwrap());
        let opts = ExactOptions {
            max_trials: 8.0,
            normaliser_tol: 1e-3,
            initial_phi_cells: 3,
            ..ExactOptions::default()
        };
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
        assert!(!set.cells[0].by_tan);
        let worst = assert_normaliser_is_the_table(&set);
        assert!(worst > 0.0);
    }
}
