//! Cells grouped by what they estimate: one group per (light, BRDF, θo), samplers compared
//! inside it.

use crate::{CellResult, StudyResults};

/// The cells of one (light, BRDF, θo).
#[derive(Debug)]
pub struct Group<'a> {
    /// Light spec.
    pub light: &'a str,
    /// BRDF spec.
    pub brdf: &'a str,
    /// Outgoing polar angle (degrees).
    pub theta_o_deg: f64,
    /// A file-name-safe identifier (`l0-b1-t30`: indices into the config's lights and
    /// BRDFs, θo in degrees).
    pub slug: String,
    /// The cells, in grid order.
    pub cells: Vec<&'a CellResult>,
}

impl Group<'_> {
    /// `BRDF at θo = …° under LIGHT`.
    pub fn title(&self) -> String {
        format!(
            "{} at θo = {}° under {}",
            self.brdf,
            self.theta_o_deg,
            short_light(self.light)
        )
    }

    /// Cells that ran and have a finite efficiency (1 / (MSE per sample at the budget N ×
    /// time)), best first.
    pub fn by_efficiency(&self) -> Vec<(&CellResult, f64)> {
        let mut v: Vec<(&CellResult, f64)> = self
            .cells
            .iter()
            .filter(|c| c.ok() && !c.zero_variance)
            .filter_map(|c| Some((*c, c.timing?.efficiency?)))
            .collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        v
    }
}

/// A light spec without a long path (`envmap:…/grace_probe_latlong.hdr` → `envmap:grace_probe_latlong.hdr`).
pub fn short_light(spec: &str) -> String {
    match spec.split_once(':') {
        Some(("envmap", path)) => format!(
            "envmap:{}",
            std::path::Path::new(path)
                .file_name()
                .map_or_else(|| path.to_string(), |f| f.to_string_lossy().into_owned())
        ),
        _ => spec.to_string(),
    }
}

/// The groups of `results`, in config order (light, BRDF, θo): the cells of the BRDF-only
/// estimator (the light and MIS cells are ranked apart, module `ranking`).
pub fn groups(results: &StudyResults) -> Vec<Group<'_>> {
    let cfg = &results.config;
    let mut out = Vec::new();
    for (li, light) in cfg.lights.iter().enumerate() {
        for (bi, brdf) in cfg.brdfs.iter().enumerate() {
            for &theta in &cfg.theta_o_deg {
                let cells: Vec<&CellResult> = results
                    .cells
                    .iter()
                    .filter(|c| &c.light == light && &c.brdf == brdf && c.theta_o_deg == theta)
                    .filter(|c| c.estimator == crate::ranking::ESTIMATOR_BRDF)
                    .collect();
                if cells.is_empty() {
                    continue;
                }
                out.push(Group {
                    light,
                    brdf,
                    theta_o_deg: theta,
                    slug: format!("l{li}-b{bi}-t{theta}"),
                    cells,
                });
            }
        }
    }
    out
}

/// Whether a sampler is one of the adaptive family.
pub fn is_adaptive(sampler: &str) -> bool {
    sampler.starts_with("adaptive")
}
