//! The classic marginal/conditional piecewise-constant 2D sampler.

use crate::{InvertibleSampler2D, Point2, Rect, Sample2, Sampler2D, UniformSource};
use serde::{Deserialize, Serialize};

use super::cdf::{
    GUIDE_PER_CELL, GuideEntry, SCAN_WINDOW, cell_of, cell_position, clamp_unit, fill_cdf,
    fill_guide_by, find_cell_guided_by, guide_bucket, in_2d_terms, invert_in, place, scan_stepwise,
    validate_values,
};
use super::error::{FORMAT_VERSION, check_version, finite_integral};
use super::{PiecewiseConstant1D, PiecewiseConstantError};

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
    /// The marginal over rows: the 1D table of the row sums on `[y0, y1]` (its guide table
    /// starts the row search; its warp places the `y` coordinate).
    marginal: PiecewiseConstant1D,
    /// Guide tables of the conditional CDFs, `2·width` entries per row, concatenated: one
    /// cache line read and a short scan instead of ~log₂(width) dependent probes of a long row.
    /// The warp is unchanged (same cell, same position, bit for bit).
    conditional_guide: RowGuides,
    /// The probability that a sample's conditional guide bucket holds a cell boundary (so
    /// that its scan takes a data-dependent number of steps): [`Self::scan_unpredictability`].
    unpredictable: f64,
    /// Whether the block path walks by the branch-free window (`unpredictable` above
    /// [`Self::WINDOW_ABOVE`]) or one cell at a time (predictable step counts: fewer instructions).
    windowed: bool,
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
        validate_values(&values).map_err(|e| in_2d_terms(e, width))?;

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
        let conditional_guide = if width - 1 <= u16::MAX_CELL {
            RowGuides::Narrow(row_guides(&conditional, width))
        } else {
            RowGuides::Wide(row_guides(&conditional, width))
        };
        // The row sums are finite and non-negative unless one overflowed: the 1D table's
        // `NonFiniteValue` of a row sum is the 2D table's overflowing total.
        let marginal = PiecewiseConstant1D::new(row_sums, y0, y1).map_err(|e| match e {
            PiecewiseConstantError::NonFiniteValue { .. } => PiecewiseConstantError::TotalNotFinite,
            other => other,
        })?;
        let unpredictable = match &conditional_guide {
            RowGuides::Narrow(g) => unpredictability(&conditional, g, marginal.cdf(), width),
            RowGuides::Wide(g) => unpredictability(&conditional, g, marginal.cdf(), width),
        };
        let total = marginal.sum();
        let cell = [(x1 - x0) / width as f64, (y1 - y0) / height as f64];
        let integral = finite_integral(total * cell[0] * cell[1])?;
        Ok(Self {
            width,
            height,
            domain,
            conditional,
            marginal,
            conditional_guide,
            unpredictable,
            windowed: unpredictable > Self::WINDOW_ABOVE,
            inv_integral: 1.0 / integral,
            cell,
            inv_cell: [width as f64 / (x1 - x0), height as f64 / (y1 - y0)],
        })
    }

    /// The probability that a sample's conditional guide bucket (one of `2·width` per row)
    /// holds a cell boundary, i.e. that its column scan takes a data-dependent number of
    /// steps: `Σ_rows P(row) · (buckets of the row holding a boundary) / buckets`. Above
    /// [`Self::WINDOW_ABOVE`] the block path walks both CDFs by a branch-free window of
    /// [`SCAN_WINDOW`] entries (mispredicted loop exits would cost more than its
    /// instructions), below it one cell at a time. Either way the same cells.
    pub fn scan_unpredictability(&self) -> f64 {
        self.unpredictable
    }

    /// The [`Self::scan_unpredictability`] above which the block path walks by the
    /// branch-free window (chosen from the shared maps, docs/benchmarks.md §23.3).
    pub const WINDOW_ABOVE: f64 = 0.1;

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
                self.marginal.place(row, dv),
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
        match &self.conditional_guide {
            RowGuides::Narrow(g) => self.sample_block(u, out, g),
            RowGuides::Wide(g) => self.sample_block(u, out, g),
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
            + (self.marginal.bytes_used() - std::mem::size_of::<PiecewiseConstant1D>())
            + self.conditional_guide.bytes()
    }
}

impl PiecewiseConstant2D {
    /// [`Sampler2D::sample_into`] over the row guides `guides` (the table's own).
    // Lane loops: each pass indexes several per-lane arrays by the lane number.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn sample_block<U: UniformSource + ?Sized, G: GuideEntry>(
        &self,
        u: &mut U,
        out: &mut [Sample2],
        guides: &[G],
    ) {
        if !self.windowed {
            return self.sample_block_stepwise(u, out, guides);
        }
        const BLOCK: usize = Lanes::LEN;
        let mut u0 = [0.0f64; BLOCK];
        let mut u1 = [0.0f64; BLOCK];
        let mut lanes = Lanes::default();
        for chunk in out.chunks_mut(BLOCK) {
            let m = chunk.len();
            for j in 0..m {
                u0[j] = clamp_unit(u.next_uniform());
                u1[j] = clamp_unit(u.next_uniform());
            }
            self.walk_block(guides, &u0[..m], &u1[..m], &mut lanes, chunk);
        }
    }

    /// The block path of tables whose scans take predictable step counts (see
    /// [`Self::scan_unpredictability`]): per sample, the uniforms, the row (one cell at a
    /// time) and the guide index; then the block's guide entries and first conditional
    /// entries, each in a loop of its own so that their misses overlap; then the column scans
    /// (one cell at a time) and the points. The same samples as the windowed passes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn sample_block_stepwise<U: UniformSource + ?Sized, G: GuideEntry>(
        &self,
        u: &mut U,
        out: &mut [Sample2],
        guides: &[G],
    ) {
        const BLOCK: usize = Lanes::LEN;
        let w = self.width;
        let gw = w * GUIDE_PER_CELL;
        let mut cols = [0.0f64; BLOCK];
        let mut rows = [(0usize, 0.0f64); BLOCK];
        let mut starts = [0usize; BLOCK];
        let mut firsts = [0.0f64; BLOCK];
        for chunk in out.chunks_mut(BLOCK) {
            for j in 0..chunk.len() {
                let u0 = clamp_unit(u.next_uniform());
                let u1 = clamp_unit(u.next_uniform());
                let (row, dv) = self.marginal.find_stepwise(u1);
                cols[j] = u0;
                rows[j] = (row, dv);
                starts[j] = row * gw + guide_bucket(u0, gw);
            }
            for j in 0..chunk.len() {
                starts[j] = guides[starts[j]].cell().min(w - 1);
            }
            for j in 0..chunk.len() {
                firsts[j] = self.conditional[rows[j].0 * (w + 1) + starts[j]][0];
            }
            std::hint::black_box(&firsts);
            for (j, slot) in chunk.iter_mut().enumerate() {
                let (row, dv) = rows[j];
                let start = row * (w + 1);
                let entries = &self.conditional[start..start + w + 1];
                let (col, du) = scan_stepwise(entries, starts[j], cols[j]);
                *slot = self.place_sample(row, dv, col, du, entries[col][1]);
            }
        }
    }

    /// The walks of one block of at most [`Lanes::LEN`] samples (clamped uniforms `u0` for the
    /// columns, `u1` for the rows), in structure-of-arrays passes of branch-free lane code:
    /// every row walk (guide entry, then the count of the next [`SCAN_WINDOW`] CDF entries
    /// `≤ u`), then every conditional guide load, then every column walk, then the points.
    /// Within a pass no lane waits for another, so the block's cache misses overlap. A lane
    /// whose window did not settle the cell (its guide entry above `u`, or a full window: both
    /// rare) is redone by the scalar scan, so the cells are exactly the binary search's.
    // Lane loops: each pass indexes several per-lane arrays by the lane number.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn walk_block<G: GuideEntry>(
        &self,
        guides: &[G],
        u0: &[f64],
        u1: &[f64],
        l: &mut Lanes,
        out: &mut [Sample2],
    ) {
        let m = out.len();
        let (w, h) = (self.width, self.height);
        let mcdf = self.marginal.cdf();
        let mguide = self.marginal.guide();
        let cond = &self.conditional[..];
        // Rows.
        for j in 0..m {
            let u = u1[j];
            let i = (mguide[guide_bucket(u, mguide.len())] as usize).min(h - 1);
            let mut steps = 0;
            for k in 1..=SCAN_WINDOW {
                steps += usize::from(mcdf[(i + k).min(h)] <= u);
            }
            l.redo[j] = (mcdf[i] > u) | (steps == SCAN_WINDOW);
            l.row[j] = (i + steps).min(h - 1);
        }
        for j in 0..m {
            if l.redo[j] {
                l.row[j] = self.marginal.find_stepwise(u1[j]).0;
            }
        }
        for j in 0..m {
            let r = l.row[j];
            l.dv[j] = cell_position(mcdf[r], mcdf[r + 1], u1[j]);
            l.base[j] = r * (w + 1);
            let gw = w * GUIDE_PER_CELL;
            l.start[j] = r * gw + guide_bucket(u0[j], gw);
        }
        // The guide entries (mostly out of cache on a large map), then the conditional
        // entries at both ends of each window, each in a loop of a few instructions per lane:
        // so that the whole block's misses are in flight at once (a window pass of ~30
        // instructions per lane would hold only a dozen lanes in the reorder buffer).
        // Coarser guides (one entry per 4 or 16 cells) measured slower: §20.5.
        for j in 0..m {
            l.start[j] = guides[l.start[j]].cell().min(w - 1);
        }
        for j in 0..m {
            let at = l.base[j] + l.start[j];
            l.touch[j] = cond[at][0] + cond[at + SCAN_WINDOW.min(w - l.start[j])][0];
        }
        std::hint::black_box(&l.touch);
        // Columns.
        for j in 0..m {
            let (u, b, i) = (u0[j], l.base[j], l.start[j]);
            let mut steps = 0;
            for k in 1..=SCAN_WINDOW {
                steps += usize::from(cond[b + (i + k).min(w)][0] <= u);
            }
            l.redo[j] = (cond[b + i][0] > u) | (steps == SCAN_WINDOW);
            l.col[j] = (i + steps).min(w - 1);
        }
        for j in 0..m {
            if l.redo[j] {
                let b = l.base[j];
                l.col[j] = scan_stepwise(&cond[b..b + w + 1], l.start[j], u0[j]).0;
            }
        }
        for (j, slot) in out.iter_mut().enumerate() {
            let at = l.base[j] + l.col[j];
            let du = cell_position(cond[at][0], cond[at + 1][0], u0[j]);
            *slot = self.place_sample(l.row[j], l.dv[j], l.col[j], du, cond[at][1]);
        }
    }
}

/// Per-lane scratch of [`PiecewiseConstant2D::walk_block`], structure of arrays.
struct Lanes {
    row: [usize; Lanes::LEN],
    dv: [f64; Lanes::LEN],
    base: [usize; Lanes::LEN],
    start: [usize; Lanes::LEN],
    col: [usize; Lanes::LEN],
    redo: [bool; Lanes::LEN],
    touch: [f64; Lanes::LEN],
}

impl Lanes {
    /// Samples per block.
    const LEN: usize = 64;
}

impl Default for Lanes {
    fn default() -> Self {
        Self {
            row: [0; Self::LEN],
            dv: [0.0; Self::LEN],
            base: [0; Self::LEN],
            start: [0; Self::LEN],
            col: [0; Self::LEN],
            redo: [false; Self::LEN],
            touch: [0.0; Self::LEN],
        }
    }
}

impl InvertibleSampler2D for PiecewiseConstant2D {
    /// Inputs outside `[0,1)` (and NaN) are clamped into it.
    #[inline]
    fn sample_square(&self, u: Point2) -> Sample2 {
        let (row, dv) = self.marginal.find(u[1]);
        let start = row * (self.width + 1);
        let entries = &self.conditional[start..start + self.width + 1];
        let gw = self.width * GUIDE_PER_CELL;
        let guides = row * gw..(row + 1) * gw;
        let u0 = clamp_unit(u[0]);
        let (col, du) = match &self.conditional_guide {
            RowGuides::Narrow(g) => find_cell_guided_by(entries, |e| e[0], &g[guides], u0),
            RowGuides::Wide(g) => find_cell_guided_by(entries, |e| e[0], &g[guides], u0),
        };
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
        let u1 = self.marginal.invert_cell(r, dv);
        Some([u0, u1])
    }
}

/// The guide tables of the conditional rows (`2·width` entries per row, concatenated), in the
/// narrowest entry type that holds a column index: `u16` up to 65 536 columns (2 MB for a
/// 1024 × 512 map, as one `u32` entry per cell took), `u32` beyond. The same start cells
/// either way.
#[derive(Debug, Clone, PartialEq)]
enum RowGuides {
    Narrow(Vec<u16>),
    Wide(Vec<u32>),
}

impl RowGuides {
    /// Heap bytes.
    fn bytes(&self) -> usize {
        match self {
            RowGuides::Narrow(g) => g.capacity() * std::mem::size_of::<u16>(),
            RowGuides::Wide(g) => g.capacity() * std::mem::size_of::<u32>(),
        }
    }
}

/// [`PiecewiseConstant2D::scan_unpredictability`] of the rows and guides of a table.
fn unpredictability<G: GuideEntry>(
    conditional: &[[f64; 2]],
    guides: &[G],
    mcdf: &[f64],
    width: usize,
) -> f64 {
    let gw = width * GUIDE_PER_CELL;
    let mut p = 0.0;
    for (r, (entries, row)) in conditional
        .chunks_exact(width + 1)
        .zip(guides.chunks_exact(gw))
        .enumerate()
    {
        // Bucket g holds a boundary when the cell of its last u (just below (g + 1)/G) is not
        // the cell its guide entry names: the next entry's cell, or the one before it when
        // that cell starts exactly at the bucket's end.
        let moving = (0..gw)
            .filter(|&g| {
                let this = row[g].cell();
                let last = match row.get(g + 1) {
                    None => width - 1,
                    Some(next) => {
                        let next = next.cell();
                        let end = (g + 1) as f64 / gw as f64;
                        if next > this && entries[next][0] >= end {
                            next - 1
                        } else {
                            next
                        }
                    }
                };
                last != this
            })
            .count();
        p += (mcdf[r + 1] - mcdf[r]) * moving as f64 / gw as f64;
    }
    p
}

/// The guide table of each row of `conditional` (rows of `width + 1` `[cdf, value]` entries).
fn row_guides<G: GuideEntry>(conditional: &[[f64; 2]], width: usize) -> Vec<G> {
    let gw = width * GUIDE_PER_CELL;
    let mut guides = vec![G::default(); conditional.len() / (width + 1) * gw];
    for (entries, guide) in conditional
        .chunks_exact(width + 1)
        .zip(guides.chunks_exact_mut(gw))
    {
        fill_guide_by(entries, |e| e[0], guide);
    }
    guides
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

impl TryFrom<Table2DData> for PiecewiseConstant2D {
    type Error = PiecewiseConstantError;
    fn try_from(d: Table2DData) -> Result<Self, PiecewiseConstantError> {
        check_version(d.version)?;
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

#[cfg(test)]
mod tests {
    use super::super::cdf::{ONE_MINUS_EPSILON, find_cell, place};
    use super::*;

    /// Tables with empty cells and rows, a spike, and a non-unit, non-square domain.
    fn tables() -> Vec<PiecewiseConstant2D> {
        let d = Rect {
            x0: -1.5,
            y0: 0.25,
            x1: 2.0,
            y1: 0.75,
        };
        let spike: Vec<f64> = (0..24 * 9)
            .map(|k| if k == 100 { 1e6 } else { (k % 5) as f64 })
            .collect();
        let holes: Vec<f64> = (0..7 * 5)
            .map(|k| {
                if k / 7 == 2 || k % 3 == 0 {
                    0.0
                } else {
                    1.0 + k as f64
                }
            })
            .collect();
        vec![
            PiecewiseConstant2D::new(24, 9, spike, d).unwrap(),
            PiecewiseConstant2D::new(7, 5, holes, Rect::UNIT).unwrap(),
            PiecewiseConstant2D::new(1, 1, vec![2.0], d).unwrap(),
        ]
    }

    #[test]
    fn the_marginal_is_the_1d_table_of_the_row_sums() {
        for t in tables() {
            let (w, h) = (t.width(), t.height());
            let values = t.values();
            let sums: Vec<f64> = values.chunks_exact(w).map(|r| r.iter().sum()).collect();
            let d = t.domain();
            let m = PiecewiseConstant1D::new(sums.clone(), d.y0, d.y1).unwrap();
            // The row search and the y coordinate are the 1D warp's, bit for bit; the x
            // coordinate is the conditional's binary search placed on the row.
            let mut row_cdf = vec![0.0; h + 1];
            fill_cdf(&sums, &mut row_cdf);
            for k in 0..4000 {
                let u = [(k as f64 * 0.618_034) % 1.0, (k as f64 + 0.5) / 4000.0];
                let s = t.sample_square(u);
                let y = m.sample(u[1]);
                assert_eq!(s.point[1].to_bits(), y.x.to_bits(), "u {u:?}");
                let (row, _) = find_cell(&row_cdf, u[1]);
                assert_eq!(row, y.index);
                let mut cdf = vec![0.0; w + 1];
                fill_cdf(&values[row * w..(row + 1) * w], &mut cdf);
                let (col, du) = find_cell(&cdf, u[0]);
                let dx = (d.x1 - d.x0) / w as f64;
                let x_ref = place(d.x0, d.x1, dx, w as f64 / (d.x1 - d.x0), col, du);
                assert_eq!(s.point[0].to_bits(), x_ref.to_bits(), "u {u:?}");
                let pdf = values[row * w + col] / t.integral();
                assert!((s.pdf - pdf).abs() <= 1e-14 * pdf, "u {u:?}");
                let inv = t.invert(s.point).unwrap();
                assert!((inv[1] - u[1]).abs() < 1e-9 && (inv[0] - u[0]).abs() < 1e-9);
            }
        }
    }

    /// SplitMix64 uniforms in `[0, 1)` (53 bits).
    fn splitmix_uniforms(seed: u64, n: usize) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = state;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect()
    }

    #[test]
    fn guided_walks_and_the_block_path_are_the_plain_binary_search() {
        // The guided walks (one-sample path) and the block path against the plain binary
        // search of each CDF, bit for bit: random u (seed 29), u = 0, 1 − ε, 1, NaN, every
        // CDF value and its float neighbours; tables with zero-weight rows and columns, a
        // spike, runs of tiny cells, and one wider than a `u16` guide holds.
        let mut t = tables();
        let wide: Vec<f64> = (0..70_000 * 2)
            .map(|k| if k % 7 == 0 { 0.0 } else { (k % 13) as f64 })
            .collect();
        t.push(PiecewiseConstant2D::new(70_000, 2, wide, Rect::UNIT).unwrap());
        let tiny: Vec<f64> = (0..40 * 6)
            .map(|k| match (k / 40, k % 40) {
                (1, _) | (_, 3) => 0.0,
                (_, c) if c > 30 => 1e-12,
                _ => 1.0 + (k % 5) as f64,
            })
            .collect();
        t.push(PiecewiseConstant2D::new(40, 6, tiny, Rect::UNIT).unwrap());
        // Each table walked both ways: the branch-free window and one cell at a time.
        let both: Vec<PiecewiseConstant2D> = t
            .iter()
            .flat_map(|t| {
                [true, false].map(|windowed| PiecewiseConstant2D {
                    windowed,
                    ..t.clone()
                })
            })
            .collect();
        for t in &both {
            let (w, h) = (t.width(), t.height());
            let values = t.values();
            let sums: Vec<f64> = values.chunks_exact(w).map(|r| r.iter().sum()).collect();
            let mut row_cdf = vec![0.0; h + 1];
            fill_cdf(&sums, &mut row_cdf);
            let mut edges = vec![0.0, -0.0, ONE_MINUS_EPSILON, 1.0, f64::NAN, 0.5];
            edges.extend(
                row_cdf
                    .iter()
                    .flat_map(|&c| [c, c.next_down(), c.next_up()]),
            );
            let mut cdfs = vec![0.0; h * (w + 1)];
            for (row, cdf) in values.chunks_exact(w).zip(cdfs.chunks_exact_mut(w + 1)) {
                fill_cdf(row, cdf);
            }
            for cdf in cdfs.chunks_exact(w + 1).step_by((h / 8).max(1)) {
                let step = (w / 300).max(1);
                edges.extend(
                    cdf.iter()
                        .step_by(step)
                        .flat_map(|&c| [c, c.next_down(), c.next_up()]),
                );
            }
            let random = splitmix_uniforms(29, 4000);
            // Pairs (u0, u1): random × random, edge × random, random × edge, edge × edge.
            let mut us = random.clone();
            for (k, &e) in edges.iter().enumerate() {
                let r = random[k % random.len()];
                us.extend([e, r, r, e, e, edges[(k * 7 + 3) % edges.len()]]);
            }
            let d = t.domain();
            let (dx, dy) = ((d.x1 - d.x0) / w as f64, (d.y1 - d.y0) / h as f64);
            let mut block = vec![
                Sample2 {
                    point: [0.0; 2],
                    pdf: 0.0
                };
                us.len() / 2
            ];
            t.sample_into(&mut crate::UniformSequence::new(&us), &mut block);
            for (pair, b) in us.chunks_exact(2).zip(&block) {
                let (u0, u1) = (clamp_unit(pair[0]), clamp_unit(pair[1]));
                let (row, dv) = find_cell(&row_cdf, u1);
                let (col, du) = find_cell(&cdfs[row * (w + 1)..(row + 1) * (w + 1)], u0);
                let x = place(d.x0, d.x1, dx, w as f64 / (d.x1 - d.x0), col, du);
                let y = place(d.y0, d.y1, dy, h as f64 / (d.y1 - d.y0), row, dv);
                let one = t.sample_square([pair[0], pair[1]]);
                assert_eq!(
                    [one.point[0].to_bits(), one.point[1].to_bits()],
                    [x.to_bits(), y.to_bits()],
                    "u {pair:?}, {w} × {h}"
                );
                assert_eq!(
                    one.pdf,
                    values[row * w + col] * t.inv_integral,
                    "u {pair:?}"
                );
                assert_eq!(
                    [b.point[0].to_bits(), b.point[1].to_bits(), b.pdf.to_bits()],
                    [x.to_bits(), y.to_bits(), one.pdf.to_bits()],
                    "block path, u {pair:?}, {w} × {h}"
                );
            }
        }
    }

    #[test]
    fn scan_unpredictability_counts_buckets_with_a_boundary_inside() {
        // Equal cells: every boundary sits on a bucket edge (2 buckets per cell), no scan
        // steps. One cell of 3 among 1s: boundaries inside buckets, in both rows alike.
        let flat = PiecewiseConstant2D::new(8, 2, vec![1.0; 16], Rect::UNIT).unwrap();
        assert_eq!(flat.scan_unpredictability(), 0.0);
        assert!(!flat.windowed);
        let mut v = vec![1.0; 8];
        v[2] = 3.0;
        let v: Vec<f64> = v.iter().chain(&v).copied().collect();
        let bumpy = PiecewiseConstant2D::new(8, 2, v, Rect::UNIT).unwrap();
        let p = bumpy.scan_unpredictability();
        // CDF 0, .1, .2, .5, .6, …, 1 against bucket edges k/16: boundaries .1, .2, .6, .7,
        // .8, .9 fall inside buckets 1, 3, 9, 11, 12, 14 (0.5 is the edge 8/16): 6 of 16.
        assert_eq!(p, 6.0 / 16.0);
        assert!(bumpy.windowed);
    }

    #[test]
    fn errors_name_the_cell_in_2d_and_the_overflow_as_the_total() {
        let e = PiecewiseConstant2D::new(3, 2, vec![1.0, 1.0, 1.0, 1.0, -2.0, 1.0], Rect::UNIT);
        assert_eq!(
            e.unwrap_err(),
            PiecewiseConstantError::Negative {
                column: 1,
                row: 1,
                value: -2.0
            }
        );
        let e = PiecewiseConstant2D::new(2, 2, vec![1.0, 1.0, f64::NAN, 1.0], Rect::UNIT);
        assert!(matches!(
            e.unwrap_err(),
            PiecewiseConstantError::NonFinite {
                column: 0,
                row: 1,
                ..
            }
        ));
        // Each value finite, a row sum overflows: the total is not finite.
        let e = PiecewiseConstant2D::new(2, 2, vec![f64::MAX, f64::MAX, 1.0, 1.0], Rect::UNIT);
        assert_eq!(e.unwrap_err(), PiecewiseConstantError::TotalNotFinite);
        let e = PiecewiseConstant2D::new(2, 2, vec![0.0; 4], Rect::UNIT);
        assert_eq!(e.unwrap_err(), PiecewiseConstantError::AllZero);
        // The 1D table names the same cell by its index.
        let e = PiecewiseConstant1D::new(vec![1.0, 1.0, 1.0, 1.0, -2.0], 0.0, 1.0);
        assert_eq!(
            e.unwrap_err(),
            PiecewiseConstantError::NegativeValue {
                index: 4,
                value: -2.0
            }
        );
    }
}
