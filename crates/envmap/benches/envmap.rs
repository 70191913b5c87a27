//! Build time and sampling throughput of the environment-map samplers.
//!
//! For the procedural sky (1024 × 512) and every map in `shared/data/envmaps` (skipped with a
//! message when the folder is absent), for the adaptive sampler (envelope / paper scheme, alias
//! / descent leaf choice, default `n_max`) and the piecewise-constant CDF baseline:
//! * `build/…`: constructing the sampler from the loaded map (luminance table included);
//! * `uv_1t/…`: a single-thread loop of `sample_uv` (planar samples, no trigonometry);
//! * `uv_block_1t/…`: the same samples drawn with `sample_into` on a reused buffer of 250
//!   (the block path: candidates and density lookups per block);
//! * `dir_1t/…`: a single-thread loop of `sample` (with direction and solid-angle pdf);
//! * `uv_par/…`: `sample_uv_par` (rayon, all threads) of 1 M samples.
//!
//! Throughput is reported in elements (samples) per second.
//! `cargo bench -p envmap --bench envmap -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use distributions::{Sample2, Sampler2D};
use envmap::{
    AdaptiveOptions, EnvMap, EnvMapSampler, LeafChoice, SamplerKind, Scheme, procedural_sky,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

mod support;

fn maps() -> Vec<(String, EnvMap)> {
    let mut maps = vec![(
        "sky".to_string(),
        procedural_sky(1024, 512).expect("procedural sky"),
    )];
    match support::real_map_paths() {
        Ok(paths) => {
            for p in paths {
                let name = p
                    .file_stem()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .split('_')
                    .next()
                    .unwrap_or("map")
                    .to_string();
                match EnvMap::load(&p) {
                    Ok(m) => {
                        eprintln!("map {name}: {} ({}×{})", p.display(), m.width(), m.height());
                        maps.push((name, m));
                    }
                    Err(e) => eprintln!("skipping {}: {e}", p.display()),
                }
            }
        }
        Err(dir) => eprintln!(
            "{} is absent: benchmarking the procedural sky only",
            dir.display()
        ),
    }
    maps
}

fn kinds() -> Vec<(&'static str, SamplerKind)> {
    let a = |scheme, leaf_choice| {
        SamplerKind::Adaptive(AdaptiveOptions::with_scheme(scheme, leaf_choice))
    };
    vec![
        ("envelope-alias", a(Scheme::Envelope, LeafChoice::Alias)),
        ("envelope-descent", a(Scheme::Envelope, LeafChoice::Descent)),
        ("paper-alias", a(Scheme::Paper, LeafChoice::Alias)),
        ("paper-descent", a(Scheme::Paper, LeafChoice::Descent)),
        ("pwc", SamplerKind::PiecewiseConstant),
    ]
}

const LOOP: usize = 100_000;
/// Buffer of the `uv_block_1t` group (`LOOP` is a multiple of it).
const BLOCK: usize = 250;
const PAR: usize = 1_000_000;

/// Group `group`: per sampler, `LOOP` calls of `draw` (one sample each, its value summed) from
/// a generator seeded with 1.
fn bench_one_sample_loop<'a>(
    c: &mut Criterion,
    group: String,
    samplers: impl IntoIterator<Item = &'a (&'static str, EnvMapSampler)>,
    draw: impl Fn(&EnvMapSampler, &mut Xoshiro256PlusPlus) -> f64,
) {
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(LOOP as u64));
    for (name, s) in samplers {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        g.bench_function(*name, |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for _ in 0..LOOP {
                    acc += draw(s, &mut rng);
                }
                acc
            })
        });
    }
    g.finish();
}

fn benches(c: &mut Criterion) {
    for (map_name, map) in maps() {
        let mut build = c.benchmark_group(format!("build/{map_name}"));
        for (name, kind) in kinds() {
            build.bench_function(name, |b| {
                b.iter(|| EnvMapSampler::new(black_box(&map), kind).expect("build"))
            });
        }
        build.finish();

        let samplers: Vec<_> = kinds()
            .into_iter()
            .map(|(name, kind)| (name, EnvMapSampler::new(&map, kind).expect("build")))
            .collect();
        for (s_name, s) in &samplers {
            if let Some(st) = s.stats() {
                eprintln!(
                    "{map_name}/{s_name}: {} bytes, {} leaves, expected mean trials {:.4}",
                    s.bytes_used(),
                    st.active_leaves,
                    st.expected_mean_trials
                );
            } else {
                eprintln!("{map_name}/{s_name}: {} bytes", s.bytes_used());
            }
        }

        bench_one_sample_loop(c, format!("uv_1t/{map_name}"), &samplers, |s, rng| {
            s.sample_uv(rng).pdf
        });

        let mut g = c.benchmark_group(format!("uv_block_1t/{map_name}"));
        g.throughput(Throughput::Elements(LOOP as u64));
        for (name, s) in &samplers {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
            let mut buf = vec![
                Sample2 {
                    point: [0.0; 2],
                    pdf: 0.0
                };
                BLOCK
            ];
            g.bench_function(*name, |b| {
                b.iter(|| {
                    let mut acc = 0.0;
                    for _ in 0..LOOP / BLOCK {
                        s.sample_into(&mut rng, &mut buf);
                        acc += buf.iter().map(|x| x.pdf).sum::<f64>();
                    }
                    acc
                })
            });
        }
        g.finish();

        let some = samplers
            .iter()
            .filter(|(n, _)| matches!(*n, "envelope-alias" | "pwc"));
        bench_one_sample_loop(c, format!("dir_1t/{map_name}"), some, |s, rng| {
            s.sample(rng).pdf_sa
        });

        let mut g = c.benchmark_group(format!("uv_par/{map_name}"));
        g.throughput(Throughput::Elements(PAR as u64));
        for (name, s) in &samplers {
            let mut seed = 0;
            g.bench_function(*name, |b| {
                b.iter(|| {
                    seed += 1;
                    s.sample_uv_par(PAR, seed)
                })
            });
        }
        g.finish();

        for (s_name, s) in &samplers {
            if let Some(st) = s.stats() {
                eprintln!(
                    "{map_name}/{s_name}: measured mean trials {:.4} over {} samples, {} bound violations",
                    st.measured_mean_trials.unwrap_or(f64::NAN),
                    st.samples,
                    st.bound_violations
                );
            }
        }
    }
}

criterion_group! {
    name = envmap_benches;
    config = Criterion::default().sample_size(20);
    targets = benches
}
criterion_main!(envmap_benches);
