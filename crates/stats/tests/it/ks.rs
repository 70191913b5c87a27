//! KS p-values against reference values, independent exact formulas, statrs, and simulation.

use crate::common;

use common::*;
use statrs::distribution::Uniform;
use statrs::function::factorial::{binomial, ln_binomial};
use statrs::stats_tests::NaNPolicy;
use statrs::stats_tests::ks_test::{
    KSOneSampleAlternativeMethod, KSTwoSampleAlternativeMethod, ks_onesample as statrs_ks1,
    ks_twosample as statrs_ks2,
};
use stats::{
    KsMethod, StatsError, kolmogorov_cdf, kolmogorov_sf, ks_onesample, ks_onesample_p_value,
    ks_statistic, ks_twosample, ks_twosample_p_value,
};

#[test]
fn kolmogorov_distribution_quantiles() {
    // Classical critical values of √n D: 1.2238 (90 %), 1.3581 (95 %), 1.6276 (99 %),
    // and the median 0.8276.
    for (x, p) in [
        (1.2238, 0.90),
        (1.3581, 0.95),
        (1.6276, 0.99),
        (0.8276, 0.5),
    ] {
        assert!(
            (kolmogorov_cdf(x) - p).abs() < 1e-4,
            "K({x}) = {}",
            kolmogorov_cdf(x)
        );
        assert!((kolmogorov_sf(x) - (1.0 - p)).abs() < 1e-4);
    }
    assert_eq!(kolmogorov_cdf(0.0), 0.0);
    assert!(kolmogorov_cdf(0.1) < 1e-40 && kolmogorov_sf(10.0) < 1e-80);
}

#[test]
fn kolmogorov_mean_is_sqrt_half_pi_ln2() {
    // E[K] = ∫ P(K > x) dx = √(π/2) ln 2: an independent check of the whole curve.
    let h = 1e-4;
    let mean: f64 = (0..100_000)
        .map(|i| kolmogorov_sf((i as f64 + 0.5) * h) * h)
        .sum();
    let exact = (std::f64::consts::PI / 2.0).sqrt() * std::f64::consts::LN_2;
    assert!((mean - exact).abs() < 1e-8, "{mean} vs {exact}");
}

#[test]
fn exact_one_sample_n1_closed_form() {
    // D_1 = max(U, 1 − U), so P(D_1 ≥ d) = 2(1 − d) on [½, 1].
    for d in [0.5, 0.6, 0.75, 0.99] {
        assert!((ks_onesample_p_value(d, 1) - 2.0 * (1.0 - d)).abs() < 1e-12);
    }
}

fn uniform_sample(seed: u64, n: usize) -> Vec<f64> {
    let mut r = rng(seed);
    (0..n).map(|_| uniform(&mut r)).collect()
}

#[test]
fn exact_one_sample_matches_statrs() {
    let unif = Uniform::new(0.0, 1.0).unwrap();
    let mut methods = Vec::new();
    for n in [2usize, 5, 10, 37, 100, 140] {
        for seed in 0..6 {
            // Skew some samples so that small p-values are covered too.
            let x: Vec<f64> = uniform_sample(seed, n)
                .into_iter()
                .map(|u| u.powf(1.0 + 0.15 * seed as f64))
                .collect();
            let ours = ks_onesample(&x, &|t| t).unwrap();
            let (d, p) = statrs_ks1(
                x.clone(),
                &unif,
                KSOneSampleAlternativeMethod::TwoSidedExact,
                NaNPolicy::Error,
            )
            .unwrap();
            assert!((ours.statistic - d).abs() < 1e-15);
            assert!(
                (ours.p_value - p).abs() < 1e-10 * p.max(1e-3),
                "n = {n}, seed {seed}: {} vs statrs {p}",
                ours.p_value
            );
            methods.push(ours.method);
        }
    }
    assert!(methods.contains(&KsMethod::Exact));
}

/// Smirnov's exact one-sided tail, written independently of the library.
fn smirnov_plus(d: f64, n: usize) -> f64 {
    let nf = n as f64;
    let jmax = (nf * (1.0 - d)).floor() as usize;
    (0..=jmax)
        .map(|j| {
            let jf = j as f64;
            binomial(n as u64, j as u64)
                * (d + jf / nf).powi(j as i32 - 1)
                * (1.0 - d - jf / nf).powi((n - j) as i32)
        })
        .sum::<f64>()
        * d
}

#[test]
fn large_statistics_match_doubled_smirnov_and_statrs() {
    // For d ≥ ½ the events D⁺ ≥ d and D⁻ ≥ d are disjoint: P(D ≥ d) = 2 P(D⁺ ≥ d) exactly.
    let unif = Uniform::new(0.0, 1.0).unwrap();
    for n in [3usize, 8, 20] {
        let x: Vec<f64> = uniform_sample(n as u64, n)
            .iter()
            .map(|u| 0.35 * u)
            .collect();
        let r = ks_onesample(&x, &|t| t).unwrap();
        assert!(r.statistic >= 0.5);
        let (_, p) = statrs_ks1(
            x,
            &unif,
            KSOneSampleAlternativeMethod::TwoSidedExact,
            NaNPolicy::Error,
        )
        .unwrap();
        let smirnov = 2.0 * smirnov_plus(r.statistic, n);
        assert!(
            (r.p_value - smirnov).abs() <= 1e-12 * smirnov.max(1e-300),
            "{} vs {smirnov}",
            r.p_value
        );
        assert!((r.p_value - p).abs() <= 1e-9 * p + 1e-15);
    }
}

#[test]
fn exact_one_sample_matches_simulation() {
    // 200 000 replicates of D_10 with a fixed seed; 4-sigma binomial bands.
    let n = 10;
    let reps = 200_000;
    let mut r = rng(2024);
    let mut ds = Vec::with_capacity(reps);
    let mut x = vec![0.0; n];
    for _ in 0..reps {
        x.iter_mut().for_each(|v| *v = uniform(&mut r));
        ds.push(ks_statistic(&x, &|t| t).unwrap());
    }
    for d in [0.2, 0.274, 0.3, 0.369, 0.41] {
        let emp = ds.iter().filter(|&&v| v >= d).count() as f64 / reps as f64;
        let p = ks_onesample_p_value(d, n);
        let sd = (p * (1.0 - p) / reps as f64).sqrt();
        assert!(
            (emp - p).abs() < 4.0 * sd,
            "d = {d}: simulated {emp}, exact {p}"
        );
    }
    // Marsaglia, Tsang & Wang's worked example: P(D_10 < 0.274) = 0.6284796154565043.
    assert!((1.0 - ks_onesample_p_value(0.274, 10) - 0.628_479_615_456_504_3).abs() < 1e-12);
}

#[test]
fn asymptotic_branch_agrees_with_the_exact_distribution_near_the_switch() {
    // statrs' exact formula works up to n = 169; our n > 140 branch is Stephens-corrected.
    let unif = Uniform::new(0.0, 1.0).unwrap();
    for seed in 0..60u64 {
        let n = [141, 155, 169][seed as usize % 3];
        let x: Vec<f64> = uniform_sample(100 + seed, n)
            .into_iter()
            .map(|u| u.powf(1.0 + 0.01 * seed as f64))
            .collect();
        let ours = ks_onesample(&x, &|t| t).unwrap();
        assert_eq!(ours.method, KsMethod::Asymptotic);
        let (_, exact) = statrs_ks1(
            x,
            &unif,
            KSOneSampleAlternativeMethod::TwoSidedExact,
            NaNPolicy::Error,
        )
        .unwrap();
        if exact > 1e-5 {
            let rel = (ours.p_value - exact).abs() / exact;
            assert!(
                rel < 0.03 || (ours.p_value - exact).abs() < 2e-3,
                "seed {seed}: {} vs {exact}",
                ours.p_value
            );
        }
    }
}

/// Brute force: every interleaving of n and m items, equally likely under the null.
fn enumerate_twosample(n: usize, m: usize) -> Vec<u64> {
    let mut out = Vec::new();
    for mask in 0u32..(1 << (n + m)) {
        if mask.count_ones() as usize != n {
            continue;
        }
        let (mut i, mut j, mut best) = (0i64, 0i64, 0i64);
        for k in 0..n + m {
            if mask >> k & 1 == 1 {
                i += 1;
            } else {
                j += 1;
            }
            best = best.max((i * m as i64 - j * n as i64).abs());
        }
        out.push(best as u64);
    }
    out
}

#[test]
fn exact_two_sample_matches_enumeration() {
    for (n, m) in [(1usize, 1usize), (3, 3), (4, 6), (5, 7)] {
        let all = enumerate_twosample(n, m);
        let mut levels = all.clone();
        levels.sort();
        levels.dedup();
        for &t in &levels {
            let emp = all.iter().filter(|&&v| v >= t).count() as f64 / all.len() as f64;
            let d = t as f64 / (n * m) as f64;
            let p = ks_twosample_p_value(d, n, m);
            assert!(
                (p - emp).abs() < 1e-12,
                "n = {n}, m = {m}, D = {d}: {p} vs {emp}"
            );
        }
    }
}

/// Gnedenko–Korolyuk: for n = m, P(D ≥ k/n) = 2 Σ_{j ≥ 1} (−1)^{j−1} C(2n, n − jk) / C(2n, n).
fn gnedenko_korolyuk(n: usize, k: usize) -> f64 {
    let mut s = 0.0;
    let mut j = 1;
    while j * k <= n {
        let sign = if j % 2 == 1 { 1.0 } else { -1.0 };
        s += sign
            * (ln_binomial(2 * n as u64, (n - j * k) as u64) - ln_binomial(2 * n as u64, n as u64))
                .exp();
        j += 1;
    }
    2.0 * s
}

#[test]
fn exact_two_sample_matches_gnedenko_korolyuk() {
    for n in [100usize, 200, 1000, 5000] {
        let mut exact_seen = false;
        for x in [0.9, 1.1, 1.3, 1.5, 1.8] {
            // √(n/2) k/n ≈ x.
            let k = (x * (2.0 * n as f64).sqrt()).round() as usize;
            let exact = gnedenko_korolyuk(n, k);
            let r = ks_twosample_p_value(k as f64 / n as f64, n, n);
            assert!(
                (r - exact).abs() < 1e-9 * exact.max(1e-6),
                "n = {n}, k = {k}: {r} vs {exact}"
            );
            exact_seen = true;
        }
        assert!(exact_seen);
    }
}

#[test]
fn asymptotic_two_sample_agrees_with_gnedenko_korolyuk_at_large_n() {
    let n = 100_000usize;
    let a: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let b: Vec<f64> = (0..n).map(|i| i as f64 + 0.5 + 600.0).collect();
    // A shift of 600 ranks gives D = 600/n, far enough to take the asymptotic branch.
    assert_eq!(ks_twosample(&a, &b).unwrap().method, KsMethod::Asymptotic);
    for x in [1.0, 1.22, 1.36, 1.63, 1.95] {
        let k = (x * (2.0 * n as f64).sqrt()).round() as usize;
        let exact = gnedenko_korolyuk(n, k);
        let p = ks_twosample_p_value(k as f64 / n as f64, n, n);
        assert!(
            (p - exact).abs() < 0.01 * exact,
            "k = {k}: asymptotic {p} vs exact {exact}"
        );
    }
}

#[test]
fn two_sample_matches_statrs_and_handles_ties() {
    let a: Vec<f64> = uniform_sample(1, 30)
        .iter()
        .map(|u| (u * 20.0).floor())
        .collect();
    let b: Vec<f64> = uniform_sample(2, 50)
        .iter()
        .map(|u| (u * 20.0).floor() + 1.0)
        .collect();
    let ours = ks_twosample(&a, &b).unwrap();
    let (d, _) = statrs_ks2(
        a.clone(),
        b.clone(),
        KSTwoSampleAlternativeMethod::TwoSidedExact,
        NaNPolicy::Error,
    )
    .unwrap();
    assert!((ours.statistic - d).abs() < 1e-12);
    let x = uniform_sample(3, 40);
    let y: Vec<f64> = uniform_sample(4, 60).iter().map(|u| u * 1.2).collect();
    let ours = ks_twosample(&x, &y).unwrap();
    let (d, p) = statrs_ks2(
        x,
        y,
        KSTwoSampleAlternativeMethod::TwoSidedExact,
        NaNPolicy::Error,
    )
    .unwrap();
    assert!((ours.statistic - d).abs() < 1e-12);
    assert!((ours.p_value - p).abs() < 1e-9, "{} vs {p}", ours.p_value);
    assert_eq!(ours.method, KsMethod::Exact);
}

#[test]
fn identical_samples_give_p_one_without_hanging() {
    let a = uniform_sample(9, 20_000);
    let r = ks_twosample(&a, &a).unwrap();
    assert_eq!(r.statistic, 0.0);
    assert_eq!(r.p_value, 1.0);
    assert_eq!(ks_twosample_p_value(0.0, 5, 5), 1.0);
}

#[test]
fn invalid_inputs_are_errors() {
    assert!(matches!(
        ks_onesample(&[], &|t| t),
        Err(StatsError::TooFewSamples { .. })
    ));
    assert!(matches!(
        ks_onesample(&[0.2, f64::NAN], &|t| t),
        Err(StatsError::NonFiniteSample { index: 1 })
    ));
    assert!(matches!(
        ks_onesample(&[0.2], &|t| 3.0 * t + 0.5),
        Err(StatsError::InvalidCdfValue { .. })
    ));
    assert!(ks_twosample(&[1.0], &[]).is_err());
    assert!(ks_twosample(&[1.0, f64::INFINITY], &[0.0]).is_err());
}
