//! Prints, for the procedural sky and every map in `shared/data/envmaps` (or the files given
//! as arguments), each sampler's build time, memory, and expected / measured mean trials.
//!
//! `cargo run --release -p envmap --example envmap_stats [-- MAP.hdr ... [--n-max X]...]`

use std::path::PathBuf;
use std::time::Instant;

use envmap::{
    AdaptiveOptions, EnvMap, EnvMapSampler, LeafChoice, SamplerKind, Scheme, procedural_sky,
};

#[path = "../benches/support/mod.rs"]
mod support;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut n_max = vec![];
    let mut files = vec![];
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--n-max" {
            n_max.push(it.next().ok_or("--n-max needs a value")?.parse::<f64>()?);
        } else {
            files.push(PathBuf::from(a));
        }
    }
    if n_max.is_empty() {
        n_max.push(AdaptiveOptions::default().tree.n_max);
    }
    if files.is_empty() {
        match support::real_map_paths() {
            Ok(paths) => files = paths,
            Err(dir) => eprintln!("{} is absent: only the procedural sky", dir.display()),
        }
    }
    let mut maps = vec![("procedural-sky".to_string(), procedural_sky(1024, 512)?)];
    for f in &files {
        maps.push((
            f.file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned(),
            EnvMap::load(f)?,
        ));
    }
    let n = 2_000_000;
    println!(
        "{:<28} {:>9} {:<26} {:>9} {:>11} {:>9} {:>9} {:>7} {:>10}",
        "map", "size", "sampler", "build ms", "bytes", "E[trials]", "trials", "viol.", "Ms/s (1t)"
    );
    for (name, map) in &maps {
        let mut kinds = vec![];
        for &nm in &n_max {
            for (scheme, leaf_choice) in [
                (Scheme::Envelope, LeafChoice::Alias),
                (Scheme::Envelope, LeafChoice::Descent),
                (Scheme::Paper, LeafChoice::Alias),
            ] {
                let mut o = AdaptiveOptions::with_scheme(scheme, leaf_choice);
                o.tree.n_max = nm;
                kinds.push(SamplerKind::Adaptive(o));
            }
        }
        kinds.push(SamplerKind::PiecewiseConstant);
        for kind in kinds {
            let s = EnvMapSampler::new(map, kind)?;
            let label = match kind {
                SamplerKind::Adaptive(o) => {
                    format!(
                        "adaptive/{:?}/{:?}/n_max={}",
                        o.tree.scheme, o.tree.leaf_choice, o.tree.n_max
                    )
                }
                SamplerKind::PiecewiseConstant => "piecewise-constant".to_string(),
            };
            let mut rng = <rand::rngs::Xoshiro256PlusPlus as rand::SeedableRng>::seed_from_u64(1);
            let t = Instant::now();
            let mut acc = 0.0;
            for _ in 0..n {
                acc += s.sample_uv(&mut rng).pdf;
            }
            let rate = n as f64 / t.elapsed().as_secs_f64() / 1e6;
            std::hint::black_box(acc);
            let (expected, measured, violations) = match s.stats() {
                Some(st) => (
                    st.expected_mean_trials,
                    st.measured_mean_trials.unwrap_or(f64::NAN),
                    st.bound_violations,
                ),
                None => (1.0, 1.0, 0),
            };
            println!(
                "{:<28} {:>9} {:<26} {:>9.2} {:>11} {:>9.4} {:>9.4} {:>7} {:>10.1}",
                name,
                format!("{}x{}", map.width(), map.height()),
                label,
                s.build_time().as_secs_f64() * 1e3,
                s.bytes_used(),
                expected,
                measured,
                violations,
                rate
            );
        }
    }
    Ok(())
}
