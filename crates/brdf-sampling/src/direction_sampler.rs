//! The common shape of every direction sampler: `sample(wo, u) -> (wi, pdf)`, `pdf(wo, wi)`.

use brdf::{Brdf, Vec3};

use crate::PdfCells;
use partition_sampler::UniformSource;

/// One sampled incident direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirSample {
    /// The sampled direction `ωi` (unit vector, local frame, normal = +z). It may lie below the
    /// horizon for samplers whose support is the whole sphere; such a sample contributes zero.
    pub wi: Vec3,
    /// Density of `wi` with respect to **solid angle**.
    pub pdf: f64,
}

impl DirSample {
    /// The sample that contributes nothing (no direction for this `ωo`): `ωi` = the normal,
    /// pdf 0.
    pub const NONE: Self = Self {
        wi: Vec3::new(0.0, 0.0, 1.0),
        pdf: 0.0,
    };
}

/// One sampled incident direction with the BRDF value the estimator `f cos θi / pdf` needs: the
/// result of [`DirectionSampler::sample_eval`] (Mitsuba's `eval_pdf_sample`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvalSample {
    /// The sampled direction `ωi`, as [`DirSample::wi`].
    pub wi: Vec3,
    /// Density of `wi` with respect to solid angle, as [`DirSample::pdf`].
    pub pdf: f64,
    /// `f_r(ωo, ωi)` of the BRDF passed to `sample_eval`; 0 for a sample that contributes
    /// nothing (`pdf` 0 or `ωi` at or below the horizon), where the BRDF is not evaluated.
    pub f: f64,
}

impl EvalSample {
    /// The sample that contributes nothing (no direction for this `ωo`): `ωi` = the normal,
    /// pdf 0, f 0.
    pub const NONE: Self = Self {
        wi: Vec3::new(0.0, 0.0, 1.0),
        pdf: 0.0,
        f: 0.0,
    };

    /// The estimator's weight `f cos θi / pdf` (0 for a sample that contributes nothing).
    #[inline]
    pub fn weight(&self) -> f64 {
        if self.pdf > 0.0 && self.wi.z > 0.0 {
            self.f * self.wi.z / self.pdf
        } else {
            0.0
        }
    }
}

/// A sampler of incident directions given an outgoing direction `ωo`.
///
/// The pdf is always with respect to solid angle on the sphere of directions. Samplers consume
/// caller-given uniforms (so QMC streams work) and are immutable and `Sync` once built. The trait
/// is object-safe: the CLI and the validation suite hold samplers as `Box<dyn DirectionSampler>`.
///
/// The methods here are the sampling ones: draw ([`Self::sample`], [`Self::sample_eval`] and
/// their batched forms [`Self::sample_eval_batch`], [`Self::sample_batch`],
/// [`Self::sample_many`]), evaluate ([`Self::pdf`], [`Self::pdf_many`], and given a known
/// `f`: [`Self::pdf_given_f`], [`Self::pdf_many_given_f`]) and the cost of the
/// structure ([`Self::bytes_used`], [`Self::prefers_batches`]). Validation and report hooks
/// are the supertrait [`SamplerDiagnostics`].
pub trait DirectionSampler: SamplerDiagnostics + Send + Sync {
    /// Draws `ωi` for the outgoing direction `wo` (unit, `wo.z > 0`).
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample;

    /// Density of `wi` given `wo`, w.r.t. solid angle; the same value `sample` reports.
    ///
    /// Both `wo` and `wi` must be **unit** vectors (as `sample` returns them): implementations
    /// may read a direction's components directly (the quadtree sets map `(wi.x, wi.y)` to the
    /// disc), so the pdf of a non-unit vector is unspecified. Callers holding arbitrary vectors
    /// (e.g. read from a file) normalise them first, once, and evaluate the BRDF at the same
    /// unit vector.
    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64;

    /// Draws `ωi` for `wo` as [`sample`](DirectionSampler::sample) does — the same direction
    /// and pdf from the same uniforms — together with `f_r(ωo, ωi)` of `brdf`: a fused
    /// sample-and-evaluate. The default samples, then evaluates `brdf` once (not at all for a
    /// sample that contributes nothing). Samplers that already evaluated `f` at the sampled
    /// direction while sampling (rejection samplers: the accepted trial) return that value when
    /// `brdf` is the very object they were built with (same address and type), so the estimator
    /// pays no further evaluation; such an `f` may differ from `brdf.eval(wo, wi)` by rounding
    /// (it was evaluated in the sampler's own frame).
    fn sample_eval(&self, brdf: &dyn Brdf, wo: &Vec3, u: &mut dyn UniformSource) -> EvalSample {
        let s = self.sample(wo, u);
        let f = if s.pdf > 0.0 && s.wi.z > 0.0 {
            brdf.eval(wo, &s.wi)
        } else {
            0.0
        };
        EvalSample {
            wi: s.wi,
            pdf: s.pdf,
            f,
        }
    }

    /// A batch of queries: `out` is cleared and receives one [`EvalSample`] per `wos[k]`, in
    /// the caller's order, each distributed as [`sample_eval`](DirectionSampler::sample_eval)
    /// at `wos[k]` (same law, same `f` contract). The results are a function of the queries and
    /// of the uniforms `u` delivers — hence of the seed only — but a sampler may consume the
    /// uniforms in its own order (queries grouped by its structure, so each group is served
    /// while its tables are in cache), so they need not equal `wos.len()` consecutive
    /// `sample_eval` calls. The default is that loop, in order.
    fn sample_eval_batch(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut Vec<EvalSample>,
    ) {
        out.clear();
        out.extend(wos.iter().map(|wo| self.sample_eval(brdf, wo, u)));
    }

    /// Draws `n` directions for one `wo` as a batch. The default draws `n` independent samples;
    /// batch-mode samplers (stratified leaf allocation) override it. Each returned pdf is the
    /// one-sample density of that direction, so `(1/n) Σ f/pdf` stays the estimator.
    fn sample_batch(&self, wo: &Vec3, n: usize, u: &mut dyn UniformSource) -> Vec<DirSample> {
        (0..n).map(|_| self.sample(wo, u)).collect()
    }

    /// `n` one-sample draws at `wo`: exactly what `n` calls of [`Self::sample`] return (the
    /// same uniforms consumed in the same order), unlike [`Self::sample_batch`], which may
    /// stratify. Override only to batch the work (e.g. one call into Python for all `n`); the
    /// validation suite draws its one-sample sets through it.
    fn sample_many(&self, wo: &Vec3, n: usize, u: &mut dyn UniformSource) -> Vec<DirSample> {
        (0..n).map(|_| self.sample(wo, u)).collect()
    }

    /// [`Self::pdf`] at `wo` for every direction of `wi`, in order. Override only to batch the
    /// work; the validation suite's pdf-consistency check calls it.
    fn pdf_many(&self, wo: &Vec3, wi: &[Vec3]) -> Vec<f64> {
        wi.iter().map(|w| self.pdf(wo, w)).collect()
    }

    /// [`Self::pdf`] at `(wo, wi)` for a caller that has already evaluated
    /// `f = f_r(ωo, ωi)` of `brdf` there (an MIS estimator's light sample: the integrand needs
    /// `f`, the weight needs the BRDF sampler's pdf). A sampler whose pdf is `f_r cos θi / A(ωo)`
    /// for the BRDF object it was built with (`adaptive-exact`) returns `f cos θi / A(ωo)`
    /// without evaluating `f_r` again when `brdf` is that object — the same value as `pdf`,
    /// provided `f` is `brdf.eval(wo, wi)` bit for bit. The default ignores `brdf` and `f` and
    /// calls [`Self::pdf`], so a caller may always pass them.
    fn pdf_given_f(&self, brdf: &dyn Brdf, wo: &Vec3, wi: &Vec3, f: f64) -> f64 {
        let _ = (brdf, f);
        self.pdf(wo, wi)
    }

    /// [`Self::pdf_given_f`] at `wo` for every direction of `wi`, in order, `f[k]` the value
    /// `brdf.eval(wo, wi[k])` (`f.len() == wi.len()`; otherwise the values are those of
    /// [`Self::pdf_many`]). The default ignores `brdf` and `f` and calls [`Self::pdf_many`] (so a
    /// sampler that batches `pdf_many` keeps batching).
    fn pdf_many_given_f(&self, brdf: &dyn Brdf, wo: &Vec3, wi: &[Vec3], f: &[f64]) -> Vec<f64> {
        let _ = (brdf, f);
        self.pdf_many(wo, wi)
    }

    /// Whether callers should batch pdf queries through [`Self::pdf_many`] wherever they can
    /// (a sampler for which one call per point is expensive, e.g. one written in Python); the
    /// validation suite then serves its quadratures from batched values. `false` by default.
    fn prefers_batches(&self) -> bool {
        false
    }

    /// True when [`Self::sample_eval`] returns an `f` the sampler computed while drawing (a
    /// rejection sampler's accepted trial) for the BRDF object it was built with, so a caller
    /// that needs `f_r(ωo, ωi)` saves an evaluation by taking it from the sample. `false` by
    /// default (`sample_eval` then evaluates `f` once after the draw, which costs a caller no
    /// less than evaluating it itself).
    fn fuses_eval(&self) -> bool {
        false
    }

    /// Bytes of the precomputed structures this sampler needs.
    fn bytes_used(&self) -> usize;
}

/// Validation and report hooks of a [`DirectionSampler`], apart from its sampling methods.
///
/// A supertrait of [`DirectionSampler`], so a `Box<dyn DirectionSampler>` still offers every
/// hook; each has a default ("nothing to declare"), so a sampler with no diagnostics writes
/// `impl SamplerDiagnostics for MySampler {}`. The hooks never change what a sampler draws or
/// the pdf it reports: the validation suite reads them to grade its quadratures and audits
/// ([`Self::pdf_cells`], [`Self::singular_directions`], [`Self::normaliser_rel_err`]), and the
/// CLI and studies print them ([`Self::bound_violations`], [`Self::build_report`]).
pub trait SamplerDiagnostics {
    /// Cumulative count of trials that found the density above its bound (samplers with an
    /// audited bound, e.g. the adaptive sets); `None` for samplers that have no bound to audit.
    fn bound_violations(&self) -> Option<u64> {
        None
    }

    /// Declared relative error of the pdf's normalising constant at `wo` (samplers whose pdf
    /// is `f·cos / Î` with a numerical `Î`); `None` when the pdf is exact by construction.
    fn normaliser_rel_err(&self, _wo: &Vec3) -> Option<f64> {
        None
    }

    /// Where the pdf at `wo` is piecewise constant (see [`PdfCells`]), for samplers that know:
    /// a validation then integrates the pdf cell by cell, exactly, instead of refining its
    /// quadrature at every jump. `None` (the default) means "no declared structure".
    fn pdf_cells(&self, _wo: &Vec3) -> Option<PdfCells> {
        None
    }

    /// A human-readable report of the built structure (layout, cost, audit), one item per
    /// line, for samplers that have one beyond [`crate::SetReport`]; `None` by default.
    fn build_report(&self) -> Option<String> {
        None
    }

    /// Directions (unit vectors, local frame) at or near which the pdf at `wo` is singular or
    /// sharply peaked — e.g. `−ωo` for the half-vector samplers, whose solid-angle pdf
    /// `p_h(h)/(2|ωo + ωi|)` has an integrable `1/|ωo + ωi|` wedge there, or the mirror
    /// direction of a narrow lobe. A validation grades its quadrature towards them (see
    /// `stats::singular`); declaring a direction never changes the pdf. Empty by default.
    fn singular_directions(&self, _wo: &Vec3) -> Vec<Vec3> {
        Vec::new()
    }
}
