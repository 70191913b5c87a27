//! The suite's test names and the outcome helpers shared by the case runner ([`crate::case`])
//! and the exact cell tests ([`crate::cells`]): a leaf module, so neither of those imports the
//! other for them.

use stats::{Binning, DEFAULT_MIN_EXPECTED, TestOutcome, chi_square_gof, histogram};

/// Test names, in report order.
pub mod names {
    /// Pearson chi-square of the one-sample draws against the reported pdf.
    pub const CHI_SQUARE: &str = "chi-square";
    /// Chi-square of the pooled batch draws.
    pub const BATCH_CHI_SQUARE: &str = "batch-chi-square";
    /// pdf returned with samples equals `pdf(x)` and is positive.
    pub const PDF_CONSISTENCY: &str = "pdf-consistency";
    /// `∫ pdf = 1` within the plan's tolerance.
    pub const NORMALISATION: &str = "normalisation";
    /// No region where the target is positive and the pdf is not.
    pub const SUPPORT: &str = "support-coverage";
    /// One-sample estimator z-test against the reference.
    pub const UNBIASEDNESS: &str = "unbiasedness";
    /// Every batch returned the number of samples asked for.
    pub const BATCH_SIZE: &str = "batch-size";
    /// z-test of the per-batch estimates against the reference.
    pub const BATCH_UNBIASEDNESS: &str = "batch-unbiasedness";
    /// Zero bound violations during the run.
    pub const BOUND_AUDIT: &str = "bound-audit";
    /// The sampler could be built.
    pub const BUILD: &str = "build";
    /// The sampler does not apply to this target (e.g. `analytic` for a model without an
    /// analytic sampler): reported, not failed.
    pub const SKIPPED: &str = "skipped";
}

/// A passed deterministic outcome recording that the case was skipped, and why.
pub(crate) fn skipped_outcome(reason: impl std::fmt::Display) -> TestOutcome {
    TestOutcome::deterministic(names::SKIPPED, f64::NAN, true, format!("skipped: {reason}"))
}

/// A failed deterministic outcome describing an error that prevented a test.
pub(crate) fn error_outcome(name: &str, error: impl std::fmt::Display) -> TestOutcome {
    TestOutcome::deterministic(name, f64::NAN, false, format!("error: {error}"))
}

/// Pearson χ² of `points` binned by `binning` against the cell `masses` (plus an empty
/// "outside" cell), judged at `alpha`.
pub(crate) fn chi_square<P: Copy + Send + Sync>(
    name: &str,
    binning: &dyn Binning<Point = P>,
    masses: &[f64],
    points: &[P],
    alpha: f64,
) -> TestOutcome {
    if points.is_empty() {
        return error_outcome(name, "no samples");
    }
    let hist = histogram(binning, points);
    let n = points.len() as f64;
    let mut observed = hist.counts;
    let mut expected: Vec<f64> = masses.iter().map(|m| m * n).collect();
    observed.push(hist.outside);
    expected.push(0.0);
    match chi_square_gof(&observed, &expected, DEFAULT_MIN_EXPECTED) {
        Ok(r) => r.outcome(name, alpha),
        Err(e) => error_outcome(name, e),
    }
}
