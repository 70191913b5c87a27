//! Microfacet reflection with Smith masking–shadowing, Walter, Marschner, Li & Torrance (2007),
//! "Microfacet models for refraction through rough surfaces" (reflection part), with the
//! anisotropic distributions of Heitz (2014).
//!
//! `f_r = F(ωi·h) · D(h) · G1(ωo) G1(ωi) / (4 cosθi cosθo)` (separable Smith G), where with
//! `s² = (h_x/αx)² + (h_y/αy)²`:
//!
//! * **Beckmann** (`beckmann`): `D = exp(−s²/h_z²) / (π αx αy h_z⁴)`,
//!   `Λ(ω) = (e^{−a²}/(a√π) − erfc(a))/2`, `a = ω_z / √((αx ω_x)² + (αy ω_y)²)`;
//! * **GGX / Trowbridge–Reitz** (`ggx`): `D = 1 / (π αx αy (s² + h_z²)²)`,
//!   `Λ(ω) = (√(1 + ((αx ω_x)² + (αy ω_y)²)/ω_z²) − 1)/2`;
//!
//! and `G1 = 1/(1 + Λ)`, `F(c) = f0 + (1 − f0)(1 − c)^5` (Schlick). Keys: `alpha ∈ [0.001, 2]`
//! (default 0.2; roughness along x), `alpha_y` (default `= alpha`), `f0 ∈ [0, 1]` (default 1:
//! a perfect conductor). `D` is normalised (`∫ D cosθh dσ = 1`) and Smith masking satisfies the
//! projected-area constraint, so the albedo is at most `max F ≤ 1`: energy-conserving, reciprocal,
//! isotropic iff `alpha = alpha_y`.

use super::{Properties, brdf_properties, model_common, model_params};
use crate::brdf::Brdf;
use crate::fresnel::fresnel_schlick;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, Range};
use crate::registry::registry_entry;
use crate::special::beckmann_lambda;
use std::f64::consts::PI;

registry_entry! {
    INFO_BECKMANN: NAME_BECKMANN = "beckmann", [], WhenParamsEqual, PARAMS,
    |v| Microfacet::from_values(v, NormalDistribution::Beckmann),
    "Beckmann microfacet with Smith G (Walter et al. 2007), anisotropic α"
}

registry_entry! {
    INFO_GGX: NAME_GGX = "ggx", ["trowbridge-reitz"], WhenParamsEqual, PARAMS,
    |v| Microfacet::from_values(v, NormalDistribution::Ggx),
    "GGX microfacet with Smith G (Walter et al. 2007), anisotropic α"
}

/// Microfacet normal distribution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalDistribution {
    /// Beckmann–Spizzichino (Gaussian slopes).
    Beckmann,
    /// GGX / Trowbridge–Reitz.
    Ggx,
}

impl NormalDistribution {
    /// The registry name of the model with this distribution (`beckmann`, `ggx`).
    pub fn model_name(self) -> &'static str {
        match self {
            NormalDistribution::Beckmann => NAME_BECKMANN,
            NormalDistribution::Ggx => NAME_GGX,
        }
    }
}

model_params! {
    /// Parameters of [`Microfacet`].
    pub struct MicrofacetParams in PARAMS {
        alpha_x as "alpha" = [0.2] in Range::closed(0.001, 2.0), "roughness α along the tangent x";
        alpha_y = [same_as alpha] in Range::closed(0.001, 2.0), "roughness α along the bitangent y";
        f0 = [1.0] in Range::closed(0.0, 1.0), "Fresnel reflectance at normal incidence (Schlick)";
    }
}

/// Walter et al. microfacet reflection BRDF (Beckmann or GGX).
#[derive(Debug, Clone)]
pub struct Microfacet {
    params: MicrofacetParams,
    dist: NormalDistribution,
    inv_ax2: f64,
    inv_ay2: f64,
    ax2: f64,
    ay2: f64,
    d_scale: f64,
}

impl Microfacet {
    /// Validate the parameters and build the model.
    pub fn new(params: MicrofacetParams, dist: NormalDistribution) -> Result<Self, ParamError> {
        params.validate(dist.model_name())?;
        let (ax, ay) = (params.alpha_x, params.alpha_y);
        Ok(Self {
            params,
            dist,
            inv_ax2: 1.0 / (ax * ax),
            inv_ay2: 1.0 / (ay * ay),
            ax2: ax * ax,
            ay2: ay * ay,
            d_scale: 1.0 / (PI * ax * ay),
        })
    }

    /// Beckmann model with the given parameters.
    pub fn beckmann(params: MicrofacetParams) -> Result<Self, ParamError> {
        Self::new(params, NormalDistribution::Beckmann)
    }

    /// GGX model with the given parameters.
    pub fn ggx(params: MicrofacetParams) -> Result<Self, ParamError> {
        Self::new(params, NormalDistribution::Ggx)
    }

    /// The normal distribution in use.
    pub fn distribution(&self) -> NormalDistribution {
        self.dist
    }

    /// Normal distribution `D(m)` for a unit microfacet normal `m` (per unit solid angle of `m`,
    /// normalised so that `∫ D(m) m_z dσ(m) = 1`).
    #[inline]
    pub fn d(&self, m: &Vec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let s2 = m.x * m.x * self.inv_ax2 + m.y * m.y * self.inv_ay2;
        let z2 = m.z * m.z;
        match self.dist {
            NormalDistribution::Beckmann => self.d_scale * (-s2 / z2).exp() / (z2 * z2),
            NormalDistribution::Ggx => {
                let t = s2 + z2;
                self.d_scale / (t * t)
            }
        }
    }

    /// Smith `Λ(ω)` for a direction in the upper hemisphere.
    #[inline]
    pub fn lambda(&self, w: &Vec3) -> f64 {
        let t2 = (w.x * w.x * self.ax2 + w.y * w.y * self.ay2) / (w.z * w.z);
        match self.dist {
            NormalDistribution::Ggx => 0.5 * ((1.0 + t2).sqrt() - 1.0),
            NormalDistribution::Beckmann => {
                if t2 <= 0.0 {
                    0.0
                } else {
                    beckmann_lambda(1.0 / t2.sqrt())
                }
            }
        }
    }

    /// Symmetries and energy: half-turn symmetric for all `αx, αy`, isotropic and mirror-symmetric
    /// iff `αx = αy`; reciprocal; conserves energy (single scattering loses energy, never gains).
    pub fn properties(&self) -> Properties {
        Properties::elliptical(self.params.alpha_x == self.params.alpha_y)
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY
    }
}

model_common!(Microfacet(MicrofacetParams, dist: NormalDistribution));

impl Brdf for Microfacet {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        let d = self.d(&h);
        let g = 1.0 / ((1.0 + self.lambda(wo)) * (1.0 + self.lambda(wi)));
        let f = fresnel_schlick(self.params.f0, wi.dot(&h));
        f * d * g / (4.0 * wi.z * wo.z)
    }
    brdf_properties!();
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
    fn analytic_lobes(&self) -> Option<crate::AnalyticLobes> {
        Some(crate::AnalyticLobes {
            diffuse: 0.0,
            specular: 1.0,
            lobe: Some(crate::SpecularLobe::Microfacet {
                distribution: self.dist,
                alpha_x: self.params.alpha_x,
                alpha_y: self.params.alpha_y,
            }),
        })
    }
    fn name(&self) -> &str {
        self.dist.model_name()
    }
}
