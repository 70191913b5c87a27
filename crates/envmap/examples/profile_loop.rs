//! A bare sampling loop for profilers (`perf stat` / `perf record`): builds one sampler for one
//! map and draws N planar samples on one thread, one `sample_uv` call per sample (`one`,
//! default) or with `sample_into` on a reused buffer of 256 (`block`; the same samples), or
//! `block` fed by the lane-parallel generator [`envmap::LaneRng`] (`lane`; other samples,
//! same law).
//! Prints wall time and the thread's CPU time per sample (from `/proc/thread-self/stat`,
//! Linux; the figure to quote on a loaded machine). `pwc-f64` is the reference of
//! `docs/benchmarks.md` §25.6: `distributions::PiecewiseConstant2D` (f64 CDFs searched from
//! guide tables, what `envmap-cdf` was before §24.4) on the same weights as `pwc`.
//!
//! `cargo run --release -p envmap --example profile_loop -- [MAP|sky] [adaptive|adaptive-descent|adaptive-paper|pwc|pwc-f64] [N] [N_MAX] [one|block|lane]`

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
    let name = args.get(1).map(String::as_str).unwrap_or("adaptive");
    if name == "pwc-f64" {
        return reference_f64(&map, &args);
    }
    let kind = match name {
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

/// The `pwc-f64` reference: `PiecewiseConstant2D` of `Y(pixel) · sin(π v_centre)` on `[0,1]²`
/// (the weights `EnvMapSampler::piecewise_constant` quantises), drawn as the other modes.
fn reference_f64(map: &EnvMap, args: &[String]) -> Result<(), Box<dyn std::error::Error>> {
    let (w, h) = (map.width(), map.height());
    let values: Vec<f64> = map
        .rgb()
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            envmap::luminance(p) * (std::f64::consts::PI * ((i / w) as f64 + 0.5) / h as f64).sin()
        })
        .collect();
    let s = distributions::PiecewiseConstant2D::new(w, h, values, distributions::Rect::UNIT)?;
    let n: usize = args
        .get(2)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(20_000_000);
    let mode = args.get(4).map(String::as_str).unwrap_or("one");
    let mut xoshiro = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(1);
    let cpu0 = thread_cpu_seconds();
    let mut acc = 0.0;
    if mode == "one" {
        for _ in 0..n {
            acc += s.sample(&mut xoshiro).pdf;
        }
    } else {
        let mut buf = [Sample2 {
            point: [0.0; 2],
            pdf: 0.0,
        }; 256];
        let mut left = n;
        while left > 0 {
            let k = left.min(buf.len());
            s.sample_into(&mut xoshiro, &mut buf[..k]);
            acc += buf[..k].iter().map(|x| x.pdf).sum::<f64>();
            left -= k;
        }
    }
    let cpu = cpu0.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
    std::hint::black_box(acc);
    println!(
        "{n} samples (pwc-f64 {mode}); thread CPU {}",
        cpu.map_or("n/a".to_string(), |c| format!(
            "{c:.2} s = {:.1} ns/sample",
            c / n as f64 * 1e9
        ))
    );
    Ok(())
}
