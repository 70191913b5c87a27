//! Every test accepts a correct sampler and rejects a deliberately broken one.
//!
//! Fixed seeds; significance level α = 0.01 per test unless stated.

use crate::common;

use common::*;
use stats::{
    Axis, ChiSquareResult, DiscBinning, QuadratureOptions, RectBinning, SphereBinning, Suite,
    chi_square_test, ks_onesample, ks_projection_test, ks_twosample, mean_z_test, normalisation,
    pdf_consistency, project, support_coverage,
};
use std::f64::consts::{PI, TAU};

const ALPHA: f64 = 0.01;

fn opts() -> QuadratureOptions {
    QuadratureOptions::default()
}

// ---------------- chi-square ----------------

/// The chi-square test of `points` against the uniform density on the unit disc (20 × 20 bins).
fn uniform_disc_chi_square(points: &[[f64; 2]]) -> ChiSquareResult {
    let disc = DiscBinning::new(20, 20).unwrap();
    chi_square_test(&disc, &uniform_disc_pdf, points, &opts()).unwrap()
}

#[test]
fn chi_square_accepts_exact_samplers() {
    let rect = RectBinning::new(RECT_X, RECT_Y, 15, 10).unwrap();
    let r = chi_square_test(&rect, &product_pdf, &product_points(1, 100_000), &opts()).unwrap();
    assert!(r.p_value >= ALPHA, "product density: {}", r.summary());

    let r = uniform_disc_chi_square(&disc_points(2, 100_000, 1.0));
    assert!(r.p_value >= ALPHA, "uniform disc: {}", r.summary());

    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    let r = chi_square_test(&hemi, &cosine_pdf, &cosine_points(3, 100_000), &opts()).unwrap();
    assert!(r.p_value >= ALPHA, "cosine hemisphere: {}", r.summary());

    let sphere = SphereBinning::sphere(20, 40).unwrap();
    let lobe = test_lobe();
    let r = chi_square_test(&sphere, &|d| lobe.pdf(d), &lobe.points(4, 100_000), &opts()).unwrap();
    assert!(r.p_value >= ALPHA, "Phong lobe: {}", r.summary());
    assert!(r.pooled_cells > 0, "the lobe leaves sparse cells to pool");
}

#[test]
fn chi_square_rejects_a_pdf_three_percent_high_on_half_the_disc() {
    // Samples are exact; the reported pdf is 3 % too high where x > 0.
    let broken = |p: [f64; 2]| uniform_disc_pdf(p) * if p[0] > 0.0 { 1.03 } else { 1.0 };
    let disc = DiscBinning::new(20, 20).unwrap();
    let pts = disc_points(5, 1_000_000, 1.0);
    let good = chi_square_test(&disc, &uniform_disc_pdf, &pts, &opts()).unwrap();
    assert!(good.p_value >= ALPHA, "{}", good.summary());
    let bad = chi_square_test(&disc, &broken, &pts, &opts()).unwrap();
    assert!(bad.p_value < ALPHA, "{}", bad.summary());
}

#[test]
fn chi_square_rejects_a_lobe_tilted_by_two_degrees() {
    let sphere = SphereBinning::sphere(20, 40).unwrap();
    let lobe = test_lobe();
    let pts = tilted_lobe(2.0).points(6, 100_000);
    let r = chi_square_test(&sphere, &|d| lobe.pdf(d), &pts, &opts()).unwrap();
    assert!(r.p_value < ALPHA, "{}", r.summary());
}

#[test]
fn chi_square_rejects_samples_outside_the_support() {
    // The disc shrunk by 1 %: an empty ring where the pdf expects samples.
    let r = uniform_disc_chi_square(&disc_points(7, 100_000, 0.99));
    assert!(r.p_value < ALPHA, "{}", r.summary());
    // Directions below the horizon for a hemisphere pdf: samples where the pdf integrates to zero.
    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    let mut pts = cosine_points(8, 10_000);
    pts[17][2] = -pts[17][2];
    let r = chi_square_test(&hemi, &cosine_pdf, &pts, &opts()).unwrap();
    assert_eq!((r.p_value, r.zero_mass_samples), (0.0, 1));
}

// ---------------- Kolmogorov–Smirnov ----------------

#[test]
fn ks_projections_accept_exact_samplers() {
    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    let pts = cosine_points(11, 50_000);
    for axis in [Axis::U, Axis::V] {
        let o = ks_projection_test(&hemi, &cosine_pdf, &pts, axis, ALPHA, &opts()).unwrap();
        assert!(o.passed, "{o}");
    }
    let rect = RectBinning::new(RECT_X, RECT_Y, 8, 8).unwrap();
    let pts = product_points(12, 50_000);
    for axis in [Axis::U, Axis::V] {
        let o = ks_projection_test(&rect, &product_pdf, &pts, axis, ALPHA, &opts()).unwrap();
        assert!(o.passed, "{o}");
    }
    // Small n: exact p-value branch.
    let small = cosine_points(13, 60);
    let o = ks_projection_test(&hemi, &cosine_pdf, &small, Axis::U, ALPHA, &opts()).unwrap();
    assert!(o.passed && o.detail.contains("Exact"), "{o}");
}

#[test]
fn chi_square_and_ks_projection_reject_cosine_samples_reported_as_uniform() {
    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    let r = chi_square_test(
        &hemi,
        &uniform_hemisphere_pdf,
        &cosine_points(3, 10_000),
        &opts(),
    )
    .unwrap();
    assert!(r.p_value < ALPHA, "{}", r.summary());
    let o = ks_projection_test(
        &hemi,
        &uniform_hemisphere_pdf,
        &cosine_points(14, 2_000),
        Axis::U,
        ALPHA,
        &opts(),
    )
    .unwrap();
    assert!(!o.passed, "{o}");
}

#[test]
fn ks_projection_rejects_a_slightly_shifted_distribution() {
    // Product-density samples shifted by +0.01 in x (0.3 % of the range).
    let rect = RectBinning::new(RECT_X, RECT_Y, 8, 8).unwrap();
    let good = product_points(15, 100_000);
    let shifted: Vec<[f64; 2]> = good
        .iter()
        .map(|p| [(p[0] + 0.01).min(RECT_X[1]), p[1]])
        .collect();
    let o = ks_projection_test(&rect, &product_pdf, &good, Axis::U, ALPHA, &opts()).unwrap();
    assert!(o.passed, "{o}");
    let o = ks_projection_test(&rect, &product_pdf, &shifted, Axis::U, ALPHA, &opts()).unwrap();
    assert!(!o.passed, "{o}");
}

#[test]
fn ks_one_sample_against_a_closed_form_cdf() {
    let disc = DiscBinning::new(4, 4).unwrap();
    // Shrinking the disc by 2 % moves the x CDF by up to 0.02/π ≈ 0.0064, i.e. 2.8/√n here.
    let x = project(&disc, &disc_points(16, 200_000, 1.0), Axis::U).values;
    assert!(ks_onesample(&x, &disc_cdf_x).unwrap().p_value >= ALPHA);
    let x = project(&disc, &disc_points(16, 200_000, 0.98), Axis::U).values;
    assert!(ks_onesample(&x, &disc_cdf_x).unwrap().p_value < ALPHA);
}

#[test]
fn ks_two_sample_compares_a_sampler_with_a_reference() {
    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    // Two different algorithms for the cosine distribution agree ...
    let a = project(&hemi, &cosine_points(17, 20_000), Axis::U).values;
    let b = project(&hemi, &cosine_points_inversion(18, 20_000), Axis::U).values;
    assert!(ks_twosample(&a, &b).unwrap().p_value >= ALPHA);
    // ... and a lobe tilted by 2° is told apart from the reference lobe.
    let sphere = SphereBinning::sphere(10, 20).unwrap();
    let good = project(&sphere, &test_lobe().points(19, 20_000), Axis::U).values;
    let same = project(&sphere, &test_lobe().points(20, 20_000), Axis::U).values;
    let tilted = project(&sphere, &tilted_lobe(2.0).points(21, 20_000), Axis::U).values;
    assert!(ks_twosample(&good, &same).unwrap().p_value >= ALPHA);
    let r = ks_twosample(&good, &tilted).unwrap();
    assert!(r.p_value < ALPHA, "{}", r.summary());
}

// ---------------- pdf consistency ----------------

#[test]
fn pdf_consistency_accepts_matching_and_rejects_mismatching_pdfs() {
    let pts = cosine_points(22, 10_000);
    let good: Vec<([f64; 3], f64)> = pts.iter().map(|&d| (d, cosine_pdf(d))).collect();
    let o = pdf_consistency(&good, &cosine_pdf, 1e-6).unwrap();
    assert!(o.passed, "{o}");
    // Reported with the uniform pdf.
    let wrong: Vec<([f64; 3], f64)> = pts.iter().map(|&d| (d, 0.5 / PI)).collect();
    assert!(!pdf_consistency(&wrong, &cosine_pdf, 1e-6).unwrap().passed);
    // Off by 1e-5 relative in one region only.
    let subtle: Vec<([f64; 3], f64)> = pts
        .iter()
        .map(|&d| (d, cosine_pdf(d) * if d[0] > 0.9 { 1.0 + 1e-5 } else { 1.0 }))
        .collect();
    let o = pdf_consistency(&subtle, &cosine_pdf, 1e-6).unwrap();
    assert!(!o.passed && o.statistic > 9e-6, "{o}");
    // A sample where the pdf vanishes.
    let mut zero = good.clone();
    zero[3] = ([1.0, 0.0, 0.0], 0.0);
    let o = pdf_consistency(&zero, &cosine_pdf, 1e-6).unwrap();
    assert!(
        !o.passed && o.detail.contains("1 samples with pdf <= 0"),
        "{o}"
    );
    assert!(pdf_consistency::<[f64; 3]>(&[], &cosine_pdf, 1e-6).is_err());
}

// ---------------- normalisation ----------------

#[test]
fn normalisation_accepts_unit_mass_and_rejects_three_percent_errors() {
    let disc = DiscBinning::new(10, 10).unwrap();
    let o = normalisation(&disc, &uniform_disc_pdf, 1.0, 1e-6, &opts()).unwrap();
    assert!(o.passed && o.statistic < 1e-9, "{o}");
    let broken = |p: [f64; 2]| uniform_disc_pdf(p) * if p[0] > 0.0 { 1.03 } else { 1.0 };
    let o = normalisation(&disc, &broken, 1.0, 1e-6, &opts()).unwrap();
    assert!(!o.passed && (o.statistic - 0.015).abs() < 1e-9, "{o}");
    let sphere = SphereBinning::sphere(10, 20).unwrap();
    let lobe = test_lobe();
    assert!(
        normalisation(&sphere, &|d| lobe.pdf(d), 1.0, 1e-6, &opts())
            .unwrap()
            .passed
    );
    // On the hemisphere the lobe loses the (tiny) part below the horizon.
    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    let o = normalisation(&hemi, &uniform_hemisphere_pdf, 1.0, 1e-9, &opts()).unwrap();
    assert!(o.passed, "{o}");
    assert!(normalisation(&hemi, &uniform_hemisphere_pdf, 1.0, 0.0, &opts()).is_err());
}

// ---------------- support coverage ----------------

#[test]
fn support_coverage_finds_holes_in_the_pdf() {
    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    let target = |d: [f64; 3]| d[2].max(0.0) * (1.0 + d[0]);
    let o = support_coverage(&hemi, &target, &cosine_pdf, 2, &opts()).unwrap();
    assert!(o.passed && o.statistic == 0.0, "{o}");
    // A lobe-only pdf that vanishes beyond 80° from its axis misses part of the target's support.
    let lobe = test_lobe();
    let truncated = |d: [f64; 3]| {
        let c = lobe.axis[0] * d[0] + lobe.axis[1] * d[1] + lobe.axis[2] * d[2];
        if c > 80f64.to_radians().cos() {
            lobe.pdf(d)
        } else {
            0.0
        }
    };
    let o = support_coverage(&hemi, &target, &truncated, 2, &opts()).unwrap();
    assert!(!o.passed && o.statistic > 0.01, "{o}");
    // A pdf that vanishes on a thin ring of the disc (0.995 < r < 0.999).
    let disc = DiscBinning::new(16, 16).unwrap();
    let holed = |p: [f64; 2]| {
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        if r > 0.995 && r < 0.999 {
            0.0
        } else {
            uniform_disc_pdf(p)
        }
    };
    let o = support_coverage(&disc, &uniform_disc_pdf, &holed, 4, &opts()).unwrap();
    assert!(!o.passed, "{o}");
    // The verdict is on the uncovered target mass: a hole where the target has underflowed to
    // 1e-300 (relative mass ~1e-301) passes; the same hole with a relative mass of ~1e-9 fails.
    let ring = |p: [f64; 2]| {
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        r > 0.995 && r < 0.999
    };
    for (level, pass) in [(1e-300, true), (1e-7, false)] {
        let target = move |p: [f64; 2]| {
            if ring(p) {
                level * uniform_disc_pdf(p)
            } else {
                uniform_disc_pdf(p)
            }
        };
        let o = support_coverage(&disc, &target, &holed, 4, &opts()).unwrap();
        assert_eq!(o.passed, pass, "{o}");
        assert!(o.statistic < 10.0 * level, "{o}");
    }
}

// ---------------- unbiasedness ----------------

#[test]
fn z_test_accepts_unbiased_and_rejects_biased_estimators() {
    // ∫_H cos²θ dω = 2π/3, estimated with uniform hemisphere sampling: f/pdf = 2π cos²θ.
    let exact = TAU / 3.0;
    let pts = uniform_hemisphere_points(23, 100_000);
    let values: Vec<f64> = pts.iter().map(|d| d[2] * d[2] / (0.5 / PI)).collect();
    let o = mean_z_test(&values, exact, ALPHA).unwrap();
    assert!(o.passed, "{o}");
    // A 3 % pdf error on half the hemisphere biases the estimate by 1.5 %.
    let biased: Vec<f64> = pts
        .iter()
        .map(|d| d[2] * d[2] / (0.5 / PI * if d[0] > 0.0 { 1.03 } else { 1.0 }))
        .collect();
    let o = mean_z_test(&biased, exact, ALPHA).unwrap();
    assert!(!o.passed, "{o}");
    // Zero-variance estimator (cosine sampling of cos θ) is exact.
    let cos_vals: Vec<f64> = cosine_points(24, 1000)
        .iter()
        .map(|d| d[2] / cosine_pdf(*d))
        .collect();
    assert!(mean_z_test(&cos_vals, PI, ALPHA).unwrap().passed);
    assert!(!mean_z_test(&cos_vals, PI * 1.001, ALPHA).unwrap().passed);
    // A single infinite value (pdf = 0 where f > 0) fails outright.
    let mut inf = values.clone();
    inf[5] = f64::INFINITY;
    assert!(!mean_z_test(&inf, exact, ALPHA).unwrap().passed);
    assert!(mean_z_test(&[1.0], 1.0, ALPHA).is_err());
}

// ---------------- suite ----------------

#[test]
fn suite_applies_the_sidak_correction() {
    let hemi = SphereBinning::hemisphere(10, 20).unwrap();
    let pts = cosine_points(25, 50_000);
    let mut suite = Suite::new(0.01).unwrap();
    suite.push(
        chi_square_test(&hemi, &cosine_pdf, &pts, &opts())
            .unwrap()
            .outcome("chi2", 0.01),
    );
    for axis in [Axis::U, Axis::V] {
        suite.push(ks_projection_test(&hemi, &cosine_pdf, &pts, axis, 0.01, &opts()).unwrap());
    }
    let with_pdf: Vec<([f64; 3], f64)> = pts.iter().map(|&d| (d, cosine_pdf(d))).collect();
    suite.push(pdf_consistency(&with_pdf, &cosine_pdf, 1e-6).unwrap());
    suite.push(normalisation(&hemi, &cosine_pdf, 1.0, 1e-6, &opts()).unwrap());
    let report = suite.report();
    assert_eq!(report.m, 3);
    assert!((report.per_test_level - (1.0 - 0.99f64.powf(1.0 / 3.0))).abs() < 1e-15);
    assert!(report.passed, "{report}");

    // p = 0.006 rejects a lone test at α = 0.01, but with m = 2 the per-test level is
    // 1 − 0.99^½ ≈ 0.005013 and it passes. Deterministic outcomes do not count in m.
    let mut s = Suite::new(0.01).unwrap();
    s.push(stats::TestOutcome::with_p_value(
        "a",
        1.0,
        0.006,
        0.01,
        String::new(),
    ));
    assert!(!s.report().passed);
    s.push(stats::TestOutcome::with_p_value(
        "b",
        1.0,
        0.9,
        0.01,
        String::new(),
    ));
    assert!(s.report().passed);
    s.push(stats::TestOutcome::deterministic(
        "c",
        0.0,
        false,
        String::new(),
    ));
    let r = s.report();
    assert_eq!(r.m, 2);
    assert!(!r.passed && r.failures().map(|o| o.name.as_str()).collect::<Vec<_>>() == ["c"]);
    assert!(Suite::new(1.0).is_err());
}
