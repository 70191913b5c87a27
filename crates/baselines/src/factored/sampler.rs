//! The factored sampler: term choice by the outgoing cell's weights, then a `θp` band (uniform
//! in `cos θp`) and a `φp` bin (uniform in `φp`) of that term; pdf = mixture over all terms.

use std::f64::consts::FRAC_1_PI;

use brdf::Vec3;
use brdf_sampling::{
    CellCoords, DirSample, DirectionSampler, PdfCellRow, PdfCells, SamplerDiagnostics,
};
use partition_sampler::UniformSource;

use crate::CosineHemisphere;
use crate::factored::grid::{
    OutgoingCells, PhiBins, ThetaBands, direction, incoming, reparametrised,
};
use crate::factored::report::FactoredReport;
use crate::options::Reparam;

/// Lawrence et al. 2004 factored BRDF importance sampling (baselines.md §A), with an optional
/// defensive cosine component.
///
/// Representation: `g(ωi | ωo) = f_r cos θi ≈ Σ_j F_j(ωo) Σ_k u_jk(θp) v_jk(φp)`, `ωp` the
/// half vector (or `ωi`), `u`, `v` piecewise constant on `θp` bands and `φp` bins. With band
/// measures `Ω_a = cos θ_a − cos θ_{a+1}` and bin widths `Δφ`, `ū = u/Σ_a u[a]Ω_a` and
/// `v̄ = v/Σ_b v[b]Δφ` make `ū(θp) v̄(φp)` a density w.r.t. the solid angle of `ωp`, and term
/// `l = (j, k)` weighs `W_l(o) = F[o, j] a_jk b_jk` in outgoing cell `o` (nearest cell).
///
/// Density w.r.t. the **solid angle of `ωi`**:
/// `p(ωi | ωo) = (1−α) J(ωi) Σ_l W_l(o) ū_l(θp) v̄_l(φp) / Σ_l W_l(o) + α max(0, cos θi)/π`,
/// `J = 1/(4 |ωi·ωh|)` in half-angle mode (1 in spherical mode). In half-angle mode samples
/// can land below the horizon (zero-contribution samples, never redrawn): the support is the
/// whole sphere and the pdf integrates to 1 over it. `α > 0` guarantees `p > 0` wherever
/// `g > 0` (NMF factors may reach zero); `α = 0` is the paper-pure sampler.
///
/// Each sample consumes exactly three uniforms: component and term, `θp` band and position,
/// `φp` bin and position.
#[derive(Debug, Clone)]
pub struct FactoredSampler {
    pub(crate) outgoing: OutgoingCells,
    pub(crate) theta_p: ThetaBands,
    pub(crate) phi_p: PhiBins,
    pub(crate) reparam: Reparam,
    pub(crate) alpha: f64,
    /// `L = J·K`.
    pub(crate) terms: usize,
    /// `rows × L`: `W_l(o) / Σ_l' W_l'(o)`.
    pub(crate) weights: Vec<f64>,
    /// `rows × (L + 1)`: the discrete CDFs of `weights`.
    pub(crate) weight_cdf: Vec<f64>,
    /// `L × n_θp`: `ū_l[a]`.
    pub(crate) u_bar: Vec<f64>,
    /// `L × (n_θp + 1)`: CDFs of `ū_l[a] Ω_a`.
    pub(crate) u_cdf: Vec<f64>,
    /// `L × n_φp`: `v̄_l[b]`.
    pub(crate) v_bar: Vec<f64>,
    /// `L × (n_φp + 1)`: CDFs of `v̄_l[b] Δφ`.
    pub(crate) v_cdf: Vec<f64>,
    pub(crate) report: FactoredReport,
}

/// Picks the bin `i` with `cdf[i] ≤ u < cdf[i+1]` (always a bin of positive mass when
/// `cdf` ends at exactly 1) and the position `t ∈ [0, 1)` of `u` inside it.
pub(crate) fn pick(cdf: &[f64], u: f64) -> (usize, f64) {
    let n = cdf.len() - 1;
    let i = cdf[1..].partition_point(|&c| c <= u).min(n - 1);
    let width = cdf[i + 1] - cdf[i];
    let t = if width > 0.0 {
        ((u - cdf[i]) / width).clamp(0.0, 1.0 - f64::EPSILON / 2.0)
    } else {
        0.5
    };
    (i, t)
}

impl FactoredSampler {
    /// The build report (fit, convergence, time, memory).
    pub fn report(&self) -> &FactoredReport {
        &self.report
    }

    /// Number of terms `L = J·K`.
    pub fn terms(&self) -> usize {
        self.terms
    }

    /// The normalised weights `W_l(o)/Σ W` of the outgoing cell of `wo`.
    pub fn term_weights(&self, wo: &Vec3) -> &[f64] {
        let (row, _) = self.outgoing.cell(wo);
        &self.weights[row * self.terms..(row + 1) * self.terms]
    }

    /// The density of term `l` alone w.r.t. the solid angle of `ωp` at `(band a, bin b)`.
    fn term_density(&self, l: usize, a: usize, b: usize) -> f64 {
        self.u_bar[l * self.theta_p.len() + a] * self.v_bar[l * self.phi_p.n + b]
    }

    /// The row of `wo`, and the `(θp band, φp bin)` and Jacobian `|dωp/dωi|` of `wi`
    /// (`None` where the factored density is zero).
    fn locate(&self, wo: &Vec3, wi: &Vec3) -> (usize, Option<(usize, usize, f64)>) {
        let (row, turn) = self.outgoing.cell(wo);
        let wo_r = turn.local_to_row(wo);
        let wi_r = turn.local_to_row(wi);
        let cell = reparametrised(self.reparam, &wo_r, &wi_r).map(|(wp, jacobian)| {
            let a = self.theta_p.band_of(wp.z);
            let b = self.phi_p.bin_of(wp.y.atan2(wp.x));
            (a, b, jacobian)
        });
        (row, cell)
    }

    /// The factored part of the density w.r.t. the solid angle of `ωi` (no defensive part):
    /// `J(ωi) Σ_l W_l(o) ū_l v̄_l / Σ_l W_l(o)`, the mixture over all terms.
    pub fn factored_pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let (row, Some((a, b, jacobian))) = self.locate(wo, wi) else {
            return 0.0;
        };
        let weights = &self.weights[row * self.terms..(row + 1) * self.terms];
        let mixture: f64 = weights
            .iter()
            .enumerate()
            .map(|(l, w)| w * self.term_density(l, a, b))
            .sum();
        mixture * jacobian
    }

    /// The density of term `l` alone w.r.t. the solid angle of `ωi`, `J(ωi) ū_l v̄_l`
    /// (0 for `l ≥ L`): what sampling term `l` gives. The sampler's pdf is the mixture of
    /// these with the weights [`FactoredSampler::term_weights`].
    pub fn term_pdf(&self, wo: &Vec3, wi: &Vec3, l: usize) -> f64 {
        match self.locate(wo, wi) {
            (_, Some((a, b, jacobian))) if l < self.terms => self.term_density(l, a, b) * jacobian,
            _ => 0.0,
        }
    }

    /// Draws `ωi` from term `l` in the outgoing cell of `wo` with two uniforms.
    fn sample_term(&self, wo: &Vec3, l: usize, u1: f64, u2: f64) -> Vec3 {
        let (_, turn) = self.outgoing.cell(wo);
        let n_theta = self.theta_p.len();
        let cdf = &self.u_cdf[l * (n_theta + 1)..(l + 1) * (n_theta + 1)];
        let (a, t) = pick(cdf, u1);
        let (c0, c1) = (self.theta_p.cos_edges[a], self.theta_p.cos_edges[a + 1]);
        let z = c0 - t * (c0 - c1);
        let n_phi = self.phi_p.n;
        let cdf = &self.v_cdf[l * (n_phi + 1)..(l + 1) * (n_phi + 1)];
        let (b, t) = pick(cdf, u2);
        let phi = (b as f64 + t) * self.phi_p.width;
        let wp = direction(z, phi);
        let wo_r = turn.local_to_row(wo);
        turn.row_to_local(&incoming(self.reparam, &wo_r, &wp))
    }
}

impl DirectionSampler for FactoredSampler {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let u0 = u.next_uniform();
        let u1 = u.next_uniform();
        let u2 = u.next_uniform();
        let wi = if u0 < self.alpha {
            CosineHemisphere::sample_square([u1, u2]).wi
        } else {
            let t = ((u0 - self.alpha) / (1.0 - self.alpha)).clamp(0.0, 1.0);
            let (row, _) = self.outgoing.cell(wo);
            let cdf = &self.weight_cdf[row * (self.terms + 1)..(row + 1) * (self.terms + 1)];
            let (l, _) = pick(cdf, t);
            self.sample_term(wo, l, u1, u2)
        };
        DirSample {
            wi,
            pdf: self.pdf(wo, &wi),
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let defensive = if self.alpha > 0.0 && wi.z > 0.0 {
            self.alpha * wi.z * FRAC_1_PI
        } else {
            0.0
        };
        let factored = if self.alpha < 1.0 {
            (1.0 - self.alpha) * self.factored_pdf(wo, wi)
        } else {
            0.0
        };
        factored + defensive
    }

    fn bytes_used(&self) -> usize {
        let floats = self.weights.len()
            + self.weight_cdf.len()
            + self.u_bar.len()
            + self.u_cdf.len()
            + self.v_bar.len()
            + self.v_cdf.len()
            + self.theta_p.cos_edges.len()
            + self.theta_p.measure.len();
        std::mem::size_of::<Self>() + floats * std::mem::size_of::<f64>()
    }
}

impl SamplerDiagnostics for FactoredSampler {
    /// The factored part is constant on each `(θp band, φp bin)` cell of the reparametrised
    /// direction `ωp` (the half vector, or `ωi` in spherical mode), turned by the row's frame;
    /// the defensive part is the cosine component of weight `α`.
    fn pdf_cells(&self, wo: &Vec3) -> Option<PdfCells> {
        if !(wo.z > 0.0) {
            return None;
        }
        let (_, turn) = self.outgoing.cell(wo);
        let edges: Vec<f64> = (0..=self.phi_p.n)
            .map(|b| b as f64 * self.phi_p.width)
            .collect();
        let c = &self.theta_p.cos_edges;
        let rows = (0..self.theta_p.len())
            .rev()
            .map(|a| PdfCellRow::turned([c[a + 1], c[a]], &edges, turn.angle()))
            .collect();
        Some(PdfCells {
            coords: match self.reparam {
                Reparam::HalfAngle => CellCoords::HalfVector { wo: *wo },
                Reparam::Spherical => CellCoords::Incident,
            },
            rows,
            cosine_weight: self.alpha,
        })
    }

    /// [`FactoredReport`]'s lines (fit, convergence, time, memory), and a line `warning: …`
    /// when a factorisation stopped at its iteration cap.
    fn build_report(&self) -> Option<String> {
        let mut s = self.report.to_string();
        if !self.report.converged() {
            s.push_str(
                "\nwarning: factored: a factorisation hit its iteration cap (--factored-iterations) before the tolerance; the residuals above are not converged",
            );
        }
        Some(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pick_skips_empty_bins_and_remaps() {
        let cdf = [0.0, 0.25, 0.25, 1.0];
        assert_eq!(pick(&cdf, 0.0), (0, 0.0));
        let (i, t) = pick(&cdf, 0.25);
        assert_eq!(i, 2);
        assert!(t.abs() < 1e-15);
        let (i, t) = pick(&cdf, 0.625);
        assert_eq!(i, 2);
        assert!((t - 0.5).abs() < 1e-15);
        assert_eq!(pick(&cdf, 1.0 - 1e-17).0, 2);
    }
}
