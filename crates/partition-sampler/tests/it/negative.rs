//! Deliberately broken variants must be caught: by the bound audit and by the chi-square test
//! (α = 0.01, fixed seeds). Also shows the envelope scheme staying exact where the papers'
//! scheme is biased by wrong integrals.

use crate::common;

use common::*;
use partition_sampler::{
    LeafChoice, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, Sampler2D, Scheme, SinPiRows,
    TabulatedDensity,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

fn map() -> (Vec<f64>, usize, usize) {
    (sun_map(32, 16, 1.0), 32, 16)
}

/// The 16 × 8 chi-square bins over the unit square.
fn bins() -> Bins {
    Bins {
        rect: Rect::UNIT,
        nx: 16,
        ny: 8,
    }
}

fn p_value<D: RegionStats>(
    s: &QuadTreeSampler<D>,
    vals: &[f64],
    w: usize,
    h: usize,
    seed: u64,
) -> f64 {
    let bins = bins();
    let masses = sun_map_masses(vals, w, h, &bins);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (hist, _) = bins.histogram((0..60_000).map(|_| s.sample(&mut rng).point));
    chi_square_p(&hist, &masses)
}

fn density(vals: &[f64], w: usize, h: usize) -> TabulatedDensity<SinPiRows> {
    sin_rows(w, h, vals.to_vec(), Rect::UNIT)
}

#[test]
fn correct_provider_passes() {
    let (vals, w, h) = map();
    let s = QuadTreeBuilder::new()
        .build(Broken::new(density(&vals, w, h), 1.0, 1.0))
        .unwrap();
    assert!(p_value(&s, &vals, w, h, 1) > ALPHA);
    assert_eq!(s.stats().bound_violations, 0);
}

#[test]
fn too_low_bounds_are_flagged_by_audit_and_rejected_by_chi_square() {
    let (vals, w, h) = map();
    let s = QuadTreeBuilder::new()
        .max_depth(3)
        .build(Broken::new(density(&vals, w, h), 0.5, 1.0))
        .unwrap();
    let p = p_value(&s, &vals, w, h, 2);
    let st = s.stats();
    assert!(st.bound_violations > 1000, "{st:?}");
    assert!(p < ALPHA, "broken bounds not detected: p = {p}");
}

#[test]
fn wrong_integrals_bias_the_paper_scheme_but_not_the_envelope() {
    let (vals, w, h) = map();
    for choice in [LeafChoice::Alias, LeafChoice::Descent] {
        // (scheme, seed, whether the wrong integrals bias it)
        for (scheme, seed, biased) in [(Scheme::Paper, 3, true), (Scheme::Envelope, 4, false)] {
            let s = QuadTreeBuilder::new()
                .scheme(scheme)
                .leaf_choice(choice)
                .build(Broken::new(density(&vals, w, h), 1.0, 1.5))
                .unwrap();
            let p = p_value(&s, &vals, w, h, seed);
            if biased {
                assert!(
                    p < ALPHA,
                    "perturbed leaf probabilities not detected ({choice:?}): p = {p}"
                );
            } else {
                assert!(
                    p > ALPHA,
                    "envelope scheme should be exact with wrong integrals ({choice:?}): p = {p}"
                );
            }
        }
    }
}

#[test]
fn chi_square_helper_rejects_a_wrong_distribution() {
    // Uniform points against the masses of a non-uniform map.
    let (vals, w, h) = map();
    let bins = bins();
    let masses = sun_map_masses(&vals, w, h, &bins);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
    use rand::RngExt;
    let (hist, _) = bins.histogram((0..20_000).map(|_| [rng.random::<f64>(), rng.random::<f64>()]));
    assert!(chi_square_p(&hist, &masses) < ALPHA);
}
