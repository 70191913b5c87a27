//! ABC model (Low, Kronander, Ynnerman & Unger 2012, "BRDF models for accurate and efficient
//! rendering of glossy surfaces", ACM TOG 31(1)) with the published fits of the 100 MERL
//! materials as presets (`abc:material=NAME`).
//!
//! Per RGB channel, with `h = (ωi + ωo)/|ωi + ωo|`:
//!
//! `f_r = kd/π + F(ωi·h) D(θh) G / (π cos θi cos θo)`,
//! * `D(θh) = A / (1 + B (1 − cos θh))^C` (`A` per channel, `B`, `C` shared),
//! * `F` the unpolarised dielectric Fresnel reflectance of index `ior`
//!   ([`fresnel_dielectric`]),
//! * `G = min(1, 2 cos θh cos θi / (ωi·h), 2 cos θh cos θo / (ωo·h))` (V-cavity),
//!
//! as evaluated by `djb::abc` in jdupuy/dj_brdf (public domain), whose table is embedded
//! (`crates/brdf/data/merl100_abc_low2012.tsv`). Isotropic, mirror- and half-turn symmetric,
//! reciprocal; bounded at the horizon (`G ≤ 2 cos θh cos θi/(ωi·h)` cancels `1/cos θi`); not
//! energy-conserving by construction.

use super::{Properties, brdf_properties};
use crate::brdf::{Brdf, luminance};
use crate::fresnel::fresnel_dielectric;
use crate::geometry::{Vec3, both_above};
use crate::models::merl_fits::FitTable;
use std::f64::consts::FRAC_1_PI;

pub(crate) const NAME: &str = "abc";

/// The embedded table (tab-separated, provenance in its header comments).
pub const TABLE: &str = include_str!("../../data/merl100_abc_low2012.tsv");

/// Fitted parameters of one material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbcParams {
    /// Diffuse albedos (R, G, B).
    pub kd: [f64; 3],
    /// NDF scales `A` (R, G, B).
    pub a: [f64; 3],
    /// NDF `B`.
    pub b: f64,
    /// NDF exponent `C`.
    pub c: f64,
    /// Index of refraction of the Fresnel term.
    pub ior: f64,
}

/// The ABC model of one MERL material.
#[derive(Debug, Clone, PartialEq)]
pub struct Abc {
    material: String,
    params: AbcParams,
}

/// The embedded table (its preset names and their close matches serve the registry).
pub(crate) static FITS: FitTable = FitTable::new(TABLE, 1);

impl Abc {
    /// The preset of a MERL material, or `None`.
    pub fn preset(material: &str) -> Option<Self> {
        let row = FITS.find(material)?;
        let v = &row.values;
        if v.len() < 9 {
            return None;
        }
        Some(Self {
            material: row.name.clone(),
            params: AbcParams {
                kd: [v[0], v[1], v[2]],
                a: [v[3], v[4], v[5]],
                b: v[6],
                c: v[7],
                ior: v[8],
            },
        })
    }

    /// The material's MERL name.
    pub fn material(&self) -> &str {
        &self.material
    }

    /// The fitted parameters.
    pub fn params(&self) -> &AbcParams {
        &self.params
    }

    /// Symmetries: isotropic, even under `y ↦ −y`, reciprocal; energy not guaranteed.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC | Properties::RECIPROCAL
    }
}

impl Brdf for Abc {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        luminance(self.eval_rgb(wo, wi))
    }

    fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        if !both_above(wo, wi) {
            return [0.0; 3];
        }
        let p = &self.params;
        let h = (wo + wi).normalize();
        let (hi, ho) = (wi.dot(&h), wo.dot(&h));
        let g = (2.0 * h.z * wi.z / hi).min(2.0 * h.z * wo.z / ho).min(1.0);
        let f = fresnel_dielectric(hi, p.ior);
        let base = (1.0 + p.b * (1.0 - h.z)).powf(p.c);
        let mut out = [0.0; 3];
        for (ch, o) in out.iter_mut().enumerate() {
            let d = p.a[ch] / base;
            let v = p.kd[ch] * FRAC_1_PI + f * d * g * FRAC_1_PI / (wi.z * wo.z);
            *o = if v.is_finite() { v.max(0.0) } else { 0.0 };
        }
        out
    }

    brdf_properties!(NAME);
}
