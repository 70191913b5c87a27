//! Unbiasedness of the reflected-radiance estimators (SRBF product, BRDF, light, MIS): each
//! agrees with an independent converged reference within 4 standard errors.
//!
//! `reduced_*` runs in CI (small maps and fits, every estimator tested); `full_tier_*` (ignored; run with
//! `cargo test -p estimators --release --test it srbf_product -- --ignored`) covers the three maps of
//! `../shared/data/envmaps`, the procedural sky, four BRDFs (diffuse, glossy, sharp,
//! MERL-layout) and three normals each; there the single-technique estimators are reported, not
//! tested
//! (see [`check`]).

use baselines::srbf::fit_envmap;
use baselines::{CosineHemisphere, SrbfOptions, SrbfSampler};
use brdf::Brdf;
use envmap::{AdaptiveOptions, EnvMap, EnvMapSampler};
use estimators::{
    Estimate, MisHeuristic, ProductScene, estimate_brdf, estimate_light, estimate_mis,
    estimate_srbf_product,
};

use crate::scenes::scene;

/// `(a − b) / √(σa² + σb²)`.
fn z(a: &Estimate, b: &Estimate) -> f64 {
    (a.estimate - b.estimate) / (a.std_err.powi(2) + b.std_err.powi(2)).sqrt()
}

/// Runs every estimator on one (map, BRDF) pair at `normals`, returns the failures. With
/// `test_single == false` the single-technique estimators (`brdf:*`, `light:*`) are printed, not
/// tested: BRDF sampling of a map with a sun, and light sampling of a sharp lobe, are rare-event
/// estimators (the sun or the lobe is hit a handful of times in 10⁵ samples, or not at all), so
/// their sample standard error is no yardstick (measured: z down to −117 on the railway map's sun,
/// −41 on the studio map's sharp lobe). SRBF product sampling and MIS are always tested.
/// The reference: balance-heuristic MIS of the cosine sampler and the map's CDF sampler
/// (independent of the SRBF fits), `n` samples from `seed`.
fn reference(scene: &ProductScene, cdf: &EnvMapSampler, n: usize, seed: u64) -> Estimate {
    estimate_mis(
        scene,
        &CosineHemisphere,
        cdf,
        MisHeuristic::Balance,
        "reference",
        n,
        seed,
    )
    .unwrap()
}

fn check(
    map: &EnvMap,
    brdf: &dyn Brdf,
    options: &SrbfOptions,
    normals: &[[f64; 3]],
    n: usize,
    n_ref: usize,
    test_single: bool,
) -> Vec<String> {
    let brdf_fit = SrbfSampler::build(brdf, options).unwrap();
    let map_fit = fit_envmap(map, options).unwrap();
    let adaptive = EnvMapSampler::adaptive(map, AdaptiveOptions::default()).unwrap();
    let cdf = EnvMapSampler::piecewise_constant(map).unwrap();
    let mut failures = Vec::new();
    for (i, normal) in normals.iter().enumerate() {
        let scene = scene(brdf, map, *normal, 0.4, [35.0, 20.0]);
        let seed = 100 * i as u64;
        // The reference uses samplers independent of the SRBF fits.
        let reference = reference(&scene, &cdf, n_ref, seed + 1);
        let mut estimates = vec![
            estimate_srbf_product(
                &scene,
                &brdf_fit,
                &map_fit,
                &cdf,
                &options.product_settings(),
                n,
                seed + 2,
            )
            .unwrap()
            .0,
            estimate_brdf(&scene, &brdf_fit, "brdf:srbf", n, seed + 3).unwrap(),
            estimate_brdf(&scene, &CosineHemisphere, "brdf:cosine", n, seed + 4).unwrap(),
            estimate_light(&scene, &adaptive, "light:adaptive", n, seed + 5).unwrap(),
            estimate_light(&scene, &cdf, "light:cdf", n, seed + 6).unwrap(),
        ];
        for (k, h) in [MisHeuristic::Balance, MisHeuristic::Power]
            .into_iter()
            .enumerate()
        {
            estimates.push(
                estimate_mis(
                    &scene,
                    &brdf_fit,
                    &adaptive,
                    h,
                    &format!("mis-{h:?}"),
                    n,
                    seed + 7 + k as u64,
                )
                .unwrap(),
            );
        }
        for e in &estimates {
            let zz = z(e, &reference);
            let single = e.estimator.starts_with("brdf:") || e.estimator.starts_with("light:");
            if !test_single && single {
                eprintln!(
                    "{} normal {normal:?}: {} z = {zz:.2} (not tested)",
                    brdf.name(),
                    e.estimator
                );
                continue;
            }
            // A single-technique estimate flagged heavy-tailed (one sample holds most of the
            // variance estimate: a rare sun hit) has no usable standard error either. Measured
            // 2026-11-26: brdf:srbf on the phong scene at normal +z, twelve seeds of 20 000
            // samples, 0.38–1.08 against 0.758, every run but one flagged (the unflagged one
            // hit the sun not at all, ±0.001).
            if single && e.heavy_tailed {
                eprintln!(
                    "{} normal {normal:?}: {} z = {zz:.2} (heavy-tailed: not tested)",
                    brdf.name(),
                    e.estimator
                );
                continue;
            }
            if zz.is_nan() || zz.abs() >= 4.0 {
                failures.push(format!(
                    "{} normal {normal:?}: {} = {:.6e} ± {:.2e} vs reference {:.6e} ± {:.2e} (z = {zz:.2})",
                    brdf.name(), e.estimator, e.estimate, e.std_err, reference.estimate, reference.std_err
                ));
            }
        }
    }
    failures
}

fn small_options() -> SrbfOptions {
    SrbfOptions {
        slices: 6,
        fit_rows: 12,
        brdf_lobes: 4,
        map_lobes: 12,
        map_fit_width: 64,
        max_iter: 60,
        ..SrbfOptions::default()
    }
}

#[test]
fn reduced_estimators_agree_with_the_reference() {
    let sky = envmap::procedural_sky(128, 64).unwrap();
    let normals = [[0.0, 0.0, 1.0], [0.5, -0.3, 0.8]];
    let mut failures = Vec::new();
    for spec in ["lambert", "phong:n=40,ks=0.6,kd=0.2"] {
        let brdf = brdf::parse_spec(spec).unwrap();
        failures.extend(check(
            &sky,
            brdf.as_ref(),
            &small_options(),
            &normals,
            20_000,
            200_000,
            true,
        ));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn reduced_detects_a_biased_estimator() {
    // The z-test has power: a light estimator whose pdf is off by 5 % is rejected.
    let sky = envmap::procedural_sky(128, 64).unwrap();
    let brdf = brdf::parse_spec("lambert").unwrap();
    let cdf = EnvMapSampler::piecewise_constant(&sky).unwrap();
    let scene = scene(brdf.as_ref(), &sky, [0.0, 0.0, 1.0], 0.0, [35.0, 20.0]);
    let reference = reference(&scene, &cdf, 200_000, 1);
    let mut biased = estimate_light(&scene, &cdf, "light", 20_000, 2).unwrap();
    assert!(z(&biased, &reference).abs() < 4.0);
    biased.estimate *= 1.05;
    assert!(
        z(&biased, &reference).abs() > 4.0,
        "{biased:?} vs {reference:?}"
    );
}

/// The maps of `../shared/data/envmaps` (relative to the workspace root).
fn shared_maps() -> Vec<(String, EnvMap)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/envmaps");
    let mut maps = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap().path();
        if path
            .extension()
            .is_some_and(|e| e == "hdr" || e == "exr" || e == "pfm")
        {
            maps.push((path.display().to_string(), EnvMap::load(&path).unwrap()));
        }
    }
    assert_eq!(maps.len(), 3, "expected three maps in {}", dir.display());
    maps
}

#[test]
#[ignore = "full tier: minutes; run with --ignored --release"]
fn full_tier_estimators_agree_with_the_reference() {
    let mut maps = shared_maps();
    maps.push((
        "procedural sky".to_string(),
        envmap::procedural_sky(1024, 512).unwrap(),
    ));
    let glossy = brdf::parse_spec("phong:n=50,ks=0.5,kd=0.3").unwrap();
    let merl: Box<dyn Brdf> = Box::new(brdf::MerlBrdf::tabulate(glossy.as_ref()));
    let brdfs: Vec<(&str, Box<dyn Brdf>)> = vec![
        ("diffuse", brdf::parse_spec("lambert").unwrap()),
        ("glossy", glossy),
        (
            "sharp",
            brdf::parse_spec("phong:n=2000,ks=0.8,kd=0.0").unwrap(),
        ),
        ("merl-layout", merl),
    ];
    let normals = [[0.0, 0.0, 1.0], [0.6, 0.2, 0.77], [-0.3, -0.8, 0.5]];
    let options = SrbfOptions::default();
    let mut failures = Vec::new();
    for (map_name, map) in &maps {
        for (label, brdf) in &brdfs {
            let f = check(
                map,
                brdf.as_ref(),
                &options,
                &normals,
                100_000,
                2_000_000,
                false,
            );
            failures.extend(f.into_iter().map(|s| format!("{map_name} / {label}: {s}")));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
