//! The normalised cosine lobe on the sphere and its mass above the horizon.
//!
//! Lobe around a unit axis `r` with exponent `n ≥ 0`, w.r.t. solid angle on S²:
//! `L_n(ω) = (n+1)/(2π) · max(0, r·ω)^n` (`∫_{S²} L_n dσ = 1`). Warp: `cos α = (1−u₁)^{1/(n+1)}`,
//! `φ = 2πu₂` in a frame whose z-axis is `r`.
//!
//! Its mass above the horizon, `A(θr, n) = ∫_Ω L_n dσ` for an axis at polar angle `θr < 90°`,
//! in lobe coordinates `(α, φ)` about `r` with `φ = 0` towards the normal: a direction is above
//! the horizon iff `cos α cos θr + sin α sin θr cos φ > 0`. For `α ≤ α* = 90° − θr` every `φ`
//! is; for `α > α*` the fraction of `φ` below the horizon is
//! `B(α) = (2/π)·asin(√(sin β / (2 sin α sin θr)))`, `β = α − α*` (closed form of the
//! azimuthal fraction). So `A = 1 − ∫_{α*}^{π/2} (n+1) cos^n α sin α · B(α) dα`, and
//! `A ≥ 1/2` (`B ≤ 1/2`). The substitution `β = θr t²` removes the square-root endpoint
//! behaviour of `B`; the integral over `t ∈ [0, 1]` uses Gauss–Legendre panels doubling in
//! width from the smaller of the lobe's decay length in `t`, `1/√((n+1) θr cot θr)`, and the
//! width `√(cos θr/θr)` over which `B` rises near grazing axes.

use std::f64::consts::{FRAC_1_PI, PI, TAU};
use std::sync::OnceLock;

use brdf::Vec3;
use brdf::quadrature::GaussLegendre;

/// Nodes per panel of the mass quadrature (the declared error compares with twice as many).
pub(crate) const MASS_NODES: usize = 16;

/// `(n+1)/(2π) · max(0, c)^n` for `c = r·ω` (0 for `c ≤ 0`, also when `n = 0`).
#[inline]
pub fn lobe_density(n: f64, c: f64) -> f64 {
    if c > 0.0 {
        (n + 1.0) / TAU * c.powf(n)
    } else {
        0.0
    }
}

/// Orthonormal tangents `(t, b)` of a unit vector `z` (Duff et al. 2017, branchless).
pub(crate) fn tangents(z: &Vec3) -> (Vec3, Vec3) {
    let sign = 1.0_f64.copysign(z.z);
    let a = -1.0 / (sign + z.z);
    let b = z.x * z.y * a;
    (
        Vec3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x),
        Vec3::new(b, sign + z.y * z.y * a, -z.y),
    )
}

/// Direction of the lobe about `axis` (unit) with exponent `n` for uniforms `u ∈ [0,1)²`.
pub fn sample_lobe(axis: &Vec3, n: f64, u: [f64; 2]) -> Vec3 {
    // ln cos α = ln(1 − u₁)/(n+1); 1 − cos α = −expm1(·) without cancellation.
    let ln_c = (1.0 - u[0]).ln() / (n + 1.0);
    let c = ln_c.exp();
    let one_minus_c = -ln_c.exp_m1();
    let s = (one_minus_c * (2.0 - one_minus_c)).max(0.0).sqrt();
    let phi = TAU * u[1];
    let (t, b) = tangents(axis);
    (t * (s * phi.cos()) + b * (s * phi.sin()) + axis * c).normalize()
}

fn rule(nodes: usize) -> &'static GaussLegendre {
    static R16: OnceLock<GaussLegendre> = OnceLock::new();
    static R32: OnceLock<GaussLegendre> = OnceLock::new();
    if nodes <= MASS_NODES {
        R16.get_or_init(|| GaussLegendre::new(MASS_NODES))
    } else {
        R32.get_or_init(|| GaussLegendre::new(2 * MASS_NODES))
    }
}

/// Mass of the lobe above the horizon, `A(θr, n) ∈ [1/2, 1]`, for an axis at polar angle
/// `theta_r ∈ [0, π/2]` (radians), with `nodes` Gauss–Legendre nodes per panel
/// ([`MASS_NODES`] or twice that).
pub fn above_horizon_mass(theta_r: f64, n: f64, nodes: usize) -> f64 {
    if !(theta_r > 0.0) {
        return 1.0;
    }
    let theta = theta_r.min(PI / 2.0);
    let sin_t = theta.sin();
    // Decay length of cos^n α in t (cos α = sin(θ(1 − t²)) ≈ sin θ · e^{−θ cot θ t²}).
    let cos_t = theta.cos();
    let decay = (n + 1.0) * theta * cos_t / sin_t;
    let t_l = if decay > 1.0 {
        decay.sqrt().recip()
    } else {
        1.0
    };
    // Near θr = 90° the azimuthal fraction turns from 0 to ~1/2 over t² ~ cos θr / θr.
    let t_c = (cos_t / theta).sqrt().max(1e-6);
    let integrand = |t: f64| {
        let t2 = t * t;
        let alpha_c = theta * (1.0 - t2); // 90° − α
        let cos_a = alpha_c.sin();
        let sin_a = alpha_c.cos();
        let x = ((theta * t2).sin() / (2.0 * sin_a * sin_t)).clamp(0.0, 1.0);
        let b = 2.0 * FRAC_1_PI * x.sqrt().asin();
        let lobe = if n == 0.0 { 1.0 } else { cos_a.powf(n) };
        (n + 1.0) * lobe * sin_a * b * 2.0 * theta * t
    };
    let gl = rule(nodes);
    let mut sum = 0.0;
    let (mut a, mut b) = (0.0, t_l.min(t_c).min(1.0));
    loop {
        sum += gl.integrate(a, b, integrand);
        // Beyond 8 decay lengths cos^n α < e^{−64} of its value at α*.
        if b >= 1.0 || b >= 8.0 * t_l {
            break;
        }
        a = b;
        b = (2.0 * b).min(1.0);
    }
    (1.0 - sum).clamp(0.5, 1.0)
}

/// Cosine-weighted hemisphere density `max(0, ω.z)/π`.
#[inline]
pub(crate) fn cosine_density(w: &Vec3) -> f64 {
    if w.z > 0.0 { w.z * FRAC_1_PI } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn tangents_are_orthonormal() {
        for z in [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.3, -0.4, 0.5).normalize(),
            Vec3::new(-1.0, 0.0, 1e-9).normalize(),
        ] {
            let (t, b) = tangents(&z);
            assert!((t.norm() - 1.0).abs() < 1e-12 && (b.norm() - 1.0).abs() < 1e-12);
            assert!(t.dot(&b).abs() < 1e-12 && t.dot(&z).abs() < 1e-12 && b.dot(&z).abs() < 1e-12);
        }
    }

    #[test]
    fn mass_matches_a_monte_carlo_count_of_lobe_samples_above_the_horizon() {
        // The fraction of lobe samples above the horizon estimates A; 4σ with 4·10⁵ samples.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        for (theta_deg, n) in [
            (30.0, 0.0),
            (60.0, 5.0),
            (85.0, 50.0),
            (89.0, 1e3),
            (45.0, 1.5),
        ] {
            let theta = f64::to_radians(theta_deg);
            let axis = Vec3::new(-theta.sin(), 0.0, theta.cos());
            let draws = 400_000;
            let above = (0..draws)
                .filter(|_| sample_lobe(&axis, n, [rng.random(), rng.random()]).z > 0.0)
                .count() as f64
                / draws as f64;
            let a = above_horizon_mass(theta, n, MASS_NODES);
            let sigma = (a * (1.0 - a) / draws as f64).sqrt().max(1e-6);
            assert!(
                (above - a).abs() < 4.0 * sigma,
                "{theta_deg} {n}: {above} vs {a}"
            );
        }
    }

    #[test]
    fn mass_has_its_closed_forms_and_converges() {
        // n = 0 is the uniform hemisphere about r: the part above the horizon is 1 − θr/π.
        for theta_deg in [10.0, 45.0, 80.0, 89.9] {
            let t = f64::to_radians(theta_deg);
            let a = above_horizon_mass(t, 0.0, MASS_NODES);
            assert!((a - (1.0 - t / PI)).abs() < 1e-12, "{theta_deg}: {a}");
        }
        // Other exponents: against a brute-force count on a (u, φ) midpoint grid.
        for (theta_deg, n) in [(20.0, 1.0), (70.0, 7.0), (88.0, 300.0), (89.5, 5e4)] {
            let t = f64::to_radians(theta_deg);
            let axis = Vec3::new(-t.sin(), 0.0, t.cos());
            let (na, np) = (4000, 2000);
            let mut brute = 0.0;
            let (tn, bn) = tangents(&axis);
            // Integrate in u = 1 − cos^{n+1} α (the lobe's CDF variable): mass = ∫ du dφ/2π.
            for i in 0..na {
                let u = (i as f64 + 0.5) / na as f64;
                let c = (1.0 - u).powf(1.0 / (n + 1.0));
                let s = (1.0 - c * c).max(0.0).sqrt();
                let mut above = 0;
                for j in 0..np {
                    let phi = TAU * (j as f64 + 0.5) / np as f64;
                    let w = tn * (s * phi.cos()) + bn * (s * phi.sin()) + axis * c;
                    above += usize::from(w.z > 0.0);
                }
                brute += above as f64 / np as f64;
            }
            brute /= na as f64;
            let a16 = above_horizon_mass(t, n, MASS_NODES);
            let a32 = above_horizon_mass(t, n, 2 * MASS_NODES);
            assert!(
                (a16 - brute).abs() < 2e-4,
                "{theta_deg} {n}: {a16} vs {brute}"
            );
            assert!((a16 - a32).abs() < 1e-9, "{theta_deg} {n}: {a16} vs {a32}");
        }
    }
}
