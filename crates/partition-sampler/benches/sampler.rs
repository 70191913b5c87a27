//! Criterion benches: build time and sampling throughput of the adaptive-partition sampler on
//! (a) a synthetic 1024 × 512 latitude–longitude map with a small sun (tabulated, `sin πv`
//! rows) and (b) a Phong lobe of exponent 1000 on the disc (sampled grid, 1024²).
//! Mean trials and memory against `n_max` are printed by `examples/nmax_sweep.rs`.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use partition_sampler::diagnostics::AuditedDraws;
use partition_sampler::{
    Domain, LeafChoice, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, SampledGridDensity,
    Sampler2D, Scheme, SharedDensity, SinPiRows, TabulatedDensity,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

mod support;
use support::{envmap, lobe};

const N: usize = 100_000;

fn bench_sampling<D: RegionStats>(
    c: &mut Criterion,
    group: &str,
    name: &str,
    s: &QuadTreeSampler<D>,
) {
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function(format!("{name}/sample"), |b| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        b.iter(|| {
            let mut acc = 0.0;
            for _ in 0..N {
                acc += s.sample(&mut rng).pdf;
            }
            black_box(acc)
        })
    });
    g.finish();
}

fn bench_extra<D: RegionStats>(c: &mut Criterion, group: &str, s: &QuadTreeSampler<D>) {
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("envelope_alias/sample_audited", |b| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut audit = partition_sampler::Audit::default();
        b.iter(|| {
            let mut acc = 0.0;
            for _ in 0..N {
                acc += s.sample_audited(&mut rng, &mut audit).pdf;
            }
            black_box(acc)
        })
    });
    g.bench_function("envelope_alias/sample_batch", |b| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        b.iter(|| {
            black_box(
                s.sample_batch(
                    N,
                    partition_sampler::AllocationMode::RandomizedRemainder,
                    &mut rng,
                )
                .samples
                .len(),
            )
        })
    });
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        g.bench_function(format!("envelope_alias/sample_par_{threads}t"), |b| {
            let mut seed = 0u64;
            b.iter(|| {
                seed += 1;
                pool.install(|| black_box(s.sample_par(N, seed).len()))
            })
        });
    }
    g.finish();
}

fn all_configs<D: RegionStats + Clone>(c: &mut Criterion, group: &str, d: &D) {
    for (name, scheme, choice) in [
        ("envelope_alias", Scheme::Envelope, LeafChoice::Alias),
        ("envelope_descent", Scheme::Envelope, LeafChoice::Descent),
        ("paper_alias", Scheme::Paper, LeafChoice::Alias),
        ("paper_descent", Scheme::Paper, LeafChoice::Descent),
    ] {
        let s = QuadTreeBuilder::new()
            .scheme(scheme)
            .leaf_choice(choice)
            .build(d.clone())
            .expect("build");
        bench_sampling(c, group, name, &s);
    }
    let s = QuadTreeBuilder::new().build(d.clone()).expect("build");
    bench_extra(c, group, &s);
}

fn envmap_benches(c: &mut Criterion) {
    let (w, h) = (1024, 512);
    let vals = envmap(w, h);
    let mut g = c.benchmark_group("envmap_1024x512");
    // Everything from the luminance values to a ready sampler (validation, row sums, lazy
    // pyramids, tree, alias table).
    g.bench_function("cold_build", |b| {
        b.iter_batched(
            || vals.clone(),
            |v| {
                let d = TabulatedDensity::new(w, h, v, Rect::UNIT)
                    .and_then(|d| d.with_row_factor(SinPiRows))
                    .expect("map");
                QuadTreeBuilder::new().build(d).expect("build")
            },
            BatchSize::LargeInput,
        )
    });
    let d = SharedDensity::new(
        TabulatedDensity::new(w, h, vals, Rect::UNIT)
            .and_then(|d| d.with_row_factor(SinPiRows))
            .expect("map"),
    );
    g.bench_function("tree_build", |b| {
        b.iter(|| QuadTreeBuilder::new().build_tree(&d).expect("tree"))
    });
    g.bench_function("tree_build_tol0", |b| {
        b.iter(|| {
            QuadTreeBuilder::new()
                .volume_tolerance(0.0)
                .build_tree(&d)
                .expect("tree")
        })
    });
    g.finish();
    all_configs(c, "envmap_1024x512", &d);
}

fn lobe_benches(c: &mut Criterion) {
    let mut g = c.benchmark_group("lobe_e1000_disc");
    g.sample_size(10);
    g.bench_function("grid_build_1024", |b| {
        b.iter(|| SampledGridDensity::new(lobe, Domain::UnitDisc, 1024).expect("grid"))
    });
    let d =
        SharedDensity::new(SampledGridDensity::new(lobe, Domain::UnitDisc, 1024).expect("grid"));
    g.bench_function("tree_build", |b| {
        b.iter(|| QuadTreeBuilder::new().build_tree(&d).expect("tree"))
    });
    g.finish();
    all_configs(c, "lobe_e1000_disc", &d);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = envmap_benches, lobe_benches
}
criterion_main!(benches);
