//! Goodness of fit of the samples against independently computed bin masses
//! (α = 0.01, fixed seeds), for both schemes and both leaf choices.

use crate::common;

use common::*;
use partition_sampler::{
    AllocationMode, Domain, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, SAMPLING_CONFIGS,
    SampledGridDensity, Sampler2D, UserBoundDensity,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Draws `n` samples, checks domain membership and pdf consistency, returns the p-value.
fn fit<D: RegionStats>(
    s: &QuadTreeSampler<D>,
    bins: &Bins,
    masses: &[f64],
    n: usize,
    seed: u64,
    domain: Domain,
) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut pts = Vec::with_capacity(n);
    for k in 0..n {
        let x = s.sample(&mut rng);
        assert!(
            domain.contains(x.point),
            "sample {:?} outside the domain",
            x.point
        );
        assert!(x.pdf > 0.0);
        if k % 97 == 0 {
            let p = s.pdf(x.point);
            assert!(
                (p - x.pdf).abs() <= 1e-9 * x.pdf,
                "pdf {p} vs sample pdf {}",
                x.pdf
            );
        }
        pts.push(x.point);
    }
    let (h, outside) = bins.histogram(pts);
    assert_eq!(outside, 0);
    chi_square_p(&h, masses)
}

/// `n × n` bins over the square around the unit disc.
fn disc_bins(n: usize) -> Bins {
    Bins {
        rect: Rect::DISC_BOUNDS,
        nx: n,
        ny: n,
    }
}

/// For the `k`-th of [`SAMPLING_CONFIGS`]: builds `density()` with `builder` set to its scheme
/// and leaf choice, checks the fit of `n` samples of seed `seed + k` ([`fit`]) and that no
/// bound was violated, then runs the test's own checks `more` on the sampler.
#[allow(clippy::too_many_arguments)]
fn fit_every_config<D: RegionStats>(
    density: impl Fn() -> D,
    builder: QuadTreeBuilder,
    bins: &Bins,
    masses: &[f64],
    n: usize,
    seed: u64,
    domain: Domain,
    more: impl Fn(&QuadTreeSampler<D>),
) {
    for (k, (scheme, choice)) in SAMPLING_CONFIGS.into_iter().enumerate() {
        let s = builder
            .scheme(scheme)
            .leaf_choice(choice)
            .build(density())
            .unwrap();
        let p = fit(&s, bins, masses, n, seed + k as u64, domain);
        assert_eq!(s.stats().bound_violations, 0, "{scheme:?} {choice:?}");
        assert!(p > ALPHA, "{scheme:?} {choice:?}: p = {p}");
        more(&s);
    }
}

#[test]
fn disc_phong_lobe_all_configs() {
    let f = phong_lobe(35.0, 30.0);
    let bins = disc_bins(24);
    let masses = bins.masses(24, f, in_disc);
    fit_every_config(
        || SampledGridDensity::new(f, Domain::UnitDisc, 256).unwrap(),
        QuadTreeBuilder::new().max_depth(8),
        &bins,
        &masses,
        60_000,
        11,
        Domain::UnitDisc,
        |s| {
            let st = s.stats();
            assert!(st.expected_mean_trials <= 2.0 + 1e-9, "{st:?}");
        },
    );
}

/// The 64 × 32 map with a sun of 1e5, `nx × ny` bins over the unit square and their masses.
fn sun_setup(nx: usize, ny: usize) -> (Vec<f64>, Bins, Vec<f64>) {
    let vals = sun_map(64, 32, 1e5);
    let bins = Bins {
        rect: Rect::UNIT,
        nx,
        ny,
    };
    let masses = sun_map_masses(&vals, 64, 32, &bins);
    (vals, bins, masses)
}

#[test]
fn sun_map_with_sin_rows_all_configs() {
    let (w, h) = (64, 32);
    let (vals, bins, masses) = sun_setup(32, 16);
    // Î is the exact integral, so the pdf integrates to one.
    let exact: f64 = (0..h)
        .map(|j| {
            let row = ((std::f64::consts::PI * j as f64 / h as f64).cos()
                - (std::f64::consts::PI * (j + 1) as f64 / h as f64).cos())
                / std::f64::consts::PI;
            vals[j * w..(j + 1) * w].iter().sum::<f64>() * row / w as f64
        })
        .sum();
    fit_every_config(
        || sin_rows(w, h, vals.clone(), Rect::UNIT),
        QuadTreeBuilder::new(),
        &bins,
        &masses,
        80_000,
        100,
        Domain::Rect(Rect::UNIT),
        |s| {
            let st = s.stats();
            assert!(
                (st.integral - exact).abs() <= 1e-12 * exact,
                "{} vs {exact}",
                st.integral
            );
        },
    );
}

#[test]
fn sun_map_background_is_fit_when_sun_is_excluded() {
    // The sun holds ~99.6% of the mass; test the background separately with a conditional
    // chi-square over samples that fall outside the sun bin.
    let (w, h) = (64, 32);
    let (vals, bins, mut masses) = sun_setup(16, 8);
    let d = sin_rows(w, h, vals, Rect::UNIT);
    let s = QuadTreeBuilder::new().build(d).unwrap();
    let sun_bin = masses
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap()
        .0;
    masses[sun_bin] = 0.0;
    let t: f64 = masses.iter().sum();
    masses.iter_mut().for_each(|m| *m /= t);
    let pts: Vec<_> = s
        .sample_par(2_000_000, 5)
        .into_iter()
        .map(|x| x.point)
        .filter(|p| bins.index(*p) != Some(sun_bin))
        .collect();
    assert!(pts.len() > 3000, "{}", pts.len());
    let (hist, _) = bins.histogram(pts);
    let p = chi_square_p(&hist, &masses);
    assert!(p > ALPHA, "p = {p}");
}

#[test]
fn sampled_gaussian_on_offset_rectangle() {
    let rect = Rect::new(-1.0, 0.5, 2.0, 2.0);
    let f = |p: [f64; 2]| 0.05 + (-((p[0] - 0.3).powi(2) + (p[1] - 1.1).powi(2)) / 0.02).exp();
    let bins = Bins {
        rect,
        nx: 20,
        ny: 10,
    };
    let masses = bins.masses(16, f, |_| true);
    fit_every_config(
        || SampledGridDensity::new(f, Domain::Rect(rect), 128).unwrap(),
        QuadTreeBuilder::new(),
        &bins,
        &masses,
        50_000,
        300,
        Domain::Rect(rect),
        |_| {},
    );
}

#[test]
fn user_bound_monotone_density() {
    let f = |p: [f64; 2]| 1.0 + 8.0 * p[0] * p[0] * p[1];
    let bound = |r: &Rect| 1.0 + 8.0 * r.x1.max(0.0).powi(2) * r.y1.max(0.0);
    let bins = Bins {
        rect: Rect::UNIT,
        nx: 12,
        ny: 12,
    };
    let masses = bins.masses(16, f, |_| true);
    fit_every_config(
        || UserBoundDensity::new(f, bound, Domain::Rect(Rect::UNIT), 8).unwrap(),
        QuadTreeBuilder::new().max_depth(6),
        &bins,
        &masses,
        40_000,
        500,
        Domain::Rect(Rect::UNIT),
        |_| {},
    );
}

#[test]
fn batch_mode_fits_both_allocations() {
    let f = phong_lobe(20.0, 12.0);
    let bins = disc_bins(16);
    let masses = bins.masses(24, f, in_disc);
    let d = SampledGridDensity::new(f, Domain::UnitDisc, 256).unwrap();
    let s = QuadTreeBuilder::new().build(d).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(77);
    // Many batches of modest size so the randomised remainders average out.
    let mut pts = Vec::new();
    for _ in 0..40 {
        let b = s.sample_batch(1000, AllocationMode::RandomizedRemainder, &mut rng);
        assert_eq!(b.samples.len(), 1000);
        assert!(b.weights.is_none());
        for x in &b.samples {
            assert!(in_disc(x.point) && (s.pdf(x.point) - x.pdf).abs() <= 1e-9 * x.pdf);
        }
        pts.extend(b.samples.iter().map(|x| x.point));
    }
    let (h, _) = bins.histogram(pts);
    assert!(chi_square_p(&h, &masses) > ALPHA);
    let b = s.sample_batch(5000, AllocationMode::Hamilton, &mut rng);
    let w = b.weights.unwrap();
    assert_eq!(w.len(), 5000);
    // Σ weights = N · Σ_{n_i > 0} p_i ≤ N.
    let sw: f64 = w.iter().sum();
    assert!(sw <= 5000.0 * (1.0 + 1e-12) && sw > 4900.0, "{sw}");
}
