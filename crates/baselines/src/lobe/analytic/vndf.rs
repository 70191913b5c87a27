//! Microfacet distributions `D`, Smith `Λ` and visible-normal sampling (GGX: Heitz 2018,
//! "Sampling the GGX distribution of visible normals"; Beckmann: Heitz & d'Eon 2014,
//! "Importance sampling microfacet-based BSDFs using the distribution of visible normals").
//!
//! With `s² = (m_x/αx)² + (m_y/αy)²` for a unit normal `m`:
//! GGX `D = 1/(π αx αy (s² + m_z²)²)`, `Λ(ω) = (√(1 + a⁻²) − 1)/2`; Beckmann
//! `D = e^{−s²/m_z²}/(π αx αy m_z⁴)`, `Λ(ω) = (e^{−a²}/(a√π) − erfc a)/2`, where
//! `a = ω_z/√((αx ω_x)² + (αy ω_y)²)`. The visible normals of `ωo` have density (w.r.t. solid
//! angle of `m`) `D_ωo(m) = G1(ωo)·max(0, ωo·m)·D(m)/ωo_z`, `G1 = 1/(1+Λ)`.

use std::f64::consts::{PI, TAU};

use brdf::Vec3;
use brdf::models::NormalDistribution;
use statrs::function::erf::{erf_inv, erfc};

/// A microfacet distribution with its roughness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Distribution {
    pub(crate) kind: NormalDistribution,
    pub(crate) alpha_x: f64,
    pub(crate) alpha_y: f64,
}

/// `1/√π`.
const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;

impl Distribution {
    /// `D(m)` per unit solid angle of `m` (`∫ D m_z dσ = 1`), 0 for `m_z ≤ 0`.
    pub(crate) fn d(&self, m: &Vec3) -> f64 {
        if !(m.z > 0.0) {
            return 0.0;
        }
        let s2 = (m.x / self.alpha_x).powi(2) + (m.y / self.alpha_y).powi(2);
        let z2 = m.z * m.z;
        let scale = 1.0 / (PI * self.alpha_x * self.alpha_y);
        match self.kind {
            NormalDistribution::Ggx => scale / (s2 + z2).powi(2),
            NormalDistribution::Beckmann => scale * (-s2 / z2).exp() / (z2 * z2),
        }
    }

    /// Smith `Λ(ω)` for `ω_z > 0`.
    pub(crate) fn lambda(&self, w: &Vec3) -> f64 {
        let t2 = ((self.alpha_x * w.x).powi(2) + (self.alpha_y * w.y).powi(2)) / (w.z * w.z);
        if !(t2 > 0.0) {
            return 0.0;
        }
        match self.kind {
            NormalDistribution::Ggx => 0.5 * ((1.0 + t2).sqrt() - 1.0),
            NormalDistribution::Beckmann => {
                let a = 1.0 / t2.sqrt();
                0.5 * ((-a * a).exp() * FRAC_1_SQRT_PI / a - erfc(a))
            }
        }
    }

    /// Density of `ωi = reflect(ωo, m)` for `m` drawn from the visible normals of `ωo`
    /// (w.r.t. solid angle of `ωi`): `G1(ωo)·D(m)/(4 ωo_z)`, `m = (ωo+ωi)/|ωo+ωi|`.
    pub(crate) fn reflected_pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let h = wo + wi;
        let len = h.norm();
        if !(wo.z > 0.0) || !(len > 0.0) {
            return 0.0;
        }
        let m = h / len;
        self.d(&m) / ((1.0 + self.lambda(wo)) * 4.0 * wo.z)
    }

    /// A visible normal of `wo` (`wo.z > 0`) for uniforms `u ∈ [0,1)²`.
    pub(crate) fn sample_visible(&self, wo: &Vec3, u: [f64; 2]) -> Vec3 {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        // Stretch to the configuration with unit roughness.
        let v = Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize();
        let m = match self.kind {
            NormalDistribution::Ggx => ggx_visible_unit(&v, u),
            NormalDistribution::Beckmann => {
                let (cos_t, sin_t) = (v.z, (v.x * v.x + v.y * v.y).sqrt());
                let (x, y) = beckmann_visible_slopes(cos_t, sin_t, u);
                let (cos_p, sin_p) = if sin_t > 0.0 {
                    (v.x / sin_t, v.y / sin_t)
                } else {
                    (1.0, 0.0)
                };
                // Rotate by φ; the normal with slopes (x, y) is (−x, −y, 1).
                let (sx, sy) = (cos_p * x - sin_p * y, sin_p * x + cos_p * y);
                Vec3::new(-sx, -sy, 1.0)
            }
        };
        // Unstretch the normal (a normal transforms with the inverse transpose).
        Vec3::new(ax * m.x, ay * m.y, m.z.max(0.0)).normalize()
    }
}

/// A visible normal of the unit-roughness GGX (a uniform point of the hemisphere's projected
/// disc as seen from `v`, lifted back onto the hemisphere).
fn ggx_visible_unit(v: &Vec3, u: [f64; 2]) -> Vec3 {
    let len2 = v.x * v.x + v.y * v.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-v.y, v.x, 0.0) / len2.sqrt()
    } else {
        Vec3::new(1.0, 0.0, 0.0)
    };
    let t2 = v.cross(&t1);
    let r = u[0].sqrt();
    let phi = TAU * u[1];
    let p1 = r * phi.cos();
    let p2 = r * phi.sin();
    // Warp the disc so that its lower half shrinks with the part of the hemisphere hidden at v.
    let s = 0.5 * (1.0 + v.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let pz = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    t1 * p1 + t2 * p2 + v * pz
}

/// Slopes `(x, y)` of a visible normal of the unit-roughness Beckmann distribution seen from
/// polar angle θ (`x` along the view azimuth). `x` has density `∝ (1 − x tanθ)e^{−x²}` on
/// `x < cot θ`, with CDF numerator `C(x) = erfc(−x)/2 + tanθ e^{−x²}/(2√π)`, inverted by
/// bracketed Newton iteration to rounding; `y` is the standard `e^{−y²}/√π`.
fn beckmann_visible_slopes(cos_t: f64, sin_t: f64, u: [f64; 2]) -> (f64, f64) {
    if !(sin_t > 1e-12) {
        // Normal incidence: the slopes are the isotropic Gaussian e^{−x²−y²}/π (polar form).
        let rho = (-(1.0 - u[0]).ln()).sqrt();
        let phi = TAU * u[1];
        return (rho * phi.cos(), rho * phi.sin());
    }
    let y = erf_inv((2.0 * u[1] - 1.0).clamp(-1.0 + f64::EPSILON, 1.0 - f64::EPSILON));
    let tan_t = sin_t / cos_t;
    let cot_t = cos_t / sin_t;
    let numerator = |x: f64| 0.5 * erfc(-x) + 0.5 * tan_t * (-x * x).exp() * FRAC_1_SQRT_PI;
    // Below −9 the CDF is < e^{−81}: no double uniform lands there.
    let (mut lo, mut hi) = (-9.0, cot_t.min(9.0));
    let total = numerator(hi);
    let target = u[0] * total;
    let mut x = 0.5 * (lo + hi);
    for _ in 0..200 {
        let f = numerator(x) - target;
        if f == 0.0 {
            break;
        }
        if f > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let df = (1.0 - x * tan_t) * (-x * x).exp() * FRAC_1_SQRT_PI;
        let newton = x - f / df;
        let next = if df > 0.0 && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let step = (next - x).abs();
        x = next;
        if step <= 1e-15 * x.abs().max(1.0) {
            break;
        }
    }
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::direction_from_angles;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    fn dists() -> Vec<Distribution> {
        let mut v = Vec::new();
        for kind in [NormalDistribution::Ggx, NormalDistribution::Beckmann] {
            for (alpha_x, alpha_y) in [(0.2, 0.2), (0.5, 0.1), (1.5, 0.8)] {
                v.push(Distribution {
                    kind,
                    alpha_x,
                    alpha_y,
                });
            }
        }
        v
    }

    #[test]
    fn visible_normal_pdf_integrates_to_one_and_matches_the_samples() {
        // Midpoint quadrature over the sphere of ωi in (cos θ, φ): ∫ p = 1, and the moments
        // P(ωi above the horizon) and E[ωi_z] of the samples agree with ∫ p·1{z>0}, ∫ p·z.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        for d in dists() {
            for theta in [0.0, 40.0, 80.0] {
                let wo = direction_from_angles(theta, 25.0);
                let (nz, np) = (800, 800);
                let (mut total, mut above, mut mean_z) = (0.0, 0.0, 0.0);
                for i in 0..nz {
                    let z = -1.0 + 2.0 * (i as f64 + 0.5) / nz as f64;
                    let r = (1.0 - z * z).sqrt();
                    for j in 0..np {
                        let phi = TAU * (j as f64 + 0.5) / np as f64;
                        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                        let p = d.reflected_pdf(&wo, &wi);
                        total += p;
                        above += if z > 0.0 { p } else { 0.0 };
                        mean_z += p * z;
                    }
                }
                let cell = 2.0 * TAU / (nz * np) as f64;
                let (total, above, mean_z) = (total * cell, above * cell, mean_z * cell);
                assert!((total - 1.0).abs() < 5e-3, "{d:?} θ={theta}: {total}");
                let n = 100_000;
                let (mut frac, mut z_sum) = (0.0, 0.0);
                for _ in 0..n {
                    let m = d.sample_visible(&wo, [rng.random(), rng.random()]);
                    assert!(wo.dot(&m) >= -1e-12 && m.z >= 0.0, "{d:?}");
                    let wi = m * (2.0 * wo.dot(&m)) - wo;
                    frac += f64::from(u8::from(wi.z > 0.0));
                    z_sum += wi.z;
                }
                let (frac, z_mean) = (frac / n as f64, z_sum / n as f64);
                // Binomial / bounded-variable 5σ bounds plus the quadrature's error.
                let se = (above * (1.0 - above) / n as f64).sqrt();
                assert!(
                    (frac - above).abs() < 5.0 * se + 5e-3,
                    "{d:?} θ={theta}: {frac} vs {above}"
                );
                assert!(
                    (z_mean - mean_z).abs() < 5.0 / (n as f64).sqrt() + 5e-3,
                    "{d:?} θ={theta}: {z_mean} vs {mean_z}"
                );
            }
        }
    }
}
