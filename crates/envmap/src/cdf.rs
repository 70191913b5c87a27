//! The marginal/conditional CDF sampler of a map on fixed-point tables: every CDF is a row of
//! `u32` boundaries in units of 2⁻³¹ (half the bytes of `f64` tables, and no separate table of
//! cell values: a cell's probability is the difference of its two boundaries), searched by a
//! branch-free binary search that the block path runs for many samples side by side.
//!
//! **The law is the stored tables'.** A row is drawn with probability `m_r = (M[r+1] − M[r]) /
//! 2³¹` and a column of that row with `c_k = (C_r[k+1] − C_r[k]) / 2³¹`, exactly: the uniform's
//! top 31 bits pick the cell (`B[i] ≤ ⌊u·2³¹⌋ < B[i+1]`) and its remaining bits place the point
//! uniformly in the cell. The pdf reported is that law, `m_r · c_k · W·H` on `[0,1]²`; the
//! quantisation only moves each cell's probability by less than 2⁻³¹ from the `f64` weights,
//! and every cell of positive weight keeps at least one unit, so no lit pixel becomes
//! unreachable.

use std::hint::select_unpredictable;

use distributions::{Point2, Sample2, Sampler2D, UniformSource};

use crate::EnvMapError;

/// log₂ of the fixed-point unit: CDF boundaries are integers in `[0, 2³¹]`.
const BITS: i32 = 31;

/// `2³¹`, the fixed-point total of every CDF.
const ONE: u32 = 1 << BITS;

/// `2³¹` as `f64`.
const ONE_F: f64 = ONE as f64;

/// Samples walked side by side by the block path: enough independent loads in flight to
/// overlap the cache misses of the conditional rows.
const BLOCK: usize = 32;

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

/// The largest `i < n` with `b[i] ≤ x`, for a CDF row `b` of `n + 1` boundaries with `b[0] = 0`
/// and `b[n] = 2³¹ > x`: a binary search whose step count depends on `n` only and whose steps
/// are selects, not branches (`select_unpredictable`: a conditional move that LLVM's x86 pass
/// would otherwise turn back into a branch, mispredicted half the time on a search).
#[inline(always)]
fn find(b: &[u32], n: usize, x: u32) -> usize {
    let mut base = 0usize;
    let mut len = n;
    while len > 1 {
        let half = len / 2;
        let probe = base + half;
        base = select_unpredictable(b[probe] <= x, probe, base);
        len -= half;
    }
    base
}

/// The uniform's top 31 bits, `⌊u·2³¹⌋`, and `u·2³¹` itself (exact: a power-of-two scaling);
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
#[derive(Debug, Clone, PartialEq)]
pub struct QuantisedCdf2D {
    width: usize,
    height: usize,
    /// `height` rows of `width + 1` boundaries: the conditional CDFs of the columns of each row
    /// (a row of zero weight holds the uniform CDF; it is never drawn).
    conditional: Vec<u32>,
    /// `height + 1` boundaries: the marginal CDF of the rows.
    marginal: Vec<u32>,
    /// `width · height / 2⁶²`: a cell's pdf on `[0,1]²` is its two widths' product times this.
    pdf_scale: f64,
}

impl QuantisedCdf2D {
    /// The sampler of `weights` (row-major, `width × height`, finite and non-negative, not all
    /// zero).
    ///
    /// Errors: [`EnvMapError::Empty`] for a zero size, [`EnvMapError::TooLarge`] for a side of
    /// 2³¹ − 1 cells or more,
    /// [`EnvMapError::SizeMismatch`] when `weights.len() ≠ width · height`,
    /// [`EnvMapError::AllBlack`] when no weight is positive or a weight or a row sum is not
    /// finite and non-negative.
    pub fn new(width: usize, height: usize, weights: &[f64]) -> Result<Self, EnvMapError> {
        // At most 2³¹ − 1 cells per CDF, so every positive cell can keep one unit.
        if width == 0 || height == 0 {
            return Err(EnvMapError::Empty { width, height });
        }
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
            conditional,
            marginal,
            pdf_scale: (width as f64 * height as f64) / (ONE_F * ONE_F),
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
    /// product over 2⁶²); 0 outside the table.
    pub fn cell_probability(&self, column: usize, row: usize) -> f64 {
        if column >= self.width || row >= self.height {
            return 0.0;
        }
        let (m, c) = self.widths(column, row);
        m * c / (ONE_F * ONE_F)
    }

    /// The stored widths (in units of 2⁻³¹) of row `row` in the marginal and of column
    /// `column` in that row's conditional.
    #[inline(always)]
    fn widths(&self, column: usize, row: usize) -> (f64, f64) {
        let m = self.marginal[row + 1] - self.marginal[row];
        let b = &self.conditional[row * (self.width + 1)..];
        (f64::from(m), f64::from(b[column + 1] - b[column]))
    }

    /// The sample of the uniforms `u0` (column) and `u1` (row).
    #[inline(always)]
    fn sample_pair(&self, u0: f64, u1: f64) -> Sample2 {
        let (w, h) = (self.width, self.height);
        let (x1, s1) = fixed(u1);
        let row = find(&self.marginal, h, x1);
        let (m_lo, m_hi) = (self.marginal[row], self.marginal[row + 1]);
        let b = &self.conditional[row * (w + 1)..(row + 1) * (w + 1)];
        let (x0, s0) = fixed(u0);
        let col = find(b, w, x0);
        let (c_lo, c_hi) = (b[col], b[col + 1]);
        self.finish(row, s1, m_lo, m_hi, col, s0, c_lo, c_hi)
    }

    /// The point and pdf of cell `(col, row)` given the scaled uniforms and the cell's
    /// boundaries.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn finish(
        &self,
        row: usize,
        s1: f64,
        m_lo: u32,
        m_hi: u32,
        col: usize,
        s0: f64,
        c_lo: u32,
        c_hi: u32,
    ) -> Sample2 {
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
        std::mem::size_of::<Self>()
            + (self.conditional.capacity() + self.marginal.capacity()) * std::mem::size_of::<u32>()
    }

    /// Up to [`BLOCK`] samples side by side: the uniforms, every row search (level by level
    /// across the lanes), every column search likewise, then the points.
    // Lane loops index several per-lane arrays by the lane number.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn sample_block<U: UniformSource + ?Sized>(&self, u: &mut U, out: &mut [Sample2]) {
        let m = out.len();
        debug_assert!(m <= BLOCK);
        let (w, h) = (self.width, self.height);
        let mut x0 = [0u32; BLOCK];
        let mut s0 = [0.0f64; BLOCK];
        let mut x1 = [0u32; BLOCK];
        let mut s1 = [0.0f64; BLOCK];
        for j in 0..m {
            (x0[j], s0[j]) = fixed(u.next_uniform());
            (x1[j], s1[j]) = fixed(u.next_uniform());
        }
        // Rows: the marginal is small (cached); level by level so the lanes' selects overlap.
        let mg = &self.marginal[..];
        let mut row = [0usize; BLOCK];
        let mut len = h;
        while len > 1 {
            let half = len / 2;
            for j in 0..m {
                let probe = row[j] + half;
                row[j] = select_unpredictable(mg[probe] <= x1[j], probe, row[j]);
            }
            len -= half;
        }
        // Columns: absolute indices into the concatenated rows, so every lane's probe of a
        // level is one independent load (the misses of the block overlap).
        let cd = &self.conditional[..];
        let mut at = [0usize; BLOCK];
        for j in 0..m {
            at[j] = row[j] * (w + 1);
        }
        let mut len = w;
        while len > 1 {
            let half = len / 2;
            for j in 0..m {
                let probe = at[j] + half;
                at[j] = select_unpredictable(cd[probe] <= x0[j], probe, at[j]);
            }
            len -= half;
        }
        for j in 0..m {
            let r = row[j];
            let col = at[j] - r * (w + 1);
            out[j] = self.finish(
                r,
                s1[j],
                mg[r],
                mg[r + 1],
                col,
                s0[j],
                cd[at[j]],
                cd[at[j] + 1],
            );
        }
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
    /// bit), walked [`BLOCK`] at a time side by side.
    fn sample_into<U: UniformSource + ?Sized>(&self, u: &mut U, out: &mut [Sample2]) {
        for chunk in out.chunks_mut(BLOCK) {
            self.sample_block(u, chunk);
        }
    }

    /// The stored law's density on `[0,1]²` at `p`: the product of its cell's two stored
    /// widths times `W·H / 2⁶²`; 0 outside the square.
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

    /// The plain linear scan: the largest `i < n` with `b[i] ≤ x`.
    fn scan(b: &[u32], n: usize, x: u32) -> usize {
        (0..n).rev().find(|&i| b[i] <= x).unwrap_or(0)
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
            assert_eq!(*t.marginal.last().unwrap(), ONE);
            for (r, b) in t.conditional.chunks_exact(w + 1).enumerate() {
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
                assert_eq!(t.marginal[r + 1] > t.marginal[r], row_positive);
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
        for (w, h, seed) in [(1, 1, 5), (3, 1, 6), (37, 19, 7), (1024, 8, 8)] {
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
            }
            // The searches against the linear scan, on random and boundary uniforms.
            let mut g = Mix(seed + 100);
            let mut us: Vec<f64> = (0..2000).map(|_| g.next_uniform()).collect();
            for &x in t.conditional.iter().chain(&t.marginal) {
                let y = f64::from(x) / ONE_F;
                us.extend([y, y.next_down(), y.next_up()]);
            }
            us.extend([0.0, -0.0, 1.0 - f64::EPSILON / 2.0, 1.0, f64::NAN, -1.0]);
            for (k, &u1) in us.iter().enumerate() {
                let u0 = us[(k * 7919) % us.len()];
                let s = t.sample_pair(u0, u1);
                let (x1, _) = fixed(u1);
                let (x0, _) = fixed(u0);
                let row = scan(&t.marginal, h, x1);
                let b = &t.conditional[row * (w + 1)..(row + 1) * (w + 1)];
                let col = scan(b, w, x0);
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
