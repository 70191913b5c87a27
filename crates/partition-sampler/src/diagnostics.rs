//! Audited draws of a [`QuadTreeSampler`]: the draws of the sampling verbs with the caller
//! holding the trial and bound-violation counts ([`Audit`]), and rejection against another
//! density under a tree's bounds. For samplers built on this crate (the BRDF sets use them to
//! audit every slice's bounds without shared writes); a caller that only wants samples uses the
//! verbs of [`QuadTreeSampler`] (crate docs, "Sampling verbs").
//!
//! The methods are those of the [`AuditedDraws`] extension trait:
//! `use partition_sampler::diagnostics::AuditedDraws;` brings them into scope.

use crate::audit::Audit;
use crate::contract::{Point2, Sample2, UniformSource};
use crate::density::RegionStats;
use crate::quadtree_sampler::QuadTreeSampler;

/// Draws that count into a caller's [`Audit`] (see the module docs).
pub trait AuditedDraws {
    /// Draws one sample exactly as [`crate::Sampler2D::sample`] does (same law, same
    /// uniforms), counting trials and violations into `audit` only (no shared state is
    /// touched; merge later with [`AuditedDraws::record_audit`] if wanted).
    fn sample_audited<U: UniformSource + ?Sized>(&self, u: &mut U, audit: &mut Audit) -> Sample2;

    /// Adds locally gathered counts to the sampler's statistics.
    fn record_audit(&self, audit: &Audit);

    /// One sample of the density `g / ∫ g` (w.r.t. area on the tree's domain) by envelope
    /// rejection under this tree's leaf bounds (leaf ∝ `V_i` with the tree's leaf choice, which
    /// must be the envelope scheme's alias or descent tables over `V_i`; see
    /// `quadtree_sampler/envelope_of.rs`). Returns the accepted point and `g` there, or `None`
    /// after [`crate::MAX_TRIALS_PER_SAMPLE`] trials (counted as exhausted). Trials,
    /// violations (`g(x) > M_i`) and the sample are counted in `audit` only.
    ///
    /// `g` is called only at points inside the domain (inside the unit circle for disc trees).
    fn sample_envelope_of<G, U>(
        &self,
        g: &G,
        u: &mut U,
        audit: &mut Audit,
    ) -> Option<(Point2, f64)>
    where
        G: Fn(Point2) -> f64 + ?Sized,
        U: UniformSource + ?Sized;

    /// Adds one [`AuditedDraws::sample_envelope_of`] call's counts to the sampler's
    /// statistics the way a plain `sample()` does: trials and samples buffered per thread,
    /// violations and exhaustion at once.
    fn record_one_sample(&self, audit: &Audit);
}

impl<D: RegionStats> AuditedDraws for QuadTreeSampler<D> {
    #[inline]
    fn sample_audited<U: UniformSource + ?Sized>(&self, u: &mut U, audit: &mut Audit) -> Sample2 {
        self.draw(u, audit)
    }

    fn record_audit(&self, audit: &Audit) {
        self.add_audit(audit);
    }

    #[inline]
    fn sample_envelope_of<G, U>(&self, g: &G, u: &mut U, audit: &mut Audit) -> Option<(Point2, f64)>
    where
        G: Fn(Point2) -> f64 + ?Sized,
        U: UniformSource + ?Sized,
    {
        self.draw_envelope_of(g, u, audit)
    }

    #[inline]
    fn record_one_sample(&self, audit: &Audit) {
        self.add_one_sample(audit);
    }
}
