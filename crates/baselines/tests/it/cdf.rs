//! The tabulated and cascade CDF samplers on analytic models (isotropic and anisotropic) and on
//! MERL-layout data: normalisation, sample/pdf agreement, unbiasedness, determinism, the
//! χ² test against the reported pdf and a deliberately broken variant it must reject.

use std::f64::consts::TAU;

use baselines::cdf::{GridShape, SliceCdf, TabulatedSlice};
use baselines::{CascadeCdf, CdfOptions, CdfOptionsError, TabulatedCdf};
use brdf::{Brdf, MerlBrdf, Vec3, direction_from_angles, parse_spec};
use brdf_sampling::{DirectionSampler, SamplerDiagnostics};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Small tables so that the tests stay fast.
fn small() -> CdfOptions {
    CdfOptions {
        slices: 8,
        anisotropic_slices: [6, 4],
        n_z: 32,
        n_phi: 64,
        supersampling: 2,
        ..CdfOptions::default()
    }
}

fn models() -> Vec<(String, Box<dyn Brdf>)> {
    [
        "lambert",
        "phong:n=50",
        "ward:alpha_x=0.08,alpha_y=0.3",
        "ggx:alpha=0.1,alpha_y=0.4",
        "strauss",
    ]
    .iter()
    .map(|s| (s.to_string(), parse_spec(s).unwrap()))
    .collect()
}

fn both(brdf: &dyn Brdf, o: &CdfOptions) -> [(&'static str, Box<dyn DirectionSampler>); 2] {
    [
        (
            "tabulated",
            Box::new(TabulatedCdf::build(brdf, o).unwrap()) as Box<dyn DirectionSampler>,
        ),
        ("cascade", Box::new(CascadeCdf::build(brdf, o).unwrap())),
    ]
}

/// `∫ pdf dω` by the midpoint rule on a `k n_z × k n_φ` grid in `(z, φ)` (dz dφ = dω).
fn integral(s: &dyn DirectionSampler, wo: &Vec3, nz: usize, nphi: usize) -> f64 {
    let mut sum = 0.0;
    for a in 0..nz {
        let z = (a as f64 + 0.5) / nz as f64;
        let r = (1.0 - z * z).sqrt();
        for b in 0..nphi {
            let phi = (b as f64 + 0.5) * TAU / nphi as f64;
            sum += s.pdf(wo, &Vec3::new(r * phi.cos(), r * phi.sin(), z));
        }
    }
    sum * TAU / (nz * nphi) as f64
}

#[test]
fn pdf_integrates_to_one_on_every_model_and_angle() {
    let o = small();
    for (spec, brdf) in models() {
        for (name, s) in both(brdf.as_ref(), &o) {
            for (theta, phi) in [(0.0, 0.0), (40.0, 0.0), (60.0, 33.0), (89.0, 200.0)] {
                let wo = direction_from_angles(theta, phi);
                let i = integral(s.as_ref(), &wo, 4 * o.n_z, 4 * o.n_phi);
                assert!(
                    (i - 1.0).abs() < 2e-3,
                    "{name} {spec} θo {theta}: ∫ pdf = {i}"
                );
            }
        }
    }
}

#[test]
fn samples_are_unit_upper_and_report_the_pdf_of_pdf() {
    let o = small();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    for (spec, brdf) in models() {
        for (name, s) in both(brdf.as_ref(), &o) {
            for (theta, phi) in [(0.0, 0.0), (30.0, 120.0), (85.0, 290.0), (89.0, 10.0)] {
                let wo = direction_from_angles(theta, phi);
                for _ in 0..5000 {
                    let d = s.sample(&wo, &mut rng);
                    assert!((d.wi.norm() - 1.0).abs() < 1e-12 && d.wi.z > 0.0);
                    assert!(d.pdf > 0.0 && d.pdf.is_finite());
                    let p = s.pdf(&wo, &d.wi);
                    assert!(
                        (p - d.pdf).abs() <= 1e-9 * d.pdf,
                        "{name} {spec} θo {theta}: sample pdf {} vs pdf {p}",
                        d.pdf
                    );
                }
            }
        }
    }
}

#[test]
fn estimator_of_the_albedo_is_unbiased() {
    // E[f cos / p] = ∫ f cos dω; 200k samples, within 4 standard errors of the quadrature.
    let o = small();
    for (spec, brdf) in models() {
        for (name, s) in both(brdf.as_ref(), &o) {
            for theta in [10.0, 70.0] {
                let wo = direction_from_angles(theta, 45.0);
                let reference = brdf::directional_albedo(brdf.as_ref(), &wo, 256, 512);
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
                let n = 200_000;
                let (mut m, mut m2) = (0.0, 0.0);
                for _ in 0..n {
                    let d = s.sample(&wo, &mut rng);
                    let w = brdf.eval(&wo, &d.wi) * d.wi.z / d.pdf;
                    m += w;
                    m2 += w * w;
                }
                let mean = m / n as f64;
                let se = ((m2 / n as f64 - mean * mean) / n as f64).sqrt();
                assert!(
                    (mean - reference).abs() < 4.0 * se + 1e-4 * reference,
                    "{name} {spec} θo {theta}: {mean} ± {se} vs {reference}"
                );
            }
        }
    }
}

#[test]
fn a_cascade_with_a_vanishing_tolerance_is_the_tabulated_cdf() {
    // ε below rounding keeps every point off a straight line; the points it drops are
    // collinear, so every slope (density) is unchanged.
    let brdf = parse_spec("phong:n=80").unwrap();
    let o = CdfOptions {
        epsilon: 1e-14,
        ..small()
    };
    let t = TabulatedCdf::build(brdf.as_ref(), &o).unwrap();
    let c = CascadeCdf::build(brdf.as_ref(), &o).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
    let wo = direction_from_angles(35.0, 10.0);
    for _ in 0..20_000 {
        let d = c.sample(&wo, &mut rng);
        let (pt, pc) = (t.pdf(&wo, &d.wi), c.pdf(&wo, &d.wi));
        assert!((pt - pc).abs() <= 1e-9 * pt, "{pt} vs {pc}");
    }
}

#[test]
fn compression_shrinks_as_epsilon_grows_and_reports_add_up() {
    let brdf = parse_spec("phong:n=50").unwrap();
    let mut last = f64::INFINITY;
    for e in [1e-4, 1e-3, 1e-2] {
        let o = CdfOptions {
            epsilon: e,
            ..small()
        };
        let c = CascadeCdf::build(brdf.as_ref(), &o).unwrap();
        let r = c.report();
        assert_eq!(r.epsilon, Some(e));
        assert_eq!(
            r.fine_points,
            8 * GridShape { n_z: 32, n_phi: 64 }.cdf_points()
        );
        assert!(r.compression_ratio() < last, "{}", r.summary());
        assert!(r.bytes > 0 && r.bytes == c.bytes_used());
        assert_eq!(r.grid_evaluations, 8 * 32 * 64 * 4);
        last = r.compression_ratio();
    }
    let t = TabulatedCdf::build(brdf.as_ref(), &small()).unwrap();
    assert_eq!(t.report().compression_ratio(), 1.0);
    assert_eq!(t.report().epsilon, None);
    assert!(t.bytes_used() >= 8 * t.report().fine_points);
}

#[test]
fn the_build_does_not_depend_on_the_thread_count() {
    let brdf = parse_spec("ward:alpha_x=0.1,alpha_y=0.25").unwrap();
    let o = small();
    let serial =
        distributions::on_threads(1, || CascadeCdf::build(brdf.as_ref(), &o).unwrap()).unwrap();
    let parallel = CascadeCdf::build(brdf.as_ref(), &o).unwrap();
    assert_eq!(serial.layout(), parallel.layout());
    assert!(serial.layout().half_turn && serial.layout().phi == 2);
    for i in 0..serial.layout().len() {
        assert_eq!(serial.slice(i), parallel.slice(i));
    }
}

#[test]
fn merl_layout_data_are_sampled_consistently_and_normalised() {
    let phong = parse_spec("phong:n=30,ks=0.6,kd=0.3").unwrap();
    let merl = MerlBrdf::tabulate(phong.as_ref());
    assert!(merl.unmeasured_count() > 0);
    let o = small();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
    for (name, s) in both(&merl, &o) {
        for theta in [0.0, 45.0, 80.0] {
            let wo = direction_from_angles(theta, 0.0);
            let i = integral(s.as_ref(), &wo, 4 * o.n_z, 4 * o.n_phi);
            assert!((i - 1.0).abs() < 2e-3, "{name} θo {theta}: ∫ pdf = {i}");
            for _ in 0..5000 {
                let d = s.sample(&wo, &mut rng);
                assert!((s.pdf(&wo, &d.wi) - d.pdf).abs() <= 1e-9 * d.pdf);
            }
        }
    }
}

#[test]
fn out_of_range_options_are_typed_errors() {
    let brdf = parse_spec("lambert").unwrap();
    let bad = CdfOptions {
        epsilon: -1.0,
        ..CdfOptions::default()
    };
    assert!(matches!(
        CascadeCdf::build(brdf.as_ref(), &bad),
        Err(CdfOptionsError::Epsilon(_))
    ));
    let bad = CdfOptions {
        n_z: 0,
        ..CdfOptions::default()
    };
    assert!(matches!(
        TabulatedCdf::build(brdf.as_ref(), &bad),
        Err(CdfOptionsError::Grid { what: "n_z", .. })
    ));
    let huge = CdfOptions {
        slices: 1024,
        n_z: 4096,
        n_phi: 4096,
        ..CdfOptions::default()
    };
    assert!(matches!(
        TabulatedCdf::build(brdf.as_ref(), &huge),
        Err(CdfOptionsError::TooLarge { .. })
    ));
}

/// The samples of `sampler` and the p-value of Pearson's χ² against `claimed`'s pdf on a
/// 16 × 32 histogram over `(z, φ)` (expected masses by an 8 × 8 midpoint rule per bin).
fn chi_square_p(
    sampler: &dyn DirectionSampler,
    claimed: &dyn DirectionSampler,
    wo: &Vec3,
    n: usize,
    seed: u64,
) -> f64 {
    let (bz, bp, q) = (16, 32, 8);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut observed = vec![0u64; bz * bp];
    for _ in 0..n {
        let d = sampler.sample(wo, &mut rng);
        let a = ((d.wi.z * bz as f64) as usize).min(bz - 1);
        let phi = d.wi.y.atan2(d.wi.x).rem_euclid(TAU);
        let b = ((phi / TAU * bp as f64) as usize).min(bp - 1);
        observed[a * bp + b] += 1;
    }
    let cell = TAU / (bz * bp * q * q) as f64;
    let mut expected = vec![0.0; bz * bp];
    for a in 0..bz * q {
        let z = (a as f64 + 0.5) / (bz * q) as f64;
        let r = (1.0 - z * z).sqrt();
        for b in 0..bp * q {
            let phi = (b as f64 + 0.5) * TAU / (bp * q) as f64;
            let p = claimed.pdf(wo, &Vec3::new(r * phi.cos(), r * phi.sin(), z));
            expected[(a / q) * bp + b / q] += p * cell * n as f64;
        }
    }
    stats::chi_square_gof(&observed, &expected, stats::DEFAULT_MIN_EXPECTED)
        .unwrap()
        .p_value
}

/// A broken cascade: samples from the compressed CDFs, but reports the **uncompressed**
/// table's pdf (baselines.md §B.5's first pitfall).
struct UncompressedPdf {
    cascade: CascadeCdf,
    table: TabulatedCdf,
}

impl DirectionSampler for UncompressedPdf {
    fn sample(
        &self,
        wo: &Vec3,
        u: &mut dyn partition_sampler::UniformSource,
    ) -> brdf_sampling::DirSample {
        let mut d = self.cascade.sample(wo, u);
        d.pdf = self.table.pdf(wo, &d.wi);
        d
    }
    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.table.pdf(wo, wi)
    }
    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for UncompressedPdf {}

#[test]
fn chi_square_accepts_the_cascade_and_rejects_the_uncompressed_pdf() {
    let brdf = parse_spec("phong:n=50").unwrap();
    let o = CdfOptions {
        epsilon: 1e-2,
        ..small()
    };
    let wo = direction_from_angles(30.0, 0.0);
    let cascade = CascadeCdf::build(brdf.as_ref(), &o).unwrap();
    let broken = UncompressedPdf {
        cascade: CascadeCdf::build(brdf.as_ref(), &o).unwrap(),
        table: TabulatedCdf::build(brdf.as_ref(), &o).unwrap(),
    };
    let n = 300_000;
    let good = chi_square_p(&cascade, &cascade, &wo, n, 21);
    assert!(good > 1e-3, "the correct cascade was rejected: p = {good}");
    let bad = chi_square_p(&broken, &broken, &wo, n, 21);
    assert!(bad < 1e-8, "the broken variant was accepted: p = {bad}");
    // And the uncompressed table passes against its own pdf.
    let table = TabulatedCdf::build(brdf.as_ref(), &o).unwrap();
    let p = chi_square_p(&table, &table, &wo, n, 22);
    eprintln!(
        "χ² p-values: cascade {good:.3e}, broken (uncompressed pdf) {bad:.3e}, tabulated {p:.3e}"
    );
    assert!(p > 1e-3, "the tabulated CDF was rejected: p = {p}");
}

#[test]
fn slices_are_usable_on_their_own() {
    // The slice API: a slice built from explicit values samples ∝ those values.
    let shape = GridShape { n_z: 2, n_phi: 2 };
    let s = TabulatedSlice::build(&[1.0, 3.0, 0.0, 4.0], shape, &CdfOptions::default());
    // Cell (0, 1) holds 3/8 of the mass on an area of (1/2)(π): density 3/(4π).
    let p = s.pdf(shape, 0.25, 4.0);
    assert!((p - 3.0 / (4.0 * std::f64::consts::PI)).abs() < 1e-12);
}
