//! The piecewise-constant density on an interval, sampled by CDF inversion.

use serde::{Deserialize, Serialize};

use super::PiecewiseConstantError;
use super::cdf::{cell_of, clamp_unit, fill_cdf, find_cell, invert_cell, place, validate_values};

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
        // One row: the 2D kernel's (column, 0) is the cell index.
        validate_values(&values, values.len()).map_err(|e| match e {
            PiecewiseConstantError::NonFinite { column, value, .. } => {
                PiecewiseConstantError::NonFiniteValue {
                    index: column,
                    value,
                }
            }
            PiecewiseConstantError::Negative { column, value, .. } => {
                PiecewiseConstantError::NegativeValue {
                    index: column,
                    value,
                }
            }
            other => other,
        })?;
        let mut cdf = vec![0.0; values.len() + 1];
        let sum = fill_cdf(&values, &mut cdf);
        if !sum.is_finite() {
            return Err(PiecewiseConstantError::TotalNotFinite);
        }
        if !(sum > 0.0) {
            return Err(PiecewiseConstantError::AllZero);
        }
        let n = values.len() as f64;
        let integral = sum * (max - min) / n;
        if !(integral.is_finite() && integral > 0.0) {
            return Err(PiecewiseConstantError::TotalNotFinite);
        }
        Ok(Self {
            values,
            cdf,
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
        let (index, du) = find_cell(&self.cdf, clamp_unit(u));
        let x = place(self.min, self.max, self.cell, self.inv_cell, index, du);
        Sample1 {
            x,
            pdf: self.values[index] / self.integral,
            index,
        }
    }

    /// Density at `x` with respect to length; 0 outside `[min, max]`.
    pub fn pdf(&self, x: f64) -> f64 {
        if !(x >= self.min && x <= self.max) {
            return 0.0;
        }
        let (i, _) = cell_of((x - self.min) * self.inv_cell, self.values.len());
        self.values[i] / self.integral
    }

    /// The `u` that [`Self::sample`] maps to `x`; `None` outside `[min, max]` or where the
    /// density is zero.
    pub fn invert(&self, x: f64) -> Option<f64> {
        if !(x >= self.min && x <= self.max) {
            return None;
        }
        let (i, du) = cell_of((x - self.min) * self.inv_cell, self.values.len());
        if self.values[i] == 0.0 {
            return None;
        }
        Some(invert_cell(&self.cdf, i, du))
    }

    /// Heap and inline bytes used by the table.
    pub fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + (self.values.capacity() + self.cdf.capacity()) * std::mem::size_of::<f64>()
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

const FORMAT_VERSION: u32 = 1;

impl TryFrom<Table1DData> for PiecewiseConstant1D {
    type Error = PiecewiseConstantError;
    fn try_from(d: Table1DData) -> Result<Self, PiecewiseConstantError> {
        if d.version != FORMAT_VERSION {
            return Err(PiecewiseConstantError::FormatVersion {
                found: d.version,
                expected: FORMAT_VERSION,
            });
        }
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
