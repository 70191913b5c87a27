//! Rejection against *another* density under a built tree's leaf bounds.
//!
//! A tree built for an envelope density `F` (for instance the maximum of a family of densities
//! `g_t` over a parameter interval) bounds every member: `g_t(x) ≤ F(x) ≤ M_i` on leaf `i`.
//! Choosing a leaf ∝ `V_i = area_i · M_i`, a point uniform in its rejection rectangle and
//! accepting it when `z · M_i < g(x)` (`z` uniform in `[0, 1)`) gives accepted points of density
//! exactly `g / ∫ g` on the union of sampleable leaves, whatever `F` was, as long as `g ≤ M_i`
//! holds; every trial with `g(x) > M_i` is counted as a bound violation. The mean number of
//! trials is `Σ V_i / ∫ g`.

use super::QuadTreeSampler;
use crate::LeafChoice;
use crate::audit::{Audit, record_one};
use crate::contract::{Point2, UniformSource};
use crate::density::RegionStats;

impl<D: RegionStats> QuadTreeSampler<D> {
    /// Adds one [`Self::draw_envelope_of`] call's counts to the sampler's statistics the way
    /// a plain `sample()` does: trials and samples buffered per thread, violations and
    /// exhaustion at once ([`crate::diagnostics::AuditedDraws::record_one_sample`]).
    #[inline]
    pub(crate) fn add_one_sample(&self, audit: &Audit) {
        record_one(&self.counters, audit);
    }

    /// One sample of the density `g / ∫ g` (w.r.t. area on the tree's domain) by envelope
    /// rejection under this tree's leaf bounds (leaf ∝ `V_i` with the tree's leaf choice, which
    /// must be the envelope scheme's alias or descent tables over `V_i`; see the module docs).
    /// Returns the accepted point and `g` there, or `None` after
    /// [`crate::MAX_TRIALS_PER_SAMPLE`] trials (counted as exhausted). Trials, violations
    /// (`g(x) > M_i`) and the sample are counted in `audit` only.
    ///
    /// `g` is called only at points inside the domain (inside the unit circle for disc trees).
    /// Public as [`crate::diagnostics::AuditedDraws::sample_envelope_of`].
    pub(crate) fn draw_envelope_of<G, U>(
        &self,
        g: &G,
        u: &mut U,
        audit: &mut Audit,
    ) -> Option<(Point2, f64)>
    where
        G: Fn(Point2) -> f64 + ?Sized,
        U: UniformSource + ?Sized,
    {
        let start = audit.trials;
        let alias =
            self.tree.params.leaf_choice == LeafChoice::Alias && !self.tree.leaves.is_empty();
        loop {
            if audit.trials - start >= crate::MAX_TRIALS_PER_SAMPLE {
                audit.exhausted += 1;
                audit.samples += 1;
                return None;
            }
            // The leaf pick's uniform and the trial's three, in this order; with the alias
            // table (one uniform per pick) in one call (one dynamic call per trial).
            let (leaf, us) = if alias {
                let us = u.next_uniform4();
                (self.alias_leaf(us[0]), [us[1], us[2], us[3]])
            } else {
                let Some(leaf) = self.pick_leaf(u) else {
                    audit.trials += 1;
                    continue;
                };
                (leaf, [u.next_uniform(), u.next_uniform(), u.next_uniform()])
            };
            let s = f64::from(leaf.u0) + us[0] * f64::from(leaf.du);
            let t = f64::from(leaf.v0) + us[1] * f64::from(leaf.dv);
            let (x, y) = if self.identity {
                (s, t)
            } else {
                (self.frame.domain_coord(0, s), self.frame.domain_coord(1, t))
            };
            let m = leaf.bound(self.bound_scale);
            let z = us[2] * m;
            audit.trials += 1;
            if self.disc && x * x + y * y >= 1.0 {
                continue;
            }
            let f = g([x, y]);
            if f > m {
                audit.violations += 1;
            }
            if z < f {
                audit.samples += 1;
                return Some(([x, y], f));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::diagnostics::AuditedDraws;
    use crate::{Audit, QuadTreeBuilder, Sampler2D, TabulatedDensity};
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    /// Envelope `F(x, y) = 1 + x` on [0,1]²; member `g = 1 + x·t` for t = 0.3 integrates to
    /// 1.15, its x-marginal mean is ∫x(1 + 0.3x) / 1.15 = (0.5 + 0.1)/1.15.
    #[test]
    fn samples_the_member_not_the_envelope() {
        let n = 64;
        let vals: Vec<f64> = (0..n * n)
            .map(|k| 1.0 + ((k % n) as f64 + 0.5) / n as f64)
            .collect();
        let d = TabulatedDensity::new(n, n, vals, crate::Rect::new(0.0, 0.0, 1.0, 1.0)).unwrap();
        let s = QuadTreeBuilder::new().build(d).unwrap();
        let g = |p: [f64; 2]| 1.0 + 0.3 * p[0];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let mut a = Audit::default();
        let k = 200_000;
        let mean = (0..k)
            .map(|_| s.sample_envelope_of(&g, &mut rng, &mut a).unwrap().0[0])
            .sum::<f64>()
            / k as f64;
        let expect = 0.6 / 1.15;
        // Standard deviation of x under g is < 0.3: 6σ of the mean is < 0.004.
        assert!((mean - expect).abs() < 0.004, "{mean} vs {expect}");
        // The envelope's own mean differs by 0.035: the test tells them apart.
        assert!((mean - (1.0 / 3.0 + 0.5) / 1.5).abs() > 0.02);
        assert_eq!(a.violations, 0);
        assert_eq!(a.samples, k as u64);
        // Mean trials Σ V_i / ∫ g ≈ 1.5 / 1.15 (the envelope's own trials were ≈ 1).
        let trials = a.trials as f64 / k as f64;
        assert!(
            (trials - s.stats().expected_mean_trials * 1.5 / 1.15).abs() < 0.02,
            "{trials}"
        );
        let _ = s.pdf([0.5, 0.5]);
    }

    #[test]
    fn a_member_above_the_bounds_is_counted() {
        let d = TabulatedDensity::new(4, 4, vec![1.0; 16], crate::Rect::new(0.0, 0.0, 1.0, 1.0))
            .unwrap();
        let s = QuadTreeBuilder::new().build(d).unwrap();
        let g = |_: [f64; 2]| 2.0;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut a = Audit::default();
        for _ in 0..100 {
            s.sample_envelope_of(&g, &mut rng, &mut a).unwrap();
        }
        assert_eq!(a.violations, a.trials);
        assert_eq!(a.trials, 100);
    }
}
