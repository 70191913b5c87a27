//! Leaf bounds per (θo, δ) sub-box of an anisotropic interval (issue 29: fewer trials on
//! anisotropic Ward at random `ωo`, docs/benchmarks.md §28.1).
//!
//! # Math
//! An interval `[θ_a, θ_b] × [δ_a, δ_b]` of an anisotropic cell holds one tree whose leaf
//! bounds `M_i` hold for **every** outgoing direction of the interval: they come from the
//! envelope `F = max_n g_n` of the query densities at its bound nodes (a uniform grid of θ × δ
//! nodes), sampled by the image map with its rim band and the peak track of the members'
//! mirror directions, times the safety factor (`build_interval.rs`). A query at `(θo, δ)` is
//! far below `M_i` on most leaves away from its own lobe (docs/benchmarks.md §27.2: 1.92
//! trials per sample on Ward's default set, 1.34 with tight per-query leaf bounds).
//!
//! The interval is cut at its middle bound nodes into [`SUB_THETA`] × [`SUB_DELTA`] closed
//! sub-boxes `[θ_a, θ_s] × [δ_a, δ_s]`, …, `[θ_s, θ_b] × [δ_s, δ_b]` (`θ_s`, `δ_s`: the
//! middle θ and δ nodes, so each sub-box's corners are bound nodes). For sub-box `s` the
//! bound of leaf `i` is
//!
//! `M_i^s = min(M_i, ⌈region(F_s, leaf_i)⌉_f32)`
//!
//! where `F_s` is the envelope of the interval's bound nodes **inside** the sub-box (its
//! corners and the nodes on its edges) and `region` is the build's own bound of a rectangle
//! (`SliceImageMap`: the image map of `F_s` with its rim band and the peak track of the members
//! `(θ, δ)` of the sub-box, times the safety factor; `crate::image_map`). It is a bound of the
//! query density on leaf `i` for every query of the sub-box **in the same sense as `M_i` is
//! for the interval**: the same construction, over the nodes that span the sub-box (their
//! spacing is the interval's, so the envelope's dips between them are the ones the interval's
//! safety factor already covers), and the peak track of the sub-box's members (65 θo × the
//! interval's δ track inside it, denser than the interval's); the minimum with `M_i` keeps
//! whichever of the two valid bounds is lower. Every trial above its bound is still counted by
//! the audit ([`crate::SamplerDiagnostics::bound_violations`]; tested with many queries per
//! sub-box in `sub_box_bounds_hold_and_cut_the_trials`).
//!
//! A query picks its sub-box by its keys (`w = √(1 − cos θo)` against `w(θ_s)`, the strip key
//! `tan δ` or `δ` against that of `δ_s`; a query on a split belongs to both sub-boxes, so either
//! side is right) and draws from that sub-box's table: the alias table over the same leaves
//! with weights `area_i · M_i^s` and the rejection test `u · M_i^s < g`. The accepted point has
//! density `g / ∫ g` whatever the bounds, so the law is unchanged; which samples are drawn
//! changes (other tables). Expected trials at a query of sub-box `s`: `Σ_i area_i M_i^s / A`.
//!
//! The bounds are computed once per kept interval after the layout is final (in parallel) and
//! saved with the set (`persist.rs`, format version 2: 4 `f32` per leaf).

use super::interval::Interval;
use super::table::LeafTable;

/// Sub-boxes of an interval along θo.
pub(super) const SUB_THETA: usize = 2;
/// Sub-boxes of an interval along δ.
pub(super) const SUB_DELTA: usize = 2;
/// Sub-boxes per interval; sub-box `(iθ, iδ)` is number `iθ · SUB_DELTA + iδ`.
pub(super) const SUBS: usize = SUB_THETA * SUB_DELTA;

/// The sampling tables of one anisotropic interval's sub-boxes and where a query's keys fall.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SubTables {
    /// The grid key `w = √(1 − cos θ_s)` of the θ split and the strip key (`tan δ_s` or `δ_s`)
    /// of the δ split.
    split: [f64; 2],
    /// One table per sub-box ([`SUBS`], numbered as there).
    tables: Box<[LeafTable; SUBS]>,
}

impl SubTables {
    /// The tables of `iv` from its stored sub-box bounds (`iv.sub_bounds`, [`SUBS`] runs of one
    /// `f32` per leaf), with the δ split keyed as the cell's strip search (`tan δ` when
    /// `by_tan`); `None` when the interval has none or a table cannot be made.
    pub(super) fn of(iv: &Interval, by_tan: bool) -> Option<Self> {
        let n = iv.tree.tree().leaves().len();
        if n == 0 || iv.sub_bounds.len() != SUBS * n {
            return None;
        }
        let [theta_s, delta_s] = iv.sub_split;
        if !(theta_s.is_finite() && delta_s.is_finite()) {
            return None;
        }
        let mut tables = Vec::with_capacity(SUBS);
        for s in 0..SUBS {
            tables.push(LeafTable::with_bounds(
                &iv.tree,
                Some(&iv.sub_bounds[s * n..(s + 1) * n]),
            )?);
        }
        let tables: Box<[LeafTable; SUBS]> = tables.into_boxed_slice().try_into().ok()?;
        Some(Self {
            split: [
                super::aniso_record::w_of_theta(theta_s),
                if by_tan { delta_s.tan() } else { delta_s },
            ],
            tables,
        })
    }

    /// The sub-box of a query with grid keys `keys = [w, d]` (see [`SubTables::split`]).
    #[inline(always)]
    pub(super) fn sub_of(&self, keys: &[f64; 2]) -> usize {
        let t = usize::from(SUB_THETA > 1 && keys[0] > self.split[0]);
        let d = usize::from(SUB_DELTA > 1 && keys[1] > self.split[1]);
        t * SUB_DELTA + d
    }

    /// The table a query with grid keys `keys` draws from.
    #[inline(always)]
    pub(super) fn table(&self, keys: &[f64; 2]) -> &LeafTable {
        &self.tables[self.sub_of(keys)]
    }

    /// Bytes of the tables.
    pub(super) fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>() + self.tables.iter().map(LeafTable::bytes_used).sum::<usize>()
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use brdf::{Brdf, parse_spec};
    use partition_sampler::{Audit, UniformSource};
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    use super::*;
    use crate::exact::density::QueryDensity;
    use crate::{ExactOptions, ExactSet};

    /// The sub-box bounds hold, and cut the trials: on a quick anisotropic Ward build (narrow
    /// cells, splits in θ and δ), every interval has its four sub-box tables, each leaf's
    /// sub-box bound is at most its interval bound, and at 16 queries per sub-box (its four
    /// corners, 10⁻⁹ rad inside, where the bounds are tightest, and 12 random ones) 200 samples
    /// each drawn by the set's own path (`draw`: the sub-box's table by the query's keys)
    /// count **no trial above its leaf's bound** (the violation counter of the audit) and take
    /// fewer trials than the interval's own table at the same queries (below 0.85 of them),
    /// as the tables' volumes say (`Σ area_i M_i^s < Σ area_i M_i` in every sub-box).
    #[test]
    fn sub_box_bounds_hold_and_cut_the_trials() {
        let spec = "ward:alpha_x=0.12,alpha_y=0.3";
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let opts = ExactOptions {
            max_trials: 8.0,
            normaliser_tol: 1e-3,
            min_width_deg: 2.0,
            ..ExactOptions::default()
        };
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
        assert!(set.cells.iter().all(|c| c.by_tan));
        let top = super::super::THETA_TOP_DEG.to_radians();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let (mut sub, mut plain) = (Audit::default(), Audit::default());
        let (mut sub_volume, mut volume) = (0.0, 0.0);
        let mut queries = 0;
        for c in &set.cells {
            for (i, iv) in c.intervals.iter().enumerate() {
                let subs = c.subs[i].as_ref().expect("every interval has sub-boxes");
                assert!(
                    c.tables[i].is_none(),
                    "the interval's own table is not kept"
                );
                let leaves: Vec<_> = iv.tree.tree().leaves().collect();
                let n = leaves.len();
                let own = LeafTable::of(&iv.tree).unwrap();
                let [ts, ds] = iv.sub_split;
                let (ta, tb) = (iv.theta[0], iv.theta[1].min(top));
                let [da, db] = iv.delta;
                assert!(
                    ta < ts && ts < tb && da < ds && ds < db,
                    "{iv:?}",
                    iv = iv.theta
                );
                for s in 0..SUBS {
                    let b = &iv.sub_bounds[s * n..(s + 1) * n];
                    let mut v = (0.0, 0.0);
                    for (l, &m) in leaves.iter().zip(b) {
                        assert!(m >= 0.0 && f64::from(m) <= l.max_bound);
                        let area = l.rect.width() * l.rect.height();
                        v.0 += area * f64::from(m);
                        v.1 += area * l.max_bound;
                    }
                    assert!(v.0 < v.1, "interval {i}, sub-box {s}: {v:?}");
                    sub_volume += v.0;
                    volume += v.1;
                    let range = |k: usize, n: usize, lo: f64, at: f64, hi: f64| match (n, k) {
                        (1, _) => (lo, hi),
                        (_, 0) => (lo, at),
                        _ => (at, hi),
                    };
                    let (t0, t1) = range(s / SUB_DELTA, SUB_THETA, ta, ts, tb);
                    let (d0, d1) = range(s % SUB_DELTA, SUB_DELTA, da, ds, db);
                    let eps = 1e-9;
                    let corners = [(t0, d0), (t0, d1), (t1, d0), (t1, d1)].map(|(t, d)| {
                        (
                            t.clamp(t0 + eps, t1 - eps).max(eps),
                            d.clamp(d0 + eps, d1 - eps),
                        )
                    });
                    let random: Vec<(f64, f64)> = (0..12)
                        .map(|_| {
                            (
                                t0 + (t1 - t0) * rng.next_uniform(),
                                d0 + (d1 - d0) * rng.next_uniform(),
                            )
                        })
                        .collect();
                    for (t, d) in corners.into_iter().chain(random) {
                        let wo = brdf::direction_from_radians(t, c.phi + d);
                        let q = set.locate_keys(&wo).unwrap();
                        assert_eq!(
                            (&set.cells[q.cell] as *const _, q.interval),
                            (c as *const _, i)
                        );
                        assert_eq!(subs.sub_of(&q.keys), s, "θ {t}, δ {d}");
                        let g = QueryDensity::in_frame(brdf.as_ref(), false, &wo, q.turn, iv.map);
                        for _ in 0..200 {
                            set.draw(&wo, &mut rng, &mut sub).unwrap();
                            own.draw(&|p| g.at(p), &mut rng, &mut plain);
                        }
                        queries += 1;
                    }
                }
            }
        }
        assert!(queries >= 16 * 4 * 8, "{queries} queries");
        assert_eq!(sub.violations, 0, "{sub:?}");
        assert_eq!(sub.exhausted, 0, "{sub:?}");
        assert_eq!(plain.violations, 0, "{plain:?}");
        let ratio = sub.trials as f64 / plain.trials as f64;
        assert!(
            ratio < 0.85,
            "trials {} vs {} ({ratio})",
            sub.trials,
            plain.trials
        );
        assert!(sub_volume < 0.85 * volume, "{sub_volume} vs {volume}");
    }
}
