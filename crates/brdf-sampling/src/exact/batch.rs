//! The coherent batch path of the exact sampler
//! ([`DirectionSampler::sample_eval_batch`](crate::DirectionSampler::sample_eval_batch)):
//! N queries located first, grouped by interval with a counting sort, and each group drawn in
//! turn, so an interval's tree, alias table and normaliser stay in cache for its group instead
//! of being fetched again for every query when ωo changes from pixel to pixel.

use brdf::{Brdf, PreparedRun, Vec3};
use partition_sampler::diagnostics::AuditedDraws;
use partition_sampler::{Audit, MAX_TRIALS_PER_SAMPLE, Point2, UniformSource};

use super::density::QueryDensity;
use super::fused::{IsoQuery, accepted, accepted_at, same_brdf};
use super::grid::TableVar;
use super::lanes::{self, Trials};
#[cfg(test)]
use super::lanes::{GOLDEN_GAMMA, mix64, unit};
use super::table::{LeafTable, query_theta};
#[cfg(test)]
use super::wave_iso::NO_WAVE;
use super::wave_iso::{IsoWave, wave_on, wave_seed};
use super::{ExactSet, Query};
use crate::disc::{DiscMap, count_evaluations};
use crate::layout::Turn;
use crate::{DirSample, EvalSample};

/// Runs of at least this many consecutive queries at one `ωo` (the same bits) on the
/// isotropic fast path draw their trials through the BRDF's caller-held
/// [`Brdf::prepare_run`] (for RGL files a blended `θo` slice, ≈ 3.4·10⁴ table entries read
/// once); shorter runs, and BRDFs without one, evaluate through
/// [`Brdf::prepare`]/[`Brdf::eval_prepared`], prepared once per run. The RGL slice's measured
/// break-even (docs/benchmarks.md §24.3): its blend costs ≈ 2.1·10⁵ instructions and saves
/// ≈ 270 per evaluation, ≈ 760 evaluations, ≈ 500 queries at ≈ 1.5 evaluations per sample.
pub(super) const PREPARED_RUN_MIN: usize = 512;

/// Trials per block call of the wavefront ([`wavefront`]): at most this many candidates'
/// `f` are evaluated in one [`PreparedRun::eval_block`] call.
const WAVE: usize = 512;

/// The stream of sample `i` of a wavefront: SplitMix64 started at `mix64(seed ⊕ mix64(i))`
/// (test support: the wavefront makes these states in lanes, [`lanes::keys`]).
#[cfg(test)]
#[derive(Clone, Copy)]
struct Stream(u64);

#[cfg(test)]
impl Stream {
    #[inline(always)]
    fn of(seed: u64, i: usize) -> Self {
        Self(mix64(seed ^ mix64(i as u64)))
    }
}

/// A sample's stream as a caller's uniform source (test support: [`LeafTable::draw`] from it
/// is the wavefront's sample).
///
/// [`LeafTable::draw`]: super::table::LeafTable::draw
#[cfg(test)]
impl UniformSource for Stream {
    fn next_uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(GOLDEN_GAMMA);
        unit(mix64(self.0))
    }
}

/// An accepted trial of [`wavefront`]: the disc point, its direction on the map and `g` there.
pub(super) type Drawn = (Point2, Vec3, f64);

/// `n` points of `g / ∫ g` on the disc by envelope rejection under `table`'s bounds, with
/// `g` the run's density on `map` ([`run_density`]'s: `f` on the projected map, `2 f cos θi`
/// on the equal-area one), as a **wavefront**: every pending sample proposes one trial per
/// pass from its own stream, the trials inside the disc are evaluated together by
/// [`PreparedRun::eval_block`] (`wave` per call), and each is accepted or rejected as
/// [`LeafTable::draw`] would (`u₃·M_i < g`; `g > M_i` counted as a violation); the rejected
/// propose again in the next pass, until accepted or [`MAX_TRIALS_PER_SAMPLE`] trials
/// (`None`, counted as exhausted). Each sample's law is `draw`'s (the same trial and test;
/// only where its uniforms come from differs): sample `i`'s uniforms are its own SplitMix64
/// stream keyed by `(seed, i)`, `seed` one 64-bit word made of two uniforms of `u`, so the
/// result is a function of `u`'s state and `i` only — not of `wave`, the pass a trial falls
/// in, nor the thread. Sample `i` is handed to `emit(i, drawn)` once, when it is decided (in
/// no particular order of `i`).
///
/// The pending samples are kept in structure-of-arrays form (index, stream state), a pass
/// making a block's trials in vector lanes ([`lanes::trials`]: uniforms, leaf pick, point,
/// bound, threshold and direction), evaluating those inside the disc in one call and testing
/// them; every pending sample makes one trial per pass, so a pass count stands for every
/// sample's trial count.
///
/// [`LeafTable::draw`]: super::table::LeafTable::draw
/// [`MAX_TRIALS_PER_SAMPLE`]: partition_sampler::MAX_TRIALS_PER_SAMPLE
#[allow(clippy::too_many_arguments)]
fn wavefront_with<E: FnMut(usize, Option<Drawn>)>(
    run: &dyn PreparedRun,
    table: &LeafTable,
    map: DiscMap,
    theta: f64,
    n: usize,
    wave: usize,
    u: &mut dyn UniformSource,
    audit: &mut Audit,
    mut emit: E,
) {
    let seed = wave_seed(u);
    let wave = wave.max(1).min(n.max(1));
    let arch = pulp::Arch::new();
    // This thread's kept arrays (`try_with`: during the thread's teardown, fresh ones; a
    // nested call finds none and makes its own).
    let mut kept = WAVE_ARRAYS
        .try_with(|s| s.take())
        .ok()
        .flatten()
        .unwrap_or_default();
    // Taken out by value: locals the compiler keeps in registers across `emit` (through the
    // box, each push would reload the vector's length: ≈ 13 instructions per sample, §29.1).
    let WaveArrays {
        mut idx,
        mut state,
        mut idx2,
        mut state2,
        t: mut kept_t,
        mut lane,
        mut rest,
        mut dirs,
        mut f,
    } = std::mem::take(&mut *kept);
    // The pending samples: index and stream state (and the next pass's). Every pending sample
    // makes one trial per pass, so after `pass` passes each has made `pass` trials.
    idx.clear();
    idx.extend(0..n);
    state.clear();
    state.resize(n, 0);
    lanes::keys(arch, seed, &mut state);
    idx2.clear();
    state2.clear();
    // One block's trials (`lanes.rs`), and its candidates inside the disc: the trial's entry
    // in the block, direction, value.
    if kept_t.as_ref().is_none_or(|t| t.room() < wave) {
        kept_t = Some(Trials::new(wave));
    }
    let t = kept_t.as_mut().expect("made above");
    if lane.len() < wave {
        lane.resize(wave, 0);
        rest.resize(wave, 0);
        dirs.resize(wave, Vec3::zeros());
        f.resize(wave, 0.0);
    }
    let thin = table.thins();
    // The thinning layer serving θo, picked once for the run.
    let base = table.layer_base(theta);
    let (mut trials, mut violations, mut pass) = (0u64, 0u64, 0u64);
    while !idx.is_empty() {
        if pass >= MAX_TRIALS_PER_SAMPLE {
            for &i in idx.iter() {
                audit.exhausted += 1;
                emit(i, None);
            }
            break;
        }
        pass += 1;
        trials += idx.len() as u64;
        idx2.clear();
        state2.clear();
        for (ib, sb) in idx.chunks(wave).zip(state.chunks_mut(wave)) {
            let len = ib.len();
            lanes::trials(arch, table, map, thin, base, sb, t);
            // The candidates inside the disc (and, with thinning bounds, whose threshold
            // `u₃·M_i` is below their sub-cell's bound `M_is ≥ g`: the others would be
            // rejected by `g` too), compacted without branches; the others propose again next
            // pass.
            let mut c = 0;
            if thin {
                // Both lists without branches: candidates in `lane`, the others in `rest`
                // (`inside` is the candidate flag: inside the disc, below the sub-cell bound).
                let mut r = 0;
                for k in 0..len {
                    let go = t.inside[k];
                    lane[c] = k;
                    dirs[c] = t.dir[k];
                    rest[r] = k;
                    c += usize::from(go);
                    r += usize::from(!go);
                }
                for &k in &rest[..r] {
                    idx2.push(ib[k]);
                    state2.push(sb[k]);
                }
            } else {
                for k in 0..len {
                    lane[c] = k;
                    dirs[c] = t.dir[k];
                    c += usize::from(t.inside[k]);
                }
                if c < len {
                    for k in (0..len).filter(|&k| !t.inside[k]) {
                        idx2.push(ib[k]);
                        state2.push(sb[k]);
                    }
                }
            }
            count_evaluations(c as u64);
            run.eval_block(&dirs[..c], &mut f[..c]);
            let bound = if thin { &t.cap } else { &t.bound };
            for ((&k, &v), &fv) in lane[..c].iter().zip(&dirs[..c]).zip(&f[..c]) {
                let g = match map {
                    DiscMap::Projected => fv,
                    DiscMap::EqualArea => 2.0 * v.z * fv,
                };
                // Above the bound it was drawn under (the sub-cell's with thinning).
                violations += u64::from(g > bound[k]);
                if t.threshold[k] < g {
                    emit(ib[k], Some(([t.x[k], t.y[k]], v, g)));
                } else {
                    idx2.push(ib[k]);
                    state2.push(sb[k]);
                }
            }
        }
        std::mem::swap(&mut idx, &mut idx2);
        std::mem::swap(&mut state, &mut state2);
    }
    audit.trials += trials;
    audit.violations += violations;
    audit.samples += n as u64;
    // Kept for the next call unless they grew past `WAVE_KEEP_MAX` samples (then freed).
    if idx.capacity().max(idx2.capacity()) <= WAVE_KEEP_MAX {
        *kept = WaveArrays {
            idx,
            state,
            idx2,
            state2,
            t: kept_t,
            lane,
            rest,
            dirs,
            f,
        };
        let _ = WAVE_ARRAYS.try_with(|s| s.set(Some(kept)));
    }
}

/// The [`EvalSample`] of an accepted trial on the **equal-area** map with direction `d` (on
/// the set's frame), `g(d) = gx = 2 f cos θi` and normaliser `a`, when the caller's BRDF is
/// the set's at the served `ωo`: `(turn·d, p, f)` with `p = (gx/a)/2`
/// (`DiscMap::EqualArea.area_to_solid_angle(gx / a, d)`) and `f = gx / (2 cos θi)` — what
/// [`accepted_at`] followed by `finish_known` with `same` and a served `ωo` returns, bit for
/// bit, when `cos θi > 0`, `p > 0` and `f` is finite; `None` otherwise (the caller then takes
/// that general path). `ident`: `turn` is the identity, whose `(1·x − 0·y, 0·x + 1·y)` is
/// `(x, y)` for finite coordinates that are not `−0` (a trial's `x0 + u·dx` never is:
/// `−0 + (+0) = +0`, and the map's `x·√(2 − r²)` keeps the sign of a nonzero `x`), so `d` is
/// then used as it is. (The RGL sets' intervals are all on the equal-area map; a projected
/// interval's run keeps the general emit.)
#[inline(always)]
fn direct_sample(turn: Turn, ident: bool, d: Vec3, gx: f64, a: f64) -> Option<EvalSample> {
    let pdf = (gx / a) * 0.5;
    let f = gx / (2.0 * d.z);
    let wi = if ident { d } else { turn.apply(&d) };
    (d.z > 0.0 && pdf > 0.0 && f.is_finite()).then_some(EvalSample { wi, pdf, f })
}

#[cfg(test)]
thread_local! {
    /// Test switch: `serve_general_run`'s wavefront emits through the general path only
    /// (no [`direct_sample`]).
    static NO_DIRECT_EMIT: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// Test count of the samples emitted through [`direct_sample`], per turn (identity,
    /// other).
    static DIRECT_EMITS: std::cell::Cell<[u64; 2]> = const { std::cell::Cell::new([0; 2]) };
}

/// Whether `serve_general_run` may emit through [`direct_sample`] (always, but for the
/// tests' reference runs).
#[inline(always)]
fn direct_emit_on() -> bool {
    #[cfg(test)]
    if NO_DIRECT_EMIT.with(std::cell::Cell::get) {
        return false;
    }
    true
}

/// Most samples whose [`WaveArrays`] a thread keeps after a wavefront (32 bytes each, 2 MiB
/// here); a longer wavefront's arrays are freed when it ends.
const WAVE_KEEP_MAX: usize = 1 << 16;

/// [`wavefront_with`]'s working arrays, kept per thread between calls (no allocation and no
/// zero-filled buffer per call once a thread has drawn a wavefront of the size): the pending
/// samples' indices and stream states (this pass's and the next's), one block's trials, and
/// its candidates inside the disc (entry in the block, direction, value) and, with thinning bounds,
/// the block entries that are not candidates. Their contents are
/// set by each call before they are read: nothing carries over but the room.
#[derive(Default)]
struct WaveArrays {
    idx: Vec<usize>,
    state: Vec<u64>,
    idx2: Vec<usize>,
    state2: Vec<u64>,
    t: Option<Trials>,
    lane: Vec<usize>,
    rest: Vec<usize>,
    dirs: Vec<Vec3>,
    f: Vec<f64>,
}

thread_local! {
    /// This thread's [`WaveArrays`], taken for the length of a wavefront.
    static WAVE_ARRAYS: std::cell::Cell<Option<Box<WaveArrays>>> =
        const { std::cell::Cell::new(None) };
}

/// [`wavefront_with`]'s samples in index order (test support).
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
fn wavefront(
    run: &dyn PreparedRun,
    table: &LeafTable,
    map: DiscMap,
    theta: f64,
    n: usize,
    wave: usize,
    u: &mut dyn UniformSource,
    audit: &mut Audit,
) -> Vec<Option<(Point2, f64)>> {
    let mut drawn = vec![None; n];
    wavefront_with(run, table, map, theta, n, wave, u, audit, |i, d| {
        drawn[i] = d.map(|(p, _, g)| (p, g));
    });
    drawn
}

/// A query's group key in [`ExactSet::sample_eval_grouped`]'s locate pass, one `u32`: an
/// isotropic fast-path query's interval (`< GENERAL`), or [`GENERAL`]` | j` for a query
/// located by the general path and stored as `general[j]`, or [`UNSERVED`] for a query the set
/// does not serve (at or below the horizon).
const GENERAL: u32 = 1 << 31;

/// The key of a query the set does not serve.
const UNSERVED: u32 = u32::MAX;

/// Most queries one grouped pass takes: its keys and indices are `u32` below [`GENERAL`]
/// (longer batches are served as consecutive passes of this many).
const MAX_PASS: usize = (GENERAL - 1) as usize;

/// The batch path's working arrays, kept per thread between calls (no allocation and no
/// zero-filled buffer per call once a thread has served a batch of the size): the queries'
/// group keys, the general queries, the counting sort's bucket starts and the serving order.
#[derive(Default)]
struct Scratch {
    /// Per query, in the caller's order: its key (see [`GENERAL`]).
    key: Vec<u32>,
    /// The general path's queries, `(group, query)`, in the caller's order.
    general: Vec<(u32, Query)>,
    /// Per group `g`, where its queries start in `order` (then, after the scatter, end).
    start: Vec<u32>,
    /// The served queries' indices, by group, the caller's order within one.
    order: Vec<u32>,
    /// Per group, the end in `order` of the span of groups from it on whose every draw is a
    /// split trial, or 0 for a group of other draws (see [`Ahead`]).
    reach: Vec<u32>,
    /// Per group: some query has its predecessor's `ωo` bits (a run of more than one query in
    /// the caller's order); then, whether the group's fast-path queries are drawn as one
    /// random-`ωo` wavefront ([`ExactSet::serve_iso_wave`]).
    repeat: Vec<bool>,
    wave: Vec<bool>,
    /// One wave group's fast-path queries, and the wavefront's working arrays.
    members: Vec<u32>,
    iso_wave: IsoWave,
}

/// The wave groups of a pass ([`ExactSet::serve_iso_wave`]): their streams' key, the `pulp`
/// dispatch, which groups they are, where each group ends in the serving order, and the
/// working arrays.
struct Waves<'a> {
    seed: u64,
    arch: pulp::Arch,
    wave: &'a [bool],
    end: &'a [u32],
    members: &'a mut Vec<u32>,
    w: &'a mut IsoWave,
}

thread_local! {
    /// This thread's [`Scratch`], taken for the length of a batch (a nested batch on the
    /// same thread finds none and makes its own).
    static SCRATCH: std::cell::Cell<Option<Box<Scratch>>> = const { std::cell::Cell::new(None) };
}

/// Split trials ([`UniformSource::next_uniform4_split`]) filled ahead per block call of
/// [`Ahead`].
const TRIALS_AHEAD: usize = 64;

/// The batch path's uniforms: `src`'s split trials filled [`TRIALS_AHEAD`] at a time
/// ([`UniformSource::fill_uniform4_split`], one call through the `dyn` per block instead of one
/// per trial) and handed out in order — **the same trials in the same order** as calls on
/// `src`. A block is at most `left` trials, `left` a lower bound (set by the caller) of the
/// split trials the pass will still draw, so every filled trial is consumed and `src` ends
/// where one call per trial would leave it. `left = 0` passes every call through.
///
/// Only a group whose every draw is a split trial fills ahead (in
/// [`ExactSet::grouped_pass`]); the other calls (never made while trials are filled) take the filled trials' values one by
/// one first (for a sequence the same values in the same order; for a generator still
/// uniforms on `[0, 1)`), then `src`'s.
struct Ahead<'a> {
    src: &'a mut dyn UniformSource,
    buf: [[f64; 4]; TRIALS_AHEAD],
    /// The next filled trial, and the end of the filled ones.
    pos: usize,
    len: usize,
    /// Within a filled trial, the next value for [`UniformSource::next_uniform`].
    part: usize,
    /// A lower bound of the split trials still to be drawn (see the type's doc).
    left: usize,
}

impl<'a> Ahead<'a> {
    fn new(src: &'a mut dyn UniformSource) -> Self {
        Self {
            src,
            buf: [[0.0; 4]; TRIALS_AHEAD],
            pos: 0,
            len: 0,
            part: 0,
            left: 0,
        }
    }

    /// The next trial when none is filled: a block of at most `left` (≥ 2) filled, else one
    /// passed through.
    #[inline(never)]
    fn refill(&mut self) -> [f64; 4] {
        let k = self.left.min(TRIALS_AHEAD);
        #[cfg(test)]
        let k = if NO_FILL.with(std::cell::Cell::get) {
            0
        } else {
            k
        };
        if k < 2 {
            return self.src.next_uniform4_split();
        }
        self.src.fill_uniform4_split(&mut self.buf[..k]);
        self.pos = 1;
        self.len = k;
        self.buf[0]
    }
}

/// The batch path's uniform source: the caller's stream itself, or [`Ahead`] over it.
trait Source: UniformSource {
    /// Sets [`Ahead`]'s lower bound of the split trials still to be drawn (nothing for the
    /// caller's stream).
    fn set_left(&mut self, _left: usize) {}
    /// This source as a `dyn UniformSource`.
    fn as_dyn(&mut self) -> &mut dyn UniformSource;
}

impl Source for dyn UniformSource + '_ {
    #[inline]
    fn as_dyn(&mut self) -> &mut dyn UniformSource {
        self
    }
}

impl Source for Ahead<'_> {
    #[inline]
    fn set_left(&mut self, left: usize) {
        self.left = left;
    }
    #[inline]
    fn as_dyn(&mut self) -> &mut dyn UniformSource {
        self
    }
}

#[cfg(test)]
thread_local! {
    /// Test support: `true` makes [`Ahead`] pass every call through (the reference).
    static NO_FILL: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// Test support: `true` turns [`ExactSet::one_wo`] off (every pass located, counted and
    /// sorted: the reference).
    static NO_ONE_WO: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

impl UniformSource for Ahead<'_> {
    fn next_uniform(&mut self) -> f64 {
        if self.pos < self.len {
            let v = self.buf[self.pos][self.part];
            self.part += 1;
            if self.part == 4 {
                self.part = 0;
                self.pos += 1;
            }
            return v;
        }
        self.src.next_uniform()
    }

    fn next_uniform4(&mut self) -> [f64; 4] {
        if self.pos < self.len {
            return [
                self.next_uniform(),
                self.next_uniform(),
                self.next_uniform(),
                self.next_uniform(),
            ];
        }
        self.src.next_uniform4()
    }

    #[inline(always)]
    fn next_uniform4_split(&mut self) -> [f64; 4] {
        if self.pos < self.len && self.part == 0 {
            let us = self.buf[self.pos];
            self.pos += 1;
            return us;
        }
        if self.pos < self.len {
            return self.next_uniform4();
        }
        self.refill()
    }
}

/// The bits of a direction: queries of one run share them.
#[inline]
fn bits(wo: &Vec3) -> [u64; 3] {
    [wo.x.to_bits(), wo.y.to_bits(), wo.z.to_bits()]
}

/// One trial point's density at a run's prepared `ωo`: [`QueryDensity::at`] (no rotation: the
/// isotropic frame) with the evaluation through the run, the same value bit for bit.
#[inline]
fn run_density(run: &dyn PreparedRun, map: DiscMap, p: Point2) -> f64 {
    let r2 = p[0] * p[0] + p[1] * p[1];
    if !(r2 < 1.0) {
        return 0.0;
    }
    count_evaluations(1);
    let v = map.to_direction(p);
    let f = run.eval(&v);
    match map {
        DiscMap::Projected => f,
        DiscMap::EqualArea => 2.0 * v.z * f,
    }
}

/// A pass's one `ωo` located ([`ExactSet::one_wo`]): by the isotropic fast path or the general
/// one.
enum OneWo {
    Iso(IsoQuery),
    General(Query),
}

/// The per-run part of an isotropic query ([`ExactSet::draw_iso`]'s, made once).
struct IsoRun<'a> {
    q: &'a IsoQuery,
    wo: &'a Vec3,
    /// The normaliser at the query's `cos θo`.
    a: f64,
    /// The rotation from the interval's frame back to the world.
    turn: Turn,
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

    /// The group of `wo` in the batch path (the interval's index in the set's list), `None`
    /// for a query the set does not serve (test support: the serving order).
    #[cfg(test)]
    fn group_of(&self, wo: &Vec3, offsets: &[usize]) -> Option<usize> {
        match self.locate_iso(wo) {
            Some(q) => Some(q.interval),
            None => self.locate_keys(wo).map(|q| offsets[q.cell] + q.interval),
        }
    }

    /// The query of `wos[0]` — the isotropic fast path's ([`ExactSet::locate_iso`]), else the
    /// general one ([`ExactSet::locate_keys`]), as the locate pass finds it — when `wos` is one
    /// run of at least [`PREPARED_RUN_MIN`] queries (every query with `wos[0]`'s bits) that
    /// the set serves; else `None`. At most one pass over `wos` (stops at the first other
    /// `ωo`).
    fn one_wo(&self, wos: &[Vec3]) -> Option<OneWo> {
        #[cfg(test)]
        if NO_ONE_WO.with(std::cell::Cell::get) {
            return None;
        }
        if wos.len() < PREPARED_RUN_MIN {
            return None;
        }
        let b0 = bits(&wos[0]);
        if !wos.iter().all(|wo| bits(wo) == b0) {
            return None;
        }
        match self.locate_iso(&wos[0]) {
            Some(q) => Some(OneWo::Iso(q)),
            None => self.locate_keys(&wos[0]).map(OneWo::General),
        }
    }

    /// The batch path: `out[k]` for `wos[k]`. Queries are located, counted per interval and
    /// served group by group in the order of the intervals (queries of one interval in the
    /// caller's order); the uniforms are consumed in that order. Queries at or below the
    /// horizon get [`EvalSample::NONE`] and consume nothing. Each sample is drawn by the
    /// one-query path's arithmetic ([`ExactSet::draw_iso`] or [`ExactSet::draw_located`]), so
    /// its law is the same, and from the same uniforms the same bits.
    ///
    /// **Random `ωo`**: an interval group of an isotropic `cos θo`-table set (the fast path)
    /// whose queries hold no run of more than one query (no query with its predecessor's bits,
    /// in the caller's order) is drawn as one wavefront ([`ExactSet::serve_iso_wave`]): each
    /// fast-path query `draw_iso`'s law from its own SplitMix64 stream keyed by one word of
    /// `u` drawn at the pass's start and by the query's index — other samples than the
    /// one-query path's from the same seed, still a function of the seed only.
    ///
    /// The locate pass keeps one `u32` key per query ([`GENERAL`]): an isotropic fast-path
    /// query is re-derived from its `ωo` when served (`r = |(ωo.x, ωo.y)|`, `cos θo`, the
    /// interval from the key: [`ExactSet::locate_iso`]'s values, bit for bit), a general one is
    /// stored once; the counting sort moves `u32` indices only. Batches of more than
    /// [`MAX_PASS`] queries are served as consecutive passes of that many.
    ///
    /// **Runs of one `ωo`** (consecutive queries with the same bits: a pixel's samples, a
    /// fixed-`ωo` benchmark) are located once, and their per-query work — the BRDF's
    /// preparation, the normaliser, the rotation back to the world — is done once per run;
    /// runs of at least [`PREPARED_RUN_MIN`] queries on the isotropic fast path evaluate
    /// their trials through the BRDF's [`Brdf::prepare_run`] when it has one. When that run
    /// [`prefers_blocks`](PreparedRun::prefers_blocks) (RGL files: evaluations in vector
    /// lanes) and the interval has a compact table, such a run of an isotropic set (fast or
    /// general path) is drawn by [`wavefront`] instead: other samples than the one-query
    /// path's (each from its own stream), the same law.
    pub(super) fn sample_eval_grouped(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut Vec<EvalSample>,
    ) {
        out.clear();
        out.resize(wos.len(), EvalSample::NONE);
        self.sample_eval_passes(brdf, wos, u, out, MAX_PASS);
    }

    /// [`ExactSet::sample_eval_grouped`] with `out` sized, in passes of at most `pass` (≥ 1,
    /// ≤ [`MAX_PASS`]) queries: each pass is grouped and served on its own, in turn.
    fn sample_eval_passes(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut [EvalSample],
        pass: usize,
    ) {
        // `try_with`: during the thread's teardown (no thread-local any more) a fresh one.
        let mut scratch = SCRATCH
            .try_with(|s| s.take())
            .ok()
            .flatten()
            .unwrap_or_default();
        let mut base = 0;
        for part in wos.chunks(pass.clamp(1, MAX_PASS)) {
            let end = base + part.len();
            self.grouped_pass(brdf, part, u, &mut out[base..end], &mut scratch);
            base = end;
        }
        let _ = SCRATCH.try_with(|s| s.set(Some(scratch)));
    }

    /// One pass of [`ExactSet::sample_eval_grouped`] over at most [`MAX_PASS`] queries, `out`
    /// holding [`EvalSample::NONE`] for each.
    fn grouped_pass(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut [EvalSample],
        scratch: &mut Scratch,
    ) {
        let Scratch {
            key,
            general,
            start,
            order,
            reach,
            repeat,
            wave,
            members,
            iso_wave,
        } = scratch;
        // A pass of one served `ωo` (a fixed-ωo benchmark's chunk, a pixel's samples) long
        // enough for a prepared run: the locate, count and sort below would find one group
        // holding one run, in the caller's order, drawn from the caller's stream (no group
        // fills ahead: it is no span; none is a wavefront group: it repeats). That run is
        // served directly by the call `serve_order` makes for it: the same samples bit for
        // bit, without the per-query bookkeeping.
        if let Some(one) = self.one_wo(wos) {
            order.clear();
            order.extend(0..wos.len() as u32);
            let mut audit = Audit::default();
            match one {
                OneWo::Iso(q) => self.serve_iso_run(brdf, &q, &wos[0], order, u, &mut audit, out),
                OneWo::General(q) => {
                    self.serve_general_run(brdf, &q, &wos[0], order, u, &mut audit, out)
                }
            }
            self.counters.record(&audit);
            return;
        }
        let offsets = self.interval_offsets();
        let groups = offsets[offsets.len() - 1];
        if groups >= MAX_PASS {
            // Never for a set this crate builds (a few hundred intervals): one query at a time.
            for (o, wo) in out.iter_mut().zip(wos) {
                *o = crate::DirectionSampler::sample_eval(self, brdf, wo, u);
            }
            return;
        }
        // Isotropic queries by the fast path's locate (`ExactSet::locate_iso`), the others
        // (anisotropic, grazing) by the general one; a query with its predecessor's bits takes
        // its key (a general query's is its stored query's). Each served query is counted in
        // its group's bucket (`start[g + 1]`) on the way.
        key.clear();
        general.clear();
        start.clear();
        start.resize(groups + 1, 0);
        repeat.clear();
        repeat.resize(groups + 1, false);
        let mut prev: Option<([u64; 3], u32, usize)> = None;
        for wo in wos {
            let b = bits(wo);
            let (k, g) = match prev {
                Some((pb, pk, pg)) if pb == b => {
                    repeat[pg] = true;
                    (pk, pg)
                }
                _ => match self.locate_iso(wo) {
                    Some(q) => (q.interval as u32, q.interval),
                    None => match self.locate_keys(wo) {
                        Some(q) => {
                            let g = offsets[q.cell] + q.interval;
                            general.push((g as u32, q));
                            (GENERAL | (general.len() - 1) as u32, g)
                        }
                        None => (UNSERVED, groups),
                    },
                },
            };
            // An unserved query (`g = groups`) has no bucket.
            if let Some(c) = start.get_mut(g + 1) {
                *c += 1;
            }
            key.push(k);
            prev = Some((b, k, g));
        }
        // Counting sort of the served queries' indices by group (stable).
        let group = |k: u32| -> Option<usize> {
            if k < GENERAL {
                Some(k as usize)
            } else if k == UNSERVED {
                None
            } else {
                Some(general[(k & !GENERAL) as usize].0 as usize)
            }
        };
        for g in 0..groups {
            start[g + 1] += start[g];
        }
        // The groups drawn as a random-ωo wavefront: an interval of an isotropic `cos θo`-table
        // set (the fast path's) with a table, some query, and no run of more than one query (a
        // run is drawn once prepared, below).
        wave.clear();
        wave.resize(groups, false);
        let mut waves = false;
        let fast = self.isotropic && self.var == TableVar::Cos;
        if let Some(cell) = self.cells.first().filter(|_| fast && wave_on()) {
            for g in 0..groups.min(cell.tables.len()) {
                let w = start[g + 1] > start[g] && !repeat[g] && cell.tables[g].is_some();
                wave[g] = w;
                waves |= w;
            }
        }
        // The spans of groups whose every draw is a split trial (an empty group, or an
        // isotropic interval with a table and fewer queries than a prepared run's: a group
        // holds each of its runs whole), whose uniforms are filled ahead (`Ahead`).
        reach.clear();
        reach.resize(groups, 0);
        let mut spans = false;
        if let Some(cell) = self.cells.first().filter(|_| self.isotropic) {
            let mut end = 0;
            for g in (0..groups.min(cell.tables.len())).rev() {
                let size = start[g + 1] - start[g];
                if !wave[g]
                    && (size == 0
                        || ((size as usize) < PREPARED_RUN_MIN && cell.tables[g].is_some()))
                {
                    end = if end == 0 { start[g + 1] } else { end };
                    reach[g] = end;
                    spans |= size > 0;
                } else {
                    end = 0;
                }
            }
        }
        let served = start[groups] as usize;
        order.clear();
        order.resize(served, 0);
        for (i, &k) in key.iter().enumerate() {
            if let Some(g) = group(k) {
                order[start[g] as usize] = i as u32;
                start[g] += 1;
            }
        }
        let mut audit = Audit::default();
        // The wave groups' streams are keyed by one word of `u`, drawn before any other draw of
        // the pass.
        let mut waves = waves.then(|| Waves {
            seed: wave_seed(u),
            arch: pulp::Arch::new(),
            wave,
            end: start,
            members,
            w: iso_wave,
        });
        let (key, general, order) = (&key[..], &general[..], &order[..]);
        if spans {
            let mut u = Ahead::new(u);
            self.serve_order(
                brdf, wos, key, general, reach, order, &mut waves, &mut u, &mut audit, out,
            );
        } else {
            // No group to fill ahead for (an anisotropic set, say): the caller's stream itself.
            self.serve_order(
                brdf, wos, key, general, reach, order, &mut waves, u, &mut audit, out,
            );
        }
        self.counters.record(&audit);
    }

    /// [`ExactSet::grouped_pass`]'s serving: the served queries in `order`, run by run, from
    /// `u` ([`Ahead`] when some group's uniforms are filled ahead, `reach` its spans).
    #[allow(clippy::too_many_arguments)]
    fn serve_order<U: Source + ?Sized>(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        key: &[u32],
        general: &[(u32, Query)],
        reach: &[u32],
        order: &[u32],
        waves: &mut Option<Waves<'_>>,
        u: &mut U,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        // Runs in the serving order: queries of one `ωo` share their interval, so a run of
        // the caller's order stays one run here.
        let mut a = 0;
        while a < order.len() {
            let first = order[a] as usize;
            let k = key[first];
            if let Some(wv) = waves
                .as_mut()
                .filter(|wv| k < GENERAL && wv.wave[k as usize])
            {
                // A wave group from here to its end: its fast-path queries as one wavefront,
                // its general ones (grazing, at the last interval) one by one.
                let end = wv.end[k as usize] as usize;
                wv.members.clear();
                for &i in &order[a..end] {
                    let ki = key[i as usize];
                    if ki < GENERAL {
                        wv.members.push(i);
                    } else {
                        u.set_left(0);
                        let q = &general[(ki & !GENERAL) as usize].1;
                        let one = std::slice::from_ref(&i);
                        let wo = &wos[i as usize];
                        self.serve_general_run(brdf, q, wo, one, u.as_dyn(), audit, out);
                    }
                }
                self.serve_iso_wave(
                    brdf, wos, k as usize, wv.members, wv.seed, wv.arch, wv.w, audit, out,
                );
                a = end;
                continue;
            }
            let wo = &wos[first];
            let b0 = bits(wo);
            let mut b = a + 1;
            while b < order.len() && bits(&wos[order[b] as usize]) == b0 {
                b += 1;
            }
            let run = &order[a..b];
            // Within a span of groups whose every draw is a split trial, each query from the
            // run's last to the span's end draws at least one: the uniforms filled ahead.
            u.set_left(if k < GENERAL {
                (reach[k as usize] as usize).saturating_sub(b - 1)
            } else {
                0
            });
            if k < GENERAL {
                let cos = wo.z.min(1.0);
                let q = IsoQuery {
                    interval: k as usize,
                    r: (wo.x * wo.x + wo.y * wo.y).sqrt(),
                    cos,
                };
                if b == a + 1 {
                    // A run of one query (a random ωo in a group that is no wavefront, or
                    // with the wavefront off): the one-query path itself, whose
                    // arithmetic `serve_iso_run` repeats for a run (the same bits).
                    let (s, f) = self.draw_iso(&q, wo, u, audit);
                    out[first] = self.finish_iso(brdf, wo, s, f);
                } else {
                    self.serve_iso_run(brdf, &q, wo, run, u.as_dyn(), audit, out);
                }
            } else {
                let q = &general[(k & !GENERAL) as usize].1;
                self.serve_general_run(brdf, q, wo, run, u.as_dyn(), audit, out);
            }
            a = b;
        }
    }

    /// The queries `run` (indices into `out`) of one isotropic query `q` at `wo`:
    /// [`ExactSet::draw_iso`]'s arithmetic with its per-query part done once.
    #[allow(clippy::too_many_arguments)]
    fn serve_iso_run(
        &self,
        brdf: &dyn Brdf,
        q: &IsoQuery,
        wo: &Vec3,
        run: &[u32],
        u: &mut dyn UniformSource,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        let cell = &self.cells[0];
        let iv = &cell.intervals[q.interval];
        let rec = &cell.iso[q.interval];
        let frame = Vec3::new(q.r, 0.0, q.cos);
        let a = rec.normaliser(q.cos, iv);
        let turn = Turn::of_azimuth(wo, q.r);
        let prepared = if run.len() >= PREPARED_RUN_MIN {
            self.brdf.prepare_run(&frame)
        } else {
            None
        };
        let at = IsoRun { q, wo, a, turn };
        // The table of the θo layer serving the query (`LeafTable::serving`).
        let table = cell.tables[q.interval]
            .as_ref()
            .map(|t| t.serving_cos(q.cos));
        match prepared {
            Some(p) if p.prefers_blocks() && table.is_some() => {
                let table = table.expect("checked");
                // `finish_iso`'s test of the caller's BRDF, made once for the run.
                let same = same_brdf(brdf, self.brdf.as_ref());
                let emit = |i: usize, d: Option<Drawn>| {
                    let (s, f) = match d {
                        Some((_, v, gx)) => accepted_at(rec.map, &at.turn, v, gx, at.a),
                        None => (DirSample::NONE, f64::NAN),
                    };
                    let f = f.is_finite().then_some(f);
                    out[run[i] as usize] = self.finish_known(brdf, at.wo, s, f, same);
                };
                let theta = query_theta(q.cos);
                wavefront_with(
                    p.as_ref(),
                    table,
                    rec.map,
                    theta,
                    run.len(),
                    WAVE,
                    u,
                    audit,
                    emit,
                );
            }
            Some(p) => {
                let g = |x| run_density(p.as_ref(), rec.map, x);
                self.serve_iso_with(brdf, &at, &g, run, u, audit, out);
            }
            None => {
                let g = QueryDensity::in_frame(
                    self.brdf.as_ref(),
                    true,
                    &frame,
                    Turn::IDENTITY,
                    rec.map,
                );
                self.serve_iso_with(brdf, &at, &|x| g.at(x), run, u, audit, out);
            }
        }
    }

    /// [`ExactSet::serve_iso_run`]'s draws with the trials' density `g`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn serve_iso_with<G: Fn(Point2) -> f64>(
        &self,
        brdf: &dyn Brdf,
        at: &IsoRun<'_>,
        g: &G,
        run: &[u32],
        u: &mut dyn UniformSource,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        let cell = &self.cells[0];
        let iv = &cell.intervals[at.q.interval];
        let rec = &cell.iso[at.q.interval];
        let table = cell.tables[at.q.interval]
            .as_ref()
            .map(|t| t.serving_cos(at.q.cos));
        for &k in run {
            let k = k as usize;
            let drawn = match table {
                Some(table) => table.draw(g, u, audit),
                None => iv.tree.sample_envelope_of(g, u, audit),
            };
            let (s, f) = match drawn {
                Some((x, gx)) => accepted(rec.map, &at.turn, x, gx, at.a),
                None => (DirSample::NONE, f64::NAN),
            };
            out[k] = self.finish_iso(brdf, at.wo, s, f);
        }
    }

    /// The queries `run` of one general query `q` at `wo`: [`ExactSet::draw_located`]'s
    /// arithmetic with the query density and the normaliser made once.
    #[allow(clippy::too_many_arguments)]
    fn serve_general_run(
        &self,
        brdf: &dyn Brdf,
        q: &Query,
        wo: &Vec3,
        run: &[u32],
        u: &mut dyn UniformSource,
        audit: &mut Audit,
        out: &mut [EvalSample],
    ) {
        let iv = self.interval(q);
        // The table of the θo layer serving the query (`ExactSet::table_of`).
        let table = self.table_of(q);
        if let Some(table) = table.filter(|_| self.isotropic && run.len() >= PREPARED_RUN_MIN) {
            // `QueryDensity::in_frame`'s frame for an isotropic set: ωo turned back by the
            // query's rotation, the trials' directions unrotated.
            let frame = if q.turn == Turn::IDENTITY {
                q.wo
            } else {
                q.turn.undo(&q.wo)
            };
            if let Some(p) = self.brdf.prepare_run(&frame).filter(|p| p.prefers_blocks()) {
                let a = self.normaliser_of(q);
                let served = q.wo == *wo;
                // `finish`'s test of the caller's BRDF, made once for the run.
                let same = same_brdf(brdf, self.brdf.as_ref());
                // The run's own BRDF at the served ωo: every value is the accepted trial's,
                // and `accepted_at` + `finish_known` reduce to `direct_sample` (their
                // per-sample tests made once here); the other samples through them.
                let direct = same && served && iv.map == DiscMap::EqualArea && direct_emit_on();
                let ident = q.turn == Turn::IDENTITY;
                let (map, turn) = (iv.map, q.turn);
                let general = |d: Option<Drawn>| -> EvalSample {
                    match d {
                        Some((_, v, gx)) => {
                            let (s, f) = accepted_at(map, &turn, v, gx, a);
                            let f = (served && f.is_finite()).then_some(f);
                            self.finish_known(brdf, wo, s, f, same)
                        }
                        None => self.finish_known(brdf, wo, DirSample::NONE, None, same),
                    }
                };
                // By value: the run's constants in the closure itself, not behind references.
                let emit = move |i: usize, d: Option<Drawn>| {
                    let e = match d {
                        Some((_, v, gx)) if direct => direct_sample(turn, ident, v, gx, a),
                        _ => None,
                    };
                    #[cfg(test)]
                    if e.is_some() {
                        let slot = usize::from(!ident);
                        DIRECT_EMITS.with(|c| {
                            let mut n = c.get();
                            n[slot] += 1;
                            c.set(n)
                        });
                    }
                    out[run[i] as usize] = match e {
                        Some(e) => e,
                        None => general(d),
                    };
                };
                let theta = query_theta(q.cos);
                wavefront_with(
                    p.as_ref(),
                    table,
                    iv.map,
                    theta,
                    run.len(),
                    WAVE,
                    u,
                    audit,
                    emit,
                );
                return;
            }
        }
        let g = QueryDensity::in_frame(self.brdf.as_ref(), self.isotropic, &q.wo, q.turn, iv.map);
        let g = |p| g.at(p);
        // The one-query path's normaliser (the anisotropic records' patches, §24.2), bit for bit.
        let a = self.normaliser_of(q);
        let served = q.wo == *wo;
        for &k in run {
            let k = k as usize;
            let drawn = match table {
                Some(table) => table.draw(&g, u, audit),
                None => iv.tree.sample_envelope_of(&g, u, audit),
            };
            out[k] = match drawn {
                Some((x, gx)) => {
                    let (s, f) = accepted(iv.map, &q.turn, x, gx, a);
                    self.finish(brdf, wo, s, (served && f.is_finite()).then_some(f))
                }
                None => self.finish(brdf, wo, DirSample::NONE, None),
            };
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use std::sync::Arc;

    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

    use brdf::{Brdf, Outgoing, PreparedRun, Vec3, parse_spec};
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

    /// Phong with a caller-held run ([`Brdf::prepare_run`]) that counts its evaluations: the
    /// run's values are `eval`'s by construction, so what is tested is the batch path's use of
    /// it.
    struct WithRun {
        inner: Arc<dyn Brdf>,
        run_evals: AtomicU64,
        /// What its run's `prefers_blocks` says (`true`: the batch draws by the wavefront).
        blocks: bool,
    }

    impl WithRun {
        /// Phong (`n = 50`) with a fresh run counter; `blocks` as the field.
        fn phong(blocks: bool) -> Self {
            Self {
                inner: Arc::from(parse_spec("phong:n=50").unwrap()),
                run_evals: AtomicU64::new(0),
                blocks,
            }
        }
    }

    /// `n` outgoing directions from `qr`: uniform in θo ∈ [0°, 89°) and φo, except every 97th
    /// grazing (89.995°) and the next below the horizon (95°).
    fn mixed_wos(qr: &mut Xoshiro256PlusPlus, n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|k| match k % 97 {
                0 => brdf::direction_from_angles(89.995, 10.0),
                1 => brdf::direction_from_angles(95.0, 10.0),
                _ => {
                    brdf::direction_from_angles(89.0 * qr.next_uniform(), 360.0 * qr.next_uniform())
                }
            })
            .collect()
    }

    /// Anisotropic Ward (`alpha_x = 0.2, alpha_y = 0.4`) with options for a quick build (the
    /// general batch path's cases).
    fn small_ward() -> (Arc<dyn Brdf>, ExactOptions) {
        let ward: Arc<dyn Brdf> = Arc::from(parse_spec("ward:alpha_x=0.2,alpha_y=0.4").unwrap());
        let small = ExactOptions {
            max_trials: 8.0,
            normaliser_tol: 1e-3,
            initial_phi_cells: 4,
            ..ExactOptions::default()
        };
        (ward, small)
    }

    /// Phong `n = 50` with a counting caller-held run whose `prefers_blocks` is `blocks`, and
    /// the two cases of the run tests: that Phong with the default options, [`small_ward`].
    #[allow(clippy::type_complexity)]
    fn phong_and_small_ward(blocks: bool) -> (Arc<WithRun>, [(Arc<dyn Brdf>, ExactOptions); 2]) {
        let phong = Arc::new(WithRun::phong(blocks));
        let (ward, small) = small_ward();
        let cases: [(Arc<dyn Brdf>, ExactOptions); 2] =
            [(phong.clone(), ExactOptions::default()), (ward, small)];
        (phong, cases)
    }

    struct Run<'a> {
        brdf: &'a WithRun,
        wo: Vec3,
    }

    impl PreparedRun for Run<'_> {
        fn eval(&self, wi: &Vec3) -> f64 {
            self.brdf.run_evals.fetch_add(1, Relaxed);
            self.brdf.inner.eval(&self.wo, wi)
        }
        fn prefers_blocks(&self) -> bool {
            self.brdf.blocks
        }
    }

    impl Brdf for WithRun {
        fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            self.inner.eval(wo, wi)
        }
        fn prepare(&self, wo: &Vec3) -> Outgoing {
            self.inner.prepare(wo)
        }
        fn eval_prepared(&self, q: &Outgoing, wi: &Vec3) -> f64 {
            self.inner.eval_prepared(q, wi)
        }
        fn prepare_run(&self, wo: &Vec3) -> Option<Box<dyn PreparedRun + '_>> {
            Some(Box::new(Run {
                brdf: self,
                wo: *wo,
            }))
        }
        fn is_isotropic(&self) -> bool {
            self.inner.is_isotropic()
        }
        fn is_mirror_symmetric(&self) -> bool {
            self.inner.is_mirror_symmetric()
        }
        fn is_half_turn_symmetric(&self) -> bool {
            self.inner.is_half_turn_symmetric()
        }
    }

    /// Runs of one `ωo` (the same bits) in the batch: the batch returns, bit for bit, what the
    /// one-query path (`sample_eval`) returns when called in the batch's serving order (by
    /// interval, the caller's order within one) from the same seed — `ωi`, pdf and `f` — and
    /// leaves the stream in the same state. Runs of 1 to 700 queries, alternating `ωo` (runs
    /// of 1), two runs at one θo and two azimuths, grazing and below-horizon runs; on Phong with a caller-held run (used by the
    /// runs of at least [`PREPARED_RUN_MIN`] only) and on anisotropic Ward (the general path).
    /// With the random-ωo wavefront off (a group of runs of one is drawn by it otherwise:
    /// other samples, tested below).
    #[test]
    fn runs_of_one_wo_draw_the_one_query_paths_bits() {
        use super::{NO_WAVE, PREPARED_RUN_MIN};
        NO_WAVE.with(|c| c.set(true));
        let (phong, cases) = phong_and_small_ward(false);
        for (brdf, opts) in cases {
            let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
            let mut qr = Xoshiro256PlusPlus::seed_from_u64(21);
            let mut random =
                || brdf::direction_from_angles(89.0 * qr.next_uniform(), 360.0 * qr.next_uniform());
            let mut wos = Vec::new();
            for len in [1, 2, 5, 64, 600, 1, 700, 3, 511, 512] {
                let wo = random();
                wos.extend(std::iter::repeat_n(wo, len));
            }
            let (a, b) = (random(), random());
            wos.extend((0..40).map(|k| if k % 2 == 0 { a } else { b }));
            wos.extend(std::iter::repeat_n(
                brdf::direction_from_angles(89.995, 10.0),
                300,
            ));
            wos.extend(std::iter::repeat_n(
                brdf::direction_from_angles(95.0, 10.0),
                4,
            ));
            // Runs at one θo and two azimuths (the same cos θo bits).
            wos.extend(std::iter::repeat_n(
                brdf::direction_from_angles(40.0, 10.0),
                5,
            ));
            wos.extend(std::iter::repeat_n(
                brdf::direction_from_angles(40.0, 200.0),
                5,
            ));
            // The same ωo again after another: a run of its own.
            wos.extend(std::iter::repeat_n(a, 530));

            let before = phong.run_evals.load(Relaxed);
            let mut r1 = Xoshiro256PlusPlus::seed_from_u64(3);
            let mut out = Vec::new();
            set.sample_eval_batch(brdf.as_ref(), &wos, &mut r1, &mut out);
            let through_runs = phong.run_evals.load(Relaxed) - before;

            // The serving order: by interval (the set's list), the caller's order within one.
            let offsets = set.interval_offsets();
            let mut order: Vec<(usize, usize)> = wos
                .iter()
                .enumerate()
                .filter_map(|(k, wo)| set.group_of(wo, &offsets).map(|g| (g, k)))
                .collect();
            order.sort_by_key(|&(g, _)| g);
            let mut r2 = Xoshiro256PlusPlus::seed_from_u64(3);
            let mut expected = vec![EvalSample::NONE; wos.len()];
            for &(_, k) in &order {
                expected[k] = set.sample_eval(brdf.as_ref(), &wos[k], &mut r2);
            }
            let key = |s: &EvalSample| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits);
            for (k, (o, e)) in out.iter().zip(&expected).enumerate() {
                assert_eq!(key(o), key(e), "{} query {k}: {o:?} vs {e:?}", brdf.name());
            }
            assert_eq!(r1.next_uniform(), r2.next_uniform(), "{}", brdf.name());
            assert!(order.len() == wos.len() - 4);
            if brdf.is_isotropic() {
                // The runs of ≥ PREPARED_RUN_MIN queries at θo ≤ 89.99° (600, 700, 512, 530
                // queries at ≈ 1.5 evaluations each) went through the run; no other did.
                assert_eq!(PREPARED_RUN_MIN, 512);
                assert!(through_runs > 2342, "{through_runs}");
                let again = phong.run_evals.load(Relaxed);
                // The runs of 1 to 64 and the run of 511 (PREPARED_RUN_MIN − 1) queries.
                let short: Vec<Vec3> = wos[..72].iter().chain(&wos[1376..1887]).copied().collect();
                assert_eq!(short[72..].iter().filter(|w| **w == short[72]).count(), 511);
                set.sample_eval_batch(brdf.as_ref(), &short, &mut r1, &mut out);
                assert_eq!(phong.run_evals.load(Relaxed), again);
            } else {
                assert_eq!(through_runs, 0);
            }
        }
        NO_WAVE.with(|c| c.set(false));
    }

    /// A pass of one `ωo` served without the locate pass ([`ExactSet::one_wo`]) draws the
    /// grouped path's samples bit for bit and leaves the caller's generator in the same state:
    /// Phong with a block-preferring run (the isotropic fast path's wavefront), anisotropic
    /// Ward (the general path, one query at a time) and the RGL fixture (the general path's
    /// wavefront), at θo 0°, 35°, 85°, grazing (89.995°) and below the horizon, in batches of
    /// 511, 512 and 4096 copies of one `ωo` and of 4096 with a last query at another `ωo` —
    /// against the same batches with `one_wo` off. The short, mixed and unserved batches
    /// do not take it; every other does (checked).
    #[test]
    fn one_wo_passes_draw_the_grouped_paths_bits() {
        use super::NO_ONE_WO;
        let (_, [phong, ward]) = phong_and_small_ward(true);
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        let rgl: Arc<dyn Brdf> = Arc::new(brdf::RglBrdf::load(&path).unwrap());
        let key = |s: &EvalSample| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits);
        let mut taken = 0;
        for (brdf, opts) in [phong, ward, (rgl, ExactOptions::default())] {
            let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
            for theta in [0.0, 35.0, 85.0, 89.995, 95.0] {
                let wo = brdf::direction_from_angles(theta, 40.0);
                let other = brdf::direction_from_angles(20.0, 300.0);
                for (len, mixed) in [(511, false), (512, false), (4096, false), (4096, true)] {
                    let mut wos = vec![wo; len];
                    if mixed {
                        wos[len - 1] = other;
                    }
                    let takes = set.one_wo(&wos).is_some();
                    let served = theta < 90.0 && set.locate_keys(&wo).is_some();
                    assert_eq!(
                        takes,
                        len >= 512 && !mixed && served,
                        "{} θo {theta}",
                        brdf.name()
                    );
                    taken += usize::from(takes);
                    let mut draws = [0, 1].map(|off| {
                        NO_ONE_WO.with(|c| c.set(off == 1));
                        let mut r = Xoshiro256PlusPlus::seed_from_u64(17 + len as u64);
                        let mut out = Vec::new();
                        set.sample_eval_batch(brdf.as_ref(), &wos, &mut r, &mut out);
                        (out, r)
                    });
                    NO_ONE_WO.with(|c| c.set(false));
                    let [(a, ra), (b, rb)] = &mut draws;
                    assert_eq!(a.len(), len);
                    for (k, (x, y)) in a.iter().zip(b.iter()).enumerate() {
                        assert_eq!(key(x), key(y), "{} θo {theta} query {k}", brdf.name());
                    }
                    assert_eq!(ra.next_uniform(), rb.next_uniform(), "{}", brdf.name());
                    if served && !mixed {
                        assert!(a.iter().all(|s| s.pdf > 0.0), "{} θo {theta}", brdf.name());
                    }
                }
            }
        }
        // Two per material at each of four served θo.
        assert_eq!(taken, 3 * 4 * 2);
    }

    /// The RGL run wavefront's direct emit (`direct_sample`) writes the samples the general
    /// emit (`accepted_at` + `finish_known`) writes, bit for bit: the fixture at θo 0, 30, 60,
    /// 80, 85, 88.5° and φo 0° (the identity turn) and 40°, 4 096 copies of one ωo, with the
    /// direct emit off (`NO_DIRECT_EMIT`) and on; the generator left in the same state; the
    /// direct emit taken for every sample (the RGL set's maps are equal-area), at both kinds
    /// of turn; with another BRDF object as the
    /// caller's (not the set's: never direct) the same bits too. Broken versions tried: the
    /// rotation skipped at every turn (`wi = d`) fails ("θo 30 φo 40 query 0"); the pdf as
    /// `(gx · (1/a))/2` fails ("θo 0 φo 0 query 8").
    #[test]
    fn rgl_direct_emit_writes_the_general_emits_bits() {
        use super::{DIRECT_EMITS, NO_DIRECT_EMIT};
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        let rgl: Arc<dyn Brdf> = Arc::new(brdf::RglBrdf::load(&path).unwrap());
        let other: Arc<dyn Brdf> = Arc::new(brdf::RglBrdf::load(&path).unwrap());
        let set = ExactSet::build(Arc::clone(&rgl), &ExactOptions::default(), None).unwrap();
        let key = |s: &EvalSample| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits);
        DIRECT_EMITS.with(|c| c.set([0; 2]));
        for caller in [&rgl, &other] {
            for theta in [0.0, 30.0, 60.0, 80.0, 85.0, 88.5] {
                for phi in [0.0, 40.0] {
                    let wos = vec![brdf::direction_from_angles(theta, phi); 4096];
                    let mut draws = [0, 1].map(|off| {
                        NO_DIRECT_EMIT.with(|c| c.set(off == 1));
                        let mut r = Xoshiro256PlusPlus::seed_from_u64(5 + theta as u64);
                        let mut out = Vec::new();
                        set.sample_eval_batch(caller.as_ref(), &wos, &mut r, &mut out);
                        (out, r)
                    });
                    NO_DIRECT_EMIT.with(|c| c.set(false));
                    let [(a, ra), (b, rb)] = &mut draws;
                    assert_eq!(a.len(), wos.len());
                    for (k, (x, y)) in a.iter().zip(b.iter()).enumerate() {
                        assert_eq!(key(x), key(y), "θo {theta} φo {phi} query {k}");
                    }
                    assert_eq!(ra.next_uniform(), rb.next_uniform(), "θo {theta} φo {phi}");
                    assert!(a.iter().all(|s| s.pdf > 0.0), "θo {theta} φo {phi}");
                }
            }
            let n = DIRECT_EMITS.with(std::cell::Cell::get);
            if Arc::ptr_eq(caller, &rgl) {
                // 7 of the 12 ωo have the identity turn (φo 0°, and the normal).
                assert_eq!(n, [7 * 4096, 5 * 4096], "direct emits");
                DIRECT_EMITS.with(|c| c.set([0; 2]));
            } else {
                assert_eq!(n, [0; 2], "another caller's BRDF is never direct");
            }
        }
    }

    /// The uniforms filled ahead (`Ahead`) are the trials one call each would draw: random-ωo
    /// batches (some grazing, some below the horizon) around a run drawn by the wavefront
    /// (Phong with a block-preferring run) or of general queries (Ward) give the same samples
    /// bit for bit, and leave the generator in the same state (the next batch and word
    /// equal), as with every call passed through; with the random-ωo wavefront off (so the
    /// random queries' groups fill ahead) and on.
    #[test]
    fn uniforms_filled_ahead_change_no_sample_and_no_stream_state() {
        use super::{NO_FILL, NO_WAVE, PREPARED_RUN_MIN};
        let (_, cases) = phong_and_small_ward(true);
        for ((brdf, opts), no_wave) in cases
            .into_iter()
            .flat_map(|c| [(c.clone(), true), (c, false)])
        {
            NO_WAVE.with(|c| c.set(no_wave));
            let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
            let mut qr = Xoshiro256PlusPlus::seed_from_u64(31);
            let mut random = |n: usize| mixed_wos(&mut qr, n);
            // Random ωo around a run long enough for the prepared run (drawn by the
            // wavefront: other calls than split trials), and a short run.
            let mut wos = random(1500);
            let at = wos[7];
            wos.extend(std::iter::repeat_n(at, PREPARED_RUN_MIN + 20));
            wos.extend(random(1200));
            wos.extend(std::iter::repeat_n(wos[20], 6));
            wos.extend(random(300));
            let key = |v: &[EvalSample]| -> Vec<[u64; 5]> {
                v.iter()
                    .map(|s| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits))
                    .collect()
            };
            let mut drawn = Vec::new();
            for no_fill in [false, true] {
                NO_FILL.with(|c| c.set(no_fill));
                let mut r = Xoshiro256PlusPlus::seed_from_u64(17);
                let mut out = Vec::new();
                set.sample_eval_batch(brdf.as_ref(), &wos, &mut r, &mut out);
                let first = key(&out);
                set.sample_eval_batch(brdf.as_ref(), &wos[..2000], &mut r, &mut out);
                drawn.push((first, key(&out), r.next_uniform().to_bits()));
            }
            NO_FILL.with(|c| c.set(false));
            NO_WAVE.with(|c| c.set(false));
            assert!(
                drawn[0] == drawn[1],
                "{} (wavefront off: {no_wave})",
                brdf.name()
            );
        }
    }

    /// Random ωo (no two consecutive queries alike), on Phong and GGX with grazing and
    /// below-horizon queries among them: every isotropic fast-path query is drawn by its
    /// group's wavefront, and its sample is, bit for bit, [`ExactSet::draw_iso`]'s at its own
    /// `ωo` from its own stream — SplitMix64 as a **generator** (`SplitMix`, started at
    /// `Stream::of(seed, i)`'s state, `seed` from the caller's stream at the batch's start, `i`
    /// the query's index), whose split trials `distributions` makes from two outputs —
    /// finished as the one-query path finishes it —
    /// so a function of the seed, `i` and `ωo_i` only, with `draw_iso`'s law; the same when
    /// the batch's other queries change; the grazing queries (the general path) are their own
    /// query's samples, the ones below the horizon empty. Also on the RGL fixture with θo layer
    /// tables built as a `cos θo`-table set (fast path): its wave groups are drawn layer by
    /// layer, each query from the layer table `draw_iso` picks (fails with the layer's queries
    /// drawn from the interval's table).
    #[test]
    fn random_wo_groups_draw_draw_isos_samples_from_their_own_streams() {
        use super::super::lanes::{GOLDEN_GAMMA, mix64};
        use super::{Stream, wave_seed};
        use partition_sampler::Audit;
        /// SplitMix64 as a `rand` generator (its outputs `mix64(state + k·γ)`, `k ≥ 1`).
        struct SplitMix(u64);
        impl rand::TryRng for SplitMix {
            type Error = std::convert::Infallible;
            fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
                self.try_next_u64().map(|w| (w >> 32) as u32)
            }
            fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
                self.0 = self.0.wrapping_add(GOLDEN_GAMMA);
                Ok(mix64(self.0))
            }
            fn try_fill_bytes(&mut self, _: &mut [u8]) -> Result<(), Self::Error> {
                unimplemented!("not used")
            }
        }
        let key = |s: &EvalSample| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits);
        let mut cases: Vec<(&str, Arc<dyn Brdf>, ExactSet)> = ["phong:n=50", "ggx:alpha=0.2"]
            .into_iter()
            .map(|spec| {
                let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
                let set =
                    ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
                (spec, brdf, set)
            })
            .collect();
        // The RGL fixture with θo layer tables on the fast path (a `cos θo` table: built
        // without following its kinks), so its wave groups are drawn layer by layer.
        let (rgl, _, layered) = layered_rgl();
        let (set, _) =
            ExactSet::build_phased(Arc::clone(&rgl), &layered, None, None, false).unwrap();
        assert_eq!(set.var, super::super::grid::TableVar::Cos);
        cases.push(("rgl paper_white, layered", rgl, set));
        for (spec, brdf, set) in cases {
            let mut by_layer = 0;
            let mut qr = Xoshiro256PlusPlus::seed_from_u64(51);
            let mut wos = mixed_wos(&mut qr, 4000);
            let rng = Xoshiro256PlusPlus::seed_from_u64(19);
            let seed = wave_seed(&mut rng.clone());
            let mut out = Vec::new();
            set.sample_eval_batch(brdf.as_ref(), &wos, &mut rng.clone(), &mut out);
            let mut audit = Audit::default();
            let (mut fast, mut general) = (0, 0);
            for (i, (wo, o)) in wos.iter().zip(&out).enumerate() {
                match set.locate_iso(wo) {
                    Some(q) => {
                        let table = set.cells[0].tables[q.interval].as_ref().unwrap();
                        by_layer += usize::from(!table.layer_tables().is_empty());
                        let mut s = SplitMix(Stream::of(seed, i).0);
                        let (d, f) = set.draw_iso(&q, wo, &mut s, &mut audit);
                        let want = set.finish_iso(brdf.as_ref(), wo, d, f);
                        assert_eq!(key(o), key(&want), "{spec} query {i}: {o:?} vs {want:?}");
                        fast += 1;
                    }
                    None if wo.z > 0.0 => {
                        assert!(o.pdf > 0.0 && o.wi.z > 0.0, "{spec} query {i}: {o:?}");
                        approx::assert_relative_eq!(o.pdf, set.pdf(wo, &o.wi), max_relative = 1e-9);
                        approx::assert_relative_eq!(
                            o.f,
                            brdf.eval(wo, &o.wi),
                            max_relative = 1e-12
                        );
                        general += 1;
                    }
                    None => assert_eq!(*o, EvalSample::NONE, "{spec} query {i}"),
                }
            }
            assert!(
                fast > 3850 && general >= 40,
                "{spec}: {fast} fast, {general} grazing"
            );
            assert!(audit.trials > audit.samples, "{spec}: some trials rejected");
            // Other queries around them: the fast-path samples of the queries kept are the same.
            let before = out.clone();
            for k in (0..wos.len()).filter(|k| k % 3 == 2) {
                wos[k] = brdf::direction_from_angles(
                    80.0 * qr.next_uniform(),
                    360.0 * qr.next_uniform(),
                );
            }
            set.sample_eval_batch(brdf.as_ref(), &wos, &mut rng.clone(), &mut out);
            let mut same = 0;
            for (k, (a, b)) in before.iter().zip(&out).enumerate() {
                if k % 3 != 2 && set.locate_iso(&wos[k]).is_some() {
                    assert_eq!(key(a), key(b), "{spec} query {k}");
                    same += 1;
                }
            }
            assert!(same > 2500, "{spec}: {same}");
            if spec.starts_with("rgl") {
                assert!(
                    by_layer > 1000,
                    "{spec}: {by_layer} queries in layered intervals"
                );
            }
        }
    }

    /// The random-ωo wavefront gives the same bits at every instruction-set level of the host
    /// (`pulp`: the baseline, AVX2 + FMA, AVX-512): Phong `n = 50`, 3000 random ωo served by
    /// [`ExactSet::serve_iso_wave`] interval by interval at each level, outputs and audits
    /// compared.
    #[test]
    fn random_wo_wavefront_bits_are_the_same_at_every_level() {
        use super::super::wave_iso::IsoWave;
        use partition_sampler::Audit;
        let mut levels = vec![pulp::Arch::Scalar];
        #[cfg(target_arch = "x86_64")]
        {
            levels.extend(pulp::x86::V3::try_new().map(pulp::Arch::V3));
            levels.extend(pulp::x86::V4::try_new().map(pulp::Arch::V4));
        }
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec("phong:n=50").unwrap());
        let set = ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
        let mut qr = Xoshiro256PlusPlus::seed_from_u64(61);
        let wos: Vec<Vec3> = (0..3000)
            .map(|_| {
                brdf::direction_from_angles(89.0 * qr.next_uniform(), 360.0 * qr.next_uniform())
            })
            .collect();
        let intervals = set.cells[0].intervals.len();
        let mut by_interval = vec![Vec::new(); intervals];
        for (i, wo) in wos.iter().enumerate() {
            by_interval[set.locate_iso(wo).expect("fast path").interval].push(i as u32);
        }
        let key = |v: &[EvalSample]| -> Vec<[u64; 5]> {
            v.iter()
                .map(|s| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits))
                .collect()
        };
        let mut first = None;
        for (level, &arch) in levels.iter().enumerate() {
            let mut out = vec![EvalSample::NONE; wos.len()];
            let mut audit = Audit::default();
            let mut w = IsoWave::default();
            for (iv, members) in by_interval.iter().enumerate() {
                set.serve_iso_wave(
                    brdf.as_ref(),
                    &wos,
                    iv,
                    members,
                    0x5eed,
                    arch,
                    &mut w,
                    &mut audit,
                    &mut out,
                );
            }
            assert!(out.iter().all(|s| s.pdf > 0.0));
            let got = (key(&out), audit);
            match &first {
                None => first = Some(got),
                Some(f) => assert!(*f == got, "level {level} of {}", levels.len()),
            }
        }
        assert!(levels.len() >= 2, "{} levels", levels.len());
    }

    /// The random-ωo wavefront's law by χ² (α = 10⁻⁴, 16 × 32 `(cos θ, φ)` bins, 4·10⁴ samples
    /// per angle): a batch alternating two ωo (no two consecutive alike, so both groups are
    /// wavefronts) at θo = 35° (projected map) and 85° (equal-area map) passes against the set's
    /// pdf at each, and two deliberately broken wavefronts are rejected at both — one that
    /// misreports each candidate's `f` by the factor `0.6 + 0.8 cos θi`, one that accepts every
    /// candidate (the envelope's law).
    #[test]
    fn random_wo_wavefront_passes_chi_square_and_broken_ones_fail() {
        use super::super::wave_iso::SKEW;
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec("phong:n=50").unwrap());
        let set = ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
        let dirs = [35.0, 85.0].map(|t: f64| brdf::direction_from_angles(t, 30.0 + t));
        assert_wavefront_chi_square(&set, dirs, |skew, wos| {
            SKEW.with(|c| c.set(skew));
            let out = batch(&set, brdf.as_ref(), wos, 29);
            SKEW.with(|c| c.set(0.0));
            out
        });
    }

    /// A random-ωo wavefront's law by χ² (α = 10⁻⁴, 16 × 32 `(cos θ, φ)` bins, 4·10⁴ samples
    /// per angle; the isotropic and the anisotropic wavefronts' tests): `draw(skew, wos)` is
    /// the batch's samples for 80 000 queries alternating the two `dirs`, drawn with the
    /// wavefront's test break `skew` (0: honest); the honest batch passes against the set's pdf
    /// at both ωo, the broken ones (`0.4`, `−1.0`) are rejected at both.
    pub(in crate::exact) fn assert_wavefront_chi_square(
        set: &ExactSet,
        dirs: [Vec3; 2],
        draw: impl Fn(f64, &[Vec3]) -> Vec<EvalSample>,
    ) {
        let bins = stats::SphereBinning::hemisphere(16, 32).unwrap();
        let quad = stats::QuadratureOptions {
            min_depth: 2,
            ..stats::QuadratureOptions::default()
        };
        let p_values = |skew: f64| -> Vec<f64> {
            let wos: Vec<Vec3> = (0..80_000).map(|k| dirs[k % 2]).collect();
            let out = draw(skew, &wos);
            dirs.iter()
                .enumerate()
                .map(|(j, wo)| {
                    let pts: Vec<[f64; 3]> = out
                        .iter()
                        .skip(j)
                        .step_by(2)
                        .map(|s| [s.wi.x, s.wi.y, s.wi.z])
                        .collect();
                    let pdf = |d: [f64; 3]| set.pdf(wo, &Vec3::new(d[0], d[1], d[2]));
                    stats::chi_square_test(&bins, &pdf, &pts, &quad)
                        .unwrap()
                        .p_value
                })
                .collect()
        };
        for (j, p) in p_values(0.0).into_iter().enumerate() {
            assert!(
                p >= 1e-4,
                "honest wavefront rejected at ωo {:?}: p = {p}",
                dirs[j]
            );
        }
        for skew in [0.4, -1.0] {
            for (j, p) in p_values(skew).into_iter().enumerate() {
                assert!(
                    p < 1e-4,
                    "broken wavefront ({skew}) passed at ωo {:?}: p = {p}",
                    dirs[j]
                );
            }
        }
    }

    /// The batch's working arrays, kept per thread between calls, carry nothing from one batch
    /// to the next: on one thread, after batches of another set and size (Ward: general
    /// queries; Phong: 5000 queries, some grazing or below the horizon), a Phong batch equals
    /// the same batch on a fresh thread, bit for bit. And batches served in passes: 3000
    /// queries in passes of 1000 are three batches of 1000 from the same stream.
    #[test]
    fn kept_working_arrays_and_passes_change_nothing() {
        let phong: Arc<dyn Brdf> = Arc::from(parse_spec("phong:n=50").unwrap());
        let (ward, small) = small_ward();
        let p = ExactSet::build(Arc::clone(&phong), &ExactOptions::default(), None).unwrap();
        let w = ExactSet::build(Arc::clone(&ward), &small, None).unwrap();
        let mut qr = Xoshiro256PlusPlus::seed_from_u64(41);
        let mut wos = |n: usize| mixed_wos(&mut qr, n);
        let (big, ward_q, last) = (wos(5000), wos(3000), wos(700));
        let key = |v: &[EvalSample]| -> Vec<[u64; 5]> {
            v.iter()
                .map(|s| [s.wi.x, s.wi.y, s.wi.z, s.pdf, s.f].map(f64::to_bits))
                .collect()
        };
        let fresh = std::thread::scope(|sc| {
            sc.spawn(|| key(&batch(&p, phong.as_ref(), &last, 12)))
                .join()
                .unwrap()
        });
        let reused = std::thread::scope(|sc| {
            sc.spawn(|| {
                batch(&w, ward.as_ref(), &ward_q, 10);
                batch(&p, phong.as_ref(), &big, 11);
                batch(&w, ward.as_ref(), &ward_q[..50], 10);
                key(&batch(&p, phong.as_ref(), &last, 12))
            })
            .join()
            .unwrap()
        });
        assert_eq!(fresh, reused);

        let mut r1 = Xoshiro256PlusPlus::seed_from_u64(13);
        let mut passes = vec![EvalSample::NONE; big[..3000].len()];
        p.sample_eval_passes(phong.as_ref(), &big[..3000], &mut r1, &mut passes, 1000);
        let mut r2 = Xoshiro256PlusPlus::seed_from_u64(13);
        let mut parts = Vec::new();
        let mut out = Vec::new();
        for part in big[..3000].chunks(1000) {
            p.sample_eval_batch(phong.as_ref(), part, &mut r2, &mut out);
            parts.extend_from_slice(&out);
        }
        assert_eq!(key(&passes), key(&parts));
        assert_eq!(r1.next_uniform(), r2.next_uniform());
        // One pass of all 3000 is another grouping: other samples.
        let mut r3 = Xoshiro256PlusPlus::seed_from_u64(13);
        p.sample_eval_batch(phong.as_ref(), &big[..3000], &mut r3, &mut out);
        assert_ne!(key(&out), key(&parts));
    }

    /// The mean of `cos θi` over the batch's samples at `wo` against its exact value under the
    /// law `f cos θi / A` (reference quadrature): `|z| < 5` (two-sided α ≈ 6e-7).
    fn assert_mean_cos(brdf: &dyn Brdf, wo: &Vec3, out: &[EvalSample], what: &str) {
        let xs: Vec<f64> = out.iter().map(|s| s.wi.z).collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let cos2 = crate::reference::albedo_of(
            |wo, wi| brdf.eval(wo, wi) * wi.z,
            brdf,
            wo,
            crate::REFERENCE_BUDGET,
        )
        .unwrap()
        .value;
        let a = crate::reference_albedo(brdf, wo).unwrap().value;
        let z = (mean - cos2 / a) / (var / n).sqrt();
        assert!(
            z.abs() < 5.0,
            "{what}: mean {mean}, exact {}, z = {z}",
            cos2 / a
        );
    }

    /// The wavefront's working arrays ([`WaveArrays`]) are kept by the thread after a
    /// wavefront of at most [`WAVE_KEEP_MAX`] samples and freed after a longer one; a
    /// wavefront drawn on kept arrays (after a longer and a shorter one) gives the same
    /// points, values and counts as on fresh ones (Phong through a block-preferring run).
    #[test]
    fn wavefront_keeps_its_arrays_only_up_to_a_size_and_they_change_nothing() {
        use super::{WAVE_ARRAYS, WAVE_KEEP_MAX, wavefront};
        use partition_sampler::Audit;
        let phong: Arc<dyn Brdf> = Arc::new(WithRun::phong(true));
        let set = ExactSet::build(Arc::clone(&phong), &ExactOptions::default(), None).unwrap();
        let wo = brdf::direction_from_angles(35.0, 0.0);
        let q = set.locate_iso(&wo).expect("the isotropic path");
        let table = set.cells[0].tables[q.interval].as_ref().unwrap();
        let map = set.cells[0].iso[q.interval].map;
        let run = phong.prepare_run(&Vec3::new(q.r, 0.0, q.cos)).unwrap();
        let draw = |n: usize| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
            let mut audit = Audit::default();
            let d = wavefront(
                run.as_ref(),
                table,
                map,
                q.cos.acos(),
                n,
                256,
                &mut rng,
                &mut audit,
            );
            let bits: Vec<_> = d
                .iter()
                .map(|d| d.map(|(p, g)| [p[0], p[1], g].map(f64::to_bits)))
                .collect();
            (bits, audit.trials, audit.violations, audit.exhausted)
        };
        let kept = || {
            WAVE_ARRAYS.with(|s| {
                let k = s.take();
                let room = k.as_ref().map(|k| k.idx.capacity());
                s.set(k);
                room
            })
        };
        WAVE_ARRAYS.with(|s| s.set(None));
        let fresh = draw(3000);
        assert!(kept().is_some_and(|c| c >= 3000), "kept after 3000");
        let _ = draw(WAVE_KEEP_MAX + 1);
        assert_eq!(kept(), None, "freed after {}", WAVE_KEEP_MAX + 1);
        let _ = draw(5000);
        assert_eq!(draw(3000), fresh);
        assert!(kept().is_some_and(|c| c <= WAVE_KEEP_MAX));
    }

    /// The wavefront (long runs of one `ωo` whose prepared run prefers blocks): each sample is
    /// a function of the seed and its index only — the same bits for blocks of 1, 7, 64, 256
    /// and 10⁴ candidates, with the same trial, violation and sample counts —; every output is
    /// its own query's (pdf = the set's pdf, `f` = the BRDF's, same seed same batch, another
    /// seed another); a run at the grazing top angle (the general path) takes it too; and the
    /// law: the mean `cos θi` at two θo within 5 standard errors of its exact value.
    #[test]
    fn wavefront_draws_depend_on_the_seed_and_index_only_with_the_exact_law() {
        use super::{PREPARED_RUN_MIN, wavefront};
        use partition_sampler::Audit;
        let phong = Arc::new(WithRun::phong(true));
        let brdf: Arc<dyn Brdf> = phong.clone();
        let set = ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
        // The wavefront itself, block sizes apart.
        let wo = brdf::direction_from_angles(35.0, 0.0);
        let q = set.locate_iso(&wo).expect("the isotropic path");
        let table = set.cells[0].tables[q.interval].as_ref().unwrap();
        let map = set.cells[0].iso[q.interval].map;
        let frame = Vec3::new(q.r, 0.0, q.cos);
        let run = brdf.prepare_run(&frame).unwrap();
        let mut first = None;
        for wave in [1, 7, 64, 256, 10_000] {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(17);
            let mut audit = Audit::default();
            let drawn = wavefront(
                run.as_ref(),
                table,
                map,
                q.cos.acos(),
                3000,
                wave,
                &mut rng,
                &mut audit,
            );
            let bits: Vec<_> = drawn
                .iter()
                .map(|d| d.map(|(p, g)| [p[0], p[1], g].map(f64::to_bits)))
                .collect();
            assert!(bits.iter().all(Option::is_some));
            let key = (
                bits,
                audit.trials,
                audit.violations,
                audit.samples,
                rng.next_uniform(),
            );
            match &first {
                None => first = Some(key),
                Some(f) => assert!(*f == key, "wave {wave}"),
            }
        }
        // Through the batch: runs of 1500 at 35°, 700 at 70° and 600 at the grazing top.
        let (a, b, c) = (
            brdf::direction_from_angles(35.0, 40.0),
            brdf::direction_from_angles(70.0, 250.0),
            brdf::direction_from_angles(89.995, 10.0),
        );
        assert!(set.locate_iso(&c).is_none(), "the general path");
        let wos: Vec<Vec3> = std::iter::repeat_n(a, 1500)
            .chain(std::iter::repeat_n(b, 700))
            .chain(std::iter::repeat_n(c, 600))
            .collect();
        assert_eq!(PREPARED_RUN_MIN, 512);
        let before = phong.run_evals.load(Relaxed);
        let out = batch(&set, brdf.as_ref(), &wos, 4);
        assert!(
            phong.run_evals.load(Relaxed) - before > 2800,
            "evaluated by the runs"
        );
        assert_eq!(out, batch(&set, brdf.as_ref(), &wos, 4));
        assert_ne!(out, batch(&set, brdf.as_ref(), &wos, 5));
        for (k, (wo, s)) in wos.iter().zip(&out).enumerate() {
            assert!(s.pdf > 0.0 && s.wi.z > 0.0, "query {k}: {s:?}");
            approx::assert_relative_eq!(s.pdf, set.pdf(wo, &s.wi), max_relative = 1e-9);
            approx::assert_relative_eq!(s.f, brdf.eval(wo, &s.wi), max_relative = 1e-12);
        }
        // The law, 4·10⁴ samples at two θo.
        for t in [35.0, 70.0] {
            let wo = brdf::direction_from_angles(t, 123.0);
            let out = batch(&set, brdf.as_ref(), &vec![wo; 40_000], 9);
            assert_mean_cos(brdf.as_ref(), &wo, &out, &format!("phong θo {t}"));
        }
    }

    /// The wavefront's law by χ² (α = 10⁻⁴, 16 × 32 `(cos θ, φ)` bins, 4·10⁴ samples, seeds
    /// fixed): its samples at θo = 35° and 70° pass against the set's pdf, and two broken
    /// wavefronts are rejected — one whose run misreports `f` by a factor `0.6 + 0.8 cos θi`
    /// (samples of another density under the honest pdf), and one that accepts every
    /// candidate (the envelope's law).
    #[test]
    fn wavefront_samples_pass_chi_square_and_broken_ones_fail() {
        use super::wavefront;
        use partition_sampler::Audit;
        struct Skewed<'a>(&'a dyn PreparedRun, f64);
        impl PreparedRun for Skewed<'_> {
            fn eval(&self, wi: &Vec3) -> f64 {
                // factor 0 accepts everything: a value above every bound.
                if self.1 == 0.0 {
                    return f64::MAX;
                }
                self.0.eval(wi) * (1.0 - self.1 + 2.0 * self.1 * wi.z)
            }
        }
        let brdf: Arc<dyn Brdf> = Arc::new(WithRun::phong(true));
        let set = ExactSet::build(Arc::clone(&brdf), &ExactOptions::default(), None).unwrap();
        let bins = stats::SphereBinning::hemisphere(16, 32).unwrap();
        let quad = stats::QuadratureOptions {
            min_depth: 2,
            ..stats::QuadratureOptions::default()
        };
        let p_value = |theta: f64, skew: Option<f64>| {
            let wo = brdf::direction_from_angles(theta, 0.0);
            let q = set.locate_iso(&wo).expect("the isotropic path");
            let table = set.cells[0].tables[q.interval].as_ref().unwrap();
            let map = set.cells[0].iso[q.interval].map;
            let frame = Vec3::new(q.r, 0.0, q.cos);
            let run = brdf.prepare_run(&frame).unwrap();
            let skewed;
            let run: &dyn PreparedRun = match skew {
                None => run.as_ref(),
                Some(k) => {
                    skewed = Skewed(run.as_ref(), k);
                    &skewed
                }
            };
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(23);
            let mut audit = Audit::default();
            let pts: Vec<[f64; 3]> = wavefront(
                run,
                table,
                map,
                q.cos.acos(),
                40_000,
                256,
                &mut rng,
                &mut audit,
            )
            .into_iter()
            .map(|d| {
                let v = map.to_direction(d.expect("accepted").0);
                [v.x, v.y, v.z]
            })
            .collect();
            let pdf = |d: [f64; 3]| set.pdf(&frame, &Vec3::new(d[0], d[1], d[2]));
            stats::chi_square_test(&bins, &pdf, &pts, &quad)
                .unwrap()
                .p_value
        };
        for theta in [35.0, 70.0] {
            let p = p_value(theta, None);
            assert!(
                p >= 1e-4,
                "honest wavefront rejected at θo {theta}: p = {p}"
            );
            for skew in [0.4, 0.0] {
                let p = p_value(theta, Some(skew));
                assert!(
                    p < 1e-4,
                    "broken wavefront ({skew}) passed at θo {theta}: p = {p}"
                );
            }
        }
    }

    /// The RGL fixture through the batch (its run's block evaluation in lanes and the
    /// wavefront): every output's pdf is the set's and `f` the BRDF's, and the mean `cos θi`
    /// of 4·10⁴ samples at θo = 30° lies within 5 standard errors of its exact value.
    #[test]
    fn rgl_runs_draw_the_exact_law_through_the_wavefront() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        let rgl: Arc<dyn Brdf> = Arc::new(brdf::RglBrdf::load(&path).unwrap());
        let set = ExactSet::build(Arc::clone(&rgl), &ExactOptions::default(), None).unwrap();
        let wo = brdf::direction_from_angles(30.0, 77.0);
        let run = rgl.prepare_run(&wo).unwrap();
        assert!(run.prefers_blocks());
        let out = batch(&set, rgl.as_ref(), &vec![wo; 40_000], 11);
        for s in out.iter().step_by(97) {
            approx::assert_relative_eq!(s.pdf, set.pdf(&wo, &s.wi), max_relative = 1e-9);
            approx::assert_relative_eq!(s.f, rgl.eval(&wo, &s.wi), max_relative = 1e-12);
        }
        assert_mean_cos(rgl.as_ref(), &wo, &out, "rgl θo 30");
    }

    /// The wavefront's sample `i` is, bit for bit, [`LeafTable::draw`]'s (the one-sample
    /// rejection loop) with the run's density and sample `i`'s own stream as the uniform
    /// source — the same point, `g`, and in total the same trial, violation and sample counts —
    /// on Phong through a block-preferring run at θo = 35° (projected map) and 85° (equal-area
    /// map), and on the RGL fixture with θo layers (`layered_rgl`) at 30° and 75° (the general
    /// path's frame; the table is the serving layer's, `ExactSet::table_of`, at 30° a layer
    /// table), 3000 samples each in blocks of 256. So the wavefront's law is `draw`'s, whatever
    /// its lanes, passes and blocks do.
    ///
    /// [`LeafTable::draw`]: super::table::LeafTable::draw
    #[test]
    fn wavefront_samples_are_draws_from_their_own_streams() {
        use super::{Stream, run_density, wave_seed, wavefront};
        use partition_sampler::Audit;
        let phong: Arc<dyn Brdf> = Arc::new(WithRun::phong(true));
        let (rgl, _, layered) = layered_rgl();
        let mut compared = 0;
        let mut by_layer = 0;
        for (brdf, angles, opts) in [
            (phong, [35.0, 85.0], ExactOptions::default()),
            (rgl, [30.0, 75.0], layered),
        ] {
            let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
            for t in angles {
                let wo = brdf::direction_from_angles(t, 0.0);
                let q = set.locate(&wo).expect("served");
                let frame = if q.turn == crate::layout::Turn::IDENTITY {
                    q.wo
                } else {
                    q.turn.undo(&q.wo)
                };
                let table = set.table_of(&q).unwrap();
                let own = set.cells[q.cell].tables[q.interval].as_ref().unwrap();
                by_layer += usize::from(!std::ptr::eq(table, own));
                let map = set.interval(&q).map;
                let run = brdf.prepare_run(&frame).unwrap();
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(31);
                let seed = wave_seed(&mut rng.clone());
                let mut audit = Audit::default();
                let drawn = wavefront(
                    run.as_ref(),
                    table,
                    map,
                    q.cos.acos(),
                    3000,
                    256,
                    &mut rng,
                    &mut audit,
                );
                let g = |p| run_density(run.as_ref(), map, p);
                let mut want_audit = Audit::default();
                for (i, d) in drawn.iter().enumerate() {
                    let mut s = Stream::of(seed, i);
                    let want = table.draw(&g, &mut s, &mut want_audit);
                    let key = |d: Option<([f64; 2], f64)>| {
                        d.map(|(p, g)| [p[0], p[1], g].map(f64::to_bits))
                    };
                    assert_eq!(key(*d), key(want), "{} θo {t} sample {i}", brdf.name());
                    compared += 1;
                }
                assert_eq!(audit, want_audit, "{} θo {t}", brdf.name());
                assert!(audit.trials > audit.samples, "some trials rejected");
            }
        }
        assert_eq!(compared, 12_000);
        assert!(by_layer >= 1, "a layer table compared");
    }

    /// Thinning (docs/benchmarks.md §30.1, §30.6): on the RGL fixture built with up to 4 θo
    /// layers of ≥ 0.5°, at a θo inside every interval (its midpoint) and, for a layered one,
    /// at its ends and at and just above each layer edge, the wavefront under the table serving
    /// θo (`ExactSet::table_of`: for a layered interval the layer's table, §31.1) with its
    /// leaves' thinning bounds draws, bit for bit, the samples of the same table without them — the same points and
    /// `g`, the same trial and sample counts, 0 violations (`g` above the bound it was drawn
    /// under) — while evaluating `f` at least 5 % less often over the set. So the sub-cell bounds
    /// are above `g` wherever a trial was decided by them, and they pay. Fails with the bounds
    /// shrunk by 12 % (`sub_bound`'s `m · q / 255 · 0.88`: other samples and violations) and
    /// with the sub-cell index transposed (`c[sx · SUB + sy]`, and later the top bits of `u₁`
    /// and `u₂` swapped in `four_outputs`: other samples); with thinning off it fails only
    /// through its evaluation clause. A saved and loaded set keeps the bounds and layers (the
    /// tables compare equal).
    #[test]
    fn thinning_bounds_change_no_sample_and_save_evaluations() {
        use super::wavefront;
        use partition_sampler::Audit;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        let rgl: Arc<dyn Brdf> = Arc::new(brdf::RglBrdf::load(&path).unwrap());
        // Up to 4 θo layers of ≥ 0.5° (the fixture's default intervals are too narrow for the
        // default's 1.5°).
        let opts = ExactOptions {
            thinning_layers: 4,
            thinning_layer_deg: 0.5,
            ..ExactOptions::default()
        };
        let set = ExactSet::build(Arc::clone(&rgl), &opts, None).unwrap();
        // Saved and loaded, the tables keep their thinning bounds and layers (format 3).
        let spec = format!("rgl:{}", path.display());
        let back = ExactSet::from_bytes(&set.to_bytes(&spec), Arc::clone(&rgl), &spec).unwrap();
        assert!(
            back.cells[0].tables == set.cells[0].tables,
            "thinning bounds saved"
        );
        let (mut evals_thin, mut evals_plain, mut thinned) = (0u64, 0u64, 0usize);
        let (mut layered, mut by_layer) = (0, 0);
        // Every interval at its midpoint, and a layered one also at its ends and layer edges.
        let mut thetas = Vec::new();
        for iv in &set.cells[0].intervals {
            thetas.push(0.5 * (iv.theta[0] + iv.theta[1]));
            if let Some(sub) = iv.sub_bounds.as_ref().filter(|s| s.layers() > 1) {
                layered += 1;
                thetas.extend([iv.theta[0].next_up(), iv.theta[1]]);
                for &e in &sub.edges {
                    thetas.extend([e, e.next_up()]);
                }
            }
        }
        assert!(layered >= 4, "{layered} layered intervals");
        for t in thetas {
            let wo = brdf::direction_from_radians(t.min(89.0f64.to_radians()), 0.0);
            let q = set.locate(&wo).expect("served");
            let frame = if q.turn == crate::layout::Turn::IDENTITY {
                q.wo
            } else {
                q.turn.undo(&q.wo)
            };
            let table = set.table_of(&q).unwrap();
            assert!(table.thins(), "every RGL interval has thinning bounds");
            let own = set.cells[q.cell].tables[q.interval].as_ref().unwrap();
            by_layer += usize::from(!std::ptr::eq(table, own));
            thinned += 1;
            let plain = table.clone().with_sub_bounds(None);
            assert!(!plain.thins());
            let map = set.interval(&q).map;
            let run = rgl.prepare_run(&frame).unwrap();
            let draw = |tb: &super::LeafTable| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(41);
                let mut audit = Audit::default();
                let e0 = crate::disc::thread_evaluations();
                let d = wavefront(
                    run.as_ref(),
                    tb,
                    map,
                    q.cos.acos(),
                    4000,
                    256,
                    &mut rng,
                    &mut audit,
                );
                let e = crate::disc::thread_evaluations() - e0;
                let bits: Vec<_> = d
                    .iter()
                    .map(|d| d.map(|(p, g)| [p[0], p[1], g].map(f64::to_bits)))
                    .collect();
                (bits, audit, e)
            };
            let (a, audit_a, e_a) = draw(table);
            let (b, audit_b, e_b) = draw(&plain);
            let deg = t.to_degrees();
            assert!(a == b, "θo {deg:.2}: thinning changed samples");
            assert_eq!(audit_a.violations, 0, "θo {deg:.2}");
            assert_eq!(audit_b.violations, 0, "θo {deg:.2}");
            assert_eq!(
                (audit_a.trials, audit_a.samples, audit_a.exhausted),
                (audit_b.trials, audit_b.samples, audit_b.exhausted),
                "θo {deg:.2}"
            );
            assert!(e_a <= e_b, "θo {deg:.2}: {e_a} > {e_b}");
            evals_thin += e_a;
            evals_plain += e_b;
        }
        assert!(thinned >= 40, "{thinned} angles");
        assert!(by_layer >= 40, "{by_layer} angles drawn from layer tables");
        let ratio = evals_thin as f64 / evals_plain as f64;
        println!("thinning: {evals_thin} / {evals_plain} evaluations = {ratio:.4}");
        assert!(
            ratio < 0.95,
            "evaluations with / without thinning {ratio:.4}"
        );
    }

    /// The RGL fixture built with up to 4 θo layers of ≥ 0.5° (its default intervals are
    /// narrower than the default's two 1.5° layers), shared by the layer-table tests.
    fn layered_rgl() -> (Arc<dyn Brdf>, ExactSet, ExactOptions) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        let rgl: Arc<dyn Brdf> = Arc::new(brdf::RglBrdf::load(&path).unwrap());
        let opts = ExactOptions {
            thinning_layers: 4,
            thinning_layer_deg: 0.5,
            ..ExactOptions::default()
        };
        let set = ExactSet::build(Arc::clone(&rgl), &opts, None).unwrap();
        (rgl, set, opts)
    }

    /// θo layer tables (docs/benchmarks.md §31.1) on the layered RGL fixture: for every layer
    /// of every layered interval, (a) the layer table has the interval's leaves (the same
    /// rectangles in the same order) and each leaf bound `M_il` is the smallest `f32` at least
    /// every sub-cell bound `sub_bound(M_i, q_ils)` of the leaf in that layer (so `≥` each of
    /// them, and `≤ M_i`); (b) its codes are the smallest whose bound `sub_bound(M_il, q')` is
    /// at least the layer's sub-cell bound; (c) drawn at the layer's middle θo with the
    /// query's density and the same uniforms (2000 samples), the layer table needs fewer
    /// trials than the interval's table — the figure printed, asserted below 0.995 over the
    /// set, as is the envelope volume `Σ dx·dy·M_il / Σ dx·dy·M_i` — with 0 violations (no `g`
    /// above `M_il`). Fails with `M_il` rounded down (`f32_at_least`
    /// returning `b as f32` rounded toward 0: (a)), with the codes not re-expressed (the
    /// interval's codes kept: (b)), and with the layer tables off (`serving` returning the
    /// interval's table: (c)).
    #[test]
    fn layer_tables_bound_their_sub_cells_and_cut_trials() {
        use super::super::density::QueryDensity;
        use super::super::table::sub_bound;
        use partition_sampler::Audit;
        let (rgl, set, _) = layered_rgl();
        let top = super::super::THETA_TOP_DEG.to_radians();
        let cell = &set.cells[0];
        let (mut layered, mut leaves) = (0, 0usize);
        let (mut trials_layer, mut trials_interval) = (0u64, 0u64);
        let (mut volume_layer, mut volume_interval) = (0.0, 0.0);
        for (iv, table) in cell.intervals.iter().zip(&cell.tables) {
            let table = table.as_ref().unwrap();
            // Every interval with thinning bounds has layer tables, one layer (§31.5) or more.
            let Some(sub) = iv.sub_bounds.as_ref() else {
                assert!(table.layer_tables().is_empty());
                continue;
            };
            layered += 1;
            let layers = table.layer_tables();
            assert_eq!(layers.len(), sub.layers());
            let n = iv.tree.tree().leaves().len();
            // The layers' θo ranges within the interval (an interval that inherited its
            // parent's tree has the parent's layer edges, some outside its own range).
            let mut ends = vec![f64::NEG_INFINITY];
            ends.extend(sub.edges.iter().copied());
            ends.push(f64::INFINITY);
            for (l, lt) in layers.iter().enumerate() {
                let codes = &sub.codes[l * n..(l + 1) * n];
                for (k, c) in codes.iter().enumerate() {
                    let [x0, dx, y0, dy, m] = table.leaf_record(k);
                    let [lx0, ldx, ly0, ldy, ml] = lt.leaf_record(k);
                    assert_eq!([x0, dx, y0, dy], [lx0, ldx, ly0, ldy], "leaf {k}");
                    // The codes' base: `M_i`, or a one-layer interval's served bound (§32.1).
                    let m = sub.leaf_base(k, m);
                    let top = c.iter().map(|&q| sub_bound(m, q)).fold(0.0, f64::max);
                    let ml32 = ml as f32;
                    assert_eq!(f64::from(ml32), ml);
                    assert!(ml >= top && ml <= m, "layer {l} leaf {k}: {ml} < {top}");
                    assert!(
                        top == 0.0 || f64::from(ml32.next_down()) < top,
                        "layer {l} leaf {k}: {ml} not the smallest f32 ≥ {top}"
                    );
                    for (s, &qs) in c.iter().enumerate() {
                        let b = sub_bound(m, qs);
                        let q = lt.code(k, s);
                        assert!(sub_bound(ml, q) >= b, "layer {l} leaf {k} sub {s}");
                        assert!(
                            q == 0 || sub_bound(ml, q - 1) < b || ml == 0.0,
                            "layer {l} leaf {k} sub {s}: code {q} not the smallest"
                        );
                    }
                    leaves += 1;
                }
                // (c) At the layer's middle θo, the query's density, the same uniforms (a
                // layer above the top angle serves no query of its own θo).
                let (a, b) = (ends[l].max(iv.theta[0]), ends[l + 1].min(iv.theta[1]));
                let t = 0.5 * (a + b);
                if !(a < b) || t >= top {
                    continue;
                }
                let wo = brdf::direction_from_radians(t, 0.0);
                let q = set.locate(&wo).expect("served");
                assert!(
                    std::ptr::eq(set.table_of(&q).unwrap(), lt),
                    "layer {l} serves"
                );
                let g = QueryDensity::in_frame(rgl.as_ref(), true, &q.wo, q.turn, iv.map);
                let g = |p| g.at(p);
                let draws = |tb: &super::LeafTable| {
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(61);
                    let mut audit = Audit::default();
                    for _ in 0..2000 {
                        assert!(tb.draw(&g, &mut rng, &mut audit).is_some());
                    }
                    assert_eq!(audit.violations, 0, "θo {:.3}°", t.to_degrees());
                    audit.trials
                };
                trials_layer += draws(lt);
                trials_interval += draws(table);
                let volume = |tb: &super::LeafTable| {
                    (0..n)
                        .map(|k| {
                            let [_, dx, _, dy, m] = tb.leaf_record(k);
                            dx * dy * m
                        })
                        .sum::<f64>()
                };
                volume_layer += volume(lt);
                volume_interval += volume(table);
            }
        }
        assert!(layered >= 4, "{layered} layered intervals");
        let ratio = trials_layer as f64 / trials_interval as f64;
        let volume = volume_layer / volume_interval;
        println!(
            "layer tables: {layered} intervals, {leaves} leaf layers; trials {trials_layer} / \
             {trials_interval} = {ratio:.4}; envelope volume {volume:.4}"
        );
        // paper_white's envelope hardly changes with θo (§30.1's factor (b): 1.005–1.017), so
        // the fall is small here (0.992 measured, ≈ 8 standard deviations of the counts); with
        // the layer tables off the two counts are equal.
        assert!(
            ratio < 0.995,
            "trials with / without layer tables {ratio:.4}"
        );
        assert!(
            volume < 0.995,
            "envelope volume with / without layer tables {volume:.4}"
        );
    }

    /// The one-query path and the fixed-ωo wavefront pick the same θo layer, also at the layer
    /// edges (docs/benchmarks.md §31.1): on the layered RGL fixture, for each inner edge `e` of
    /// every layered interval (inside it and below the top angle), at the three floats
    /// `cos θo` on each side of where [`layer_of`]`(acos(cos θo))` switches from layer `j + 1`
    /// to `j` (both layers reached at every edge, asserted), (a) `draw_located`'s sample is, bit for bit, the rejection draw
    /// of the table of the layer [`layer_of`] gives for `θo = acos(cos θo)` from the same
    /// uniforms, and (b) the batch path's fixed-ωo run (a wavefront) draws, bit for bit,
    /// [`wavefront`]'s samples under that table. Fails with the layer off by one in one path
    /// (`table_of` taking `layer_of(θo) + 1`, clamped: (a); the batch path's table the next
    /// layer's: (b)).
    ///
    /// [`layer_of`]: super::super::table::layer_of
    /// [`wavefront`]: super::wavefront
    #[test]
    fn one_query_path_and_wavefront_pick_the_same_layer_at_its_edges() {
        use super::super::density::QueryDensity;
        use super::super::fused::{accepted, accepted_at};
        use super::super::table::{layer_of, query_theta};
        use super::{WAVE, wavefront_with};
        use partition_sampler::Audit;
        let (rgl, set, _) = layered_rgl();
        let top = super::super::THETA_TOP_DEG.to_radians() - 1e-9;
        let cell = &set.cells[0];
        let key = |s: &crate::DirSample| [s.wi.x, s.wi.y, s.wi.z, s.pdf].map(f64::to_bits);
        let (mut edges, mut compared) = (0, 0);
        for (iv, table) in cell.intervals.iter().zip(&cell.tables) {
            let table = table.as_ref().unwrap();
            let Some(sub) = iv.sub_bounds.as_ref().filter(|s| s.layers() > 1) else {
                continue;
            };
            for (j, &e) in sub.edges.iter().enumerate() {
                if !(e > iv.theta[0] && e < iv.theta[1].min(top)) {
                    // An inherited edge outside the interval, or above the top angle: no query
                    // of the interval has this θo.
                    continue;
                }
                let layer = |c: f64| layer_of(&sub.edges, query_theta(c)).unwrap();
                // The largest `cos θo` of layer `j + 1`, found by ulp steps from `cos e`.
                let mut c = e.cos();
                while layer(c) > j {
                    c = c.next_up();
                }
                while layer(c) <= j {
                    c = c.next_down();
                }
                // Three floats on each side of the switch.
                for _ in 0..2 {
                    c = c.next_down();
                }
                let mut seen = [false; 2];
                for _ in 0..6 {
                    let theta = query_theta(c);
                    let l = layer_of(&sub.edges, theta).unwrap();
                    assert!(l == j || l == j + 1, "edge {j}: layer {l}");
                    seen[l - j] = true;
                    let want_table = &table.layer_tables()[l];
                    let wo = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
                    let q = set.locate(&wo).expect("served");
                    // (a) The one-query path.
                    let g = QueryDensity::in_frame(rgl.as_ref(), true, &q.wo, q.turn, iv.map);
                    let a = set.normaliser_of(&q);
                    let mut r1 = Xoshiro256PlusPlus::seed_from_u64(71);
                    let mut r2 = r1.clone();
                    let (mut a1, mut a2) = (Audit::default(), Audit::default());
                    for _ in 0..20 {
                        let (got, _) = set.draw_located(&q, &wo, &mut r1, &mut a1);
                        let (x, gx) = want_table.draw(&|p| g.at(p), &mut r2, &mut a2).unwrap();
                        let (want, _) = accepted(iv.map, &q.turn, x, gx, a);
                        assert_eq!(key(&got), key(&want), "edge {j}, cos {c:e}: one-query path");
                    }
                    // (b) The batch path's run: a wavefront.
                    let n = super::PREPARED_RUN_MIN;
                    let out = batch(&set, rgl.as_ref(), &vec![wo; n], 73);
                    let run = rgl.prepare_run(&q.wo).unwrap();
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(73);
                    let mut want = vec![crate::DirSample::NONE; n];
                    let mut audit = Audit::default();
                    wavefront_with(
                        run.as_ref(),
                        want_table,
                        iv.map,
                        theta,
                        n,
                        WAVE,
                        &mut rng,
                        &mut audit,
                        |i, d| {
                            if let Some((_, v, gx)) = d {
                                want[i] = accepted_at(iv.map, &q.turn, v, gx, a).0;
                            }
                        },
                    );
                    for (i, (o, w)) in out.iter().zip(&want).enumerate() {
                        let o = crate::DirSample {
                            wi: o.wi,
                            pdf: o.pdf,
                        };
                        assert_eq!(key(&o), key(w), "edge {j}, cos {c:e}: wavefront sample {i}");
                    }
                    compared += 1;
                    c = c.next_up();
                }
                assert_eq!(seen, [true, true], "edge {j} at {e}: both layers reached");
                edges += 1;
            }
        }
        assert!(edges >= 8, "{edges} edges");
        println!("layer edges: {edges}, {compared} cos θo compared");
    }
}
