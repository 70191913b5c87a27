//! A bare sampling loop for profilers (`perf stat` / `perf record`): builds one sampler for one
//! map and draws N planar samples on one thread.
//!
//! `cargo run --release -p envmap --example profile_loop -- [MAP|sky] [adaptive|adaptive-descent|adaptive-paper|pwc] [N] [N_MAX]`

use std::time::Instant;

use envmap::{
    AdaptiveOptions, EnvMap, EnvMapSampler, LeafChoice, SamplerKind, Scheme, procedural_sky,
};
use rand::SeedableRng;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let map = match args.first().map(String::as_str) {
        None | Some("sky") => procedural_sky(1024, 512)?,
        Some(path) => EnvMap::load(path)?,
    };
    let n_max: Option<f64> = args.get(3).map(|s| s.parse()).transpose()?;
    let mut base = AdaptiveOptions::default();
    base.tree.n_max = n_max.unwrap_or(base.tree.n_max);
    let kind = match args.get(1).map(String::as_str).unwrap_or("adaptive") {
        "adaptive" => SamplerKind::Adaptive(base),
        "adaptive-descent" => {
            let mut o = base;
            o.tree.leaf_choice = LeafChoice::Descent;
            SamplerKind::Adaptive(o)
        }
        "adaptive-paper" => {
            let mut o = base;
            o.tree.scheme = Scheme::Paper;
            SamplerKind::Adaptive(o)
        }
        "pwc" => SamplerKind::PiecewiseConstant,
        other => return Err(format!("unknown sampler {other}").into()),
    };
    let n: usize = args
        .get(2)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(20_000_000);
    let s = EnvMapSampler::new(&map, kind)?;
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(1);
    let t = Instant::now();
    let mut acc = 0.0;
    for _ in 0..n {
        acc += s.sample_uv(&mut rng).pdf;
    }
    let secs = t.elapsed().as_secs_f64();
    std::hint::black_box(acc);
    println!(
        "{} samples in {secs:.3} s: {:.2} M samples/s",
        n,
        n as f64 / secs / 1e6
    );
    Ok(())
}
