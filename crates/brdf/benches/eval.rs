//! Evaluation throughput of a few models on a fixed set of direction pairs (the sampler's grid
//! builder calls `eval` millions of times).

use brdf::{Brdf, Vec3, direction_from_angles, parse_spec};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

fn pairs() -> Vec<(Vec3, Vec3)> {
    let wo = direction_from_angles(35.0, 10.0);
    let mut v = Vec::new();
    for i in 0..32 {
        for j in 0..32 {
            let wi = direction_from_angles(0.5 + 88.0 * i as f64 / 31.0, 360.0 * j as f64 / 32.0);
            v.push((wo, wi));
        }
    }
    v
}

fn bench_eval(c: &mut Criterion) {
    let pairs = pairs();
    let mut group = c.benchmark_group("eval");
    group.throughput(Throughput::Elements(pairs.len() as u64));
    for spec in [
        "lambert",
        "phong",
        "ward",
        "ggx",
        "beckmann",
        "cook-torrance",
        "oren-nayar",
        "ashikhmin-shirley",
        "poulin-fournier",
        "htsg",
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
