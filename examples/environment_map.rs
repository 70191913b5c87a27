//! Sample directions ∝ luminance per solid angle of a lat-long map (the built-in sky, or the
//! `.hdr/.exr/.pfm` file given as the first argument) and estimate the map's total power.
//!
//! `cargo run --release -p brdf-lab-examples --example environment_map [-- FILE.hdr]`

use envmap::{AdaptiveOptions, EnvMap, EnvMapSampler, SamplerKind};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let map = match std::env::args().nth(1) {
        Some(path) => EnvMap::load(path)?,
        None => envmap::procedural_sky(1024, 512)?,
    };
    let sampler = EnvMapSampler::new(&map, SamplerKind::Adaptive(AdaptiveOptions::default()))?;
    let samples = sampler.sample_par(1_000_000, 7);
    // ∫ Y dω estimated by (1/N) Σ Y / pdf_sa: zero variance for an exact sampler.
    let estimate: f64 = samples
        .iter()
        .map(|s| envmap::luminance(map.radiance_uv(s.u, s.v)) / s.pdf_sa)
        .sum::<f64>()
        / samples.len() as f64;
    println!(
        "{}x{} map, built in {:.2} ms, {} bytes; ∫ Y dω ≈ {estimate:.6}",
        map.width(),
        map.height(),
        sampler.build_time().as_secs_f64() * 1e3,
        sampler.bytes_used()
    );
    if let Some(s) = sampler.stats() {
        println!(
            "mean trials {:.4}, bound violations {}",
            s.measured_mean_trials.unwrap_or(f64::NAN),
            s.bound_violations
        );
    }
    Ok(())
}
