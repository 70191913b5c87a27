//! `adaptive`, `adaptive-mixture` and `adaptive-exact` side by side (issue 14): at random
//! outgoing directions (θo uniform in [0°, 89.5°], φo uniform), the L1 distance between each
//! pdf and the ideal `f·cos / A`, `|∫ pdf − 1|`, the cv² of the importance weight `f·cos / pdf`
//! (its luminance for coloured models), BRDF evaluations per sample, bound violations, and per
//! set the build time (wall and CPU), memory and the single-thread throughput ratio
//! exact / adaptive measured in the same run.
//!
//! `cargo run --release -p brdf-sampling --example exact_table -- [--angles 200] [--samples 4000]
//!   [--specs 'spec;spec'] [--skip name,name]`
//!
//! `A` is the reference albedo (`brdf_sampling::reference_albedo`, adaptive quadrature, error
//! ≪ 1e-6); the L1 integral uses the midpoint rule on a 128 × 256 grid in (cosθ, φ), so for
//! `adaptive-exact` it is the exact `|A/Â − 1|` times (1 + the grid's relative error on
//! `∫ f cos`); `|∫ pdf − 1|` is the grid's `∫ pdf` over its `∫ f cos / A`, minus 1 (the grid
//! error cancels). The last line gives `max |A/Â − 1|` over all angles directly.

use std::sync::Arc;
use std::time::Instant;

use brdf::{Brdf, MerlBrdf, Vec3, direction_from_angles, parse_spec};
use brdf_sampling::{
    DirectionSampler, ExactOptions, ExactSet, QuadTreeSet, SetOptions, Variant,
    disc::thread_evaluations, reference_albedo,
};
use partition_sampler::UniformSource;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

mod support;
use support::{arg, cpu_seconds, integrate, table_specs};

const N_COS: usize = 128;
const N_PHI: usize = 256;

/// Per-sampler figures over the random angles.
#[derive(Default, Clone, Copy)]
struct Figures {
    l1_mean: f64,
    l1_max: f64,
    norm_max: f64,
    cv2_mean: f64,
    evals: f64,
    violations: u64,
    msps: f64,
}

fn figures(
    s: &dyn DirectionSampler,
    brdf: &dyn Brdf,
    angles: &[(Vec3, f64)],
    samples: usize,
    l1_every: usize,
) -> Figures {
    let mut f = Figures::default();
    let v0 = s.bound_violations().unwrap_or(0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(99);
    let (mut evals, mut drawn, mut n_l1) = (0u64, 0usize, 0usize);
    let mut secs = 0.0;
    for (k, (wo, a)) in angles.iter().enumerate() {
        if k % l1_every == 0 {
            let l1 = integrate(
                &|wi| (s.pdf(wo, wi) - brdf.eval(wo, wi) * wi.z / a).abs(),
                N_COS,
                N_PHI,
            );
            // Relative to the same grid's integral of the ideal pdf: the grid's own error on
            // ∫ f cos cancels.
            let norm = (integrate(&|wi| s.pdf(wo, wi), N_COS, N_PHI)
                / integrate(&|wi| brdf.eval(wo, wi) * wi.z / a, N_COS, N_PHI)
                - 1.0)
                .abs();
            f.l1_mean += l1;
            f.l1_max = f.l1_max.max(l1);
            f.norm_max = f.norm_max.max(norm);
            n_l1 += 1;
        }
        let e0 = thread_evaluations();
        let t0 = Instant::now();
        let ws: Vec<f64> = (0..samples)
            .map(|_| {
                let d = s.sample(wo, &mut rng);
                if d.pdf > 0.0 {
                    let rgb = brdf.eval_rgb(wo, &d.wi);
                    brdf::luminance(rgb) * d.wi.z / d.pdf
                } else {
                    0.0
                }
            })
            .collect();
        secs += t0.elapsed().as_secs_f64();
        evals += thread_evaluations() - e0;
        drawn += samples;
        let m = ws.iter().sum::<f64>() / samples as f64;
        let var = ws.iter().map(|w| (w - m).powi(2)).sum::<f64>() / (samples - 1) as f64;
        f.cv2_mean += var / (m * m);
    }
    f.l1_mean /= n_l1.max(1) as f64;
    f.cv2_mean /= angles.len() as f64;
    // Evaluations in `sample` only: the luminance weights' evaluations are made outside the
    // disc counter.
    f.evals = evals as f64 / drawn as f64;
    f.violations = s.bound_violations().unwrap_or(0) - v0;
    f.msps = drawn as f64 / secs / 1e6;
    f
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n_angles: usize = arg(&args, "--angles").unwrap_or(200);
    let samples: usize = arg(&args, "--samples").unwrap_or(4000);
    let l1_every: usize = arg(&args, "--l1-every").unwrap_or(4);
    let skip: Vec<String> = arg::<String>(&args, "--skip")
        .map(|s| s.split(',').map(str::to_string).collect())
        .unwrap_or_default();
    let specs = table_specs(&args);
    println!(
        "{} random θo ∈ [0°, 89.5°] per model (L1 and ∫pdf at every {}th), {} samples per angle",
        n_angles, l1_every, samples
    );
    println!(
        "| model | sampler | L1 mean | L1 max | max abs(∫pdf−1) | cv² mean | evals/smp | viol. | build s | CPU s | KiB | trees | Msmp/s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut sums = [[0.0f64; 4]; 3];
    let mut ratio_sum = 0.0;
    let mut worst_exact_formula = 0.0f64;
    let mut n_models = 0;
    for spec in specs.iter().filter(|s| !skip.iter().any(|k| k == *s)) {
        let brdf: Arc<dyn Brdf> =
            if let Some(inner) = spec.strip_prefix("merl(").and_then(|s| s.strip_suffix(')')) {
                Arc::new(MerlBrdf::tabulate(&*parse_spec(inner)?))
            } else {
                Arc::from(parse_spec(spec)?)
            };
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(2026);
        let angles: Vec<(Vec3, f64)> = (0..n_angles)
            .map(|_| {
                let t = rng.next_uniform() * 89.5;
                let p = if brdf.is_isotropic() {
                    0.0
                } else {
                    rng.next_uniform() * 360.0
                };
                let wo = direction_from_angles(t, p);
                let a = reference_albedo(brdf.as_ref(), &wo).map_or(f64::NAN, |r| r.value);
                (wo, a)
            })
            .collect();
        let opts = SetOptions::default();
        let (c0, t0) = (cpu_seconds(), Instant::now());
        let set = QuadTreeSet::build(Arc::clone(&brdf), Variant::Adaptive, &opts)?;
        let (set_wall, set_cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        let (c0, t0) = (cpu_seconds(), Instant::now());
        let exact = ExactSet::build(Arc::clone(&brdf), &ExactOptions::with_set(opts), None)?;
        let (ex_wall, ex_cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        let adaptive = figures(&set, brdf.as_ref(), &angles, samples, l1_every);
        let set_kib = set.bytes_used() as f64 / 1024.0;
        let trees = set.len();
        let mixture_set = set.with_mixture(true);
        let mixture = figures(&mixture_set, brdf.as_ref(), &angles, samples, l1_every);
        let ex = figures(&exact, brdf.as_ref(), &angles, samples, l1_every);
        for (wo, a) in &angles {
            if let Some(ah) = exact.normaliser(wo) {
                worst_exact_formula = worst_exact_formula.max((a / ah - 1.0).abs());
            }
        }
        let rows = [
            ("adaptive", adaptive, set_wall, set_cpu, set_kib, trees),
            (
                "adaptive-mixture",
                mixture,
                set_wall,
                set_cpu,
                set_kib,
                trees,
            ),
            (
                "adaptive-exact",
                ex,
                ex_wall,
                ex_cpu,
                exact.bytes_used() as f64 / 1024.0,
                exact.len(),
            ),
        ];
        for (i, (name, f, wall, cpu, kib, trees)) in rows.iter().enumerate() {
            println!(
                "| {spec} | {name} | {:.2e} | {:.2e} | {:.1e} | {:.2e} | {:.3} | {} | {:.3} | {:.2} | {:.1} | {} | {:.2} |",
                f.l1_mean,
                f.l1_max,
                f.norm_max,
                f.cv2_mean,
                f.evals,
                f.violations,
                wall,
                cpu,
                kib,
                trees,
                f.msps
            );
            sums[i][0] += f.evals;
            sums[i][1] += kib;
            sums[i][2] += wall;
            sums[i][3] = sums[i][3].max(f.l1_max);
        }
        ratio_sum += adaptive.msps / ex.msps;
        n_models += 1;
        let r = exact.report();
        println!(
            "|  | exact layout | {} intervals, worst ΣV/A {:.2}, A err ≤ {:.1e} |  |  |  |  |  |  |  |  |  |  |",
            r.trees, r.worst_trials, r.max_normaliser_rel_err
        );
    }
    let n = n_models.max(1) as f64;
    for (i, name) in ["adaptive", "adaptive-mixture", "adaptive-exact"]
        .iter()
        .enumerate()
    {
        println!(
            "mean over {n_models} models, {name}: evals/sample {:.3}, memory {:.1} KiB, build {:.3} s; worst L1 {:.2e}",
            sums[i][0] / n,
            sums[i][1] / n,
            sums[i][2] / n,
            sums[i][3]
        );
    }
    println!(
        "throughput adaptive / exact (single thread, same run): mean {:.2}×; exact formula max |A/Â − 1| over all angles: {:.2e}",
        ratio_sum / n,
        worst_exact_formula
    );
    Ok(())
}
