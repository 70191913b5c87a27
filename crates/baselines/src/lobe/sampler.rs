//! `lobe-sphere` and `lobe-hemisphere`: the fitted cosine lobe around the mirror direction,
//! mixed with cosine hemisphere sampling.

use std::cell::Cell;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

use brdf::{Brdf, Vec3, direction_from_radians, mirror};
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::{UniformSource, count_trials};
use rayon::prelude::*;

use super::LobeError;
use super::cosine_lobe::{
    MASS_NODES, above_horizon_mass, cosine_density, lobe_density, sample_lobe,
};
use super::fit::{SecondMoment, fit_slice};
use crate::CosineHemisphere;
use crate::options::LobeOptions;

/// Where the lobe lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LobeSupport {
    /// The whole lobe on S²: samples below the horizon are kept as zero-contribution samples
    /// and the pdf is the lobe's density there.
    Sphere,
    /// The lobe truncated to Ω and renormalised by its exact above-horizon mass.
    Hemisphere,
}

/// The fitted lobe of one outgoing slice.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LobeFit {
    /// Slice centre: outgoing polar angle in degrees.
    pub theta_o: f64,
    /// Slice centre: outgoing azimuth in degrees (0 for isotropic BRDFs).
    pub phi_o: f64,
    /// Lobe exponent `n`.
    pub exponent: f64,
    /// Weight `w` of the cosine (defensive) component.
    pub defensive: f64,
    /// The fit's second moment `∫ g²/p dσ` at the slice centre (its quadrature).
    pub second_moment: f64,
}

/// Largest number of lobe draws per `lobe-hemisphere` sample. Each draw lands above the
/// horizon with probability `A ≥ 1/2`, so all fail with probability `≤ 2⁻⁶⁴`; then (and only
/// then) the sample is a cosine-hemisphere draw, a deviation from the stated density of at
/// most `2⁻⁶⁴` in probability.
pub const MAX_LOBE_TRIALS: usize = 64;

/// Cosine lobe about the mirror direction `ω_r = (−ωo.x, −ωo.y, ωo.z)`, with a per-slice fitted
/// exponent, mixed with cosine-weighted hemisphere sampling.
///
/// Density w.r.t. solid angle, with the nearest slice's exponent `n` and weight `w`
/// (nearest by `θo`, and by `φo` for anisotropic BRDFs; the same slice in `sample` and `pdf`):
/// * [`LobeSupport::Sphere`]: `p(ω) = w·cos⁺θ/π + (1−w)·L_n(ω)` on S², with
///   `L_n = (n+1)/(2π) max(0, ω_r·ω)^n`; samples below the horizon contribute zero.
/// * [`LobeSupport::Hemisphere`]: `p(ω) = w·cosθ/π + (1−w)·L_n(ω)/A(θo, n)` on Ω, `A` the
///   lobe's mass above the horizon (quadrature, declared by
///   [`brdf_sampling::SamplerDiagnostics::normaliser_rel_err`]); the truncated lobe is drawn by rejection of
///   below-horizon lobe draws (at most [`MAX_LOBE_TRIALS`]).
///
/// The cosine component is what keeps the sampler unbiased: for `θo > 0` the lobe is zero on
/// `{ω ∈ Ω : ω_r·ω ≤ 0}`, where diffuse BRDFs are not; the fit keeps `w ≥ min_defensive`.
pub struct LobeSampler {
    support: LobeSupport,
    theta_slices: usize,
    phi_slices: usize,
    /// Azimuth period of the slices: `π` for half-turn-symmetric BRDFs, else `2π`.
    phi_period: f64,
    fits: Vec<LobeFit>,
}

impl std::fmt::Debug for LobeSampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LobeSampler")
            .field("support", &self.support)
            .field("theta_slices", &self.theta_slices)
            .field("phi_slices", &self.phi_slices)
            .finish_non_exhaustive()
    }
}

impl LobeSampler {
    /// Fits the lobe of `brdf` per outgoing slice (`options.slices` polar slices; times
    /// `options.phi_slices` azimuth slices when the BRDF is not isotropic).
    ///
    /// Errors: the options' [`LobeError`]s.
    pub fn new(
        brdf: &Arc<dyn Brdf>,
        support: LobeSupport,
        options: &LobeOptions,
    ) -> Result<Self, LobeError> {
        options.validate()?;
        let theta_slices = options.slices;
        let phi_slices = if brdf.is_isotropic() {
            1
        } else {
            options.phi_slices
        };
        // A half-turn-symmetric BRDF's slice at φo + π is the one at φo turned by π, and so is
        // the mirror direction: the fit repeats with period π.
        let phi_period = if brdf.is_half_turn_symmetric() {
            PI
        } else {
            TAU
        };
        let truncated = support == LobeSupport::Hemisphere;
        let n_max = options.exponent.unwrap_or(options.max_exponent);
        // Slices are fitted in parallel; each fit is deterministic, so the result is too.
        let fits: Vec<LobeFit> = (0..theta_slices * phi_slices)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k / phi_slices, k % phi_slices);
                let theta = FRAC_PI_2 * (i as f64 + 0.5) / theta_slices as f64;
                let phi = if phi_slices == 1 {
                    0.0
                } else {
                    phi_period * (j as f64 + 0.5) / phi_slices as f64
                };
                let wo = direction_from_radians(theta, phi);
                let moment = SecondMoment::new(brdf.as_ref(), &wo, n_max, truncated);
                let (exponent, defensive, second_moment) = fit_slice(
                    &moment,
                    options.exponent,
                    options.min_exponent,
                    options.max_exponent,
                    options.min_defensive,
                );
                LobeFit {
                    theta_o: theta.to_degrees(),
                    phi_o: phi.to_degrees(),
                    exponent,
                    defensive,
                    second_moment,
                }
            })
            .collect();
        Ok(Self {
            support,
            theta_slices,
            phi_slices,
            phi_period,
            fits,
        })
    }

    /// Where the lobe lives.
    pub fn support(&self) -> LobeSupport {
        self.support
    }

    /// The fitted slices, polar-major (`theta_slices × phi_slices`; the azimuths cover `[0, π)`
    /// for half-turn-symmetric BRDFs, `[0, 2π)` otherwise).
    pub fn fits(&self) -> &[LobeFit] {
        &self.fits
    }

    /// The fitted exponent of every slice, in [`LobeSampler::fits`] order.
    pub fn exponents(&self) -> Vec<f64> {
        self.fits.iter().map(|f| f.exponent).collect()
    }

    /// The slice used for `wo`: the nearest centre in `θo` (and in `φo` when anisotropic).
    pub fn fit_at(&self, wo: &Vec3) -> &LobeFit {
        let theta = wo.z.clamp(-1.0, 1.0).acos();
        let i =
            ((theta / FRAC_PI_2 * self.theta_slices as f64) as usize).min(self.theta_slices - 1);
        let j = if self.phi_slices == 1 {
            0
        } else {
            let phi = wo.y.atan2(wo.x).rem_euclid(self.phi_period);
            ((phi / self.phi_period * self.phi_slices as f64) as usize).min(self.phi_slices - 1)
        };
        &self.fits[i * self.phi_slices + j]
    }

    /// Above-horizon mass of the lobe at `wo` with `nodes` nodes per panel.
    ///
    /// A pure function of `(θo, n, nodes)`; the last value is remembered per thread, since
    /// callers evaluate many pdfs at one `ωo` (no shared state: the sampler stays `Sync`).
    fn mass(&self, wo: &Vec3, n: f64, nodes: usize) -> f64 {
        thread_local! {
            static LAST: Cell<(u64, u64, usize, f64)> = const { Cell::new((u64::MAX, u64::MAX, 0, 0.0)) };
        }
        let theta = wo.z.clamp(-1.0, 1.0).acos();
        let key = (theta.to_bits(), n.to_bits(), nodes);
        LAST.with(|last| {
            let (t, e, k, value) = last.get();
            if (t, e, k) == key {
                return value;
            }
            let value = above_horizon_mass(theta, n, nodes);
            last.set((key.0, key.1, key.2, value));
            value
        })
    }
}

impl DirectionSampler for LobeSampler {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let pick = u.next_uniform();
        let u0 = u.next_uniform();
        let u1 = u.next_uniform();
        let fit = self.fit_at(wo);
        count_trials(1);
        let wi = if !(wo.z > 0.0) || pick < fit.defensive {
            CosineHemisphere::sample_square([u0, u1]).wi
        } else {
            let r = mirror(wo);
            match self.support {
                LobeSupport::Sphere => sample_lobe(&r, fit.exponent, [u0, u1]),
                LobeSupport::Hemisphere => {
                    let mut w = sample_lobe(&r, fit.exponent, [u0, u1]);
                    let mut trials = 1;
                    while !(w.z > 0.0) && trials < MAX_LOBE_TRIALS {
                        let v = [u.next_uniform(), u.next_uniform()];
                        w = sample_lobe(&r, fit.exponent, v);
                        trials += 1;
                    }
                    // The retried lobe directions below the horizon (`bench`'s trials; the
                    // first proposal is counted above).
                    count_trials(trials as u64 - 1);
                    if w.z > 0.0 {
                        w
                    } else {
                        CosineHemisphere::sample_square([u0, u1]).wi
                    }
                }
            }
        };
        DirSample {
            wi,
            pdf: self.pdf(wo, &wi),
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let cosine = cosine_density(wi);
        if !(wo.z > 0.0) {
            return cosine;
        }
        let fit = self.fit_at(wo);
        let lobe = lobe_density(fit.exponent, mirror(wo).dot(wi));
        let w = fit.defensive;
        match self.support {
            LobeSupport::Sphere => w * cosine + (1.0 - w) * lobe,
            LobeSupport::Hemisphere => {
                if wi.z > 0.0 {
                    w * cosine + (1.0 - w) * lobe / self.mass(wo, fit.exponent, MASS_NODES)
                } else {
                    0.0
                }
            }
        }
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>() + self.fits.len() * std::mem::size_of::<LobeFit>()
    }
}

impl SamplerDiagnostics for LobeSampler {
    fn normaliser_rel_err(&self, wo: &Vec3) -> Option<f64> {
        if self.support == LobeSupport::Sphere || !(wo.z > 0.0) {
            return None;
        }
        let n = self.fit_at(wo).exponent;
        let a = self.mass(wo, n, MASS_NODES);
        let fine = self.mass(wo, n, 2 * MASS_NODES);
        // A 2⁻⁵² floor: the mass is a sum of rounded terms even when both rules agree.
        Some(((a - fine).abs() / fine).max(f64::EPSILON))
    }

    /// The fitted exponents and cosine weights over the slices (the fit), and the memory.
    fn build_report(&self) -> Option<String> {
        let range = |f: fn(&LobeFit) -> f64| {
            self.fits
                .iter()
                .map(f)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                    (lo.min(x), hi.max(x))
                })
        };
        let (n_lo, n_hi) = range(|f| f.exponent);
        let (w_lo, w_hi) = range(|f| f.defensive);
        Some(format!(
            "lobe       {} slices ({} θo × {} φo), {}; exponent n in [{n_lo:.4}, {n_hi:.4}], cosine weight in [{w_lo:.3}, {w_hi:.3}]; {} bytes",
            self.fits.len(),
            self.theta_slices,
            self.phi_slices,
            match self.support {
                LobeSupport::Sphere => "on the sphere",
                LobeSupport::Hemisphere => "truncated to the hemisphere",
            },
            self.bytes_used()
        ))
    }

    /// The mirror direction, where the lobe `max(0, ω_r·ωi)^n` peaks (narrowly for a large
    /// fitted exponent `n`: width `≈ 1/√n`).
    fn singular_directions(&self, wo: &Vec3) -> Vec<Vec3> {
        if wo.z > 0.0 {
            vec![mirror(wo)]
        } else {
            Vec::new()
        }
    }
}
