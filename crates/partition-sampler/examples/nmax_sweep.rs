//! Prints build time, memory, mean trials and sampling rate against `n_max` and `max_depth`
//! for a peaked Phong lobe on the disc (exponent 1000, sampled grid) and a synthetic
//! 1024 × 512 environment map with a small sun (tabulated, `sin πv` rows).
//!
//! Run: `cargo run --release -p partition-sampler --example nmax_sweep`. Sampling rates are
//! per CPU-second of one thread; build times are wall-clock.

use std::time::Instant;

use partition_sampler::{
    Domain, LeafChoice, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, SampledGridDensity,
    Sampler2D, Scheme, SharedDensity, SinPiRows, TabulatedDensity,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// `max(0, r·v)^e` on the disc, mirror direction at 30°.
fn lobe(p: [f64; 2]) -> f64 {
    let z2 = 1.0 - p[0] * p[0] - p[1] * p[1];
    if z2 < 0.0 {
        return 0.0;
    }
    let (s, c) = 30f64.to_radians().sin_cos();
    let d = s * p[0] + c * z2.sqrt();
    if d > 0.0 { d.powf(1000.0) } else { 0.0 }
}

/// Synthetic sky: smooth gradient, mild texture and a sun of radius ~2 texels, 1e5 brighter.
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

/// CPU time of the calling thread in seconds (Linux `schedstat`; wall time elsewhere): the
/// machine may be shared, so rates are per CPU-second.
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

fn rate<D: RegionStats>(s: &QuadTreeSampler<D>, n: usize) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let t = cpu_s();
    let mut acc = 0.0;
    for _ in 0..n {
        acc += s.sample(&mut rng).pdf;
    }
    std::hint::black_box(acc);
    n as f64 / (cpu_s() - t) / 1e6
}

fn row<D: RegionStats>(label: &str, s: &QuadTreeSampler<D>, build_ms: f64) {
    let m = rate(s, 2_000_000);
    let st = s.stats();
    println!(
        "{label:<28} {:>7} {:>7} {:>3} {:>8.3} {:>8.3} {:>9.1} {:>8.2} {:>7.1} {:>5}",
        st.nodes,
        st.active_leaves,
        st.depth,
        st.expected_mean_trials,
        st.measured_mean_trials.unwrap_or(f64::NAN),
        s.tree().bytes_used() as f64 / 1024.0,
        build_ms,
        m,
        st.bound_violations
    );
}

fn header(title: &str) {
    println!("\n{title}");
    println!(
        "{:<28} {:>7} {:>7} {:>3} {:>8} {:>8} {:>9} {:>8} {:>7} {:>5}",
        "config",
        "nodes",
        "leaves",
        "d",
        "E[trial]",
        "trials",
        "tree KiB",
        "build ms",
        "M/s",
        "viol"
    );
}

fn main() {
    let t = Instant::now();
    let lobe_grid =
        SharedDensity::new(SampledGridDensity::new(lobe, Domain::UnitDisc, 1024).expect("grid"));
    let grid_ms = t.elapsed().as_secs_f64() * 1e3;
    let (w, h) = (1024, 512);
    let t = Instant::now();
    let map = SharedDensity::new(
        TabulatedDensity::new(w, h, envmap(w, h), Rect::UNIT)
            .expect("map")
            .with_row_factor(SinPiRows)
            .expect("rows"),
    );
    let map_ms = t.elapsed().as_secs_f64() * 1e3;
    println!(
        "lobe grid 1024² build {grid_ms:.1} ms, {:.1} MiB, rel. err. of integral {:.2e}; map 1024×512 pyramids {map_ms:.2} ms, {:.1} MiB",
        lobe_grid.bytes_used() as f64 / 1048576.0,
        lobe_grid.0.estimated_rel_err(),
        map.bytes_used() as f64 / 1048576.0
    );

    for (name, scheme) in [("envelope", Scheme::Envelope), ("paper", Scheme::Paper)] {
        header(&format!(
            "n_max sweep, Phong lobe e=1000 on the disc, max_depth 12, {name} scheme"
        ));
        for n_max in [1.3, 1.6, 2.0, 2.3, 2.6] {
            let t = Instant::now();
            let s = QuadTreeBuilder::new()
                .n_max(n_max)
                .scheme(scheme)
                .build(lobe_grid.clone())
                .expect("build");
            let ms = t.elapsed().as_secs_f64() * 1e3;
            row(&format!("n_max {n_max}"), &s, ms);
        }
        header(&format!(
            "n_max sweep, 1024x512 map with sun, max_depth 12, {name} scheme"
        ));
        for n_max in [1.3, 1.6, 2.0, 2.3, 2.6] {
            let t = Instant::now();
            let s = QuadTreeBuilder::new()
                .n_max(n_max)
                .scheme(scheme)
                .build(map.clone())
                .expect("build");
            let ms = t.elapsed().as_secs_f64() * 1e3;
            row(&format!("n_max {n_max}"), &s, ms);
        }
    }
    header("max_depth sweep, n_max 2, envelope + alias (lobe)");
    for d in [5, 6, 7, 8, 9, 10, 11, 12, 14, 16] {
        let t = Instant::now();
        let s = QuadTreeBuilder::new()
            .max_depth(d)
            .build(lobe_grid.clone())
            .expect("build");
        row(
            &format!("lobe depth {d}"),
            &s,
            t.elapsed().as_secs_f64() * 1e3,
        );
    }
    header("max_depth sweep, n_max 2, envelope + alias (map)");
    for d in [5, 6, 7, 8, 9, 10, 11, 12, 14, 16] {
        let t = Instant::now();
        let s = QuadTreeBuilder::new()
            .max_depth(d)
            .build(map.clone())
            .expect("build");
        row(
            &format!("map depth {d}"),
            &s,
            t.elapsed().as_secs_f64() * 1e3,
        );
    }
    header("volume tolerance sweep, n_max 2, default depth (lobe / map)");
    for tol in [0.0, 1e-8, 1e-6, 1e-4] {
        let t = Instant::now();
        let s = QuadTreeBuilder::new()
            .volume_tolerance(tol)
            .build(lobe_grid.clone())
            .expect("build");
        row(
            &format!("lobe tol {tol:e}"),
            &s,
            t.elapsed().as_secs_f64() * 1e3,
        );
        let t = Instant::now();
        let s = QuadTreeBuilder::new()
            .volume_tolerance(tol)
            .build(map.clone())
            .expect("build");
        row(
            &format!("map tol {tol:e}"),
            &s,
            t.elapsed().as_secs_f64() * 1e3,
        );
    }
    header("leaf choice, n_max 2, default depth");
    for (name, choice) in [
        ("alias", LeafChoice::Alias),
        ("descent", LeafChoice::Descent),
    ] {
        let s = QuadTreeBuilder::new()
            .leaf_choice(choice)
            .build(lobe_grid.clone())
            .expect("build");
        row(&format!("lobe {name}"), &s, 0.0);
        let s = QuadTreeBuilder::new()
            .leaf_choice(choice)
            .build(map.clone())
            .expect("build");
        row(&format!("map {name}"), &s, 0.0);
    }
}
