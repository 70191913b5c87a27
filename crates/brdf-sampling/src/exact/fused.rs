//! The fused sample-and-evaluate of the exact sampler ([`DirectionSampler::sample_eval`]):
//! the accepted rejection trial already evaluated `f_r(ωo, ωi)`, so the estimator's `f` is
//! returned with the sample instead of being evaluated again.
//!
//! [`DirectionSampler::sample_eval`]: crate::DirectionSampler::sample_eval

use brdf::{Brdf, Vec3};

use super::ExactSet;
use crate::{DirSample, EvalSample};

impl ExactSet {
    /// The [`EvalSample`] of a drawn sample `s` at `wo`, with `f` the accepted trial's value
    /// from [`ExactSet::draw_with_f`]: that value when `brdf` is the set's own BRDF object,
    /// otherwise one evaluation of `brdf`; 0 for a sample that contributes nothing.
    #[inline]
    pub(super) fn finish(
        &self,
        brdf: &dyn Brdf,
        wo: &Vec3,
        s: DirSample,
        f: Option<f64>,
    ) -> EvalSample {
        let f = if !(s.pdf > 0.0 && s.wi.z > 0.0) {
            0.0
        } else {
            match f {
                Some(f) if same_brdf(brdf, self.brdf.as_ref()) => f,
                _ => brdf.eval(wo, &s.wi),
            }
        };
        EvalSample {
            wi: s.wi,
            pdf: s.pdf,
            f,
        }
    }
}

/// True when `a` and `b` are the same BRDF object: same address **and** same vtable (a
/// wrapper struct may share its first field's address). A false "no" (one type with two
/// vtables, from two codegen units) only costs the caller one evaluation; zero-sized BRDFs
/// are never taken as the same (distinct zero-sized values may share an address).
#[inline]
pub(super) fn same_brdf(a: &dyn Brdf, b: &dyn Brdf) -> bool {
    std::mem::size_of_val(a) != 0 && std::ptr::eq(a as *const dyn Brdf, b as *const dyn Brdf)
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use brdf::{Brdf, Vec3, parse_spec};
    use partition_sampler::UniformSource;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    use crate::{DirectionSampler, ExactOptions, ExactSet};

    // The counting wrapper (`eval`, `eval_rgb` and `eval_prepared` on the calling thread).
    use brdf::CountingBrdf as Counted;
    use brdf::thread_evaluations as evals;

    /// Outgoing directions of the test: random θo up to past the served top (89.99°), a few
    /// at and below the horizon.
    fn query(i: usize, rng: &mut Xoshiro256PlusPlus) -> Vec3 {
        let phi = 360.0 * rng.next_uniform();
        let theta = match i % 50 {
            0 => 89.995,
            1 => 90.0,
            2 => 95.0,
            _ => 89.999 * rng.next_uniform(),
        };
        brdf::direction_from_angles(theta, phi)
    }

    fn set_of(spec: &str) -> (Arc<dyn Brdf>, ExactSet) {
        let model: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let brdf: Arc<dyn Brdf> = Arc::new(Counted(model));
        let mut opts = ExactOptions::default();
        if !brdf.is_isotropic() {
            // A small anisotropic build: this test needs samples, not a tight envelope or an
            // accurate normaliser.
            opts.max_trials = 8.0;
            opts.normaliser_tol = 1e-3;
            opts.initial_phi_cells = 4;
        }
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
        (brdf, set)
    }

    /// `sample_eval` draws the very samples of `sample` (same uniforms consumed, same `ωi` and
    /// pdf bits), returns `f_r(ωo, ωi)` to rounding (the accepted trial's value, evaluated in
    /// the interval's frame; the served grazing queries and the query's own BRDF when it is
    /// another object: one evaluation), and evaluates the set's own BRDF no more often than
    /// `sample` does — the estimator's evaluation is saved.
    #[test]
    fn sample_eval_returns_the_accepted_trials_f_with_the_same_samples() {
        for spec in ["phong:n=50", "ward:alpha_x=0.2,alpha_y=0.4"] {
            let (brdf, set) = set_of(spec);
            // The compact tables draw what the trees' own walks draw (`table.rs`).
            assert!(
                super::super::table::walks::assert_table_walks_match_trees(&set) >= 2 * set.len()
            );
            let other: Arc<dyn Brdf> = Arc::new(Counted(Arc::from(parse_spec(spec).unwrap())));
            let (mut r1, mut r2, mut r3) = (
                Xoshiro256PlusPlus::seed_from_u64(5),
                Xoshiro256PlusPlus::seed_from_u64(5),
                Xoshiro256PlusPlus::seed_from_u64(5),
            );
            let mut qr = Xoshiro256PlusPlus::seed_from_u64(6);
            let (mut e_plain, mut e_fused, mut e_other) = (0, 0, 0);
            let (mut contributing, mut grazing) = (0u64, 0u64);
            let top_cos = crate::exact::THETA_TOP_DEG.to_radians().cos();
            for i in 0..4000 {
                let wo = query(i, &mut qr);
                let before = evals();
                let s = set.sample(&wo, &mut r1);
                e_plain += evals() - before;
                let before = evals();
                let f = set.sample_eval(brdf.as_ref(), &wo, &mut r2);
                e_fused += evals() - before;
                let before = evals();
                let o = set.sample_eval(other.as_ref(), &wo, &mut r3);
                e_other += evals() - before;
                assert_eq!((s.wi, s.pdf), (f.wi, f.pdf), "{spec} ωo {wo:?}");
                assert_eq!((o.wi, o.pdf), (f.wi, f.pdf), "{spec} ωo {wo:?}");
                let live = s.pdf > 0.0 && s.wi.z > 0.0;
                contributing += u64::from(live);
                grazing += u64::from(live && wo.z < top_cos);
                let exact = if live { brdf.eval(&wo, &s.wi) } else { 0.0 };
                approx::assert_relative_eq!(f.f, exact, max_relative = 1e-12);
                // Another object of the same model is evaluated at `ωi`: exactly `eval`.
                assert_eq!(o.f, exact, "{spec} ωo {wo:?}");
                if !live {
                    assert_eq!(f.f, 0.0);
                }
            }
            // The streams stayed in step.
            let next = r1.next_uniform();
            assert_eq!(next, r2.next_uniform());
            assert_eq!(next, r3.next_uniform());
            // Only the grazing queries (served at THETA_TOP_DEG) pay an evaluation.
            assert!(grazing > 0);
            assert_eq!(
                e_fused,
                e_plain + grazing,
                "{spec}: evaluations fused vs sampling only"
            );
            // Another object of the same model: the estimator's evaluation, always.
            assert_eq!(e_other, e_plain + contributing, "{spec}");
            assert!(contributing > 3800, "{spec}: {contributing}");
        }
    }
}
