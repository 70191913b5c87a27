//! A prepared run of the kNN interpolant at one `ωo` whose block evaluation is
//! [`Brdf::eval`] **bit for bit** (issue 29, docs/benchmarks.md §30.3): what the envelope trees'
//! image maps evaluate (their bounds are audited against `eval`, so no rounding may differ).
//!
//! `eval(ωo, ωi)` is, at the remapped point `p` (`remap_dirs`, the same formulae here, `libm`'s
//! `atan2`), `Σ_k w_k L_k / Σ_k w_k` over the [`NEIGHBOURS`] nearest samples in the order
//! `(d², file index)`, with `w_k = max(0, expm1((c − d_k²)/2h²))` and `c` the `K`-th smallest
//! squared distance (`K = NEIGHBOURS + 1`). The block path finds the same terms differently:
//!
//! 1. The squared distances to every candidate of `p`'s grid cell (`search::CellList`, the
//!    list `eval`'s search scans) in vector lanes, with the search's `dist2` formula (the same
//!    bits), and the `K` smallest *values* kept by replacing the farthest (as the quadrature
//!    evaluator, `node.rs`), so `c` is exact.
//! 2. `w_k > 0` exactly when `d_k² < c` (`c − d_k² > 0` is exact and `expm1` of a positive
//!    double is positive): those samples — at most `NEIGHBOURS`, all among the kept — are
//!    sorted by `(d², file index)`, the order of `eval`'s list, and blended with `libm`'s
//!    `expm1` in that order. `eval`'s other terms are the samples tied with `c`, at the end
//!    of its list, with `w = 0`: they add `+0` to both sums, which changes no bit.
//!
//! Points outside the grid, cells of fewer than `K` candidates, directions on the pole and
//! `eval`'s equal-weights branch (no sample strictly nearer than `c`) take `eval` itself; the
//! grid interpolation ([`Interpolation::Grid`]) has no run. Test:
//! `block_evaluation_is_eval_bit_for_bit`.

use std::f64::consts::PI;

use super::search::{self, K, SOA_PAD};
use super::{BANDWIDTH, CornellBrdf, Interpolation, NEIGHBOURS};
use crate::brdf::{Brdf, PreparedRun};
use crate::geometry::Vec3;

/// `f_r(ωo, ·)` of a [`CornellBrdf`] with the kNN interpolant at one `ωo` above the horizon
/// (from [`Brdf::prepare_run`]): [`PreparedRun::eval`] is `eval(ωo, ωi)`, and
/// [`PreparedRun::eval_block`] the same values bit for bit through the lanes search of the
/// [module docs](self).
pub(super) struct CornellRun<'a> {
    brdf: &'a CornellBrdf,
    wo: Vec3,
    /// `ωo,x² + ωo,y²` (as `remap_dirs` computes it).
    ro: f64,
    arch: pulp::Arch,
}

impl<'a> CornellRun<'a> {
    /// The run of `brdf` at `wo`; `None` for the grid interpolation or `wo` not above the
    /// horizon (or not finite).
    pub(super) fn new(brdf: &'a CornellBrdf, wo: &Vec3) -> Option<Self> {
        if brdf.interp != Interpolation::Knn
            || !(wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite())
        {
            return None;
        }
        Some(Self {
            brdf,
            wo: *wo,
            ro: wo.x * wo.x + wo.y * wo.y,
            arch: preferred_arch(),
        })
    }
}

impl CornellBrdf {
    /// `out[k] = f_r(ωo, wi[k])` =
    /// [`eval`](Brdf::eval)`(wo, wi[k])` bit for bit, for `k < min(wi.len(), out.len())`: with
    /// the kNN interpolant and `ωo` above the horizon through the lanes search of the
    /// [module docs](self) (a run's [`PreparedRun::eval_block`]), else one `eval` per direction.
    /// For callers that hold the material itself rather than a boxed run (the envelope trees'
    /// bound nodes, one block of ≤ 64 directions at a time).
    pub fn eval_block_at(&self, wo: &Vec3, wi: &[Vec3], out: &mut [f64]) {
        match CornellRun::new(self, wo) {
            Some(run) => run.eval_block(wi, out),
            None => {
                for (w, o) in wi.iter().zip(out.iter_mut()) {
                    *o = self.eval(wo, w);
                }
            }
        }
    }
}

/// AVX2 + FMA when the host has it (as the quadrature evaluator: AVX-512 measured slower for
/// these short lanes, §27.3), else `pulp`'s choice.
fn preferred_arch() -> pulp::Arch {
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        return pulp::Arch::V3(v3);
    }
    pulp::Arch::new()
}

impl PreparedRun for CornellRun<'_> {
    #[inline]
    fn eval(&self, wi: &Vec3) -> f64 {
        self.brdf.eval(&self.wo, wi)
    }

    /// `out[k] = eval(ωo, wi[k])` bit for bit, through the lanes search (module docs).
    fn eval_block(&self, wi: &[Vec3], out: &mut [f64]) {
        self.arch.dispatch(Block { run: self, wi, out });
    }

    fn prefers_blocks(&self) -> bool {
        true
    }
}

/// One block's evaluations as a `pulp` operation.
struct Block<'r, 'a> {
    run: &'r CornellRun<'a>,
    wi: &'r [Vec3],
    out: &'r mut [f64],
}

impl pulp::WithSimd for Block<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let run = self.run;
        let data = &*run.brdf.data;
        let wo = &run.wo;
        for (wi, o) in self.wi.iter().zip(self.out.iter_mut()) {
            *o = if !(wi.z > 0.0) {
                0.0
            } else {
                let ri = wi.x * wi.x + wi.y * wi.y;
                if ri > 0.0 && run.ro > 0.0 {
                    // `remap_dirs`' point, the same operations.
                    let cross = wo.x * wi.y - wo.y * wi.x;
                    let dot = wo.x * wi.x + wo.y * wi.y;
                    let p = [
                        (ri * run.ro).sqrt(),
                        cross.abs().atan2(dot) / PI,
                        wi.z * wo.z,
                    ];
                    exact_blend(&data.tree, &data.lum, &p).unwrap_or_else(|| run.brdf.eval(wo, wi))
                } else {
                    run.brdf.eval(wo, wi)
                }
            };
        }
    }
}

/// `knn_luminance_at(p)` bit for bit (module docs), or `None` where `eval` must decide.
#[inline(always)]
fn exact_blend(tree: &search::Tree, lum: &[f64], p: &[f64; 3]) -> Option<f64> {
    let cell = tree.cell_list_of(p)?;
    let (n, s) = (cell.index.len(), cell.stride());
    if n < K {
        return None;
    }
    let (xs, rest) = cell.xyz.split_at(s);
    let (ys, zs) = rest.split_at(s);
    // The K smallest squared distances (ties in any order) and their places in the list:
    // the first K candidates, then each nearer one replaces the farthest kept. A block of
    // `SOA_PAD` whose smallest is not below the farthest kept is passed over. Padding points
    // are never kept (the `n ≥ K` real candidates come first and are all nearer).
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
            // `search::dist2(sample, p)`: the same operations in the same order.
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
    let cut = far;
    // The samples strictly nearer than the cut, sorted by (d², file index): `eval`'s terms of
    // positive weight, in its order.
    let mut d2 = [0.0f64; NEIGHBOURS];
    let mut idx = [0u32; NEIGHBOURS];
    let mut m = 0usize;
    for (&d, &a) in kept.iter().zip(&at) {
        if d < cut && m < NEIGHBOURS {
            let i = cell.index[a];
            let mut j = m;
            while j > 0 && (d < d2[j - 1] || (d == d2[j - 1] && i < idx[j - 1])) {
                d2[j] = d2[j - 1];
                idx[j] = idx[j - 1];
                j -= 1;
            }
            d2[j] = d;
            idx[j] = i;
            m += 1;
        }
    }
    if m == 0 {
        // `eval`'s equal weights.
        return None;
    }
    let inv = 1.0 / (2.0 * BANDWIDTH * BANDWIDTH);
    let (mut sum, mut total) = (0.0, 0.0);
    for (&d, &i) in d2[..m].iter().zip(&idx[..m]) {
        let w = ((cut - d) * inv).exp_m1().max(0.0);
        sum += w * lum[i as usize];
        total += w;
    }
    if total > 0.0 { Some(sum / total) } else { None }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random pairs (xorshift) with shared azimuths, poles and grazing directions now and then;
    /// `ωo` fixed per run of 200.
    fn runs(n_runs: usize, per_run: usize, mut state: u64) -> Vec<(Vec3, Vec<Vec3>)> {
        let mut u = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let dir = |k: usize, u: &mut dyn FnMut() -> f64| {
            if k.is_multiple_of(211) {
                return Vec3::new(0.0, 0.0, 1.0);
            }
            let (z, phi) = (u(), std::f64::consts::TAU * u());
            let z = if k.is_multiple_of(97) { 1e-6 * z } else { z };
            let s = (1.0 - z * z).sqrt();
            Vec3::new(s * phi.cos(), s * phi.sin(), z)
        };
        (0..n_runs)
            .map(|r| {
                let wo = dir(r + 1, &mut u);
                let wis = (0..per_run).map(|k| dir(k + 7 * r, &mut u)).collect();
                (wo, wis)
            })
            .collect()
    }

    /// Issue 29: a run's block evaluation is `eval` bit for bit (the envelope trees' bounds are
    /// audited against `eval`) on 40 000 random pairs of the synthetic lobe file (many
    /// equidistant samples: ties at the cut and among the blended) and of every shared file,
    /// and the lanes path (not `eval`'s fall-back) serves nearly all of them (39 811 of
    /// 40 000). Fails when one point's list is cut short (its farthest blended sample dropped:
    /// the first synthetic pair differs in the 14th digit). Not caught: ties of `d²` among the
    /// blended samples ordered by distance only (exact ties are of measure zero at random
    /// pairs).
    #[test]
    fn block_evaluation_is_eval_bit_for_bit() {
        let mut files = vec![("synthetic".to_string(), super::super::tests::synthetic())];
        files.extend(super::super::tests::shared_files());
        for (name, text) in files {
            let b = CornellBrdf::parse(&text)
                .unwrap()
                .with_interpolation(Interpolation::Knn);
            let (mut pairs, mut lanes) = (0usize, 0usize);
            for (wo, wis) in runs(200, 200, 0x9e37_79b9_7f4a_7c15) {
                let run = b.prepare_run(&wo).expect("a run above the horizon");
                assert!(run.prefers_blocks());
                let mut out = vec![f64::NAN; wis.len()];
                run.eval_block(&wis, &mut out);
                for (wi, &got) in wis.iter().zip(&out) {
                    let want = b.eval(&wo, wi);
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "{name}: ωo {wo:?}, ωi {wi:?}: block {got:e}, eval {want:e}"
                    );
                    assert_eq!(run.eval(wi).to_bits(), want.to_bits());
                    let mut one = [f64::NAN];
                    b.eval_block_at(&wo, std::slice::from_ref(wi), &mut one);
                    assert_eq!(one[0].to_bits(), want.to_bits());
                    pairs += 1;
                    let data = &*b.data;
                    let p = super::super::remap_dirs(&wo, wi);
                    lanes += usize::from(
                        wi.z > 0.0
                            && wi.x * wi.x + wi.y * wi.y > 0.0
                            && exact_blend(&data.tree, &data.lum, &p).is_some(),
                    );
                }
            }
            eprintln!("{name}: {pairs} pairs bit for bit, {lanes} through the lanes");
            assert!(lanes * 10 >= pairs * 9, "{name}: {lanes} of {pairs}");
        }
        // No run at or below the horizon, nor for the grid interpolation.
        let b = CornellBrdf::parse(&super::super::tests::synthetic()).unwrap();
        assert!(b.prepare_run(&Vec3::new(1.0, 0.0, 0.0)).is_none());
        let g = b.with_interpolation(Interpolation::Grid);
        assert!(g.prepare_run(&Vec3::new(0.0, 0.0, 1.0)).is_none());
    }

    /// Instructions per evaluation at one `ωo` on a coherent lattice of the projected disc (the
    /// envelope trees' image maps ask for 64 neighbouring points at a time), for cachegrind:
    /// `CORNELL_EVALS=N CORNELL_IMPL=eval|block|loop valgrind --tool=cachegrind --cache-sim=no
    /// TEST_BINARY block_cost_probe --ignored --exact`, at two `N`, the difference divided by the
    /// difference of `N` (`cayman`, θo = 57°; docs/benchmarks.md §30.3).
    #[test]
    #[ignore = "a cachegrind probe"]
    fn block_cost_probe() {
        let n: usize = std::env::var("CORNELL_EVALS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(10_000);
        let which = std::env::var("CORNELL_IMPL").unwrap_or_default();
        let Some((_, text)) = super::super::tests::shared_files().into_iter().nth(1) else {
            return;
        };
        let b = CornellBrdf::parse(&text).unwrap();
        let wo = crate::direction_from_radians(57f64.to_radians(), 0.0);
        // Rows of 64 points of a 256 × 256 lattice over the disc's square, off-disc skipped.
        let side = 256usize;
        let mut wis = Vec::with_capacity(n);
        let mut k = 0usize;
        while wis.len() < n {
            let (i, j) = (k % side, (k / side) % side);
            k += 1;
            let (x, y) = (
                (i as f64 + 0.5) / side as f64 * 2.0 - 1.0,
                (j as f64 + 0.5) / side as f64 * 2.0 - 1.0,
            );
            let r2 = x * x + y * y;
            if r2 < 1.0 {
                wis.push(Vec3::new(x, y, (1.0 - r2).sqrt()));
            }
        }
        let mut out = vec![0.0; 64];
        let mut sum = 0.0;
        for chunk in wis.chunks(64) {
            match which.as_str() {
                "eval" => {
                    for (o, wi) in out.iter_mut().zip(chunk) {
                        *o = b.eval(&wo, wi);
                    }
                }
                "block" => b.eval_block_at(&wo, chunk, &mut out[..chunk.len()]),
                // The loop alone, to subtract.
                _ => {
                    for (o, wi) in out.iter_mut().zip(chunk) {
                        *o = wi.z;
                    }
                }
            }
            sum += out[..chunk.len()].iter().sum::<f64>();
        }
        eprintln!("sum {sum}");
    }
}
