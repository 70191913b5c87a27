//! Adapters from the project's sampler traits to [`SamplerUnderTest`].

use std::sync::Arc;

use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler};
use envmap::EnvMapSampler;
use partition_sampler::{AllocationMode, QuadTreeSampler, RegionStats, Sampler2D, UniformSource};

use crate::subject::{Dir3, Point2, SamplerUnderTest};

/// A [`DirectionSampler`] for one fixed outgoing direction `ωo`: points are incident
/// directions, pdfs are w.r.t. solid angle (`DirectionSampler::pdf(ωo, ωi)`), batches come
/// from `DirectionSampler::sample_batch`, the audit and the declared normaliser error from
/// the sampler itself.
pub struct DirectionAtWo {
    sampler: Arc<dyn DirectionSampler>,
    wo: Vec3,
}

impl DirectionAtWo {
    /// Adapts `sampler` at `wo` (unit, `wo.z > 0`).
    pub fn new(sampler: Arc<dyn DirectionSampler>, wo: Vec3) -> Self {
        Self { sampler, wo }
    }
}

fn dir_of(v: &Vec3) -> Dir3 {
    [v.x, v.y, v.z]
}

impl SamplerUnderTest<Dir3> for DirectionAtWo {
    fn sample(&self, u: &mut dyn UniformSource) -> (Dir3, f64) {
        let s = self.sampler.sample(&self.wo, u);
        (dir_of(&s.wi), s.pdf)
    }

    fn pdf(&self, p: Dir3) -> f64 {
        self.sampler.pdf(&self.wo, &Vec3::new(p[0], p[1], p[2]))
    }

    fn sample_batch(&self, n: usize, u: &mut dyn UniformSource) -> Vec<(Dir3, f64)> {
        dir_pairs(&self.sampler.sample_batch(&self.wo, n, u))
    }

    fn sample_many(&self, n: usize, u: &mut dyn UniformSource) -> Vec<(Dir3, f64)> {
        dir_pairs(&self.sampler.sample_many(&self.wo, n, u))
    }

    fn prefers_batches(&self) -> bool {
        self.sampler.prefers_batches()
    }

    fn pdf_many(&self, points: &[Dir3]) -> Vec<f64> {
        let wi: Vec<Vec3> = points.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        self.sampler.pdf_many(&self.wo, &wi)
    }

    fn bound_violations(&self) -> Option<u64> {
        self.sampler.bound_violations()
    }

    fn normaliser_rel_err(&self) -> Option<f64> {
        self.sampler.normaliser_rel_err(&self.wo)
    }

    fn pdf_cells(&self) -> Option<brdf_sampling::PdfCells> {
        self.sampler.pdf_cells(&self.wo)
    }

    fn singular_points(&self) -> Vec<Dir3> {
        self.sampler
            .singular_directions(&self.wo)
            .iter()
            .map(dir_of)
            .collect()
    }
}

/// Any [`Sampler2D`] (pdf w.r.t. area on its domain); batches are independent draws.
pub struct PlainPlanar<S>(pub S);

impl<S: Sampler2D + Send> SamplerUnderTest<Point2> for PlainPlanar<S> {
    fn sample(&self, u: &mut dyn UniformSource) -> (Point2, f64) {
        planar_draw(&self.0, u)
    }

    fn pdf(&self, p: Point2) -> f64 {
        self.0.pdf(p)
    }
}

/// Direction samples as `(direction, pdf)` pairs.
fn dir_pairs(samples: &[DirSample]) -> Vec<(Dir3, f64)> {
    samples.iter().map(|s| (dir_of(&s.wi), s.pdf)).collect()
}

/// One draw of a planar sampler as `(point, pdf)`.
fn planar_draw<S: Sampler2D>(sampler: &S, u: &mut dyn UniformSource) -> (Point2, f64) {
    let s = sampler.sample(u);
    (s.point, s.pdf)
}

/// A [`QuadTreeSampler`]: one-sample draws of its configured scheme, batches by its stratified
/// batch mode with [`AllocationMode::RandomizedRemainder`] (unbiased), and its bound audit.
pub struct QuadTreePlanar<D>(pub QuadTreeSampler<D>);

impl<D: RegionStats + Send> SamplerUnderTest<Point2> for QuadTreePlanar<D> {
    fn sample(&self, u: &mut dyn UniformSource) -> (Point2, f64) {
        planar_draw(&self.0, u)
    }

    fn pdf(&self, p: Point2) -> f64 {
        self.0.pdf(p)
    }

    fn sample_batch(&self, n: usize, u: &mut dyn UniformSource) -> Vec<(Point2, f64)> {
        let b = self
            .0
            .sample_batch(n, AllocationMode::RandomizedRemainder, u);
        b.samples.iter().map(|s| (s.point, s.pdf)).collect()
    }

    fn bound_violations(&self) -> Option<u64> {
        Some(self.0.stats().bound_violations)
    }

    fn normaliser_rel_err(&self) -> Option<f64> {
        self.0.stats().integral_rel_err
    }
}

/// An [`EnvMapSampler`] on `[0, 1]²` (pdf w.r.t. area in `(u, v)`); the adaptive one uses its
/// quadtree's batch mode and audit.
pub struct EnvMapPlanar(pub EnvMapSampler);

impl SamplerUnderTest<Point2> for EnvMapPlanar {
    fn sample(&self, u: &mut dyn UniformSource) -> (Point2, f64) {
        let s = self.0.sample_uv(u);
        (s.point, s.pdf)
    }

    fn pdf(&self, p: Point2) -> f64 {
        self.0.pdf_uv(p[0], p[1])
    }

    fn sample_batch(&self, n: usize, u: &mut dyn UniformSource) -> Vec<(Point2, f64)> {
        match self.0.as_adaptive() {
            Some(q) => q
                .sample_batch(n, AllocationMode::RandomizedRemainder, u)
                .samples
                .iter()
                .map(|s| (s.point, s.pdf))
                .collect(),
            None => (0..n).map(|_| self.sample(u)).collect(),
        }
    }

    fn bound_violations(&self) -> Option<u64> {
        self.0.stats().map(|s| s.bound_violations)
    }

    fn normaliser_rel_err(&self) -> Option<f64> {
        self.0.stats().and_then(|s| s.integral_rel_err)
    }
}
