//! The measured-materials benchmark of docs/benchmarks.md: relative variance per sample
//! ("cv²") of the luminance of `f·cos/pdf` for the shared RGL materials at θo ∈ {0, 30, 60,
//! 80}°, for `adaptive`, `adaptive-mixture`, `adaptive-exact` and `rgl-native` in the same run,
//! with each sampler's sampling throughput (one thread, sampling only; and two threads
//! including one evaluation of `f` per sample, the figure Mitsuba's `bsdf.sample` reports),
//! the file read time and the build time.
//!
//! ```text
//! cargo run --release -p samplers --example measured_cv2 -- [DIR] [N]
//! ```
//! `DIR` defaults to `../shared/data/measured/rgl` (relative to the repository root), `N` (samples
//! per case) to 1,000,000. Seed fixed (1).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use brdf::{Brdf, direction_from_angles};
use brdf_sampling::SetOptions;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use samplers::{DirectionRequest, build_direction};

const ANGLES: [f64; 4] = [0.0, 30.0, 60.0, 80.0];
const SAMPLERS: [&str; 4] = [
    "adaptive",
    "adaptive-mixture",
    "adaptive-exact",
    "rgl-native",
];

/// Samples per second on two threads, each drawing `n / 2` samples (its own generator) at
/// `wo` and evaluating `f(ωo, ωi)` once per sample, as a renderer computing the weight
/// `f·cos/pdf` does (Mitsuba's `bsdf.sample` returns that weight).
fn two_thread_rate(
    sampler: &dyn brdf_sampling::DirectionSampler,
    brdf: &dyn Brdf,
    wo: &brdf::Vec3,
    n: usize,
) -> f64 {
    let t = Instant::now();
    std::thread::scope(|scope| {
        for k in 0..2u64 {
            scope.spawn(move || {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(100 + k);
                let mut acc = 0.0;
                for _ in 0..n / 2 {
                    let s = sampler.sample(wo, &mut rng);
                    if s.pdf > 0.0 {
                        acc += brdf.eval(wo, &s.wi) * s.wi.z / s.pdf;
                    }
                }
                std::hint::black_box(acc);
            });
        }
    });
    (n / 2 * 2) as f64 / t.elapsed().as_secs_f64() / 1e6
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut args = std::env::args().skip(1);
    let dir = args
        .next()
        .map_or_else(|| root.join("../shared/data/measured/rgl"), PathBuf::from);
    let n: usize = args.next().map_or(Ok(1_000_000), |s| s.parse())?;
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
        .collect();
    files.sort();
    println!("N = {n} samples per case, seed 1; cv² = Var[Y(f)·cos/pdf] / E[Y(f)·cos/pdf]²");
    println!(
        "| material | sampler | build s | M samples/s (1 thr) | M samples/s (2 thr, with f) | cv² 0° | cv² 30° | cv² 60° | cv² 80° |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for file in files {
        let t = Instant::now();
        let b = brdf::RglBrdf::load(&file)?;
        let read = t.elapsed().as_secs_f64();
        let name = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        println!("<!-- {name}: read in {:.1} ms -->", 1e3 * read);
        let brdf: Arc<dyn Brdf> = Arc::new(b);
        for sampler in SAMPLERS {
            let options = SetOptions::default();
            let t = Instant::now();
            let built =
                build_direction(sampler, &DirectionRequest::new(Arc::clone(&brdf), &options))?;
            let build = t.elapsed().as_secs_f64();
            let mut cells = Vec::new();
            let mut sample_time = 0.0;
            let mut rate2 = 0.0;
            for theta in ANGLES {
                let wo = direction_from_angles(theta, 0.0);
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
                let t = Instant::now();
                let samples = built.sampler.sample_batch(&wo, n, &mut rng);
                sample_time += t.elapsed().as_secs_f64();
                let weights: Vec<f64> = samples
                    .iter()
                    .map(|s| {
                        if s.wi.z > 0.0 && s.pdf > 0.0 {
                            brdf.eval(&wo, &s.wi) * s.wi.z / s.pdf
                        } else {
                            0.0
                        }
                    })
                    .collect();
                rate2 += two_thread_rate(built.sampler.as_ref(), brdf.as_ref(), &wo, n)
                    / ANGLES.len() as f64;
                // Two passes: an exact sampler's weights are equal to ~1e-16, which
                // E[w²] − E[w]² would drown in cancellation.
                let mean = weights.iter().sum::<f64>() / n as f64;
                let var = weights.iter().map(|w| (w - mean) * (w - mean)).sum::<f64>() / n as f64;
                cells.push(format!("{:.2e}", var / (mean * mean)));
            }
            let rate = (ANGLES.len() * n) as f64 / sample_time / 1e6;
            println!(
                "| {name} | {sampler} | {build:.2} | {rate:.2} | {rate2:.2} | {} |",
                cells.join(" | ")
            );
        }
    }
    Ok(())
}
