//! Locating a query (cell, interval, rotation) and drawing one direction.

use brdf::{Vec3, direction_from_radians};
use partition_sampler::diagnostics::AuditedDraws;
use partition_sampler::{Audit, UniformSource};

use crate::direction_sampler::DirSample;
use crate::layout::Turn;

use super::density::QueryDensity;
use super::grid::TableVar;
use super::interval::{Interval, Query};
use super::options::THETA_TOP_DEG;
use super::set::ExactSet;
use super::table::{LeafTable, query_theta};
use super::walk::{rem_period, round_index};

impl ExactSet {
    /// The tabulated normaliser `A(θo, δ) = ∫ f_r(ωo, ·) cos θi dσ` used by the pdf at `wo`
    /// (`None` below the horizon).
    pub fn normaliser(&self, wo: &Vec3) -> Option<f64> {
        let q = self.locate(wo)?;
        Some(self.normaliser_of(&q))
    }

    /// The pdf's normaliser at a located query: the interval's table for isotropic sets, the
    /// interval's record of patches over the query's keys for anisotropic ones
    /// ([`AnisoRecord::normaliser`](super::aniso_record::AnisoRecord::normaliser)).
    #[inline]
    pub(super) fn normaliser_of(&self, q: &Query) -> f64 {
        if self.isotropic {
            return self.interval(q).normaliser(self.var, q);
        }
        let c = &self.cells[q.cell];
        c.aniso[q.interval].normaliser(q.keys[0], q.keys[1], q.cos, &c.patches)
    }

    pub(super) fn interval(&self, q: &Query) -> &Interval {
        &self.cells[q.cell].intervals[q.interval]
    }

    /// The compact table a located query draws from (`None`: the interval's tree): its
    /// interval's [`LeafTable`], or the table of the θo layer serving the query
    /// ([`LeafTable::serving`] at θo = [`query_theta`]`(cos θo)`; for an isotropic `θo`-table
    /// set that is the query's table variable, the same bits).
    #[inline]
    pub(super) fn table_of(&self, q: &Query) -> Option<&LeafTable> {
        let table = self.cells[q.cell].tables[q.interval].as_ref()?;
        if self.isotropic && self.var == TableVar::Theta {
            // `locate`'s `var` is `cos.acos()` with `cos = q.cos ∈ (0, 1]`: `query_theta`'s.
            debug_assert!(q.var.to_bits() == query_theta(q.cos).to_bits());
            Some(table.serving(q.var))
        } else {
            Some(table.serving_cos(q.cos))
        }
    }

    /// Cell, interval, θo, δ and rotation of `wo`; `None` at or below the horizon.
    #[inline]
    pub(super) fn locate(&self, wo: &Vec3) -> Option<Query> {
        self.locate_with::<true>(wo)
    }

    /// [`ExactSet::locate`] for drawing: the same query, but an anisotropic one without its
    /// angles `θo` and `δ` (NaN; drawing and the normaliser need only the keys, issue 29).
    #[inline]
    pub(super) fn locate_keys(&self, wo: &Vec3) -> Option<Query> {
        self.locate_with::<false>(wo)
    }

    /// [`ExactSet::locate`] (`ANGLES`) or [`ExactSet::locate_keys`].
    #[inline]
    fn locate_with<const ANGLES: bool>(&self, wo: &Vec3) -> Option<Query> {
        if !(wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite()) {
            return None;
        }
        let mut served = *wo;
        if wo.z < self.top_cos {
            // f_r at grazing θo may diverge (1/cos θo factors) where no bound node was put:
            // serve the direction at `top` (same azimuth) instead, so that the bounds hold and
            // the pdf stays normalised; the law differs from f_r(ωo, ·) cos θi only there.
            let top = THETA_TOP_DEG.to_radians();
            let (s, r) = (top.sin(), (wo.x * wo.x + wo.y * wo.y).sqrt());
            served = Vec3::new(wo.x / r * s, wo.y / r * s, self.top_cos);
        }
        let wo = &served;
        let cos = wo.z.min(1.0);
        // `dkey`: the strip search's azimuth key (`tan δ` or `δ`, `Cell::by_tan`).
        let (cell, turn, delta, dkey) = if self.isotropic {
            // The rotation that takes the frame's ωo (at φ = 0) to the query's, without
            // trigonometry: (cos φo, sin φo) = (x, y)/r.
            let r = (wo.x * wo.x + wo.y * wo.y).sqrt();
            let turn = Turn::of_azimuth(wo, r);
            (0, turn, 0.0, 0.0)
        } else if let Some(found) = super::walk::cell_offset(
            wo,
            self.period,
            self.cells[0].tan_half,
            |k| self.cells[k].phi_turn,
            self.cells.len(),
        ) {
            let (k, turn, tan) = found;
            let delta = if ANGLES {
                super::walk::atan_halved(tan)
            } else {
                f64::NAN
            };
            (k, turn, delta, tan)
        } else {
            let phi = wo.y.atan2(wo.x);
            let n = self.cells.len();
            let step = self.period / n as f64;
            let k = round_index(rem_period(phi, self.period) / step) % n;
            let rot = phi - self.cells[k].phi;
            let mut delta = rem_period(rot, self.period);
            if delta > 0.5 * self.period {
                delta -= self.period;
            }
            let turn = super::walk::turn_from_cell(wo, self.cells[k].phi_turn);
            let dkey = if self.cells[k].by_tan {
                turn.sin / turn.cos
            } else {
                delta
            };
            (k, turn, delta, dkey)
        };
        let var = match self.var {
            TableVar::Cos => cos,
            // Anisotropic sets: θo without `acos` (`walk::theta_of`; within a few ulp), and
            // only when asked for (the normaliser takes `√(1 − cos θo)`).
            TableVar::Theta if !self.isotropic => {
                if ANGLES {
                    super::walk::theta_of(cos, (wo.x * wo.x + wo.y * wo.y).sqrt())
                } else {
                    f64::NAN
                }
            }
            TableVar::Theta => cos.acos(),
        };
        let c = &self.cells[cell];
        let interval = if self.isotropic {
            c.interval_of(c.search_key(cos, var), dkey)
        } else {
            c.interval_direct(c.search_key(cos, var), dkey)
        };
        let keys = if self.isotropic {
            [0.0; 2]
        } else {
            [(1.0 - cos).sqrt(), dkey]
        };
        Some(Query {
            keys,
            cell,
            interval,
            wo: served,
            var,
            cos,
            delta,
            turn,
        })
    }

    /// One direction; `audit` receives the trials.
    #[inline]
    pub(super) fn draw(
        &self,
        wo: &Vec3,
        u: &mut dyn UniformSource,
        audit: &mut Audit,
    ) -> Option<DirSample> {
        if let Some(q) = self.locate_iso(wo) {
            return Some(self.draw_iso(&q, wo, u, audit).0);
        }
        self.draw_with_f(wo, u, audit).map(|(s, _)| s)
    }

    /// [`ExactSet::draw`] and the `f_r` of the accepted trial, evaluated in the interval's
    /// frame at the served `ωo` (`None` when no trial was accepted or the query was served
    /// at another `ωo`, above [`THETA_TOP_DEG`]).
    #[inline]
    pub(super) fn draw_with_f(
        &self,
        wo: &Vec3,
        u: &mut dyn UniformSource,
        audit: &mut Audit,
    ) -> Option<(DirSample, Option<f64>)> {
        let q = self.locate_keys(wo)?;
        Some(self.draw_located(&q, wo, u, audit))
    }

    /// [`ExactSet::draw_with_f`] at a query already located (`q = self.locate(wo)`).
    #[inline]
    pub(super) fn draw_located(
        &self,
        q: &Query,
        wo: &Vec3,
        u: &mut dyn UniformSource,
        audit: &mut Audit,
    ) -> (DirSample, Option<f64>) {
        let q = *q;
        let iv = self.interval(&q);
        let g = QueryDensity::in_frame(self.brdf.as_ref(), self.isotropic, &q.wo, q.turn, iv.map);
        let drawn = match self.table_of(&q) {
            Some(table) => table.draw(&|p| g.at(p), u, audit),
            None => iv.tree.sample_envelope_of(&|p| g.at(p), u, audit),
        };
        match drawn {
            Some((x, gx)) => {
                let a = self.normaliser_of(&q);
                let (s, f) = super::fused::accepted(iv.map, &q.turn, x, gx, a);
                let served = q.wo == *wo;
                (s, (served && f.is_finite()).then_some(f))
            }
            None => (DirSample::NONE, None),
        }
    }

    /// Draws `per_interval` samples at outgoing directions uniform in every interval (θ
    /// and φ uniform in the interval's ranges) on the calling thread, and counts trials,
    /// BRDF evaluations, violations and exhausted samples (also added to the trees' counts).
    pub fn measure_cost(&self, per_interval: usize, seed: u64) -> crate::CostMeasurement {
        use rand::SeedableRng;
        let before = crate::disc::thread_evaluations();
        let mut total = Audit::default();
        let mut index = 0u64;
        for c in &self.cells {
            for iv in &c.intervals {
                let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(
                    partition_sampler::chunk_seed(seed, index),
                );
                index += 1;
                let ([lo, hi], [da, db]) = (iv.theta, iv.delta);
                let mut a = Audit::default();
                for _ in 0..per_interval {
                    let theta = lo + rng.next_uniform() * (hi - lo);
                    let phi = if self.isotropic {
                        0.0
                    } else {
                        c.phi + da + rng.next_uniform() * (db - da)
                    };
                    let wo = direction_from_radians(theta, phi);
                    let _ = self.draw(&wo, &mut rng, &mut a);
                }
                iv.tree.record_audit(&a);
                total.merge(&a);
            }
        }
        crate::CostMeasurement {
            samples: total.samples,
            trials: total.trials,
            evaluations: crate::disc::thread_evaluations() - before,
            violations: total.violations,
            exhausted: total.exhausted,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{rem_period, round_index};
    use proptest::prelude::*;

    /// Bit for bit `rem_euclid`, also at the edges (`±p`, `±2p`, signed zeros, NaN).
    fn same_as_rem_euclid(x: f64, p: f64) -> Result<(), TestCaseError> {
        let (got, want) = (rem_period(x, p), x.rem_euclid(p));
        prop_assert!(
            got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
            "{x} mod {p}: {got:e} vs {want:e}"
        );
        Ok(())
    }

    proptest! {
        #[test]
        fn rem_period_is_rem_euclid(x in -30.0f64..30.0, p in 0.1f64..7.0) {
            same_as_rem_euclid(x, p)?;
        }

        #[test]
        fn round_index_is_round(t in 0.0f64..1e6, k in 0u32..1000) {
            prop_assert_eq!(round_index(t), t.round() as usize);
            let half = f64::from(k) + 0.5;
            for h in [half, half.next_down(), half.next_up()] {
                prop_assert_eq!(round_index(h), h.round() as usize, "{}", h);
            }
        }
    }

    #[test]
    fn rem_period_at_the_edges() {
        use std::f64::consts::{PI, TAU};
        for p in [PI, TAU, PI / 2.0, 0.3] {
            for x in [
                0.0,
                -0.0,
                p,
                -p,
                2.0 * p,
                -2.0 * p,
                p.next_up(),
                p.next_down(),
                -p.next_up(),
                -p.next_down(),
                (2.0 * p).next_down(),
                -(2.0 * p).next_down(),
                1e-300,
                -1e-300,
                PI,
                -PI,
                f64::NAN,
                1e20,
                -1e20,
            ] {
                same_as_rem_euclid(x, p).unwrap();
            }
        }
        assert_eq!(round_index(f64::NAN), 0);
        assert_eq!(round_index(0.49999999999999994), 0);
    }
}
