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
use super::wave_aniso::{AnisoWave, Located};
#[cfg(test)]
use super::wave_iso::NO_WAVE;
use super::wave_iso::{wave_on, wave_seed};
use crate::layout::Turn;
use crate::{DirSample, EvalSample};

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
    /// Per query, its group with its run flag (see [`FOLLOWS`]), or [`UNSERVED`] (grown, never
    /// cleared: entry `k` is written before it is read).
    group: Vec<u32>,
    /// The counting sort's bucket starts (then ends) per group.
    count: Vec<u32>,
    /// The serving order: query indices with their run flags.
    order: Vec<u32>,
    /// Per group, whether it is drawn as a random-`ωo` wavefront
    /// ([`ExactSet::serve_aniso_wave`]).
    wave: Vec<bool>,
    /// One wave group's queries served at their own `ωo`, and the wavefront's working arrays.
    members: Vec<u32>,
    aniso_wave: AnisoWave,
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
            wave,
            members,
            aniso_wave,
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
        if group.len() < wos.len() {
            group.resize(wos.len(), UNSERVED);
        }
        let group = &mut group[..wos.len()];
        count.clear();
        count.resize(groups as usize + 1, 0);
        // `group[k]`: the query's group, with `FOLLOWS` when it continues its predecessor's
        // run (the same `ωo` bits: a pixel's samples take the predecessor's location), or
        // `UNSERVED`.
        let mut prev = [u64::MAX; 3];
        let mut prev_group = UNSERVED;
        for ((k, wo), gk) in wos.iter().enumerate().zip(group.iter_mut()) {
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
            *gk = g;
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
        // `count[g]` is now group `g`'s end in `order`. A group of the caller's random `ωo` (no
        // run of one `ωo`) whose interval has a table is drawn as one wavefront.
        wave.clear();
        wave.resize(groups as usize, false);
        let mut waves = false;
        if wave_on() {
            let mut s = 0;
            for (g, w) in wave.iter_mut().enumerate() {
                let e = count[g] as usize;
                let span = &order[s..e];
                if let Some(&first) = span.first() {
                    let q = &located[first as usize];
                    let cell = &self.cells[q.cell as usize];
                    *w = cell.tables[q.interval as usize].is_some()
                        && span.iter().all(|&k| k & FOLLOWS == 0);
                    waves |= *w;
                }
                s = e;
            }
        }
        // The wave groups' streams are keyed by one word of `u`, drawn before any other draw of
        // the pass.
        let seed = if waves { wave_seed(u) } else { 0 };
        let arch = pulp::Arch::new();
        let mut audit = Audit::default();
        let mut s = 0;
        for (g, &is_wave) in wave.iter().enumerate() {
            let e = count[g] as usize;
            let span = &order[s..e];
            s = e;
            if is_wave {
                // Its queries served at their own `ωo` as one wavefront; the others (served at
                // the top angle) one by one from `u`.
                members.clear();
                for &k in span {
                    let wo = &wos[k as usize];
                    if wo.z >= self.top_cos {
                        members.push(k);
                    } else {
                        let k = k as usize;
                        out[k] = self.draw_aniso(brdf, wo, &located[k], u, &mut audit);
                    }
                }
                let q = &located[span[0] as usize];
                self.serve_aniso_wave(
                    brdf,
                    wos,
                    located,
                    q.cell as usize,
                    q.interval as usize,
                    members,
                    seed,
                    arch,
                    aniso_wave,
                    &mut audit,
                    out,
                );
                continue;
            }
            // Runs of one `ωo` of the caller's order stay runs in the serving order (they
            // share their interval, and the sort is stable): the density and normaliser made
            // once.
            let mut a = 0;
            while a < span.len() {
                let k = (span[a] & !FOLLOWS) as usize;
                let mut b = a + 1;
                while b < span.len() && span[b] & FOLLOWS != 0 {
                    b += 1;
                }
                if b == a + 1 {
                    out[k] = self.draw_aniso(brdf, &wos[k], &located[k], u, &mut audit);
                } else {
                    self.serve_aniso_run(
                        brdf,
                        &wos[k],
                        &located[k],
                        &span[a..b],
                        u,
                        &mut audit,
                        out,
                    );
                }
                a = b;
            }
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

    /// `n` outgoing directions drawn from `qr`: `φ` uniform in [0°, 360°), and `θo` uniform
    /// in [0°, 89.999°) but for every 97th from `k = 0, 1, 2` on: 89.995° (grazing), 90°
    /// (the horizon) and 97° (below it).
    fn random_wos(qr: &mut Xoshiro256PlusPlus, n: usize) -> Vec<Vec3> {
        (0..n)
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
            .collect()
    }

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
        // The run-by-run path (the random-ωo wavefront is tested below).
        super::NO_WAVE.with(|c| c.set(true));
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
        let mut wos = random_wos(&mut qr, 3000);
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
        super::NO_WAVE.with(|c| c.set(false));
    }

    /// SplitMix64 as a `rand` generator (its outputs `mix64(state + k·γ)`, `k ≥ 1`): a
    /// wavefront query's stream as a caller's uniform source.
    struct SplitMix(u64);
    impl rand::TryRng for SplitMix {
        type Error = std::convert::Infallible;
        fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
            self.try_next_u64().map(|w| (w >> 32) as u32)
        }
        fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
            self.0 = self.0.wrapping_add(super::super::lanes::GOLDEN_GAMMA);
            Ok(super::super::lanes::mix64(self.0))
        }
        fn try_fill_bytes(&mut self, _: &mut [u8]) -> Result<(), Self::Error> {
            unimplemented!("not used")
        }
    }

    /// The random-ωo wavefront of the anisotropic batch path (anisotropic Ward, 4000 random
    /// ωo with grazing, horizon, below-horizon and non-finite ones, no two alike): each query
    /// served at its own ωo in an interval with a table is, bit for bit (`ωi`, pdf, `f`), the
    /// one-query anisotropic draw (`draw_aniso`) from its own stream `stream_key(seed, i)`,
    /// `seed` the word of the caller's first two uniforms — with the set's own BRDF object and
    /// with another one; the grazing ones (served at the top angle) are samples of the set's
    /// pdf with the BRDF's `f`; the others empty. Then other ωo put around them leave the
    /// wavefront samples of the queries kept unchanged (a function of the seed and the index
    /// only, not of the grouping).
    #[test]
    fn random_wo_groups_draw_draw_anisos_samples_from_their_own_streams() {
        use super::super::wave_iso::stream_key;
        use super::wave_seed;
        use partition_sampler::Audit;
        let spec = "ward:alpha_x=0.12,alpha_y=0.3";
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let other: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let set = ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
        let mut qr = Xoshiro256PlusPlus::seed_from_u64(51);
        let mut wos = random_wos(&mut qr, 4000);
        wos[500] = Vec3::new(f64::NAN, 0.0, 1.0);
        wos[501] = Vec3::new(0.3, f64::INFINITY, 0.5);
        let key = |s: &EvalSample| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits);
        let rng = Xoshiro256PlusPlus::seed_from_u64(19);
        let seed = wave_seed(&mut rng.clone());
        let mut audit = Audit::default();
        for by in [&brdf, &other] {
            let mut out = Vec::new();
            set.sample_eval_batch(by.as_ref(), &wos, &mut rng.clone(), &mut out);
            let (mut wave, mut top, mut none) = (0, 0, 0);
            for (i, (wo, o)) in wos.iter().zip(&out).enumerate() {
                let Some(q) = set.locate_aniso(wo) else {
                    assert_eq!(*o, EvalSample::NONE, "query {i}");
                    none += 1;
                    continue;
                };
                let table = set.cells[q.cell as usize].tables[q.interval as usize].is_some();
                if wo.z >= set.top_cos && table {
                    let mut s = SplitMix(stream_key(seed, i as u64));
                    let want = set.draw_aniso(by.as_ref(), wo, &q, &mut s, &mut audit);
                    assert_eq!(key(o), key(&want), "query {i}: {o:?} vs {want:?}");
                    wave += 1;
                } else {
                    assert!(o.pdf > 0.0 && o.wi.z > 0.0, "query {i}: {o:?}");
                    approx::assert_relative_eq!(o.pdf, set.pdf(wo, &o.wi), max_relative = 1e-9);
                    approx::assert_relative_eq!(o.f, brdf.eval(wo, &o.wi), max_relative = 1e-12);
                    top += 1;
                }
            }
            assert!(
                wave > 3800 && top >= 40 && none >= 40,
                "{wave} wave, {top} top, {none} none"
            );
        }
        assert!(audit.trials > audit.samples, "some trials rejected");
        let mut out = Vec::new();
        set.sample_eval_batch(brdf.as_ref(), &wos, &mut rng.clone(), &mut out);
        let before = out.clone();
        for k in (0..wos.len()).filter(|k| k % 3 == 2) {
            wos[k] =
                brdf::direction_from_angles(80.0 * qr.next_uniform(), 360.0 * qr.next_uniform());
        }
        set.sample_eval_batch(brdf.as_ref(), &wos, &mut rng.clone(), &mut out);
        let mut same = 0;
        for (k, (a, b)) in before.iter().zip(&out).enumerate() {
            if k % 3 != 2 && wos[k].z >= set.top_cos {
                assert_eq!(key(a), key(b), "query {k}");
                same += 1;
            }
        }
        assert!(same > 2500, "{same}");
    }

    /// The anisotropic random-ωo wavefront's law by χ² (α = 10⁻⁴, 16 × 32 `(cos θ, φ)` bins,
    /// 4·10⁴ samples per angle): a batch alternating two ωo of anisotropic Ward (no two
    /// consecutive alike, so both groups are wavefronts) at θo = 30° and 75° passes against
    /// the set's pdf at each, and two deliberately broken wavefronts are rejected at both —
    /// one that misreports each candidate's `f` by the factor `0.6 + 0.8 cos θi`, one that
    /// accepts every candidate (the envelope's law).
    #[test]
    fn random_wo_aniso_wavefront_passes_chi_square_and_broken_ones_fail() {
        use super::super::batch::tests::assert_wavefront_chi_square;
        use super::super::wave_iso::SKEW;
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec("ward:alpha_x=0.12,alpha_y=0.3").unwrap());
        let set = ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
        let dirs = [30.0, 75.0].map(|t: f64| brdf::direction_from_angles(t, 20.0 + t));
        assert_wavefront_chi_square(&set, dirs, |skew, wos| {
            SKEW.with(|c| c.set(skew));
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(29);
            let mut out = Vec::new();
            set.sample_eval_batch(brdf.as_ref(), wos, &mut rng, &mut out);
            SKEW.with(|c| c.set(0.0));
            out
        });
    }
}
