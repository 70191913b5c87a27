//! The data of a ranking — verdicts, entries, the ranking of one comparison — and the
//! estimator names, apart from the rule that makes them (module [`crate::ranking`]): the
//! results (module `results`) and the groups hold rankings and estimator names without
//! depending on the rule, so no two files of the crate import each other.

use serde::{Deserialize, Serialize};

/// Family-wise significance level of the comparisons with the best, per comparison.
pub const ALPHA: f64 = 0.05;

/// Name of the multiple-comparison rule.
pub const RULE: &str = "sidak";

/// The estimator of the study's main cells: BRDF sampling alone.
pub const ESTIMATOR_BRDF: &str = "brdf";

/// Light sampling alone (its comparisons rank the map samplers).
pub const ESTIMATOR_LIGHT: &str = "light";

/// `best`, `tied` or `worse`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// The point-estimate most efficient sampler.
    Best,
    /// Its efficiency ratio's interval contains 1.
    Tied,
    /// Significantly less efficient than the best.
    Worse,
}

impl Verdict {
    /// `best`, `tied` or `worse`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Best => "best",
            Verdict::Tied => "tied",
            Verdict::Worse => "worse",
        }
    }
}

/// One sampler (sampler and mode) of a comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// `sampler` or `sampler (batch)` ([`crate::CellResult::label`]).
    pub sampler: String,
    /// The cell's `index` (the `index` column of results.csv).
    pub cell: usize,
    /// Its verdict.
    pub verdict: Verdict,
    /// Efficiency `1 / (MSE × s per sample)`; `None` for an exact (zero-variance) sampler.
    pub efficiency: Option<f64>,
    /// `se(ln efficiency)` (MSE and time parts in quadrature).
    pub se_log_efficiency: Option<f64>,
    /// Its part from the MSE, `se(ln MSE)`.
    pub se_log_mse: Option<f64>,
    /// Its part from the time, `se(ln t)` over the timing repeats.
    pub se_log_time: Option<f64>,
    /// `E_best / E_x` (1 for the best; `None` when either is exact).
    pub ratio: Option<f64>,
    /// Lower end of the ratio's interval at the corrected level.
    pub ratio_lo: Option<f64>,
    /// Upper end of the ratio's interval at the corrected level.
    pub ratio_hi: Option<f64>,
    /// `worse` only because of the time: the MSE ratio's interval alone contains 1.
    pub by_time: bool,
    /// The cell's spread estimate is unreliable (it has warnings, ⚠ in the report): its
    /// interval is optimistic.
    pub unreliable: bool,
    /// BRDF evaluations per sample made by the sampler (a cost that does not depend on load).
    pub evaluations_per_sample: f64,
}

/// A sampler of the comparison left out, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Excluded {
    /// Sampler label.
    pub sampler: String,
    /// The cell's `index`.
    pub cell: usize,
    /// Why.
    pub reason: String,
}

/// The ranking of one comparison (BRDF, θo, light, estimator).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ranking {
    /// BRDF spec.
    pub brdf: String,
    /// Outgoing polar angle (degrees).
    pub theta_o: f64,
    /// Light spec.
    pub light: String,
    /// Estimator ([`ESTIMATOR_BRDF`]).
    pub estimator: String,
    /// The map sampler every ranked BRDF sampler is paired with (MIS comparisons only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light_sampler: Option<String>,
    /// The most efficient sampler (point estimate).
    pub best: String,
    /// The samplers statistically tied with it.
    pub tied: Vec<String>,
    /// The samplers significantly less efficient.
    pub worse: Vec<String>,
    /// Family-wise level α of the comparison.
    pub alpha: f64,
    /// Multiple-comparison rule ([`RULE`]).
    pub rule: String,
    /// Comparisons with the best (`m`).
    pub comparisons: usize,
    /// Two-sided confidence level of each interval, `(1 − α)^(1/m)`.
    pub level: f64,
    /// Every sampler that was ranked, best first then by decreasing efficiency.
    pub entries: Vec<Entry>,
    /// Samplers left out.
    pub excluded: Vec<Excluded>,
}

impl Ranking {
    /// The cell indices (results.csv `index`) of the ranked samplers.
    pub fn rows(&self) -> Vec<usize> {
        self.entries.iter().map(|e| e.cell).collect()
    }

    /// [`Self::rows`] as text: `3, 7, 9`.
    pub fn rows_text(&self) -> String {
        self.rows()
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The entry of `sampler`.
    pub fn entry(&self, sampler: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.sampler == sampler)
    }
}
