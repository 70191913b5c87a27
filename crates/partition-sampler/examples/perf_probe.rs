//! Quick interleaved timing (thread CPU time) of hot-path variants (single thread): plain `sample` against
//! `sample_audited`, and a map with and without the `sin πv` row factor.
//!
//! Run: `cargo run --release -p partition-sampler --example perf_probe`

use partition_sampler::diagnostics::AuditedDraws;
use partition_sampler::{
    Audit, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, SinPiRows, TabulatedDensity,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

#[path = "../benches/support/mod.rs"]
mod support;
use support::{cpu_s, envmap, rate};

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
            rate(&s_sin, n),
            audited(&s_sin, n),
            rate(&s_unit, n),
            audited(&s_unit, n)
        );
    }
}
