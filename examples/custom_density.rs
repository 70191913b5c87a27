//! The generic sampler on a density that is not a BRDF: a ring with a bright spot on the unit
//! disc, sampled exactly by rejection in the quadtree's leaves.
//!
//! `cargo run --release -p brdf-lab-examples --example custom_density`

use partition_sampler::{Domain, QuadTreeBuilder, SampledGridDensity, Sampler2D};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // f(x, y) ≥ 0 on the unit disc: a Gaussian ring of radius 0.6 plus a narrow spot.
    let f = |p: [f64; 2]| {
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        let ring = (-((r - 0.6) / 0.05).powi(2)).exp();
        let spot = 20.0 * (-((p[0] - 0.3).powi(2) + (p[1] + 0.2).powi(2)) / 0.001).exp();
        ring + spot
    };
    // Bounds and integrals from a dense grid (512²), bounds widened by the default safety factor.
    let density = SampledGridDensity::new(f, Domain::UnitDisc, 512)?;
    let sampler = QuadTreeBuilder::new().n_max(2.0).build(density)?;

    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let n = 1_000_000;
    let mut inside_spot = 0usize;
    for _ in 0..n {
        let s = sampler.sample(&mut rng);
        if (s.point[0] - 0.3).powi(2) + (s.point[1] + 0.2).powi(2) < 0.01 {
            inside_spot += 1;
        }
    }
    let stats = sampler.stats();
    println!(
        "{} leaves, depth {}, {} bytes; expected trials {:.3}, measured {:.3}; bound violations {}",
        stats.leaves,
        stats.depth,
        stats.bytes,
        stats.expected_mean_trials,
        stats.measured_mean_trials.unwrap_or(f64::NAN),
        stats.bound_violations
    );
    println!(
        "fraction of samples within 0.1 of the spot: {:.4}",
        inside_spot as f64 / n as f64
    );
    Ok(())
}
