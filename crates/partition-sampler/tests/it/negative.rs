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

fn p_value<D: RegionStats>(
    s: &QuadTreeSampler<D>,
    vals: &[f64],
    w: usize,
    h: usize,
    seed: u64,
) -> f64 {
    let bins = Bins {
        rect: Rect::UNIT,
        nx: 16,
        ny: 8,
    };
    let masses = sun_map_masses(vals, w, h, &bins);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (hist, _) = bins.histogram((0..60_000).map(|_| s.sample(&mut rng).point));
    chi_square_p(&hist, &masses)
}

fn density(vals: &[f64], w: usize, h: usize) -> TabulatedDensity<SinPiRows> {
    TabulatedDensity::new(w, h, vals.to_vec(), Rect::UNIT)
        .unwrap()
        .with_row_factor(SinPiRows)
        .unwrap()
}

#[test]
fn correct_provider_passes() {
    let (vals, w, h) = map();
    let wrapped = Broken {
        inner: density(&vals, w, h),
        bound_scale: 1.0,
        left_integral_scale: 1.0,
    };
    let s = QuadTreeBuilder::new().build(wrapped).unwrap();
    assert!(p_value(&s, &vals, w, h, 1) > ALPHA);
    assert_eq!(s.stats().bound_violations, 0);
}

#[test]
fn too_low_bounds_are_flagged_by_audit_and_rejected_by_chi_square() {
    let (vals, w, h) = map();
    let wrapped = Broken {
        inner: density(&vals, w, h),
        bound_scale: 0.5,
        left_integral_scale: 1.0,
    };
    let s = QuadTreeBuilder::new().max_depth(3).build(wrapped).unwrap();
    let p = p_value(&s, &vals, w, h, 2);
    let st = s.stats();
    assert!(st.bound_violations > 1000, "{st:?}");
    assert!(p < ALPHA, "broken bounds not detected: p = {p}");
}

#[test]
fn wrong_integrals_bias_the_paper_scheme_but_not_the_envelope() {
    let (vals, w, h) = map();
    for choice in [LeafChoice::Alias, LeafChoice::Descent] {
        let paper = Broken {
            inner: density(&vals, w, h),
            bound_scale: 1.0,
            left_integral_scale: 1.5,
        };
        let s = QuadTreeBuilder::new()
            .scheme(Scheme::Paper)
            .leaf_choice(choice)
            .build(paper)
            .unwrap();
        let p = p_value(&s, &vals, w, h, 3);
        assert!(
            p < ALPHA,
            "perturbed leaf probabilities not detected ({choice:?}): p = {p}"
        );
        let env = Broken {
            inner: density(&vals, w, h),
            bound_scale: 1.0,
            left_integral_scale: 1.5,
        };
        let s = QuadTreeBuilder::new()
            .scheme(Scheme::Envelope)
            .leaf_choice(choice)
            .build(env)
            .unwrap();
        let p = p_value(&s, &vals, w, h, 4);
        assert!(
            p > ALPHA,
            "envelope scheme should be exact with wrong integrals ({choice:?}): p = {p}"
        );
    }
}

#[test]
fn chi_square_helper_rejects_a_wrong_distribution() {
    // Uniform points against the masses of a non-uniform map.
    let (vals, w, h) = map();
    let bins = Bins {
        rect: Rect::UNIT,
        nx: 16,
        ny: 8,
    };
    let masses = sun_map_masses(&vals, w, h, &bins);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
    use rand::RngExt;
    let (hist, _) = bins.histogram((0..20_000).map(|_| [rng.random::<f64>(), rng.random::<f64>()]));
    assert!(chi_square_p(&hist, &masses) < ALPHA);
}
