//! [`DirectionSampler`] for [`ExactSet`].

use brdf::{Brdf, Vec3};
use partition_sampler::{Audit, Sampler2D, UniformSource};

use crate::direction_sampler::{DirSample, DirectionSampler, EvalSample, SamplerDiagnostics};

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
            None => DirSample {
                wi: Vec3::new(0.0, 0.0, 1.0),
                pdf: 0.0,
            },
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
