//! The anisotropic batch path's random-`ωo` wavefront (issue 29, docs/benchmarks.md §28.7):
//! `wave_iso.rs`'s wavefront for anisotropic sets. The queries of one interval group, each
//! at its own `ωo`, are drawn together: every pending query proposes one trial per pass in
//! vector lanes ([`lanes::trials_split`](super::lanes::trials_split): its own SplitMix64 stream, the leaf pick, the
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
use partition_sampler::Audit;

use super::ExactSet;
use super::wave_iso::{WaveFrame, WaveLists, stream_key};
use crate::EvalSample;
use crate::layout::Turn;

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

/// The working arrays of [`ExactSet::serve_aniso_wave`], kept by the caller between groups
/// (and per thread between batches): the wavefront's lists ([`WaveLists`]) and per query its
/// rotation `R_δ` as `(sin δ, cos δ)` (`None` for the identity, which is not applied, as
/// `QueryDensity::in_frame` does).
#[derive(Default)]
pub(super) struct AnisoWave {
    lists: WaveLists,
    rot: Vec<Option<(f64, f64)>>,
}

/// The anisotropic [`WaveFrame`]: per query its rotation `R_δ` from the interval's frame to
/// the world's, `ω = R_δ v = (cos δ v_x − sin δ v_y, sin δ v_x + cos δ v_y, v_z)`
/// (`QueryDensity::at`'s arithmetic inside the disc; `None` is the identity).
struct Rotated<'a>(&'a [Option<(f64, f64)>]);

impl WaveFrame for Rotated<'_> {
    #[inline(always)]
    fn eval(&self, model: &dyn Brdf, prep: &Outgoing, q: usize, v: &Vec3) -> f64 {
        match self.0[q] {
            None => model.eval_prepared(prep, v),
            Some((s, c)) => {
                let wi = Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
                model.eval_prepared(prep, &wi)
            }
        }
    }
}

impl ExactSet {
    /// The anisotropic queries `members` (indices into `wos`, `located` and `out`; each
    /// located in interval `interval` of cell `cell`, which has a table, and served at its own
    /// `ωo`: `wos[i].z ≥ top_cos`) drawn as one wavefront from the streams keyed by `seed`
    /// (see the module docs): `out[i]` is the one-query anisotropic draw's sample at `wos[i]`
    /// from query `i`'s stream, finished as [`ExactSet::finish`] finishes it (the accepted
    /// trial's `f`, or one evaluation of `brdf` when it is another object), or the empty
    /// sample after [`MAX_TRIALS_PER_SAMPLE`](partition_sampler::MAX_TRIALS_PER_SAMPLE) trials (counted as exhausted). Trials,
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
        // Per query: the one-query draw's preparation (`QueryDensity::in_frame` for an
        // anisotropic BRDF, the record's normaliser), written through slices.
        let n = members.len();
        if w.rot.len() < n {
            w.rot.resize(n, None);
        }
        let s = w.lists.slots(n);
        let lists = s
            .prep
            .iter_mut()
            .zip(s.norm.iter_mut())
            .zip(s.turn.iter_mut());
        let per_query = lists.zip(s.state.iter_mut()).zip(w.rot[..n].iter_mut());
        for (&i, ((((p, a), t), st), r)) in members.iter().zip(per_query) {
            let wo = &wos[i as usize];
            let q = &located[i as usize];
            *p = self.brdf.prepare(wo);
            *a = rec.normaliser(q.keys[0], q.keys[1], q.cos, &c.patches);
            *t = q.turn;
            *st = stream_key(seed, u64::from(i));
            *r = (q.turn != Turn::IDENTITY).then_some((q.turn.sin, q.turn.cos));
        }
        let AnisoWave { lists, rot } = w;
        self.run_wave(
            brdf,
            wos,
            members,
            table,
            map,
            &Rotated(rot),
            arch,
            lists,
            audit,
            out,
        );
    }
}
