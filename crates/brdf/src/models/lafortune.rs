//! Lafortune et al. (1997) generalised cosine lobes ("Non-linear approximation of reflectance
//! functions"), the model the seed papers call Lafortune (Lafortune & Willems 1994).
//!
//! `f_r = kd/π + Σ_j ks_j · (n_j+2)/(2π) · max(0, Cx_j ωo.x ωi.x + Cy_j ωo.y ωi.y + Cz_j ωo.z ωi.z)^{n_j}`.
//!
//! The published form `Σ_j [Cx ωo.x ωi.x + …]^{n}` puts the lobe magnitude into the `C`
//! coefficients; the form above is the same family with `C` rescaled by
//! `(ks (n+2)/2π)^{1/n}`, which makes `ks` read as an albedo. `Cx = Cy = −1, Cz = 1` is the
//! modified Phong lobe; `|Cx| > Cz` moves the peak towards grazing (off-specular reflection);
//! `Cx ≠ Cy` is anisotropic.
//!
//! Spec keys (one lobe): `kd` (default 0.3), `ks` (0.6), `cx` (−1), `cy` (−1), `cz` (0.95),
//! `n` (20, the exponent the GRAPP paper used). More lobes through [`Lafortune::new`].
//! Constraint: `n · ln(max(|Cx|, |Cy|, |Cz|)) ≤ 600` so that the lobe cannot overflow.
//! Reciprocal (the lobe is symmetric in ωo, ωi). With every `|C| ≤ 1` each lobe is bounded by a
//! Phong lobe of the same `n`, so the model conserves energy when additionally
//! `kd + Σ ks ≤ 1`.

use super::{Properties, brdf_properties};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate, validate_key};
use crate::registry::registry_entry;
use std::f64::consts::{FRAC_1_PI, PI};

registry_entry! {
    INFO: NAME = "lafortune", [], WhenParamsEqual, PARAMS,
    Lafortune::from_values,
    "generalised cosine lobe (Cx xx' + Cy yy' + Cz zz')^n (Lafortune et al. 1997)"
}

/// Largest allowed `n · ln(max|C|)` (keeps `C^n` far from overflow).
const MAX_LOG_LOBE: f64 = 600.0;

pub(crate) const PARAMS: &[ParamInfo] = &[
    param("kd", 0.3, Range::closed(0.0, 1.0), "diffuse albedo"),
    param(
        "ks",
        0.6,
        Range::closed(0.0, 1.0),
        "lobe albedo scale (normal-incidence albedo when C = (−1,−1,1))",
    ),
    param(
        "cx",
        -1.0,
        Range::closed(-10.0, 10.0),
        "lobe coefficient Cx (tangent)",
    ),
    param(
        "cy",
        -1.0,
        Range::closed(-10.0, 10.0),
        "lobe coefficient Cy (bitangent)",
    ),
    param(
        "cz",
        0.95,
        Range::closed(-10.0, 10.0),
        "lobe coefficient Cz (normal)",
    ),
    param("n", 20.0, Range::closed(0.0, 1e5), "lobe exponent"),
];

/// One generalised cosine lobe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LafortuneLobe {
    /// Albedo scale of the lobe.
    pub ks: f64,
    /// Tangent coefficient.
    pub cx: f64,
    /// Bitangent coefficient.
    pub cy: f64,
    /// Normal coefficient.
    pub cz: f64,
    /// Exponent.
    pub n: f64,
}

/// Parameters of [`Lafortune`].
#[derive(Debug, Clone, PartialEq)]
pub struct LafortuneParams {
    /// Diffuse albedo.
    pub kd: f64,
    /// Specular lobes (at least one is not required; zero lobes is Lambertian).
    pub lobes: Vec<LafortuneLobe>,
}

impl Default for LafortuneParams {
    fn default() -> Self {
        let [kd, ks, cx, cy, cz, n] = defaults(PARAMS);
        Self {
            kd,
            lobes: vec![LafortuneLobe { ks, cx, cy, cz, n }],
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct PreparedLobe {
    scale: f64,
    cx: f64,
    cy: f64,
    cz: f64,
    n: f64,
}

/// Lafortune generalised-cosine-lobe BRDF.
#[derive(Debug, Clone)]
pub struct Lafortune {
    params: LafortuneParams,
    diffuse: f64,
    lobes: Vec<PreparedLobe>,
}

impl Lafortune {
    /// Validate the parameters (each lobe field against the spec ranges) and build the model.
    pub fn new(params: LafortuneParams) -> Result<Self, ParamError> {
        validate_key(NAME, PARAMS, "kd", params.kd)?;
        let mut lobes = Vec::with_capacity(params.lobes.len());
        for l in &params.lobes {
            validate(NAME, &PARAMS[1..], &[l.ks, l.cx, l.cy, l.cz, l.n])?;
            // The lobe base is at most max|C| (|ωo.x ωi.x| + |ωo.y ωi.y| + |ωo.z ωi.z| ≤ 1), so
            // its power stays finite when n·ln(max|C|) ≤ 600.
            let cmax = l.cx.abs().max(l.cy.abs()).max(l.cz.abs());
            if cmax > 1.0 && l.n * cmax.ln() > MAX_LOG_LOBE {
                return Err(ParamError::Constraint {
                    model: NAME,
                    message: format!(
                        "lobe max|C|^n = {cmax}^{} overflows; need n·ln(max|C|) ≤ {MAX_LOG_LOBE}",
                        l.n
                    ),
                });
            }
            lobes.push(PreparedLobe {
                scale: l.ks * (l.n + 2.0) / (2.0 * PI),
                cx: l.cx,
                cy: l.cy,
                cz: l.cz,
                n: l.n,
            });
        }
        Ok(Self {
            diffuse: params.kd * FRAC_1_PI,
            lobes,
            params,
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &LafortuneParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [kd, ks, cx, cy, cz, n] = crate::params::take(v);
        Self::new(LafortuneParams {
            kd,
            lobes: vec![LafortuneLobe { ks, cx, cy, cz, n }],
        })
    }

    /// Symmetries and energy: products `x x'`, `y y'`, `z z'` only (half-turn symmetric; isotropic and
    /// mirror-symmetric iff `Cx = Cy` for every lobe), reciprocal; conserves energy when
    /// `kd + Σ ks ≤ 1` and every `|C| ≤ 1`.
    pub fn properties(&self) -> Properties {
        let ks: f64 = self.params.lobes.iter().map(|l| l.ks).sum();
        let bounded_lobes = self
            .params
            .lobes
            .iter()
            .all(|l| l.cx.abs() <= 1.0 && l.cy.abs() <= 1.0 && l.cz.abs() <= 1.0);
        Properties::elliptical(self.params.lobes.iter().all(|l| l.cx == l.cy))
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY.when(self.params.kd + ks <= 1.0 && bounded_lobes)
    }
}

crate::params::default_from!(Lafortune = Self::new(LafortuneParams::default()));

impl Brdf for Lafortune {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let (px, py, pz) = (wo.x * wi.x, wo.y * wi.y, wo.z * wi.z);
        let mut f = self.diffuse;
        for l in &self.lobes {
            let c = l.cx * px + l.cy * py + l.cz * pz;
            if c > 0.0 {
                f += l.scale * c.powf(l.n);
            }
        }
        f
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}
