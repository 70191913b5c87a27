//! Sampling a lat-long map: goodness of fit against exact cell masses, pdf consistency, the
//! solid-angle conversion, reproducibility, real maps.

use std::f64::consts::PI;

use distributions::on_threads;
use envmap::latlong::{sin_integral, uv_to_direction};
use envmap::{
    AdaptiveOptions, EnvMap, EnvMapError, EnvMapSampler, LeafChoice, SamplerKind, Scheme,
    procedural_sky,
};
use partition_sampler::{QuadTreeBuilder, Rect, Sampler2D, TabulatedDensity};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

use crate::support;

/// Significance level of every chi-square test in this file.
const ALPHA: f64 = 1e-3;
/// Sub-rows per pixel row in the chi-square bins (tests the sin(πv) shape inside a pixel).
const SUB: usize = 4;

/// Binned chi-square ([`stats::chi_square_gof`]): expected counts below 5 are pooled; a hit in
/// a zero-mass cell fails.
fn chi_square_p(observed: &[u64], probabilities: &[f64]) -> f64 {
    let n = observed.iter().sum::<u64>() as f64;
    let expected: Vec<f64> = probabilities.iter().map(|p| p * n).collect();
    let test = stats::chi_square_gof(observed, &expected, stats::DEFAULT_MIN_EXPECTED);
    test.expect("at least two cells").p_value
}

/// A 16 × 8 map: a smooth gradient, a black band, and a tiny very bright "sun" pixel.
fn small_map() -> EnvMap {
    let (w, h) = (16, 8);
    let rgb = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if y == 6 && x < 8 {
                [0.0; 3]
            } else if (x, y) == (11, 2) {
                [4000.0, 3800.0, 3500.0]
            } else {
                let t = 0.2 + 0.1 * x as f32 + 0.3 * y as f32;
                [t, 0.5 * t, 1.5 * t]
            }
        })
        .collect();
    EnvMap::new(w, h, rgb).unwrap()
}

/// Exact bin probabilities of `Y(pixel)·row_weight` on `W × (H·SUB)` bins, `row_weight(v0, v1)`
/// being the integral of the row factor over a sub-row.
fn bin_masses(map: &EnvMap, row_weight: impl Fn(usize, f64, f64) -> f64) -> Vec<f64> {
    let (w, h) = (map.width(), map.height());
    let lum = map.luminance();
    let mut m = vec![0.0; w * h * SUB];
    for y in 0..h {
        for k in 0..SUB {
            let v0 = (y * SUB + k) as f64 / (h * SUB) as f64;
            let v1 = (y * SUB + k + 1) as f64 / (h * SUB) as f64;
            for x in 0..w {
                m[(y * SUB + k) * w + x] = lum[y * w + x] * row_weight(y, v0, v1);
            }
        }
    }
    let total: f64 = m.iter().sum();
    m.iter().map(|x| x / total).collect()
}

/// The exact target `Y · sin(πv)`.
fn exact_masses(map: &EnvMap) -> Vec<f64> {
    bin_masses(map, |_, v0, v1| sin_integral(v0, v1))
}

/// The piecewise-constant approximation `Y · sin(π v_centre)`.
fn midpoint_masses(map: &EnvMap) -> Vec<f64> {
    let h = map.height();
    bin_masses(map, |y, v0, v1| {
        (PI * (y as f64 + 0.5) / h as f64).sin() * (v1 - v0)
    })
}

fn histogram<S: Sampler2D>(s: &S, w: usize, h: usize, n: usize, seed: u64) -> Vec<u64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut counts = vec![0u64; w * h * SUB];
    for _ in 0..n {
        let p = s.sample(&mut rng).point;
        let x = ((p[0] * w as f64) as usize).min(w - 1);
        let r = ((p[1] * (h * SUB) as f64) as usize).min(h * SUB - 1);
        counts[r * w + x] += 1;
    }
    counts
}

fn adaptive(scheme: Scheme, leaf_choice: LeafChoice) -> SamplerKind {
    SamplerKind::Adaptive(AdaptiveOptions::with_scheme(scheme, leaf_choice))
}

const ADAPTIVE_KINDS: [(Scheme, LeafChoice); 3] = [
    (Scheme::Envelope, LeafChoice::Alias),
    (Scheme::Envelope, LeafChoice::Descent),
    (Scheme::Paper, LeafChoice::Alias),
];

#[test]
fn adaptive_matches_exact_masses() {
    let map = small_map();
    let exact = exact_masses(&map);
    for (i, &(scheme, choice)) in ADAPTIVE_KINDS.iter().enumerate() {
        let s = EnvMapSampler::new(&map, adaptive(scheme, choice)).unwrap();
        let counts = histogram(&s, map.width(), map.height(), 300_000, 10 + i as u64);
        let p = chi_square_p(&counts, &exact);
        assert!(p > ALPHA, "{scheme:?}/{choice:?}: p = {p}");
        let stats = s.stats().unwrap();
        assert_eq!(stats.bound_violations, 0);
        assert_eq!(stats.exhausted, 0);
    }
}

#[test]
fn piecewise_constant_matches_its_midpoint_masses() {
    let map = small_map();
    let s = EnvMapSampler::piecewise_constant(&map).unwrap();
    let counts = histogram(&s, map.width(), map.height(), 300_000, 20);
    let p = chi_square_p(&counts, &midpoint_masses(&map));
    assert!(p > ALPHA, "p = {p}");
}

/// Negative tests: the same chi-square test rejects (a) the piecewise-constant sampler against
/// the exact target on this coarse map (its midpoint approximation of sin(πv) is detectably
/// off with 8 rows), and (b) an adaptive sampler that forgets the sin(πv) factor.
#[test]
fn chi_square_rejects_wrong_densities() {
    let map = small_map();
    let exact = exact_masses(&map);
    let pwc = EnvMapSampler::piecewise_constant(&map).unwrap();
    let p = chi_square_p(&histogram(&pwc, 16, 8, 300_000, 30), &exact);
    assert!(p < ALPHA, "midpoint approximation not detected: p = {p}");

    let no_sin = TabulatedDensity::new(16, 8, map.luminance(), Rect::UNIT).unwrap();
    let broken = QuadTreeBuilder::new().build(no_sin).unwrap();
    let p = chi_square_p(&histogram(&broken, 16, 8, 300_000, 31), &exact);
    assert!(p < ALPHA, "missing sin(πv) not detected: p = {p}");
}

fn all_kinds() -> Vec<SamplerKind> {
    let mut k: Vec<SamplerKind> = ADAPTIVE_KINDS
        .iter()
        .map(|&(s, c)| adaptive(s, c))
        .collect();
    k.push(SamplerKind::PiecewiseConstant);
    k
}

#[test]
fn sample_pdfs_match_pdf_queries() {
    let map = small_map();
    for kind in all_kinds() {
        let s = EnvMapSampler::new(&map, kind).unwrap();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        for _ in 0..20_000 {
            let e = s.sample(&mut rng);
            assert!((0.0..1.0).contains(&e.u) && (0.0..1.0).contains(&e.v));
            assert!(
                e.pdf_uv > 0.0 && e.pdf_sa > 0.0 && e.pdf_sa.is_finite(),
                "{kind:?}: {e:?}"
            );
            assert_eq!(e.pdf_uv, s.pdf_uv(e.u, e.v), "{kind:?}");
            let sa = s.pdf_sa(e.direction);
            // The round trip through the direction recovers v by acos, whose relative error
            // near a pole grows as ε / (π·min(v, 1 − v))² (2.8e-9 at v = 1 − 4.3e-5).
            let pole = f64::EPSILON / (PI * e.v.min(1.0 - e.v)).powi(2);
            assert!(
                (sa - e.pdf_sa).abs() <= (1e-9 + pole) * e.pdf_sa,
                "{kind:?}: {sa} vs {} at {e:?}",
                e.pdf_sa
            );
            let expected = e.pdf_uv / (2.0 * PI * PI * (PI * e.v).sin());
            assert!((e.pdf_sa - expected).abs() <= 1e-12 * expected);
            let d = uv_to_direction(e.u, e.v);
            assert_eq!(d, e.direction);
        }
        assert_eq!(s.pdf_uv(-0.1, 0.5), 0.0);
        assert_eq!(s.pdf_sa([0.0, 0.0, 0.0]), 0.0);
    }
}

/// ∫ pdf_sa dω = 1, by two quadratures: on the lat-long grid (with dω = sinθ dθ dφ) and on an
/// equal-area (z, φ) grid (dω = dz dφ), which does not share the map's parametrisation.
#[test]
fn solid_angle_pdf_integrates_to_one() {
    let map = small_map();
    for kind in all_kinds() {
        let s = EnvMapSampler::new(&map, kind).unwrap();
        let (nu, nv) = (16 * 8, 8 * 32);
        let mut latlong = 0.0;
        for j in 0..nv {
            let v = (j as f64 + 0.5) / nv as f64;
            let d_omega = (2.0 * PI / nu as f64) * (PI / nv as f64) * (PI * v).sin();
            for i in 0..nu {
                latlong += s.pdf_sa(uv_to_direction((i as f64 + 0.5) / nu as f64, v)) * d_omega;
            }
        }
        assert!(
            (latlong - 1.0).abs() < 2e-4,
            "{kind:?}: lat-long quadrature {latlong}"
        );
        let (nz, nphi) = (1024, 1024);
        let mut equal_area = 0.0;
        for a in 0..nz {
            let z = -1.0 + 2.0 * (a as f64 + 0.5) / nz as f64;
            let r = (1.0 - z * z).sqrt();
            for b in 0..nphi {
                let phi = 2.0 * PI * (b as f64 + 0.5) / nphi as f64;
                equal_area += s.pdf_sa([r * phi.cos(), r * phi.sin(), z]);
            }
        }
        equal_area *= 4.0 * PI / (nz * nphi) as f64;
        assert!(
            (equal_area - 1.0).abs() < 5e-3,
            "{kind:?}: equal-area quadrature {equal_area}"
        );
    }
}

#[test]
fn parallel_batches_are_reproducible() {
    let map = small_map();
    for kind in all_kinds() {
        let s = EnvMapSampler::new(&map, kind).unwrap();
        let n = 10_000;
        let one = on_threads(1, || s.sample_par(n, 4)).unwrap();
        let two = on_threads(2, || s.sample_par(n, 4)).unwrap();
        assert_eq!(one, two, "{kind:?}");
        let uv = s.sample_uv_par(n, 4);
        assert!(
            uv.iter()
                .zip(&one)
                .all(|(a, b)| a.point == [b.u, b.v] && a.pdf == b.pdf_uv)
        );
        assert_ne!(s.sample_uv_par(n, 5), uv);
    }
}

/// The batch path through the lane-parallel generator (`sample_uv_par_lanes`, `LaneRng`): the
/// same law as the serial path (chi-square at `ALPHA` against the exact masses for the adaptive
/// sampler, the midpoint masses for the CDF), every sample's pdf equal to the pdf query, and
/// the batch a function of `(n, seed)` whatever the thread count.
#[test]
fn lane_batches_have_the_target_law_and_are_reproducible() {
    let map = small_map();
    let (w, h) = (map.width(), map.height());
    for (kind, masses) in [
        (
            adaptive(Scheme::Envelope, LeafChoice::Alias),
            exact_masses(&map),
        ),
        (SamplerKind::PiecewiseConstant, midpoint_masses(&map)),
    ] {
        let s = EnvMapSampler::new(&map, kind).unwrap();
        let batch = s.sample_uv_par_lanes(300_000, 40);
        let mut counts = vec![0u64; w * h * SUB];
        for x in &batch {
            let p = x.point;
            let col = ((p[0] * w as f64) as usize).min(w - 1);
            let row = ((p[1] * (h * SUB) as f64) as usize).min(h * SUB - 1);
            counts[row * w + col] += 1;
            assert_eq!(x.pdf, s.pdf_uv(p[0], p[1]), "{kind:?}");
        }
        let p = chi_square_p(&counts, &masses);
        assert!(p > ALPHA, "{kind:?}: p = {p}");
        let n = 10_000;
        let one = on_threads(1, || s.sample_uv_par_lanes(n, 4)).unwrap();
        let two = on_threads(2, || s.sample_uv_par_lanes(n, 4)).unwrap();
        assert_eq!(one, two, "{kind:?}");
        assert_ne!(s.sample_uv_par_lanes(n, 5), one);
    }
}

#[test]
fn builder_errors_are_typed() {
    let map = small_map();
    let mut bad = AdaptiveOptions::default();
    bad.tree.n_max = 0.5;
    assert!(matches!(
        EnvMapSampler::adaptive(&map, bad),
        Err(EnvMapError::Build(_))
    ));
    let mut bad = AdaptiveOptions::default();
    bad.tree.max_depth = 1000;
    assert!(matches!(
        EnvMapSampler::adaptive(&map, bad),
        Err(EnvMapError::Build(_))
    ));
}

#[test]
fn accessors() {
    let map = small_map();
    let a = EnvMapSampler::adaptive(&map, AdaptiveOptions::default()).unwrap();
    assert!(a.as_adaptive().is_some() && a.as_piecewise_constant().is_none());
    assert!(a.memory().is_some() && a.bytes_used() > 0);
    let p = EnvMapSampler::piecewise_constant(&map).unwrap();
    assert!(p.stats().is_none() && p.memory().is_none() && p.as_piecewise_constant().is_some());
    assert_eq!((p.width(), p.height()), (16, 8));
}

/// Both samplers on the procedural sky and on the real maps (when present): positive finite
/// pdfs, no bound violation, mean trials close to 1.
#[test]
fn real_maps_and_sky_sample_cleanly() {
    let mut maps = vec![(
        "procedural sky 256×128".to_string(),
        procedural_sky(256, 128).unwrap(),
    )];
    match support::real_map_paths() {
        Ok(paths) => {
            for path in paths {
                maps.push((path.display().to_string(), EnvMap::load(&path).unwrap()));
            }
        }
        Err(dir) => eprintln!("skipping real maps: {} is absent", dir.display()),
    }
    for (name, map) in &maps {
        for kind in [
            SamplerKind::Adaptive(AdaptiveOptions::default()),
            SamplerKind::PiecewiseConstant,
        ] {
            let s = EnvMapSampler::new(map, kind).unwrap();
            let batch = s.sample_par(50_000, 1);
            assert!(
                batch
                    .iter()
                    .all(|e| e.pdf_uv > 0.0 && e.pdf_sa > 0.0 && e.pdf_sa.is_finite()),
                "{name} {kind:?}"
            );
            if let Some(st) = s.stats() {
                assert_eq!(st.bound_violations, 0, "{name}");
                assert_eq!(st.exhausted, 0, "{name}");
                let trials = st.measured_mean_trials.unwrap();
                let n_max = AdaptiveOptions::default().tree.n_max;
                assert!(trials <= n_max * 1.02, "{name}: {trials} trials");
                assert!(
                    (trials / st.expected_mean_trials - 1.0).abs() < 0.05,
                    "{name}: {trials} trials"
                );
                eprintln!(
                    "{name}: {}×{}, adaptive {} bytes, mean trials {trials:.4} (expected {:.4}); cdf {} bytes",
                    map.width(),
                    map.height(),
                    s.bytes_used(),
                    st.expected_mean_trials,
                    EnvMapSampler::piecewise_constant(map).unwrap().bytes_used()
                );
            }
        }
    }
}
