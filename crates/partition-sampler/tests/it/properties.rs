//! Invariants over random inputs: samples in the domain, pdf ≥ 0 and > 0 where f > 0,
//! sample and pdf agree, serde round trips give identical samples, switching the leaf choice
//! rebuilds exactly the builder's descent CDFs.

use partition_sampler::{
    Domain, LeafChoice, QuadTree, QuadTreeBuilder, QuadTreeSampler, Rect, SampledGridDensity,
    Sampler2D, Scheme, SinPiRows, TabulatedDensity,
};
use proptest::prelude::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

fn grid() -> impl Strategy<Value = (usize, usize, Vec<f64>)> {
    (1usize..9, 1usize..9).prop_flat_map(|(w, h)| {
        (
            Just(w),
            Just(h),
            prop::collection::vec(prop_oneof![Just(0.0), 0.0f64..10.0, Just(1e5)], w * h),
        )
    })
}

fn rect() -> impl Strategy<Value = Rect> {
    (-5.0f64..5.0, -5.0f64..5.0, 0.01f64..4.0, 0.01f64..4.0)
        .prop_map(|(x, y, w, h)| Rect::new(x, y, x + w, y + h))
}

fn scheme() -> impl Strategy<Value = (Scheme, LeafChoice)> {
    proptest::sample::select(partition_sampler::SAMPLING_CONFIGS.to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn tabulated_samples_and_pdf((w, h, vals) in grid(), r in rect(), sin in any::<bool>(), (sc, lc) in scheme(),
                                 n_max in 1.1f64..4.0, depth in 0u32..10, seed in any::<u64>()) {
        prop_assume!(vals.iter().any(|&v| v > 0.0));
        let d = TabulatedDensity::new(w, h, vals.clone(), r).unwrap();
        let b = QuadTreeBuilder::new().n_max(n_max).max_depth(depth).scheme(sc).leaf_choice(lc);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        if sin {
            let s = b.build(d.with_row_factor(SinPiRows).unwrap()).unwrap();
            check(&s, r, &mut rng)?;
        } else {
            let s = b.build(d).unwrap();
            check(&s, r, &mut rng)?;
        }
    }

    #[test]
    fn disc_samples_and_pdf(cx in -0.9f64..0.9, cy in -0.9f64..0.9, e in 1.0f64..200.0, (sc, lc) in scheme(), seed in any::<u64>()) {
        let f = move |p: [f64; 2]| 1e-3 + (-(e * ((p[0] - cx).powi(2) + (p[1] - cy).powi(2)))).exp();
        let d = SampledGridDensity::new(f, Domain::UnitDisc, 32).unwrap();
        let s = QuadTreeBuilder::new().scheme(sc).leaf_choice(lc).build(d).unwrap();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        for _ in 0..100 {
            let x = s.sample(&mut rng);
            prop_assert!(x.point[0].powi(2) + x.point[1].powi(2) <= 1.0);
            prop_assert!(x.pdf > 0.0);
        }
        for _ in 0..100 {
            let p = [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
            let inside = p[0] * p[0] + p[1] * p[1] <= 1.0;
            let pdf = s.pdf(p);
            prop_assert!(pdf >= 0.0);
            prop_assert_eq!(pdf > 0.0, inside, "p = {:?}", p);
        }
    }

    #[test]
    fn with_leaf_choice_rebuilds_identical_cdfs((w, h, vals) in grid(), paper in any::<bool>(),
                                               cx in -0.9f64..0.9, e in 1.0f64..200.0, seed in any::<u64>()) {
        prop_assume!(vals.iter().any(|&v| v > 0.0));
        let sc = if paper { Scheme::Paper } else { Scheme::Envelope };
        let b = |lc| QuadTreeBuilder::new().scheme(sc).leaf_choice(lc);
        let d = TabulatedDensity::new(w, h, vals, Rect::new(0.1, -0.3, 0.7, 2.0)).unwrap();
        check_switch(b(LeafChoice::Descent).build(d.clone()).unwrap(),
                     b(LeafChoice::Alias).build(d).unwrap(), seed)?;
        let f = move |p: [f64; 2]| 1e-3 + (-(e * ((p[0] - cx).powi(2) + p[1] * p[1]))).exp();
        let disc = || SampledGridDensity::new(f, Domain::UnitDisc, 32).unwrap();
        check_switch(b(LeafChoice::Descent).build(disc()).unwrap(),
                     b(LeafChoice::Alias).build(disc()).unwrap(), seed)?;
    }

    #[test]
    fn serde_round_trip_gives_identical_samples((w, h, vals) in grid(), (sc, lc) in scheme(), seed in any::<u64>()) {
        prop_assume!(vals.iter().any(|&v| v > 0.0));
        let d = TabulatedDensity::new(w, h, vals, Rect::UNIT).unwrap().with_row_factor(SinPiRows).unwrap();
        let s = QuadTreeBuilder::new().scheme(sc).leaf_choice(lc).build(d.clone()).unwrap();
        let bytes = s.tree().to_bytes();
        let tree = QuadTree::from_bytes(&bytes).unwrap();
        prop_assert_eq!(&tree, s.tree());
        let json = serde_json::to_string(s.tree()).unwrap();
        let tree_json: QuadTree = serde_json::from_str(&json).unwrap();
        // JSON float parsing is not bit-exact: only check that the tree attaches again.
        prop_assert!(QuadTreeSampler::from_parts(tree_json, d.clone()).is_ok());
        let r = QuadTreeSampler::from_parts(tree, d).unwrap();
        let (mut a, mut b) = (Xoshiro256PlusPlus::seed_from_u64(seed), Xoshiro256PlusPlus::seed_from_u64(seed));
        for _ in 0..50 {
            let x = s.sample(&mut a);
            prop_assert_eq!(x, r.sample(&mut b));
        }
    }
}

/// A tree built with `Descent` and one built with `Alias` then switched to `Descent` are
/// bit-identical (same encoding, hence the same CDFs) and draw identical samples; switching
/// back to `Alias` frees the CDFs.
fn check_switch<D: partition_sampler::RegionStats>(
    descent: QuadTreeSampler<D>,
    alias: QuadTreeSampler<D>,
    seed: u64,
) -> Result<(), TestCaseError> {
    let alias_bytes = alias.tree().to_bytes();
    let alias_node_bytes = alias.tree().node_bytes();
    let switched = alias.with_leaf_choice(LeafChoice::Descent);
    prop_assert_eq!(switched.tree(), descent.tree());
    prop_assert_eq!(switched.tree().to_bytes(), descent.tree().to_bytes());
    prop_assert_eq!(
        switched.tree().node_bytes(),
        alias_node_bytes + 24 * switched.tree().counts().internal
    );
    let (mut a, mut b) = (
        Xoshiro256PlusPlus::seed_from_u64(seed),
        Xoshiro256PlusPlus::seed_from_u64(seed),
    );
    for _ in 0..50 {
        prop_assert_eq!(switched.sample(&mut a), descent.sample(&mut b));
    }
    let back = switched.with_leaf_choice(LeafChoice::Alias);
    prop_assert_eq!(back.tree().to_bytes(), alias_bytes);
    prop_assert_eq!(back.tree().node_bytes(), alias_node_bytes);
    Ok(())
}

fn check<D: partition_sampler::RegionStats>(
    s: &QuadTreeSampler<D>,
    r: Rect,
    rng: &mut Xoshiro256PlusPlus,
) -> Result<(), TestCaseError> {
    for _ in 0..100 {
        let x = s.sample(rng);
        prop_assert!(r.contains(x.point), "{:?} outside {:?}", x.point, r);
        prop_assert!(x.pdf > 0.0);
        let p = s.pdf(x.point);
        prop_assert!((p - x.pdf).abs() <= 1e-9 * x.pdf, "{} vs {}", p, x.pdf);
    }
    for _ in 0..100 {
        let p = [rng.random_range(r.x0..r.x1), rng.random_range(r.y0..r.y1)];
        let f = s.density().eval_point(p);
        let pdf = s.pdf(p);
        prop_assert!(pdf >= 0.0);
        prop_assert_eq!(pdf > 0.0, f > 0.0, "p = {:?}, f = {}", p, f);
    }
    prop_assert_eq!(s.stats().bound_violations, 0);
    Ok(())
}

trait EvalPoint {
    fn eval_point(&self, p: [f64; 2]) -> f64;
}
impl<T: partition_sampler::Density> EvalPoint for T {
    fn eval_point(&self, p: [f64; 2]) -> f64 {
        self.eval(p)
    }
}
