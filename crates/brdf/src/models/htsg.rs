//! He, Torrance, Sillion & Greenberg (1991), "A comprehensive physical model for light
//! reflection" — the directional-diffuse term plus a uniform-diffuse term.
//!
//! `f_r = |F|² G S D / (π cosθi cosθo) + kd/π`. The ideal specular term
//! `ρ_sp ∝ |F|² e^{−g} S Δ` is a Dirac delta around the mirror direction and cannot be evaluated
//! as a function; it is omitted (a sampler cannot represent it either). With `s = ωi + ωo`
//! (unit vectors), `k = 2π/λ` and the wave-vector change `v = k s`:
//!
//! * **D** (eq. 78, physical-units form as in Westin's reference code):
//!   `D = (π² τ² / (4 λ²)) Σ_{m≥1} e^{−g} g^m / (m! m) · exp(−v_xy² τ² / (4m))`,
//!   `g = (k σ (cosθi + cosθo))²`, `v_xy² = k² (s_x² + s_y²)`.
//!   **Truncation:** the Poisson series is summed from `m = 1` until `m > g` and the weight
//!   `e^{−g} g^m/(m! m)` drops below `10⁻¹⁴/g` (absolute error ≲ 10⁻¹⁴ of the lobe peak), at most
//!   500 terms. For very rough surfaces the sum is blended linearly into Beckmann's rough-surface
//!   limit `e^{−v_xy²τ²/(4g)}/g` for `g ∈ [150, 200]` (limit only above 200).
//! * **G** (eq. 76) `= (s·s / s_z)² · [(ŝr·k̂i)² + (p̂r·k̂i)²][(ŝi·k̂r)² + (p̂i·k̂r)²] / |k̂r × k̂i|⁴`;
//!   each bracket equals `1 − (k̂i·k̂r)² = |k̂r × k̂i|²` because `(ŝ, p̂, k̂)` is orthonormal, so
//!   `G = (s·s / s_z)²` exactly.
//! * **S** (eqs. 23–25, with the errata's exponential): `S = S1(θi) S1(θo)`,
//!   `S1 = (1 − ½ erfc(a)) / (Λ(a) + 1)`, `a = τ cotθ / (2σ0)`,
//!   `Λ(a) = (e^{−a²}/(a√π) − erfc(a))/2`.
//! * **Effective roughness** (eqs. 80–82): `σ = σ0 / √(1 + z0²/σ0²)` with `x = z0/σ0` solving
//!   `x e^{x²/2} = (Ki + Ko)/√(8π)`, `K(θ) = tanθ · erfc(τ / (2 σ0 tanθ))` (Newton iteration).
//! * **F**: unpolarised Fresnel reflectance of index `ior + i·kappa` at the local angle
//!   `cos = ωi·h = |s|/2`.
//!
//! Keys (seed 000 used σ = 0.5, τ = 3, λ = 800): `sigma ∈ (0, 10]` µm (RMS height σ0, default
//! 0.5), `tau ∈ (0, 100]` µm (autocorrelation length, default 3), `lambda ∈ [100, 10⁴]` nm
//! (wavelength, default 800), `ior ∈ (0, 100]` (default 1.5), `kappa ∈ [0, 100]` (default 0),
//! `kd ∈ [0, 1]` (uniform diffuse albedo, default 0). Reciprocal and isotropic; energy
//! conservation is not claimed (Kirchhoff approximation).

use crate::brdf::Brdf;
use crate::fresnel::fresnel_conductor;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use crate::special::{beckmann_lambda, erfc};
use std::f64::consts::{FRAC_1_PI, PI};

pub(crate) const NAME: &str = "htsg";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param(
        "sigma",
        0.5,
        Range::left_open(0.0, 10.0),
        "RMS surface height σ0 (µm)",
    ),
    param(
        "tau",
        3.0,
        Range::left_open(0.0, 100.0),
        "autocorrelation length τ (µm)",
    ),
    param(
        "lambda",
        800.0,
        Range::closed(100.0, 10_000.0),
        "wavelength λ (nm)",
    ),
    param(
        "ior",
        1.5,
        Range::left_open(0.0, 100.0),
        "refractive index, real part",
    ),
    param(
        "kappa",
        0.0,
        Range::closed(0.0, 100.0),
        "refractive index, imaginary part (extinction)",
    ),
    param("kd", 0.0, Range::closed(0.0, 1.0), "uniform-diffuse albedo"),
];

/// Below this `g` the Poisson series alone is used.
const G_SERIES_ONLY: f64 = 150.0;
/// Above this `g` only Beckmann's rough-surface limit is used.
const G_LIMIT_ONLY: f64 = 200.0;
/// Hard cap on series terms.
const MAX_TERMS: usize = 500;

/// Parameters of [`Htsg`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HtsgParams {
    /// RMS roughness σ0 in µm.
    pub sigma: f64,
    /// Autocorrelation length τ in µm.
    pub tau: f64,
    /// Wavelength in nm.
    pub lambda: f64,
    /// Real part of the refractive index.
    pub ior: f64,
    /// Extinction coefficient.
    pub kappa: f64,
    /// Uniform diffuse albedo.
    pub kd: f64,
}

impl Default for HtsgParams {
    fn default() -> Self {
        let [sigma, tau, lambda, ior, kappa, kd] = defaults(PARAMS);
        Self {
            sigma,
            tau,
            lambda,
            ior,
            kappa,
            kd,
        }
    }
}

/// He–Torrance–Sillion–Greenberg BRDF (directional-diffuse + uniform-diffuse).
#[derive(Debug, Clone)]
pub struct Htsg {
    params: HtsgParams,
    /// Wavenumber k = 2π/λ in 1/µm.
    k: f64,
    /// π²τ²/(4λ²), λ in µm.
    d_prefactor: f64,
    /// τ/(2σ0).
    tau_over_2sigma: f64,
}

impl Htsg {
    /// Validate the parameters and build the model.
    pub fn new(params: HtsgParams) -> Result<Self, ParamError> {
        let HtsgParams {
            sigma,
            tau,
            lambda,
            ior,
            kappa,
            kd,
        } = params;
        validate(NAME, PARAMS, &[sigma, tau, lambda, ior, kappa, kd])?;
        let lambda_um = lambda * 1e-3;
        Ok(Self {
            params,
            k: 2.0 * PI / lambda_um,
            d_prefactor: PI * PI * tau * tau / (4.0 * lambda_um * lambda_um),
            tau_over_2sigma: tau / (2.0 * sigma),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &HtsgParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [sigma, tau, lambda, ior, kappa, kd] = super::take(v);
        Self::new(HtsgParams {
            sigma,
            tau,
            lambda,
            ior,
            kappa,
            kd,
        })
    }

    /// Single-direction shadowing `S1(θ)` for `cosθ = c`.
    #[inline]
    fn shadow(&self, c: f64) -> f64 {
        let s = (1.0 - c * c).max(0.0).sqrt();
        if s <= 0.0 {
            return 1.0;
        }
        let a = self.tau_over_2sigma * c / s;
        (1.0 - 0.5 * erfc(a)) / (beckmann_lambda(a) + 1.0)
    }

    /// `K(θ) = tanθ erfc(τ/(2σ0 tanθ))` for `cosθ = c`.
    #[inline]
    fn k_fn(&self, c: f64) -> f64 {
        let s = (1.0 - c * c).max(0.0).sqrt();
        if s <= 0.0 {
            return 0.0;
        }
        let tan = s / c;
        tan * erfc(self.tau_over_2sigma / tan)
    }

    /// Effective roughness σ(θi, θo) in µm.
    fn effective_sigma(&self, ci: f64, co: f64) -> f64 {
        let q = (self.k_fn(ci) + self.k_fn(co)) / (8.0 * PI).sqrt();
        if !(q > 0.0) {
            return self.params.sigma;
        }
        // Solve x e^{x²/2} = q (increasing, convex for x ≥ 0) by Newton's method.
        let mut x = if q <= 1.0 { q } else { (2.0 * q.ln()).sqrt() };
        for _ in 0..50 {
            let e = (0.5 * x * x).exp();
            let dx = (x * e - q) / ((1.0 + x * x) * e);
            x = (x - dx).max(0.0);
            if dx.abs() <= 1e-14 * (1.0 + x) {
                break;
            }
        }
        self.params.sigma / (1.0 + x * x).sqrt()
    }

    /// `Σ_{m≥1} e^{−g} g^m/(m! m) e^{−a/m}` (see the module docs for the truncation).
    fn series(g: f64, a: f64) -> f64 {
        let mut w = (-g).exp(); // e^{-g} g^m / m! at m = 0
        let mut sum = 0.0;
        let tol = 1e-14 / g.max(1.0);
        for m in 1..=MAX_TERMS {
            let mf = m as f64;
            w *= g / mf;
            let term = w / mf;
            sum += term * (-a / mf).exp();
            if mf > g && term < tol {
                break;
            }
        }
        sum
    }

    /// Directional-diffuse distribution `D` (dimensionless).
    fn distribution(&self, g: f64, a: f64) -> f64 {
        let limit = |g: f64| (-a / g).exp() / g;
        let s = if g <= G_SERIES_ONLY {
            Self::series(g, a)
        } else if g >= G_LIMIT_ONLY {
            limit(g)
        } else {
            let t = (g - G_SERIES_ONLY) / (G_LIMIT_ONLY - G_SERIES_ONLY);
            (1.0 - t) * Self::series(g, a) + t * limit(g)
        };
        self.d_prefactor * s
    }
}

impl Default for Htsg {
    fn default() -> Self {
        super::expect_default(Self::new(HtsgParams::default()))
    }
}

impl Brdf for Htsg {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let (ci, co) = (wi.z, wo.z);
        let s = wo + wi;
        let sxy2 = s.x * s.x + s.y * s.y;
        let ss = sxy2 + s.z * s.z;
        let geo = (ss / s.z) * (ss / s.z);
        let fres = fresnel_conductor(0.5 * ss.sqrt(), self.params.ior, self.params.kappa);
        let shadow = self.shadow(ci) * self.shadow(co);
        let sigma = self.effective_sigma(ci, co);
        let ks = self.k * sigma * s.z;
        let g = ks * ks;
        let a = self.k * self.k * sxy2 * self.params.tau * self.params.tau / 4.0;
        let d = self.distribution(g, a);
        fres * geo * shadow * d / (PI * ci * co) + self.params.kd * FRAC_1_PI
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_reciprocal(&self) -> bool {
        true
    }
    fn name(&self) -> &str {
        NAME
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::direction_from_angles;
    use crate::models::{Microfacet, MicrofacetParams};

    #[test]
    fn series_matches_rough_limit_for_large_g() {
        for a in [0.0, 10.0, 100.0, 400.0] {
            let (s, l) = (Htsg::series(150.0, a), (-a / 150.0f64).exp() / 150.0);
            assert!((s - l).abs() < 0.02 * l, "a={a}: series {s} limit {l}");
        }
        // Small g: only the first terms matter,
        // Σ ≈ e^{-g}(g e^{-a} + g²/4 e^{-a/2} + g³/18 e^{-a/3}).
        let (g, a) = (1e-3f64, 0.5f64);
        let expect = (-g).exp()
            * (g * (-a).exp()
                + g * g / 4.0 * (-a / 2.0).exp()
                + g.powi(3) / 18.0 * (-a / 3.0).exp());
        assert!((Htsg::series(g, a) - expect).abs() < 1e-9 * expect);
    }

    /// In the rough, near-normal regime HTSG reduces to a Beckmann microfacet BRDF with
    /// RMS slope m = 2σ0/τ (checks the prefactor, G and S algebra independently).
    #[test]
    fn geometric_optics_limit_is_beckmann_microfacet() {
        let p = HtsgParams {
            sigma: 2.0,
            tau: 12.0,
            lambda: 500.0,
            ior: 20.0,
            kappa: 0.0,
            kd: 0.0,
        };
        let h = Htsg::new(p).unwrap();
        let m = 2.0 * p.sigma / p.tau;
        let mf = Microfacet::beckmann(MicrofacetParams {
            alpha_x: m,
            alpha_y: m,
            f0: 1.0,
        })
        .unwrap();
        let wo = direction_from_angles(15.0, 0.0);
        for (t, phi) in [(15.0, 180.0), (10.0, 170.0), (25.0, 190.0), (18.0, 150.0)] {
            let wi = direction_from_angles(t, phi);
            let half = (wo + wi).normalize();
            let g1 = 1.0 / ((1.0 + mf.lambda(&wo)) * (1.0 + mf.lambda(&wi)));
            let f = fresnel_conductor(wi.dot(&half), p.ior, p.kappa);
            let expect = f * mf.d(&half) * g1 / (4.0 * wo.z * wi.z);
            let got = h.eval(&wo, &wi);
            assert!(
                (got - expect).abs() < 0.02 * expect,
                "θi={t}: {got} vs {expect}"
            );
        }
    }

    #[test]
    fn effective_roughness_shrinks_at_grazing() {
        let h = Htsg::default();
        assert!((h.effective_sigma(1.0, 1.0) - 0.5).abs() < 1e-12);
        let s = h.effective_sigma(0.05, 0.05);
        assert!(s < 0.5 && s > 0.0);
        // x e^{x²/2} = q is solved accurately.
        let (ci, co) = (0.05, 0.3);
        let q = (h.k_fn(ci) + h.k_fn(co)) / (8.0 * PI).sqrt();
        let x = (((0.5 / h.effective_sigma(ci, co)).powi(2)) - 1.0).sqrt();
        assert!((x * (0.5 * x * x).exp() - q).abs() < 1e-9 * q);
    }
}
