//! The piecewise-constant density on an interval, sampled by CDF inversion.

use serde::{Deserialize, Serialize};

use super::PiecewiseConstantError;
use super::cdf::{
    GUIDE_PER_CELL, cell_of, clamp_unit, fill_cdf, fill_guide, find_cell_guided, guide_bucket,
    invert_cell, place, scan_stepwise_by, validate_values,
};
use super::error::{FORMAT_VERSION, check_version, finite_integral};

/// One draw of a [`PiecewiseConstant1D`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample1 {
    /// The point, in `[min, max)`.
    pub x: f64,
    /// Density of `x` with respect to length on `[min, max]`.
    pub pdf: f64,
    /// Index of the cell that contains `x`.
    pub index: usize,
}

/// A density on `[min, max]` proportional to `n` non-negative values, constant on each of the
/// `n` equal cells: `p(x) = f_i / ∫f` with respect to length, sampled by inverting its CDF.
///
/// ```
/// use distributions::PiecewiseConstant1D;
/// let d = PiecewiseConstant1D::new(vec![1.0, 3.0], 0.0, 2.0).unwrap();
/// let s = d.sample(0.5); // the CDF reaches 0.25 at x = 1
/// assert_eq!(s.index, 1);
/// assert!((s.pdf - 0.75).abs() < 1e-12);
/// assert!((d.invert(s.x).unwrap() - 0.5).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Table1DData", into = "Table1DData")]
pub struct PiecewiseConstant1D {
    values: Vec<f64>,
    cdf: Vec<f64>,
    /// Guide table of `cdf` (`2n` entries, [`fill_guide`]): the search starts there instead of
    /// a binary search (the same cell and position, bit for bit).
    guide: Vec<u32>,
    /// `Σ values`, as [`fill_cdf`] summed them (a 2D table's marginal gives it its total).
    sum: f64,
    integral: f64,
    min: f64,
    max: f64,
    cell: f64,
    inv_cell: f64,
}

impl PiecewiseConstant1D {
    /// Builds the sampler of the density ∝ `values` on `[min, max]`.
    ///
    /// Errors, in 1D terms: no value ([`EmptyInterval`](PiecewiseConstantError::EmptyInterval)),
    /// a degenerate interval ([`InvalidInterval`](PiecewiseConstantError::InvalidInterval)), a
    /// NaN/infinite or negative value named by its cell index
    /// ([`NonFiniteValue`](PiecewiseConstantError::NonFiniteValue),
    /// [`NegativeValue`](PiecewiseConstantError::NegativeValue)), all values zero, or an
    /// overflowing sum.
    pub fn new(values: Vec<f64>, min: f64, max: f64) -> Result<Self, PiecewiseConstantError> {
        if values.is_empty() {
            return Err(PiecewiseConstantError::EmptyInterval);
        }
        if !(min.is_finite() && max.is_finite() && min < max) {
            return Err(PiecewiseConstantError::InvalidInterval { min, max });
        }
        validate_values(&values)?;
        let mut cdf = vec![0.0; values.len() + 1];
        let sum = fill_cdf(&values, &mut cdf);
        if !sum.is_finite() {
            return Err(PiecewiseConstantError::TotalNotFinite);
        }
        if !(sum > 0.0) {
            return Err(PiecewiseConstantError::AllZero);
        }
        let mut guide = vec![0u32; values.len() * GUIDE_PER_CELL];
        fill_guide(&cdf, &mut guide);
        let n = values.len() as f64;
        let integral = finite_integral(sum * (max - min) / n)?;
        Ok(Self {
            values,
            cdf,
            guide,
            sum,
            integral,
            min,
            max,
            cell: (max - min) / n,
            inv_cell: n / (max - min),
        })
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Always `false`: construction rejects empty tables.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// `∫ f(x) dx` over `[min, max]` of the (unnormalised) step function.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// The interval `(min, max)`.
    pub fn domain(&self) -> (f64, f64) {
        (self.min, self.max)
    }

    /// The cell values as given.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The normalised CDF at the `n + 1` cell boundaries (`cdf[0] = 0`, `cdf[n] = 1`).
    pub fn cdf(&self) -> &[f64] {
        &self.cdf
    }

    /// Warps one uniform `u ∈ [0,1)` (clamped into it) to a point, its pdf and its cell.
    #[inline]
    pub fn sample(&self, u: f64) -> Sample1 {
        let (index, du) = self.find(u);
        Sample1 {
            x: self.place(index, du),
            pdf: self.values[index] / self.integral,
            index,
        }
    }

    /// The cell `i` with `cdf[i] ≤ u < cdf[i+1]` of `u` (clamped into `[0, 1)`) and the
    /// position of `u` inside it, from the guide table (the binary search's answer).
    #[inline(always)]
    pub(crate) fn find(&self, u: f64) -> (usize, f64) {
        find_cell_guided(&self.cdf, &self.guide, clamp_unit(u))
    }

    /// [`Self::find`] by the one-cell-at-a-time scan (the same cell and position).
    #[inline(always)]
    pub(crate) fn find_stepwise(&self, u: f64) -> (usize, f64) {
        let u = clamp_unit(u);
        let g = guide_bucket(u, self.guide.len());
        scan_stepwise_by(&self.cdf, |&c| c, self.guide[g] as usize, u)
    }

    /// The point at position `du ∈ [0, 1)` of cell `index`, in `[min, max)` and inside that
    /// cell as [`Self::pdf`] locates it.
    #[inline(always)]
    pub(crate) fn place(&self, index: usize, du: f64) -> f64 {
        place(self.min, self.max, self.cell, self.inv_cell, index, du)
    }

    /// The guide table of [`Self::cdf`] (one entry per cell, [`fill_guide`]).
    #[inline(always)]
    pub(crate) fn guide(&self) -> &[u32] {
        &self.guide
    }

    /// `Σ values` (unnormalised, before the cell width).
    pub(crate) fn sum(&self) -> f64 {
        self.sum
    }

    /// The cell of `x ∈ [min, max]` and the position of `x` inside it; `None` outside.
    #[inline]
    pub(crate) fn locate(&self, x: f64) -> Option<(usize, f64)> {
        if !(x >= self.min && x <= self.max) {
            return None;
        }
        Some(cell_of((x - self.min) * self.inv_cell, self.values.len()))
    }

    /// Density at `x` with respect to length; 0 outside `[min, max]`.
    pub fn pdf(&self, x: f64) -> f64 {
        match self.locate(x) {
            Some((i, _)) => self.values[i] / self.integral,
            None => 0.0,
        }
    }

    /// The `u` that [`Self::sample`] maps to `x`; `None` outside `[min, max]` or where the
    /// density is zero.
    pub fn invert(&self, x: f64) -> Option<f64> {
        let (i, du) = self.locate(x)?;
        if self.values[i] == 0.0 {
            return None;
        }
        Some(self.invert_cell(i, du))
    }

    /// The `u` mapped to position `du ∈ [0, 1]` of cell `i`.
    #[inline]
    pub(crate) fn invert_cell(&self, i: usize, du: f64) -> f64 {
        invert_cell(&self.cdf, i, du)
    }

    /// Heap and inline bytes used by the table.
    pub fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + (self.values.capacity() + self.cdf.capacity()) * std::mem::size_of::<f64>()
            + self.guide.capacity() * std::mem::size_of::<u32>()
    }
}

/// Serialised form: the inputs and a format version; deserialisation re-validates them.
#[derive(Serialize, Deserialize)]
struct Table1DData {
    version: u32,
    min: f64,
    max: f64,
    values: Vec<f64>,
}

impl TryFrom<Table1DData> for PiecewiseConstant1D {
    type Error = PiecewiseConstantError;
    fn try_from(d: Table1DData) -> Result<Self, PiecewiseConstantError> {
        check_version(d.version)?;
        Self::new(d.values, d.min, d.max)
    }
}

impl From<PiecewiseConstant1D> for Table1DData {
    fn from(t: PiecewiseConstant1D) -> Self {
        Self {
            version: FORMAT_VERSION,
            min: t.min,
            max: t.max,
            values: t.values,
        }
    }
}
