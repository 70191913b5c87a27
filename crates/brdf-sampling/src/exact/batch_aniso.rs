//! The batch path of anisotropic sets (issue 29 item 1:
//! [`DirectionSampler::sample_eval_batch`](crate::DirectionSampler::sample_eval_batch) on
//! anisotropic BRDFs at random `ωo`).
//!
//! The law and the samples are those of [`ExactSet::sample_eval_grouped`] (the general batch
//! path): the queries are located by [`ExactSet::locate_keys`]'s arithmetic, counting-sorted by
//! interval (the set's list, `cell` then `interval`; the caller's order within one) and drawn
//! in that order by [`ExactSet::draw_located`]'s arithmetic — so from the same uniforms the
//! same bits. What differs is the bookkeeping: one 48-byte record per query ([`Located`]:
//! the normaliser grid's keys, `cos θo`, the rotation and the interval) instead of the general
//! path's 112-byte `Option<(batch::Located, usize)>`, the normaliser and the trials' density made
//! from it directly, and a query's whole `Query` rebuilt only when it was served at another
//! `ωo` (above [`THETA_TOP_DEG`](super::THETA_TOP_DEG)). As there, consecutive queries with
//! the same `ωo` bits (a pixel's samples) are located once, and such a run's density and
//! normaliser are made once.

use brdf::{Brdf, Vec3};
use partition_sampler::diagnostics::AuditedDraws;
use partition_sampler::{Audit, UniformSource};

use super::ExactSet;
use super::density::QueryDensity;
use super::fused::accepted;
use crate::layout::Turn;
use crate::{DirSample, EvalSample};

/// A located anisotropic query, as its draw reads it: the normaliser grid's keys
/// `w = √(1 − cos θo)` and the strip key (`tan δ` or `δ`), `cos θo`, the rotation from the
/// interval's frame to the world's, and the interval (its cell and index in the cell).
#[derive(Debug, Clone, Copy)]
struct Located {
    keys: [f64; 2],
    cos: f64,
    turn: Turn,
    cell: u32,
    interval: u32,
}

/// The group of a query that is not served (at or below the horizon, not finite).
const UNSERVED: u32 = u32::MAX;

/// The flag of a query that continues its predecessor's run (the same `ωo` bits), on its
/// group and on its entry of the serving order (whose other bits are the query's index).
const FOLLOWS: u32 = 1 << 31;

/// Most queries of one pass (their indices below [`FOLLOWS`]).
const MAX_PASS: usize = (FOLLOWS - 1) as usize;

/// Most azimuth cells this path serves (the options allow 64 per turn).
const MAX_CELLS: usize = 64;

/// The anisotropic batch path's working arrays, kept per thread between calls (no allocation
/// and no zero-filled buffer per call once a thread has served a batch of the size).
#[derive(Default)]
struct Scratch {
    /// Per query, its location (written before it is read; never cleared).
    located: Vec<Located>,
    /// Per query, its group with its run flag (see [`FOLLOWS`]), or [`UNSERVED`].
    group: Vec<u32>,
    /// The counting sort's bucket starts (then ends) per group.
    count: Vec<u32>,
    /// The serving order: query indices with their run flags.
    order: Vec<u32>,
}

thread_local! {
    /// This thread's [`Scratch`], taken for the length of a batch (a nested batch on the
    /// same thread finds none and makes its own).
    static SCRATCH: std::cell::Cell<Option<Box<Scratch>>> = const { std::cell::Cell::new(None) };
}

/// The bits of a direction: the queries of one run share them.
#[inline]
fn bits(wo: &Vec3) -> [u64; 3] {
    [wo.x.to_bits(), wo.y.to_bits(), wo.z.to_bits()]
}

impl ExactSet {
    /// The batch path of an anisotropic set: `out[k]` for `wos[k]`, the samples of
    /// [`ExactSet::sample_eval_grouped`] bit for bit (see the module docs). A query's `f` is
    /// its accepted trial's when `brdf` is the set's own object and the query was served at its
    /// own `ωo`; a query at or below the horizon gets [`EvalSample::NONE`] and consumes no
    /// uniform.
    pub(super) fn sample_eval_aniso(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut Vec<EvalSample>,
    ) {
        debug_assert!(!self.isotropic);
        out.clear();
        out.resize(wos.len(), EvalSample::NONE);
        // Passes of at most `MAX_PASS` queries: a query index and its run flag share a `u32`.
        if wos.len() > MAX_PASS {
            let mut part = Vec::new();
            for (k, chunk) in wos.chunks(MAX_PASS).enumerate() {
                self.sample_eval_aniso(brdf, chunk, u, &mut part);
                out[k * MAX_PASS..k * MAX_PASS + chunk.len()].copy_from_slice(&part);
            }
            return;
        }
        // This thread's working arrays (none when a batch is nested on the thread: fresh ones).
        let mut scratch = SCRATCH.with(std::cell::Cell::take).unwrap_or_default();
        let Scratch {
            located,
            group,
            count,
            order,
        } = &mut *scratch;
        // The first group of each cell: groups are the set's intervals in one list.
        let mut base = [0u32; MAX_CELLS];
        let mut groups = 0u32;
        for (b, c) in base.iter_mut().zip(&self.cells) {
            *b = groups;
            groups += c.intervals.len() as u32;
        }
        if self.cells.len() > MAX_CELLS || groups >= FOLLOWS {
            // Not the layouts this path is for (never built by the options' ranges).
            SCRATCH.with(|s| s.set(Some(scratch)));
            return self.sample_eval_grouped(brdf, wos, u, out);
        }
        let dummy = Located {
            keys: [0.0; 2],
            cos: 1.0,
            turn: Turn::IDENTITY,
            cell: 0,
            interval: 0,
        };
        // Grown, never cleared: every entry read below is written first.
        if located.len() < wos.len() {
            located.resize(wos.len(), dummy);
        }
        group.clear();
        group.reserve(wos.len());
        count.clear();
        count.resize(groups as usize + 1, 0);
        // `group[k]`: the query's group, with `FOLLOWS` when it continues its predecessor's
        // run (the same `ωo` bits: a pixel's samples take the predecessor's location), or
        // `UNSERVED`.
        let mut prev = [u64::MAX; 3];
        let mut prev_group = UNSERVED;
        for (k, wo) in wos.iter().enumerate() {
            let now = bits(wo);
            let g = if k > 0 && now == prev {
                if prev_group != UNSERVED {
                    located[k] = located[k - 1];
                    count[prev_group as usize + 1] += 1;
                    prev_group | FOLLOWS
                } else {
                    UNSERVED
                }
            } else if let Some(q) = self.locate_aniso(wo) {
                located[k] = q;
                let g = base[q.cell as usize] + q.interval;
                count[g as usize + 1] += 1;
                prev_group = g;
                g
            } else {
                prev_group = UNSERVED;
                UNSERVED
            };
            group.push(g);
            prev = now;
        }
        // Counting sort by group (stable: the caller's order within a group); each entry of
        // `order` the query's index with its run flag.
        for g in 0..groups as usize {
            count[g + 1] += count[g];
        }
        let served = count[groups as usize] as usize;
        order.clear();
        order.resize(served, 0);
        for (k, &g) in group.iter().enumerate() {
            if g != UNSERVED {
                let at = &mut count[(g & !FOLLOWS) as usize];
                order[*at as usize] = k as u32 | (g & FOLLOWS);
                *at += 1;
            }
        }
        let mut audit = Audit::default();
        // Runs of one `ωo` of the caller's order stay runs in the serving order (they share
        // their interval, and the sort is stable): the density and normaliser made once.
        let mut a = 0;
        while a < order.len() {
            let k = (order[a] & !FOLLOWS) as usize;
            let mut b = a + 1;
            while b < order.len() && order[b] & FOLLOWS != 0 {
                b += 1;
            }
            if b == a + 1 {
                out[k] = self.draw_aniso(brdf, &wos[k], &located[k], u, &mut audit);
            } else {
                self.serve_aniso_run(brdf, &wos[k], &located[k], &order[a..b], u, &mut audit, out);
            }
            a = b;
        }
        SCRATCH.with(|s| s.set(Some(scratch)));
        self.counters.record(&audit);
    }

    /// [`ExactSet::locate_keys`]'s query of `wo` as a [`Located`] record, the same values bit
    /// for bit: inline for the common case (`ωo` served as given in a narrow azimuth cell,
    /// [`super::walk::cell_offset`]), through `locate_keys` otherwise (wide cells, the grazing
    /// top, below the horizon).
    #[inline(always)]
    fn locate_aniso(&self, wo: &Vec3) -> Option<Located> {
        let narrow = if wo.z >= self.top_cos && wo.x.is_finite() && wo.y.is_finite() {
            super::walk::cell_offset(
                wo,
                self.period,
                self.cells[0].tan_half,
                |k| self.cells[k].phi_turn,
                self.cells.len(),
            )
        } else {
            None
        };
        let Some((cell, turn, tan)) = narrow else {
            let q = self.locate_keys(wo)?;
            return Some(Located {
                keys: q.keys,
                cos: q.cos,
                turn: q.turn,
                cell: q.cell as u32,
                interval: q.interval as u32,
            });
        };
        // `locate_with`'s arithmetic for a query served as given (`wo.z ≥ top_cos > 0`).
        let cos = wo.z.min(1.0);
        let c = &self.cells[cell];
        let interval = c.interval_direct(c.search_key(cos, f64::NAN), tan);
        Some(Located {
            keys: [(1.0 - cos).sqrt(), tan],
            cos,
            turn,
            cell: cell as u32,
            interval: interval as u32,
        })
    }

    /// One sample of a located anisotropic query `q` of `wo`: [`ExactSet::draw_located`]'s
    /// arithmetic (the same density, table, trials, normaliser and sample), finished as
    /// [`ExactSet::finish`] does.
    #[inline]
    fn draw_aniso(
        &self,
        brdf: &dyn Brdf,
        wo: &Vec3,
        q: &Located,
        u: &mut dyn UniformSource,
        audit: &mut Audit,
    ) -> EvalSample {
        if !(wo.z >= self.top_cos) {
            // Served at the top angle (another `ωo`): the general path, whose `f` is not the
            // query's.
            let Some(full) = self.locate_keys(wo) else {
                return EvalSample::NONE;
            };
            let (s, f) = self.draw_located(&full, wo, u, audit);
            return self.finish(brdf, wo, s, f);
        }
        let c = &self.cells[q.cell as usize];
        let i = q.interval as usize;
        let iv = &c.intervals[i];
        let g = QueryDensity::in_frame(self.brdf.as_ref(), false, wo, q.turn, iv.map);
        let drawn = match &c.tables[i] {
            Some(table) => table.draw(&|p| g.at(p), u, audit),
            None => iv.tree.sample_envelope_of(&|p| g.at(p), u, audit),
        };
        let Some((x, gx)) = drawn else {
            return self.finish(brdf, wo, DirSample::NONE, None);
        };
        let a = c.aniso[i].normaliser(q.keys[0], q.keys[1], q.cos, &c.patches);
        let (s, f) = accepted(iv.map, &q.turn, x, gx, a);
        self.finish(brdf, wo, s, f.is_finite().then_some(f))
    }

    /// The queries `run` (indices into `out`) of one located anisotropic query `q` of `wo`:
    /// [`ExactSet::draw_located`]'s arithmetic (the same density, table, trials, normaliser
    /// and samples) with the density and the normaliser made once, each sample finished as
    /// [`ExactSet::finish`] does.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn serve_aniso_run(
        &self,
        brdf: &dyn Brdf,
        wo: &Vec3,
        q: &Located,
        run: &[u32],
        u: &mut dyn UniformSource,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        if !(wo.z >= self.top_cos) {
            // Served at the top angle (another `ωo`): the general path, whose `f` is not the
            // query's.
            let Some(full) = self.locate_keys(wo) else {
                return;
            };
            for &k in run {
                let (s, f) = self.draw_located(&full, wo, u, audit);
                out[(k & !FOLLOWS) as usize] = self.finish(brdf, wo, s, f);
            }
            return;
        }
        let c = &self.cells[q.cell as usize];
        let i = q.interval as usize;
        let iv = &c.intervals[i];
        let g = QueryDensity::in_frame(self.brdf.as_ref(), false, wo, q.turn, iv.map);
        let g = |p| g.at(p);
        let mut a = None;
        for &k in run {
            let drawn = match &c.tables[i] {
                Some(table) => table.draw(&g, u, audit),
                None => iv.tree.sample_envelope_of(&g, u, audit),
            };
            out[(k & !FOLLOWS) as usize] = match drawn {
                Some((x, gx)) => {
                    let a = *a.get_or_insert_with(|| {
                        c.aniso[i].normaliser(q.keys[0], q.keys[1], q.cos, &c.patches)
                    });
                    let (s, f) = accepted(iv.map, &q.turn, x, gx, a);
                    self.finish(brdf, wo, s, f.is_finite().then_some(f))
                }
                None => self.finish(brdf, wo, DirSample::NONE, None),
            };
        }
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

    /// The anisotropic batch path on narrow azimuth cells (`tan δ` keys, the default layout of
    /// anisotropic Ward) at random `ωo`: the batch returns, bit for bit, what the one-query
    /// path (`sample_eval`) returns when called in the batch's serving order (intervals in the
    /// set's list, `cell` then `interval`; the caller's order within one) from the same seed —
    /// `ωi`, pdf and `f` — and leaves the stream in the same state; with the set's own BRDF
    /// object (the accepted trial's `f`) and with another object of the same model (`f`
    /// evaluated). The queries: random θo up to 89.999°, repeated `ωo` (runs, one of them again
    /// after a query of its interval: two runs), the grazing top (served at another `ωo`), at
    /// and below the horizon, and a non-finite one twice in a row.
    #[test]
    fn aniso_batch_draws_the_one_query_paths_bits_in_serving_order() {
        let spec = "ward:alpha_x=0.12,alpha_y=0.3";
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let other: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let opts = ExactOptions {
            max_trials: 8.0,
            normaliser_tol: 1e-3,
            min_width_deg: 2.0,
            ..ExactOptions::default()
        };
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
        assert!(set.cells.len() >= 2 && set.cells.iter().all(|c| c.by_tan));
        assert!(
            set.len() > set.cells.len(),
            "some cells hold several intervals"
        );
        let mut qr = Xoshiro256PlusPlus::seed_from_u64(12);
        let mut wos: Vec<Vec3> = (0..3000)
            .map(|k| {
                let phi = 360.0 * qr.next_uniform();
                let theta = match k % 97 {
                    0 => 89.995,
                    1 => 90.0,
                    2 => 97.0,
                    _ => 89.999 * qr.next_uniform(),
                };
                brdf::direction_from_angles(theta, phi)
            })
            .collect();
        let run = brdf::direction_from_angles(41.0, 123.0);
        wos.extend(std::iter::repeat_n(run, 50));
        wos.push(Vec3::new(f64::NAN, 0.0, 1.0));
        // A run after an unserved one of the same bits, and the first run again after another
        // query of its interval's group (separate runs in the serving order).
        wos.push(Vec3::new(f64::NAN, 0.0, 1.0));
        let near = brdf::direction_from_angles(41.5, 123.5);
        let (a, b) = (
            set.locate_keys(&run).unwrap(),
            set.locate_keys(&near).unwrap(),
        );
        assert_eq!((a.cell, a.interval), (b.cell, b.interval));
        wos.push(near);
        wos.extend(std::iter::repeat_n(run, 3));
        wos.extend(wos[..300].to_vec());
        // The serving order: by interval in the set's list, the caller's order within one.
        let mut base = vec![0];
        for c in &set.cells {
            base.push(base[base.len() - 1] + c.intervals.len());
        }
        let mut order: Vec<(usize, usize)> = wos
            .iter()
            .enumerate()
            .filter_map(|(k, wo)| set.locate_keys(wo).map(|q| (base[q.cell] + q.interval, k)))
            .collect();
        order.sort_by_key(|&(g, _)| g);
        let groups = order
            .iter()
            .map(|&(g, _)| g)
            .collect::<std::collections::BTreeSet<_>>();
        assert!(groups.len() > 10 && order.len() < wos.len());
        let key = |s: &EvalSample| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits);
        for (who, by) in [("own object", &brdf), ("another object", &other)] {
            let mut r1 = Xoshiro256PlusPlus::seed_from_u64(4);
            let mut out = vec![EvalSample::NONE; 7];
            set.sample_eval_batch(by.as_ref(), &wos, &mut r1, &mut out);
            assert_eq!(out.len(), wos.len());
            let mut r2 = Xoshiro256PlusPlus::seed_from_u64(4);
            let mut expected = vec![EvalSample::NONE; wos.len()];
            for &(_, k) in &order {
                expected[k] = set.sample_eval(by.as_ref(), &wos[k], &mut r2);
            }
            for (k, (o, e)) in out.iter().zip(&expected).enumerate() {
                assert_eq!(
                    key(o),
                    key(e),
                    "{who}, query {k} ({:?}): {o:?} vs {e:?}",
                    wos[k]
                );
            }
            assert_eq!(
                r1.next_uniform(),
                r2.next_uniform(),
                "{who}: the streams in step"
            );
            let drawn = out.iter().filter(|s| s.pdf > 0.0).count();
            assert!(
                drawn + 100 > order.len(),
                "{who}: {drawn} of {}",
                order.len()
            );
        }
    }
}
