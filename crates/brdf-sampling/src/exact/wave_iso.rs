//! The isotropic batch path's random-`ωo` wavefront (issue 29, docs/benchmarks.md §28.2): the
//! queries of one interval group, each at its own `ωo`, drawn together — every pending query
//! proposes one trial per pass in vector lanes ([`lanes::trials`]: its own SplitMix64 stream,
//! the leaf pick, the point, bound, threshold and direction; the interval's one table serves
//! all of them, or with θo layer tables the layer's table serves its queries, one wavefront per
//! layer), the trials inside the disc are evaluated at their own query's prepared `ωo`,
//! and acceptance and the next pass's pending list are made without branches.
//!
//! Each query's law is [`ExactSet::draw_iso`]'s — the same trial, density, acceptance test,
//! normaliser and pdf — with its uniforms from its own stream: query `i` of a pass (the
//! caller's index) reads SplitMix64 started at `mix64(seed ⊕ mix64(i))`, `seed` one 64-bit
//! word made of two uniforms of the caller's stream at the pass's start, two outputs per
//! trial split into its four 32-bit uniforms ([`lanes::split_trial`]: what
//! `UniformSource::next_uniform4_split` makes of a generator's two words, the uniforms
//! `draw_iso` reads); the last pending queries of a group (fewer than a lane group) draw one
//! by one from the same streams. So a sample is a
//! function of that stream's state, `i` and `ωo_i` only (not of the other queries, the block
//! size, the grouping or the thread), and bit for bit `draw_iso` from the stream
//! (tested in `batch.rs`). These are other samples than the one-query path's from the same
//! seed (same law).

use brdf::{Brdf, Outgoing, Vec3};
use partition_sampler::{Audit, MAX_TRIALS_PER_SAMPLE, UniformSource};

use super::ExactSet;
use super::fused::accepted_at;
use super::lanes::{self, Trials, mix64};
use super::table::{LeafTable, query_theta};
use crate::disc::{DiscMap, count_evaluations};
use crate::layout::Turn;
use crate::{DirSample, EvalSample};

/// Pending queries per block of a wavefront ([`ExactSet::run_wave`]): at most this many trials
/// are made in lanes and evaluated per block.
const WAVE_BLOCK: usize = 256;

/// Pending queries below which [`ExactSet::run_wave`] finishes them one by one (a lane
/// group's 16 trials would be mostly padding).
const WAVE_TAIL: usize = 16;

/// The working arrays of a wavefront (the isotropic and the anisotropic one), kept by the
/// caller between groups (and per thread between batches): per query of the group its
/// prepared `ωo`, normaliser `A` and rotation back to the world; the pending queries (their
/// places in the group) and their stream states (this pass's and the next one's); one
/// block's trials, the candidates inside the disc, their values `g`, and the accepted ones.
pub(super) struct WaveLists {
    prep: Vec<Outgoing>,
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
    /// An interval group with θo layer tables ([`ExactSet::serve_iso_wave`]): per query its
    /// layer, and one layer's queries.
    layer: Vec<usize>,
    in_layer: Vec<u32>,
}

impl Default for WaveLists {
    fn default() -> Self {
        Self {
            prep: Vec::new(),
            norm: Vec::new(),
            turn: Vec::new(),
            idx: Vec::new(),
            state: Vec::new(),
            idx2: Vec::new(),
            state2: Vec::new(),
            t: Trials::new(WAVE_BLOCK),
            lane: vec![0; WAVE_BLOCK],
            g: vec![0.0; WAVE_BLOCK],
            acc: vec![0; WAVE_BLOCK],
            layer: Vec::new(),
            in_layer: Vec::new(),
        }
    }
}

impl WaveLists {
    /// The per-query lists of a new group of `n` queries, grown to `n` (never shrunk; every
    /// entry `0..n` is written by the caller before [`ExactSet::run_wave`] reads it), as
    /// slices of length `n`: prepared `ωo`, normaliser `A`, rotation back to the world, first
    /// stream state; the pending list is set to the group's places `0..n`. Written through
    /// slices, not pushed: no capacity check and no reload of a list's length per query.
    #[inline(always)]
    pub(super) fn slots(&mut self, n: usize) -> Slots<'_> {
        if self.prep.len() < n {
            self.prep.resize(n, Outgoing::new(Vec3::new(0.0, 0.0, 1.0)));
            self.norm.resize(n, 0.0);
            self.turn.resize(n, Turn::IDENTITY);
        }
        // Each on its own: a pass swaps the pending lists with the next pass's.
        if self.idx.len() < n {
            self.idx.resize(n, 0);
        }
        if self.state.len() < n {
            self.state.resize(n, 0);
        }
        for (k, i) in self.idx[..n].iter_mut().enumerate() {
            *i = k as u32;
        }
        Slots {
            prep: &mut self.prep[..n],
            norm: &mut self.norm[..n],
            turn: &mut self.turn[..n],
            state: &mut self.state[..n],
        }
    }
}

/// The per-query lists of a group as [`WaveLists::slots`] hands them out (each of the group's
/// length): query `k`'s prepared `ωo`, normaliser `A`, rotation back to the world and first
/// stream state.
pub(super) struct Slots<'a> {
    pub(super) prep: &'a mut [Outgoing],
    pub(super) norm: &'a mut [f64],
    pub(super) turn: &'a mut [Turn],
    pub(super) state: &'a mut [u64],
}

/// The isotropic wavefront's working arrays ([`WaveLists`]; its queries need no rotation).
pub(super) type IsoWave = WaveLists;

/// How a wavefront evaluates the BRDF at a trial direction: `f(ωo_q, ω)` with `ω` the trial
/// direction `v` (in the interval's frame) taken to the BRDF's frame — the identity for an
/// isotropic set, the query's rotation `R_δ` for an anisotropic one (`wave_aniso.rs`).
pub(super) trait WaveFrame {
    /// `f(prep, ω(q, v))` by `model`, `prep` query `q`'s prepared `ωo`.
    fn eval(&self, model: &dyn Brdf, prep: &Outgoing, q: usize, v: &Vec3) -> f64;
}

/// The isotropic [`WaveFrame`]: `ω = v` (the interval's frame is the BRDF's, `ωo` in the
/// plane `φ = 0`).
pub(super) struct Unrotated;

impl WaveFrame for Unrotated {
    #[inline(always)]
    fn eval(&self, model: &dyn Brdf, prep: &Outgoing, _q: usize, v: &Vec3) -> f64 {
        model.eval_prepared(prep, v)
    }
}

/// `g` of trial direction `v` (on the map `map`) for query `q` of a wavefront: `f(ωo_q, ω)`
/// (see [`WaveFrame`]) on the projected map, `2 v_z f` on the equal-area one.
#[inline(always)]
fn density<F: WaveFrame>(
    frame: &F,
    model: &dyn Brdf,
    map: DiscMap,
    prep: &Outgoing,
    q: usize,
    v: &Vec3,
) -> f64 {
    let f = frame.eval(model, prep, q, v);
    #[cfg(test)]
    let f = skewed(f, v);
    match map {
        DiscMap::Projected => f,
        DiscMap::EqualArea => 2.0 * v.z * f,
    }
}

/// The first state of query `i`'s stream in a wavefront keyed by `seed`: `mix64(seed ⊕
/// mix64(i))` (SplitMix64's outputs then follow at `state + k·γ`, `k ≥ 1`).
#[inline(always)]
pub(super) fn stream_key(seed: u64, i: u64) -> u64 {
    mix64(seed ^ mix64(i))
}

/// The key of a wavefront's streams (the isotropic and the anisotropic ones): one 64-bit word
/// made of two uniforms of `u` (their 53-bit integers, the second shifted by 11).
pub(super) fn wave_seed(u: &mut dyn UniformSource) -> u64 {
    let [a, b] = [u.next_uniform(), u.next_uniform()];
    let bits = |x: f64| (x * (1u64 << 53) as f64) as u64;
    bits(a) ^ (bits(b) << 11)
}

/// Whether batch groups may be drawn as random-`ωo` wavefronts (always, but for tests that
/// compare the other paths' bits).
#[inline]
pub(super) fn wave_on() -> bool {
    #[cfg(test)]
    {
        !NO_WAVE.with(std::cell::Cell::get)
    }
    #[cfg(not(test))]
    {
        true
    }
}

#[cfg(test)]
thread_local! {
    /// Test support: `true` turns the random-ωo wavefronts off (every group served run by run).
    pub(super) static NO_WAVE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

impl ExactSet {
    /// The isotropic fast-path queries `members` (indices into `wos` and `out`, all in
    /// interval `interval`, which has a table) drawn as one wavefront from the streams keyed by
    /// `seed` (see the module docs; with θo layer tables, one wavefront per layer, each from
    /// the layer's table as `draw_iso` picks it): `out[i]` is [`ExactSet::draw_iso`]'s sample at `wos[i]`
    /// from query `i`'s stream, finished as the one-query path finishes it (the accepted
    /// trial's `f`, or one evaluation of `brdf` when it is another object), or the empty
    /// sample after [`MAX_TRIALS_PER_SAMPLE`] trials (counted as exhausted). Trials,
    /// violations (`g > M_i`) and samples are counted in `audit` as `draw_iso` counts them.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn serve_iso_wave(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        interval: usize,
        members: &[u32],
        seed: u64,
        arch: pulp::Arch,
        w: &mut IsoWave,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        let Some(table) = self.cells[0].tables[interval].as_ref() else {
            return;
        };
        let layers = table.layer_tables();
        if layers.is_empty() {
            self.serve_iso_wave_in(
                brdf, wos, interval, members, table, seed, arch, w, audit, out,
            );
            return;
        }
        // θo layer tables: one wavefront per layer over its queries (the layer `draw_iso`
        // picks, `LeafTable::serving_cos`; past the last, the interval's own table). Each
        // query's sample stays a function of its stream, index and `ωo` only.
        let (mut layer, mut in_layer) = (
            std::mem::take(&mut w.layer),
            std::mem::take(&mut w.in_layer),
        );
        layer.clear();
        layer.extend(members.iter().map(|&i| {
            let cos = wos[i as usize].z.min(1.0);
            table
                .serving_layer(query_theta(cos))
                .unwrap_or(layers.len())
        }));
        for l in 0..=layers.len() {
            in_layer.clear();
            in_layer.extend(
                members
                    .iter()
                    .zip(&layer)
                    .filter(|&(_, &k)| k == l)
                    .map(|(&i, _)| i),
            );
            if !in_layer.is_empty() {
                let t = layers.get(l).unwrap_or(table);
                self.serve_iso_wave_in(
                    brdf, wos, interval, &in_layer, t, seed, arch, w, audit, out,
                );
            }
        }
        w.layer = layer;
        w.in_layer = in_layer;
    }

    /// [`ExactSet::serve_iso_wave`]'s queries `members` drawn from `table` (the interval's, or
    /// the layer table serving every one of them).
    #[allow(clippy::too_many_arguments)]
    fn serve_iso_wave_in(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        interval: usize,
        members: &[u32],
        table: &LeafTable,
        seed: u64,
        arch: pulp::Arch,
        w: &mut IsoWave,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        let cell = &self.cells[0];
        let iv = &cell.intervals[interval];
        let rec = &cell.iso[interval];
        let map = rec.map;
        // Per query: `draw_iso`'s preparation, in the interval's frame `(r, 0, cos θo)`.
        let s = w.slots(members.len());
        let lists = s
            .prep
            .iter_mut()
            .zip(s.norm.iter_mut())
            .zip(s.turn.iter_mut());
        for ((&i, ((p, a), t)), st) in members.iter().zip(lists).zip(s.state.iter_mut()) {
            let wo = &wos[i as usize];
            let cos = wo.z.min(1.0);
            let r = (wo.x * wo.x + wo.y * wo.y).sqrt();
            *p = self.brdf.prepare(&Vec3::new(r, 0.0, cos));
            *a = rec.normaliser(cos, iv);
            *t = Turn::of_azimuth(wo, r);
            *st = stream_key(seed, u64::from(i));
        }
        self.run_wave(
            brdf, wos, members, table, map, &Unrotated, arch, w, audit, out,
        );
    }

    /// The passes of a wavefront (the isotropic and the anisotropic one) over the group's
    /// queries `members` (indices into `wos` and `out`), prepared in `w` (per query its
    /// prepared `ωo`, normaliser, turn and first stream state, in `members`' order): per pass
    /// every pending query's next trial from `table` in lanes ([`lanes::trials_split`]), the
    /// candidates inside the disc valued `g` at their own query ([`WaveFrame`], times `2 v_z`
    /// on the equal-area map), acceptance `u₃·M_i < g` and the next pass's list without
    /// branches; below [`WAVE_TAIL`] pending queries, one by one from the same streams. An
    /// accepted trial `(v, g)` gives `accepted_at`'s sample (pdf `g / A` on the map, the turn
    /// applied), finished by [`ExactSet::finish_iso`]; after [`MAX_TRIALS_PER_SAMPLE`]
    /// trials the empty sample (counted as exhausted). Trials, violations (`g > M_i`) and
    /// samples are counted in `audit` as `LeafTable::draw` counts them.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn run_wave<F: WaveFrame>(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        members: &[u32],
        table: &LeafTable,
        map: DiscMap,
        frame: &F,
        arch: pulp::Arch,
        w: &mut WaveLists,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        let n = members.len();
        // Room for the next pass's list (its entries are written before they are read).
        if w.idx2.len() < n {
            w.idx2.resize(n, 0);
        }
        if w.state2.len() < n {
            w.state2.resize(n, 0);
        }
        let WaveLists {
            prep,
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
            ..
        } = w;
        let model = self.brdf.as_ref();
        let (mut trials, mut violations, mut pass) = (0u64, 0u64, 0u64);
        let mut pending = n;
        while pending >= WAVE_TAIL {
            if pass >= MAX_TRIALS_PER_SAMPLE {
                for &k in &idx[..pending] {
                    audit.exhausted += 1;
                    let i = members[k as usize] as usize;
                    out[i] = self.finish_iso(brdf, &wos[i], DirSample::NONE, f64::NAN);
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
                .chunks(WAVE_BLOCK)
                .zip(state[..pending].chunks_mut(WAVE_BLOCK))
            {
                let len = ib.len();
                lanes::trials_split(arch, table, map, sb, t);
                // The candidates inside the disc, compacted without branches; the others (a
                // few per cent) propose again next pass.
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
                    *gj = density(frame, model, map, &prep[q], q, &t.dir[k]);
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
                    out[i] = self.finish_iso(brdf, &wos[i], s, f);
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
                let gx = density(frame, model, map, &prep[q], q, &v);
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
            out[i] = self.finish_iso(brdf, &wos[i], s, f);
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
pub(super) fn skewed(f: f64, v: &Vec3) -> f64 {
    let k = SKEW.with(std::cell::Cell::get);
    if k < 0.0 {
        f64::MAX
    } else if k > 0.0 {
        f * (1.0 - k + 2.0 * k * v.z)
    } else {
        f
    }
}
