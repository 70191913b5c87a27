//! Pearson chi-square goodness of fit over binned counts, with pooling of sparse cells.

use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

use crate::error::StatsError;
use crate::outcome::TestOutcome;

/// The conventional pooling threshold: cells expecting fewer than 5 samples are pooled.
pub const DEFAULT_MIN_EXPECTED: f64 = 5.0;

/// Result of [`chi_square_gof`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChiSquareResult {
    /// Pearson statistic `X² = Σ (O − E)² / E` over the cells after pooling
    /// (`+∞` when samples fell where the expected count is zero).
    pub statistic: f64,
    /// Degrees of freedom, `cells − 1`.
    pub dof: usize,
    /// Upper-tail probability `P(χ²_dof ≥ X²)`; exactly 0 for samples where the pdf integrates to zero.
    pub p_value: f64,
    /// Number of input cells with `0 < E < min_expected` that were merged into the pooled cell.
    pub pooled_cells: usize,
    /// Number of cells entering the statistic after pooling (the pooled cell counts as one).
    pub cells: usize,
    /// Samples that landed in cells whose expected count is exactly zero
    /// ("samples where the pdf integrates to zero"); any such sample rejects the null.
    pub zero_mass_samples: u64,
}

impl ChiSquareResult {
    /// One-line human-readable summary of the statistic, degrees of freedom and pooling.
    pub fn summary(&self) -> String {
        if self.zero_mass_samples > 0 {
            format!(
                "{} samples where the pdf integrates to zero (immediate rejection)",
                self.zero_mass_samples
            )
        } else {
            format!(
                "X2 = {:.4}, dof = {}, p = {:.4e}; {} cells ({} pooled)",
                self.statistic, self.dof, self.p_value, self.cells, self.pooled_cells
            )
        }
    }

    /// The uniform [`TestOutcome`] of this result at significance level `alpha`
    /// (passed iff `p ≥ alpha`).
    pub fn outcome(&self, name: &str, alpha: f64) -> TestOutcome {
        TestOutcome::with_p_value(name, self.statistic, self.p_value, alpha, self.summary())
    }
}

/// Pearson chi-square goodness-of-fit test of observed counts against expected counts.
///
/// `expected[i]` is the expected number of samples in cell `i` (`N × ∫_cell pdf`), so the
/// statistic also sees a density that does not integrate to one. Cells are treated as follows:
/// - `E = 0` and `O = 0`: ignored (outside the support, nothing observed);
/// - `E = 0` and `O > 0`: samples where the pdf integrates to zero — immediate rejection,
///   `statistic = +∞`, `p_value = 0`, counted in `zero_mass_samples`;
/// - `0 < E < min_expected`: summed into one pooled cell; if the pooled cell still expects
///   fewer than `min_expected` samples it is merged into the remaining cell with the smallest
///   expected count (the first such cell on ties);
/// - otherwise the cell enters the statistic as it is.
///
/// Degrees of freedom are `cells − 1`; the p-value is the chi-square survival function
/// (statrs `ChiSquared::sf`).
///
/// # Errors
/// Length mismatch, a negative or non-finite expected count, a non-positive `min_expected`,
/// or fewer than two cells left after pooling (when no zero-mass sample already decides the test).
pub fn chi_square_gof(
    observed: &[u64],
    expected: &[f64],
    min_expected: f64,
) -> Result<ChiSquareResult, StatsError> {
    if observed.len() != expected.len() {
        return Err(StatsError::LengthMismatch {
            observed: observed.len(),
            expected: expected.len(),
        });
    }
    if !(min_expected > 0.0 && min_expected.is_finite()) {
        return Err(StatsError::InvalidMinExpected(min_expected));
    }
    if let Some((index, &value)) = expected
        .iter()
        .enumerate()
        .find(|(_, e)| !(**e >= 0.0 && e.is_finite()))
    {
        return Err(StatsError::InvalidExpected { index, value });
    }

    let mut cells: Vec<(f64, f64)> = Vec::with_capacity(expected.len());
    let mut pooled = (0.0_f64, 0.0_f64);
    let mut pooled_cells = 0usize;
    let mut zero_mass_samples = 0u64;
    for (&o, &e) in observed.iter().zip(expected) {
        if e == 0.0 {
            zero_mass_samples = zero_mass_samples.saturating_add(o);
        } else if e < min_expected {
            pooled.0 += o as f64;
            pooled.1 += e;
            pooled_cells += 1;
        } else {
            cells.push((o as f64, e));
        }
    }
    if pooled_cells > 0 {
        if pooled.1 >= min_expected || cells.is_empty() {
            cells.push(pooled);
        } else {
            let mut smallest = 0;
            for (i, c) in cells.iter().enumerate() {
                if c.1 < cells[smallest].1 {
                    smallest = i;
                }
            }
            cells[smallest].0 += pooled.0;
            cells[smallest].1 += pooled.1;
        }
    }

    let n_cells = cells.len();
    if zero_mass_samples > 0 {
        return Ok(ChiSquareResult {
            statistic: f64::INFINITY,
            dof: n_cells.saturating_sub(1),
            p_value: 0.0,
            pooled_cells,
            cells: n_cells,
            zero_mass_samples,
        });
    }
    if n_cells < 2 {
        return Err(StatsError::TooFewCells { cells: n_cells });
    }
    let statistic: f64 = cells
        .iter()
        .map(|&(o, e)| {
            let d = o - e;
            d * d / e
        })
        .sum();
    let dof = n_cells - 1;
    let p_value = chi_square_sf(statistic, dof);
    Ok(ChiSquareResult {
        statistic,
        dof,
        p_value,
        pooled_cells,
        cells: n_cells,
        zero_mass_samples,
    })
}

/// Upper tail `P(χ²_dof ≥ x)` of the chi-square distribution (statrs), clamped to `[0, 1]`.
/// Returns NaN for `dof = 0`.
pub fn chi_square_sf(x: f64, dof: usize) -> f64 {
    match ChiSquared::new(dof as f64) {
        Ok(dist) => dist.sf(x).clamp(0.0, 1.0),
        Err(_) => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn hand_computed_example() {
        // Cells 3 and 4 (E = 2 and 4) pool into one cell with E = 6 >= 5.
        let r = chi_square_gof(&[12, 8, 1, 5], &[10.0, 10.0, 2.0, 4.0], 5.0).unwrap();
        assert_eq!(r.cells, 3);
        assert_eq!(r.pooled_cells, 2);
        assert_eq!(r.dof, 2);
        let x2 = 4.0 / 10.0 + 4.0 / 10.0 + 0.0 / 6.0;
        assert_relative_eq!(r.statistic, x2, max_relative = 1e-14);
        // dof 2: sf(x) = exp(-x/2).
        assert_relative_eq!(r.p_value, (-x2 / 2.0).exp(), max_relative = 1e-10);
    }
}
