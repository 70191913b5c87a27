//! The Rust batch path that `DirectionSampler.sample` wraps, timed without Python: N queries at
//! one ωo in fixed chunks of `PAR_CHUNK` (one generator per chunk), sample + BRDF luminance, on
//! rayon. Prints the median ns per sample over the repeats.
//!
//! `cargo run --release -p brdf-lab-python --example batch_bench -- SAMPLER SPEC [N] [REPEATS]`

use std::sync::Arc;
use std::time::Instant;

use brdf_sampling::SetOptions;
use partition_sampler::{PAR_CHUNK, chunk_rng};
use rayon::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("adaptive", String::as_str);
    let spec = args.get(2).map_or("ggx:alpha=0.2", String::as_str);
    let n: usize = args.get(3).map_or(Ok(1_000_000), |s| s.parse())?;
    let repeats: usize = args.get(4).map_or(Ok(5), |s| s.parse())?;
    let brdf: Arc<dyn brdf::Brdf> = Arc::from(brdf::parse_spec(spec)?);
    let options = SetOptions::default();
    let built = samplers::build_direction(
        name,
        &samplers::DirectionRequest::new(Arc::clone(&brdf), &options),
    )?;
    let wo = brdf::direction_from_angles(45.0, 0.0);
    let mut times = Vec::new();
    let mut checksum = 0.0;
    for r in 0..repeats {
        let start = Instant::now();
        let mut out = vec![([0.0; 3], 0.0, 0.0); n];
        out.par_chunks_mut(PAR_CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let mut rng = chunk_rng(r as u64, c as u64);
                for slot in chunk {
                    let s = built.sampler.sample(&wo, &mut rng);
                    let f = if s.pdf > 0.0 && s.wi.z > 0.0 {
                        brdf.eval(&wo, &s.wi)
                    } else {
                        0.0
                    };
                    *slot = ([s.wi.x, s.wi.y, s.wi.z], s.pdf, f);
                }
            });
        times.push(start.elapsed().as_secs_f64());
        checksum += out.iter().map(|o| o.2).sum::<f64>();
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    println!(
        "rust-batch {name} {spec} n={n} threads={} median {:.1} ns/sample (checksum {checksum:.3e})",
        rayon::current_num_threads(),
        median * 1e9 / n as f64
    );
    Ok(())
}
