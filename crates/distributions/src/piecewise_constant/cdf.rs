//! Shared kernels: validation, normalised CDF construction and CDF search.

use super::PiecewiseConstantError;
use crate::index::{floor_index, index_to_f64};

/// The largest `f64` below 1.
pub const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// Maps any number to `[0, 1)`: NaN and negatives to 0, values ≥ 1 to [`ONE_MINUS_EPSILON`].
#[inline]
pub fn clamp_unit(u: f64) -> f64 {
    if u >= 0.0 {
        u.min(ONE_MINUS_EPSILON)
    } else {
        0.0
    }
}

/// Checks that every value is finite and non-negative, in 1D terms: the first offending
/// cell's index and value, as [`PiecewiseConstantError::NonFiniteValue`] or
/// [`PiecewiseConstantError::NegativeValue`] (a 2D table renames the index to its column and
/// row with [`in_2d_terms`]).
pub(crate) fn validate_values(values: &[f64]) -> Result<(), PiecewiseConstantError> {
    for (index, &value) in values.iter().enumerate() {
        if !value.is_finite() {
            return Err(PiecewiseConstantError::NonFiniteValue { index, value });
        }
        if !(value >= 0.0) {
            return Err(PiecewiseConstantError::NegativeValue { index, value });
        }
    }
    Ok(())
}

/// A 1D cell error of a row-major `width`-column grid in 2D terms (column and row); other
/// errors unchanged.
pub(crate) fn in_2d_terms(e: PiecewiseConstantError, width: usize) -> PiecewiseConstantError {
    let at = |index: usize| (index % width.max(1), index / width.max(1));
    match e {
        PiecewiseConstantError::NonFiniteValue { index, value } => {
            let (column, row) = at(index);
            PiecewiseConstantError::NonFinite { column, row, value }
        }
        PiecewiseConstantError::NegativeValue { index, value } => {
            let (column, row) = at(index);
            PiecewiseConstantError::Negative { column, row, value }
        }
        other => other,
    }
}

/// Writes the normalised CDF of `values` (non-negative masses of `n` cells) into `cdf`
/// (length `n + 1`) and returns the plain sum. `cdf[0] = 0`, `cdf[n] = 1`, non-decreasing.
/// With a zero (or non-finite) sum the CDF is that of the uniform distribution (such a row is
/// never selected by a 2D sampler; a baseline's zero-mass row gets a defined conditional).
pub fn fill_cdf(values: &[f64], cdf: &mut [f64]) -> f64 {
    let n = values.len();
    debug_assert_eq!(cdf.len(), n + 1);
    let mut acc = 0.0;
    cdf[0] = 0.0;
    for (c, &v) in cdf[1..].iter_mut().zip(values) {
        acc += v;
        *c = acc;
    }
    if acc.is_finite() && acc > 0.0 {
        let inv = 1.0 / acc;
        for c in &mut cdf[1..n] {
            // Division keeps the order (rounding is monotone); clamp guards inv-rounding.
            *c = (*c * inv).min(1.0);
        }
    } else {
        let inv_n = 1.0 / n as f64;
        for (i, c) in cdf[1..n].iter_mut().enumerate() {
            *c = (i + 1) as f64 * inv_n;
        }
    }
    cdf[n] = 1.0;
    acc
}

/// Finds the cell `i` with `cdf[i] ≤ u < cdf[i+1]` for `u ∈ [0,1)`, and the position
/// `du ∈ [0,1)` of `u` inside it. The interval found always has positive width.
#[inline]
pub fn find_cell(cdf: &[f64], u: f64) -> (usize, f64) {
    find_cell_by(cdf, |&c| c, u)
}

/// [`find_cell`] over entries whose CDF value is `key(entry)`.
#[inline(always)]
pub(crate) fn find_cell_by<T>(cdf: &[T], key: impl Fn(&T) -> f64, u: f64) -> (usize, f64) {
    let n = cdf.len() - 1;
    // Interior entries ≤ u: cdf[0] = 0 ≤ u and cdf[n] = 1 > u are implied.
    let i = cdf[1..n].partition_point(|c| key(c) <= u);
    let (lo, hi) = (key(&cdf[i]), key(&cdf[i + 1]));
    let du = ((u - lo) / (hi - lo)).clamp(0.0, ONE_MINUS_EPSILON);
    (i, du)
}

/// Fills the guide table of a normalised CDF (`cdf.len() = n + 1`, `cdf[0] = 0`,
/// `cdf[n] = 1`, non-decreasing, CDF value `key(entry)`): `guide[g]` is the cell that
/// [`find_cell`] returns for `u = g / G`, `G = guide.len() ≥ 1`. O(n + G).
pub(crate) fn fill_guide_by<T, G: GuideEntry>(cdf: &[T], key: impl Fn(&T) -> f64, guide: &mut [G]) {
    let n = cdf.len() - 1;
    let g_len = guide.len() as f64;
    let mut i = 0usize;
    for (g, slot) in guide.iter_mut().enumerate() {
        let x = g as f64 / g_len;
        while i + 1 < n && key(&cdf[i + 1]) <= x {
            i += 1;
        }
        *slot = G::from_cell(i);
    }
}

/// The integer type of a guide table's entries: `u32`, or `u16` for rows of at most 65 536
/// cells (half the bytes, so more of a large table's guides stay in cache; the same cells).
pub(crate) trait GuideEntry: Copy + Default {
    /// The largest cell index the type holds.
    const MAX_CELL: usize;
    /// The entry of cell `i ≤ MAX_CELL`.
    fn from_cell(i: usize) -> Self;
    /// The cell index of the entry.
    fn cell(self) -> usize;
}

/// `GuideEntry` for an unsigned integer type narrower than `usize`.
macro_rules! guide_entry {
    ($t:ty) => {
        impl GuideEntry for $t {
            const MAX_CELL: usize = <$t>::MAX as usize;
            #[inline(always)]
            fn from_cell(i: usize) -> Self {
                debug_assert!(i <= Self::MAX_CELL);
                i as $t
            }
            #[inline(always)]
            fn cell(self) -> usize {
                self as usize
            }
        }
    };
}

guide_entry!(u32);
guide_entry!(u16);

/// The guide table of the normalised CDF `cdf` (as [`fill_cdf`] writes it), `guide.len() ≥ 1`
/// entries: `guide[g]` is the cell [`find_cell`] returns for `u = g / guide.len()`. O(n + G).
pub fn fill_guide(cdf: &[f64], guide: &mut [u32]) {
    fill_guide_by(cdf, |&c| c, guide)
}

/// [`find_cell`] from a guide table ([`fill_guide`] of the same CDF): the same cell and
/// position for every `u ∈ [0, 1)`, found by a short scan from `guide[⌊u·G⌋]` instead of a
/// binary search (O(1) expected for `G` near the cell count; coarser guides trade a longer
/// scan, within one cache line for `G = n/8`, for less memory).
#[inline]
pub fn find_cell_guided(cdf: &[f64], guide: &[u32], u: f64) -> (usize, f64) {
    find_cell_guided_by(cdf, |&c| c, guide, u)
}

/// [`find_cell_by`] started from a guide table ([`fill_guide_by`]) instead of a binary
/// search: the same cell and position for every `u ∈ [0,1)` (the scan from the guide's entry
/// first steps down while the CDF exceeds `u` — only possible through rounding of `u·G` — then
/// up while the next edge is ≤ `u`, so it ends at the largest `i < n` with `cdf[i] ≤ u`,
/// exactly what the binary search finds). The expected scan is O(1) when `G ≈ n`.
#[inline(always)]
pub(crate) fn find_cell_guided_by<T, G: GuideEntry>(
    cdf: &[T],
    key: impl Fn(&T) -> f64,
    guide: &[G],
    u: f64,
) -> (usize, f64) {
    let g = guide_bucket(u, guide.len());
    scan_by(cdf, key, guide[g].cell(), u)
}

/// The guide-table bucket `min(⌊u·G⌋, G − 1)` of `u` for a guide of `G ≥ 1` entries.
#[inline(always)]
pub(crate) fn guide_bucket(u: f64, g_len: usize) -> usize {
    floor_index(u * index_to_f64(g_len), g_len - 1)
}

/// The scan of [`find_cell_guided_by`] from cell `start` (a guide entry) over `[cdf, value]`
/// entries, one cell at a time: the cell and position [`find_cell`] gives for `u`.
#[inline(always)]
pub(crate) fn scan_stepwise(cdf: &[[f64; 2]], start: usize, u: f64) -> (usize, f64) {
    scan_stepwise_by(cdf, |e| e[0], start, u)
}

/// [`scan_by`] one cell at a time.
#[inline(always)]
pub(crate) fn scan_stepwise_by<T>(
    cdf: &[T],
    key: impl Fn(&T) -> f64,
    start: usize,
    u: f64,
) -> (usize, f64) {
    let n = cdf.len() - 1;
    let mut i = start.min(n - 1);
    while i > 0 && key(&cdf[i]) > u {
        i -= 1;
    }
    while i + 1 < n && key(&cdf[i + 1]) <= u {
        i += 1;
    }
    (i, cell_position(key(&cdf[i]), key(&cdf[i + 1]), u))
}

/// How many CDF entries past the guide's start the 2D block path's branch-free walks compare
/// in one step (`PiecewiseConstant2D`'s windowed block path).
pub(crate) const SCAN_WINDOW: usize = 4;

/// Guide buckets per cell of the tables' guide tables (fewer cell boundaries per bucket: a
/// scan's step count is more often 0).
pub(crate) const GUIDE_PER_CELL: usize = 2;

/// The cell of `u` from a start cell, one cell at a time: down while `cdf[i] > u` (only
/// through the rounding of a guide bucket), then up while the next edge is `≤ u`.
#[inline(always)]
fn scan_by<T>(cdf: &[T], key: impl Fn(&T) -> f64, start: usize, u: f64) -> (usize, f64) {
    scan_stepwise_by(cdf, key, start, u)
}

/// The position in `[0, 1)` of `u` inside the CDF interval `[lo, hi)` of its cell.
#[inline(always)]
pub(crate) fn cell_position(lo: f64, hi: f64, u: f64) -> f64 {
    ((u - lo) / (hi - lo)).clamp(0.0, ONE_MINUS_EPSILON)
}

/// The uniform number mapped by the CDF to position `du ∈ [0,1]` inside cell `i`.
#[inline]
pub(crate) fn invert_cell(cdf: &[f64], i: usize, du: f64) -> f64 {
    invert_in(cdf[i], cdf[i + 1], du)
}

/// The uniform number at position `du ∈ [0,1]` of the CDF interval `[lo, hi]`.
#[inline]
pub(crate) fn invert_in(lo: f64, hi: f64, du: f64) -> f64 {
    (lo + du * (hi - lo)).clamp(0.0, ONE_MINUS_EPSILON)
}

/// Index of the cell of `t ∈ [0, n]` (scaled coordinate) and its fractional part, clamped.
#[inline]
pub(crate) fn cell_of(t: f64, n: usize) -> (usize, f64) {
    let i = floor_index(t, n - 1);
    (i, (t - index_to_f64(i)).clamp(0.0, 1.0))
}

/// The coordinate at fraction `t ∈ [0,1)` of cell `i` of an axis from `lo` to `hi`, nudged
/// to the cell centre in the (probability ~1e-16) event that rounding puts it in another cell
/// as [`cell_of`] sees it, or on the excluded upper edge `hi`: so `pdf(point)` always reads
/// the sampled cell and points stay in `[lo, hi)`.
#[inline]
pub(crate) fn place(lo: f64, hi: f64, size: f64, inv_size: f64, i: usize, t: f64) -> f64 {
    let fi = index_to_f64(i);
    let x = lo + (fi + t) * size;
    // `⌊max(s, 0)⌋ == i` for `s = (x − lo)/size` (the cell `cell_of` sees), without the
    // float-to-integer conversion: `i ≤ s < i + 1`, where for `i = 0` negatives and NaN
    // count as inside (they floor to 0).
    let s = (x - lo) * inv_size;
    if x < hi && !(s >= fi + 1.0) && (i == 0 || s >= fi) {
        x
    } else {
        lo + (fi + 0.5) * size
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdf_is_normalised_and_monotone() {
        let mut cdf = vec![0.0; 5];
        let s = fill_cdf(&[1.0, 0.0, 2.0, 1.0], &mut cdf);
        assert_eq!(s, 4.0);
        assert_eq!(cdf, vec![0.0, 0.25, 0.25, 0.75, 1.0]);
    }

    #[test]
    fn find_cell_skips_empty_cells() {
        let cdf = [0.0, 0.25, 0.25, 0.75, 1.0];
        assert_eq!(find_cell(&cdf, 0.0), (0, 0.0));
        assert_eq!(find_cell(&cdf, 0.25).0, 2);
        assert_eq!(find_cell(&cdf, 0.5), (2, 0.5));
        assert_eq!(find_cell(&cdf, ONE_MINUS_EPSILON).0, 3);
    }

    #[test]
    fn guided_search_is_the_binary_search() {
        // CDFs with empty cells, a spike, runs of tiny cells; guides coarser, equal and finer
        // than the cell count; u on a fine grid, at bucket edges and their float neighbours.
        let shapes: Vec<Vec<f64>> = vec![
            vec![1.0],
            vec![0.0, 1.0, 0.0],
            vec![1.0, 0.0, 0.0, 2.0, 1.0],
            (0..200)
                .map(|k| if k == 77 { 1e6 } else { (k % 3) as f64 * 1e-9 })
                .collect(),
            (0..513).map(|k| ((k * 37) % 11) as f64).collect(),
        ];
        for values in &shapes {
            let mut cdf = vec![0.0; values.len() + 1];
            fill_cdf(values, &mut cdf);
            for g_len in [1, 3, values.len(), 2 * values.len() + 1] {
                let mut guide = vec![0u32; g_len];
                fill_guide_by(&cdf, |&c| c, &mut guide);
                let mut us: Vec<f64> = (0..20_000).map(|k| k as f64 / 20_000.0).collect();
                for g in 0..=g_len {
                    let x = g as f64 / g_len as f64;
                    us.extend([x, x.next_down(), x.next_up()]);
                }
                us.extend(cdf.iter().flat_map(|&c| [c, c.next_down(), c.next_up()]));
                for u in us.into_iter().map(clamp_unit) {
                    assert_eq!(
                        find_cell_guided_by(&cdf, |&c| c, &guide, u),
                        find_cell(&cdf, u),
                        "u = {u}, G = {g_len}, values {values:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn place_keeps_the_cast_based_cell_test() {
        // The check of `place` written with the float-to-integer cast, as before: the same
        // coordinate for every axis, cell and fraction tried (edges, their neighbours, NaN).
        fn place_by_cast(lo: f64, hi: f64, size: f64, inv: f64, i: usize, t: f64) -> f64 {
            let x = lo + (i as f64 + t) * size;
            if x < hi && ((x - lo) * inv).max(0.0) as usize == i {
                x
            } else {
                lo + (i as f64 + 0.5) * size
            }
        }
        let ts = [
            0.0,
            -0.0,
            1e-300,
            0.25,
            0.5,
            1.0f64.next_down(),
            ONE_MINUS_EPSILON,
            1.0,
            -1e-17,
            f64::NAN,
        ];
        for (lo, hi, n) in [
            (0.0, 1.0, 1usize),
            (0.0, 1.0, 3),
            (-1.0, 1.0, 7),
            (0.1, 0.7, 1024),
            (-3.3, 1e-9, 513),
            (1e8, 1e8 + 1.0, 4096),
        ] {
            let size = (hi - lo) / n as f64;
            let inv = n as f64 / (hi - lo);
            for i in (0..n).step_by((n / 64).max(1)).chain([n - 1]) {
                for &t in &ts {
                    let (a, b) = (
                        place(lo, hi, size, inv, i, t),
                        place_by_cast(lo, hi, size, inv, i, t),
                    );
                    assert_eq!(
                        a.to_bits(),
                        b.to_bits(),
                        "lo {lo} hi {hi} n {n} i {i} t {t}"
                    );
                }
            }
        }
    }

    #[test]
    fn clamp_unit_handles_nan_and_one() {
        assert_eq!(clamp_unit(f64::NAN), 0.0);
        assert_eq!(clamp_unit(-1.0), 0.0);
        assert!(clamp_unit(1.0) < 1.0);
    }
}
