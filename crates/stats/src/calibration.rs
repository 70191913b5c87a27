//! Calibration: how often does a test reject a *correct* sampler?

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use statrs::distribution::{Binomial, DiscreteCDF};

use crate::error::StatsError;

/// Observed rejection rate of a test over many seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Nominal level: a run rejects iff `p < alpha`.
    pub alpha: f64,
    /// Number of runs (seeds).
    pub runs: usize,
    /// Number of rejections.
    pub rejections: usize,
    /// `rejections / runs`.
    pub rate: f64,
    /// The p-value of every run, in seed order.
    pub p_values: Vec<f64>,
    /// Two-sided binomial p-value of `rejections` under `Binomial(runs, alpha)`:
    /// small values mean the rate is inconsistent with the nominal level.
    pub binomial_p_value: f64,
}

impl Calibration {
    /// The same runs judged at another level `alpha` (the p-values are reused).
    ///
    /// # Errors
    /// [`StatsError::InvalidAlpha`].
    pub fn with_alpha(&self, alpha: f64) -> Result<Calibration, StatsError> {
        from_p_values(self.p_values.clone(), alpha)
    }
}

fn from_p_values(p_values: Vec<f64>, alpha: f64) -> Result<Calibration, StatsError> {
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(StatsError::InvalidAlpha(alpha));
    }
    let runs = p_values.len();
    let rejections = p_values.iter().filter(|&&p| !(p >= alpha)).count();
    Ok(Calibration {
        alpha,
        runs,
        rejections,
        rate: rejections as f64 / runs.max(1) as f64,
        binomial_p_value: binomial_two_sided(rejections, runs, alpha),
        p_values,
    })
}

/// Runs `test(seed)` (returning a p-value) for every seed, in parallel, and counts rejections
/// at level `alpha`. Deterministic: one run per seed, results in seed order.
///
/// # Errors
/// An invalid `alpha`, no seeds, or the first error returned by a run.
pub fn calibrate<F>(seeds: &[u64], alpha: f64, test: F) -> Result<Calibration, StatsError>
where
    F: Fn(u64) -> Result<f64, StatsError> + Sync,
{
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(StatsError::InvalidAlpha(alpha));
    }
    if seeds.is_empty() {
        return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
    }
    let p_values = seeds
        .par_iter()
        .map(|&s| test(s))
        .collect::<Result<Vec<f64>, StatsError>>()?;
    from_p_values(p_values, alpha)
}

/// `min(1, 2 min(P(X ≤ k), P(X ≥ k)))` for `X ~ Binomial(n, p)`.
fn binomial_two_sided(k: usize, n: usize, p: f64) -> f64 {
    let Ok(b) = Binomial::new(p, n as u64) else {
        return f64::NAN;
    };
    let lower = b.cdf(k as u64);
    let upper = if k == 0 { 1.0 } else { b.sf(k as u64 - 1) };
    (2.0 * lower.min(upper)).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomial_p_value_is_large_at_the_mean_and_small_far_away() {
        assert!(binomial_two_sided(10, 200, 0.05) > 0.5);
        assert!(binomial_two_sided(0, 200, 0.05) < 1e-3);
        assert!(binomial_two_sided(30, 200, 0.05) < 1e-5);
    }
}
