//! Evaluation throughput of analytic models (the sampler's quadtree builder calls `eval` millions
//! of times per model).
//!
//! Fixed set of 4096 direction pairs (seed 2024): `ωo` with `θo` uniform in `[0°, 89°]` and `φo`
//! uniform, `ωi` cosine-distributed on the upper hemisphere. Criterion's throughput is in
//! evaluations, so its "time" divided by 4096 is the cost of one `eval`.
//!
//! Run: `cargo bench -p brdf --bench eval -- --warm-up-time 1 --measurement-time 3`
//! (append a model name, e.g. `htsg`, to run only that one).

use brdf::{Brdf, Vec3, direction_from_radians, parse_spec};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use std::f64::consts::PI;
use std::hint::black_box;

/// Number of direction pairs per iteration.
const PAIRS: usize = 4096;

fn pairs() -> Vec<(Vec3, Vec3)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2024);
    (0..PAIRS)
        .map(|_| {
            let theta_o = rng.random_range(0.0..89.0f64).to_radians();
            let phi_o = rng.random_range(0.0..2.0 * PI);
            // Cosine-weighted: sinθi = √u, φi uniform.
            let u: f64 = rng.random();
            let theta_i = u.sqrt().asin();
            let phi_i = rng.random_range(0.0..2.0 * PI);
            (
                direction_from_radians(theta_o, phi_o),
                direction_from_radians(theta_i, phi_i),
            )
        })
        .collect()
}

fn bench_eval(c: &mut Criterion) {
    let pairs = pairs();
    let mut group = c.benchmark_group("eval");
    group.throughput(Throughput::Elements(pairs.len() as u64));
    for spec in [
        "htsg",
        "htsg:sigma=5,tau=30",
        "poulin-fournier",
        "ggx",
        "phong",
        "lambert",
        "ward",
        "beckmann",
        "cook-torrance",
        "oren-nayar",
        "ashikhmin-shirley",
    ] {
        let Ok(model) = parse_spec(spec) else {
            continue;
        };
        group.bench_function(spec, |b| {
            b.iter(|| {
                let mut s = 0.0;
                for (wo, wi) in &pairs {
                    s += model.eval(black_box(wo), black_box(wi));
                }
                s
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_eval);
criterion_main!(benches);
