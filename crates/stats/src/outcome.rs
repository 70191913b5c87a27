//! Uniform test outcomes, the Šidák correction, and the suite that applies it.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::StatsError;

/// The outcome of one test of a sampler.
///
/// Statistical tests carry a p-value and pass iff `p ≥` their significance level;
/// deterministic checks (pdf consistency, normalisation, support) carry no p-value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TestOutcome {
    /// Test name.
    pub name: String,
    /// The test statistic (its meaning is stated in `detail` and by the producing function).
    pub statistic: f64,
    /// p-value for statistical tests, `None` for deterministic checks.
    pub p_value: Option<f64>,
    /// Whether the sampler passed.
    pub passed: bool,
    /// Human-readable details (counts, tolerances, failure reasons).
    pub detail: String,
}

impl TestOutcome {
    /// A statistical outcome judged at level `alpha`: passed iff `p ≥ alpha` (NaN fails).
    pub fn with_p_value(
        name: &str,
        statistic: f64,
        p_value: f64,
        alpha: f64,
        detail: String,
    ) -> Self {
        Self {
            name: name.to_owned(),
            statistic,
            p_value: Some(p_value),
            passed: p_value >= alpha,
            detail,
        }
    }

    /// A deterministic outcome (no p-value).
    pub fn deterministic(name: &str, statistic: f64, passed: bool, detail: String) -> Self {
        Self {
            name: name.to_owned(),
            statistic,
            p_value: None,
            passed,
            detail,
        }
    }
}

impl fmt::Display for TestOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verdict = if self.passed { "PASS" } else { "FAIL" };
        match self.p_value {
            Some(p) => write!(
                f,
                "[{verdict}] {}: statistic = {:.6e}, p = {:.4e}; {}",
                self.name, self.statistic, p, self.detail
            ),
            None => write!(
                f,
                "[{verdict}] {}: statistic = {:.6e}; {}",
                self.name, self.statistic, self.detail
            ),
        }
    }
}

/// Šidák per-test level `1 − (1 − α)^{1/m}`: `m` independent tests at this level reject a
/// correct sampler with total probability `α`. `m = 0` returns `α`; NaN for `α ∉ [0, 1]`.
pub fn sidak_level(alpha: f64, m: usize) -> f64 {
    if !(0.0..=1.0).contains(&alpha) {
        return f64::NAN;
    }
    if m == 0 {
        return alpha;
    }
    // 1 − exp(ln(1 − α)/m), computed without cancellation.
    -((-alpha).ln_1p() / m as f64).exp_m1()
}

/// Collects the outcomes of a validation run and judges them with a Šidák-corrected level.
///
/// The family-wise level `α` is shared by the `m` outcomes that carry a p-value (deterministic
/// checks cannot reject a correct sampler by chance, so they use none of it); each of those
/// passes iff `p ≥ sidak_level(α, m)`. The suite passes iff every outcome passes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Suite {
    alpha: f64,
    outcomes: Vec<TestOutcome>,
}

impl Suite {
    /// An empty suite with family-wise significance level `alpha ∈ (0, 1)`.
    ///
    /// # Errors
    /// [`StatsError::InvalidAlpha`].
    pub fn new(alpha: f64) -> Result<Self, StatsError> {
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(StatsError::InvalidAlpha(alpha));
        }
        Ok(Self {
            alpha,
            outcomes: Vec::new(),
        })
    }

    /// Adds an outcome.
    pub fn push(&mut self, outcome: TestOutcome) {
        self.outcomes.push(outcome);
    }

    /// The family-wise level.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Outcomes as pushed (not yet re-judged).
    pub fn outcomes(&self) -> &[TestOutcome] {
        &self.outcomes
    }

    /// Number of outcomes with a p-value (the `m` of the correction).
    pub fn m(&self) -> usize {
        self.outcomes.iter().filter(|o| o.p_value.is_some()).count()
    }

    /// The Šidák per-test level for the current `m`.
    pub fn per_test_level(&self) -> f64 {
        sidak_level(self.alpha, self.m())
    }

    /// Judges every outcome: p-valued ones at the per-test level, deterministic ones as given.
    pub fn report(&self) -> SuiteReport {
        let level = self.per_test_level();
        let outcomes: Vec<TestOutcome> = self
            .outcomes
            .iter()
            .map(|o| {
                let mut o = o.clone();
                if let Some(p) = o.p_value {
                    o.passed = p >= level;
                }
                o
            })
            .collect();
        SuiteReport {
            alpha: self.alpha,
            m: self.m(),
            per_test_level: level,
            passed: outcomes.iter().all(|o| o.passed),
            outcomes,
        }
    }
}

/// A judged suite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SuiteReport {
    /// Family-wise significance level.
    pub alpha: f64,
    /// Number of outcomes with a p-value.
    pub m: usize,
    /// Šidák per-test level `1 − (1 − α)^{1/m}`.
    pub per_test_level: f64,
    /// Outcomes with `passed` re-judged at `per_test_level`.
    pub outcomes: Vec<TestOutcome>,
    /// Whether every outcome passed.
    pub passed: bool,
}

impl SuiteReport {
    /// The failed outcomes.
    pub fn failures(&self) -> impl Iterator<Item = &TestOutcome> {
        self.outcomes.iter().filter(|o| !o.passed)
    }
}

impl fmt::Display for SuiteReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "suite {}: alpha = {}, m = {}, per-test level = {:.4e}",
            if self.passed { "PASSED" } else { "FAILED" },
            self.alpha,
            self.m,
            self.per_test_level
        )?;
        for o in &self.outcomes {
            writeln!(f, "  {o}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn sidak_inverts_to_the_family_level() {
        for (alpha, m) in [(0.01, 1usize), (0.01, 7), (0.05, 100), (1e-6, 3)] {
            let a = sidak_level(alpha, m);
            let family = 1.0 - (1.0 - a).powi(m as i32);
            assert_relative_eq!(family, alpha, max_relative = 1e-9);
            assert!(a >= alpha / m as f64);
        }
        assert_eq!(sidak_level(0.01, 0), 0.01);
        assert!(sidak_level(1.5, 3).is_nan());
    }
}
