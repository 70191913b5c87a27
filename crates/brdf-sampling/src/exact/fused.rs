//! The fused sample-and-evaluate of the exact sampler ([`DirectionSampler::sample_eval`]):
//! the accepted rejection trial already evaluated `f_r(ωo, ωi)`, so the estimator's `f` is
//! returned with the sample instead of being evaluated again.
//!
//! [`DirectionSampler::sample_eval`]: crate::DirectionSampler::sample_eval

use brdf::{Brdf, Vec3};
use partition_sampler::{Audit, Point2, UniformSource};

use super::ExactSet;
use super::density::QueryDensity;
use super::grid::TableVar;
use crate::disc::DiscMap;
use crate::layout::Turn;
use crate::{DirSample, EvalSample};

/// An isotropic query located for [`ExactSet::draw_iso`] (issue 29, the per-query cost):
/// the interval, and the served `ωo` in the interval's frame, `(r, 0, cos θo)` with
/// `r = |(ωo.x, ωo.y)|` — the rotation of `ωo` to azimuth 0 with no division, so the trials'
/// density can be prepared before the rotation back to the world (`(x, y)/r`) is known.
#[derive(Debug, Clone, Copy)]
pub(super) struct IsoQuery {
    pub(super) interval: usize,
    pub(super) r: f64,
    pub(super) cos: f64,
}

impl ExactSet {
    /// The isotropic query of `wo` when the fast path serves it: an isotropic set (its
    /// normaliser tables over `cos θo`), `ωo`
    /// above [`THETA_TOP_DEG`](super::THETA_TOP_DEG)'s cosine with finite components; `None`
    /// otherwise (the general [`ExactSet::locate`] then serves the query, the grazing ones at
    /// the top angle, or refuses it at and below the horizon). The interval is the one
    /// `locate` finds: the same search key `1 − cos θo` and guide table.
    #[inline]
    pub(super) fn locate_iso(&self, wo: &Vec3) -> Option<IsoQuery> {
        if !(self.isotropic
            && self.var == TableVar::Cos
            && wo.z >= self.top_cos
            && wo.x.is_finite()
            && wo.y.is_finite())
        {
            return None;
        }
        let cos = wo.z.min(1.0);
        Some(IsoQuery {
            interval: self.cells[0].interval_of(TableVar::Cos.key(cos), 0.0),
            r: (wo.x * wo.x + wo.y * wo.y).sqrt(),
            cos,
        })
    }

    /// One direction at an isotropic query (`q = self.locate_iso(wo)`), with the accepted
    /// trial's `f` (NaN when none was accepted or it is not finite): the law of
    /// [`ExactSet::draw_located`] — the same interval, table, trials, normaliser and pdf — with
    /// the trials' `ωo` at `(r, 0, cos θo)` instead of `R_{−φo} ωo` (the same direction to
    /// rounding), the normaliser inline and no `Option` hand-offs.
    #[inline]
    pub(super) fn draw_iso<U: UniformSource + ?Sized>(
        &self,
        q: &IsoQuery,
        wo: &Vec3,
        u: &mut U,
        audit: &mut Audit,
    ) -> (DirSample, f64) {
        let cell = &self.cells[0];
        let iv = &cell.intervals[q.interval];
        let rec = &cell.iso[q.interval];
        let frame = Vec3::new(q.r, 0.0, q.cos);
        let g = QueryDensity::in_frame(self.brdf.as_ref(), true, &frame, Turn::IDENTITY, rec.map);
        // The normaliser and the rotation back to the world depend on the query only: issued
        // before the trials, their dependent chains (Horner's rule, two divisions) run in the
        // shadow of the trials' evaluations instead of after the loop's last, mispredicted
        // branch. Bit for bit the pdf's normaliser ([`IsoRecord::normaliser`]).
        let a = rec.normaliser(q.cos, iv);
        let turn = Turn::of_azimuth(wo, q.r);
        let drawn = match cell.tables[q.interval]
            .as_ref()
            .map(|t| t.serving_cos(q.cos))
        {
            Some(table) => table.draw(&|p| g.at(p), u, audit),
            None => {
                use partition_sampler::diagnostics::AuditedDraws;
                iv.tree.sample_envelope_of(&|p| g.at(p), u, audit)
            }
        };
        let Some((x, gx)) = drawn else {
            let none = DirSample::NONE;
            return (none, f64::NAN);
        };
        accepted(rec.map, &turn, x, gx, a)
    }

    /// [`ExactSet::finish`] for an accepted trial's `f` given as a number (NaN or infinite:
    /// none; `brdf` is then evaluated).
    #[inline]
    pub(super) fn finish_iso(
        &self,
        brdf: &dyn Brdf,
        wo: &Vec3,
        s: DirSample,
        f: f64,
    ) -> EvalSample {
        self.finish(brdf, wo, s, f.is_finite().then_some(f))
    }

    /// The [`EvalSample`] of a drawn sample `s` at `wo`, with `f` the accepted trial's value
    /// from [`ExactSet::draw_with_f`]: that value when `brdf` is the set's own BRDF object,
    /// otherwise one evaluation of `brdf`; 0 for a sample that contributes nothing.
    #[inline]
    pub(super) fn finish(
        &self,
        brdf: &dyn Brdf,
        wo: &Vec3,
        s: DirSample,
        f: Option<f64>,
    ) -> EvalSample {
        self.finish_known(brdf, wo, s, f, same_brdf(brdf, self.brdf.as_ref()))
    }

    /// [`ExactSet::finish`] with `same = same_brdf(brdf, set's BRDF)` decided once by the
    /// caller for many samples (a run's; the batch path): the same [`EvalSample`] —
    /// `(s.wi, s.pdf, f)` with `f = 0` unless `s.pdf > 0` and `s.wi.z > 0`, else the given `f`
    /// when `same`, else `brdf.eval(wo, s.wi)`.
    #[inline(always)]
    pub(super) fn finish_known(
        &self,
        brdf: &dyn Brdf,
        wo: &Vec3,
        s: DirSample,
        f: Option<f64>,
        same: bool,
    ) -> EvalSample {
        let f = if !(s.pdf > 0.0 && s.wi.z > 0.0) {
            0.0
        } else {
            match f {
                Some(f) if same => f,
                _ => brdf.eval(wo, &s.wi),
            }
        };
        EvalSample {
            wi: s.wi,
            pdf: s.pdf,
            f,
        }
    }
}

/// The sample of an accepted trial at the disc point `x` with `g(x) = gx` and normaliser `a`:
/// the direction `turn · map(x)`, its pdf `gx / a` in solid angle, and `f_r` there — `g` is
/// `f_r` on the projected map and `2 f_r cos θi` on the equal-area one (`cos θi > 0` where a
/// trial is accepted: `g > 0`).
#[inline]
pub(super) fn accepted(map: DiscMap, turn: &Turn, x: Point2, gx: f64, a: f64) -> (DirSample, f64) {
    accepted_at(map, turn, map.to_direction(x), gx, a)
}

/// [`accepted`] with the trial's direction `d = map.to_direction(x)` already made (the batch
/// path's wavefront keeps it from the evaluation).
#[inline]
pub(super) fn accepted_at(map: DiscMap, turn: &Turn, d: Vec3, gx: f64, a: f64) -> (DirSample, f64) {
    let s = DirSample {
        wi: turn.apply(&d),
        pdf: map.area_to_solid_angle(gx / a, &d),
    };
    let f = match map {
        DiscMap::Projected => gx,
        DiscMap::EqualArea => gx / (2.0 * d.z),
    };
    (s, f)
}

/// True when `a` and `b` are the same BRDF object: same address **and** same vtable (a
/// wrapper struct may share its first field's address). A false "no" (one type with two
/// vtables, from two codegen units) only costs the caller one evaluation; zero-sized BRDFs
/// are never taken as the same (distinct zero-sized values may share an address).
#[inline]
pub(super) fn same_brdf(a: &dyn Brdf, b: &dyn Brdf) -> bool {
    std::mem::size_of_val(a) != 0 && std::ptr::eq(a as *const dyn Brdf, b as *const dyn Brdf)
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use brdf::{Brdf, Vec3, parse_spec};
    use partition_sampler::UniformSource;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    use crate::{DirectionSampler, ExactOptions, ExactSet};

    // The counting wrapper (`eval`, `eval_rgb` and `eval_prepared` on the calling thread).
    use brdf::CountingBrdf as Counted;
    use brdf::thread_evaluations as evals;

    /// Outgoing directions of the test: random θo up to past the served top (89.99°), a few
    /// at and below the horizon.
    fn query(i: usize, rng: &mut Xoshiro256PlusPlus) -> Vec3 {
        let phi = 360.0 * rng.next_uniform();
        let theta = match i % 50 {
            0 => 89.995,
            1 => 90.0,
            2 => 95.0,
            _ => 89.999 * rng.next_uniform(),
        };
        brdf::direction_from_angles(theta, phi)
    }

    fn set_of(spec: &str) -> (Arc<dyn Brdf>, ExactSet) {
        let model: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        let brdf: Arc<dyn Brdf> = Arc::new(Counted(model));
        let mut opts = ExactOptions::default();
        if !brdf.is_isotropic() {
            // A small anisotropic build: this test needs samples, not a tight envelope or an
            // accurate normaliser.
            opts.max_trials = 8.0;
            opts.normaliser_tol = 1e-3;
            opts.initial_phi_cells = 4;
        }
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None).unwrap();
        (brdf, set)
    }

    /// The isotropic fast path (`locate_iso`, `draw_iso`) serves what the general path
    /// (`locate`, `draw_located`) serves: the same interval for every query — also exactly at
    /// the intervals' θ edges and their neighbouring floats — the same normaliser bits (the
    /// inline records), and from the same uniforms the
    /// same trials (streams in step), `ωi` and pdf to 1e-13 and the accepted trial's `f` to
    /// 1e-13 (the trials' `ωo` is `(r, 0, cos θo)` rather than `R_{−φo} ωo`, the same
    /// direction to rounding). Grazing queries, at and below the horizon, are left to the
    /// general path.
    #[test]
    fn the_isotropic_fast_path_draws_what_the_general_path_draws() {
        use partition_sampler::Audit;
        for spec in ["phong:n=50", "ggx:alpha=0.2"] {
            let (_, set) = set_of(spec);
            let cell = &set.cells[0];
            let mut wos: Vec<Vec3> = cell
                .upper
                .iter()
                .flat_map(|&t| [t.next_down(), t, t.next_up()])
                .filter(|t| *t < crate::exact::THETA_TOP_DEG.to_radians())
                .map(|t| brdf::direction_from_radians(t, 1.3))
                .collect();
            let mut qr = Xoshiro256PlusPlus::seed_from_u64(16);
            wos.extend((0..3000).map(|i| query(i, &mut qr)));
            wos.push(Vec3::new(0.0, 0.0, 1.0));
            let (mut r1, mut r2) = (
                Xoshiro256PlusPlus::seed_from_u64(7),
                Xoshiro256PlusPlus::seed_from_u64(7),
            );
            let (mut a1, mut a2) = (Audit::default(), Audit::default());
            let mut served = 0;
            for wo in &wos {
                let Some(iso) = set.locate_iso(wo) else {
                    assert!(wo.z < set.top_cos, "{spec}: {wo:?} not served");
                    continue;
                };
                served += 1;
                let q = set.locate(wo).unwrap();
                assert_eq!((q.cell, q.interval), (0, iso.interval), "{spec}: {wo:?}");
                let iv = set.interval(&q);
                assert_eq!(
                    set.cells[0].iso[q.interval]
                        .normaliser(iso.cos, iv)
                        .to_bits(),
                    iv.normaliser(set.var, &q).to_bits(),
                    "{spec}: {wo:?}"
                );
                let (s, f) = set.draw_located(&q, wo, &mut r1, &mut a1);
                let (si, fi) = set.draw_iso(&iso, wo, &mut r2, &mut a2);
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * a.abs().max(b.abs());
                let (w, wi) = (s.wi, si.wi);
                assert!(
                    close(s.pdf, si.pdf)
                        && close(f.unwrap_or(f64::NAN), fi)
                        && (w.x - wi.x).abs() < 1e-13
                        && (w.y - wi.y).abs() < 1e-13
                        && (w.z - wi.z).abs() < 1e-13,
                    "{spec} {wo:?}: {s:?} {f:?} vs {si:?} {fi}"
                );
            }
            assert_eq!(a1, a2, "{spec}");
            assert_eq!(r1.next_uniform(), r2.next_uniform(), "{spec}");
            assert!(served > 2800, "{spec}: {served}");
        }
    }

    /// `sample_eval` draws the very samples of `sample` (same uniforms consumed, same `ωi` and
    /// pdf bits), returns `f_r(ωo, ωi)` to rounding (the accepted trial's value, evaluated in
    /// the interval's frame; the served grazing queries and the query's own BRDF when it is
    /// another object: one evaluation), and evaluates the set's own BRDF no more often than
    /// `sample` does — the estimator's evaluation is saved.
    #[test]
    fn sample_eval_returns_the_accepted_trials_f_with_the_same_samples() {
        for spec in ["phong:n=50", "ward:alpha_x=0.2,alpha_y=0.4"] {
            let (brdf, set) = set_of(spec);
            // The compact tables draw what the trees' own walks draw (`table.rs`).
            assert!(
                super::super::table::walks::assert_table_walks_match_trees(&set) >= 2 * set.len()
            );
            let other: Arc<dyn Brdf> = Arc::new(Counted(Arc::from(parse_spec(spec).unwrap())));
            let (mut r1, mut r2, mut r3) = (
                Xoshiro256PlusPlus::seed_from_u64(5),
                Xoshiro256PlusPlus::seed_from_u64(5),
                Xoshiro256PlusPlus::seed_from_u64(5),
            );
            let mut qr = Xoshiro256PlusPlus::seed_from_u64(6);
            let (mut e_plain, mut e_fused, mut e_other) = (0, 0, 0);
            let (mut contributing, mut grazing) = (0u64, 0u64);
            let top_cos = crate::exact::THETA_TOP_DEG.to_radians().cos();
            for i in 0..4000 {
                let wo = query(i, &mut qr);
                let before = evals();
                let s = set.sample(&wo, &mut r1);
                e_plain += evals() - before;
                let before = evals();
                let f = set.sample_eval(brdf.as_ref(), &wo, &mut r2);
                e_fused += evals() - before;
                let before = evals();
                let o = set.sample_eval(other.as_ref(), &wo, &mut r3);
                e_other += evals() - before;
                assert_eq!((s.wi, s.pdf), (f.wi, f.pdf), "{spec} ωo {wo:?}");
                assert_eq!((o.wi, o.pdf), (f.wi, f.pdf), "{spec} ωo {wo:?}");
                let live = s.pdf > 0.0 && s.wi.z > 0.0;
                contributing += u64::from(live);
                grazing += u64::from(live && wo.z < top_cos);
                let exact = if live { brdf.eval(&wo, &s.wi) } else { 0.0 };
                approx::assert_relative_eq!(f.f, exact, max_relative = 1e-12);
                // Another object of the same model is evaluated at `ωi`: exactly `eval`.
                assert_eq!(o.f, exact, "{spec} ωo {wo:?}");
                if !live {
                    assert_eq!(f.f, 0.0);
                }
            }
            // The streams stayed in step.
            let next = r1.next_uniform();
            assert_eq!(next, r2.next_uniform());
            assert_eq!(next, r3.next_uniform());
            // Only the grazing queries (served at THETA_TOP_DEG) pay an evaluation.
            assert!(grazing > 0);
            assert_eq!(
                e_fused,
                e_plain + grazing,
                "{spec}: evaluations fused vs sampling only"
            );
            // Another object of the same model: the estimator's evaluation, always.
            assert_eq!(e_other, e_plain + contributing, "{spec}");
            assert!(contributing > 3800, "{spec}: {contributing}");
        }
    }
}
