//! Invariants under random outgoing directions, uniforms and incident directions (proptest):
//! samples lie on the upper unit hemisphere with pdf > 0 equal to `pdf(wo, wi)`; `pdf ≥ 0`,
//! `pdf = 0` below the horizon, and `pdf > 0` wherever `f_r cos > 0` for BRDFs whose support
//! is the whole hemisphere for every `ωo` (so the slice approximation keeps full support).

use crate::common;

use std::sync::OnceLock;

use brdf::{Vec3, direction_from_angles};
use brdf_sampling::{DirectionSampler, QuadTreeSet, Variant};
use common::*;
use partition_sampler::UniformSequence;
use proptest::prelude::*;

const SPECS: [&str; 4] = ["lambert", "phong:n=50", "ggx:alpha=0.1", "oren-nayar"];

fn sets() -> &'static Vec<QuadTreeSet> {
    static SETS: OnceLock<Vec<QuadTreeSet>> = OnceLock::new();
    SETS.get_or_init(|| {
        let mut v = Vec::new();
        for spec in SPECS {
            v.push(build(spec, Variant::Adaptive, &test_options()));
            v.push(build(spec, Variant::Paper, &test_options()).with_mixture(true));
        }
        v.push(build(
            "ward:alpha_x=0.08,alpha_y=0.3",
            Variant::Adaptive,
            &test_options(),
        ));
        v
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn samples_are_on_the_upper_hemisphere_with_consistent_pdf(
        k in 0usize..9,
        theta in 0.0f64..89.9,
        phi in 0.0f64..360.0,
        us in proptest::collection::vec(0.0f64..1.0, 64),
    ) {
        let set = &sets()[k];
        let wo = direction_from_angles(theta, phi);
        let mut u = UniformSequence::new(&us);
        let s = set.sample(&wo, &mut u);
        prop_assert!(s.pdf > 0.0);
        prop_assert!(s.wi.z > 0.0 && (s.wi.norm() - 1.0).abs() < 1e-12);
        let p = set.pdf(&wo, &s.wi);
        prop_assert!((p - s.pdf).abs() <= 1e-9 * p.max(s.pdf), "{} vs {}", p, s.pdf);
    }

    #[test]
    fn pdf_is_nonnegative_and_covers_the_support(
        k in 0usize..9,
        theta in 0.0f64..89.9,
        phi in 0.0f64..360.0,
        ti in 0.0f64..90.0,
        pi in 0.0f64..360.0,
    ) {
        let set = &sets()[k];
        let wo = direction_from_angles(theta, phi);
        let wi = direction_from_angles(ti, pi);
        let p = set.pdf(&wo, &wi);
        prop_assert!(p >= 0.0 && p.is_finite());
        if set.brdf().eval(&wo, &wi) * wi.z > 0.0 {
            prop_assert!(p > 0.0, "f cos > 0 but pdf = 0 at wi = {:?}", wi);
        }
        let below = Vec3::new(wi.x, wi.y, -wi.z);
        prop_assert_eq!(set.pdf(&wo, &below), 0.0);
        // Below-horizon outgoing directions: no density.
        prop_assert_eq!(set.pdf(&Vec3::new(wo.x, wo.y, -wo.z.max(1e-3)), &wi), 0.0);
    }
}
