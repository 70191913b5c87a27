//! Unbiasedness of every reflected-radiance estimator under adversarial maps (issue 27).
//!
//! Each case is a small lat-long map built in memory, a shading frame and GGX (`α = 0.15`, whose
//! polynomial tail the SRBF fits' vMF lobes do not follow) at `θo = 40°`. Every estimator —
//! SRBF product, BRDF sampling (`srbf`, `cosine`), light sampling (`envmap-adaptive`,
//! `envmap-cdf`) and MIS (balance and power, `srbf` with each map sampler) — is compared with a
//! deterministic per-pixel quadrature ([`quadrature_reference`]) at two sample counts.
//!
//! **Criterion.** `|F − Q| < 4·σ̂ + e_Q` with `σ̂` the estimator's standard error and `e_Q` the
//! quadrature's error estimate: per check a two-sided normal level of 6.3·10⁻⁵, so over the
//! 9 estimators × 2 counts × 7 cases = 126 checks a family-wise false-alarm rate below 0.8 %
//! (Šidák: `1 − (1 − 6.3·10⁻⁵)¹²⁶`). Seeds are fixed, so the outcome is reproducible.
//! Heavy-tail flags ([`Estimate::heavy_tailed`]) are printed beside each line (see [`verdict`]).
//!
//! **Shown to fail on broken estimators.** At this CI size the pre-fix mixture (product and
//! BRDF lobes only) reaches the GGX tail through vMF tails, so it is heavy-tailed rather than
//! cleanly biased: the unit test `issue_27_bias_is_gone_and_its_mutant_is_detected` rejects it
//! through the heavy-tail flag at 8 of 8 seeds; at the size (default fits, 256 × 128,
//! 10⁶ samples) it is cleanly biased (−8 %, docs/validation.md, "Product estimators:
//! unbiasedness under adversarial maps").
//! [`the_check_rejects_samplers_that_miss_part_of_the_support`] shows the same for a BRDF
//! sampler and a map sampler that never draw part of the integrand's support (while MIS of
//! either with an intact technique passes); the unit test
//! `issue_27_bias_is_gone_and_its_mutant_is_detected` runs the pre-fix mixture in CI.
//!
//! The 10⁶-sample check of the issue's own 256 × 128 cases is `full_adversarial_cases`
//! (ignored; `cargo test -p estimators --release --test it product_adversarial -- --ignored`).

use baselines::srbf::{EnvSrbf, fit_envmap};
use baselines::{CosineHemisphere, SrbfOptions, SrbfSampler};
use brdf::{Brdf, Vec3};
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use envmap::latlong::uv_to_direction;
use envmap::{AdaptiveOptions, EnvMap, EnvMapSampler};
use estimators::{
    Estimate, LocalFrame, MisHeuristic, ProductScene, estimate_brdf, estimate_light, estimate_mis,
    estimate_srbf_product, quadrature_reference,
};
use partition_sampler::UniformSource;

use crate::scenes::{column, map, scene};

/// The shading normal.
const NORMAL: [f64; 3] = [0.3, 0.2, 0.93];

/// One adversarial case.
struct Case {
    name: &'static str,
    map: EnvMap,
    normal: [f64; 3],
}

/// The adversarial maps at `w × w/2`.
fn cases(w: usize) -> Vec<Case> {
    let h = w / 2;
    let frame = LocalFrame::new(NORMAL, 0.0).unwrap();
    // Local z of a pixel's centre.
    let local_z = move |x: usize, y: usize| {
        let d = uv_to_direction((x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64);
        frame.to_local(&Vec3::new(d[0], d[1], d[2])).z
    };
    let xs = |u: f64| ((u * w as f64).round() as usize) % w;
    vec![
        Case {
            name: "column straddling the seam (u = 0)",
            map: column(w, h, 0, 0.0, 1.0),
            normal: NORMAL,
        },
        Case {
            name: "column at u = 0.09",
            map: column(w, h, xs(0.09), 0.0, 1.0),
            normal: NORMAL,
        },
        Case {
            name: "column below the map's horizon, above the surface's (v in [0.5, 0.62])",
            map: column(w, h, 0, 0.5, 0.62),
            normal: NORMAL,
        },
        Case {
            name: "bright poles (first and last rows), normal tilted down",
            map: map(w, h, |_, y| (y == 0 || y == h - 1).then_some(300.0)),
            normal: [0.8, 0.2, -0.3],
        },
        Case {
            name: "bright poles (first and last rows), normal tilted up",
            map: map(w, h, |_, y| (y == 0 || y == h - 1).then_some(300.0)),
            normal: [0.8, 0.2, 0.3],
        },
        Case {
            name: "single hot pixel near the surface's horizon at the seam",
            map: map(w, h, |x, y| {
                (x == 0 && y == (0.55 * h as f64) as usize).then_some(3e4)
            }),
            normal: NORMAL,
        },
        Case {
            name: "zero in the shading frame's lower hemisphere",
            map: map(w, h, |x, y| {
                if local_z(x, y) <= 0.0 {
                    Some(0.0)
                } else {
                    let dx = (x + w - xs(0.09)) % w;
                    (dx <= 1 || dx == w - 1).then_some(300.0)
                }
            }),
            normal: NORMAL,
        },
    ]
}

/// The fits and samplers of one case.
struct Setup<'a> {
    scene: ProductScene<'a>,
    brdf_fit: &'a SrbfSampler,
    map_fit: EnvSrbf,
    adaptive: EnvMapSampler,
    cdf: EnvMapSampler,
    options: &'a SrbfOptions,
}

impl<'a> Setup<'a> {
    fn new(
        case: &'a Case,
        brdf: &'a dyn Brdf,
        brdf_fit: &'a SrbfSampler,
        options: &'a SrbfOptions,
    ) -> Self {
        Self {
            scene: scene(brdf, &case.map, case.normal, 0.0, [40.0, 0.0]),
            brdf_fit,
            map_fit: fit_envmap(&case.map, options).unwrap(),
            adaptive: EnvMapSampler::adaptive(&case.map, AdaptiveOptions::default()).unwrap(),
            cdf: EnvMapSampler::piecewise_constant(&case.map).unwrap(),
            options,
        }
    }

    /// Every estimator with `n` samples (seeds derived from `seed`).
    fn estimates(&self, brdf_sampler: &dyn DirectionSampler, n: usize, seed: u64) -> Vec<Estimate> {
        let s = &self.scene;
        let mut out = vec![
            estimate_srbf_product(
                s,
                self.brdf_fit,
                &self.map_fit,
                &self.adaptive,
                &self.options.product_settings(),
                n,
                seed,
            )
            .unwrap()
            .0,
            estimate_brdf(s, brdf_sampler, "brdf:srbf", n, seed + 1).unwrap(),
            estimate_brdf(s, &CosineHemisphere, "brdf:cosine", n, seed + 2).unwrap(),
            estimate_light(s, &self.adaptive, "light:envmap-adaptive", n, seed + 3).unwrap(),
            estimate_light(s, &self.cdf, "light:envmap-cdf", n, seed + 4).unwrap(),
        ];
        let mut k = 5;
        for (lname, light) in [
            ("envmap-adaptive", &self.adaptive),
            ("envmap-cdf", &self.cdf),
        ] {
            for h in [MisHeuristic::Balance, MisHeuristic::Power] {
                let name = format!("mis-{h:?}:srbf+{lname}").to_lowercase();
                out.push(estimate_mis(s, brdf_sampler, light, h, &name, n, seed + k).unwrap());
                k += 1;
            }
        }
        out
    }
}

/// `|F − Q| < 4σ̂ + e_Q`; `Some(reason)` when the check fails. A heavy-tail flag
/// ([`Estimate::warning`]) is printed, not failed: on these maps single-technique estimators
/// are heavy-tailed by construction (a 300-radiance column on a 0.15 background seen by BRDF
/// sampling, a GGX peak over dim noise seen by light sampling), and so is the product
/// estimator with the CI's coarse map fit where the column crosses the GGX peak (measured on
/// the lower-hemisphere-zero case: one sample holds 8–24 % of the variance estimate at
/// 2·10⁴ samples without the light component, 7–13 % with β = 0.1, 5–6 % with β = 0.2). A
/// heavy tail mostly *under*states `σ̂`, which makes the bias check stricter.
fn verdict(e: &Estimate, q: f64, q_err: f64) -> Option<String> {
    let off = (e.estimate - q).abs();
    let z = (e.estimate - q) / e.std_err;
    let line = format!(
        "{} = {:.5} ± {:.5} vs quadrature {q:.5} (±{q_err:.1e}): {:+.2} %, z = {z:+.2}",
        e.estimator,
        e.estimate,
        e.std_err,
        100.0 * (e.estimate / q - 1.0)
    );
    // NaN estimates fail too.
    (off.is_nan() || off >= 4.0 * e.std_err + q_err).then_some(line)
}

/// Small fits (seconds): the bias of issue 27 shows with them too.
fn small_options() -> SrbfOptions {
    SrbfOptions {
        slices: 8,
        fit_rows: 16,
        brdf_lobes: 4,
        map_lobes: 12,
        map_fit_width: 64,
        max_iter: 60,
        ..SrbfOptions::default()
    }
}

/// Runs every case at every `n`; returns the failures (and prints every line).
fn run(w: usize, options: &SrbfOptions, ns: &[usize], sub: usize) -> Vec<String> {
    let brdf = brdf::parse_spec("ggx:alpha=0.15").unwrap();
    let brdf_fit = SrbfSampler::build(brdf.as_ref(), options).unwrap();
    let mut failures = Vec::new();
    for (c, case) in cases(w).iter().enumerate() {
        let setup = Setup::new(case, brdf.as_ref(), &brdf_fit, options);
        let (q, q_err) = quadrature_reference(&setup.scene, sub);
        assert!(q > 0.0 && q_err < 1e-3 * q, "{}: {q} ± {q_err}", case.name);
        for (k, &n) in ns.iter().enumerate() {
            for e in setup.estimates(&brdf_fit, n, 1000 * c as u64 + 100 * k as u64) {
                match verdict(&e, q, q_err) {
                    Some(f) => {
                        eprintln!("FAIL {} (n = {n}): {f}", case.name);
                        failures.push(format!("{} (n = {n}): {f}", case.name));
                    }
                    None => eprintln!(
                        "ok   {} (n = {n}): {} z = {:+.2}{}",
                        case.name,
                        e.estimator,
                        (e.estimate - q) / e.std_err,
                        e.warning().map(|w| format!(" ({w})")).unwrap_or_default()
                    ),
                }
            }
        }
    }
    failures
}

#[test]
fn every_estimator_agrees_with_the_quadrature_on_adversarial_maps() {
    let failures = run(128, &small_options(), &[20_000, 80_000], 8);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A cosine sampler that never draws the local `x > 0` half (folded onto `x < 0`, density
/// `2 cos θ/π` there, 0 on the other half): a BRDF sampler that misses part of the support.
struct HalfCosine;

impl DirectionSampler for HalfCosine {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let s = CosineHemisphere.sample(wo, u);
        let wi = Vec3::new(-s.wi.x.abs(), s.wi.y, s.wi.z);
        DirSample {
            wi,
            pdf: self.pdf(wo, &wi),
        }
    }
    fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        if wi.x <= 0.0 && wi.z > 0.0 {
            2.0 * wi.z * std::f64::consts::FRAC_1_PI
        } else {
            0.0
        }
    }
    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for HalfCosine {}

#[test]
fn the_check_rejects_samplers_that_miss_part_of_the_support() {
    // The seam case (its column is near the surface's horizon on the local +x side). A BRDF
    // sampler that never draws local x > 0, and a map sampler built on the map with the
    // column set to 0 below v = 0.25 (where it meets the GGX tail): their single-technique estimators are
    // biased and must be rejected at both counts; MIS with the intact other technique stays
    // unbiased (the union of the supports covers the integrand) and must pass.
    let options = small_options();
    let brdf = brdf::parse_spec("ggx:alpha=0.15").unwrap();
    let brdf_fit = SrbfSampler::build(brdf.as_ref(), &options).unwrap();
    let case = cases(128).swap_remove(0);
    let setup = Setup::new(&case, brdf.as_ref(), &brdf_fit, &options);
    let (q, q_err) = quadrature_reference(&setup.scene, 8);
    let cut = map(128, 64, |x, y| {
        let on_column = x <= 1 || x == 127;
        on_column.then_some(if y < 16 { 300.0 } else { 0.0 })
    });
    let cut_cdf = EnvMapSampler::piecewise_constant(&cut).unwrap();
    let s = &setup.scene;
    for (k, n) in [20_000, 80_000].into_iter().enumerate() {
        let seed = 7 + 100 * k as u64;
        let biased = [
            estimate_brdf(s, &HalfCosine, "brdf:half-cosine", n, seed).unwrap(),
            estimate_light(s, &cut_cdf, "light:cut-cdf", n, seed + 1).unwrap(),
        ];
        for e in &biased {
            assert!(verdict(e, q, q_err).is_some(), "not rejected: {e:?} vs {q}");
        }
        let unbiased = [
            estimate_mis(
                s,
                &HalfCosine,
                &setup.adaptive,
                MisHeuristic::Balance,
                "mis-half",
                n,
                seed + 2,
            )
            .unwrap(),
            estimate_mis(
                s,
                &brdf_fit,
                &cut_cdf,
                MisHeuristic::Balance,
                "mis-cut",
                n,
                seed + 3,
            )
            .unwrap(),
        ];
        for e in &unbiased {
            // The bias part of the check (the cut MIS is heavy-tailed: the column's lower part
            // is left to BRDF sampling).
            assert!(
                (e.estimate - q).abs() < 4.0 * e.std_err + q_err,
                "{e:?} vs {q}"
            );
        }
    }
}

#[test]
#[ignore = "10⁶ samples on the issue's 256 × 128 maps with the default fits: minutes"]
fn full_adversarial_cases() {
    // 10⁶ only: at 10⁵ BRDF-only sampling of the hot pixel is a rare event (about 0.2 expected
    // hits), missed outright (measured −29 %, z = −318), which no standard error can show.
    let failures = run(256, &SrbfOptions::default(), &[1_000_000], 8);
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn quadrature_reference_matches_a_closed_form() {
    // A constant map of radiance 1 under Lambert (albedo 1): L_r = 1 for any frame (the
    // quadrature sees the map in world space and the cosine in the local frame).
    let one = EnvMap::new(64, 32, vec![[1.0; 3]; 64 * 32]).unwrap();
    let lambert = brdf::parse_spec("lambert").unwrap();
    for normal in [[0.0, 0.0, 1.0], NORMAL, [0.8, 0.2, -0.3]] {
        let scene = scene(lambert.as_ref(), &one, normal, 0.3, [40.0, 0.0]);
        let (q, e) = quadrature_reference(&scene, 4);
        let albedo = lambert.eval(&scene.wo, &Vec3::z()) * std::f64::consts::PI;
        assert!(
            (q - albedo).abs() < 1e-3 && e < 1e-3,
            "{normal:?}: {q} ± {e}"
        );
    }
}
