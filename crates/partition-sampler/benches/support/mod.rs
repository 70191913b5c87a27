//! Densities and timers shared by partition-sampler's benches and examples (included with
//! `mod support;` from `benches/` and `#[path = "../benches/support/mod.rs"] mod support;` from
//! `examples/`). Not every includer uses every item.
#![allow(dead_code)]

use std::time::Instant;

use partition_sampler::{QuadTreeSampler, RegionStats, Sampler2D};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Phong exponent of [`lobe`].
pub(crate) const LOBE_EXPONENT: f64 = 1000.0;

/// A peaked density on the unit disc: `max(0, r·v)^1000` with the mirror direction `r` at 30°.
pub(crate) fn lobe(p: [f64; 2]) -> f64 {
    let z2 = 1.0 - p[0] * p[0] - p[1] * p[1];
    if z2 < 0.0 {
        return 0.0;
    }
    let (s, c) = 30f64.to_radians().sin_cos();
    let d = s * p[0] + c * z2.sqrt();
    if d > 0.0 { d.powf(LOBE_EXPONENT) } else { 0.0 }
}

/// Synthetic `w × h` lat-long luminance map (row-major): smooth gradient, mild texture and a sun
/// of radius ~2 texels, 1e5 brighter.
pub(crate) fn envmap(w: usize, h: usize) -> Vec<f64> {
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
pub(crate) fn cpu_s() -> f64 {
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

/// Millions of plain `sample` calls per CPU-second of this thread, over `n` draws.
pub(crate) fn rate<D: RegionStats>(s: &QuadTreeSampler<D>, n: usize) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let t = cpu_s();
    let mut acc = 0.0;
    for _ in 0..n {
        acc += s.sample(&mut rng).pdf;
    }
    std::hint::black_box(acc);
    n as f64 / (cpu_s() - t) / 1e6
}
