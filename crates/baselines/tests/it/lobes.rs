//! The lobe baselines (`LobeSampler` on S² and on Ω) and the analytic samplers against the
//! required tests of baselines.md §0.5: pdf consistency, normalisation by quadrature, E[g/p]
//! against a quadrature of ∫ g, support coverage; property tests; and a deliberately broken
//! variant that the same z-test rejects.

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use baselines::lobe::{above_horizon_mass, lobe_density, sample_lobe};
use baselines::{AnalyticSampler, LobeError, LobeOptions, LobeSampler, LobeSupport};
use brdf::{Brdf, Vec3, direction_from_angles, directional_albedo, mirror};
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;
use proptest::prelude::*;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// A labelled sampler with its BRDF.
type Case = (String, Arc<dyn Brdf>, Box<dyn DirectionSampler>);
/// A BRDF with its samplers.
type Built = (Arc<dyn Brdf>, Vec<Box<dyn DirectionSampler>>);

fn brdf(spec: &str) -> Arc<dyn Brdf> {
    Arc::from(brdf::parse_spec(spec).unwrap())
}

/// Every model with an analytic sampler, with parameters broad enough for a 1000² quadrature.
const ANALYTIC: &[&str] = &[
    "lambert",
    "phong:n=20",
    "phong:n=30,kd=0",
    "blinn:n=30",
    "lewis:n=20",
    "ward:alpha_x=0.2,alpha_y=0.35",
    "ward-original:alpha_x=0.25",
    "ggx:alpha=0.3,alpha_y=0.6",
    "beckmann:alpha=0.4,alpha_y=0.25",
    "cook-torrance:m=0.3",
];

const ANGLES: &[f64] = &[0.0, 30.0, 60.0, 85.0, 89.0];

/// `∫_{S²} pdf dσ` by a midpoint rule in polar coordinates `(α, φ)` about `axis` (weight
/// `sin α`), which keeps a `1/r` peak at the axis integrable.
fn integral(s: &dyn DirectionSampler, wo: &Vec3, axis: &Vec3, n: usize) -> f64 {
    let t = if axis.x.abs() < 0.9 {
        Vec3::x().cross(axis).normalize()
    } else {
        Vec3::y().cross(axis).normalize()
    };
    let b = axis.cross(&t);
    let mut sum = 0.0;
    for i in 0..n {
        let alpha = PI * (i as f64 + 0.5) / n as f64;
        let (sa, ca) = alpha.sin_cos();
        let mut ring = 0.0;
        for j in 0..n {
            let phi = TAU * (j as f64 + 0.5) / n as f64;
            ring += s.pdf(
                wo,
                &(t * (sa * phi.cos()) + b * (sa * phi.sin()) + axis * ca),
            );
        }
        sum += ring * sa;
    }
    sum * (PI / n as f64) * (TAU / n as f64)
}

/// Mean and standard error of `f·cos/p` over `n` samples (0 below the horizon).
fn estimate(s: &dyn DirectionSampler, b: &dyn Brdf, wo: &Vec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..n {
        let d = s.sample(wo, &mut rng);
        let g = b.eval(wo, &d.wi) * d.wi.z.max(0.0);
        let v = if g > 0.0 { g / d.pdf } else { 0.0 };
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean) / n as f64).sqrt())
}

fn lobe_samplers(b: &Arc<dyn Brdf>) -> Vec<(&'static str, LobeSampler)> {
    [
        ("lobe-sphere", LobeSupport::Sphere),
        ("lobe-hemisphere", LobeSupport::Hemisphere),
    ]
    .into_iter()
    .map(|(name, support)| {
        (
            name,
            LobeSampler::new(b, support, &LobeOptions::default()).unwrap(),
        )
    })
    .collect()
}

#[test]
fn pdfs_integrate_to_one() {
    // Lobe samplers: 1 over S² (sphere; below-horizon mass included) or over Ω (hemisphere).
    for spec in ["phong:n=20", "ggx:alpha=0.3,alpha_y=0.6", "oren-nayar"] {
        let b = brdf(spec);
        for (name, s) in lobe_samplers(&b) {
            for &theta in ANGLES {
                let wo = direction_from_angles(theta, 40.0);
                let total = integral(&s, &wo, &mirror(&wo), 1000);
                assert!(
                    (total - 1.0).abs() < 2e-3,
                    "{name} {spec} θ={theta}: {total}"
                );
            }
        }
    }
    for spec in ANALYTIC {
        let b = brdf(spec);
        let s = AnalyticSampler::new(b.as_ref()).unwrap();
        for &theta in ANGLES {
            let wo = direction_from_angles(theta, 40.0);
            // About −ωo: half-vector samplers have an integrable 1/r peak there (every h ⊥ ωo
            // reflects to −ωo).
            let total = integral(&s, &wo, &-wo, 1000);
            assert!(
                (total - 1.0).abs() < 3e-3,
                "analytic {spec} θ={theta}: {total}"
            );
        }
    }
}

#[test]
fn estimates_of_the_albedo_match_its_quadrature() {
    // E[f cos / p] = ∫_Ω f cos dσ (unbiasedness, every sampler on every kind of model).
    let mut cases: Vec<Case> = Vec::new();
    for spec in [
        "phong:n=50",
        "ggx:alpha=0.2,alpha_y=0.5",
        "oren-nayar",
        "lambert",
    ] {
        let b = brdf(spec);
        for (name, s) in lobe_samplers(&b) {
            cases.push((format!("{name} {spec}"), Arc::clone(&b), Box::new(s)));
        }
    }
    for spec in ANALYTIC {
        let b = brdf(spec);
        let s = AnalyticSampler::new(b.as_ref()).unwrap();
        cases.push((format!("analytic {spec}"), b, Box::new(s)));
    }
    for (k, (label, b, s)) in cases.iter().enumerate() {
        for (t, &theta) in [0.0, 60.0, 85.0].iter().enumerate() {
            let wo = direction_from_angles(theta, 20.0);
            let reference = directional_albedo(b.as_ref(), &wo, 256, 1024);
            let (mean, se) = estimate(s.as_ref(), b.as_ref(), &wo, 100_000, (10 * k + t) as u64);
            let z = (mean - reference) / se.max(1e-12);
            assert!(
                z.abs() < 4.5 || (mean - reference).abs() < 1e-3 * reference,
                "{label} θ={theta}: {mean} ± {se} vs {reference} (z = {z:.2})"
            );
        }
    }
}

#[test]
fn no_direction_with_positive_integrand_has_zero_pdf() {
    // Support coverage on a (z, φ) grid of Ω, including the grazing band.
    for spec in [
        "oren-nayar",
        "phong:n=50",
        "ward:alpha_x=0.1,alpha_y=0.4",
        "lambert",
    ] {
        let b = brdf(spec);
        let mut samplers: Vec<(String, Box<dyn DirectionSampler>)> = lobe_samplers(&b)
            .into_iter()
            .map(|(n, s)| (n.to_owned(), Box::new(s) as Box<dyn DirectionSampler>))
            .collect();
        if let Ok(a) = AnalyticSampler::new(b.as_ref()) {
            samplers.push(("analytic".into(), Box::new(a)));
        }
        for (name, s) in &samplers {
            for &theta in ANGLES {
                let wo = direction_from_angles(theta, 10.0);
                for i in 0..200 {
                    let z = (i as f64 + 0.5) / 200.0;
                    let r = (1.0 - z * z).sqrt();
                    for j in 0..200 {
                        let phi = TAU * (j as f64 + 0.5) / 200.0;
                        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                        if b.eval(&wo, &wi) > 0.0 {
                            assert!(s.pdf(&wo, &wi) > 0.0, "{name} {spec} θ={theta} {wi:?}");
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn models_without_an_analytic_sampler_are_refused_by_name() {
    let e = AnalyticSampler::new(brdf("oren-nayar").as_ref()).unwrap_err();
    assert!(matches!(&e, LobeError::NoAnalyticSampler { model } if model == "oren-nayar"));
    assert!(e.to_string().contains("has no analytic sampler"));
}

#[test]
fn fitted_exponents_follow_the_model_and_the_override_wins() {
    let b = brdf("phong:n=200,kd=0.1,ks=0.9");
    let s = LobeSampler::new(&b, LobeSupport::Hemisphere, &LobeOptions::default()).unwrap();
    assert_eq!(s.exponents().len(), LobeOptions::DEFAULT_SLICES);
    // Near normal incidence the mirror lobe of Phong n = 200 is the best lobe.
    assert!(
        (100.0..400.0).contains(&s.fits()[0].exponent),
        "{:?}",
        s.fits()[0]
    );
    let sharper = brdf("phong:n=2000,kd=0.1,ks=0.9");
    let s2 = LobeSampler::new(&sharper, LobeSupport::Hemisphere, &LobeOptions::default()).unwrap();
    assert!(s2.fits()[0].exponent > 3.0 * s.fits()[0].exponent);
    let fixed = LobeOptions {
        exponent: Some(7.0),
        ..LobeOptions::default()
    };
    let s3 = LobeSampler::new(&b, LobeSupport::Sphere, &fixed).unwrap();
    assert!(s3.exponents().iter().all(|&n| n == 7.0));
    // Anisotropic models get a (θ, φ) grid; sampling and pdf use the same slice.
    let aniso = brdf("ggx:alpha=0.1,alpha_y=0.5");
    let s4 = LobeSampler::new(&aniso, LobeSupport::Sphere, &LobeOptions::default()).unwrap();
    assert_eq!(
        s4.fits().len(),
        LobeOptions::DEFAULT_SLICES * LobeOptions::DEFAULT_PHI_SLICES
    );
    assert!(s4.bytes_used() > s4.fits().len() * 8);
}

/// The broken variant: the sphere lobe's pdf renormalised over Ω (divided by the lobe's
/// above-horizon mass `A`) while its below-horizon samples are kept.
struct RenormalisedSphereLobe(LobeSampler);

impl DirectionSampler for RenormalisedSphereLobe {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let wi = self.0.sample(wo, u).wi;
        DirSample {
            wi,
            pdf: self.pdf(wo, &wi),
        }
    }
    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let fit = self.0.fit_at(wo);
        let a = above_horizon_mass(wo.z.acos(), fit.exponent, 16);
        let lobe = lobe_density(fit.exponent, mirror(wo).dot(wi)) / a;
        fit.defensive * wi.z.max(0.0) / PI + (1.0 - fit.defensive) * lobe
    }
    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for RenormalisedSphereLobe {}

#[test]
fn a_z_test_rejects_the_sphere_lobe_renormalised_over_the_hemisphere() {
    // Same samples, same z-test: the correct pdf passes, the renormalised one is rejected.
    let b = brdf("phong:n=3,kd=0.2,ks=0.8");
    let options = LobeOptions {
        exponent: Some(3.0),
        ..LobeOptions::default()
    };
    let wo = direction_from_angles(70.0, 0.0);
    let reference = directional_albedo(b.as_ref(), &wo, 128, 256);
    let good = LobeSampler::new(&b, LobeSupport::Sphere, &options).unwrap();
    let (mean, se) = estimate(&good, b.as_ref(), &wo, 200_000, 99);
    let z_good = (mean - reference) / se;
    let bad = RenormalisedSphereLobe(LobeSampler::new(&b, LobeSupport::Sphere, &options).unwrap());
    let (mean, se) = estimate(&bad, b.as_ref(), &wo, 200_000, 99);
    let z_bad = (mean - reference) / se;
    assert!(good.fit_at(&wo).defensive < 0.5, "{:?}", good.fit_at(&wo));
    assert!(z_good.abs() < 4.0, "correct pdf: z = {z_good}");
    assert!(z_bad.abs() > 10.0, "broken pdf: z = {z_bad}");
}

#[test]
fn lobe_warp_reaches_grazing_angles_without_cancellation() {
    // Exponent 10⁶: 1 − cos α ~ 10⁻⁶ must keep sin α accurate (from −expm1), unit vectors.
    let axis = Vec3::new(0.0, 0.0, 1.0);
    let w = sample_lobe(&axis, 1e6, [0.5, 0.25]);
    let expected = 1.0 - (0.5f64.ln() / (1e6 + 1.0)).exp();
    assert!(((1.0 - w.z) - expected).abs() < 1e-12 && (w.norm() - 1.0).abs() < 1e-12);
}

fn unit(theta: f64, phi: f64) -> Vec3 {
    let (st, ct) = theta.sin_cos();
    Vec3::new(st * phi.cos(), st * phi.sin(), ct)
}

/// A fixed list of uniforms (cycled).
struct Fixed(Vec<f64>, usize);

impl UniformSource for Fixed {
    fn next_uniform(&mut self) -> f64 {
        let v = self.0[self.1 % self.0.len()];
        self.1 += 1;
        v
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn sample_and_pdf_agree_and_pdfs_are_non_negative(
        theta in 0.0f64..1.5621,
        phi in 0.0f64..TAU,
        us in proptest::collection::vec(0.0f64..1.0, 8),
        wt in 0.0f64..PI,
        wp in 0.0f64..TAU,
        model in 0usize..4,
    ) {
        use std::sync::OnceLock;
        static BUILT: OnceLock<Vec<Built>> = OnceLock::new();
        let built = BUILT.get_or_init(|| {
            ["phong:n=80", "ggx:alpha=0.15,alpha_y=0.4", "beckmann:alpha=0.05", "ward"]
                .iter()
                .map(|spec| {
                    let b = brdf(spec);
                    let mut v: Vec<Box<dyn DirectionSampler>> = lobe_samplers(&b)
                        .into_iter()
                        .map(|(_, s)| Box::new(s) as Box<dyn DirectionSampler>)
                        .collect();
                    v.push(Box::new(AnalyticSampler::new(b.as_ref()).unwrap()));
                    (b, v)
                })
                .collect()
        });
        let wo = unit(theta, phi);
        for s in &built[model].1 {
            let d = s.sample(&wo, &mut Fixed(us.clone(), 0));
            prop_assert!((d.wi.norm() - 1.0).abs() < 1e-9);
            let p = s.pdf(&wo, &d.wi);
            prop_assert!(d.pdf > 0.0 && p.is_finite());
            prop_assert!((p - d.pdf).abs() <= 1e-9 * p.max(1e-300));
            let any = s.pdf(&wo, &unit(wt, wp));
            prop_assert!(any >= 0.0 && any.is_finite());
        }
    }
}

/// The half-vector samplers' density has an integrable `1/|ωo + ωi|` peak at `ωi = −ωo` (the
/// fold of the reflection map). Approaching it along a fixed tangent `t`, `|ωo + ωi|·pdf`
/// tends to `(1 − p_d)·p_h(t)/2`, a finite limit: the density must follow that law down to
/// `|ωo + ωi| ≈ 10⁻¹¹` instead of dissolving into round-off (`1 + ωo·ωi` is `O(|s|²)`, so
/// computing `ωo·h` by a dot product leaves no correct digit there, which made the validation
/// suite's quadrature refine forever at θo = 85°–89°).
#[test]
fn half_vector_densities_stay_exact_next_to_the_fold_at_minus_wo() {
    for spec in [
        "blinn:n=100",
        "lewis:n=50",
        "ward",
        "ward-original:alpha_x=0.2",
    ] {
        let b = brdf(spec);
        let s = AnalyticSampler::new(b.as_ref()).unwrap();
        for theta in [60.0, 85.0, 89.0] {
            let wo = direction_from_angles(theta, 0.0);
            // The unit tangent at −ωo closest to the normal: the half vector of the limit.
            let t = (Vec3::z() - wo * wo.z).normalize();
            let scaled = |d: f64| {
                let wi = (-wo + t * d).normalize();
                (wo + wi).norm() * s.pdf(&wo, &wi)
            };
            // At |s| = 1e-7 the half vector is within ~1e-7 of t: p_h(h) is within ~n·1e-7
            // of its limit.
            let limit = scaled(1e-7);
            assert!(limit > 0.0, "{spec} at {theta}°: {limit}");
            for d in [1e-8, 1e-9, 1e-10, 1e-11] {
                let v = scaled(d);
                assert!(
                    (v / limit - 1.0).abs() < 1e-3,
                    "{spec} at {theta}°, |s| = {d:e}: |s|·pdf = {v:e}, at 1e-7: {limit:e}"
                );
            }
        }
    }
}

/// The declared singular directions (which the validation's KS quadrature grades towards) are
/// true: for the half-vector samplers the pdf grows like `1/|ωo + ωi|` towards the declared
/// `−ωo`, and the mirror direction is the lobe's peak; a cosine-only model declares nothing.
#[test]
fn analytic_samplers_declare_their_singular_directions() {
    let wo = direction_from_angles(80.0, 0.0);
    for spec in [
        "blinn:n=100",
        "lewis:n=50",
        "ward",
        "ward-original:alpha_x=0.2",
    ] {
        let s = AnalyticSampler::new(brdf(spec).as_ref()).unwrap();
        let declared = s.singular_directions(&wo);
        assert!(declared.contains(&-wo), "{spec}: {declared:?}");
        assert!(declared.contains(&mirror(&wo)), "{spec}: {declared:?}");
        let t = (Vec3::z() - wo * wo.z).normalize();
        let near = |d: f64| s.pdf(&wo, &(-wo + t * d).normalize());
        assert!(near(1e-9) > 50.0 * near(1e-7), "{spec}: no peak at −ωo");
    }
    let phong = AnalyticSampler::new(brdf("phong").as_ref()).unwrap();
    assert_eq!(phong.singular_directions(&wo), vec![mirror(&wo)]);
    let lambert = AnalyticSampler::new(brdf("lambert").as_ref()).unwrap();
    assert!(lambert.singular_directions(&wo).is_empty());
}
