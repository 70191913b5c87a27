//! Broken direction samplers.

use std::f64::consts::{FRAC_1_PI, TAU};

use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;

use super::bases::{LobeMixture, cosine_direction};

/// Cosine-weighted sampling that reports the uniform hemisphere pdf `1/(2π)` (the classic
/// forgotten-cosine bug). Its pdf integrates to one and is self-consistent: only the tests that
/// look at where samples land can catch it.
#[derive(Debug, Clone, Copy, Default)]
pub struct CosineReportedUniform;

impl DirectionSampler for CosineReportedUniform {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let wi = cosine_direction(u);
        DirSample {
            pdf: self.pdf(wo, &wi),
            wi,
        }
    }

    fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        if wi.z > 0.0 { 1.0 / TAU } else { 0.0 }
    }

    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for CosineReportedUniform {}

/// Cosine-weighted sampling restricted to `θ ≤ θ_max`, renormalised there
/// (`p = cos θ / (π sin²θ_max)`), 0 beyond: a hole in the support near the horizon. The pdf is
/// normalised and consistent; the estimator misses the mass beyond `θ_max`.
#[derive(Debug, Clone, Copy)]
pub struct TruncatedCosine {
    /// `θ_max` in degrees.
    pub theta_max_deg: f64,
}

impl DirectionSampler for TruncatedCosine {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let s2 = self.theta_max_deg.to_radians().sin().powi(2);
        let (u1, u2) = (u.next_uniform(), u.next_uniform());
        let r2 = u1 * s2;
        let r = r2.sqrt();
        let (s, c) = (TAU * u2).sin_cos();
        let wi = Vec3::new(r * c, r * s, (1.0 - r2).sqrt());
        DirSample {
            pdf: self.pdf(wo, &wi),
            wi,
        }
    }

    fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        let t = self.theta_max_deg.to_radians();
        if wi.z > 0.0 && wi.z >= t.cos() {
            wi.z * FRAC_1_PI / t.sin().powi(2)
        } else {
            0.0
        }
    }

    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for TruncatedCosine {}

/// A correct sampler whose reported pdf is `factor` times too high where `ωi.y > 0` and
/// `2 − factor` times elsewhere. For `ωo` in the `xz`-plane the base is symmetric in `y`, so the
/// reported pdf still integrates to one and stays self-consistent: the pdf is off by ±3 % in
/// one region and only the distribution tests can see it.
#[derive(Debug, Clone, Copy)]
pub struct RegionScaledPdf {
    /// The correct sampler.
    pub base: LobeMixture,
    /// Factor in the region `ωi.y > 0` (e.g. 1.03).
    pub factor: f64,
}

impl RegionScaledPdf {
    fn scale(&self, wi: &Vec3) -> f64 {
        if wi.y > 0.0 {
            self.factor
        } else {
            2.0 - self.factor
        }
    }
}

impl DirectionSampler for RegionScaledPdf {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let s = self.base.sample(wo, u);
        DirSample {
            wi: s.wi,
            pdf: s.pdf * self.scale(&s.wi),
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.base.pdf(wo, wi) * self.scale(wi)
    }

    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for RegionScaledPdf {}

/// Any direction sampler whose reported pdf (from `sample` and `pdf` alike) is multiplied by
/// `factor`: a normaliser off by `1/factor − 1` (e.g. `adaptive-exact` with `A(θo)` 1 % too
/// large). Self-consistent; its pdf integrates to `factor`.
pub struct ScaledPdf {
    /// The honest sampler.
    pub inner: std::sync::Arc<dyn DirectionSampler>,
    /// The factor.
    pub factor: f64,
}

impl DirectionSampler for ScaledPdf {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let s = self.inner.sample(wo, u);
        DirSample {
            pdf: s.pdf * self.factor,
            ..s
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.inner.pdf(wo, wi) * self.factor
    }

    fn bytes_used(&self) -> usize {
        self.inner.bytes_used()
    }
}

impl SamplerDiagnostics for ScaledPdf {
    fn bound_violations(&self) -> Option<u64> {
        self.inner.bound_violations()
    }
}
