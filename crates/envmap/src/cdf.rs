//! The marginal/conditional CDF sampler of a map on fixed-point tables: every CDF is a row of
//! `u32` boundaries in units of 2⁻³⁰ (half the bytes of `f64` tables, and no separate table of
//! cell values: a cell's probability is the difference of its two boundaries), searched by
//! counting: a 16-ary tree of cache lines per row (every 256th, every 16th, every boundary),
//! where each level is one aligned 64-byte load and a count of its 16 entries `≤ x` (compares
//! the compiler vectorises: one AVX-512 compare, two AVX2 ones), with no branch on the data.
//! The block path runs the levels of [`BLOCK`] samples side by side, compiled for the best
//! instruction set `pulp` finds at run time.
//!
//! **The law is the stored tables'.** A row is drawn with probability `m_r = (M[r+1] − M[r]) /
//! 2³⁰` and a column of that row with `c_k = (C_r[k+1] − C_r[k]) / 2³⁰`, exactly: the uniform's
//! top 30 bits pick the cell (`B[i] ≤ ⌊u·2³⁰⌋ < B[i+1]`) and its remaining bits place the point
//! uniformly in the cell. The pdf reported is that law, `m_r · c_k · W·H` on `[0,1]²`; the
//! quantisation only moves each cell's probability by about 2⁻³⁰ from the `f64` weights, and
//! every cell of positive weight keeps at least one unit, so no lit pixel becomes
//! unreachable.

use std::hint::select_unpredictable;

use distributions::{InvertibleSampler2D, Point2, Sample2, Sampler2D, UniformSource};

use crate::EnvMapError;

/// log₂ of the fixed-point unit: CDF boundaries are integers in `[0, 2³⁰]` (so that they
/// compare as `i32`, the compare every x86 vector level has).
const BITS: i32 = 30;

/// `2³⁰`, the fixed-point total of every CDF.
const ONE: u32 = 1 << BITS;

/// `2³⁰` as `f64`.
const ONE_F: f64 = ONE as f64;

/// Samples walked side by side by the block path: enough independent loads in flight to
/// overlap the cache misses of the conditional rows.
const BLOCK: usize = 32;

/// Entries per line of a counting tree.
const FAN: usize = 16;

/// One cache line of 16 boundaries.
#[repr(align(64))]
#[derive(Debug, Clone, Copy, PartialEq)]
struct Line([u32; FAN]);

/// How many entries of a line are `≤ x` (all entries and `x` are at most 2³⁰: `i32`
/// compares), by the instruction set at hand.
trait Count: Copy {
    /// Whether the count beats the binary search (a vector compare); the block path walks
    /// by binary search otherwise.
    const FAST: bool;

    /// `#{k < 16 : line[k] ≤ x}`.
    fn count(self, line: &Line, x: u32) -> usize;
}

/// The count in scalar code: a bit mask of the 16 compares and its population count (the
/// one-sample path, and the block path where AVX-512 is absent).
#[derive(Debug, Clone, Copy)]
struct ScalarCount;

impl Count for ScalarCount {
    const FAST: bool = false;

    #[inline(always)]
    fn count(self, line: &Line, x: u32) -> usize {
        let x = x as i32;
        let mut mask = 0u32;
        for (k, &v) in line.0.iter().enumerate() {
            mask |= u32::from((v as i32) <= x) << k;
        }
        mask.count_ones() as usize
    }
}

/// The count in AVX-512 through `pulp`'s safe `V4` operations: one 16-lane compare into a
/// mask register, and its population count. (Left to the vectoriser, the 16 compares became
/// a chain of mask-bit extractions slower than the scalar binary search.)
impl Count for pulp::x86::V4 {
    const FAST: bool = true;

    #[inline(always)]
    fn count(self, line: &Line, x: u32) -> usize {
        let v: pulp::i32x16 = pulp::cast(line.0);
        let mask = self.cmp_le_i32x16(v, self.splat_i32x16(x as i32));
        mask.0.count_ones() as usize
    }
}

/// `rows` CDFs of `n` cells each (boundaries `B[0] = 0 ≤ … ≤ B[n] = 2³⁰`) as counting trees.
///
/// Level `ℓ` of a row holds `T_ℓ[m] = B[m·16^ℓ]` for `m·16^ℓ < n` and 2³⁰ beyond (level 0 is
/// the boundaries themselves, `B[n] = 2³⁰` included), in lines of 16. With `q_ℓ = ⌊i/16^ℓ⌋`
/// for the cell `i` sought (the largest `i < n` with `B[i] ≤ x`), the top level has one line
/// (`q_D = 0`) and `q_ℓ = 16·q_{ℓ+1} + #{k < 16 : T_ℓ[16·q_{ℓ+1} + k] ≤ x} − 1`: the `T` are
/// monotone, `T_ℓ[16·q_{ℓ+1}] ≤ x`, and `T_ℓ[16·q_{ℓ+1} + 16] > x`.
///
/// **Guides** (the one-sample path): per row `G = 2^g` buckets of the fixed-point range
/// (`g = ⌈log₂ ⌈n/4⌉⌉`, so about one bucket per 4 cells), bucket `j` holding the level-0 line
/// `⌊i_j / 16⌋` of the cell `i_j` of `x_j = j · 2³⁰ / G`. For `x` in bucket `j = ⌊x·G/2³⁰⌋`
/// the cell `i` of `x` has `i ≥ i_j`, so its line is found by counting from line `⌊i_j/16⌋`
/// forward (`B[16·⌊i_j/16⌋] ≤ B[i_j] ≤ x`); each bucket holds `1/G` of the row's probability
/// and the lines it spans sum to at most `lines + G`, so a draw counts at most
/// `1 + lines/G` lines on average (≤ 1.26 for 1024 cells) against one per level of the tree,
/// in a chain of two dependent loads (guide, line) instead of one per level.
#[derive(Debug, Clone, PartialEq)]
struct CountTree {
    n: usize,
    /// Per level, lowest first: lines per row, and the rows' lines concatenated.
    levels: Vec<(usize, Vec<Line>)>,
    /// `G` guide entries per row (level-0 line indices), rows concatenated; empty when a row
    /// has more than `u16::MAX` lines (the one-sample path then walks the levels).
    guide: Vec<u16>,
    /// `30 − g`: the bucket of `x` is `x >> guide_shift`.
    guide_shift: u32,
}

impl CountTree {
    /// The trees of `boundaries`, `rows` runs of `n + 1` boundaries.
    fn new(n: usize, rows: usize, boundaries: &[u32]) -> Self {
        let mut levels = Vec::new();
        let mut stride = 1usize; // 16^ℓ
        loop {
            let per_row = n / (stride * FAN) + 1;
            let mut lines = vec![Line([ONE; FAN]); per_row * rows];
            for (b, out) in boundaries
                .chunks_exact(n + 1)
                .zip(lines.chunks_exact_mut(per_row))
            {
                for (m, i) in (0..n).step_by(stride).enumerate() {
                    out[m / FAN].0[m % FAN] = b[i];
                }
            }
            levels.push((per_row, lines));
            if stride.saturating_mul(FAN) >= n {
                break;
            }
            stride *= FAN;
        }
        let (guide, guide_shift) = Self::guides(n, rows, boundaries);
        Self {
            n,
            levels,
            guide,
            guide_shift,
        }
    }

    /// The guides of `rows` runs of `n + 1` boundaries (see the type docs) and their shift.
    fn guides(n: usize, rows: usize, boundaries: &[u32]) -> (Vec<u16>, u32) {
        let g = n
            .div_ceil(4)
            .max(1)
            .next_power_of_two()
            .trailing_zeros()
            .min(BITS as u32);
        let shift = BITS as u32 - g;
        let buckets = 1usize << g;
        if n / FAN >= usize::from(u16::MAX) {
            return (Vec::new(), shift);
        }
        let mut guide = Vec::with_capacity(buckets * rows);
        for b in boundaries.chunks_exact(n + 1) {
            // Merge walk: `i` is the cell of `x_j` (largest `i < n` with `B[i] ≤ x_j`).
            let mut i = 0usize;
            for j in 0..buckets {
                let x = (j as u32) << shift;
                while i + 1 < n && b[i + 1] <= x {
                    i += 1;
                }
                guide.push((i / FAN) as u16);
            }
        }
        (guide, shift)
    }

    /// The cell of `x < 2³⁰` in row `row` (as [`Self::find`]) from the row's guide: count the
    /// guide's line, then the following lines while the previous count was full and the next
    /// line's first boundary is `≤ x`. Falls back to [`Self::find`] without guides.
    #[inline(always)]
    fn find_guided<C: Count>(&self, c: C, row: usize, x: u32) -> usize {
        if self.guide.is_empty() {
            return self.find(c, row, x);
        }
        let (per_row, lines) = &self.levels[0];
        let line = &lines[row * per_row..(row + 1) * per_row];
        let buckets = 1usize << (BITS as u32 - self.guide_shift);
        let mut q = usize::from(self.guide[row * buckets + (x >> self.guide_shift) as usize]);
        let mut k = c.count(&line[q], x);
        while k == FAN && q + 1 < line.len() {
            let next = c.count(&line[q + 1], x);
            if next == 0 {
                break;
            }
            q += 1;
            k = next;
        }
        FAN * q + k - 1
    }

    /// Boundary `i ≤ n` of row `row`.
    #[inline(always)]
    fn boundary(&self, row: usize, i: usize) -> u32 {
        let (per_row, lines) = &self.levels[0];
        lines[row * per_row + i / FAN].0[i % FAN]
    }

    /// The cell of `x < 2³⁰` in row `row`: the largest `i < n` with `B[i] ≤ x`.
    #[inline(always)]
    fn find<C: Count>(&self, c: C, row: usize, x: u32) -> usize {
        let mut q = 0usize;
        for (per_row, lines) in self.levels.iter().rev() {
            q = FAN * q + c.count(&lines[row * per_row + q], x) - 1;
        }
        q
    }

    /// The same cell by a binary search of the boundaries (level 0), whose steps are
    /// `select_unpredictable`s (conditional moves: a branch there mispredicts half the
    /// time): the search of the levels without AVX-512, where the 16-entry count is slow.
    #[inline(always)]
    fn find_binary(&self, row: usize, x: u32) -> usize {
        let (per_row, lines) = &self.levels[0];
        let row = &lines[row * per_row..(row + 1) * per_row];
        let mut base = 0usize;
        let mut len = self.n;
        while len > 1 {
            let half = len / 2;
            let probe = base + half;
            let v = row[probe / FAN].0[probe % FAN];
            base = select_unpredictable(v <= x, probe, base);
            len -= half;
        }
        base
    }

    /// Bytes of the lines.
    fn bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|(_, l)| l.capacity() * std::mem::size_of::<Line>())
            .sum::<usize>()
            + 2 * self.guide.capacity()
    }
}

/// Boundaries `B[0] = 0 ≤ B[1] ≤ … ≤ B[n] = 2³¹` of a CDF of `weights` (finite, ≥ 0, positive
/// sum `total`) written to `out[..=n]`: each positive weight gets one unit, the other
/// `2³¹ − #positive` units are shared by the rounded-down prefix sums (so a zero weight gets
/// exactly zero units, and the last boundary is exactly 2³¹).
fn quantise(weights: &[f64], total: f64, out: &mut [u32]) {
    let positive = weights.iter().filter(|&&w| w > 0.0).count() as u64;
    let rest = u64::from(ONE) - positive;
    let scale = rest as f64 / total;
    // From the last positive weight on, every boundary is 2³¹ (the rounded prefix sums may
    // fall short of `rest` there, which would give a trailing zero weight the remainder).
    let last = weights.iter().rposition(|&w| w > 0.0).unwrap_or(0);
    let mut prefix = 0.0f64;
    let mut ones = 0u64;
    out[0] = 0;
    for (k, &w) in weights.iter().enumerate() {
        prefix += w;
        ones += u64::from(w > 0.0);
        // Monotone in `prefix` (a zero weight leaves it unchanged); capped at `rest`.
        let shared = if k >= last {
            rest
        } else {
            ((prefix * scale) as u64).min(rest)
        };
        out[k + 1] = (ones + shared) as u32;
    }
}

/// The uniform's top 30 bits, `⌊u·2³⁰⌋`, and `u·2³⁰` itself (exact: a power-of-two scaling);
/// NaN and negatives count as 0, values ≥ 1 as the largest number below 1.
#[inline(always)]
fn fixed(u: f64) -> (u32, f64) {
    let s = if u >= 0.0 {
        (u * ONE_F).min(ONE_F - ONE_F * f64::EPSILON / 2.0)
    } else {
        0.0
    };
    (s as u32, s)
}

/// The coordinate of position `t ∈ [0, 1)` in cell `i` of `n` cells of `[0, 1)`, guaranteed to
/// lie in that cell as [`cell_of`] sees it (the cell's midpoint where rounding would leave it).
#[inline(always)]
fn place(i: usize, t: f64, n: f64, inv_n: f64) -> f64 {
    let fi = i as f64;
    let x = (fi + t) * inv_n;
    let s = x * n;
    if x < 1.0 && s >= fi && s < fi + 1.0 {
        x
    } else {
        (fi + 0.5) * inv_n
    }
}

/// The cell of `p ∈ [0, 1]` among `n` cells: `⌊p·n⌋`, with `p = 1` in the last cell.
#[inline(always)]
fn cell_of(p: f64, n: usize) -> usize {
    ((p * n as f64) as usize).min(n - 1)
}

/// The piecewise-constant CDF sampler of a `width × height` table of non-negative weights on
/// `[0,1]²` (row 0 at `v = 0`), on fixed-point CDF tables (see the [module docs](self)).
///
/// Two uniforms per sample, the first for the column and the second for the row (the order of
/// `distributions::PiecewiseConstant2D`); [`Sampler2D::sample_into`] walks [`BLOCK`] samples
/// side by side and returns the same samples as that many [`Sampler2D::sample`] calls, bit for
/// bit.
#[derive(Debug, Clone)]
pub struct QuantisedCdf2D {
    width: usize,
    height: usize,
    /// `height` rows: the conditional CDFs of the columns of each row (a row of zero weight
    /// holds the uniform CDF; it is never drawn).
    conditional: CountTree,
    /// One row: the marginal CDF of the rows.
    marginal: CountTree,
    /// `width · height / 2⁶⁰`: a cell's pdf on `[0,1]²` is its two widths' product times this.
    pdf_scale: f64,
    /// The instruction set of the block path (`pulp`'s runtime dispatch).
    arch: pulp::Arch,
}

impl QuantisedCdf2D {
    /// The sampler of `weights` (row-major, `width × height`, finite and non-negative, not all
    /// zero).
    ///
    /// Errors: [`EnvMapError::Empty`] for a zero size, [`EnvMapError::TooLarge`] for a side of
    /// 2³⁰ − 1 cells or more, [`EnvMapError::SizeMismatch`] when `weights.len() ≠ width ·
    /// height`, [`EnvMapError::AllBlack`] when no weight is positive or a weight or a row sum
    /// is not finite and non-negative.
    pub fn new(width: usize, height: usize, weights: &[f64]) -> Result<Self, EnvMapError> {
        if width == 0 || height == 0 {
            return Err(EnvMapError::Empty { width, height });
        }
        // Fewer than 2³⁰ cells per CDF, so every positive cell can keep one unit.
        let too_large = EnvMapError::TooLarge {
            width,
            height,
            max: ONE as usize - 1,
        };
        if width >= ONE as usize || height >= ONE as usize {
            return Err(too_large);
        }
        let expected = width.checked_mul(height).ok_or(too_large)?;
        if weights.len() != expected {
            return Err(EnvMapError::SizeMismatch {
                width,
                height,
                expected,
                got: weights.len(),
            });
        }
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(EnvMapError::AllBlack);
        }
        let row_sums: Vec<f64> = weights
            .chunks_exact(width)
            .map(|r| r.iter().sum())
            .collect();
        let total: f64 = row_sums.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(EnvMapError::AllBlack);
        }
        let mut marginal = vec![0u32; height + 1];
        quantise(&row_sums, total, &mut marginal);
        let mut conditional = vec![0u32; (width + 1) * height];
        let uniform = vec![1.0; width];
        for ((row, out), &sum) in weights
            .chunks_exact(width)
            .zip(conditional.chunks_exact_mut(width + 1))
            .zip(&row_sums)
        {
            if sum > 0.0 {
                quantise(row, sum, out);
            } else {
                quantise(&uniform, width as f64, out);
            }
        }
        Ok(Self {
            width,
            height,
            conditional: CountTree::new(width, height, &conditional),
            marginal: CountTree::new(height, 1, &marginal),
            pdf_scale: (width as f64 * height as f64) / (ONE_F * ONE_F),
            arch: pulp::Arch::new(),
        })
    }

    /// Columns of the table.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows of the table.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The probability of cell `(column, row)` as the sampler draws it (its two stored widths'
    /// product over 2⁶⁰); 0 outside the table.
    pub fn cell_probability(&self, column: usize, row: usize) -> f64 {
        if column >= self.width || row >= self.height {
            return 0.0;
        }
        let (m, c) = self.widths(column, row);
        m * c / (ONE_F * ONE_F)
    }

    /// The stored widths (in units of 2⁻³⁰) of row `row` in the marginal and of column
    /// `column` in that row's conditional.
    #[inline(always)]
    fn widths(&self, column: usize, row: usize) -> (f64, f64) {
        let (mg, cd) = (&self.marginal, &self.conditional);
        let m = mg.boundary(0, row + 1) - mg.boundary(0, row);
        let c = cd.boundary(row, column + 1) - cd.boundary(row, column);
        (f64::from(m), f64::from(c))
    }

    /// The sample of the uniforms `u0` (column) and `u1` (row): the guided count
    /// ([`CountTree::find_guided`]) in AVX-512 where the CPU has it (one call into the `V4`
    /// build per sample), else the binary search. The same cell either way.
    #[inline(always)]
    fn sample_pair(&self, u0: f64, u1: f64) -> Sample2 {
        match self.arch {
            pulp::Arch::V4(simd) => simd.vectorize(
                #[inline(always)]
                || self.sample_pair_guided(simd, u0, u1),
            ),
            _ => self.sample_pair_binary(u0, u1),
        }
    }

    /// [`Self::sample_pair`] by the guided count with the count `c`.
    #[inline(always)]
    fn sample_pair_guided<C: Count>(&self, c: C, u0: f64, u1: f64) -> Sample2 {
        let (x1, s1) = fixed(u1);
        let row = self.marginal.find_guided(c, 0, x1);
        let (x0, s0) = fixed(u0);
        let col = self.conditional.find_guided(c, row, x0);
        self.finish(row, s1, col, s0)
    }

    /// The sample of `u0`, `u1` by the counting walk of the levels with the count `c` (the
    /// block path's search; the tests' reference for the one-sample path).
    #[cfg(test)]
    fn sample_pair_counted<C: Count>(&self, c: C, u0: f64, u1: f64) -> Sample2 {
        let (x1, s1) = fixed(u1);
        let row = self.marginal.find(c, 0, x1);
        let (x0, s0) = fixed(u0);
        let col = self.conditional.find(c, row, x0);
        self.finish(row, s1, col, s0)
    }

    /// [`Self::sample_pair`] by the binary search.
    #[inline(always)]
    fn sample_pair_binary(&self, u0: f64, u1: f64) -> Sample2 {
        let (x1, s1) = fixed(u1);
        let row = self.marginal.find_binary(0, x1);
        let (x0, s0) = fixed(u0);
        let col = self.conditional.find_binary(row, x0);
        self.finish(row, s1, col, s0)
    }

    /// The point and pdf of cell `(col, row)` given the scaled uniforms.
    #[inline(always)]
    fn finish(&self, row: usize, s1: f64, col: usize, s0: f64) -> Sample2 {
        let (mg, cd) = (&self.marginal, &self.conditional);
        let (m_lo, m_hi) = (mg.boundary(0, row), mg.boundary(0, row + 1));
        let (c_lo, c_hi) = (cd.boundary(row, col), cd.boundary(row, col + 1));
        let (dm, dc) = (f64::from(m_hi - m_lo), f64::from(c_hi - c_lo));
        let (w, h) = (self.width as f64, self.height as f64);
        Sample2 {
            point: [
                place(col, (s0 - f64::from(c_lo)) / dc, w, 1.0 / w),
                place(row, (s1 - f64::from(m_lo)) / dm, h, 1.0 / h),
            ],
            pdf: dm * dc * self.pdf_scale,
        }
    }

    /// Bytes of the tables and the struct.
    pub fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>() + self.conditional.bytes() + self.marginal.bytes()
    }

    /// Up to [`BLOCK`] samples side by side: the uniforms, every row search (level by level
    /// across the lanes, so the lanes' loads overlap), every column search likewise, then the
    /// points.
    // Lane loops index several per-lane arrays by the lane number.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn sample_block<U: UniformSource + ?Sized, C: Count>(
        &self,
        c: C,
        u: &mut U,
        out: &mut [Sample2],
    ) {
        let m = out.len();
        debug_assert!(m <= BLOCK);
        let mut x0 = [0u32; BLOCK];
        let mut s0 = [0.0f64; BLOCK];
        let mut x1 = [0u32; BLOCK];
        let mut s1 = [0.0f64; BLOCK];
        for j in 0..m {
            (x0[j], s0[j]) = fixed(u.next_uniform());
            (x1[j], s1[j]) = fixed(u.next_uniform());
        }
        let mut row = [0usize; BLOCK];
        let mut col = [0usize; BLOCK];
        if !C::FAST {
            // Without AVX-512: the binary searches, lane by lane (independent chains).
            for j in 0..m {
                row[j] = self.marginal.find_binary(0, x1[j]);
            }
            for j in 0..m {
                col[j] = self.conditional.find_binary(row[j], x0[j]);
            }
            for j in 0..m {
                out[j] = self.finish(row[j], s1[j], col[j], s0[j]);
            }
            return;
        }
        for (_, lines) in self.marginal.levels.iter().rev() {
            for j in 0..m {
                row[j] = FAN * row[j] + c.count(&lines[row[j]], x1[j]) - 1;
            }
        }
        for (per_row, lines) in self.conditional.levels.iter().rev() {
            for j in 0..m {
                col[j] = FAN * col[j] + c.count(&lines[row[j] * per_row + col[j]], x0[j]) - 1;
            }
        }
        for j in 0..m {
            out[j] = self.finish(row[j], s1[j], col[j], s0[j]);
        }
    }
}

/// Equality of the tables (the dispatch level is not part of the sampler's law).
impl PartialEq for QuantisedCdf2D {
    fn eq(&self, other: &Self) -> bool {
        (self.width, self.height, &self.conditional, &self.marginal)
            == (
                other.width,
                other.height,
                &other.conditional,
                &other.marginal,
            )
    }
}

/// [`QuantisedCdf2D::sample_block`] over a slice with the count `c`, as a `pulp` operation
/// (compiled for the instruction set it is dispatched to).
struct Blocks<'a, U: ?Sized, C> {
    table: &'a QuantisedCdf2D,
    c: C,
    u: &'a mut U,
    out: &'a mut [Sample2],
}

impl<U: UniformSource + ?Sized, C: Count> pulp::WithSimd for Blocks<'_, U, C> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        for chunk in self.out.chunks_mut(BLOCK) {
            self.table.sample_block(self.c, self.u, chunk);
        }
    }
}

impl QuantisedCdf2D {
    /// The block path at the instruction-set level `level`: AVX-512 (`V4`) where `pulp`
    /// finds it (and `level` allows it), else the scalar count compiled for AVX2 (`V3`) or
    /// the x86-64 baseline. Every level gives the same samples (integer compares).
    fn sample_into_at<U: UniformSource + ?Sized>(
        &self,
        level: pulp::Arch,
        u: &mut U,
        out: &mut [Sample2],
    ) {
        use pulp::WithSimd;
        match level {
            pulp::Arch::V4(simd) => {
                let op = Blocks {
                    table: self,
                    c: simd,
                    u,
                    out,
                };
                simd.vectorize(
                    #[inline(always)]
                    || op.with_simd(simd),
                )
            }
            other => other.dispatch(Blocks {
                table: self,
                c: ScalarCount,
                u,
                out,
            }),
        }
    }
}

/// The warp of the unit square and its inverse (`u[0]` picks the column, `u[1]` the row).
impl InvertibleSampler2D for QuantisedCdf2D {
    /// Inputs outside `[0,1)` (and NaN) are clamped into it.
    #[inline]
    fn sample_square(&self, u: Point2) -> Sample2 {
        self.sample_pair(u[0], u[1])
    }

    /// `None` outside the square and on cells the sampler never draws (zero stored width):
    /// the uniforms `(C_r[c] + t_c·ΔC) / 2³⁰, (M[r] + t_r·ΔM) / 2³⁰` of the point's cell and
    /// position `t` in it (up to rounding).
    fn invert(&self, p: Point2) -> Option<Point2> {
        if !(p[0] >= 0.0 && p[0] <= 1.0 && p[1] >= 0.0 && p[1] <= 1.0) {
            return None;
        }
        let (col, row) = (cell_of(p[0], self.width), cell_of(p[1], self.height));
        let (mg, cd) = (&self.marginal, &self.conditional);
        let (m_lo, m_hi) = (mg.boundary(0, row), mg.boundary(0, row + 1));
        let (c_lo, c_hi) = (cd.boundary(row, col), cd.boundary(row, col + 1));
        if m_hi == m_lo || c_hi == c_lo {
            return None;
        }
        let within = |x: f64, i: usize, lo: u32, hi: u32| {
            let t = (x - i as f64).clamp(0.0, 1.0);
            ((f64::from(lo) + t * f64::from(hi - lo)) / ONE_F).min(1.0 - f64::EPSILON / 2.0)
        };
        Some([
            within(p[0] * self.width as f64, col, c_lo, c_hi),
            within(p[1] * self.height as f64, row, m_lo, m_hi),
        ])
    }
}

impl Sampler2D for QuantisedCdf2D {
    /// Two uniforms: the first for the column, the second for the row.
    #[inline]
    fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2 {
        let u0 = u.next_uniform();
        let u1 = u.next_uniform();
        self.sample_pair(u0, u1)
    }

    /// The samples of as many [`Sampler2D::sample`] calls (same uniforms, same samples, bit for
    /// bit), walked [`BLOCK`] at a time side by side (the same numbers at every dispatch
    /// level: integer compares and the one-sample path's floating-point operations).
    fn sample_into<U: UniformSource + ?Sized>(&self, u: &mut U, out: &mut [Sample2]) {
        self.sample_into_at(self.arch, u, out);
    }

    /// The stored law's density on `[0,1]²` at `p`: the product of its cell's two stored
    /// widths times `W·H / 2⁶⁰`; 0 outside the square.
    fn pdf(&self, p: Point2) -> f64 {
        if !(p[0] >= 0.0 && p[0] <= 1.0 && p[1] >= 0.0 && p[1] <= 1.0) {
            return 0.0;
        }
        let (col, row) = (cell_of(p[0], self.width), cell_of(p[1], self.height));
        let (m, c) = self.widths(col, row);
        m * c * self.pdf_scale
    }

    fn bytes_used(&self) -> usize {
        QuantisedCdf2D::bytes_used(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use distributions::UniformSequence;

    /// SplitMix64 uniforms (53 bits), for tests independent of the crate's generators.
    struct Mix(u64);

    impl UniformSource for Mix {
        fn next_uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The reference search (std's `partition_point`): the largest `i < n` with `b[i] ≤ x`.
    fn scan(b: &[u32], n: usize, x: u32) -> usize {
        b[..n].partition_point(|&v| v <= x).max(1) - 1
    }

    /// The baseline and every `pulp` level this CPU has (AVX2, AVX-512).
    fn levels() -> Vec<pulp::Arch> {
        let mut l = vec![pulp::Arch::Scalar];
        l.extend(pulp::x86::V3::try_new().map(pulp::Arch::V3));
        l.extend(pulp::x86::V4::try_new().map(pulp::Arch::V4));
        l
    }

    /// The `n + 1` stored boundaries of row `row` of `tree`.
    fn bounds(tree: &CountTree, row: usize) -> Vec<u32> {
        (0..=tree.n).map(|i| tree.boundary(row, i)).collect()
    }

    #[test]
    fn counting_trees_find_the_reference_searchs_cell() {
        // Sizes at and around the levels' edges (1 to 4 levels), rows with runs of equal
        // boundaries (zero-width cells), every boundary and its neighbours as `x`.
        let mut g = Mix(11);
        for n in [1, 2, 15, 16, 17, 255, 256, 257, 1024, 4097] {
            let rows = 3;
            let mut b = Vec::new();
            for r in 0..rows {
                // Row 2: a spike over a dim rest, so that guide buckets span many lines.
                let spike = (g.next_uniform() * n as f64) as usize;
                let w: Vec<f64> = (0..n)
                    .map(|i| {
                        let u = g.next_uniform();
                        match r {
                            2 if i == spike => 1e6,
                            2 => 1e-3 * u,
                            _ if u < 0.3 => 0.0,
                            _ => u,
                        }
                    })
                    .collect();
                let mut out = vec![0u32; n + 1];
                if w.iter().any(|&x| x > 0.0) {
                    quantise(&w, w.iter().sum(), &mut out);
                } else {
                    quantise(&vec![1.0; n], n as f64, &mut out);
                }
                b.extend(out);
            }
            let tree = CountTree::new(n, rows, &b);
            for r in 0..rows {
                let row = &b[r * (n + 1)..(r + 1) * (n + 1)];
                assert_eq!(bounds(&tree, r), row);
                let mut xs: Vec<u32> = (0..200).map(|_| fixed(g.next_uniform()).0).collect();
                for &v in row {
                    xs.extend([v.saturating_sub(1), v, v + 1]);
                }
                for x in xs.into_iter().filter(|&x| x < ONE) {
                    let want = scan(row, n, x);
                    assert_eq!(tree.find(ScalarCount, r, x), want, "n {n}, row {r}, x {x}");
                    assert_eq!(
                        tree.find_binary(r, x),
                        want,
                        "binary: n {n}, row {r}, x {x}"
                    );
                    assert_eq!(
                        tree.find_guided(ScalarCount, r, x),
                        want,
                        "guided: n {n}, row {r}, x {x}"
                    );
                    if let Some(simd) = pulp::x86::V4::try_new() {
                        let got = simd.vectorize(|| tree.find(simd, r, x));
                        assert_eq!(got, want, "V4: n {n}, row {r}, x {x}");
                        let got = simd.vectorize(|| tree.find_guided(simd, r, x));
                        assert_eq!(got, want, "V4 guided: n {n}, row {r}, x {x}");
                    }
                }
            }
        }
    }

    fn table(width: usize, height: usize, seed: u64) -> Vec<f64> {
        let mut g = Mix(seed);
        (0..width * height)
            .map(|i| {
                let r = g.next_uniform();
                // Zero cells, whole zero rows, tiny cells and a spike.
                if i / width == 2 || r < 0.2 {
                    0.0
                } else if r < 0.3 {
                    1e-300
                } else if i == 7 {
                    1e12
                } else {
                    r
                }
            })
            .collect()
    }

    #[test]
    fn quantised_cdfs_keep_every_positive_cell_and_sum_to_one() {
        for (w, h, seed) in [(1, 1, 1), (7, 5, 2), (64, 33, 3), (1000, 3, 4)] {
            let v = table(w, h, seed);
            let t = QuantisedCdf2D::new(w, h, &v).unwrap();
            let marginal = bounds(&t.marginal, 0);
            assert_eq!(*marginal.last().unwrap(), ONE);
            for r in 0..h {
                let b = bounds(&t.conditional, r);
                assert_eq!((b[0], b[w]), (0, ONE));
                let row = &v[r * w..(r + 1) * w];
                let row_positive = row.iter().any(|&x| x > 0.0);
                for c in 0..w {
                    assert!(b[c] <= b[c + 1]);
                    // A positive weight keeps ≥ 1 unit, a zero weight none (in a lit row).
                    if row_positive {
                        assert_eq!(b[c + 1] > b[c], row[c] > 0.0, "({c}, {r})");
                    }
                }
                assert_eq!(marginal[r + 1] > marginal[r], row_positive);
            }
            let total: f64 = (0..h)
                .flat_map(|r| (0..w).map(move |c| (c, r)))
                .map(|(c, r)| t.cell_probability(c, r))
                .sum();
            assert!((total - 1.0).abs() < 1e-12, "{total}");
            // Close to the f64 weights: each probability within a few units of 2⁻³¹.
            let sum: f64 = v.iter().sum();
            for r in 0..h {
                for c in 0..w {
                    let p = t.cell_probability(c, r);
                    let exact = v[r * w + c] / sum;
                    assert!(
                        (p - exact).abs() < 1e-8 + 1e-6 * exact,
                        "({c}, {r}): {p} vs {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn block_path_equals_the_one_sample_path_and_the_plain_search() {
        for (w, h, seed) in [
            (1, 1, 5),
            (3, 1, 6),
            (37, 19, 7),
            (1024, 8, 8),
            (5000, 2, 9),
        ] {
            let v = table(w, h, seed);
            let t = QuantisedCdf2D::new(w, h, &v).unwrap();
            for len in [1, 31, 32, 33, 200] {
                let mut a = Mix(seed);
                let mut b = Mix(seed);
                let one: Vec<Sample2> = (0..len).map(|_| t.sample(&mut a)).collect();
                let mut blk = vec![
                    Sample2 {
                        point: [0.0; 2],
                        pdf: 0.0
                    };
                    len
                ];
                t.sample_into(&mut b, &mut blk);
                assert_eq!(one, blk, "{w}×{h}, {len}");
                assert_eq!(a.0, b.0, "uniforms consumed");
                // Every dispatch level this CPU has, not only the best one.
                for level in levels() {
                    let mut c = Mix(seed);
                    blk.fill(Sample2 {
                        point: [0.0; 2],
                        pdf: 0.0,
                    });
                    t.sample_into_at(level, &mut c, &mut blk);
                    assert_eq!(one, blk, "{w}×{h}, {len}, {level:?}");
                }
            }
            // The searches against the linear scan, on random and boundary uniforms.
            let mut g = Mix(seed + 100);
            let mut us: Vec<f64> = (0..2000).map(|_| g.next_uniform()).collect();
            let rows: Vec<Vec<u32>> = (0..h).map(|r| bounds(&t.conditional, r)).collect();
            let marginal = bounds(&t.marginal, 0);
            let all: Vec<u32> = rows.iter().flatten().chain(&marginal).copied().collect();
            for &x in &all {
                let y = f64::from(x) / ONE_F;
                us.extend([y, y.next_down(), y.next_up()]);
            }
            us.extend([0.0, -0.0, 1.0 - f64::EPSILON / 2.0, 1.0, f64::NAN, -1.0]);
            let pairs: Vec<[f64; 2]> = (0..us.len())
                .map(|k| [us[(k * 7919) % us.len()], us[k]])
                .collect();
            // The block path at every level on these uniforms (boundaries exactly hit: the
            // compares' `≤`), against the one-sample path.
            let flat: Vec<f64> = pairs.iter().flatten().copied().collect();
            let one: Vec<Sample2> = pairs.iter().map(|&[a, b]| t.sample_pair(a, b)).collect();
            // The one-sample path's three walks give the same samples.
            for (&[a, b], s) in pairs.iter().zip(&one) {
                for other in [
                    t.sample_pair_binary(a, b),
                    t.sample_pair_counted(ScalarCount, a, b),
                    t.sample_pair_guided(ScalarCount, a, b),
                ] {
                    assert_eq!(
                        (s.point.map(f64::to_bits), s.pdf.to_bits()),
                        (other.point.map(f64::to_bits), other.pdf.to_bits())
                    );
                }
            }
            for level in levels() {
                let mut blk = vec![
                    Sample2 {
                        point: [0.0; 2],
                        pdf: 0.0
                    };
                    pairs.len()
                ];
                t.sample_into_at(level, &mut UniformSequence::new(&flat), &mut blk);
                for (a, b) in one.iter().zip(&blk) {
                    // NaN inputs give the same sample; compare bits.
                    assert_eq!(
                        (a.point.map(f64::to_bits), a.pdf.to_bits()),
                        (b.point.map(f64::to_bits), b.pdf.to_bits()),
                        "{level:?}"
                    );
                }
            }
            for &[u0, u1] in &pairs {
                let s = t.sample_pair(u0, u1);
                let (x1, _) = fixed(u1);
                let (x0, _) = fixed(u0);
                let row = scan(&marginal, h, x1);
                let col = scan(&rows[row], w, x0);
                assert!(
                    s.point[0] >= 0.0 && s.point[0] < 1.0 && s.point[1] >= 0.0 && s.point[1] < 1.0
                );
                assert_eq!(
                    (cell_of(s.point[0], w), cell_of(s.point[1], h)),
                    (col, row),
                    "u = ({u0}, {u1})"
                );
                assert!(s.pdf > 0.0);
                assert_eq!(s.pdf, t.pdf(s.point));
            }
        }
    }

    #[test]
    fn invert_undoes_the_warp() {
        let (w, h) = (37, 19);
        let t = QuantisedCdf2D::new(w, h, &table(w, h, 12)).unwrap();
        let mut g = Mix(13);
        for _ in 0..2000 {
            let u = [g.next_uniform(), g.next_uniform()];
            let s = t.sample_square(u);
            let back = t.invert(s.point).unwrap();
            assert!((back[0] - u[0]).abs() < 1e-12 && (back[1] - u[1]).abs() < 1e-12);
        }
        // Row 2 has zero weight: never drawn, not invertible; outside the square neither.
        assert_eq!(t.invert([0.5, 2.5 / h as f64]), None);
        assert_eq!(t.invert([1.5, 0.5]), None);
    }

    #[test]
    fn bad_tables_are_typed_errors() {
        assert!(matches!(
            QuantisedCdf2D::new(0, 1, &[]),
            Err(EnvMapError::Empty { .. })
        ));
        assert!(matches!(
            QuantisedCdf2D::new(2, 1, &[1.0]),
            Err(EnvMapError::SizeMismatch { .. })
        ));
        for bad in [
            [0.0, 0.0],
            [1.0, f64::NAN],
            [1.0, -1.0],
            [f64::MAX, f64::MAX],
        ] {
            assert!(matches!(
                QuantisedCdf2D::new(2, 1, &bad),
                Err(EnvMapError::AllBlack)
            ));
        }
    }
}
