//! Issue 27's scene: a 256 × 128 map of dim noise with a 300-radiance column 3 pixels wide at
//! `u ≈ U`, GGX `α = 0.15`, normal `(0.3, 0.2, 0.93)`, `θo = 40°`; every estimator with the
//! default SRBF options against the per-pixel quadrature, optionally writing the map as PFM
//! (for `brdf-lab product --map`). Figures: docs/validation.md, "Product estimators:
//! unbiasedness under adversarial maps".
//!
//! `cargo run --release -p estimators --example product_bias -- [U [N [OUT.pfm]]]`

use baselines::srbf::fit_envmap;
use baselines::{SrbfOptions, SrbfSampler};
use envmap::{AdaptiveOptions, EnvMapSampler};
use estimators::{
    Estimate, MisHeuristic, estimate_brdf, estimate_light, estimate_mis, estimate_srbf_product,
    quadrature_reference,
};

#[path = "../tests/it/scenes.rs"]
mod scenes;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let uc: f64 = args.get(1).map_or(Ok(0.0), |s| s.parse())?;
    let n: usize = args.get(2).map_or(Ok(1_000_000), |s| s.parse())?;
    let (w, h) = (256usize, 128usize);
    let xc = ((uc * w as f64).round() as usize) % w;
    let map = scenes::column(w, h, xc, 0.0, 1.0);
    if let Some(path) = args.get(3) {
        // PFM: little-endian (negative scale), rows bottom to top.
        let mut bytes = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
        for y in (0..h).rev() {
            for x in 0..w {
                for c in map.pixel(x, y).ok_or("pixel")? {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        std::fs::write(path, bytes)?;
    }
    let brdf = brdf::parse_spec("ggx:alpha=0.15")?;
    let scene = scenes::scene(brdf.as_ref(), &map, [0.3, 0.2, 0.93], 0.0, [40.0, 0.0]);
    let (q, q_err) = quadrature_reference(&scene, 8);
    println!("column at u = {uc}: quadrature {q:.6} ± {q_err:.1e}");
    let options = SrbfOptions::default();
    let brdf_fit = SrbfSampler::build(brdf.as_ref(), &options)?;
    let map_fit = fit_envmap(&map, &options)?;
    let adaptive = EnvMapSampler::adaptive(&map, AdaptiveOptions::default())?;
    let cdf = EnvMapSampler::piecewise_constant(&map)?;
    let show = |e: &Estimate| {
        println!(
            "{:<36} {:.5} ± {:.5}  {:+6.2} %  z = {:+6.2}  {}",
            e.estimator,
            e.estimate,
            e.std_err,
            100.0 * (e.estimate / q - 1.0),
            (e.estimate - q) / e.std_err,
            e.warning().unwrap_or_default()
        )
    };
    let settings = options.product_settings();
    show(&estimate_srbf_product(&scene, &brdf_fit, &map_fit, &adaptive, &settings, n, 1)?.0);
    show(&estimate_brdf(&scene, &brdf_fit, "brdf:srbf", n, 2)?);
    show(&estimate_light(
        &scene,
        &adaptive,
        "light:envmap-adaptive",
        n,
        3,
    )?);
    show(&estimate_light(&scene, &cdf, "light:envmap-cdf", n, 4)?);
    for (k, h) in [MisHeuristic::Balance, MisHeuristic::Power]
        .into_iter()
        .enumerate()
    {
        let name = format!("mis-{h:?}:srbf+envmap-adaptive").to_lowercase();
        show(&estimate_mis(
            &scene,
            &brdf_fit,
            &adaptive,
            h,
            &name,
            n,
            5 + k as u64,
        )?);
    }
    Ok(())
}
