//! Quick interleaved timing (thread CPU time) of hot-path variants (single thread): plain `sample` against
//! `sample_audited`, and a map with and without the `sin πv` row factor.
//!
//! Run: `cargo run --release -p partition-sampler --example perf_probe`

use std::time::Instant;

use partition_sampler::{
    Audit, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, Sampler2D, SinPiRows,
    TabulatedDensity,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

fn envmap(w: usize, h: usize) -> Vec<f64> {
    let (sx, sy) = (0.3 * w as f64, 0.3 * h as f64);
    (0..w * h)
        .map(|k| {
            let (i, j) = ((k % w) as f64, (k / w) as f64);
            let sky =
                0.5 + 0.5 * (j / h as f64) + 0.1 * ((i * 0.05).sin() * (j * 0.07).cos()).abs();
            let sun = if (i - sx).powi(2) + (j - sy).powi(2) < 4.0 {
                1e5
            } else {
                0.0
            };
            sky + sun
        })
        .collect()
}

/// CPU time of the calling thread in seconds (Linux `schedstat`), falling back to wall time
/// elsewhere; the machine running this may be shared, so CPU time is the fair measure.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| {
            s.split_whitespace()
                .next()
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map_or_else(|| START.with(|t| t.elapsed().as_secs_f64()), |ns| ns * 1e-9)
}

thread_local! {
    static START: Instant = Instant::now();
}

fn plain<D: RegionStats>(s: &QuadTreeSampler<D>, n: usize) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let t = cpu_s();
    let mut acc = 0.0;
    for _ in 0..n {
        acc += s.sample(&mut rng).pdf;
    }
    std::hint::black_box(acc);
    n as f64 / (cpu_s() - t) / 1e6
}

fn audited<D: RegionStats>(s: &QuadTreeSampler<D>, n: usize) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let mut a = Audit::default();
    let t = cpu_s();
    let mut acc = 0.0;
    for _ in 0..n {
        acc += s.sample_audited(&mut rng, &mut a).pdf;
    }
    std::hint::black_box(acc);
    n as f64 / (cpu_s() - t) / 1e6
}

fn main() {
    let (w, h) = (1024, 512);
    let vals = envmap(w, h);
    let t = cpu_s();
    let d = TabulatedDensity::new(w, h, vals.clone(), Rect::UNIT).expect("map");
    let t_new = (cpu_s() - t) * 1e3;
    let t = cpu_s();
    let ds = d.clone().with_row_factor(SinPiRows).expect("rows");
    let t_rows = (cpu_s() - t) * 1e3;
    let t = cpu_s();
    let s_sin = QuadTreeBuilder::new().build(ds).expect("build");
    let t_build = (cpu_s() - t) * 1e3;
    let s_unit = QuadTreeBuilder::new().build(d).expect("build");
    println!("new {t_new:.2} ms, with_row_factor {t_rows:.2} ms, tree build {t_build:.3} ms");
    let n = 5_000_000;
    for round in 0..3 {
        println!(
            "round {round}: sin plain {:.1} M/s, sin audited {:.1} M/s, unit plain {:.1} M/s, unit audited {:.1} M/s",
            plain(&s_sin, n),
            audited(&s_sin, n),
            plain(&s_unit, n),
            audited(&s_unit, n)
        );
    }
}
