//! Shifted Gamma Distribution model (Bagher, Soler & Holzschuch 2012, "Accurate fitting of
//! measured reflectances using a Shifted Gamma micro-facet distribution", CGF 31(4)) with the
//! published per-channel fits of the 100 MERL materials as presets (`sgd:material=NAME`).
//!
//! Per RGB channel, with `h = (ωi + ωo)/|ωi + ωo|`, `cos θd = ωi·h`:
//!
//! `f_r = (ρd + ρs F(θd) D(θh) G1(θi) G1(θo) / (cos θi cos θo)) / π`,
//! * `D(θh) = κ e^{−a} / (π a^p cos⁴θh)` with `a = α + tan²θh / α` (the shifted gamma),
//! * `F(θd) = F0 − F1 cos θd + (1 − F0)(1 − cos θd)⁵`,
//! * `G1(θ) = clamp(1 + Λ (1 − exp(c · max(0, θ − θ0)^k)), 0, 1)`,
//!
//! as evaluated by `djb::sgd` in jdupuy/dj_brdf (public domain), whose tables are embedded
//! (`crates/brdf/data/merl100_sgd_bagher2012.tsv`). A channel that comes out negative (the
//! fitted Fresnel can dip below zero) is clamped to 0. Isotropic, mirror- and half-turn
//! symmetric, reciprocal (every factor is symmetric in `ωi ↔ ωo`); not energy-conserving by
//! construction. Declared unbounded at the horizon (the safe answer): `f` carries `1/cos θi`,
//! cancelled only where a fit's shadowing term reaches 0 before the horizon.

use super::{Properties, brdf_properties};
use crate::brdf::{Brdf, luminance};
use crate::geometry::{Vec3, both_above};
use crate::models::merl_fits::FitTable;
use std::f64::consts::FRAC_1_PI;

pub(crate) const NAME: &str = "sgd";

/// The embedded table (tab-separated, provenance in its header comments).
pub const TABLE: &str = include_str!("../../data/merl100_sgd_bagher2012.tsv");

/// Fitted parameters of one channel (the table's columns, in order).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SgdChannel {
    /// Diffuse albedo ρd.
    pub rho_d: f64,
    /// Specular scale ρs.
    pub rho_s: f64,
    /// Shift α of the distribution.
    pub alpha: f64,
    /// Gamma exponent p.
    pub p: f64,
    /// Fresnel F0.
    pub f0: f64,
    /// Fresnel F1.
    pub f1: f64,
    /// NDF scale κ.
    pub kappa: f64,
    /// Shadowing Λ.
    pub lambda: f64,
    /// Shadowing c.
    pub c: f64,
    /// Shadowing k.
    pub k: f64,
    /// Shadowing θ0 (radians).
    pub theta0: f64,
}

/// The SGD model of one MERL material.
#[derive(Debug, Clone, PartialEq)]
pub struct Sgd {
    material: String,
    channels: [SgdChannel; 3],
}

/// The embedded table (its preset names and their close matches serve the registry).
pub(crate) static FITS: FitTable = FitTable::new(TABLE, 2);

impl Sgd {
    /// The preset of a MERL material (its MERL name or the table's other name), or `None`.
    pub fn preset(material: &str) -> Option<Self> {
        let row = FITS.find(material)?;
        // 12 groups of 3 (the last, the fit error, unused).
        if row.values.len() < 33 {
            return None;
        }
        let col = |g: usize, ch: usize| row.values[3 * g + ch];
        let channel = |ch: usize| SgdChannel {
            rho_d: col(0, ch),
            rho_s: col(1, ch),
            alpha: col(2, ch),
            p: col(3, ch),
            f0: col(4, ch),
            f1: col(5, ch),
            kappa: col(6, ch),
            lambda: col(7, ch),
            c: col(8, ch),
            k: col(9, ch),
            theta0: col(10, ch),
        };
        Some(Self {
            material: row.name.clone(),
            channels: [channel(0), channel(1), channel(2)],
        })
    }

    /// The material's MERL name.
    pub fn material(&self) -> &str {
        &self.material
    }

    /// The fitted parameters of the R, G and B channels.
    pub fn channels(&self) -> &[SgdChannel; 3] {
        &self.channels
    }

    /// Symmetries: isotropic, even under `y ↦ −y`, reciprocal; the fitted shadowing term leaves
    /// `f_r` unbounded at the horizon; energy not guaranteed.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC | Properties::RECIPROCAL | Properties::UNBOUNDED_AT_HORIZON
    }
}

fn g1(cos_theta: f64, p: &SgdChannel) -> f64 {
    let excess = (cos_theta.clamp(-1.0, 1.0).acos() - p.theta0).max(0.0);
    let e = (p.c * excess.powf(p.k)).exp();
    if p.lambda == 0.0 {
        return 1.0;
    }
    let g = 1.0 + p.lambda * (1.0 - e);
    if g.is_nan() { 0.0 } else { g.clamp(0.0, 1.0) }
}

fn ndf(cos_h: f64, p: &SgdChannel) -> f64 {
    let c2 = cos_h * cos_h;
    let t2 = (1.0 - c2) / c2;
    let a = p.alpha + t2 / p.alpha;
    p.kappa * (-a).exp() * FRAC_1_PI / (a.powf(p.p) * c2 * c2)
}

impl Brdf for Sgd {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        luminance(self.eval_rgb(wo, wi))
    }

    fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        if !both_above(wo, wi) {
            return [0.0; 3];
        }
        let h = (wo + wi).normalize();
        let cd = wi.dot(&h).clamp(0.0, 1.0);
        let s = 1.0 - cd;
        self.channels.map(|p| {
            let fresnel = p.f0 - cd * p.f1 + s.powi(5) * (1.0 - p.f0);
            let spec = fresnel * ndf(h.z, &p) * g1(wi.z, &p) * g1(wo.z, &p) / (wi.z * wo.z);
            let v = (p.rho_d + p.rho_s * spec) * FRAC_1_PI;
            if v.is_finite() { v.max(0.0) } else { 0.0 }
        })
    }

    brdf_properties!(NAME);
}
