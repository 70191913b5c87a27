//! A bare sampling loop for profilers (`perf stat` / `perf record`): builds one sampler for one
//! map and draws N planar samples on one thread, one `sample_uv` call per sample (`one`,
//! default) or with `sample_into` on a reused buffer of 256 (`block`; the same samples), or
//! `block` fed by the lane-parallel generator [`envmap::LaneRng`] (`lane`; other samples,
//! same law).
//! Prints wall time and the thread's CPU time per sample (from `/proc/thread-self/stat`,
//! Linux; the figure to quote on a loaded machine).
//!
//! `cargo run --release -p envmap --example profile_loop -- [MAP|sky] [adaptive|adaptive-descent|adaptive-paper|pwc] [N] [N_MAX] [one|block|lane]`

use std::time::Instant;

use distributions::{Sample2, Sampler2D, thread_cpu_seconds};
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
    let mode = args.get(4).map(String::as_str).unwrap_or("one");
    let (block, lanes) = match mode {
        "one" => (false, false),
        "block" => (true, false),
        "lane" => (true, true),
        other => return Err(format!("unknown mode {other} (one|block|lane)").into()),
    };
    let s = EnvMapSampler::new(&map, kind)?;
    let mut xoshiro = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(1);
    let mut lane_rng = envmap::LaneRng::seed_from_u64(1);
    let draw: &mut dyn FnMut(&EnvMapSampler, &mut [Sample2]) = if lanes {
        &mut |s, out| s.sample_into(&mut lane_rng, out)
    } else {
        &mut |s, out| s.sample_into(&mut xoshiro, out)
    };
    let cpu0 = thread_cpu_seconds();
    let t = Instant::now();
    let mut acc = 0.0;
    if block {
        let mut buf = [Sample2 {
            point: [0.0; 2],
            pdf: 0.0,
        }; 256];
        let mut left = n;
        while left > 0 {
            let k = left.min(buf.len());
            draw(&s, &mut buf[..k]);
            acc += buf[..k].iter().map(|x| x.pdf).sum::<f64>();
            left -= k;
        }
    } else {
        for _ in 0..n {
            acc += s.sample_uv(&mut xoshiro).pdf;
        }
    }
    let secs = t.elapsed().as_secs_f64();
    let cpu = cpu0.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
    std::hint::black_box(acc);
    println!(
        "{} samples ({}) in {secs:.3} s: {:.2} M samples/s wall; thread CPU {}",
        n,
        mode,
        n as f64 / secs / 1e6,
        cpu.map_or("n/a".to_string(), |c| format!(
            "{c:.2} s = {:.1} ns/sample",
            c / n as f64 * 1e9
        ))
    );
    Ok(())
}
