//! The anisotropic batch path's random-`ωo` wavefront (issue 29, docs/benchmarks.md §28.7):
//! `wave_iso.rs`'s wavefront for anisotropic sets. The queries of one interval group, each
//! at its own `ωo`, are drawn together: every pending query proposes one trial per pass in
//! vector lanes ([`lanes::trials_split`]: its own SplitMix64 stream, the leaf pick, the
//! point, bound, threshold and direction `v`; the interval's one table serves all of them),
//! the trials inside the disc are evaluated at their own query's prepared `ωo` — `f(ωo,
//! R_δ v)`, `R_δ` the query's rotation from the interval's frame to the world's, as
//! `QueryDensity::in_frame` evaluates an anisotropic BRDF — and acceptance and the next
//! pass's pending list are made without branches.
//!
//! Each query's law is the one-query anisotropic draw's (`batch_aniso.rs`'s `draw_aniso`,
//! [`ExactSet::draw_located`]'s arithmetic) — the same trial, density `g = f` (projected map)
//! or `2 cos θi f` (equal-area map), acceptance test `u₃·M_i < g`, normaliser (the record's
//! `A(w, key, cos θo)`) and pdf `g / A` — with its uniforms from its own stream, seeded as
//! `wave_iso`'s: query `i` (the caller's index) reads SplitMix64 started at
//! [`stream_key`]`(seed, i)`, two outputs per trial split into its four 32-bit uniforms
//! ([`lanes::split_trial`]); the last pending queries of a group (fewer than a lane group)
//! draw one by one from the same streams. So a sample is a function of that stream's state,
//! `i` and `ωo_i` only (not of the other queries, the grouping or the thread), and bit for
//! bit `draw_aniso` from the stream (tested in `batch_aniso.rs`). These are other samples
//! than the one-query path's from the same seed (same law).

use brdf::{Brdf, Outgoing, Vec3};
use partition_sampler::{Audit, MAX_TRIALS_PER_SAMPLE};

use super::ExactSet;
use super::fused::accepted_at;
use super::lanes::{self, Trials};
use super::wave_iso::stream_key;
use crate::disc::{DiscMap, count_evaluations};
use crate::layout::Turn;
use crate::{DirSample, EvalSample};

/// A located anisotropic query, as its draw reads it: the normaliser grid's keys
/// `w = √(1 − cos θo)` and the strip key (`tan δ` or `δ`), `cos θo`, the rotation from the
/// interval's frame to the world's, and the interval (its cell and index in the cell).
#[derive(Debug, Clone, Copy)]
pub(super) struct Located {
    pub(super) keys: [f64; 2],
    pub(super) cos: f64,
    pub(super) turn: Turn,
    pub(super) cell: u32,
    pub(super) interval: u32,
}

/// Pending queries per block of [`ExactSet::serve_aniso_wave`]: at most this many trials are
/// made in lanes and evaluated per block.
const WAVE_ANISO: usize = 256;

/// Pending queries below which [`ExactSet::serve_aniso_wave`] finishes them one by one (a
/// lane group's 16 trials would be mostly padding).
const WAVE_TAIL: usize = 16;

/// The working arrays of [`ExactSet::serve_aniso_wave`], kept by the caller between groups
/// (and per thread between batches): per query of the group its prepared `ωo`, its rotation
/// `R_δ` as `(sin δ, cos δ)` (`None` for the identity, which is not applied, as
/// `QueryDensity::in_frame` does), normaliser and rotation back to the world; the pending
/// queries and their stream states (this pass's and the next one's); one block's trials, the
/// candidates inside the disc, their values, and the accepted ones.
pub(super) struct AnisoWave {
    prep: Vec<Outgoing>,
    rot: Vec<Option<(f64, f64)>>,
    norm: Vec<f64>,
    turn: Vec<Turn>,
    idx: Vec<u32>,
    state: Vec<u64>,
    idx2: Vec<u32>,
    state2: Vec<u64>,
    t: Trials,
    lane: Vec<u32>,
    g: Vec<f64>,
    acc: Vec<u32>,
}

impl Default for AnisoWave {
    fn default() -> Self {
        Self {
            prep: Vec::new(),
            rot: Vec::new(),
            norm: Vec::new(),
            turn: Vec::new(),
            idx: Vec::new(),
            state: Vec::new(),
            idx2: Vec::new(),
            state2: Vec::new(),
            t: Trials::new(WAVE_ANISO),
            lane: vec![0; WAVE_ANISO],
            g: vec![0.0; WAVE_ANISO],
            acc: vec![0; WAVE_ANISO],
        }
    }
}

/// `g` of a trial direction `v` (on the interval's map) for a query prepared as `prep` with
/// rotation `rot`: `f(ωo, R_δ v)` on the projected map, `2 v_z f(ωo, R_δ v)` on the
/// equal-area one — `QueryDensity::at`'s arithmetic inside the disc.
#[inline(always)]
fn density_at(
    model: &dyn Brdf,
    map: DiscMap,
    prep: &Outgoing,
    rot: Option<(f64, f64)>,
    v: &Vec3,
) -> f64 {
    let wi = match rot {
        None => *v,
        Some((s, c)) => Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z),
    };
    let f = model.eval_prepared(prep, &wi);
    #[cfg(test)]
    let f = skewed(f, v);
    match map {
        DiscMap::Projected => f,
        DiscMap::EqualArea => 2.0 * v.z * f,
    }
}

impl ExactSet {
    /// The anisotropic queries `members` (indices into `wos`, `located` and `out`; each
    /// located in interval `interval` of cell `cell`, which has a table, and served at its own
    /// `ωo`: `wos[i].z ≥ top_cos`) drawn as one wavefront from the streams keyed by `seed`
    /// (see the module docs): `out[i]` is the one-query anisotropic draw's sample at `wos[i]`
    /// from query `i`'s stream, finished as [`ExactSet::finish`] finishes it (the accepted
    /// trial's `f`, or one evaluation of `brdf` when it is another object), or the empty
    /// sample after [`MAX_TRIALS_PER_SAMPLE`] trials (counted as exhausted). Trials,
    /// violations (`g > M_i`) and samples are counted in `audit` as `LeafTable::draw` counts
    /// them.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn serve_aniso_wave(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        located: &[Located],
        cell: usize,
        interval: usize,
        members: &[u32],
        seed: u64,
        arch: pulp::Arch,
        w: &mut AnisoWave,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        let c = &self.cells[cell];
        let iv = &c.intervals[interval];
        let rec = &c.aniso[interval];
        let Some(table) = c.tables[interval].as_ref() else {
            return;
        };
        let map = iv.map;
        let n = members.len();
        // Per query: the one-query draw's preparation (`QueryDensity::in_frame` for an
        // anisotropic BRDF, the record's normaliser).
        w.prep.clear();
        w.rot.clear();
        w.norm.clear();
        w.turn.clear();
        w.idx.clear();
        w.state.clear();
        for (k, &i) in members.iter().enumerate() {
            let wo = &wos[i as usize];
            let q = &located[i as usize];
            w.prep.push(self.brdf.prepare(wo));
            w.rot
                .push((q.turn != Turn::IDENTITY).then_some((q.turn.sin, q.turn.cos)));
            w.norm
                .push(rec.normaliser(q.keys[0], q.keys[1], q.cos, &c.patches));
            w.turn.push(q.turn);
            w.idx.push(k as u32);
            w.state.push(stream_key(seed, u64::from(i)));
        }
        // Room for the next pass's list (its entries are written before they are read).
        if w.idx2.len() < n {
            w.idx2.resize(n, 0);
            w.state2.resize(n, 0);
        }
        let AnisoWave {
            prep,
            rot,
            norm,
            turn,
            idx,
            state,
            idx2,
            state2,
            t,
            lane,
            g,
            acc,
        } = w;
        let model = self.brdf.as_ref();
        let (mut trials, mut violations, mut pass) = (0u64, 0u64, 0u64);
        let mut pending = n;
        while pending >= WAVE_TAIL {
            if pass >= MAX_TRIALS_PER_SAMPLE {
                for &k in &idx[..pending] {
                    audit.exhausted += 1;
                    let i = members[k as usize] as usize;
                    out[i] = self.finish(brdf, &wos[i], DirSample::NONE, None);
                }
                pending = 0;
                break;
            }
            pass += 1;
            trials += pending as u64;
            // The next pass's pending queries, written without branches (`np` advances by
            // the rejected ones).
            let mut np = 0;
            for (ib, sb) in idx[..pending]
                .chunks(WAVE_ANISO)
                .zip(state[..pending].chunks_mut(WAVE_ANISO))
            {
                let len = ib.len();
                lanes::trials_split(arch, table, map, sb, t);
                // The candidates inside the disc, compacted without branches; the others
                // propose again next pass.
                let mut c = 0;
                for k in 0..len {
                    lane[c] = k as u32;
                    c += usize::from(t.inside[k]);
                }
                if c < len {
                    for k in (0..len).filter(|&k| !t.inside[k]) {
                        idx2[np] = ib[k];
                        state2[np] = sb[k];
                        np += 1;
                    }
                }
                count_evaluations(c as u64);
                for (gj, &k) in g[..c].iter_mut().zip(&lane[..c]) {
                    let k = k as usize;
                    let q = ib[k] as usize;
                    *gj = density_at(model, map, &prep[q], rot[q], &t.dir[k]);
                }
                // Acceptance (`u₃·M_i < g`, `draw`'s test) without branches: the accepted
                // candidates' entries gathered in `acc`, the rejected queries in the next
                // pass's list.
                let mut na = 0;
                for (j, (&k, &gj)) in lane[..c].iter().zip(&g[..c]).enumerate() {
                    let k = k as usize;
                    violations += u64::from(gj > t.bound[k]);
                    let ok = t.threshold[k] < gj;
                    acc[na] = j as u32;
                    na += usize::from(ok);
                    idx2[np] = ib[k];
                    state2[np] = sb[k];
                    np += usize::from(!ok);
                }
                for &j in &acc[..na] {
                    let j = j as usize;
                    let k = lane[j] as usize;
                    let q = ib[k] as usize;
                    let (s, f) = accepted_at(map, &turn[q], t.dir[k], g[j], norm[q]);
                    let i = members[q] as usize;
                    out[i] = self.finish(brdf, &wos[i], s, f.is_finite().then_some(f));
                }
            }
            std::mem::swap(idx, idx2);
            std::mem::swap(state, state2);
            pending = np;
        }
        // The last few pending queries (fewer than a lane group) one by one: the same trials
        // from the same streams, `LeafTable::draw`'s loop with the passes' trials counted.
        for (&q, &st) in idx[..pending].iter().zip(&state[..pending]) {
            let q = q as usize;
            let i = members[q] as usize;
            let mut st = st;
            let mut made = pass;
            let found = loop {
                if made >= MAX_TRIALS_PER_SAMPLE {
                    audit.exhausted += 1;
                    break None;
                }
                let us = lanes::split_trial(&mut st);
                made += 1;
                let Some((x, m)) = table.propose(us) else {
                    continue;
                };
                count_evaluations(1);
                let v = map.to_direction(x);
                let gx = density_at(model, map, &prep[q], rot[q], &v);
                violations += u64::from(gx > m);
                if us[3] * m < gx {
                    break Some((v, gx));
                }
            };
            trials += made - pass;
            let (s, f) = match found {
                Some((v, gx)) => accepted_at(map, &turn[q], v, gx, norm[q]),
                None => (DirSample::NONE, f64::NAN),
            };
            out[i] = self.finish(brdf, &wos[i], s, f.is_finite().then_some(f));
        }
        audit.trials += trials;
        audit.violations += violations;
        audit.samples += n as u64;
    }
}

#[cfg(test)]
thread_local! {
    /// Test support, a deliberately broken wavefront: `k > 0` misreports each candidate's `f`
    /// by the factor `1 − k + 2k·cos θi` (samples of another density under the honest pdf),
    /// `k < 0` accepts every candidate (the envelope's law); 0 (the default) is the honest one.
    pub(super) static SKEW: std::cell::Cell<f64> = const { std::cell::Cell::new(0.0) };
}

/// [`SKEW`]'s break applied to a candidate's `f` at `v` (test support).
#[cfg(test)]
fn skewed(f: f64, v: &Vec3) -> f64 {
    let k = SKEW.with(std::cell::Cell::get);
    if k < 0.0 {
        f64::MAX
    } else if k > 0.0 {
        f * (1.0 - k + 2.0 * k * v.z)
    } else {
        f
    }
}
