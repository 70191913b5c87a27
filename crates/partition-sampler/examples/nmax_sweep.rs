//! Prints build time, memory, mean trials and sampling rate against `n_max` and `max_depth`
//! for a peaked Phong lobe on the disc (exponent 1000, sampled grid) and a synthetic
//! 1024 × 512 environment map with a small sun (tabulated, `sin πv` rows).
//!
//! Run: `cargo run --release -p partition-sampler --example nmax_sweep`. Sampling rates are
//! per CPU-second of one thread; build times are wall-clock.

use std::time::Instant;

use partition_sampler::{
    Domain, LeafChoice, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, SampledGridDensity,
    Scheme, SharedDensity, SinPiRows, TabulatedDensity,
};

#[path = "../benches/support/mod.rs"]
mod support;
use support::{envmap, lobe, rate};

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

/// The `n_max` values of the sweeps.
const N_MAX: [f64; 5] = [1.3, 1.6, 2.0, 2.3, 2.6];
/// The depths of the `max_depth` sweeps.
const DEPTHS: [u32; 10] = [5, 6, 7, 8, 9, 10, 11, 12, 14, 16];

/// Builds `density` with `builder` and prints its [`row`] with the build's wall time.
fn timed_row<D: RegionStats>(label: &str, builder: QuadTreeBuilder, density: D) {
    let t = Instant::now();
    let s = builder.build(density).expect("build");
    row(label, &s, t.elapsed().as_secs_f64() * 1e3);
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
        for n_max in N_MAX {
            let b = QuadTreeBuilder::new().n_max(n_max).scheme(scheme);
            timed_row(&format!("n_max {n_max}"), b, lobe_grid.clone());
        }
        header(&format!(
            "n_max sweep, 1024x512 map with sun, max_depth 12, {name} scheme"
        ));
        for n_max in N_MAX {
            let b = QuadTreeBuilder::new().n_max(n_max).scheme(scheme);
            timed_row(&format!("n_max {n_max}"), b, map.clone());
        }
    }
    header("max_depth sweep, n_max 2, envelope + alias (lobe)");
    for d in DEPTHS {
        let b = QuadTreeBuilder::new().max_depth(d);
        timed_row(&format!("lobe depth {d}"), b, lobe_grid.clone());
    }
    header("max_depth sweep, n_max 2, envelope + alias (map)");
    for d in DEPTHS {
        let b = QuadTreeBuilder::new().max_depth(d);
        timed_row(&format!("map depth {d}"), b, map.clone());
    }
    header("volume tolerance sweep, n_max 2, default depth (lobe / map)");
    for tol in [0.0, 1e-8, 1e-6, 1e-4] {
        let b = QuadTreeBuilder::new().volume_tolerance(tol);
        timed_row(&format!("lobe tol {tol:e}"), b, lobe_grid.clone());
        timed_row(&format!("map tol {tol:e}"), b, map.clone());
    }
    header("leaf choice, n_max 2, default depth");
    for (name, choice) in [
        ("alias", LeafChoice::Alias),
        ("descent", LeafChoice::Descent),
    ] {
        let b = QuadTreeBuilder::new().leaf_choice(choice);
        let s = b.build(lobe_grid.clone()).expect("build");
        row(&format!("lobe {name}"), &s, 0.0);
        let s = b.build(map.clone()).expect("build");
        row(&format!("map {name}"), &s, 0.0);
    }
}
