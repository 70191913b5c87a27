//! Spherical Gaussians (Gaussian SRBFs) and the von Mises–Fisher distribution on S².
//!
//! A Gaussian SRBF with centre `ξ ∈ S²` and bandwidth `λ > 0` is
//! `G(η; ξ, λ) = e^{λ(η·ξ − 1)}` (always evaluated in this form: `e^{λ η·ξ}` overflows for large
//! `λ`). Its integral over the sphere (solid angle) is `2π(1 − e^{−2λ})/λ`, and normalised it is
//! exactly the vMF density with concentration `κ = λ`:
//! `p(η) = κ e^{κ(η·ξ − 1)} / (2π(1 − e^{−2κ}))` w.r.t. solid angle on the whole sphere.
//! Sampling follows Jakob 2012 (baselines.md §D): `s = 1 − W = −log1p((1 − u)·expm1(−2κ))/κ`,
//! `sin θ = √(s(2 − s))`, which is exact and overflow-free for `κ` up to 10⁵ and beyond.

use std::f64::consts::{PI, TAU};

use brdf::Vec3;

/// `λ` below which the closed forms switch to their `λ → 0` limits.
const TINY_LAMBDA: f64 = 1e-8;

/// One Gaussian SRBF lobe `c · e^{λ(η·ξ − 1)}` with `c ≥ 0`, unit `ξ`, `λ ≥ 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SgLobe {
    /// Unit centre `ξ`.
    pub axis: Vec3,
    /// Bandwidth `λ` (the vMF concentration `κ` of the normalised lobe).
    pub lambda: f64,
    /// Amplitude `c` (the lobe's value at its centre).
    pub amplitude: f64,
}

impl SgLobe {
    /// Value `c · e^{λ(η·ξ − 1)}` at the unit direction `eta`.
    #[inline]
    pub fn eval(&self, eta: &Vec3) -> f64 {
        self.amplitude * sg(eta.dot(&self.axis), self.lambda)
    }

    /// Integral over the whole sphere w.r.t. solid angle: `c · 2π(1 − e^{−2λ})/λ`.
    #[inline]
    pub fn integral(&self) -> f64 {
        self.amplitude * sg_integral(self.lambda)
    }

    /// The product of two lobes, itself a lobe (closed form, baselines.md §C.3):
    /// `p = λ₁ξ₁ + λ₂ξ₂`, `λ_m = ‖p‖`, `ξ_m = p/λ_m`, `c_m = c₁c₂ e^{λ_m − λ₁ − λ₂}` (the
    /// exponent is combined before `exp`, so nothing overflows).
    pub fn product(&self, other: &SgLobe) -> SgLobe {
        let p = self.axis * self.lambda + other.axis * other.lambda;
        let lambda = p.norm();
        let axis = if lambda > 0.0 {
            p / lambda
        } else {
            Vec3::new(0.0, 0.0, 1.0)
        };
        SgLobe {
            axis,
            lambda,
            amplitude: self.amplitude
                * other.amplitude
                * (lambda - self.lambda - other.lambda).min(0.0).exp(),
        }
    }
}

/// `e^{λ(cos − 1)}`, the unit-amplitude SRBF at `cos = η·ξ`.
#[inline]
pub fn sg(cos: f64, lambda: f64) -> f64 {
    (lambda * (cos.min(1.0) - 1.0)).exp()
}

/// `∫_{S²} e^{λ(η·ξ − 1)} dη = 2π(1 − e^{−2λ})/λ`, computed as `2π·(−expm1(−2λ))/λ`
/// (limit 4π at `λ = 0`).
#[inline]
pub fn sg_integral(lambda: f64) -> f64 {
    if lambda < TINY_LAMBDA {
        4.0 * PI * (1.0 - lambda)
    } else {
        TAU * (-(-2.0 * lambda).exp_m1()) / lambda
    }
}

/// The vMF density on S² w.r.t. solid angle at `cos = μ·ω`:
/// `κ e^{κ(cos − 1)} / (2π(1 − e^{−2κ}))`, and `1/(4π)` for `κ = 0`.
#[inline]
pub fn vmf_pdf(cos: f64, kappa: f64) -> f64 {
    sg(cos, kappa) / sg_integral(kappa)
}

/// `W = μ·ω` of a vMF sample from `u ∈ [0,1)`, returned as `(W, 1 − W)` with `1 − W` computed
/// directly (`−log1p((1 − u)·expm1(−2κ))/κ`), clamped to `[0, 2]`.
#[inline]
pub fn vmf_sample_cos(u: f64, kappa: f64) -> (f64, f64) {
    let s = if kappa < TINY_LAMBDA {
        2.0 * u // uniform sphere: W uniform on [−1, 1]
    } else {
        -((1.0 - u) * (-2.0 * kappa).exp_m1()).ln_1p() / kappa
    };
    let s = s.clamp(0.0, 2.0);
    (1.0 - s, s)
}

/// A vMF direction with mean `mu` (unit) and concentration `kappa` from `u ∈ [0,1)²`
/// (`u[0]` → azimuth, `u[1]` → `W`), rotated into the frame whose z-axis is `mu`.
pub fn vmf_sample(mu: &Vec3, kappa: f64, u: [f64; 2]) -> Vec3 {
    let (w, s) = vmf_sample_cos(u[1], kappa);
    let sin_t = (s * (2.0 - s)).max(0.0).sqrt();
    let (sp, cp) = (TAU * u[0]).sin_cos();
    let (t, b) = orthonormal_basis(mu);
    (t * (sin_t * cp) + b * (sin_t * sp) + mu * w).normalize()
}

/// A right-handed orthonormal basis `(t, b)` completing the unit `n` (`t × b = n`), branchless
/// construction of Duff et al. 2017.
pub fn orthonormal_basis(n: &Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn sg_integral_matches_quadrature() {
        // Midpoint rule in cos θ (the lobe around +z depends on cos θ only).
        for lambda in [0.1, 1.0, 10.0, 100.0, 300.0] {
            let n = 400_000;
            let q: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                    sg(c, lambda) * TAU * 2.0 / n as f64
                })
                .sum();
            assert_relative_eq!(sg_integral(lambda), q, max_relative = 1e-6);
        }
        assert_relative_eq!(sg_integral(0.0), 4.0 * PI);
    }

    #[test]
    fn sg_product_identity_holds_pointwise() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let dir = |rng: &mut Xoshiro256PlusPlus| vmf_sample(&Vec3::z(), 0.0, rng.random());
        for _ in 0..200 {
            let a = SgLobe {
                axis: dir(&mut rng),
                lambda: 50.0 * rng.random::<f64>(),
                amplitude: 3.0 * rng.random::<f64>(),
            };
            let b = SgLobe {
                axis: dir(&mut rng),
                lambda: 500.0 * rng.random::<f64>(),
                amplitude: 0.5,
            };
            let m = a.product(&b);
            let eta = dir(&mut rng);
            let lhs = a.eval(&eta) * b.eval(&eta);
            assert!((lhs - m.eval(&eta)).abs() <= 1e-12 * lhs.max(1e-300) + 1e-300);
        }
        // Large bandwidths: no overflow.
        let a = SgLobe {
            axis: Vec3::z(),
            lambda: 2e4,
            amplitude: 1.0,
        };
        let m = a.product(&a);
        assert_relative_eq!(m.lambda, 4e4);
        assert_relative_eq!(m.amplitude, 1.0);
    }

    #[test]
    fn vmf_mean_cosine_and_inverse_pdf() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let mu = Vec3::new(0.3, -0.5, 0.8).normalize();
        for kappa in [0.01, 1.0, 10.0, 100.0, 5000.0] {
            let n = 200_000;
            let (mut sum_c, mut sum_c2, mut inv_pdf, mut inv_pdf2) = (0.0, 0.0, 0.0, 0.0);
            for _ in 0..n {
                let w = vmf_sample(&mu, kappa, rng.random());
                assert!((w.norm() - 1.0).abs() < 1e-12);
                let c = mu.dot(&w);
                sum_c += c;
                sum_c2 += c * c;
                let ip = 1.0 / vmf_pdf(c, kappa);
                inv_pdf += ip;
                inv_pdf2 += ip * ip;
            }
            let nf = n as f64;
            let expected = if kappa < 1e-3 {
                // coth κ − 1/κ ≈ κ/3 for small κ (cancellation otherwise).
                kappa / 3.0
            } else {
                1.0 / kappa.tanh() - 1.0 / kappa
            };
            let mean_c = sum_c / nf;
            let se_c = ((sum_c2 / nf - mean_c * mean_c).max(0.0) / nf).sqrt();
            assert!(
                (mean_c - expected).abs() < 5.0 * se_c + 1e-12,
                "κ={kappa}: {mean_c} vs {expected} ± {se_c}"
            );
            // E[1/p] = 4π (the heavy tail of 1/p makes this a fair test only for small κ).
            if kappa <= 1.0 {
                let m = inv_pdf / nf;
                let se = ((inv_pdf2 / nf - m * m) / nf).sqrt();
                assert!(
                    (m - 4.0 * PI).abs() < 5.0 * se + 1e-9,
                    "κ={kappa}: E[1/p]={m} ± {se}"
                );
            }
            // ∫ p dω = 1 by quadrature in cos θ (graded towards cos = 1 for large κ).
            let q = 200_000;
            let total: f64 = (0..q)
                .map(|i| {
                    let t = (i as f64 + 0.5) / q as f64;
                    // cos = 1 − 2t², dc = 4t dt.
                    vmf_pdf(1.0 - 2.0 * t * t, kappa) * TAU * 4.0 * t / q as f64
                })
                .sum();
            assert!((total - 1.0).abs() < 1e-6, "κ={kappa}: ∫p = {total}");
        }
    }

    #[test]
    fn vmf_cos_cdf_matches_closed_form() {
        // The CDF of W at a few points: F(w) = (e^{κ(w−1)} − e^{−2κ})/(1 − e^{−2κ}).
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(6);
        for kappa in [0.5, 20.0, 2000.0] {
            let n = 100_000;
            let ws: Vec<f64> = (0..n)
                .map(|_| vmf_sample_cos(rng.random(), kappa).0)
                .collect();
            for q in [0.1, 0.5, 0.9] {
                // The w with F(w) = q.
                let w = 1.0 + (q + (1.0 - q) * (-2.0 * kappa).exp()).ln() / kappa;
                let frac = ws.iter().filter(|&&x| x <= w).count() as f64 / n as f64;
                assert!(
                    (frac - q).abs() < 5.0 * (q * (1.0 - q) / n as f64).sqrt(),
                    "κ={kappa} q={q} got {frac}"
                );
            }
        }
    }

    #[test]
    fn basis_is_orthonormal() {
        for n in [
            Vec3::z(),
            -Vec3::z(),
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(1.0, 0.0, -1e-12).normalize(),
        ] {
            let (t, b) = orthonormal_basis(&n);
            assert!((t.norm() - 1.0).abs() < 1e-12 && (b.norm() - 1.0).abs() < 1e-12);
            assert!(t.dot(&b).abs() < 1e-12 && t.dot(&n).abs() < 1e-12 && b.dot(&n).abs() < 1e-12);
            assert!((t.cross(&b) - n).norm() < 1e-12);
        }
    }
}
