//! Does sampling the mixture of the two θ-neighbouring slices help? Prints the variance of the
//! estimator weights `f_r cos θi / pdf` (the albedo estimator) at outgoing directions halfway
//! between two slices (the worst case for the nearest-slice rule), for the nearest slice and for
//! the mixture, with 9 and 90 slices, plus the BRDF evaluations per sample of each.
//!
//! Run: `cargo run --release -p brdf-sampling --example mixture_variance`

use std::sync::Arc;

use brdf::{Brdf, parse_spec};
use brdf_sampling::{QuadTreeSet, SetOptions, Variant, sampled_albedo};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Mean and variance of `f cos / pdf` over `n` samples.
fn weights(set: &QuadTreeSet, brdf: &dyn Brdf, theta_deg: f64, n: usize) -> (f64, f64) {
    let wo = brdf::direction_from_angles(theta_deg, 20.0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let e = sampled_albedo(set, brdf, &wo, n, &mut rng);
    (e.mean, e.variance)
}

fn main() {
    let n = 200_000;
    println!(
        "| model                  | slices | θo (between) | albedo  | Var nearest | Var mixture |    ratio | evals/sample n / m |"
    );
    println!(
        "|------------------------|--------|--------------|---------|-------------|-------------|----------|--------------------|"
    );
    for spec in [
        "phong:n=50",
        "phong:n=1000",
        "ggx:alpha=0.1",
        "cook-torrance",
        "oren-nayar",
        "ward:alpha_x=0.08,alpha_y=0.3",
    ] {
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(spec).expect("spec"));
        for slices in [9usize, 90] {
            let opts = SetOptions {
                slices,
                anisotropic_slices: [slices.min(32), 16],
                ..SetOptions::default()
            };
            let near =
                QuadTreeSet::build(Arc::clone(&brdf), Variant::Adaptive, &opts).expect("build");
            let mix = QuadTreeSet::build(Arc::clone(&brdf), Variant::Adaptive, &opts)
                .expect("build")
                .with_mixture(true);
            let k = near.layout().theta as f64;
            let cost_n = near
                .measure_cost(2000, 3)
                .evaluations_per_sample()
                .unwrap_or(f64::NAN);
            let cost_m = mix
                .measure_cost(2000, 3)
                .evaluations_per_sample()
                .unwrap_or(f64::NAN);
            for target in [30.0, 60.0, 80.0] {
                // Halfway between the slice centres around `target`: a bin edge j · 90° / K.
                let theta = (target * k / 90.0).round() * 90.0 / k;
                let (mean, vn) = weights(&near, brdf.as_ref(), theta, n);
                let (_, vm) = weights(&mix, brdf.as_ref(), theta, n);
                println!(
                    "| {spec:<22} | {:>6} | {theta:>12.2} | {mean:>7.4} | {vn:>11.3e} | {vm:>11.3e} | {:>8.1e} | {cost_n:>8.3} / {cost_m:<7.3} |",
                    near.layout().len(),
                    vm / vn
                );
            }
        }
    }
}
