//! Piecewise-constant densities on a `W × H` grid, optionally times a smooth per-row factor,
//! with exact region bounds and integrals from max and sum pyramids.

use std::f64::consts::PI;
use std::sync::OnceLock;

use crate::contract::Point2;
use crate::density::{
    Density, DensityShape, IntegralSource, ProviderKind, RegionEstimate, RegionStats,
};
use crate::error::DensityError;
use crate::index::{floor_index, index_to_f64};
use crate::pyramid::{CellSource, Pyramid, snap};
use crate::rect::{Domain, Rect};

/// A smooth factor `g(t) ≥ 0` of the normalised row coordinate `t = (y − y0)/(y1 − y0) ∈ [0, 1]`
/// that multiplies a tabulated density: `f(x, y) = v[i, j] · g(t)`.
///
/// Implementations give the exact maximum and integral over any `[ta, tb] ⊆ [0, 1]`, so the
/// region statistics stay exact.
pub trait RowFactor: Sync {
    /// `g(t)`.
    fn eval(&self, t: f64) -> f64;
    /// An upper bound of `eval(t)` for every floating-point `t ∈ [ta, tb]` (the exact maximum,
    /// widened only by rounding margins).
    fn max_on(&self, ta: f64, tb: f64) -> f64;
    /// `∫_{ta}^{tb} g(t) dt`.
    fn integral(&self, ta: f64, tb: f64) -> f64;
    /// `out[k] = self.eval(ts[k])` for every `k` (the shorter length wins), bit for bit: the
    /// block path of [`TabulatedDensity::eval_block`] calls it once per block of row
    /// coordinates so that an implementation can evaluate them in vector lanes.
    #[inline]
    fn eval_block(&self, ts: &[f64], out: &mut [f64]) {
        for (o, &t) in out.iter_mut().zip(ts) {
            *o = self.eval(t);
        }
    }
}

/// The constant factor `g(t) = 1` (a plain piecewise-constant density).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UnitRows;

impl RowFactor for UnitRows {
    #[inline]
    fn eval(&self, _t: f64) -> f64 {
        1.0
    }
    #[inline]
    fn max_on(&self, _ta: f64, _tb: f64) -> f64 {
        1.0
    }
    #[inline]
    fn integral(&self, ta: f64, tb: f64) -> f64 {
        tb - ta
    }
}

/// `g(t) = sin(π t)`: the Jacobian of the latitude-longitude map, so a map with
/// `f(u, v) = Y(u, v) · sin(π v)` samples directions ∝ luminance with respect to solid angle
/// (`p_σ = p_A(u, v) / (2π² sin θ)` for `(u, v) ∈ [0, 1]²`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SinPiRows;

/// Taylor coefficients of `sin(π r) = Σ_k c_k r^(2k+1)`, `c_k = (−1)^k π^(2k+1) / (2k+1)!`.
/// Eleven terms: on `|r| ≤ 1/2` the first omitted term is `(π/2)^23 / 23! ≈ 1.3·10⁻¹⁸`.
const SIN_PI_COEFFS: [f64; 11] = {
    let mut c = [0.0; 11];
    let mut term = PI; // π^(2k+1) / (2k+1)! with its sign
    let mut k = 0;
    while k < 11 {
        c[k] = term;
        let n = (2 * k + 2) as f64;
        term = -term * PI * PI / (n * (n + 1.0));
        k += 1;
    }
    c
};

/// `sin(π t)` for `t ∈ [0, 1]` without a call to `sin`: folded to `r = min(t, 1 − t) ∈ [0, ½]`
/// (`1 − t` is exact there, Sterbenz) and evaluated as the odd polynomial of
/// [`SIN_PI_COEFFS`] by Horner's rule in `r²`; within a few ulps of `(π t).sin()` (tested),
/// clamped to `[0, 1]`. Other `t` use `(π t).sin()`.
#[inline(always)]
pub fn sin_pi_unit(t: f64) -> f64 {
    if !(0.0..=1.0).contains(&t) {
        return (PI * t).sin();
    }
    sin_pi_poly(t)
}

/// The polynomial branch of [`sin_pi_unit`] for `t ∈ [0, 1]`, free of branches (the fold and
/// the clamp are selects) so that a loop of it vectorises. Outside `[0, 1]` its value is not
/// `sin(π t)`.
#[inline(always)]
fn sin_pi_poly(t: f64) -> f64 {
    let r = if t > 0.5 { 1.0 - t } else { t };
    let r2 = r * r;
    let c = &SIN_PI_COEFFS;
    let mut p = c[10];
    let mut k = 10;
    while k > 0 {
        k -= 1;
        p = p * r2 + c[k];
    }
    (r * p).clamp(0.0, 1.0)
}

/// `out[k] = `[`sin_pi_unit`]`(ts[k])` for every `k` (the shorter length wins), bit for bit:
/// the polynomial of every entry in one branch-free loop, compiled for the best vector
/// extension of this CPU by `pulp`'s runtime dispatch (AVX2 where present: four `f64` lanes;
/// the x86-64 baseline otherwise). The loop uses only IEEE multiplies, adds and selects —
/// never fused multiply-adds, which Rust does not contract — so every path returns the same
/// numbers as the scalar function. Entries outside `[0, 1]` are then redone by `sin`, as
/// [`sin_pi_unit`] does.
pub fn sin_pi_unit_block(ts: &[f64], out: &mut [f64]) {
    let n = ts.len().min(out.len());
    let (ts, out) = (&ts[..n], &mut out[..n]);
    let outside = pulp::Arch::new().dispatch(SinPiBlock { ts, out });
    if outside != 0 {
        for (o, &t) in out.iter_mut().zip(ts) {
            if !(0.0..=1.0).contains(&t) {
                *o = (PI * t).sin();
            }
        }
    }
}

/// The loop of [`sin_pi_unit_block`] as a `pulp` operation (inlined into, and compiled for,
/// each instruction set `pulp` dispatches to); returns how many `ts` lie outside `[0, 1]`.
struct SinPiBlock<'a> {
    ts: &'a [f64],
    out: &'a mut [f64],
}

impl pulp::WithSimd for SinPiBlock<'_> {
    type Output = usize;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> usize {
        let mut outside = 0usize;
        for (o, &t) in self.out.iter_mut().zip(self.ts) {
            *o = sin_pi_poly(t);
            outside += usize::from(!(0.0..=1.0).contains(&t));
        }
        outside
    }
}

impl RowFactor for SinPiRows {
    /// [`sin_pi_unit`]`(t)` (the polynomial route: a quarter of the cost of `sin` on the
    /// environment-map hot path, same value to a few ulps).
    #[inline]
    fn eval(&self, t: f64) -> f64 {
        sin_pi_unit(t)
    }
    /// [`sin_pi_unit_block`]: the same numbers as [`Self::eval`], several per instruction.
    #[inline]
    fn eval_block(&self, ts: &[f64], out: &mut [f64]) {
        sin_pi_unit_block(ts, out);
    }
    fn max_on(&self, ta: f64, tb: f64) -> f64 {
        // sin(πt) is unimodal on [0, 1] with its peak at t = 1/2.
        if ta <= 0.5 && tb >= 0.5 {
            return 1.0;
        }
        let m = (PI * ta).sin().max((PI * tb).sin());
        // Margin against non-monotone rounding of `sin`; `sin ≤ 1` always.
        (m * (1.0 + 1e-12) + 1e-300).min(1.0)
    }
    fn integral(&self, ta: f64, tb: f64) -> f64 {
        // (cos πa − cos πb)/π written without cancellation.
        2.0 * (0.5 * PI * (ta + tb)).sin() * (0.5 * PI * (tb - ta)).sin() / PI
    }
}

/// A piecewise-constant density on a `W × H` grid of equal cells over a rectangle, times an
/// optional row factor: `f(x, y) = v[j·W + i] · g(t)` on cell `(i, j)`, with row 0 on the `y0`
/// side and `t = (y − y0)/(y1 − y0)`.
///
/// Region statistics are **exact** (up to rounding): the maximum and the integral of `f` over
/// any rectangle come from max and sum pyramids (O(1) for rectangles aligned on the grid's
/// power-of-two blocks, O(perimeter) otherwise); partially covered cells are integrated exactly
/// through [`RowFactor::integral`]. Integrals are with respect to area in domain units.
#[derive(Clone)]
pub struct TabulatedDensity<R: RowFactor = UnitRows> {
    width: usize,
    height: usize,
    values: Vec<f64>,
    domain: Rect,
    factor: R,
    /// `max g` on row `j` (times nothing: multiply by the cell value).
    row_max: Vec<f64>,
    /// `∫ g dt` over row `j`, times the domain height and the cell width: the integral of `f`
    /// over cell `(i, j)` is `v · row_int[j]`.
    row_int: Vec<f64>,
    /// Cells per domain unit in x and y.
    sx: f64,
    sy: f64,
    inv_h: f64,
    /// `cell width · domain height`, the area factor of a partial cell.
    area_unit: f64,
    /// `Σ_i v[i, j]` per row.
    row_sum: Vec<f64>,
    /// Built on the first region query (a density used only for pointwise evaluation or a
    /// re-attached tree never pays for it).
    pyramid: OnceLock<Pyramid>,
    total: f64,
}

impl TabulatedDensity<UnitRows> {
    /// A piecewise-constant density with `width × height` cells over `domain`; `values` is
    /// row-major with row 0 on the `y0` side.
    ///
    /// Errors: empty grid, length mismatch, a NaN / negative / infinite value (the first one is
    /// named), an invalid domain, or an all-zero grid. Building is O(W·H).
    pub fn new(
        width: usize,
        height: usize,
        values: Vec<f64>,
        domain: Rect,
    ) -> Result<Self, DensityError> {
        if width == 0 || height == 0 {
            return Err(DensityError::EmptyGrid { width, height });
        }
        if width > u32::MAX as usize / 2 || height > u32::MAX as usize / 2 {
            return Err(DensityError::GridTooLarge { width, height });
        }
        let expected = width
            .checked_mul(height)
            .ok_or(DensityError::GridTooLarge { width, height })?;
        if values.len() != expected {
            return Err(DensityError::LengthMismatch {
                expected,
                got: values.len(),
            });
        }
        if !domain.is_valid() {
            return Err(DensityError::InvalidDomain(domain));
        }
        let mut row_sum = Vec::with_capacity(height);
        for (row, r) in values.chunks_exact(width).enumerate() {
            let mut s = 0.0;
            for (column, &value) in r.iter().enumerate() {
                if !(value.is_finite() && value >= 0.0) {
                    return Err(DensityError::InvalidValue {
                        index: row * width + column,
                        column,
                        row,
                        value,
                    });
                }
                s += value;
            }
            row_sum.push(s);
        }
        Self::assemble(width, height, values, row_sum, domain, UnitRows)
    }
}

impl<R: RowFactor> TabulatedDensity<R> {
    /// The same grid times the row factor `g` (e.g. [`SinPiRows`]); O(H), the pyramids are
    /// (re)built lazily.
    ///
    /// Errors: the factor returns an invalid max or integral on some row, or the product is
    /// zero everywhere.
    pub fn with_row_factor<G: RowFactor>(self, g: G) -> Result<TabulatedDensity<G>, DensityError> {
        TabulatedDensity::assemble(
            self.width,
            self.height,
            self.values,
            self.row_sum,
            self.domain,
            g,
        )
    }

    fn assemble(
        width: usize,
        height: usize,
        values: Vec<f64>,
        row_sum: Vec<f64>,
        domain: Rect,
        factor: R,
    ) -> Result<Self, DensityError> {
        let hf = height as f64;
        let cell_w = domain.width() / width as f64;
        let mut row_max = Vec::with_capacity(height);
        let mut row_int = Vec::with_capacity(height);
        for row in 0..height {
            let (ta, tb) = (row as f64 / hf, (row + 1) as f64 / hf);
            let m = factor.max_on(ta, tb);
            let i = factor.integral(ta, tb);
            if !(m.is_finite() && m >= 0.0) {
                return Err(DensityError::InvalidRowFactor {
                    row,
                    what: "max",
                    value: m,
                });
            }
            if !(i.is_finite() && i >= 0.0) {
                return Err(DensityError::InvalidRowFactor {
                    row,
                    what: "integral",
                    value: i,
                });
            }
            row_max.push(m);
            row_int.push(i * domain.height() * cell_w);
        }
        let total: f64 = row_sum.iter().zip(&row_int).map(|(s, i)| s * i).sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(DensityError::ZeroTotal);
        }
        Ok(Self {
            width,
            height,
            values,
            domain,
            factor,
            row_max,
            row_int,
            sx: width as f64 / domain.width(),
            sy: hf / domain.height(),
            inv_h: 1.0 / hf,
            area_unit: cell_w * domain.height(),
            row_sum,
            pyramid: OnceLock::new(),
            total,
        })
    }

    fn pyramid(&self) -> &Pyramid {
        self.pyramid
            .get_or_init(|| Pyramid::build(self.width, self.height, self))
    }

    /// Grid width `W`.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Grid height `H`.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The cell values, row-major, row 0 on the `y0` side.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The domain rectangle.
    pub fn rect(&self) -> Rect {
        self.domain
    }

    /// The row factor.
    pub fn row_factor(&self) -> &R {
        &self.factor
    }

    /// `∫_D f dA`, exact up to rounding (row sums times the rows' factor integrals).
    pub fn total_integral(&self) -> f64 {
        self.total
    }
}

impl<R: RowFactor> std::fmt::Debug for TabulatedDensity<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TabulatedDensity")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("domain", &self.domain)
            .field("row_factor", &std::any::type_name::<R>())
            .field("total", &self.total)
            .finish_non_exhaustive()
    }
}

impl<R: RowFactor> CellSource for TabulatedDensity<R> {
    #[inline]
    fn full(&self, i: usize, j: usize) -> (f64, f64) {
        let v = self.values[j * self.width + i];
        (v * self.row_max[j], v * self.row_int[j])
    }

    fn partial(&self, i: usize, j: usize, xa: f64, xb: f64, ya: f64, yb: f64) -> (f64, f64) {
        let v = self.values[j * self.width + i];
        let (ta, tb) = (ya * self.inv_h, yb * self.inv_h);
        let m = v * self.factor.max_on(ta, tb);
        let s = v * (xb - xa) * self.area_unit * self.factor.integral(ta, tb).max(0.0);
        (m, s)
    }
}

/// Points per chunk of [`TabulatedDensity::eval_block`] (the quadtree sampler's block size).
const EVAL_CHUNK: usize = 64;

impl<R: RowFactor> TabulatedDensity<R> {
    /// Index of the cell of `p` in `values` and `p`'s scaled row coordinate `fy ∈ [0, H]`;
    /// `None` outside the domain.
    #[inline(always)]
    fn cell_index(&self, p: Point2) -> Option<(usize, f64)> {
        let fx = (p[0] - self.domain.x0) * self.sx;
        let fy = (p[1] - self.domain.y0) * self.sy;
        let (w, h) = (index_to_f64(self.width), index_to_f64(self.height));
        if !(fx >= 0.0 && fx <= w && fy >= 0.0 && fy <= h) {
            return None;
        }
        let i = floor_index(fx, self.width - 1);
        let j = floor_index(fy, self.height - 1);
        Some((j * self.width + i, fy))
    }
}

impl<R: RowFactor> Density for TabulatedDensity<R> {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        match self.cell_index(p) {
            Some((k, fy)) => self.values[k] * self.factor.eval(fy * self.inv_h),
            None => 0.0,
        }
    }

    /// Four passes per chunk of [`EVAL_CHUNK`] points, in structure-of-arrays form and
    /// compiled for the best vector extension of this CPU (`pulp`'s runtime dispatch, AVX2
    /// where present): the cell indices and row coordinates `t` of the chunk (arithmetic and
    /// compares only, in vector lanes), then the cell values (independent loads, so the cache
    /// misses of a chunk overlap), then the row factors in one [`RowFactor::eval_block`] call
    /// (vector lanes for [`SinPiRows`]), then the products. Same values as [`Self::eval`], bit
    /// for bit: the same expressions in the same order, no fused multiply-adds, and the cell
    /// index truncated through `i32` — equal to [`floor_index`]'s `u32` for the points inside
    /// the grid (`0 ≤ fx ≤ W < 2³¹`, checked at construction); points outside get no load.
    #[inline]
    fn eval_block(&self, points: &[Point2], out: &mut [f64]) {
        pulp::Arch::new().dispatch(EvalBlock {
            density: self,
            points,
            out,
        });
    }
}

/// [`TabulatedDensity::eval_block`]'s passes as a `pulp` operation (inlined into, and compiled
/// for, each instruction set `pulp` dispatches to).
struct EvalBlock<'a, R: RowFactor> {
    density: &'a TabulatedDensity<R>,
    points: &'a [Point2],
    out: &'a mut [f64],
}

impl<R: RowFactor> pulp::WithSimd for EvalBlock<'_, R> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let d = self.density;
        let mut cells = [0u64; EVAL_CHUNK];
        let mut ts = [0.0f64; EVAL_CHUNK];
        let mut gs = [0.0f64; EVAL_CHUNK];
        for (pc, oc) in self
            .points
            .chunks(EVAL_CHUNK)
            .zip(self.out.chunks_mut(EVAL_CHUNK))
        {
            let n = pc.len().min(oc.len());
            d.cells_of(&pc[..n], &mut cells[..n], &mut ts[..n]);
            for (o, &k) in oc[..n].iter_mut().zip(&cells[..n]) {
                // `u64::MAX` (outside) finds no value: the marker −1 (values are ≥ 0, checked
                // at construction).
                *o = usize::try_from(k)
                    .ok()
                    .and_then(|k| d.values.get(k))
                    .copied()
                    .unwrap_or(-1.0);
            }
            d.factor.eval_block(&ts[..n], &mut gs[..n]);
            for (o, &g) in oc[..n].iter_mut().zip(&gs[..n]) {
                *o = if *o < 0.0 { 0.0 } else { *o * g };
            }
        }
    }
}

impl<R: RowFactor> TabulatedDensity<R> {
    /// For each point: its index in `values` ([`Self::cell_index`]'s), or `u64::MAX` outside
    /// the domain, and its row coordinate `t = fy / H` (what [`Density::eval`] passes to the
    /// row factor). Free of branches (compares combined by `&`, selects), so the loop
    /// vectorises; the cell index goes through `i32`, which for `0 ≤ fx ≤ W < 2³¹` truncates
    /// as [`floor_index`]'s `u32` does.
    #[inline(always)]
    fn cells_of(&self, points: &[Point2], cells: &mut [u64], ts: &mut [f64]) {
        let (x0, y0, sx, sy, inv_h) =
            (self.domain.x0, self.domain.y0, self.sx, self.sy, self.inv_h);
        let (w, h) = (index_to_f64(self.width), index_to_f64(self.height));
        // `width, height ≤ u32::MAX / 2` (checked at construction): the last indices fit i32.
        let last_i = i32::try_from(self.width - 1).unwrap_or(i32::MAX);
        let last_j = i32::try_from(self.height - 1).unwrap_or(i32::MAX);
        let width = self.width as u64;
        for ((c, t), p) in cells.iter_mut().zip(ts.iter_mut()).zip(points) {
            let fx = (p[0] - x0) * sx;
            let fy = (p[1] - y0) * sy;
            *t = fy * inv_h;
            let inside = (fx >= 0.0) & (fx <= w) & (fy >= 0.0) & (fy <= h);
            let i = (fx as i32).min(last_i) as u32;
            let j = (fy as i32).min(last_j) as u32;
            let cell = u64::from(j) * width + u64::from(i);
            *c = if inside { cell } else { u64::MAX };
        }
    }
}

impl<R: RowFactor> RegionStats for TabulatedDensity<R> {
    fn domain(&self) -> Domain {
        Domain::Rect(self.domain)
    }

    fn region(&self, cell: &Rect) -> RegionEstimate {
        let (wf, hf) = (self.width as f64, self.height as f64);
        let xa = snap((cell.x0 - self.domain.x0) * self.sx, wf);
        let xb = snap((cell.x1 - self.domain.x0) * self.sx, wf);
        let ya = snap((cell.y0 - self.domain.y0) * self.sy, hf);
        let yb = snap((cell.y1 - self.domain.y0) * self.sy, hf);
        let (max_bound, integral) = self.pyramid().query(self, xa, xb, ya, yb);
        RegionEstimate {
            max_bound,
            integral,
            integral_rel_err: Some(0.0),
        }
    }

    fn integral_source(&self) -> IntegralSource {
        IntegralSource::Exact
    }

    fn total_rel_err(&self) -> Option<f64> {
        Some(0.0)
    }

    fn shape(&self) -> DensityShape {
        DensityShape {
            kind: ProviderKind::Tabulated,
            domain: Domain::Rect(self.domain),
            dims: [self.width as u64, self.height as u64],
            fingerprint: self.total.to_bits(),
        }
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + 8 * (self.values.capacity()
                + self.row_max.capacity()
                + self.row_int.capacity()
                + self.row_sum.capacity())
            + self.pyramid.get().map_or(0, Pyramid::bytes_used)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_rows_integral_and_max() {
        let g = SinPiRows;
        assert!((g.integral(0.0, 1.0) - 2.0 / PI).abs() < 1e-15);
        assert!((g.integral(0.1, 0.3) - ((0.1 * PI).cos() - (0.3 * PI).cos()) / PI).abs() < 1e-15);
        assert_eq!(g.max_on(0.2, 0.7), 1.0);
        assert!(g.max_on(0.1, 0.2) >= (0.2 * PI).sin());
    }

    #[test]
    fn polynomial_sin_pi_matches_libm() {
        // Dense grid plus the ends and the fold point: a few ulps of `sin` of the folded
        // argument (`(π t).sin()` itself is inaccurate near t = 1, where `π t` rounds: it
        // gives 1.2e-16 at t = 1), and never above the bound `max_on` reports for the pixel
        // row around it.
        let n = 1_000_000;
        let mut worst = 0.0f64;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let folded = if t > 0.5 { 1.0 - t } else { t };
            let (a, b) = (sin_pi_unit(t), (PI * folded).sin());
            let err = (a - b).abs() / b.max(f64::MIN_POSITIVE);
            if b > 0.0 {
                worst = worst.max(err);
            }
            let row = ((t * 512.0) as usize).min(511);
            let (ta, tb) = (row as f64 / 512.0, (row + 1) as f64 / 512.0);
            assert!(a <= SinPiRows.max_on(ta, tb), "t = {t}");
        }
        assert!(worst < 1e-15, "worst relative error {worst:e}");
        assert_eq!(sin_pi_unit(0.0), 0.0);
        assert_eq!(sin_pi_unit(1.0), 0.0);
        assert_eq!(sin_pi_unit(0.5), 1.0);
        assert_eq!(sin_pi_unit(1.5), (1.5 * PI).sin());
    }

    #[test]
    fn sin_pi_block_is_sin_pi_unit_bit_for_bit() {
        // The vector loop against the scalar function on a dense grid, the fold point and
        // its neighbours, the ends, signed zero, values outside [0, 1] (redone by `sin`) and
        // NaN, at every length up to 70 and offsets that leave a lane remainder.
        let mut ts: Vec<f64> = (0..=20_000).map(|k| k as f64 / 20_000.0).collect();
        for x in [0.5f64, 0.0, 1.0, 0.25, 0.75] {
            ts.extend([x, x.next_up(), x.next_down()]);
        }
        ts.extend([-0.0, -0.1, 1.5, -3.0, 1e300, f64::NAN, f64::INFINITY]);
        let mut out = vec![f64::NAN; ts.len()];
        sin_pi_unit_block(&ts, &mut out);
        for (t, o) in ts.iter().zip(&out) {
            assert_eq!(o.to_bits(), sin_pi_unit(*t).to_bits(), "t = {t:e}");
        }
        for len in 0..70 {
            for off in [0, 1, 3] {
                let part = &ts[20_000 - off - len..20_000 - off];
                let mut o = vec![0.0; len];
                SinPiRows.eval_block(part, &mut o);
                for (t, g) in part.iter().zip(&o) {
                    assert_eq!(g.to_bits(), SinPiRows.eval(*t).to_bits(), "t = {t:e}");
                }
            }
        }
    }

    #[test]
    fn eval_block_is_eval() {
        let (w, h) = (7usize, 5usize);
        let vals: Vec<f64> = (0..w * h).map(|k| (k % 4) as f64 * 0.5).collect();
        let d = TabulatedDensity::new(w, h, vals, Rect::new(-1.0, 2.0, 3.0, 4.5))
            .unwrap()
            .with_row_factor(SinPiRows)
            .unwrap();
        let mut pts: Vec<Point2> = (0..400)
            .map(|k| [-1.5 + 0.013 * k as f64, 1.8 + 0.0071 * k as f64])
            .collect();
        // The domain's edges and their float neighbours (fx = W and fy = H are inside, in the
        // last cell), cell edges, signed zeros, NaN and infinities.
        let (xs, ys): ([f64; 4], [f64; 4]) = ([-1.0, 3.0, 1.0 / 7.0, 0.0], [2.0, 4.5, 2.5, 0.0]);
        for &x in &xs {
            for &y in &ys {
                for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (-1.0, -1.0)] {
                    let nx = if dx > 0.0 {
                        x.next_up()
                    } else if dx < 0.0 {
                        x.next_down()
                    } else {
                        x
                    };
                    let ny = if dy > 0.0 {
                        y.next_up()
                    } else if dy < 0.0 {
                        y.next_down()
                    } else {
                        y
                    };
                    pts.push([nx, ny]);
                }
            }
        }
        pts.extend([
            [-0.0, 3.0],
            [1.0, -0.0],
            [f64::NAN, 3.0],
            [1.0, f64::NAN],
            [f64::INFINITY, 3.0],
            [1.0, f64::NEG_INFINITY],
        ]);
        let mut out = vec![f64::NAN; pts.len()];
        d.eval_block(&pts, &mut out);
        for (p, o) in pts.iter().zip(&out) {
            assert_eq!(o.to_bits(), d.eval(*p).to_bits(), "{p:?}");
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_and_avx512_levels_give_the_scalar_numbers() {
        // `eval_block` and `sin_pi_unit_block` run only the best level `pulp` finds; this runs
        // their operations at AVX2 (`V3`) and AVX-512 (`V4`) where the CPU has them, against
        // the scalar functions, bit for bit.
        let mut ts: Vec<f64> = (0..=4000).map(|k| k as f64 / 4000.0).collect();
        ts.extend([
            0.5f64.next_up(),
            0.5f64.next_down(),
            1.0f64.next_down(),
            -0.0,
        ]);
        let d = TabulatedDensity::new(9, 5, (0..45).map(|k| (k % 7) as f64).collect(), Rect::UNIT)
            .unwrap()
            .with_row_factor(SinPiRows)
            .unwrap();
        let pts: Vec<Point2> = (0..1000)
            .map(|k| [-0.05 + 0.0011 * k as f64, 1.02 - 0.00105 * k as f64])
            .chain([
                [1.0, 1.0],
                [0.0, 0.0],
                [f64::NAN, 0.5],
                [0.5, 1.0f64.next_up()],
            ])
            .collect();
        let check = |level: &str,
                     vectorize: &dyn Fn(SinPiBlock<'_>) -> usize,
                     eval: &dyn Fn(EvalBlock<'_, SinPiRows>)| {
            let mut out = vec![f64::NAN; ts.len()];
            assert_eq!(
                vectorize(SinPiBlock {
                    ts: &ts,
                    out: &mut out
                }),
                0,
                "{level}"
            );
            for (t, o) in ts.iter().zip(&out) {
                assert_eq!(o.to_bits(), sin_pi_unit(*t).to_bits(), "{level}: t = {t:e}");
            }
            let mut out = vec![f64::NAN; pts.len()];
            eval(EvalBlock {
                density: &d,
                points: &pts,
                out: &mut out,
            });
            for (p, o) in pts.iter().zip(&out) {
                assert_eq!(o.to_bits(), d.eval(*p).to_bits(), "{level}: {p:?}");
            }
        };
        if let Some(v3) = pulp::x86::V3::try_new() {
            check("V3", &|op| pulp::Simd::vectorize(v3, op), &|op| {
                pulp::Simd::vectorize(v3, op)
            });
        }
        if let Some(v4) = pulp::x86::V4::try_new() {
            check("V4", &|op| pulp::Simd::vectorize(v4, op), &|op| {
                pulp::Simd::vectorize(v4, op)
            });
        }
    }

    #[test]
    fn exact_region_stats_with_sin_rows() {
        let (w, h) = (6usize, 5usize);
        let vals: Vec<f64> = (0..w * h).map(|k| 1.0 + (k % 7) as f64).collect();
        let d = TabulatedDensity::new(w, h, vals.clone(), Rect::UNIT)
            .unwrap()
            .with_row_factor(SinPiRows)
            .unwrap();
        // Brute-force integral over an unaligned rectangle with fine midpoint quadrature.
        let r = Rect::new(0.13, 0.21, 0.77, 0.93);
        let n = 2000;
        let mut s = 0.0;
        let mut m = 0.0f64;
        for a in 0..n {
            for b in 0..n {
                let x = r.x0 + (a as f64 + 0.5) / n as f64 * r.width();
                let y = r.y0 + (b as f64 + 0.5) / n as f64 * r.height();
                let f = d.eval([x, y]);
                s += f;
                m = m.max(f);
            }
        }
        s *= r.area() / (n * n) as f64;
        let e = d.region(&r);
        assert!((e.integral - s).abs() < 1e-4 * s, "{} vs {}", e.integral, s);
        assert!(e.max_bound >= m && e.max_bound <= m * 1.01);
        assert!(
            (d.total_integral() - d.region(&Rect::UNIT).integral).abs()
                < 1e-12 * d.total_integral()
        );
    }

    #[test]
    fn rejects_bad_values() {
        let bad = TabulatedDensity::new(2, 2, vec![1.0, 2.0, f64::NAN, 1.0], Rect::UNIT);
        assert!(matches!(
            bad,
            Err(DensityError::InvalidValue {
                index: 2,
                column: 0,
                row: 1,
                ..
            })
        ));
        assert!(matches!(
            TabulatedDensity::new(1, 1, vec![-1.0], Rect::UNIT),
            Err(DensityError::InvalidValue { .. })
        ));
        assert!(matches!(
            TabulatedDensity::new(1, 1, vec![f64::INFINITY], Rect::UNIT),
            Err(DensityError::InvalidValue { .. })
        ));
        assert_eq!(
            TabulatedDensity::new(2, 1, vec![0.0, 0.0], Rect::UNIT).unwrap_err(),
            DensityError::ZeroTotal
        );
        assert!(matches!(
            TabulatedDensity::new(0, 3, vec![], Rect::UNIT),
            Err(DensityError::EmptyGrid { .. })
        ));
        assert!(matches!(
            TabulatedDensity::new(2, 2, vec![1.0], Rect::UNIT),
            Err(DensityError::LengthMismatch { .. })
        ));
        let flat = Rect::new(0.0, 0.0, 0.0, 1.0);
        assert!(matches!(
            TabulatedDensity::new(1, 1, vec![1.0], flat),
            Err(DensityError::InvalidDomain(_))
        ));
    }
}
