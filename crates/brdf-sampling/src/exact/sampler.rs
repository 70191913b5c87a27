//! [`DirectionSampler`] for [`ExactSet`].

use brdf::{Brdf, Vec3};
use partition_sampler::{Audit, Sampler2D, UniformSource};

use crate::direction_sampler::{DirSample, DirectionSampler, EvalSample, SamplerDiagnostics};

use super::fused::same_brdf;
use super::interval::Interval;
use super::layout::Cell;
use super::set::ExactSet;

impl DirectionSampler for ExactSet {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let mut a = Audit::default();
        if let Some(q) = self.locate_iso(wo) {
            let (s, _) = self.draw_iso(&q, wo, u, &mut a);
            self.counters.record(&a);
            return s;
        }
        match self.draw(wo, u, &mut a) {
            Some(s) => {
                self.counters.record(&a);
                s
            }
            None => DirSample::NONE,
        }
    }

    /// The accepted trial's `f` when `brdf` is the set's own BRDF object and the query was
    /// served at its own `ωo` (θo ≤ [`THETA_TOP_DEG`]); otherwise one evaluation of `brdf`.
    fn sample_eval(&self, brdf: &dyn Brdf, wo: &Vec3, u: &mut dyn UniformSource) -> EvalSample {
        let mut a = Audit::default();
        if let Some(q) = self.locate_iso(wo) {
            let (s, f) = self.draw_iso(&q, wo, u, &mut a);
            self.counters.record(&a);
            return self.finish_iso(brdf, wo, s, f);
        }
        let Some((s, f)) = self.draw_with_f(wo, u, &mut a) else {
            return EvalSample::NONE;
        };
        self.counters.record(&a);
        self.finish(brdf, wo, s, f)
    }

    /// `true`: the accepted trial evaluated `f` (see [`Self::sample_eval`]).
    fn fuses_eval(&self) -> bool {
        true
    }

    /// Queries grouped by interval (a counting sort), each group drawn while its tree is
    /// hot; see [`ExactSet::sample_eval_grouped`].
    fn sample_eval_batch(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut Vec<EvalSample>,
    ) {
        if !self.isotropic {
            return self.sample_eval_aniso(brdf, wos, u, out);
        }
        self.sample_eval_grouped(brdf, wos, u, out);
    }

    /// `f_r(ωo, ωi) cos θi / A(θo, δ)` above the horizon, 0 below.
    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let Some(q) = self.locate(wo) else {
            return 0.0;
        };
        let a = self.normaliser_of(&q);
        self.brdf.eval(&q.wo, wi) * wi.z / a
    }

    /// [`DirectionSampler::pdf`] at every `wi`, `ωo` located once.
    fn pdf_many(&self, wo: &Vec3, wi: &[Vec3]) -> Vec<f64> {
        let Some(q) = self.locate(wo) else {
            return vec![0.0; wi.len()];
        };
        let a = self.normaliser_of(&q);
        wi.iter()
            .map(|w| {
                if w.z > 0.0 {
                    self.brdf.eval(&q.wo, w) * w.z / a
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// `f cos θi / A(θo, δ)` with the caller's `f` when `brdf` is the set's own BRDF object and
    /// the query is served at its own `ωo` (θo ≤ [`THETA_TOP_DEG`]): the pdf's value with no
    /// evaluation (bit for bit when `f = brdf.eval(wo, wi)`); otherwise [`Self::pdf`].
    fn pdf_given_f(&self, brdf: &dyn Brdf, wo: &Vec3, wi: &Vec3, f: f64) -> f64 {
        self.pdf_many_given_f(brdf, wo, std::slice::from_ref(wi), std::slice::from_ref(&f))[0]
    }

    /// [`Self::pdf_given_f`] at every `wi`, `ωo` located once; [`Self::pdf_many`] when `brdf`
    /// is not the set's own object, the query is served at another `ωo` or the lengths differ.
    fn pdf_many_given_f(&self, brdf: &dyn Brdf, wo: &Vec3, wi: &[Vec3], f: &[f64]) -> Vec<f64> {
        if f.len() != wi.len() || !same_brdf(brdf, self.brdf.as_ref()) {
            return self.pdf_many(wo, wi);
        }
        let Some(q) = self.locate(wo) else {
            return vec![0.0; wi.len()];
        };
        if q.wo != *wo {
            return self.pdf_many(wo, wi);
        }
        let a = self.normaliser_of(&q);
        wi.iter()
            .zip(f)
            .map(|(w, &f)| if w.z > 0.0 { f * w.z / a } else { 0.0 })
            .collect()
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + self
                .cells
                .iter()
                .map(|c| {
                    std::mem::size_of::<Cell>()
                        + c.upper.capacity() * 8
                        + std::mem::size_of_val(c.iso.as_slice())
                        + std::mem::size_of_val(c.aniso.as_slice())
                        + std::mem::size_of_val(c.patches.as_slice())
                        + c.direct_bytes()
                        + c.tables
                            .iter()
                            .flatten()
                            .map(|t| t.bytes_used())
                            .sum::<usize>()
                        + c.intervals
                            .iter()
                            .map(|iv| {
                                std::mem::size_of::<Interval>()
                                    + iv.tree.bytes_used()
                                    + iv.table.bytes_used()
                            })
                            .sum::<usize>()
                })
                .sum::<usize>()
    }
}

impl SamplerDiagnostics for ExactSet {
    fn bound_violations(&self) -> Option<u64> {
        let trees: u64 = self
            .cells
            .iter()
            .flat_map(|c| c.intervals.iter())
            .map(|iv| iv.tree.stats().bound_violations)
            .sum();
        Some(trees + self.counters.snapshot().violations)
    }

    fn normaliser_rel_err(&self, wo: &Vec3) -> Option<f64> {
        let q = self.locate(wo)?;
        Some(self.interval(&q).norm_err)
    }

    /// The [`ExactReport`]: the interval layout per azimuth cell, trials, normaliser error,
    /// audit, build cost and memory.
    fn build_report(&self) -> Option<String> {
        Some(self.report().to_string())
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use brdf::{Brdf, CountingBrdf, Vec3, parse_spec, thread_evaluations};
    use partition_sampler::UniformSource;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    use crate::{DirectionSampler, ExactOptions, ExactSet};

    /// `spec`'s set built with a counting wrapper of the model (the object a caller's `f`
    /// must come from); a small anisotropic build.
    fn set_of(spec: &str) -> (Arc<dyn Brdf>, ExactSet) {
        let model: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let brdf: Arc<dyn Brdf> = Arc::new(CountingBrdf(model));
        let mut opts = ExactOptions::default();
        if !brdf.is_isotropic() {
            opts.max_trials = 8.0;
            opts.normaliser_tol = 1e-3;
            opts.initial_phi_cells = 4;
        }
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
        (brdf, set)
    }

    /// The pdf from a known `f` (issue 29, MIS light samples) is the pdf bit for bit: for the
    /// set's own BRDF object and `f = brdf.eval(ωo, ωi)`, `pdf_given_f` and
    /// `pdf_many_given_f` (and the located-once `pdf_many`) equal `pdf` at every `(ωo, ωi)`
    /// — random θo up to past the served top (89.99°, where the pdf is `f` at the *served*
    /// `ωo` and the caller's `f` must not be used), at and below the horizon, `ωi` on the
    /// whole sphere — and `pdf_many_given_f` evaluates nothing where the query is served at
    /// its own `ωo`. Another object of the same model, or a wrong `f`, falls back to the
    /// evaluation / changes the value (the override trusts only its own object's `f`).
    #[test]
    fn the_pdf_given_f_is_the_pdf_bit_for_bit_and_evaluates_nothing() {
        for spec in [
            "phong:n=50",
            "ggx:alpha=0.2",
            "ward:alpha_x=0.12,alpha_y=0.3",
        ] {
            let (brdf, set) = set_of(spec);
            let other: Arc<dyn Brdf> = Arc::new(CountingBrdf(Arc::from(parse_spec(spec).unwrap())));
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(41);
            let mut served = 0usize;
            for i in 0..400 {
                let theta = match i % 40 {
                    0 => 89.995,
                    1 => 89.9999,
                    2 => 90.0,
                    3 => 95.0,
                    _ => 89.99 * rng.next_uniform(),
                };
                let wo = brdf::direction_from_angles(theta, 360.0 * rng.next_uniform());
                let wis: Vec<Vec3> = (0..24)
                    .map(|j| {
                        let t = if j % 6 == 0 { 100.0 } else { 90.0 } * rng.next_uniform();
                        brdf::direction_from_angles(t, 360.0 * rng.next_uniform())
                    })
                    .collect();
                let fs: Vec<f64> = wis.iter().map(|wi| brdf.eval(&wo, wi)).collect();
                let want: Vec<u64> = wis.iter().map(|wi| set.pdf(&wo, wi).to_bits()).collect();
                let bits = |v: Vec<f64>| v.into_iter().map(f64::to_bits).collect::<Vec<_>>();
                let before = thread_evaluations();
                let given = set.pdf_many_given_f(brdf.as_ref(), &wo, &wis, &fs);
                let evals = thread_evaluations() - before;
                assert_eq!(bits(given), want, "{spec}: pdf_many_given_f at {wo:?}");
                let one: Vec<f64> = wis
                    .iter()
                    .zip(&fs)
                    .map(|(wi, &f)| set.pdf_given_f(brdf.as_ref(), &wo, wi, f))
                    .collect();
                assert_eq!(bits(one), want, "{spec}: pdf_given_f at {wo:?}");
                assert_eq!(bits(set.pdf_many(&wo, &wis)), want, "{spec}: pdf_many");
                let foreign = set.pdf_many_given_f(other.as_ref(), &wo, &wis, &fs);
                assert_eq!(bits(foreign), want, "{spec}: another object's f");
                if theta < 89.99 {
                    served += 1;
                    assert_eq!(evals, 0, "{spec}: {evals} evaluations at {wo:?}");
                    // A wrong f is taken as given for the own object (so the test above is
                    // not vacuous): the value moves.
                    let wrong: Vec<f64> = fs.iter().map(|f| 1.5 * f).collect();
                    let moved = set.pdf_many_given_f(brdf.as_ref(), &wo, &wis, &wrong);
                    assert!(
                        moved.iter().zip(&want).any(|(a, b)| a.to_bits() != *b),
                        "{spec}: a wrong f left the pdf unchanged at {wo:?}"
                    );
                }
            }
            assert!(served > 300, "{spec}: {served} served queries");
        }
    }
}
