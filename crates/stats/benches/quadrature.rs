//! Cost of the expected-count quadrature, the projection CDFs and the KS p-values.

use criterion::{Criterion, criterion_group, criterion_main};
use stats::{
    Axis, QuadratureOptions, SphereBinning, expected_masses, ks_twosample, projection_cdf,
};
use std::f64::consts::TAU;
use std::hint::black_box;

/// Phong lobe, exponent 20, axis at θ = 30°, φ = 40° (w.r.t. solid angle).
fn lobe(d: [f64; 3]) -> f64 {
    let (t, p) = (30f64.to_radians(), 40f64.to_radians());
    let a = [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
    let c = a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
    if c <= 0.0 {
        0.0
    } else {
        21.0 / TAU * c.powi(20)
    }
}

fn bench(c: &mut Criterion) {
    let bins = SphereBinning::sphere(20, 40).unwrap();
    for n in [1_000_000u64, 1_000_000_000] {
        c.bench_function(&format!("expected_masses lobe 20x40 N={n:e}"), |b| {
            b.iter(|| expected_masses(&lobe, &bins, black_box(n)))
        });
    }
    c.bench_function("projection_cdf lobe cos(theta) n=1e6", |b| {
        b.iter(|| {
            projection_cdf(
                &bins,
                &lobe,
                Axis::U,
                black_box(1_000_000),
                &QuadratureOptions::default(),
            )
        })
    });
    // Two samples of 10⁴ shifted by a fraction of their spread: exact lattice p-value.
    let a: Vec<f64> = (0..10_000)
        .map(|i| ((i as f64 + 0.5) / 1e4).sqrt())
        .collect();
    let bb: Vec<f64> = (0..10_000)
        .map(|i| ((i as f64 + 0.3) / 1e4).sqrt())
        .collect();
    c.bench_function("ks_twosample exact 1e4 x 1e4", |b| {
        b.iter(|| ks_twosample(black_box(&a), black_box(&bb)))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
