//! Cells grouped by what they estimate: one group per (light, BRDF, θo), samplers compared
//! inside it.

pub use crate::names::{short_brdf, short_light};
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
    /// `BRDF at θo = …° under LIGHT` (short names: no paths).
    pub fn title(&self) -> String {
        format!(
            "{} at θo = {}° under {}",
            short_brdf(self.brdf),
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

/// A material family, for the report's answers in words.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Family {
    /// Analytic models without a glossy lobe (Lambert, Oren–Nayar, Minnaert, Schlick's diffuse).
    DiffuseAnalytic,
    /// Isotropic analytic models with a glossy lobe.
    GlossyAnalytic,
    /// Anisotropic analytic models (at their parameters).
    AnisotropicAnalytic,
    /// Published fits of MERL-100 materials (`sgd:`, `abc:`).
    MerlFit,
    /// Measured files: RGL, Cornell, MERL.
    Measured,
}

/// Analytic models with no glossy lobe.
const DIFFUSE_MODELS: [&str; 4] = ["lambert", "oren-nayar", "minnaert", "schlick-diffuse"];

impl Family {
    /// Every family, in report order.
    pub const ALL: [Family; 5] = [
        Family::DiffuseAnalytic,
        Family::GlossyAnalytic,
        Family::AnisotropicAnalytic,
        Family::MerlFit,
        Family::Measured,
    ];

    /// The family of a BRDF spec; anisotropy is read from the built model
    /// (`Brdf::is_isotropic`), so `ward:alpha_x=0.1,alpha_y=0.3` is anisotropic and the
    /// default `ward` is not.
    pub fn of(spec: &str) -> Family {
        let name = spec.split(':').next().unwrap_or(spec).trim();
        match name {
            "rgl" | "cornell" | "merl" => Family::Measured,
            "sgd" | "abc" => Family::MerlFit,
            _ if DIFFUSE_MODELS.contains(&name) => Family::DiffuseAnalytic,
            _ => match brdf::parse_spec(spec) {
                Ok(b) if !b.is_isotropic() => Family::AnisotropicAnalytic,
                _ => Family::GlossyAnalytic,
            },
        }
    }

    /// The family in words (plural).
    pub fn describe(self) -> &'static str {
        match self {
            Family::DiffuseAnalytic => "diffuse analytic models",
            Family::GlossyAnalytic => "glossy isotropic analytic models",
            Family::AnisotropicAnalytic => "anisotropic analytic models",
            Family::MerlFit => "MERL-100 fits (SGD, ABC)",
            Family::Measured => "measured files (RGL, Cornell, MERL)",
        }
    }
}

/// Most materials in one sphere sheet: a study with more renders a subset
/// ([`sheet_brdfs`]), so that the default study's images stay cheap.
pub const SHEET_MAX_BRDFS: usize = 6;

/// The BRDFs of the sphere sheet, at most `max`: the first of each [`Family`] in config order,
/// then the next ones in config order; all of them when there are at most `max`. Config order
/// is kept.
pub fn sheet_brdfs(brdfs: &[String], max: usize) -> Vec<String> {
    if brdfs.len() <= max {
        return brdfs.to_vec();
    }
    let mut chosen: Vec<usize> = Vec::new();
    let mut seen = Vec::new();
    for (i, b) in brdfs.iter().enumerate() {
        let f = Family::of(b);
        if !seen.contains(&f) && chosen.len() < max {
            seen.push(f);
            chosen.push(i);
        }
    }
    for i in 0..brdfs.len() {
        if chosen.len() >= max {
            break;
        }
        if !chosen.contains(&i) {
            chosen.push(i);
        }
    }
    chosen.sort_unstable();
    chosen.into_iter().map(|i| brdfs[i].clone()).collect()
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
                    .filter(|c| c.estimator == crate::verdict::ESTIMATOR_BRDF)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn families_short_names_and_the_sheet_subset() {
        assert_eq!(Family::of("lambert"), Family::DiffuseAnalytic);
        assert_eq!(Family::of("ggx"), Family::GlossyAnalytic);
        assert_eq!(
            Family::of("ward:alpha_x=0.1,alpha_y=0.3"),
            Family::AnisotropicAnalytic
        );
        assert_eq!(Family::of("sgd:material=red-fabric"), Family::MerlFit);
        assert_eq!(Family::of("rgl:/x/paper_white_rgb.bsdf"), Family::Measured);
        assert_eq!(
            short_brdf("rgl:/a/b/paper_white_rgb.bsdf"),
            "rgl:paper_white_rgb"
        );
        assert_eq!(short_brdf("abc:material=red-fabric"), "abc:red-fabric");
        assert_eq!(short_brdf("phong:n=50"), "phong:n=50");
        let brdfs: Vec<String> = [
            "lambert",
            "phong",
            "ggx",
            "oren-nayar",
            "cook-torrance",
            "rgl:/x/a.bsdf",
            "cornell:/x/b.brdf",
            "sgd:material=red-fabric",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let sheet = sheet_brdfs(&brdfs, 4);
        // One per family first, in config order.
        assert_eq!(
            sheet,
            [
                "lambert",
                "phong",
                "rgl:/x/a.bsdf",
                "sgd:material=red-fabric"
            ]
            .map(String::from)
        );
        // Then the next ones in config order.
        assert_eq!(sheet_brdfs(&brdfs, 5)[2], "ggx");
        assert_eq!(sheet_brdfs(&brdfs[..3], 4), brdfs[..3].to_vec());
    }
}
