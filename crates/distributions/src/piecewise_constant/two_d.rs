//! The classic marginal/conditional piecewise-constant 2D sampler.

use crate::{InvertibleSampler2D, Point2, Rect, Sample2, Sampler2D, UniformSource};
use serde::{Deserialize, Serialize};

use super::PiecewiseConstantError;
use super::cdf::{
    cell_of, clamp_unit, fill_cdf, fill_guide_by, find_cell_guided_by, guide_bucket, invert_cell,
    invert_in, place, scan_from, validate_values,
};

/// A density on a rectangle proportional to a `width × height` grid of non-negative values,
/// constant on each cell, sampled by inverting the marginal CDF of the rows and then the
/// conditional CDF of the columns of the chosen row (two uniforms per sample).
///
/// Cell `(column c, row r)` covers `[x0 + c·Δx, x0 + (c+1)·Δx) × [y0 + r·Δy, y0 + (r+1)·Δy)`,
/// `values` is row-major with row 0 at `y0`. The pdf is `p(x, y) = f_rc / ∫f` **with respect
/// to area on the domain**, where `∫f = Σ f · Δx·Δy`.
///
/// `sample_square([u0, u1])` uses `u1` for the row and `u0` for the column, so that
/// `invert ∘ sample_square` is the identity on `[0,1)²` (up to rounding).
///
/// ```
/// use distributions::{InvertibleSampler2D, PiecewiseConstant2D, Rect, Sampler2D};
/// let unit = Rect { x0: 0.0, y0: 0.0, x1: 1.0, y1: 1.0 };
/// let t = PiecewiseConstant2D::new(2, 1, vec![1.0, 3.0], unit).unwrap();
/// let s = t.sample_square([0.5, 0.5]);
/// assert!(s.point[0] > 0.5);                  // the right cell holds 3/4 of the mass
/// assert!((s.pdf - 1.5).abs() < 1e-12);        // 3 / (4 · 0.5)
/// assert!((t.pdf(s.point) - s.pdf).abs() < 1e-12);
/// let u = t.invert(s.point).unwrap();
/// assert!((u[0] - 0.5).abs() < 1e-12 && (u[1] - 0.5).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Table2DData", into = "Table2DData")]
pub struct PiecewiseConstant2D {
    width: usize,
    height: usize,
    domain: Rect,
    /// `height` rows of `width + 1` entries `[cdf_k, value_k]`, concatenated: the conditional
    /// CDF of the row at its column boundaries, interleaved with the cell values (the last
    /// entry's value is 0) so that the value of the sampled cell shares a cache line with the
    /// CDF entries the binary search just read.
    conditional: Vec<[f64; 2]>,
    /// Marginal CDF over rows, `height + 1` entries.
    marginal: Vec<f64>,
    /// Guide table of the marginal CDF (`height` entries, see `cdf::fill_guide_by`): the row
    /// search starts there instead of a binary search.
    marginal_guide: Vec<u32>,
    /// Guide tables of the conditional CDFs, `width` entries per row, concatenated: one
    /// cache line read and a short scan instead of ~log₂(width) dependent probes of a long row.
    /// The warp is unchanged (same cell, same position, bit for bit).
    conditional_guide: Vec<u32>,
    /// `1 / ∫f`: the pdf of a cell is its value times this.
    inv_integral: f64,
    /// Cell sizes `Δx`, `Δy` and their inverses.
    cell: [f64; 2],
    inv_cell: [f64; 2],
}

impl PiecewiseConstant2D {
    /// Builds the sampler of the density ∝ `values` (row-major, `width × height`, row 0 at
    /// `domain.y0`) on `domain`.
    ///
    /// Errors: zero width or height, a length other than `width·height`, a NaN, infinite or
    /// negative value (naming its column and row), all values zero, an overflowing sum, or a
    /// degenerate domain.
    pub fn new(
        width: usize,
        height: usize,
        values: Vec<f64>,
        domain: Rect,
    ) -> Result<Self, PiecewiseConstantError> {
        if width == 0 || height == 0 {
            return Err(PiecewiseConstantError::Empty { width, height });
        }
        let expected = width.saturating_mul(height);
        if values.len() != expected {
            return Err(PiecewiseConstantError::SizeMismatch {
                width,
                height,
                expected,
                got: values.len(),
            });
        }
        let Rect { x0, y0, x1, y1 } = domain;
        if !(x0.is_finite()
            && x1.is_finite()
            && y0.is_finite()
            && y1.is_finite()
            && x0 < x1
            && y0 < y1)
        {
            return Err(PiecewiseConstantError::InvalidDomain { x0, y0, x1, y1 });
        }
        validate_values(&values, width)?;

        let mut conditional = Vec::with_capacity(height * (width + 1));
        let mut row_sums = Vec::with_capacity(height);
        let mut cdf = vec![0.0; width + 1];
        for row in values.chunks_exact(width) {
            row_sums.push(fill_cdf(row, &mut cdf));
            conditional.extend(
                cdf.iter()
                    .zip(row.iter().chain([&0.0]))
                    .map(|(&c, &v)| [c, v]),
            );
        }
        let mut conditional_guide = vec![0u32; height * width];
        for (entries, guide) in conditional
            .chunks_exact(width + 1)
            .zip(conditional_guide.chunks_exact_mut(width))
        {
            fill_guide_by(entries, |e| e[0], guide);
        }
        let mut marginal = vec![0.0; height + 1];
        let total = fill_cdf(&row_sums, &mut marginal);
        let mut marginal_guide = vec![0u32; height];
        fill_guide_by(&marginal, |&c| c, &mut marginal_guide);
        if !total.is_finite() || row_sums.iter().any(|s| !s.is_finite()) {
            return Err(PiecewiseConstantError::TotalNotFinite);
        }
        if !(total > 0.0) {
            return Err(PiecewiseConstantError::AllZero);
        }
        let cell = [(x1 - x0) / width as f64, (y1 - y0) / height as f64];
        let integral = total * cell[0] * cell[1];
        if !(integral.is_finite() && integral > 0.0) {
            return Err(PiecewiseConstantError::TotalNotFinite);
        }
        Ok(Self {
            width,
            height,
            domain,
            conditional,
            marginal,
            marginal_guide,
            conditional_guide,
            inv_integral: 1.0 / integral,
            cell,
            inv_cell: [width as f64 / (x1 - x0), height as f64 / (y1 - y0)],
        })
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The domain rectangle.
    pub fn domain(&self) -> Rect {
        self.domain
    }

    /// The value of cell `(column, row)` as given; 0 out of range.
    pub fn value(&self, column: usize, row: usize) -> f64 {
        if column >= self.width || row >= self.height {
            return 0.0;
        }
        self.entry(column, row)[1]
    }

    /// The cell values as given (row-major).
    pub fn values(&self) -> Vec<f64> {
        self.conditional
            .chunks_exact(self.width + 1)
            .flat_map(|r| r[..self.width].iter().map(|e| e[1]))
            .collect()
    }

    #[inline]
    fn entry(&self, column: usize, row: usize) -> [f64; 2] {
        self.conditional[row * (self.width + 1) + column]
    }

    /// `∫f` over the domain of the unnormalised step function (`Σ f · Δx·Δy`).
    pub fn integral(&self) -> f64 {
        1.0 / self.inv_integral
    }

    /// Probability mass of cell `(column, row)`, i.e. `f · Δx·Δy / ∫f`; 0 out of range.
    pub fn cell_mass(&self, column: usize, row: usize) -> f64 {
        if column >= self.width || row >= self.height {
            return 0.0;
        }
        self.entry(column, row)[1] * self.inv_integral * self.cell[0] * self.cell[1]
    }

    /// Column and row of the cell containing `p`, `None` outside the (closed) domain.
    #[inline]
    fn locate(&self, p: Point2) -> Option<((usize, f64), (usize, f64))> {
        let Rect { x0, y0, x1, y1 } = self.domain;
        if !(p[0] >= x0 && p[0] <= x1 && p[1] >= y0 && p[1] <= y1) {
            return None;
        }
        Some((
            cell_of((p[0] - x0) * self.inv_cell[0], self.width),
            cell_of((p[1] - y0) * self.inv_cell[1], self.height),
        ))
    }

    /// The sample at position `(du, dv)` of cell `(col, row)`, whose value is `value`.
    #[inline(always)]
    fn place_sample(&self, row: usize, dv: f64, col: usize, du: f64, value: f64) -> Sample2 {
        let d = &self.domain;
        Sample2 {
            point: [
                place(d.x0, d.x1, self.cell[0], self.inv_cell[0], col, du),
                place(d.y0, d.y1, self.cell[1], self.inv_cell[1], row, dv),
            ],
            pdf: value * self.inv_integral,
        }
    }

    /// Draws `n` samples in parallel; the result depends only on `(n, seed)` (see
    /// [`crate::sample_par`]).
    pub fn sample_par(&self, n: usize, seed: u64) -> Vec<Sample2> {
        crate::sample_par(self, n, seed)
    }
}

impl Sampler2D for PiecewiseConstant2D {
    /// Two uniforms: the first for the column, the second for the row.
    #[inline]
    fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2 {
        let u0 = u.next_uniform();
        let u1 = u.next_uniform();
        self.sample_square([u0, u1])
    }

    /// The draws of [`Sampler2D::sample`] (same uniforms, same samples, bit for bit) in blocks:
    /// first the uniforms, the rows (the marginal is small and cached) and the guide entries
    /// of every sample of the block, loaded together so that their cache misses overlap; then
    /// the conditional scans and the points.
    fn sample_into<U: UniformSource + ?Sized>(&self, u: &mut U, out: &mut [Sample2]) {
        const BLOCK: usize = 64;
        let w = self.width;
        let mut cols = [0.0f64; BLOCK];
        let mut rows = [(0usize, 0.0f64); BLOCK];
        let mut starts = [0u32; BLOCK];
        let mut firsts = [0.0f64; BLOCK];
        for chunk in out.chunks_mut(BLOCK) {
            for j in 0..chunk.len() {
                let u0 = clamp_unit(u.next_uniform());
                let u1 = clamp_unit(u.next_uniform());
                let (row, dv) =
                    find_cell_guided_by(&self.marginal, |&c| c, &self.marginal_guide, u1);
                let g = guide_bucket(u0, w);
                cols[j] = u0;
                rows[j] = (row, dv);
                starts[j] = self.conditional_guide[row * w + g];
            }
            // Second stage: the conditional entry each scan starts from, loaded for the whole
            // block in a branch-free loop, so that these misses overlap too (in the scan loop
            // below they would wait behind its data-dependent branches).
            for j in 0..chunk.len() {
                firsts[j] = self.conditional[rows[j].0 * (w + 1) + starts[j] as usize][0];
            }
            std::hint::black_box(&firsts);
            for (j, slot) in chunk.iter_mut().enumerate() {
                let (row, dv) = rows[j];
                let start = row * (w + 1);
                let entries = &self.conditional[start..start + w + 1];
                let (col, du) = scan_from(entries, starts[j] as usize, cols[j]);
                *slot = self.place_sample(row, dv, col, du, entries[col][1]);
            }
        }
    }

    /// `f_rc / ∫f` w.r.t. area for `p` in cell `(c, r)`; 0 outside the domain.
    fn pdf(&self, p: Point2) -> f64 {
        match self.locate(p) {
            Some(((c, _), (r, _))) => self.entry(c, r)[1] * self.inv_integral,
            None => 0.0,
        }
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.conditional.capacity() * std::mem::size_of::<[f64; 2]>()
            + self.marginal.capacity() * std::mem::size_of::<f64>()
            + (self.marginal_guide.capacity() + self.conditional_guide.capacity())
                * std::mem::size_of::<u32>()
    }
}

impl InvertibleSampler2D for PiecewiseConstant2D {
    /// Inputs outside `[0,1)` (and NaN) are clamped into it.
    #[inline]
    fn sample_square(&self, u: Point2) -> Sample2 {
        let (row, dv) = find_cell_guided_by(
            &self.marginal,
            |&c| c,
            &self.marginal_guide,
            clamp_unit(u[1]),
        );
        let start = row * (self.width + 1);
        let entries = &self.conditional[start..start + self.width + 1];
        let guide = &self.conditional_guide[row * self.width..(row + 1) * self.width];
        let (col, du) = find_cell_guided_by(entries, |e| e[0], guide, clamp_unit(u[0]));
        self.place_sample(row, dv, col, du, entries[col][1])
    }

    /// `None` outside the domain and on zero-density cells (where the warp is not bijective).
    fn invert(&self, p: Point2) -> Option<Point2> {
        let ((c, du), (r, dv)) = self.locate(p)?;
        let [lo, value] = self.entry(c, r);
        if value == 0.0 {
            return None;
        }
        let u0 = invert_in(lo, self.entry(c + 1, r)[0], du);
        let u1 = invert_cell(&self.marginal, r, dv);
        Some([u0, u1])
    }
}

/// Serialised form: the inputs and a format version; deserialisation re-validates them.
#[derive(Serialize, Deserialize)]
struct Table2DData {
    version: u32,
    width: usize,
    height: usize,
    domain: [f64; 4],
    values: Vec<f64>,
}

const FORMAT_VERSION: u32 = 1;

impl TryFrom<Table2DData> for PiecewiseConstant2D {
    type Error = PiecewiseConstantError;
    fn try_from(d: Table2DData) -> Result<Self, PiecewiseConstantError> {
        if d.version != FORMAT_VERSION {
            return Err(PiecewiseConstantError::FormatVersion {
                found: d.version,
                expected: FORMAT_VERSION,
            });
        }
        let [x0, y0, x1, y1] = d.domain;
        Self::new(d.width, d.height, d.values, Rect { x0, y0, x1, y1 })
    }
}

impl From<PiecewiseConstant2D> for Table2DData {
    fn from(t: PiecewiseConstant2D) -> Self {
        let Rect { x0, y0, x1, y1 } = t.domain;
        Self {
            version: FORMAT_VERSION,
            width: t.width,
            height: t.height,
            domain: [x0, y0, x1, y1],
            values: t.values(),
        }
    }
}
