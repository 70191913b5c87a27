//! `|∫ pdf − 1|` of `adaptive-exact` (and optionally `adaptive`) at many outgoing angles,
//! against an **independent** fine quadrature of `A(θo) = ∫ f_r(ωo, ·) cos θi dσ` (issue 27,
//! item 4).
//!
//! `cargo run --release -p brdf-sampling --example norm_gap -- --spec SPEC [--angles 180]
//!   [--n 1024] [--check-n 2048] [--ref-every 16] [--adaptive] [--at θ,θ,…] [--write-merl PATH]
//!   [--count]`
//!
//! `--count`: the build's evaluations are all counted (the BRDF wrapped in a `CountingBrdf`,
//! summed over the rayon threads), also those of split intervals and of a set-level table of
//! `A(θo)` (Cornell data), which the set's report leaves out.
//!
//! `--ref-every K`: the adaptive reference quadrature (`reference_albedo`, 4·10⁶ evaluations,
//! its own error estimate printed) at every K-th angle (0: never), a second reference where
//! the midpoint rule is too coarse (sharp lobes). The node rule's own value at each angle
//! (`ExactSet::node_rule_at`, no interpolation) splits the gap into the quadrature's part and
//! the interpolation's.
//!
//! RGL materials also get the albedo integrated over the interpolant's own cells
//! (`rgl_reference_albedo`, with its own error: the same rule at half the order), a reference
//! that resolves 10⁻⁵ up to 89.9° (docs/benchmarks.md §13.13). `--cells-orders 4,8,16 --at …`
//! prints that rule alone at several orders (no set built).
//!
//! `SPEC` is a model spec (`rgl:PATH`, `cornell:PATH`, `merl:PATH`, …) or `merl(SPEC)`: the
//! model `SPEC` tabulated in the MERL layout (nearest-bin lookup, `MerlBrdf::tabulate`).
//!
//! The angles are `θo_k = 89.5° · (k + 0.37)/n` (`k = 0 … n − 1`: none of them on a regular
//! node grid, most between the sampler's table nodes, the last ones grazing), plus 88°, 88.5°,
//! 89°, 89.5° and 89.9°. For an isotropic BRDF at `φo = 0`, `∫ pdf = A(θo) / Â(θo)` exactly (`pdf =
//! f cos / Â`), so `|∫ pdf − 1| = |A / Â − 1|`; `Â` is the set's
//! [`ExactSet::normaliser`]. `A` is the midpoint rule on `2n × 2n` equal-area
//! cells (concentric map, see `fine_albedo`): no Gauss rule, no tree, no table, so
//! none of the sampler's machinery. Its own error is checked at every 8th angle against the
//! same rule on `check-n × 2 check-n` cells (printed: the largest relative difference).

use std::sync::Arc;
use std::time::Instant;

use brdf::{Brdf, MerlBrdf, Vec3, direction_from_angles, parse_spec};
use brdf_sampling::{
    DirectionSampler, ExactOptions, ExactSet, QuadTreeSet, SamplerDiagnostics, SetOptions, Variant,
    reference_albedo, rgl_albedo_in_cells, rgl_reference_albedo,
};
mod support;
use support::{arg, cpu_seconds};

/// `∫ f(ωo, ωi) cos θi dσ(ωi)` by the midpoint rule on `2n × 2n` cells of the square
/// `[−1, 1]²`, mapped to the hemisphere by Shirley and Chiu's concentric map followed by the
/// equal-area (Lambert) lift `z = 1 − r²` (`dσ = 2 dA_disc = 2 · (π/4) du dv`): every cell
/// has the same solid angle, so the rule's resolution is uniform over the hemisphere (a grid
/// in `(cos θi, φi)` is 3.5° coarse in θ at the pole at n = 512, which made it 4e-4 off near
/// normal incidence on the sharp RGL materials).
fn fine_albedo(brdf: &dyn Brdf, wo: &Vec3, n: usize) -> f64 {
    brdf_sampling::equal_area_hemisphere_integral(&|wi| brdf.eval(wo, wi) * wi.z, n)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let spec: String = arg(&args, "--spec").ok_or("--spec SPEC is required")?;
    let n_angles: usize = arg(&args, "--angles").unwrap_or(180);
    let n: usize = arg(&args, "--n").unwrap_or(1024);
    let check_n: usize = arg(&args, "--check-n").unwrap_or(2048);
    let with_adaptive = args.iter().any(|a| a == "--adaptive");
    let ref_every: usize = arg(&args, "--ref-every").unwrap_or(16);
    // `--count`: every evaluation of the build counted (a `CountingBrdf` summed over the
    // rayon threads), also those of split intervals and of a set-level normaliser table,
    // which the report's count leaves out.
    let count_all = args.iter().any(|a| a == "--count");
    let brdf: Arc<dyn Brdf> =
        if let Some(inner) = spec.strip_prefix("merl(").and_then(|s| s.strip_suffix(')')) {
            Arc::new(MerlBrdf::tabulate(&*parse_spec(inner)?))
        } else {
            Arc::from(parse_spec(&spec)?)
        };
    if let Some(rgl) = brdf
        .as_any()
        .and_then(|a| a.downcast_ref::<brdf::RglBrdf>())
    {
        let deg: Vec<String> = rgl
            .theta_slices()
            .iter()
            .map(|t| format!("{:.2}", t.to_degrees()))
            .collect();
        println!("θo slices of the table (°): {}", deg.join(", "));
    }
    if let Some(path) = arg::<String>(&args, "--write-merl") {
        // The MERL layout of `merl(SPEC)` as a file (for `brdf-lab sample --brdf merl:PATH`).
        let inner = spec
            .strip_prefix("merl(")
            .and_then(|s| s.strip_suffix(')'))
            .ok_or("--write-merl needs --spec 'merl(SPEC)'")?;
        MerlBrdf::tabulate(&*parse_spec(inner)?).write(std::path::Path::new(&path))?;
        println!("wrote {path}");
        return Ok(());
    }
    if let Some(orders) = arg::<String>(&args, "--cells-orders") {
        // The cell rule alone (`rgl_albedo_in_cells`) at several orders, against the adaptive
        // reference quadrature: its convergence, no set built.
        let rgl = brdf
            .as_any()
            .and_then(|a| a.downcast_ref::<brdf::RglBrdf>())
            .ok_or("--cells-orders needs an RGL material")?;
        println!(
            "grids: {:?}; mirror-symmetric: {}",
            rgl.grids(),
            rgl.is_mirror_symmetric()
        );
        let orders: Vec<usize> = orders.split(',').filter_map(|v| v.parse().ok()).collect();
        let list = arg::<String>(&args, "--at").ok_or("--cells-orders needs --at")?;
        for t in list.split(',').filter_map(|v| v.parse::<f64>().ok()) {
            let mut line = format!("| {t:.3} |");
            for &o in &orders {
                let c0 = cpu_seconds();
                let c = rgl_albedo_in_cells(rgl, t.to_radians(), o)?;
                line += &format!(
                    " {:.10} (±{:.1e}, {} ev, {:.2} CPU-s) |",
                    c.value,
                    c.abs_err / c.value,
                    c.evaluations,
                    cpu_seconds() - c0
                );
            }
            if ref_every > 0 {
                let r = reference_albedo(brdf.as_ref(), &direction_from_angles(t, 0.0))?;
                line += &format!(
                    " adaptive ref {:.10} (±{:.1e}) |",
                    r.value,
                    r.abs_err / r.value
                );
            }
            println!("{line}");
        }
        return Ok(());
    }
    let opts = ExactOptions::with_set(SetOptions::default());
    let all_threads = || {
        rayon::broadcast(|_| brdf::thread_evaluations())
            .iter()
            .sum::<u64>()
            + if rayon::current_thread_index().is_none() {
                brdf::thread_evaluations()
            } else {
                0
            }
    };
    let built_on: Arc<dyn Brdf> = if count_all {
        Arc::new(brdf::CountingBrdf(Arc::clone(&brdf)))
    } else {
        Arc::clone(&brdf)
    };
    let (c0, t0, e0) = (cpu_seconds(), Instant::now(), all_threads());
    let exact = ExactSet::build(built_on, &opts, None)?;
    let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    if count_all {
        println!("evaluations of the whole build: {}", all_threads() - e0);
    }
    let rep = exact.report();
    let edges: Vec<String> = rep.layout[0]
        .theta_edges_deg
        .iter()
        .map(|t| format!("{t:.2}"))
        .collect();
    println!("interval edges (°): {}", edges.join(", "));
    println!(
        "{spec}: adaptive-exact {} intervals, build {wall:.2} s wall / {cpu:.2} CPU-s, {} evaluations, declared A error ≤ {:.2e}",
        rep.trees, rep.build_evaluations, rep.max_normaliser_rel_err
    );
    let adaptive = if with_adaptive {
        Some(QuadTreeSet::build(
            Arc::clone(&brdf),
            Variant::Adaptive,
            &SetOptions::default(),
        )?)
    } else {
        None
    };
    let mut angles: Vec<f64> = (0..n_angles)
        .map(|k| 89.5 * (k as f64 + 0.37) / n_angles as f64)
        .collect();
    angles.extend([88.0, 88.5, 89.0, 89.5, 89.9]);
    if let Some(list) = arg::<String>(&args, "--at") {
        angles = list.split(',').filter_map(|v| v.parse().ok()).collect();
    }
    let merl = brdf.as_any().and_then(|a| a.downcast_ref::<MerlBrdf>());
    println!(
        "| θo ° | A (fine) | Â | A/Â − 1 | declared | node rule at θo: A/N − 1 (its estimate) | interpolation N/Â − 1 | ref. quad. A/Â − 1 | in bins A/Â − 1 | RGL cells A_c/Â − 1 (own error) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let rgl = brdf
        .as_any()
        .and_then(|a| a.downcast_ref::<brdf::RglBrdf>());
    let (mut worst_cells, mut worst_cells_at, mut worst_cells_err) = (0.0f64, 0.0, 0.0f64);
    let mut worst_ref_vs_cells = 0.0f64;
    let (mut worst, mut worst_at, mut worst_check, mut under) = (0.0f64, 0.0, 0.0f64, 0usize);
    let mut worst_adaptive = 0.0f64;
    let (mut worst_ref, mut worst_ref_vs_fine) = (0.0f64, 0.0f64);
    for (k, &t) in angles.iter().enumerate() {
        let wo = direction_from_angles(t, 0.0);
        let a = fine_albedo(brdf.as_ref(), &wo, n);
        if k % 8 == 0 && check_n > 0 {
            let b = fine_albedo(brdf.as_ref(), &wo, check_n);
            worst_check = worst_check.max((a / b - 1.0).abs());
        }
        let a_hat = exact.normaliser(&wo).ok_or("no normaliser")?;
        let gap = a / a_hat - 1.0;
        let declared = exact.normaliser_rel_err(&wo).unwrap_or(f64::NAN);
        if gap.abs() > declared {
            under += 1;
        }
        if gap.abs() > worst {
            (worst, worst_at) = (gap.abs(), t);
        }
        if let Some(set) = &adaptive {
            // ∫ pdf of the nearest slice = A(θo) over the slice's own normaliser is not
            // available directly: integrate the pdf with the same fine rule.
            let m = fine_pdf(set, &wo, n);
            worst_adaptive = worst_adaptive.max((m - 1.0).abs());
            println!(
                "adaptive at {t:.3}°: ∫pdf − 1 = {:+.2e}, declared at θo {:.1e}, declared max over slices {:.1e}",
                m - 1.0,
                set.normaliser_rel_err(&wo).unwrap_or(f64::NAN),
                set.report().max_integral_rel_err.unwrap_or(f64::NAN)
            );
        }
        let (r, r_err) = if ref_every > 0 && k % ref_every == 0 {
            reference_albedo(brdf.as_ref(), &wo).map_or((f64::NAN, f64::NAN), |r| {
                (r.value / a_hat - 1.0, r.abs_err / r.value)
            })
        } else {
            (f64::NAN, f64::NAN)
        };
        if r.is_finite() {
            worst_ref = worst_ref.max(r.abs());
            worst_ref_vs_fine = worst_ref_vs_fine.max(((r + 1.0) / (gap + 1.0) - 1.0).abs());
        }
        // MERL layout: also the table integrated over its own bins to 1e-6 (a second
        // reference, `MerlBrdf::albedo_in_bins`; the set's nodes use it at 1e-5).
        let bins = merl.map_or(String::new(), |m| {
            let b = m.albedo_in_bins(t.to_radians(), 1e-6, 5_000_000);
            format!(
                " {:+.2e} (±{:.0e}) |",
                b.value / a_hat - 1.0,
                b.abs_err / b.value
            )
        });
        // The gap split into the node rule's own error (the rule run at θo itself, no
        // interpolation) and the interpolation's (`ExactSet::node_rule_at`).
        let (node, node_err) = exact.node_rule_at(&wo).unwrap_or((f64::NAN, f64::NAN));
        // RGL: the albedo integrated over the interpolant's own cells (`rgl_reference_albedo`,
        // its own error: the same rule at half the order).
        let cells = rgl.map_or(String::new(), |rgl| {
            match rgl_reference_albedo(rgl, t.to_radians()) {
                Ok(c) => {
                    let g = c.value / a_hat - 1.0;
                    if g.abs() > worst_cells {
                        (worst_cells, worst_cells_at) = (g.abs(), t);
                    }
                    worst_cells_err = worst_cells_err.max(c.abs_err / c.value);
                    if r.is_finite() {
                        worst_ref_vs_cells =
                            worst_ref_vs_cells.max(((r + 1.0) / (g + 1.0) - 1.0).abs());
                    }
                    format!(" {g:+.2e} (±{:.0e}) |", c.abs_err / c.value)
                }
                Err(e) => format!(" {e} |"),
            }
        });
        println!(
            "| {t:.3} | {a:.8} | {a_hat:.8} | {gap:+.2e} | {declared:.1e} | {:+.2e} ({node_err:.1e}) | {:+.2e} | {r:+.2e} (±{r_err:.0e}) |{bins}{cells}",
            a / node - 1.0,
            node / a_hat - 1.0
        );
    }
    println!(
        "{spec}: max |A/Â − 1| = {worst:.2e} at θo = {worst_at:.3}° over {} angles; declared error below the gap at {under} of them; fine rule n = {n} vs {check_n}: max rel. difference {worst_check:.1e}",
        angles.len()
    );
    if worst_ref > 0.0 {
        println!(
            "{spec}: reference quadrature: max |A_ref/Â − 1| = {worst_ref:.2e}; max |A_ref/A_fine − 1| = {worst_ref_vs_fine:.1e}"
        );
    }
    if rgl.is_some() {
        println!(
            "{spec}: RGL cell rule: max |A_cells/Â − 1| = {worst_cells:.2e} at θo = {worst_cells_at:.3}°; its own error ≤ {worst_cells_err:.1e}; max |A_ref/A_cells − 1| = {worst_ref_vs_cells:.1e}"
        );
    }
    if adaptive.is_some() {
        println!("{spec}: adaptive (nearest slice) max |∫pdf − 1| = {worst_adaptive:.2e}");
    }
    Ok(())
}

/// `∫ pdf(ωo, ·) dσ` by the midpoint rule on `n × 2n` cells of `(cos θi, φi)`.
fn fine_pdf(s: &dyn DirectionSampler, wo: &Vec3, n: usize) -> f64 {
    brdf_sampling::upper_hemisphere_integral(&|wi| s.pdf(wo, wi), n, 2 * n)
}
