//! Deterministic quadrature over the hemisphere (used for albedo checks and by the coupled model).

use crate::brdf::Brdf;
use crate::geometry::Vec3;
use std::f64::consts::{FRAC_PI_2, PI};

/// A piece of an adaptive quadrature that knows its error estimate (the order in which
/// [`WorstFirst`] ranks pieces).
pub trait ErrorEstimate {
    /// The piece's error estimate (larger is worse; compared with [`f64::total_cmp`]).
    fn error_estimate(&self) -> f64;
}

/// A piece of an adaptive quadrature ordered by its [`ErrorEstimate`] alone, so that a
/// [`BinaryHeap`](std::collections::BinaryHeap) of them pops the piece with the largest error
/// first (the work list of every adaptive rule in the workspace). Dereferences to the piece.
#[derive(Debug, Clone)]
pub struct WorstFirst<T>(pub T);

impl<T: ErrorEstimate> PartialEq for WorstFirst<T> {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other).is_eq()
    }
}

impl<T: ErrorEstimate> Eq for WorstFirst<T> {}

impl<T: ErrorEstimate> PartialOrd for WorstFirst<T> {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl<T: ErrorEstimate> Ord for WorstFirst<T> {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.error_estimate().total_cmp(&other.0.error_estimate())
    }
}

impl<T> std::ops::Deref for WorstFirst<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.0
    }
}

/// Gauss–Legendre rule with `n` nodes on `[-1, 1]` (exact for polynomials of degree `2n − 1`).
#[derive(Debug, Clone)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// Build the `n`-point rule (`n ≥ 1`) by Newton iteration on the Legendre polynomial `P_n`.
    pub fn new(n: usize) -> Self {
        let n = n.max(1);
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n.div_ceil(2) {
            let mut x = (PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // Recurrence for P_n(x) and P_{n-1}(x).
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let kf = k as f64;
                    let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
                    p0 = p1;
                    p1 = p2;
                }
                let pn = if n == 1 { x } else { p1 };
                let pn1 = if n == 1 { 1.0 } else { p0 };
                dp = nf * (x * pn - pn1) / (x * x - 1.0);
                let dx = pn / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        if n == 1 {
            nodes[0] = 0.0;
            weights[0] = 2.0;
        }
        Self { nodes, weights }
    }

    /// Nodes on `[-1, 1]`, ascending.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Weights (sum to 2).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// `∫_a^b g(x) dx` with this rule mapped to `[a, b]`.
    pub fn integrate(&self, a: f64, b: f64, mut g: impl FnMut(f64) -> f64) -> f64 {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        let mut s = 0.0;
        for (x, w) in self.nodes.iter().zip(&self.weights) {
            s += w * g(mid + half * x);
        }
        s * half
    }
}

/// Points of the Gauss–Legendre rule used inside each θ panel.
const PANEL_POINTS: usize = 8;

/// `∫_Ω g(ω) cosθ dσ(ω)` over the upper hemisphere (projected solid angle).
///
/// θ ∈ [0, π/2] is split into `theta_panels` equal panels, each with an 8-point Gauss–Legendre
/// rule; φ uses the `phi_points`-point trapezoid rule (spectrally accurate for periodic
/// integrands). Cost: `8 · theta_panels · phi_points` evaluations of `g`. Sharp lobes need the
/// node spacing (`π/(16·theta_panels)` in θ, `2π/phi_points` in φ) well below the lobe width.
pub fn projected_hemisphere_integral(
    theta_panels: usize,
    phi_points: usize,
    mut g: impl FnMut(&Vec3) -> f64,
) -> f64 {
    let gl = GaussLegendre::new(PANEL_POINTS);
    let panels = theta_panels.max(1);
    let nphi = phi_points.max(1);
    let dphi = 2.0 * PI / nphi as f64;
    let width = FRAC_PI_2 / panels as f64;
    let mut phis = Vec::with_capacity(nphi);
    for j in 0..nphi {
        phis.push(((j as f64 + 0.5) * dphi).sin_cos());
    }
    let mut total = 0.0;
    for p in 0..panels {
        let a = p as f64 * width;
        total += gl.integrate(a, a + width, |theta| {
            let (st, ct) = theta.sin_cos();
            let mut ring = 0.0;
            for &(sp, cp) in &phis {
                ring += g(&Vec3::new(st * cp, st * sp, ct));
            }
            ring * dphi * ct * st
        });
    }
    total
}

/// Directional albedo `ρ(ωo) = ∫_Ω f_r(ωo, ωi) cosθi dσ(ωi)` by
/// [`projected_hemisphere_integral`].
pub fn directional_albedo(
    brdf: &(impl Brdf + ?Sized),
    wo: &Vec3,
    theta_panels: usize,
    phi_points: usize,
) -> f64 {
    projected_hemisphere_integral(theta_panels, phi_points, |wi| brdf.eval(wo, wi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        for n in [1, 2, 3, 5, 8, 16] {
            let gl = GaussLegendre::new(n);
            assert_relative_eq!(gl.weights().iter().sum::<f64>(), 2.0, epsilon = 1e-13);
            let deg = 2 * n - 1;
            // ∫_0^1 x^deg dx = 1/(deg+1)
            let v = gl.integrate(0.0, 1.0, |x| x.powi(deg as i32));
            assert_relative_eq!(v, 1.0 / (deg as f64 + 1.0), epsilon = 1e-13);
        }
    }

    #[test]
    fn hemisphere_measures() {
        // ∫ cosθ dσ = π; ∫ cos²θ dσ = 2π/3.
        let a = projected_hemisphere_integral(4, 16, |_| 1.0);
        assert_relative_eq!(a, PI, epsilon = 1e-12);
        let b = projected_hemisphere_integral(4, 16, |w| w.z);
        assert_relative_eq!(b, 2.0 * PI / 3.0, epsilon = 1e-12);
        // A non-axisymmetric integrand: ∫ x² cosθ dσ = π/4.
        let c = projected_hemisphere_integral(8, 32, |w| w.x * w.x);
        assert_relative_eq!(c, PI / 4.0, epsilon = 1e-12);
    }
}
