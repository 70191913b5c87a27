//! `analytic`: the model's own importance sampler, as a renderer would use it.
//!
//! A one-sample mixture of cosine-weighted hemisphere sampling (probability
//! `p_d = diffuse/(diffuse + specular)` from the model's [`AnalyticLobes`]) and the specular
//! lobe's standard sampler; the pdf is the exact mixture `p_d·cos⁺θ/π + (1 − p_d)·p_s(ωi)`,
//! w.r.t. solid angle on S² (lobe samples below the horizon are zero-contribution samples):
//! * Phong — the cosine lobe `(n+1)/(2π) max(0, ω_r·ωi)^n` about the mirror direction;
//! * half-vector (Blinn, Lewis) — `h` from `(n+1)/(2π) (n·h)^n`, `ωi = 2(ωo·h)h − ωo`,
//!   `p_s = p_h(h)/(4|ωo·h|)` with `h` the half vector of `(ωo, ωi)` turned to `h_z > 0`;
//! * Ward — Ward's sampler of the half-vector slopes (Gaussian `e^{−(s_x/αx)² − (s_y/αy)²}`),
//!   `p_h = e^{−tan²θh(cos²φh/αx² + sin²φh/αy²)}/(π αx αy cos³θh)`, reflected as above;
//! * microfacet (GGX, Beckmann, Cook–Torrance's Beckmann) — visible normals of `ωo`,
//!   `p_s = G1(ωo) D(m)/(4 ωo_z)`.

mod vndf;

use std::f64::consts::{FRAC_1_PI, TAU};

use brdf::{AnalyticLobes, Brdf, SpecularLobe, Vec3, mirror};
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;

use super::LobeError;
use super::cosine_lobe::{cosine_density, lobe_density, sample_lobe};
use crate::CosineHemisphere;
use vndf::Distribution;

/// The specular part's sampler.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Specular {
    Phong(f64),
    HalfVector(f64),
    Ward { alpha_x: f64, alpha_y: f64 },
    Microfacet(Distribution),
}

/// The model's own importance sampler (see the module docs); support: the sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyticSampler {
    /// Probability of the cosine component.
    diffuse_probability: f64,
    specular: Option<Specular>,
}

impl AnalyticSampler {
    /// The analytic sampler of `brdf`.
    ///
    /// Errors: [`LobeError::NoAnalyticSampler`] when the model has none
    /// ([`Brdf::analytic_lobes`] is `None`), [`LobeError::BadAnalyticLobes`] for a negative or
    /// non-finite weight, exponent or roughness.
    pub fn new(brdf: &dyn Brdf) -> Result<Self, LobeError> {
        let lobes = brdf
            .analytic_lobes()
            .ok_or_else(|| LobeError::NoAnalyticSampler {
                model: brdf.name().to_owned(),
            })?;
        Self::from_lobes(&lobes).map_err(|reason| LobeError::BadAnalyticLobes {
            model: brdf.name().to_owned(),
            reason,
        })
    }

    /// The sampler of an explicit description.
    fn from_lobes(lobes: &AnalyticLobes) -> Result<Self, String> {
        let AnalyticLobes {
            diffuse,
            specular,
            lobe,
        } = *lobes;
        if !(diffuse >= 0.0 && diffuse.is_finite() && specular >= 0.0 && specular.is_finite()) {
            return Err(format!(
                "weights must be finite and ≥ 0 (diffuse {diffuse}, specular {specular})"
            ));
        }
        let positive = |what: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(v)
            } else {
                Err(format!("{what} = {v} must be finite and > 0"))
            }
        };
        let exponent = |n: f64| {
            if n >= 0.0 && n.is_finite() {
                Ok(n)
            } else {
                Err(format!("exponent {n} must be finite and ≥ 0"))
            }
        };
        let spec = match lobe {
            None => None,
            Some(SpecularLobe::Phong { exponent: n }) => Some(Specular::Phong(exponent(n)?)),
            Some(SpecularLobe::HalfVector { exponent: n }) => {
                Some(Specular::HalfVector(exponent(n)?))
            }
            Some(SpecularLobe::Ward { alpha_x, alpha_y }) => Some(Specular::Ward {
                alpha_x: positive("alpha_x", alpha_x)?,
                alpha_y: positive("alpha_y", alpha_y)?,
            }),
            Some(SpecularLobe::Microfacet {
                distribution,
                alpha_x,
                alpha_y,
            }) => Some(Specular::Microfacet(Distribution {
                kind: distribution,
                alpha_x: positive("alpha_x", alpha_x)?,
                alpha_y: positive("alpha_y", alpha_y)?,
            })),
        };
        let diffuse_probability = match spec {
            Some(_) if diffuse + specular > 0.0 => diffuse / (diffuse + specular),
            Some(_) => 0.5,
            None => 1.0,
        };
        Ok(Self {
            diffuse_probability,
            specular: spec,
        })
    }

    /// Probability of drawing from the cosine (diffuse) component.
    pub fn diffuse_probability(&self) -> f64 {
        self.diffuse_probability
    }

    /// Density of the specular component at `wi` (w.r.t. solid angle on S²), `wo.z > 0`.
    fn specular_pdf(spec: &Specular, wo: &Vec3, wi: &Vec3) -> f64 {
        match spec {
            Specular::Phong(n) => lobe_density(*n, mirror(wo).dot(wi)),
            Specular::HalfVector(n) => reflected(wo, wi, |h| lobe_density(*n, h.z)),
            Specular::Ward { alpha_x, alpha_y } => {
                reflected(wo, wi, |h| ward_half_pdf(*alpha_x, *alpha_y, h))
            }
            Specular::Microfacet(d) => d.reflected_pdf(wo, wi),
        }
    }

    /// A draw of the specular component, `wo.z > 0`.
    fn sample_specular(spec: &Specular, wo: &Vec3, u: [f64; 2]) -> Vec3 {
        let reflect = |h: Vec3| (h * (2.0 * wo.dot(&h)) - wo).normalize();
        match spec {
            Specular::Phong(n) => sample_lobe(&mirror(wo), *n, u),
            Specular::HalfVector(n) => reflect(sample_lobe(&Vec3::z(), *n, u)),
            Specular::Ward { alpha_x, alpha_y } => {
                let rho = (-(1.0 - u[0]).ln()).sqrt();
                let psi = TAU * u[1];
                let (sx, sy) = (alpha_x * rho * psi.cos(), alpha_y * rho * psi.sin());
                reflect(Vec3::new(-sx, -sy, 1.0).normalize())
            }
            Specular::Microfacet(d) => reflect(d.sample_visible(wo, u)),
        }
    }
}

/// Density of `ωi = reflect(ωo, h)` for `h` drawn from `p_h` on the upper hemisphere:
/// `p_h(h)/(4|ωo·h|)` with `h = ±(ωo+ωi)/|ωo+ωi|`, the sign making `h_z > 0` (the one `h` that
/// maps to `ωi`).
///
/// For unit `ωo`, `ωi` and `s = ωo + ωi`, `ωo·s = 1 + ωo·ωi = |s|²/2`, so `|ωo·h| = |s|/2` and
/// the density is `p_h(h)/(2|s|)`. That form is used because it is stable: the density has an
/// integrable `1/|s|` peak at `ωi = −ωo` (below the horizon; a fold of the reflection map),
/// where `ωo·h` computed as a dot product loses every digit to cancellation (`1 + ωo·ωi` is
/// `O(|s|²)`), while `|s|` keeps its relative accuracy down to `|s| ≈ 10⁻¹⁵`.
fn reflected(wo: &Vec3, wi: &Vec3, p_h: impl Fn(&Vec3) -> f64) -> f64 {
    let s = wo + wi;
    let len = s.norm();
    if !(len > 0.0) {
        return 0.0;
    }
    let h = if s.z >= 0.0 { s / len } else { -s / len };
    p_h(&h) / (2.0 * len)
}

/// Ward's half-vector density (w.r.t. solid angle of `h`): the Gaussian of the slopes
/// `(h_x/h_z, h_y/h_z)` divided by the Jacobian `1/cos³θh`.
fn ward_half_pdf(alpha_x: f64, alpha_y: f64, h: &Vec3) -> f64 {
    if !(h.z > 0.0) {
        return 0.0;
    }
    let (sx, sy) = (h.x / h.z, h.y / h.z);
    let e = (-(sx / alpha_x).powi(2) - (sy / alpha_y).powi(2)).exp();
    e * FRAC_1_PI / (alpha_x * alpha_y * h.z.powi(3))
}

impl DirectionSampler for AnalyticSampler {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let pick = u.next_uniform();
        let uv = [u.next_uniform(), u.next_uniform()];
        let wi = match &self.specular {
            Some(spec) if wo.z > 0.0 && pick >= self.diffuse_probability => {
                Self::sample_specular(spec, wo, uv)
            }
            _ => CosineHemisphere::sample_square(uv).wi,
        };
        DirSample {
            wi,
            pdf: self.pdf(wo, &wi),
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let cosine = cosine_density(wi);
        match &self.specular {
            Some(spec) if wo.z > 0.0 => {
                let pd = self.diffuse_probability;
                pd * cosine + (1.0 - pd) * Self::specular_pdf(spec, wo, wi)
            }
            _ => cosine,
        }
    }

    fn bytes_used(&self) -> usize {
        // Nothing is precomputed: a few model parameters.
        0
    }
}

impl SamplerDiagnostics for AnalyticSampler {
    /// The mirror direction (the specular lobe's peak) and, for the samplers that reflect a
    /// half vector (Blinn, Lewis, Ward, microfacet), `−ωo`: the fold of the reflection map,
    /// where the half vector `(ωo+ωi)/|ωo+ωi|` has no limit, so the pdf's value depends on the
    /// direction of approach — an integrable `1/|ωo+ωi|` wedge for `p_h/(2|ωo+ωi|)`, a bounded
    /// one for the visible-normal pdf `G1 D(m)/(4 ωo_z)`. None for the cosine part alone.
    fn singular_directions(&self, wo: &Vec3) -> Vec<Vec3> {
        match &self.specular {
            Some(Specular::Phong(_)) if wo.z > 0.0 => vec![mirror(wo)],
            Some(_) if wo.z > 0.0 => vec![mirror(wo), -wo],
            _ => Vec::new(),
        }
    }
}
