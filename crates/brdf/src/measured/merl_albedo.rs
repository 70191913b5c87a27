//! The directional albedo `A(θo) = ∫ f_r(ωo, ωi) cos θi dσ(ωi)` of a MERL table integrated
//! over the table's own bins (issue 27): the nearest-bin lookup is piecewise constant, with
//! edges everywhere in `ωi`, so a quadrature in `ωi` converges slowly (a Gauss rule on 16 000
//! points is 10⁻³ off, a midpoint rule needs millions of cells for 10⁻⁴).
//!
//! # Math
//! Substitute the half vector `h = (ωi + ωo)/|ωi + ωo|` for `ωi`: `ωi = 2 (h·ωo) h − ωo`,
//! `dσ(ωi) = 4 (h·ωo) dσ(h)`, and with `h = (sin θh cos φ, sin θh sin φ, cos θh)`,
//! `ωo = (sin θo, 0, cos θo)`:
//! `A = ∫ dθh sin θh ∫ dφ 4 u (2 u cos θh − cos θo) f`, `u = h·ωo = P + Q cos φ`,
//! `P = cos θh cos θo`, `Q = sin θh sin θo`, over `ωi.z = 2 u cos θh − cos θo > 0`.
//! On a ring of constant `θh` (inside one θh bin of the table, whose edges are
//! `θh = (π/2)(i/90)²`) every other edge of the lookup is a root in `φ` with a closed form:
//! a θd edge `cos θd_j = u` is `cos φ = (cos θd_j − P)/Q`; a φd edge (the folded angle of the
//! difference vector `d = R_y(−θh) R_z(−φ) ωo`, `d_x = cos θh sin θo cos φ − sin θh cos θo`,
//! `d_y = −sin θo sin φ`, crossing the line at `φd_k = kπ/180`) is
//! `α cos φ + β sin φ = γ` with `α = −sin φd_k cos θh sin θo`, `β = −cos φd_k sin θo`,
//! `γ = −sin φd_k sin θh cos θo`; the horizon is `cos φ = (cos θo/(2 cos θh) − P)/Q`. Between
//! consecutive roots the bin, hence `f`, is constant (one lookup at the piece's middle), and
//! `∫ u dφ`, `∫ u² dφ` are closed forms: the ring integral is exact up to rounding. The ring
//! integral is continuous in `θh` (the roots move continuously, with square-root kinks where an
//! edge curve is tangent to a ring); the outer integral is a Gauss–Legendre rule in every θh
//! bin, and its error estimate the difference from a rule of lower order.

use std::f64::consts::{FRAC_PI_2, PI};

use crate::brdf::Brdf;
use crate::geometry::Vec3;
use crate::merl::{MerlBrdf, RES_PHI_D, RES_THETA_D, RES_THETA_H};
use crate::quadrature::{ErrorEstimate, GaussLegendre, WorstFirst};

/// [`MerlBrdf::albedo_in_bins`]: the integral, its error estimate and the lookups it cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MerlAlbedo {
    /// `A(θo)` (1, not 1/sr: the integral of `f_r cos θi` over the hemisphere).
    pub value: f64,
    /// `|A_order − A_lower|`: the difference from the rule of the lower order in θh (an upper
    /// estimate of the higher order's error).
    pub abs_err: f64,
    /// Table lookups spent (one per constant piece of a ring).
    pub evaluations: u64,
}

/// Outgoing polar angle (radians, 80°) above which the first pieces in θh are narrowed.
const GRAZING_FROM: f64 = 80.0 * PI / 180.0;
/// Narrowest first piece (radians, 0.05°).
const MIN_PIECE: f64 = 0.05 * PI / 180.0;

/// One piece `[a, b]` of the θh axis: its 2-point Gauss value and `|Gauss − midpoint|`.
struct Piece {
    a: f64,
    b: f64,
    value: f64,
    err: f64,
}

impl ErrorEstimate for Piece {
    fn error_estimate(&self) -> f64 {
        self.err
    }
}

/// `(cos, sin)` of the table's θd edges `jπ/180`, `j = 1 … 89`, and of its φd edges `kπ/180`,
/// `k = 0 … 179`.
struct Edges {
    theta_d: Vec<f64>,
    phi_d: Vec<(f64, f64)>,
}

impl Edges {
    fn new() -> Self {
        let step_d = FRAC_PI_2 / RES_THETA_D as f64;
        let step_p = PI / RES_PHI_D as f64;
        Self {
            theta_d: (1..RES_THETA_D)
                .map(|j| (j as f64 * step_d).cos())
                .collect(),
            phi_d: (0..RES_PHI_D)
                .map(|k| {
                    let (s, c) = (k as f64 * step_p).sin_cos();
                    (c, s)
                })
                .collect(),
        }
    }
}

impl MerlBrdf {
    /// The directional albedo at the outgoing polar angle `theta_o` (radians; the table is
    /// isotropic, `φo` does not matter) integrated over the table's bins (see the module docs):
    /// exact rings of constant `θh`; in `θh`, pieces cut at the table's θh edges and where the
    /// horizon starts to clip the rings (`θh = π/4 ± θo/2`), each integrated by the 2-point
    /// Gauss rule with the midpoint rule as its error estimate, and the piece of largest
    /// estimate halved while the summed estimate exceeds `rel_tol · A` and fewer than
    /// `max_evaluations` lookups were spent. 0 at or beyond `θo = 90°`.
    pub fn albedo_in_bins(&self, theta_o: f64, rel_tol: f64, max_evaluations: u64) -> MerlAlbedo {
        if !(theta_o.is_finite() && theta_o.abs() < FRAC_PI_2) {
            return MerlAlbedo {
                value: 0.0,
                abs_err: 0.0,
                evaluations: 0,
            };
        }
        let edges = Edges::new();
        let (so, co) = theta_o.abs().sin_cos();
        let wo = Vec3::new(so, 0.0, co);
        let mut evaluations = 0u64;
        let mut roots = Vec::with_capacity(2 * (RES_THETA_D + RES_PHI_D) + 2);
        let mut cuts: Vec<f64> = (0..=RES_THETA_H)
            .map(|k| {
                let x = k as f64 / RES_THETA_H as f64;
                FRAC_PI_2 * x * x
            })
            .collect();
        let half = 0.5 * theta_o.abs();
        cuts.extend([0.25 * PI - half, 0.25 * PI + half]);
        cuts.retain(|t| (0.0..=FRAC_PI_2).contains(t));
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        // Near grazing, every θh bin has layers at its ends a fraction of `90° − θo` wide
        // (bins whose centre configuration lies below the horizon: unmeasured, read as 0)
        // that the 2-point rule and the midpoint rule miss alike (at θo = 89° on the MERL
        // layout of `phong:n=50`: +4e-4 in each of 11 bins, all of one sign, with an estimate
        // of 1e-5): the pieces start at most (90° − θo)/4 wide there.
        let widest = if theta_o.abs() > GRAZING_FROM {
            (0.25 * (FRAC_PI_2 - theta_o.abs())).max(MIN_PIECE)
        } else {
            f64::INFINITY
        };
        let cuts: Vec<f64> = cuts
            .windows(2)
            .flat_map(|w| {
                let n = ((w[1] - w[0]) / widest).ceil().max(1.0) as usize;
                (0..n).map(move |k| w[0] + (w[1] - w[0]) * (k as f64 / n as f64))
            })
            .chain(std::iter::once(FRAC_PI_2))
            .collect();
        // The 2-point Gauss rule (`crate::quadrature`, the workspace's one home of Gauss–Legendre
        // nodes) and the midpoint rule on [a, b].
        let gauss = GaussLegendre::new(2);
        let mut piece = |a: f64, b: f64, evaluations: &mut u64| -> WorstFirst<Piece> {
            let mut ring = |t: f64| self.ring(&wo, t, &edges, &mut roots, evaluations);
            let value = gauss.integrate(a, b, &mut ring);
            let mid = (b - a) * ring(0.5 * (a + b));
            WorstFirst(Piece {
                a,
                b,
                value,
                err: (value - mid).abs(),
            })
        };
        let mut heap: std::collections::BinaryHeap<WorstFirst<Piece>> = cuts
            .windows(2)
            .filter(|w| w[1] > w[0])
            .map(|w| piece(w[0], w[1], &mut evaluations))
            .collect();
        let total = |heap: &std::collections::BinaryHeap<WorstFirst<Piece>>| {
            heap.iter()
                .fold((0.0, 0.0), |(v, e), p| (v + p.value, e + p.err))
        };
        let (mut value, mut err) = total(&heap);
        while err > rel_tol * value.abs() && evaluations < max_evaluations {
            let Some(worst) = heap.pop() else { break };
            let m = 0.5 * (worst.a + worst.b);
            if !(m > worst.a && m < worst.b) {
                heap.push(worst);
                break;
            }
            heap.push(piece(worst.a, m, &mut evaluations));
            heap.push(piece(m, worst.b, &mut evaluations));
            // Re-summed (a few hundred pieces): no drift from running updates.
            (value, err) = total(&heap);
        }
        MerlAlbedo {
            value,
            abs_err: err,
            evaluations,
        }
    }

    /// `sin θh ∫ dφ 4 u (2 u cos θh − cos θo) f` over the ring `θh` (see the module docs).
    fn ring(
        &self,
        wo: &Vec3,
        theta_h: f64,
        edges: &Edges,
        roots: &mut Vec<f64>,
        evaluations: &mut u64,
    ) -> f64 {
        let (sh, ch) = theta_h.sin_cos();
        let (so, co) = (wo.x, wo.z);
        if !(ch > 0.0) {
            return 0.0;
        }
        let (p, q) = (ch * co, sh * so);
        // The visible range |φ| < φm: ωi above the horizon, u > cos θo / (2 cos θh).
        let need = 0.5 * co / ch;
        let phi_max = if q > 0.0 {
            let c = (need - p) / q;
            if c >= 1.0 {
                return 0.0;
            }
            if c <= -1.0 { PI } else { c.acos() }
        } else if p > need {
            PI
        } else {
            return 0.0;
        };
        roots.clear();
        roots.push(-phi_max);
        roots.push(phi_max);
        let inside = |phi: f64| phi > -phi_max && phi < phi_max;
        let push_pm = |roots: &mut Vec<f64>, phi: f64| {
            for r in [phi, -phi] {
                if inside(r) {
                    roots.push(r);
                }
            }
        };
        if q > 0.0 {
            for &cd in &edges.theta_d {
                let c = (cd - p) / q;
                if c > -1.0 && c < 1.0 {
                    push_pm(roots, c.acos());
                }
            }
        }
        for &(cp, sp) in &edges.phi_d {
            let (alpha, beta, gamma) = (-sp * ch * so, -cp * so, -sp * sh * co);
            let r = alpha.hypot(beta);
            if r > 0.0 && gamma.abs() < r {
                let (phi0, spread) = (beta.atan2(alpha), (gamma / r).acos());
                for mut phi in [phi0 + spread, phi0 - spread] {
                    if phi > PI {
                        phi -= 2.0 * PI;
                    } else if phi <= -PI {
                        phi += 2.0 * PI;
                    }
                    if inside(phi) {
                        roots.push(phi);
                    }
                }
            }
        }
        roots.sort_by(f64::total_cmp);
        // ∫ u = P Δ + Q Δsin, ∫ u² = P² Δ + 2PQ Δsin + Q² (Δ/2 + Δsin2/4).
        let mut sum = 0.0;
        for w in roots.windows(2) {
            let (a, b) = (w[0], w[1]);
            if !(b > a) {
                continue;
            }
            let m = 0.5 * (a + b);
            let (sm, cm) = m.sin_cos();
            let h = Vec3::new(sh * cm, sh * sm, ch);
            let u = p + q * cm;
            let wi = 2.0 * u * h - wo;
            if !(wi.z > 0.0) {
                continue;
            }
            *evaluations += 1;
            let f = self.eval(wo, &wi);
            if f == 0.0 {
                continue;
            }
            let d = b - a;
            let ds = b.sin() - a.sin();
            let ds2 = (2.0 * b).sin() - (2.0 * a).sin();
            let iu = p * d + q * ds;
            let iu2 = p * p * d + 2.0 * p * q * ds + q * q * (0.5 * d + 0.25 * ds2);
            sum += f * (2.0 * ch * iu2 - co * iu);
        }
        4.0 * sh * sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table of one value in the bins `θh_i < k`, 0 elsewhere: at normal incidence
    /// `A = (π/2)(1 − cos 4θe)` with `θe = (π/2)(k/90)²` the edge (for `θe ≤ π/4`).
    #[test]
    fn normal_incidence_matches_the_closed_form() {
        for k in [10usize, 30, 60] {
            let table = MerlBrdf::from_fn(|th, _, _| {
                let i = (th / FRAC_PI_2).sqrt() * RES_THETA_H as f64;
                if (i as usize) < k { [1.0; 3] } else { [0.0; 3] }
            });
            let te = FRAC_PI_2 * (k as f64 / 90.0).powi(2);
            let exact = 0.5 * PI * (1.0 - (4.0 * te).cos());
            let a = table.albedo_in_bins(0.0, 1e-9, 10_000_000);
            assert!(
                (a.value / exact - 1.0).abs() < 1e-12,
                "{k}: {a:?} vs {exact}"
            );
        }
    }

    /// Constant `f = 1`: `A = π` at every θo (the rings cover the hemisphere exactly once),
    /// within the declared error, itself at most the target.
    #[test]
    fn a_constant_table_integrates_to_pi() {
        let table = MerlBrdf::from_fn(|_, _, _| [1.0; 3]);
        for t in [0.0f64, 37.3, 80.0, 89.5] {
            let a = table.albedo_in_bins(t.to_radians(), 1e-6, 2_000_000);
            assert!(a.abs_err <= 1e-6 * a.value, "{t}: {a:?}");
            assert!((a.value - PI).abs() <= a.abs_err.max(1e-12), "{t}: {a:?}");
        }
    }
}

#[cfg(test)]
mod probe {
    use super::*;

    /// Convergence with the tolerance on the MERL layout of a Phong lobe (printed; `--ignored`).
    #[test]
    #[ignore]
    fn probe_orders() {
        let phong = crate::parse_spec("phong:n=50").unwrap();
        let table = MerlBrdf::tabulate(&*phong);
        for t in [36.6f64, 85.0, 88.0, 89.0, 89.5, 89.9, 89.99] {
            let tols = [1e-3, 1e-4, 3e-5, 1e-5, 1e-6, 1e-8];
            let r: Vec<MerlAlbedo> = tols
                .iter()
                .map(|&tol| table.albedo_in_bins(t.to_radians(), tol, 50_000_000))
                .collect();
            let best = r[r.len() - 1].value;
            let s: Vec<String> = r
                .iter()
                .map(|a| {
                    format!(
                        "{:+.1e}/{:.0e}/{}",
                        a.value / best - 1.0,
                        a.abs_err / best,
                        a.evaluations
                    )
                })
                .collect();
            println!("{t}: {best:.9} {}", s.join("  "));
        }
    }
}
