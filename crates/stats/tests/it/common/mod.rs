//! Exact samplers of known densities, shared by the integration tests.
#![allow(dead_code)]

use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use std::f64::consts::{PI, TAU};

pub(crate) fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

pub(crate) fn uniform(rng: &mut Xoshiro256PlusPlus) -> f64 {
    rng.random::<f64>()
}

// ---------- product density on the rectangle [-1, 2] x [0.5, 1.5] ----------

pub(crate) const RECT_X: [f64; 2] = [-1.0, 2.0];
pub(crate) const RECT_Y: [f64; 2] = [0.5, 1.5];
const LAMBDA: f64 = 2.0;

/// Density of s = (x + 1)/3 on [0, 1]: λ e^{−λ s} / (1 − e^{−λ}).
fn f_s(s: f64) -> f64 {
    LAMBDA * (-LAMBDA * s).exp() / (1.0 - (-LAMBDA).exp())
}

/// Density of t = y − 0.5 on [0, 1]: (1 + 3t²)/2.
fn g_t(t: f64) -> f64 {
    0.5 * (1.0 + 3.0 * t * t)
}

/// Product density on the rectangle (w.r.t. area).
pub(crate) fn product_pdf(p: [f64; 2]) -> f64 {
    if !(p[0] >= RECT_X[0] && p[0] <= RECT_X[1] && p[1] >= RECT_Y[0] && p[1] <= RECT_Y[1]) {
        return 0.0;
    }
    f_s((p[0] + 1.0) / 3.0) / 3.0 * g_t(p[1] - 0.5)
}

/// CDF of the x marginal.
pub(crate) fn product_cdf_x(x: f64) -> f64 {
    let s = ((x + 1.0) / 3.0).clamp(0.0, 1.0);
    (1.0 - (-LAMBDA * s).exp()) / (1.0 - (-LAMBDA).exp())
}

/// CDF of the y marginal.
pub(crate) fn product_cdf_y(y: f64) -> f64 {
    let t = (y - 0.5).clamp(0.0, 1.0);
    0.5 * (t + t * t * t)
}

/// Exact sample by inversion of both marginals.
pub(crate) fn product_sample(rng: &mut Xoshiro256PlusPlus) -> [f64; 2] {
    let (u1, u2) = (uniform(rng), uniform(rng));
    let s = -(1.0 - u1 * (1.0 - (-LAMBDA).exp())).ln() / LAMBDA;
    // (t + t³)/2 = u2: Cardano, one real root.
    let q = u2;
    let r = (q * q + 1.0 / 27.0).sqrt();
    let t = (q + r).cbrt() + (q - r).cbrt();
    [-1.0 + 3.0 * s, 0.5 + t]
}

pub(crate) fn product_points(seed: u64, n: usize) -> Vec<[f64; 2]> {
    let mut r = rng(seed);
    (0..n).map(|_| product_sample(&mut r)).collect()
}

// ---------- unit disc ----------

pub(crate) fn uniform_disc_pdf(p: [f64; 2]) -> f64 {
    if p[0] * p[0] + p[1] * p[1] <= 1.0 {
        1.0 / PI
    } else {
        0.0
    }
}

pub(crate) fn disc_points(seed: u64, n: usize, radius_scale: f64) -> Vec<[f64; 2]> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| {
            let (u1, u2) = (uniform(&mut r), uniform(&mut r));
            let rad = u1.sqrt() * radius_scale;
            let phi = TAU * u2;
            [rad * phi.cos(), rad * phi.sin()]
        })
        .collect()
}

/// CDF of the x coordinate of the uniform disc: 1/2 + (x√(1−x²) + asin x)/π.
pub(crate) fn disc_cdf_x(x: f64) -> f64 {
    let x = x.clamp(-1.0, 1.0);
    0.5 + (x * (1.0 - x * x).sqrt() + x.asin()) / PI
}

// ---------- directions ----------

pub(crate) fn cosine_pdf(d: [f64; 3]) -> f64 {
    d[2].max(0.0) / PI
}

pub(crate) fn uniform_hemisphere_pdf(d: [f64; 3]) -> f64 {
    if d[2] >= 0.0 { 0.5 / PI } else { 0.0 }
}

pub(crate) fn cosine_points(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| {
            let (u1, u2) = (uniform(&mut r), uniform(&mut r));
            let (rad, phi) = (u1.sqrt(), TAU * u2);
            [rad * phi.cos(), rad * phi.sin(), (1.0 - u1).sqrt()]
        })
        .collect()
}

/// Cosine-weighted directions by inversion in (cos θ, φ): cos θ = √u (a different algorithm
/// from [`cosine_points`], same distribution).
pub(crate) fn cosine_points_inversion(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| {
            let (u1, u2) = (uniform(&mut r), uniform(&mut r));
            let c = u1.sqrt();
            let s = (1.0 - c * c).max(0.0).sqrt();
            let phi = TAU * u2;
            [s * phi.cos(), s * phi.sin(), c]
        })
        .collect()
}

pub(crate) fn uniform_hemisphere_points(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| {
            let (c, phi) = (uniform(&mut r), TAU * uniform(&mut r));
            let s = (1.0 - c * c).max(0.0).sqrt();
            [s * phi.cos(), s * phi.sin(), c]
        })
        .collect()
}

/// A Phong lobe on the sphere: pdf (e + 1)/(2π) max(0, a·ω)^e w.r.t. solid angle.
#[derive(Clone, Copy)]
pub(crate) struct Lobe {
    pub(crate) axis: [f64; 3],
    pub(crate) exponent: f64,
}

pub(crate) fn dir(theta: f64, phi: f64) -> [f64; 3] {
    [
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    ]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

impl Lobe {
    pub(crate) fn pdf(&self, d: [f64; 3]) -> f64 {
        let c = self.axis[0] * d[0] + self.axis[1] * d[1] + self.axis[2] * d[2];
        if c <= 0.0 {
            0.0
        } else {
            (self.exponent + 1.0) / TAU * c.powf(self.exponent)
        }
    }

    pub(crate) fn sample(&self, rng: &mut Xoshiro256PlusPlus) -> [f64; 3] {
        let (u1, u2) = (uniform(rng), uniform(rng));
        let c = u1.powf(1.0 / (self.exponent + 1.0));
        let s = (1.0 - c * c).max(0.0).sqrt();
        let b = TAU * u2;
        let a = self.axis;
        let helper = if a[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let t = normalize(cross(helper, a));
        let bt = cross(a, t);
        let (x, y) = (s * b.cos(), s * b.sin());
        [
            x * t[0] + y * bt[0] + c * a[0],
            x * t[1] + y * bt[1] + c * a[1],
            x * t[2] + y * bt[2] + c * a[2],
        ]
    }

    pub(crate) fn points(&self, seed: u64, n: usize) -> Vec<[f64; 3]> {
        let mut r = rng(seed);
        (0..n).map(|_| self.sample(&mut r)).collect()
    }
}

/// The lobe used across tests: axis at θ = 30°, φ = 40°, exponent 20.
pub(crate) fn test_lobe() -> Lobe {
    Lobe {
        axis: dir(30f64.to_radians(), 40f64.to_radians()),
        exponent: 20.0,
    }
}

/// The same lobe tilted by `degrees` away from the pole.
pub(crate) fn tilted_lobe(degrees: f64) -> Lobe {
    Lobe {
        axis: dir((30.0 + degrees).to_radians(), 40f64.to_radians()),
        exponent: 20.0,
    }
}

pub(crate) fn uniform_sphere_points(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| {
            let (c, phi) = (2.0 * uniform(&mut r) - 1.0, TAU * uniform(&mut r));
            let s = (1.0 - c * c).max(0.0).sqrt();
            [s * phi.cos(), s * phi.sin(), c]
        })
        .collect()
}
