//! Ashikhmin & Shirley (2000), "An anisotropic Phong BRDF model".
//!
//! With `h` the normalised half vector, `k·h = ωi·h`:
//!
//! * specular `ρs = √((nu+1)(nv+1))/(8π) · (n·h)^{(nu h_x² + nv h_y²)/(1 − h_z²)} / ((k·h) max(cosθi, cosθo)) · F(k·h)`,
//!   `F(c) = Rs + (1 − Rs)(1 − c)^5` (Schlick);
//! * diffuse `ρd = 28 Rd/(23π) (1 − Rs) (1 − (1 − cosθi/2)^5)(1 − (1 − cosθo/2)^5)`.
//!
//! Keys: `nu` (default 100), `nv` (default `= nu`), both in `[0, 10⁵]` (exponents along tangent x
//! and bitangent y); `rs` (0.3) and `rd` (0.6), both in `[0, 1]`. Reciprocal; isotropic iff
//! `nu = nv`. The paper designs the model to conserve energy (the specular lobe is normalised
//! only approximately); the tests confirm albedo ≤ 1 for `rs, rd ≤ 1` at the angles checked, and
//! `conserves_energy()` reports true.

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, above_with_half};
use crate::params::Range;
use std::f64::consts::PI;

model! {
    /// Parameters of [`AshikhminShirley`].
    pub struct AshikhminShirleyParams in PARAMS {
        nu = [100.0] in Range::closed(0.0, 1e5), "Phong exponent along the tangent x";
        nv = [same_as nu] in Range::closed(0.0, 1e5), "Phong exponent along the bitangent y";
        rs = [0.3] in Range::closed(0.0, 1.0), "specular reflectance at normal incidence";
        rd = [0.6] in Range::closed(0.0, 1.0), "diffuse reflectance";
    }
    registry INFO: NAME = "ashikhmin-shirley", ["ashikhmin"], WhenParamsEqual,
        "anisotropic Phong with Fresnel and coupled diffuse (Ashikhmin & Shirley 2000)";
    /// Ashikhmin–Shirley anisotropic Phong BRDF.
    pub struct AshikhminShirley(params) {
        spec_scale: f64 = ((params.nu + 1.0) * (params.nv + 1.0)).sqrt() / (8.0 * PI),
        diff_scale: f64 = 28.0 * params.rd / (23.0 * PI) * (1.0 - params.rs),
    }
}

impl AshikhminShirley {
    /// Symmetries and energy: half-turn symmetric for all `nu, nv` (terms in `h_x²`, `h_y²`),
    /// isotropic and mirror-symmetric iff `nu = nv`; reciprocal; conserves energy.
    pub fn properties(&self) -> Properties {
        Properties::elliptical(self.params.nu == self.params.nv)
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY
    }
}

#[inline]
fn pow5(x: f64) -> f64 {
    let x2 = x * x;
    x2 * x2 * x
}

impl Brdf for AshikhminShirley {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some((ci, co, h)) = above_with_half(wo, wi) else {
            return 0.0;
        };
        let kh = wi.dot(&h).clamp(1e-12, 1.0);
        let sin2 = h.x * h.x + h.y * h.y;
        let lobe = if sin2 > 1e-300 {
            let e = (self.params.nu * h.x * h.x + self.params.nv * h.y * h.y) / sin2;
            h.z.powf(e)
        } else {
            1.0
        };
        let fres = self.params.rs + (1.0 - self.params.rs) * pow5(1.0 - kh);
        let spec = self.spec_scale * lobe / (kh * ci.max(co)) * fres;
        let diff = self.diff_scale * (1.0 - pow5(1.0 - 0.5 * ci)) * (1.0 - pow5(1.0 - 0.5 * co));
        spec + diff
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}
