//! Correct analytic direction samplers: the bases of the direction mutants (and their controls).

use std::f64::consts::{FRAC_1_PI, TAU};

use brdf::{Vec3, direction_from_angles};
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;

/// Cosine-weighted hemisphere sampling: `p(ωi) = cos θi / π` w.r.t. solid angle on `z > 0`.
#[derive(Debug, Clone, Copy, Default)]
pub struct CosineHemisphere;

/// A cosine-weighted direction from two uniforms (`z > 0`).
pub fn cosine_direction(u: &mut dyn UniformSource) -> Vec3 {
    let (u1, u2) = (u.next_uniform(), u.next_uniform());
    let r = u1.sqrt();
    let (s, c) = (TAU * u2).sin_cos();
    Vec3::new(r * c, r * s, (1.0 - u1).sqrt())
}

/// `cos θ / π` on `z > 0`, else 0.
pub fn cosine_pdf(wi: &Vec3) -> f64 {
    if wi.z > 0.0 { wi.z * FRAC_1_PI } else { 0.0 }
}

impl DirectionSampler for CosineHemisphere {
    fn sample(&self, _wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let wi = cosine_direction(u);
        DirSample {
            pdf: cosine_pdf(&wi),
            wi,
        }
    }

    fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        cosine_pdf(wi)
    }

    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for CosineHemisphere {}

/// A mixture of cosine-weighted hemisphere sampling and a Phong lobe
/// `p_lobe(ωi) = (n+1)/(2π) max(0, a·ωi)^n` around an axis `a` (support on the sphere: lobe
/// samples may fall below the horizon and then contribute zero).
///
/// The axis is the mirror direction of `ωo`, or, with `slice_step = Some(Δ)`, the mirror
/// direction of the nearest "slice" `θ_j = Δ · round(θo/Δ)` at `ωo`'s azimuth (the way tabulated
/// samplers handle `ωo`). The knobs below are all neutral in [`LobeMixture::correct`]; the
/// mutants set them to break the sampler in one specific way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LobeMixture {
    /// Lobe exponent `n ≥ 0`.
    pub exponent: f64,
    /// Probability of drawing from the cosine component.
    pub select_diffuse: f64,
    /// Weights `(w_cos, w_lobe)` of the components in the reported pdf.
    pub pdf_weights: [f64; 2],
    /// Slice spacing in degrees, or `None` to use `θo` itself.
    pub slice_step: Option<f64>,
    /// The pdf uses slice `j + pdf_slice_offset` when sampling used slice `j`.
    pub pdf_slice_offset: i32,
    /// Sampled lobe axis tilted by this many degrees in the plane of incidence (the pdf uses
    /// the untilted axis).
    pub lobe_tilt_deg: f64,
}

impl LobeMixture {
    /// A correct mixture with cosine weight `w` and lobe exponent `n`.
    pub fn correct(w: f64, n: f64) -> Self {
        Self {
            exponent: n,
            select_diffuse: w,
            pdf_weights: [w, 1.0 - w],
            slice_step: None,
            pdf_slice_offset: 0,
            lobe_tilt_deg: 0.0,
        }
    }

    /// Lobe axis for `wo`, slice offset `offset` and extra tilt (degrees).
    fn axis(&self, wo: &Vec3, offset: i32, tilt: f64) -> Vec3 {
        let theta = wo.z.clamp(-1.0, 1.0).acos().to_degrees();
        let phi = wo.y.atan2(wo.x).to_degrees();
        let theta_slice = match self.slice_step {
            Some(step) => {
                (((theta / step).round() as i64 + i64::from(offset)) as f64 * step).clamp(0.0, 89.9)
            }
            None => theta,
        };
        // Mirror of (θ, φ) is (θ, φ + 180°).
        direction_from_angles(theta_slice + tilt, phi + 180.0)
    }

    fn lobe_pdf(&self, axis: &Vec3, wi: &Vec3) -> f64 {
        let c = axis.dot(wi);
        if c > 0.0 {
            (self.exponent + 1.0) / TAU * c.powf(self.exponent)
        } else {
            0.0
        }
    }

    fn sample_lobe(&self, axis: &Vec3, u: &mut dyn UniformSource) -> Vec3 {
        let (u1, u2) = (u.next_uniform(), u.next_uniform());
        let cos_a = (1.0 - u1).powf(1.0 / (self.exponent + 1.0));
        let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
        let helper = if axis.x.abs() < 0.9 {
            Vec3::new(1.0, 0.0, 0.0)
        } else {
            Vec3::new(0.0, 1.0, 0.0)
        };
        let t = helper.cross(axis).normalize();
        let b = axis.cross(&t);
        let (s, c) = (TAU * u2).sin_cos();
        (t * (sin_a * c) + b * (sin_a * s) + axis * cos_a).normalize()
    }

    fn mixture_pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let axis = self.axis(wo, self.pdf_slice_offset, 0.0);
        self.pdf_weights[0] * cosine_pdf(wi) + self.pdf_weights[1] * self.lobe_pdf(&axis, wi)
    }
}

impl DirectionSampler for LobeMixture {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let wi = if u.next_uniform() < self.select_diffuse {
            cosine_direction(u)
        } else {
            self.sample_lobe(&self.axis(wo, 0, self.lobe_tilt_deg), u)
        };
        DirSample {
            pdf: self.mixture_pdf(wo, &wi),
            wi,
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.mixture_pdf(wo, wi)
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
    }
}

impl SamplerDiagnostics for LobeMixture {}
