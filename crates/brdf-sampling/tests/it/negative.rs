//! The statistical checks must reject deliberately broken samplers (α = 1e-4, fixed seeds):
//! a pdf evaluated on the neighbouring slice, a pdf without the cosine conversion, a pdf that
//! forgets the azimuthal rotation, and leaf bounds that are too low (coarse image map, no
//! safety factor). The honest sampler passes the same checks.

use crate::common;

use brdf::Vec3;
use brdf_sampling::{
    DirSample, DirectionSampler, QuadTreeSet, SamplerDiagnostics, SetOptions, SliceChoice, Variant,
};
use common::*;
use partition_sampler::UniformSource;

/// How a broken wrapper misreports the pdf.
#[derive(Clone, Copy)]
enum Bug {
    NeighbourSlice,
    NoCosine,
    NoRotation,
}

struct Broken<'a> {
    set: &'a QuadTreeSet,
    bug: Bug,
}

impl DirectionSampler for Broken<'_> {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let s = self.set.sample(wo, u);
        DirSample {
            wi: s.wi,
            pdf: self.pdf(wo, &s.wi),
        }
    }
    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some(c) = self.set.layout().nearest(wo) else {
            return 0.0;
        };
        match self.bug {
            Bug::NeighbourSlice => {
                let n = SliceChoice {
                    index: c.index + 1,
                    ..c
                };
                self.set.slice_area_pdf(&n, wi) * wi.z
            }
            Bug::NoCosine => self.set.slice_area_pdf(&c, wi),
            Bug::NoRotation => {
                self.set.slice_area_pdf(
                    &SliceChoice {
                        rotation: brdf_sampling::Turn::IDENTITY,
                        ..c
                    },
                    wi,
                ) * wi.z
            }
        }
    }
    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for Broken<'_> {}

#[test]
fn broken_pdfs_are_rejected_and_the_honest_one_passes() {
    let set = build("phong:n=50", Variant::Adaptive, &test_options());
    // θo = 33°: nearest slice 35°, neighbour 45°; φo = 37°.
    let wo = wo_at(33.0);
    let honest = draw(&set, &wo, 20_000, 5);
    let r = chi_square(&honest, &|w| set.pdf(&wo, w));
    assert!(
        r.p_value >= ALPHA,
        "honest sampler rejected: {}",
        r.summary()
    );
    for (bug, name) in [
        (Bug::NeighbourSlice, "neighbour slice"),
        (Bug::NoCosine, "no cosine"),
        (Bug::NoRotation, "no rotation"),
    ] {
        let b = Broken { set: &set, bug };
        let samples = draw(&b, &wo, 20_000, 5);
        let r = chi_square(&samples, &|w| b.pdf(&wo, w));
        println!("{name}: {}", r.summary());
        assert!(r.p_value < ALPHA, "{name} not detected: {}", r.summary());
    }
}

/// A narrow retro-reflection lobe (peak at `ωi = ωo`, away from the mirror direction that the
/// image map samples explicitly) over a weak diffuse floor.
struct Retro;

impl brdf::Brdf for Retro {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        0.02 + 40.0 * (-(wi - wo).norm_squared() / 0.004).exp()
    }
    fn is_isotropic(&self) -> bool {
        true
    }
}

#[test]
fn bounds_too_low_are_audited_and_rejected() {
    // A 8 × 8 image map without safety factor cannot see a narrow retro-reflection lobe: the
    // leaf bounds are too low, the audit counts violations and the samples follow min(f, M).
    let opts = SetOptions {
        slices: 9,
        grid: 8,
        safety_factor: 1.0,
        ..SetOptions::default().with_depth(2)
    };
    let retro: std::sync::Arc<dyn brdf::Brdf> = std::sync::Arc::new(Retro);
    let set = QuadTreeSet::build(retro.clone(), Variant::Adaptive, &opts).unwrap();
    let wo = wo_at(35.0);
    let samples = draw(&set, &wo, 20_000, 9);
    let rep = set.report();
    assert!(rep.bound_violations > 0, "{rep}");
    let r = chi_square(&samples, &|w| set.pdf(&wo, w));
    assert!(
        r.p_value < ALPHA,
        "too-low bounds not detected: {}",
        r.summary()
    );
    // The defaults on the same BRDF and direction: no violation, test passes.
    let good = QuadTreeSet::build(retro, Variant::Adaptive, &test_options()).unwrap();
    let samples = draw(&good, &wo, 20_000, 9);
    assert_eq!(good.report().bound_violations, 0);
    let r = chi_square(&samples, &|w| good.pdf(&wo, w));
    assert!(r.p_value >= ALPHA, "{}", r.summary());
}
