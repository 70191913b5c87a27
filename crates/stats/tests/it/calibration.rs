//! False-rejection rates of the tests on correct samplers.
//!
//! The quick test runs in CI with few seeds and a wide tolerance; the `#[ignore]`d ones are
//! the real calibration (run with `cargo test -p stats --release --test it calibration -- --ignored
//! --nocapture`), checking that the observed rejection rate is consistent with the nominal
//! level (two-sided binomial p-value > 1e-3) and that the p-values look uniform.

use crate::common;

use common::*;
use stats::{
    Axis, Binning, Calibration, QuadratureOptions, RectBinning, SphereBinning, StatsError,
    calibrate, chi_square_gof, expected_masses, histogram, ks_onesample, ks_twosample, project,
    projection_cdf,
};

fn check(name: &str, c: &Calibration) {
    let mean_p = c.p_values.iter().sum::<f64>() / c.runs as f64;
    let unif = ks_onesample(&c.p_values, &|p| p.clamp(0.0, 1.0)).unwrap();
    println!(
        "{name}: {} / {} rejections at alpha = {} (rate {:.3}), binomial p = {:.3}, mean p-value {:.3}, KS uniformity p = {:.3}",
        c.rejections, c.runs, c.alpha, c.rate, c.binomial_p_value, mean_p, unif.p_value
    );
    assert!(
        c.binomial_p_value > 1e-3,
        "{name}: rejection rate {} vs nominal {}",
        c.rate,
        c.alpha
    );
}

/// Chi-square p-values, one per seed, of `n` points of `points(seed, n)` in `bins` against the
/// bin masses of `pdf` (minimum expected count 5).
fn chi_square_calibration<B: Binning + Sync>(
    seeds: &[u64],
    alpha: f64,
    n: usize,
    bins: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    points: impl Fn(u64, usize) -> Vec<B::Point> + Sync,
) -> Calibration {
    let expected: Vec<f64> = expected_masses(pdf, bins, n as u64)
        .iter()
        .map(|m| m * n as f64)
        .collect();
    calibrate(seeds, alpha, |seed| {
        let h = histogram(bins, &points(seed, n));
        Ok(chi_square_gof(&h.counts, &expected, 5.0)?.p_value)
    })
    .unwrap()
}

/// [`chi_square_calibration`] of the test lobe on 20 × 40 sphere bins.
fn chi_square_lobe(seeds: &[u64], alpha: f64, n: usize) -> Calibration {
    let lobe = test_lobe();
    let bins = SphereBinning::sphere(20, 40).unwrap();
    chi_square_calibration(seeds, alpha, n, &bins, &|d| lobe.pdf(d), |seed, n| {
        lobe.points(seed, n)
    })
}

/// [`chi_square_calibration`] of the product density on 8 × 8 rectangle bins.
fn chi_square_rect(seeds: &[u64], alpha: f64, n: usize) -> Calibration {
    let bins = RectBinning::new(RECT_X, RECT_Y, 8, 8).unwrap();
    chi_square_calibration(seeds, alpha, n, &bins, &product_pdf, product_points)
}

fn ks_cos_theta(seeds: &[u64], alpha: f64, n: usize) -> Calibration {
    let bins = SphereBinning::sphere(10, 20).unwrap();
    let lobe = test_lobe();
    let cdf = projection_cdf(
        &bins,
        &|d| lobe.pdf(d),
        Axis::U,
        n as u64,
        &QuadratureOptions::default(),
    )
    .unwrap();
    calibrate(seeds, alpha, |seed| {
        let x = project(&bins, &lobe.points(seed, n), Axis::U).values;
        Ok(ks_onesample(&x, &|t| cdf.eval(t))?.p_value)
    })
    .unwrap()
}

fn ks_two(seeds: &[u64], alpha: f64, n: usize, m: usize) -> Calibration {
    calibrate(seeds, alpha, |seed| {
        let a: Vec<f64> = cosine_points(2 * seed, n).iter().map(|d| d[2]).collect();
        let b: Vec<f64> = cosine_points_inversion(2 * seed + 1, m)
            .iter()
            .map(|d| d[2])
            .collect();
        Ok(ks_twosample(&a, &b)?.p_value)
    })
    .unwrap()
}

#[test]
fn quick_false_rejection_rates_are_plausible() {
    // α = 0.2 so that 60 seeds carry information (≈12 expected rejections).
    let seeds: Vec<u64> = (0..60).collect();
    check("chi-square N=2000", &chi_square_rect(&seeds, 0.2, 2_000));
    check("KS exact n=100", &ks_cos_theta(&seeds, 0.2, 100));
    check("KS asymptotic n=1000", &ks_cos_theta(&seeds, 0.2, 1_000));
    check("KS two-sample 80x120", &ks_two(&seeds, 0.2, 80, 120));
}

#[test]
fn a_test_that_never_rejects_is_flagged() {
    let c = calibrate(&(0..60).collect::<Vec<u64>>(), 0.2, |_| Ok(0.9)).unwrap();
    assert_eq!(c.rejections, 0);
    assert!(c.binomial_p_value < 1e-3);
    let e = calibrate(&[1, 2], 0.2, |s| {
        if s == 2 {
            Err(StatsError::InvalidAlpha(0.0))
        } else {
            Ok(0.5)
        }
    });
    assert!(e.is_err());
    assert!(calibrate(&[], 0.2, |_| Ok(0.5)).is_err());
}

#[test]
#[ignore = "calibration run: ~3 minutes in release mode"]
fn false_rejection_rates_are_nominal_over_200_seeds() {
    let seeds: Vec<u64> = (1000..1200).collect();
    // Chi-square on a narrow lobe with 10⁶ samples: the regime where a fixed per-bin rule fails.
    let lobe_chi2 = chi_square_lobe(&seeds, 0.05, 1_000_000);
    let runs = [
        ("chi-square lobe N=1e6", lobe_chi2),
        (
            "chi-square rect N=1e5",
            chi_square_rect(&seeds, 0.05, 100_000),
        ),
        ("KS exact n=50", ks_cos_theta(&seeds, 0.05, 50)),
        ("KS asymptotic n=1e5", ks_cos_theta(&seeds, 0.05, 100_000)),
        (
            "KS two-sample exact 1e4 x 1.5e4",
            ks_two(&seeds, 0.05, 10_000, 15_000),
        ),
        (
            "KS two-sample asymptotic 1e5 x 1e5",
            ks_two(&seeds, 0.05, 100_000, 100_000),
        ),
    ];
    for (name, c) in &runs {
        check(name, c);
        check(name, &c.with_alpha(0.01).unwrap());
    }
}

#[test]
#[ignore = "calibration run at 10⁷ samples: ~3 minutes in release mode"]
fn chi_square_is_calibrated_at_ten_million_samples() {
    let seeds: Vec<u64> = (5000..5100).collect();
    check(
        "chi-square lobe N=1e7",
        &chi_square_lobe(&seeds, 0.1, 10_000_000),
    );
}
