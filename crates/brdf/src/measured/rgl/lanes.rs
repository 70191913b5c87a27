//! RGL evaluations at one prepared slice, many `ωi` at once, in vector lanes (issue 29, item 3;
//! docs/benchmarks.md §25.3).
//!
//! [`eval_block`] returns, for each `ωi` of a block, **bit for bit** the value of the scalar
//! slice path (`RglBrdf::eval_on_slice`, itself `Brdf::eval` bit for bit): the same operations
//! in the same order on the same values, laid out as structure-of-arrays passes over blocks
//! of [`LANES`] directions so the compiler vectorises them:
//!
//! 1. the half vector `m = (ωo + ωi)/|ωo + ωi|`, its elevation `θm = 2 asin(|m − n|/2)`,
//!    `u_m = (√(2θm/π), frac((φm − φo + π)/2π))`, with branch-free copies of the `libm`
//!    crate's (FreeBSD msun's) `asin` and `atan2`: each range's formula computed in every
//!    lane and the lane's one selected, the same coefficients and operations, so the same
//!    bits; a lane that meets one of msun's special cases (`atan2` with a zero, unit or
//!    infinite argument, `|y/x|` beyond `2^±64`, `asin(1)`, an azimuth fraction outside
//!    `[0, 1)`) is recomputed by the scalar functions after the pass;
//! 2. the cells of `u_m` on the `vndf` slice and on `ndf`, then their corners read (a gather);
//! 3. the VNDF inversion `s = (F_{X|Y}(x | y), F_Y(y))` and `D(u_m)/(4σ)`, the cell of `s`
//!    on the luminance slice, its corners read (a gather);
//! 4. `f = max(Y(s) · D/(4σ), 0) / cos θi` (0 below the horizon or for `ωi = −ωo`).
//!
//! Rust never contracts `a·b + c` into a fused multiply-add, so the lanes round as the scalar
//! code does whatever the target features. [`eval_block`] dispatches at run time (`pulp`, as
//! `partition-sampler` and `envmap` do: the workspace forbids `unsafe`) to copies compiled for
//! AVX-512 or AVX2 + FMA when the host has them, else the baseline build.

// msun's constants as FreeBSD publishes them (decimal with their hex in libm's source); the
// bit-identity test against `libm` checks every one.
#![allow(clippy::excessive_precision, clippy::approx_constant)]

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::angles::{fast, theta_to_u};
use crate::geometry::Vec3;
use crate::measured::warp::{BilinearTable, Warp2DSlice};

/// Directions per structure-of-arrays block.
pub(super) const LANES: usize = 16;

/// What one run's block evaluation reads: the prepared `ωo` and its blended slice.
pub(super) struct BlockRun<'a> {
    /// `ωo`.
    pub(super) wo: Vec3,
    /// `(cos φo, sin φo)`.
    pub(super) cos_o: f64,
    /// See `cos_o`.
    pub(super) sin_o: f64,
    /// `4 σ(u_o)`.
    pub(super) four_sigma: f64,
    /// Whether the file applies `D/(4σ)`.
    pub(super) jacobian: bool,
    /// `ωo` above the horizon with a positive `4σ` (else every value is 0).
    pub(super) valid: bool,
    /// The `vndf` slice blended at θo.
    pub(super) vndf: &'a Warp2DSlice,
    /// The `ndf` table (one slice, read unblended).
    pub(super) ndf: &'a BilinearTable,
    /// The luminance slice blended at θo.
    pub(super) lum: &'a BilinearTable,
}

// msun's asin (libm 0.2.16 `asin.rs`).
const PIO2_HI: f64 = 1.570_796_326_794_896_558_00e+00;
const PIO2_LO: f64 = 6.123_233_995_736_766_035_87e-17;
const P_S0: f64 = 1.666_666_666_666_666_574_15e-01;
const P_S1: f64 = -3.255_658_186_224_009_154_05e-01;
const P_S2: f64 = 2.012_125_321_348_629_258_81e-01;
const P_S3: f64 = -4.005_553_450_067_941_140_27e-02;
const P_S4: f64 = 7.915_349_942_898_145_321_76e-04;
const P_S5: f64 = 3.479_331_075_960_211_675_70e-05;
const Q_S1: f64 = -2.403_394_911_734_414_218_78e+00;
const Q_S2: f64 = 2.020_945_760_233_505_694_71e+00;
const Q_S3: f64 = -6.882_839_716_054_532_930_30e-01;
const Q_S4: f64 = 7.703_815_055_590_193_527_91e-02;

// msun's atan and atan2 (libm 0.2.16 `atan.rs`, `atan2.rs`).
const ATANHI: [f64; 4] = [
    4.636_476_090_008_060_935_15e-01,
    7.853_981_633_974_482_789_99e-01,
    9.827_937_232_473_290_540_82e-01,
    1.570_796_326_794_896_558_00e+00,
];
const ATANLO: [f64; 4] = [
    2.269_877_745_296_168_709_24e-17,
    3.061_616_997_868_383_017_93e-17,
    1.390_331_103_123_099_845_16e-17,
    6.123_233_995_736_766_035_87e-17,
];
const AT: [f64; 11] = [
    3.333_333_333_333_293_180_27e-01,
    -1.999_999_999_987_648_324_76e-01,
    1.428_571_427_250_346_637_11e-01,
    -1.111_111_040_546_235_578_80e-01,
    9.090_887_133_436_506_561_96e-02,
    -7.691_876_205_044_829_994_95e-02,
    6.661_073_137_387_531_206_69e-02,
    -5.833_570_133_790_573_486_45e-02,
    4.976_877_994_615_932_360_17e-02,
    -3.653_157_274_421_691_552_70e-02,
    1.628_582_011_536_578_236_23e-02,
];
const PI_LO: f64 = 1.224_646_799_147_353_177_2e-16;

/// The positive `f64` whose high word is `hi` and low word 0: msun's `ix < hi` tests on a
/// non-negative argument are `x < high(hi)`.
#[inline(always)]
const fn high(hi: u64) -> f64 {
    f64::from_bits(hi << 32)
}

/// msun's `R(z)` of `asin`.
#[inline(always)]
fn comp_r(z: f64) -> f64 {
    let p = z * (P_S0 + z * (P_S1 + z * (P_S2 + z * (P_S3 + z * (P_S4 + z * P_S5)))));
    let q = 1.0 + z * (Q_S1 + z * (Q_S2 + z * (Q_S3 + z * Q_S4)));
    p / q
}

/// `asin(x)` for `x ∈ [0, 1)`, bit for bit `libm::asin`, branch-free; the flag is set when
/// `x` is outside `[0, 1)` (or NaN): the value is then not `libm`'s.
#[inline(always)]
pub(super) fn asin_lane(x: f64) -> (f64, bool) {
    let special = !(0.0..1.0).contains(&x);
    let small = x < high(0x3e50_0000);
    let lt_half = x < 0.5;
    let z = (1.0 - x) * 0.5;
    let r = comp_r(if lt_half { x * x } else { z });
    let below_half = x + x * r;
    let s = z.sqrt();
    let big = PIO2_HI - (2. * (s + s * r) - PIO2_LO);
    let f = f64::from_bits(s.to_bits() & 0xffff_ffff_0000_0000);
    let c = (z - f * f) / (s + f);
    let mid = 0.5 * PIO2_HI - (2.0 * s * r - (PIO2_LO - 2.0 * c) - (0.5 * PIO2_HI - 2.0 * f));
    let above_half = if x >= high(0x3fef_3333) { big } else { mid };
    let v = if small {
        x
    } else if lt_half {
        below_half
    } else {
        above_half
    };
    (v, special)
}

/// `atan(t)` for `t ∈ [0, 2^66)`, bit for bit `libm::atan`, branch-free; flagged outside.
#[inline(always)]
fn atan_pos(t: f64) -> (f64, bool) {
    let special = !(0.0..high(0x4410_0000)).contains(&t);
    let tiny = t < high(0x3fdc_0000);
    let (num, den, hi, lo) = if tiny {
        (t, 1.0, 0.0, 0.0)
    } else if t < high(0x3fe6_0000) {
        (2. * t - 1., 2. + t, ATANHI[0], ATANLO[0])
    } else if t < high(0x3ff3_0000) {
        (t - 1., t + 1., ATANHI[1], ATANLO[1])
    } else if t < high(0x4003_8000) {
        (t - 1.5, 1. + 1.5 * t, ATANHI[2], ATANLO[2])
    } else {
        (-1., t, ATANHI[3], ATANLO[3])
    };
    // `t / 1` is `t`: the id −1 range needs no reduction.
    let x = num / den;
    let z = x * x;
    let w = z * z;
    let s1 = z * (AT[0] + w * (AT[2] + w * (AT[4] + w * (AT[6] + w * (AT[8] + w * AT[10])))));
    let s2 = w * (AT[1] + w * (AT[3] + w * (AT[5] + w * (AT[7] + w * AT[9]))));
    let reduced = hi - (x * (s1 + s2) - lo - x);
    let v = if t < high(0x3e40_0000) {
        t
    } else if tiny {
        x - x * (s1 + s2)
    } else {
        reduced
    };
    (v, special)
}

/// `atan2(y, x)`, bit for bit `libm::atan2` where the flag is clear; the flag is set for
/// msun's special cases (a NaN, zero or infinite argument, `x = 1`, `|y/x| > 2^64`, or
/// `x < 0` with `|y/x| < 2^−64`), whose values this does not compute.
#[inline(always)]
pub(super) fn atan2_lane(y: f64, x: f64) -> (f64, bool) {
    let (bx, by) = (x.to_bits(), y.to_bits());
    let (ix, iy) = ((bx >> 32) & 0x7fff_ffff, (by >> 32) & 0x7fff_ffff);
    let (ax, ay) = (bx & 0x7fff_ffff_ffff_ffff, by & 0x7fff_ffff_ffff_ffff);
    let (neg_x, neg_y) = (bx >> 63 == 1, by >> 63 == 1);
    let special = x.is_nan()
        || y.is_nan()
        || x == 1.0
        || ay == 0
        || ax == 0
        || ix >= 0x7ff0_0000
        || iy >= 0x7ff0_0000
        || ix + (64 << 20) < iy
        || (neg_x && iy + (64 << 20) < ix);
    let (z, bad) = atan_pos((y / x).abs());
    let v = match (neg_x, neg_y) {
        (false, false) => z,
        (false, true) => -z,
        (true, false) => PI - (z - PI_LO),
        (true, true) => (z - PI_LO) - PI,
    };
    (v, special || bad)
}

/// Cell index (as `f64`) and fraction of `pos` on a grid axis of `n` points: `grid_cell`'s
/// `(pos.clamp(0, 1) · (n − 1))` with NaN as 0, the cell `⌊·⌋` capped at `n − 2` (`+ 0.0`
/// turns a `−0` floor into the scalar cast's `+0`), the fraction the remainder.
#[inline(always)]
fn axis_cell(pos: f64, n: usize) -> (f64, f64) {
    let s = pos.clamp(0.0, 1.0) * (n - 1) as f64;
    let s = if s.is_nan() { 0.0 } else { s };
    let c = (s.floor() + 0.0).min((n - 2) as f64);
    (c, s - c)
}

/// `2⁵²`: the `f64`s in `[2⁵², 2⁵³)` are the integers, spaced by 1.
const TWO52: f64 = 4_503_599_627_370_496.0;

/// The `usize` of an **integral** `c ∈ [0, 2⁵²)` (a cell index, or a row-major grid index
/// `cy·nx + cx` made of them, exact in `f64`): `c + 2⁵²` is exact and its bits are those of
/// `2⁵²` plus `c`. The value of `c as usize` for such `c`, in vector lanes (an integer
/// subtraction) where the saturating cast costs a dozen scalar instructions per lane.
#[inline(always)]
fn index(c: f64) -> u64 {
    (c + TWO52).to_bits().wrapping_sub(TWO52.to_bits())
}

/// The bilinear interpolant of corners `v = [v00, v10, v01, v11]` at fractions `(fx, fy)`:
/// `BilinearTable::eval_single`'s expression.
#[inline(always)]
fn bilinear(v: [f64; 4], fx: f64, fy: f64) -> f64 {
    let [v00, v10, v01, v11] = v;
    (1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11)
}

/// The four corners of the cell at row-major grid index `k` of a grid of `nx` columns.
#[inline(always)]
fn corners(d: &[f64], nx: usize, k: u64) -> [f64; 4] {
    // One slice over both rows: two bounds checks instead of four.
    let w = &d[k as usize..][..nx + 2];
    [w[0], w[1], w[nx], w[nx + 1]]
}

/// One block of at most [`LANES`] directions (see the module docs). The passes are written
/// so that each is one loop over all [`LANES`] lanes without a branch on lane data (the
/// compiler vectorises them; a branch on the run's constants is taken once per pass): the
/// cells' grid indices are made in the lanes by [`index`], and only the gathers read lane by
/// lane.
#[inline(always)]
fn block(run: &BlockRun<'_>, wi: &[Vec3], out: &mut [f64]) {
    let n = wi.len().min(out.len()).min(LANES);
    let z0 = [0.0; LANES];
    let (mut u0, mut u1, mut wz, mut norms) = (z0, z0, z0, z0);
    let mut special = [0u64; LANES];
    let (wox, woy, woz) = (run.wo.x, run.wo.y, run.wo.z);
    let (cos_o, sin_o) = (run.cos_o, run.sin_o);
    // Pass 1: half vector and its angles (padded lanes evaluate the normal).
    let (mut xs, mut ys, mut zs) = (z0, z0, [1.0; LANES]);
    for j in 0..n {
        (xs[j], ys[j], zs[j]) = (wi[j].x, wi[j].y, wi[j].z);
    }
    for j in 0..LANES {
        let s = [wox + xs[j], woy + ys[j], woz + zs[j]];
        let norm = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
        let h = [s[0] / norm, s[1] / norm, s[2] / norm];
        let y = cos_o * s[1] - sin_o * s[0];
        let x = cos_o * s[0] + sin_o * s[1];
        let dist = (h[0] * h[0] + h[1] * h[1] + (h[2] - 1.0) * (h[2] - 1.0)).sqrt();
        let (a, bad_a) = asin_lane((0.5 * dist).clamp(-1.0, 1.0));
        let theta: f64 = 2.0 * a;
        u0[j] = (theta.max(0.0) / FRAC_PI_2).sqrt();
        let (rel, bad_r) = atan2_lane(y, x);
        let u = (rel + PI) / TAU;
        let in_range = (0.0..1.0).contains(&u);
        u1[j] = if in_range { u } else { 0.0 };
        special[j] = u64::from(bad_a | bad_r | !in_range);
        wz[j] = zs[j];
        norms[j] = norm;
    }
    let valid = |j: usize| run.valid && wz[j] > 0.0 && norms[j] > 1e-12;
    // msun's special cases, one lane at a time, by the scalar path's functions (rare: one
    // test per block when there are none).
    if special.iter().fold(0, |a, &s| a | s) != 0 {
        for j in 0..n {
            if special[j] != 0 && valid(j) {
                let s = run.wo + wi[j];
                let h = s / s.norm();
                let y = cos_o * s.y - sin_o * s.x;
                let x = cos_o * s.x + sin_o * s.y;
                u0[j] = theta_to_u(fast::elevation(&h));
                u1[j] = fast::unit_azimuth(fast::atan2(y, x));
            }
        }
    }
    // Pass 2: cells of u_m on the vndf slice and on ndf, as grid indices.
    let (vnx, vny, _area_scale, cells, rows) = run.vndf.parts();
    let (nnx, nny, ndf) = run.ndf.parts();
    let (mut fx, mut fy) = (z0, z0);
    let (mut nfx, mut nfy) = (z0, z0);
    let (mut vk, mut vrow, mut nk) = ([0u64; LANES], [0u64; LANES], [0u64; LANES]);
    let (vnx_f, nnx_f) = (vnx as f64, nnx as f64);
    for j in 0..LANES {
        let (cx, fxj) = axis_cell(u0[j], vnx);
        let (cy, fyj) = axis_cell(u1[j], vny);
        let (ncx, nfxj) = axis_cell(u0[j], nnx);
        let (ncy, nfyj) = axis_cell(u1[j], nny);
        (fx[j], fy[j], nfx[j], nfy[j]) = (fxj, fyj, nfxj, nfyj);
        vk[j] = index(cy * vnx_f + cx);
        vrow[j] = index(cy);
        nk[j] = index(ncy * nnx_f + ncx);
    }
    // Gather: the inversion's grid points and rows, ndf's corners.
    let mut v = [[0.0; 4]; LANES];
    let mut along = [[0.0; 2]; LANES];
    let mut row = [[0.0; 3]; LANES];
    for j in 0..LANES {
        // One slice over both rows: two bounds checks instead of four.
        let w = &cells[vk[j] as usize..][..vnx + 2];
        let [v00, a0] = w[0];
        let [v01, a1] = w[vnx];
        v[j] = [v00, w[1][0], v01, w[vnx + 1][0]];
        along[j] = [a0, a1];
        let r = &rows[vrow[j] as usize..][..2];
        let [m0, r0] = r[0];
        row[j] = [m0, r0, r[1][1]];
    }
    // Pass 3: D/(4σ) (its corners gathered first), the inversion, the cell of s on the
    // luminance slice.
    let mut factor = [1.0; LANES];
    if run.jacobian {
        let mut nd = [[0.0; 4]; LANES];
        for j in 0..LANES {
            nd[j] = corners(ndf, nnx, nk[j]);
        }
        for j in 0..LANES {
            factor[j] = bilinear(nd[j], nfx[j], nfy[j]) / run.four_sigma;
        }
    }
    let (lnx, lny, lum) = run.lum.parts();
    let lnx_f = lnx as f64;
    let (mut lk, mut lfx, mut lfy) = ([0u64; LANES], z0, z0);
    for j in 0..LANES {
        let (fx, fy) = (fx[j], fy[j]);
        let [v00, v10, v01, v11] = v[j];
        let [along0, along1] = along[j];
        let [m0, r0, r1] = row[j];
        let c0 = (1.0 - fy) * v00 + fy * v01;
        let c1 = (1.0 - fy) * v10 + fy * v11;
        let row_total = (1.0 - fy) * r0 + fy * r1;
        let al = fx * (c0 + 0.5 * fx * (c1 - c0)) + (1.0 - fy) * along0 + fy * along1;
        // The quotient in every lane, kept where the row has mass (a select, no branch).
        let q = al / row_total;
        let ux = if row_total > 0.0 { q } else { 0.0 };
        let uy = fy * (r0 + 0.5 * fy * (r1 - r0)) + m0;
        let (lcx, lfxj) = axis_cell(ux, lnx);
        let (lcy, lfyj) = axis_cell(uy, lny);
        (lfx[j], lfy[j]) = (lfxj, lfyj);
        lk[j] = index(lcy * lnx_f + lcx);
    }
    // Gather: the luminance corners; pass 4: the value.
    let mut lc = [[0.0; 4]; LANES];
    for j in 0..LANES {
        lc[j] = corners(lum, lnx, lk[j]);
    }
    let mut f = z0;
    for j in 0..LANES {
        let y = bilinear(lc[j], lfx[j], lfy[j]);
        let value = (y * factor[j]).max(0.0) / wz[j];
        f[j] = if wz[j] > 0.0 && norms[j] > 1e-12 {
            value
        } else {
            0.0
        };
    }
    if !run.valid {
        f = z0;
    }
    if n == LANES {
        out[..LANES].copy_from_slice(&f);
    } else {
        out[..n].copy_from_slice(&f[..n]);
    }
}

/// Every block of `wi` through [`block`].
#[inline(always)]
fn blocks(run: &BlockRun<'_>, wi: &[Vec3], out: &mut [f64]) {
    for (w, o) in wi.chunks(LANES).zip(out.chunks_mut(LANES)) {
        block(run, w, o);
    }
}

/// [`blocks`] as a `pulp` operation (inlined into, and compiled for, each instruction set
/// `pulp` dispatches to).
struct Blocks<'a, 'r> {
    run: &'a BlockRun<'r>,
    wi: &'a [Vec3],
    out: &'a mut [f64],
}

impl pulp::WithSimd for Blocks<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        blocks(self.run, self.wi, self.out);
    }
}

/// `out[k] = f_r(ωo, wi[k])` at the run's slice for `k < min(wi.len(), out.len())`, bit for bit
/// the scalar slice path, compiled for the instruction set `level` (`pulp`'s runtime
/// dispatch: AVX-512 F/VL/DQ/BW/CD as `V4`, AVX2 + FMA as `V3`, or the baseline).
pub(super) fn eval_block_at(level: pulp::Arch, run: &BlockRun<'_>, wi: &[Vec3], out: &mut [f64]) {
    level.dispatch(Blocks { run, wi, out });
}

/// [`eval_block_at`] with the host's best instruction set.
#[inline]
pub(super) fn eval_block(run: &BlockRun<'_>, wi: &[Vec3], out: &mut [f64]) {
    eval_block_at(pulp::Arch::new(), run, wi, out);
}

/// The instruction-set levels of this host, the baseline first (for tests).
#[cfg(test)]
pub(super) fn levels() -> Vec<pulp::Arch> {
    let mut l = vec![pulp::Arch::Scalar];
    #[cfg(target_arch = "x86_64")]
    {
        l.extend(pulp::x86::V3::try_new().map(pulp::Arch::V3));
        l.extend(pulp::x86::V4::try_new().map(pulp::Arch::V4));
    }
    l
}
