//! `QuadTree::with_leaf_integrals`: the papers' scheme is exact only with exact leaf integrals.
//! A coarse image map's integrals leave its pdf off; replacing them with accurate ones makes
//! `∫ pdf = 1` and the leaf frequencies follow the new probabilities.

use partition_sampler::{
    BuildError, Domain, Point2, QuadTreeBuilder, QuadTreeSampler, Rect, SampledGridDensity,
    Sampler2D, Scheme,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// A narrow peak (σ = 0.03) that a 16² midpoint grid integrates poorly.
fn peak(p: Point2) -> f64 {
    let (dx, dy) = (p[0] - 0.23, p[1] + 0.11);
    0.05 + (-(dx * dx + dy * dy) / (2.0 * 0.03 * 0.03)).exp()
}

/// `∫_rect f` by the midpoint rule on a `k × k` sub-grid (accurate for k = 64 on leaves).
fn integral(f: fn(Point2) -> f64, r: &Rect, k: usize) -> f64 {
    let (w, h) = (r.width() / k as f64, r.height() / k as f64);
    let mut s = 0.0;
    for j in 0..k {
        for i in 0..k {
            s += f([r.x0 + (i as f64 + 0.5) * w, r.y0 + (j as f64 + 0.5) * h]);
        }
    }
    s * w * h
}

/// `∫ pdf dA` over the square by the midpoint rule on 1024².
fn pdf_mass<S: Sampler2D>(s: &S) -> f64 {
    integral_of(|p| s.pdf(p))
}

fn integral_of(g: impl Fn(Point2) -> f64) -> f64 {
    let n = 1024;
    let h = 2.0 / n as f64;
    let mut s = 0.0;
    for j in 0..n {
        for i in 0..n {
            s += g([-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h]);
        }
    }
    s * h * h
}

#[test]
fn exact_leaf_integrals_make_the_papers_scheme_exact() {
    let f: fn(Point2) -> f64 = peak;
    let rect = Rect::new(-1.0, -1.0, 1.0, 1.0);
    let density = SampledGridDensity::new(f, Domain::Rect(rect), 16).unwrap();
    let tree = QuadTreeBuilder::new()
        .scheme(Scheme::Paper)
        .max_depth(3)
        .build_tree(&density)
        .unwrap();
    let grid_sampler = QuadTreeSampler::from_parts(tree.clone(), density.clone()).unwrap();
    // Negative control: the grid's integrals leave the pdf off by more than 1 %.
    let off = (pdf_mass(&grid_sampler) - 1.0).abs();
    assert!(off > 0.01, "grid integrals unexpectedly exact: {off}");

    let exact: Vec<f64> = tree.leaves().map(|l| integral(f, &l.rect, 64)).collect();
    let fixed_tree = tree
        .clone()
        .with_leaf_integrals(exact.clone(), None)
        .unwrap();
    let fixed = QuadTreeSampler::from_parts(fixed_tree.clone(), density).unwrap();
    let mass = pdf_mass(&fixed);
    assert!((mass - 1.0).abs() < 2e-3, "∫ pdf = {mass}");

    // Leaf frequencies follow I_i / Î (4σ binomial bounds, 200 000 samples).
    let n = 200_000;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let leaves: Vec<Rect> = fixed_tree.leaves().map(|l| l.rect).collect();
    let mut counts = vec![0usize; leaves.len()];
    for _ in 0..n {
        let s = fixed.sample(&mut rng);
        if let Some(i) = leaves.iter().position(|r| r.contains_half_open(s.point)) {
            counts[i] += 1;
        }
    }
    let total: f64 = exact.iter().sum();
    for (c, i) in counts.iter().zip(&exact) {
        let p = i / total;
        let sd = (n as f64 * p * (1.0 - p)).sqrt();
        assert!(
            (*c as f64 - n as f64 * p).abs() <= 4.0 * sd + 1.0,
            "count {c} vs expected {}",
            n as f64 * p
        );
    }
}

#[test]
fn invalid_leaf_integrals_are_typed_errors() {
    let d = SampledGridDensity::new(peak as fn(Point2) -> f64, Domain::UnitDisc, 32).unwrap();
    let tree = QuadTreeBuilder::new().build_tree(&d).unwrap();
    let n = tree.leaves().len();
    for bad in [
        vec![1.0; n + 1],
        vec![f64::NAN; n],
        vec![-1.0; n],
        vec![0.0; n],
    ] {
        assert!(matches!(
            tree.clone().with_leaf_integrals(bad, None),
            Err(BuildError::InvalidLeafIntegrals(_))
        ));
    }
}
