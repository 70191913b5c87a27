//! The sampler-under-test abstraction: anything with `sample(u) → (x, pdf)`, `pdf(x)` and a
//! batch form, plus what it is meant to sample and the integrals used to test its estimator.

use std::sync::Arc;

use partition_sampler::UniformSource;
use serde::{Deserialize, Serialize};

use crate::domain::Domain;

/// A direction `[x, y, z]` in the local frame (normal `+z`).
pub type Dir3 = [f64; 3];

/// A point of a planar domain.
pub type Point2 = [f64; 2];

/// A scalar function on the points of a domain.
pub type ScalarFn<P> = Arc<dyn Fn(P) -> f64 + Send + Sync>;

/// A sampler as the suite sees it, on points `P` (`[f64; 3]` directions with pdfs w.r.t. solid
/// angle, or `[f64; 2]` planar points with pdfs w.r.t. area).
///
/// Object-safe: direction samplers are adapted for one fixed `ωo`
/// ([`crate::adapters::DirectionAtWo`]), planar samplers directly
/// ([`crate::adapters::PlainPlanar`], [`crate::adapters::QuadTreePlanar`]).
pub trait SamplerUnderTest<P>: Send + Sync {
    /// One point and the pdf the sampler reports for it.
    fn sample(&self, u: &mut dyn UniformSource) -> (P, f64);

    /// The pdf of `p`, evaluated independently of sampling.
    fn pdf(&self, p: P) -> f64;

    /// `n` points drawn as one batch (stratified samplers override this). Each reported pdf is
    /// the one-sample density, so `(1/n) Σ g/pdf` estimates `∫ g`.
    fn sample_batch(&self, n: usize, u: &mut dyn UniformSource) -> Vec<(P, f64)> {
        (0..n).map(|_| self.sample(u)).collect()
    }

    /// `n` one-sample draws: exactly what `n` calls of [`Self::sample`] return (the same
    /// uniforms in the same order). Override only to batch the work (e.g. a sampler written in
    /// Python, called once per chunk of [`crate::DRAW_CHUNK`] draws).
    fn sample_many(&self, n: usize, u: &mut dyn UniformSource) -> Vec<(P, f64)> {
        (0..n).map(|_| self.sample(u)).collect()
    }

    /// [`Self::pdf`] of every point, in order (override only to batch the work).
    fn pdf_many(&self, points: &[P]) -> Vec<f64>
    where
        P: Clone,
    {
        points.iter().map(|p| self.pdf(p.clone())).collect()
    }

    /// Whether pdf queries should come in batches ([`Self::pdf_many`]) wherever the suite can
    /// arrange it, including its quadratures (e.g. a sampler written in Python, for which one
    /// call per point costs far more than the arithmetic). `false` by default.
    fn prefers_batches(&self) -> bool {
        false
    }

    /// Cumulative count of rejection trials with `f > M_i` (bound violations), for samplers
    /// that audit their bounds; `None` otherwise.
    fn bound_violations(&self) -> Option<u64> {
        None
    }

    /// The sampler's own estimate of the relative error of its pdf normaliser (e.g. the grid
    /// integral `Î` of a quadtree, for which the pdf is `f/Î`), when it declares one.
    fn normaliser_rel_err(&self) -> Option<f64> {
        None
    }

    /// Where the pdf is piecewise constant, for direction samplers that declare it
    /// ([`brdf_sampling::SamplerDiagnostics::pdf_cells`]): the suite then integrates it exactly
    /// (see [`crate::cells`]). `None` by default.
    fn pdf_cells(&self) -> Option<brdf_sampling::PdfCells> {
        None
    }

    /// Points where the pdf is singular or sharply peaked, for samplers that declare them
    /// ([`brdf_sampling::SamplerDiagnostics::singular_directions`]): the KS projection CDFs grade
    /// their quadrature towards them. Empty by default.
    fn singular_points(&self) -> Vec<P> {
        Vec::new()
    }
}

/// An integral with an accurately known value, and how the value was obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// The value.
    pub value: f64,
    /// Estimated absolute error of `value`.
    pub abs_error: f64,
    /// How it was computed (quadrature rule, closed form...).
    pub rule: String,
}

/// An integral `∫ g dμ` (same measure as the sampler's pdf) estimated by `(1/N) Σ g(x)/pdf(x)`.
#[derive(Clone)]
pub struct Estimand<P> {
    /// Short label (e.g. `albedo`).
    pub label: String,
    /// The integrand `g ≥ 0`.
    pub integrand: ScalarFn<P>,
    /// The reference value of `∫ g dμ`.
    pub reference: Reference,
}

/// One sampler in one setting, with everything the tests need.
#[derive(Clone)]
pub struct Subject<P> {
    /// The sampler.
    pub sampler: Arc<dyn SamplerUnderTest<P>>,
    /// Its domain (decides the binning and the pdf's measure).
    pub domain: Domain,
    /// The function the sampler is meant to follow (e.g. `f_r cos θ`): wherever it is positive
    /// the pdf must be positive (support coverage).
    pub target: ScalarFn<P>,
    /// Estimand of the one-sample unbiasedness test.
    pub single: Estimand<P>,
    /// Estimand of the batch unbiasedness test (should not be proportional to the pdf, so that
    /// a biased batch allocation shows).
    pub batch: Estimand<P>,
}

/// A subject on directions or on a planar domain.
#[derive(Clone)]
pub enum AnySubject {
    /// Directions (hemisphere or sphere).
    Direction(Subject<Dir3>),
    /// Planar points (disc or unit square).
    Planar(Subject<Point2>),
}

impl AnySubject {
    /// The domain.
    pub fn domain(&self) -> Domain {
        match self {
            AnySubject::Direction(s) => s.domain,
            AnySubject::Planar(s) => s.domain,
        }
    }
}
