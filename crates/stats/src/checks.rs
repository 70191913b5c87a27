//! Sampler checks that produce [`TestOutcome`]s: chi-square and KS on a binned domain,
//! pdf consistency, normalisation, support coverage, and estimator unbiasedness.

use rayon::prelude::*;

use crate::binning::{Axis, Binning, histogram};
use crate::cdf::{
    MarginalMemo, project, projection_cdf_with_memo, projection_cdf_with_singularities,
};
use crate::chi_square::{ChiSquareResult, DEFAULT_MIN_EXPECTED, chi_square_gof};
use crate::error::StatsError;
use crate::ks::ks_onesample;
use crate::outcome::TestOutcome;
use crate::quadrature::{GaussLegendre, PatchMap, QuadratureOptions, integrate};

/// Chi-square test of `points` against `pdf` on `binning`.
///
/// Observed counts per bin, expected counts `N ∫_bin pdf dμ` by [`crate::expected_masses_with`]
/// (accuracy tied to `N`), pooling below [`DEFAULT_MIN_EXPECTED`]. Points outside the binned
/// domain form one extra cell with expected count zero, so any of them rejects the sampler
/// (reported as samples where the pdf integrates to zero).
///
/// # Errors
/// Empty `points`, invalid options, a pdf whose bin masses are negative or non-finite, or too
/// few cells after pooling.
pub fn chi_square_test<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    points: &[B::Point],
    opts: &QuadratureOptions,
) -> Result<ChiSquareResult, StatsError> {
    if points.is_empty() {
        return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
    }
    let hist = histogram(binning, points);
    let n = points.len() as u64;
    let table = crate::quadrature::expected_masses_with(pdf, binning, n, opts)?;
    let mut observed = hist.counts;
    let mut expected: Vec<f64> = table.masses.iter().map(|m| m * n as f64).collect();
    observed.push(hist.outside);
    expected.push(0.0);
    chi_square_gof(&observed, &expected, DEFAULT_MIN_EXPECTED)
}

/// One-sample KS test of the projection of `points` onto parameter axis `axis` against the
/// projection of `pdf` (its CDF tabulated by [`crate::projection_cdf`]), judged at level `alpha`.
///
/// Points outside the domain fail the test outright (`p = 0`).
///
/// # Errors
/// Empty `points`, invalid options, or a pdf whose projection is not a valid CDF.
pub fn ks_projection_test<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    points: &[B::Point],
    axis: Axis,
    alpha: f64,
    opts: &QuadratureOptions,
) -> Result<TestOutcome, StatsError> {
    ks_projection_test_with_singularities(binning, pdf, points, axis, alpha, opts, &[])
}

/// [`ks_projection_test`] for a pdf with integrable point singularities at the parameter
/// coordinates `singular` (its CDF tabulated by [`projection_cdf_with_singularities`], which
/// grades its quadrature towards them).
///
/// # Errors
/// As [`ks_projection_test`].
pub fn ks_projection_test_with_singularities<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    points: &[B::Point],
    axis: Axis,
    alpha: f64,
    opts: &QuadratureOptions,
    singular: &[[f64; 2]],
) -> Result<TestOutcome, StatsError> {
    ks_projection(binning, pdf, points, axis, alpha, opts, singular, None)
}

/// [`ks_projection_test_with_singularities`] with the CDF's marginals reused from (and kept in)
/// `memo` ([`MarginalMemo`]; for runs repeated pass by pass over batched pdf values). The same
/// outcome as without it when the memo belongs to the same inputs.
///
/// # Errors
/// As [`ks_projection_test`].
#[allow(clippy::too_many_arguments)]
pub fn ks_projection_test_with_memo<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    points: &[B::Point],
    axis: Axis,
    alpha: f64,
    opts: &QuadratureOptions,
    singular: &[[f64; 2]],
    memo: &MarginalMemo,
) -> Result<TestOutcome, StatsError> {
    ks_projection(
        binning,
        pdf,
        points,
        axis,
        alpha,
        opts,
        singular,
        Some(memo),
    )
}

#[allow(clippy::too_many_arguments)]
fn ks_projection<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    points: &[B::Point],
    axis: Axis,
    alpha: f64,
    opts: &QuadratureOptions,
    singular: &[[f64; 2]],
    memo: Option<&MarginalMemo>,
) -> Result<TestOutcome, StatsError> {
    if points.is_empty() {
        return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
    }
    let name = format!("KS projection {axis:?}");
    let proj = project(binning, points, axis);
    if proj.outside > 0 {
        return Ok(TestOutcome::with_p_value(
            &name,
            f64::INFINITY,
            0.0,
            alpha,
            format!("{} samples outside the domain", proj.outside),
        ));
    }
    let n = points.len() as u64;
    let cdf = match memo {
        Some(memo) => projection_cdf_with_memo(binning, pdf, axis, n, opts, singular, memo)?,
        None => projection_cdf_with_singularities(binning, pdf, axis, n, opts, singular)?,
    };
    let r = ks_onesample(&proj.values, &|x| cdf.eval(x))?;
    Ok(r.outcome(&name, alpha))
}

/// pdf consistency: the density returned with each sample equals `pdf(point)` re-evaluated,
/// within relative tolerance `rel_tol` (1e-6 is typical), and both are > 0 (a sample can only
/// land where the density is positive).
///
/// The statistic is the largest relative discrepancy `|p_s − p_e| / max(|p_s|, |p_e|)`.
///
/// # Errors
/// Empty `samples` or an invalid tolerance.
pub fn pdf_consistency<P: Copy>(
    samples: &[(P, f64)],
    pdf: &dyn Fn(P) -> f64,
    rel_tol: f64,
) -> Result<TestOutcome, StatsError> {
    if samples.is_empty() {
        return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
    }
    if !(rel_tol > 0.0 && rel_tol.is_finite()) {
        return Err(StatsError::InvalidTolerance(rel_tol));
    }
    let mut worst = (0.0_f64, 0usize, 0.0, 0.0);
    let (mut mismatches, mut non_positive) = (0usize, 0usize);
    for (i, &(p, returned)) in samples.iter().enumerate() {
        let again = pdf(p);
        let scale = returned.abs().max(again.abs());
        let rel = if returned == again {
            0.0
        } else if scale > 0.0 && scale.is_finite() {
            (returned - again).abs() / scale
        } else {
            f64::INFINITY
        };
        if !(rel <= rel_tol) {
            mismatches += 1;
        }
        if !(returned > 0.0 && again > 0.0) {
            non_positive += 1;
        }
        if !(rel <= worst.0) {
            worst = (rel, i, returned, again);
        }
    }
    let passed = mismatches == 0 && non_positive == 0;
    let detail = format!(
        "{} samples, {} pdf mismatches beyond rel. tol. {:e} (worst {:.3e} at sample {}: returned {:e}, re-evaluated {:e}), {} samples with pdf <= 0",
        samples.len(),
        mismatches,
        rel_tol,
        worst.0,
        worst.1,
        worst.2,
        worst.3,
        non_positive
    );
    Ok(TestOutcome::deterministic(
        "pdf consistency",
        worst.0,
        passed,
        detail,
    ))
}

/// Normalisation: `|∫ pdf dμ − expected_mass| ≤ tolerance` over the binning's domain, with the
/// integral computed by adaptive quadrature to `tolerance / 10`.
///
/// The statistic is `|∫ pdf dμ − expected_mass|`.
///
/// # Errors
/// Invalid tolerance or options.
pub fn normalisation<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    expected_mass: f64,
    tolerance: f64,
    opts: &QuadratureOptions,
) -> Result<TestOutcome, StatsError> {
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return Err(StatsError::InvalidTolerance(tolerance));
    }
    let r = integrate(pdf, binning, 0.1 * tolerance, opts)?;
    let dev = (r.value - expected_mass).abs();
    let detail = format!(
        "integral = {:.10} (quadrature error estimate {:.2e}, {}converged, {} evaluations), expected {}, tolerance {:e}",
        r.value,
        r.error_estimate,
        if r.converged { "" } else { "NOT " },
        r.evaluations,
        expected_mass,
        tolerance
    );
    Ok(TestOutcome::deterministic(
        "normalisation",
        dev,
        dev <= tolerance,
        detail,
    ))
}

/// Largest uncovered target-mass fraction [`support_coverage`] accepts: `10⁻¹²`.
pub const COVERAGE_MASS_TOLERANCE: f64 = 1e-12;

/// Support coverage: the target mass where the pdf is not positive
/// (`target > 0` and `!(pdf > 0)`) is the relative bias of the estimator `target / pdf`.
///
/// Both functions are evaluated at the Gauss–Legendre nodes (order `opts.order`) of every bin
/// patch split into `resolution × resolution` cells. The statistic is the uncovered mass
/// fraction `∫_{pdf = 0} target / ∫ target`; the test passes iff it is at most
/// [`COVERAGE_MASS_TOLERANCE`] (a hole whose mass is below it is numerically invisible: e.g.
/// the underflowing tails of a Beckmann lobe, `f ≈ 10⁻³⁰⁷`). The detail also reports the
/// number of uncovered nodes and the uncovered fraction of the support's measure.
///
/// # Errors
/// `resolution = 0` or invalid options.
pub fn support_coverage<B: Binning + ?Sized>(
    binning: &B,
    target: &(dyn Fn(B::Point) -> f64 + Sync),
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    resolution: usize,
    opts: &QuadratureOptions,
) -> Result<TestOutcome, StatsError> {
    opts.validate()?;
    if resolution == 0 {
        return Err(StatsError::InvalidQuadrature(
            "resolution must be >= 1".into(),
        ));
    }
    let rule = GaussLegendre::new(opts.order);
    let one = |_: B::Point| 1.0;
    // Per bin: (measure where target > 0, measure where also pdf is not > 0, bad nodes,
    // target mass, uncovered target mass).
    let per_bin: Vec<(f64, f64, u64, f64, f64)> = (0..binning.n_bins())
        .into_par_iter()
        .map(|bin| {
            let mut acc = (0.0, 0.0, 0u64, 0.0, 0.0);
            for patch in binning.bin_patches(bin) {
                let map = PatchMap::new(binning, &one, patch);
                let ar = map.a_range();
                let ha = 0.5 * (ar[1] - ar[0]) / resolution as f64;
                let ht = 0.5 / resolution as f64;
                for ci in 0..resolution {
                    let ca = ar[0] + (2 * ci + 1) as f64 * ha;
                    for cj in 0..resolution {
                        let ct = (2 * cj + 1) as f64 * ht;
                        for (xa, wa) in rule.points() {
                            for (xt, wt) in rule.points() {
                                let (uv, w) = map.map(ca + ha * xa, ct + ht * xt);
                                let pt = binning.point_at(uv);
                                let t = target(pt);
                                if t > 0.0 {
                                    let dm = w * wa * wt * ha * ht;
                                    acc.0 += dm;
                                    acc.3 += t * dm;
                                    if !(pdf(pt) > 0.0) {
                                        acc.1 += dm;
                                        acc.2 += 1;
                                        acc.4 += t * dm;
                                    }
                                }
                            }
                        }
                    }
                }
            }
            acc
        })
        .collect();
    let (mut covered, mut missed, mut bad, mut mass, mut lost) = (0.0, 0.0, 0u64, 0.0, 0.0);
    for (c, m, b, t, l) in per_bin {
        covered += c;
        missed += m;
        bad += b;
        mass += t;
        lost += l;
    }
    let fraction = if covered > 0.0 { missed / covered } else { 0.0 };
    let lost_fraction = if mass > 0.0 { lost / mass } else { 0.0 };
    let detail = format!(
        "{bad} test points where target > 0 but pdf is not > 0; uncovered target mass {lost_fraction:.3e} (tolerance {COVERAGE_MASS_TOLERANCE:e}), uncovered fraction of the support's measure {fraction:.3e}"
    );
    Ok(TestOutcome::deterministic(
        "support coverage",
        lost_fraction,
        lost_fraction <= COVERAGE_MASS_TOLERANCE,
        detail,
    ))
}

/// Unbiasedness z-test: is the mean of the estimator values `f(x_i)/pdf(x_i)` consistent with
/// an accurately known `reference` integral?
///
/// `z = (mean − reference) / √(s²/n)` with the unbiased sample variance `s²`; the two-sided
/// p-value is `2 Φ(−|z|)`. Judged at level `alpha`. Non-finite values fail the test outright
/// (`p = 0`). The standard error is floored at `1e-12 · max(|mean|, |reference|)`, so a
/// zero-variance estimator passes iff its mean equals the reference to about 1e-12 relative.
/// The reference must be far more accurate than `√(s²/n)`.
///
/// # Errors
/// Fewer than two values or a non-finite reference.
pub fn mean_z_test(values: &[f64], reference: f64, alpha: f64) -> Result<TestOutcome, StatsError> {
    const NAME: &str = "unbiasedness";
    if values.len() < 2 {
        return Err(StatsError::TooFewSamples {
            needed: 2,
            got: values.len(),
        });
    }
    if !reference.is_finite() {
        return Err(StatsError::InvalidMass { mass: reference });
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Ok(TestOutcome::with_p_value(
            NAME,
            f64::INFINITY,
            0.0,
            alpha,
            format!("estimator value {i} is not finite ({})", values[i]),
        ));
    }
    let (mean, var) = mean_variance(values);
    // Floor the standard error at the rounding level of the values, so a zero-variance
    // estimator is compared with the reference to floating-point accuracy.
    let se = (var / values.len() as f64)
        .sqrt()
        .max(1e-12 * mean.abs().max(reference.abs()));
    let (z, p) = two_sided_z(mean, reference, se);
    let detail = format!(
        "mean {mean:.8e} vs reference {reference:.8e}, standard error {se:.3e}, z = {z:.3}, n = {}",
        values.len()
    );
    Ok(TestOutcome::with_p_value(NAME, z, p, alpha, detail))
}

/// The sample mean of `values` and their unbiased sample variance `Σ (v − mean)² / (n − 1)`
/// (`values` should hold at least two).
pub fn mean_variance(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    (mean, var)
}

/// The two-sided z-test of `mean` against `reference` with standard error `se`: `(z, p)` with
/// `z = (mean − reference) / se` and `p = 2 Φ(−|z|)`. With `se = 0`, `z` is 0 when `mean` equals
/// `reference` and `+∞` (so `p = 0`) otherwise.
pub fn two_sided_z(mean: f64, reference: f64, se: f64) -> (f64, f64) {
    let z = if se > 0.0 {
        (mean - reference) / se
    } else if mean == reference {
        0.0
    } else {
        f64::INFINITY
    };
    (
        z,
        statrs::function::erf::erfc(z.abs() / std::f64::consts::SQRT_2),
    )
}
