//! Criterion benchmarks of quadtree sets: building a default 90-slice set (a few analytic
//! models and a synthetic MERL table), and drawing / evaluating directions.
//!
//! Run briefly: `cargo bench -p brdf-sampling --bench sets -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use brdf::{Brdf, MerlBrdf, parse_spec};
use brdf_sampling::{DirectionSampler, QuadTreeSet, SetOptions, Variant};
use criterion::{Criterion, criterion_group, criterion_main};
use partition_sampler::UniformSource;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// `phong:n=50` tabulated on the MERL grid (`MerlBrdf::tabulate`): the measured-data lookup.
fn synthetic_merl() -> Arc<dyn Brdf> {
    Arc::new(MerlBrdf::tabulate(
        &*parse_spec("phong:n=50").expect("spec"),
    ))
}

fn build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build_90_slices");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    let opts = SetOptions::default();
    let mut models: Vec<(String, Arc<dyn Brdf>)> =
        ["lambert", "phong", "ggx", "cook-torrance", "oren-nayar"]
            .iter()
            .map(|s| (s.to_string(), Arc::from(parse_spec(s).expect("spec"))))
            .collect();
    models.push(("merl(phong:n=50)".into(), synthetic_merl()));
    for (name, brdf) in models {
        g.bench_function(&name, |b| {
            b.iter(|| {
                black_box(
                    QuadTreeSet::build(Arc::clone(&brdf), Variant::Adaptive, &opts).expect("build"),
                )
            })
        });
    }
    g.finish();
}

fn sample(c: &mut Criterion) {
    let mut g = c.benchmark_group("sample_1000");
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let wos: Vec<_> = (0..1000)
        .map(|_| {
            brdf::direction_from_angles(rng.random::<f64>() * 89.0, rng.random::<f64>() * 360.0)
        })
        .collect();
    for spec in ["phong", "ggx:alpha=0.1"] {
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(spec).expect("spec"));
        for (label, variant, mixture) in [
            ("adaptive", Variant::Adaptive, false),
            ("adaptive-paper", Variant::Paper, false),
            ("adaptive-mixture", Variant::Adaptive, true),
        ] {
            let set = QuadTreeSet::build(Arc::clone(&brdf), variant, &SetOptions::default())
                .expect("build")
                .with_mixture(mixture);
            g.bench_function(format!("{spec}/{label}"), |b| {
                b.iter(|| {
                    let u: &mut dyn UniformSource = &mut rng;
                    let mut acc = 0.0;
                    for wo in &wos {
                        acc += set.sample(wo, u).pdf;
                    }
                    black_box(acc)
                })
            });
        }
        let set = QuadTreeSet::build(Arc::clone(&brdf), Variant::Adaptive, &SetOptions::default())
            .expect("build");
        let wis: Vec<_> = wos.iter().map(brdf::mirror).collect();
        g.bench_function(format!("{spec}/pdf"), |b| {
            b.iter(|| {
                wos.iter()
                    .zip(&wis)
                    .map(|(o, i)| set.pdf(o, i))
                    .sum::<f64>()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, build, sample);
criterion_main!(benches);
