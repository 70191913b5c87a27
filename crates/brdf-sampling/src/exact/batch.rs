//! The coherent batch path of the exact sampler
//! ([`DirectionSampler::sample_eval_batch`](crate::DirectionSampler::sample_eval_batch)):
//! N queries located first, grouped by interval with a counting sort, and each group drawn in
//! turn, so an interval's tree, alias table and normaliser stay in cache for its group instead
//! of being fetched again for every query when ωo changes from pixel to pixel.

use brdf::{Brdf, Vec3};
use partition_sampler::{Audit, UniformSource};

use super::fused::IsoQuery;
use super::{ExactSet, Query};
use crate::EvalSample;

/// A query located by the isotropic fast path or the general one.
enum Located {
    Iso(IsoQuery),
    General(Query),
}

impl ExactSet {
    /// Index of every interval of the set in one list: `offsets[cell] + interval`.
    fn interval_offsets(&self) -> Vec<usize> {
        let mut offsets = Vec::with_capacity(self.cells.len() + 1);
        let mut total = 0;
        for c in &self.cells {
            offsets.push(total);
            total += c.intervals.len();
        }
        offsets.push(total);
        offsets
    }

    /// The batch path: `out[k]` for `wos[k]`. Queries are located, counted per interval and
    /// served group by group in the order of the intervals (queries of one interval in the
    /// caller's order); the uniforms are consumed in that order. Queries at or below the
    /// horizon get [`EvalSample::NONE`] and consume nothing. Each sample is drawn by the
    /// one-query path's code ([`ExactSet::draw_iso`] or [`ExactSet::draw_located`]), so its
    /// law is the same.
    pub(super) fn sample_eval_grouped(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut Vec<EvalSample>,
    ) {
        out.clear();
        out.resize(wos.len(), EvalSample::NONE);
        let offsets = self.interval_offsets();
        let groups = offsets[offsets.len() - 1];
        // Isotropic queries by the fast path's locate (`ExactSet::locate_iso`), the others
        // (anisotropic, grazing) by the general one.
        let located: Vec<Option<(Located, usize)>> = wos
            .iter()
            .map(|wo| match self.locate_iso(wo) {
                Some(q) => Some((Located::Iso(q), q.interval)),
                None => self
                    .locate(wo)
                    .map(|q| (Located::General(q), offsets[q.cell] + q.interval)),
            })
            .collect();
        // Counting sort of the located queries by interval (stable).
        let mut start = vec![0usize; groups + 1];
        for (_, g) in located.iter().flatten() {
            start[g + 1] += 1;
        }
        for g in 0..groups {
            start[g + 1] += start[g];
        }
        let mut order = vec![0usize; start[groups]];
        for (k, l) in located.iter().enumerate() {
            if let Some((_, g)) = l {
                order[start[*g]] = k;
                start[*g] += 1;
            }
        }
        let mut audit = Audit::default();
        for &k in &order {
            let Some((q, _)) = &located[k] else {
                continue;
            };
            let wo = &wos[k];
            out[k] = match q {
                Located::Iso(q) => {
                    let (s, f) = self.draw_iso(q, wo, u, &mut audit);
                    self.finish_iso(brdf, wo, s, f)
                }
                Located::General(q) => {
                    let (s, f) = self.draw_located(q, wo, u, &mut audit);
                    self.finish(brdf, wo, s, f)
                }
            };
        }
        self.counters.record(&audit);
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use brdf::{Brdf, Vec3, parse_spec};
    use partition_sampler::UniformSource;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    use crate::{DirectionSampler, EvalSample, ExactOptions, ExactSet};

    fn batch(set: &ExactSet, brdf: &dyn Brdf, wos: &[Vec3], seed: u64) -> Vec<EvalSample> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut out = vec![EvalSample::NONE; 3];
        set.sample_eval_batch(brdf, wos, &mut rng, &mut out);
        out
    }

    /// Every output belongs to its own query (caller's order): its pdf is the set's pdf at
    /// that query's ωo and its `f` the BRDF there; the batch is a function of the seed; and a
    /// query at or below the horizon gets the empty sample. Then the law: a batch that
    /// alternates two outgoing angles in different intervals gives, per angle, a mean cos θi
    /// within 5 standard errors of its exact value (two-sided, α ≈ 6e-7 per angle).
    #[test]
    fn batch_outputs_follow_their_own_query_in_order_with_the_one_query_law() {
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec("phong:n=200").unwrap());
        let set = ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
        let mut qr = Xoshiro256PlusPlus::seed_from_u64(8);
        let wos: Vec<Vec3> = (0..3000)
            .map(|k| match k % 100 {
                0 => brdf::direction_from_angles(95.0, 10.0),
                1 => brdf::direction_from_angles(89.995, 10.0),
                _ => {
                    brdf::direction_from_angles(89.0 * qr.next_uniform(), 360.0 * qr.next_uniform())
                }
            })
            .collect();
        let out = batch(&set, brdf.as_ref(), &wos, 4);
        assert_eq!(out.len(), wos.len());
        assert_eq!(out, batch(&set, brdf.as_ref(), &wos, 4));
        assert_ne!(out, batch(&set, brdf.as_ref(), &wos, 5));
        for (k, (wo, s)) in wos.iter().zip(&out).enumerate() {
            if wo.z <= 0.0 {
                assert_eq!(*s, EvalSample::NONE);
                continue;
            }
            assert!(s.pdf > 0.0 && s.wi.z > 0.0, "query {k}: {s:?}");
            approx::assert_relative_eq!(s.pdf, set.pdf(wo, &s.wi), max_relative = 1e-9);
            approx::assert_relative_eq!(s.f, brdf.eval(wo, &s.wi), max_relative = 1e-12);
        }

        let angles = [13.37, 71.9];
        let dirs = angles.map(|t| brdf::direction_from_angles(t, 20.0));
        let wos: Vec<Vec3> = (0..40_000).map(|k| dirs[k % 2]).collect();
        let out = batch(&set, brdf.as_ref(), &wos, 9);
        for (j, wo) in dirs.iter().enumerate() {
            let xs: Vec<f64> = out.iter().skip(j).step_by(2).map(|s| s.wi.z).collect();
            let n = xs.len() as f64;
            let mean = xs.iter().sum::<f64>() / n;
            let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let cos2 = crate::reference::albedo_of(
                |wo, wi| brdf.eval(wo, wi) * wi.z,
                brdf.as_ref(),
                wo,
                crate::REFERENCE_BUDGET,
            )
            .unwrap()
            .value;
            let a = crate::reference_albedo(brdf.as_ref(), wo).unwrap().value;
            let z = (mean - cos2 / a) / (var / n).sqrt();
            assert!(z.abs() < 5.0, "θo {}: mean {mean}, z = {z}", angles[j]);
        }
    }
}
