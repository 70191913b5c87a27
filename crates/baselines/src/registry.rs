//! Every direction sampler of the project by its command-line name.
//!
//! The adaptive samplers come from `brdf-sampling`; the BRDF-blind baselines from this crate.
//! The CLI and the validation suite build samplers only through [`build_direction_sampler`],
//! so a new sampler is one entry here.

use std::sync::Arc;

use brdf::Brdf;
use brdf_sampling::{DirectionSampler, Progress, SamplerError, SetOptions};

use crate::hemisphere::{CosineHemisphere, UniformHemisphere};

/// Names of the direction samplers, with a one-line description each.
pub const DIRECTION_SAMPLERS: &[(&str, &str)] = &[
    (
        "adaptive",
        "adaptive partition (quadtree + rejection), envelope scheme: exact, the default",
    ),
    (
        "adaptive-paper",
        "adaptive partition as in the papers: leaf ∝ I_i, CDF descent, image-map bounds",
    ),
    (
        "adaptive-mixture",
        "adaptive, mixture of the two θ-neighbouring slices (exact mixture pdf)",
    ),
    (
        "adaptive-paper-mixture",
        "adaptive-paper with the two-slice mixture",
    ),
    ("uniform", "uniform on the hemisphere, p = 1/(2π)"),
    ("cosine", "cosine-weighted hemisphere, p = cosθ/π"),
];

/// Builds the direction sampler `name` for `brdf` (`options` configure the adaptive sets;
/// `progress` reports `(slices done, total)` while they build).
///
/// Errors: [`SamplerError::UnknownSampler`] listing every name of [`DIRECTION_SAMPLERS`], or a
/// build error of the adaptive set.
pub fn build_direction_sampler(
    name: &str,
    brdf: Arc<dyn Brdf>,
    options: &SetOptions,
    progress: Option<Progress<'_>>,
) -> Result<Box<dyn DirectionSampler>, SamplerError> {
    match name.trim() {
        "uniform" => Ok(Box::new(UniformHemisphere)),
        "cosine" => Ok(Box::new(CosineHemisphere)),
        other => brdf_sampling::build_sampler_with_progress(other, brdf, options, progress)
            .map_err(|e| match e {
                SamplerError::UnknownSampler { name, .. } => SamplerError::UnknownSampler {
                    name,
                    known: DIRECTION_SAMPLERS
                        .iter()
                        .map(|(n, _)| n.to_string())
                        .collect(),
                },
                e => e,
            }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_name_builds_and_unknown_names_list_all() {
        let brdf: Arc<dyn Brdf> = Arc::from(brdf::parse_spec("lambert").expect("spec"));
        let options = SetOptions {
            slices: 3,
            ..SetOptions::default()
        };
        for (name, _) in DIRECTION_SAMPLERS {
            let s = build_direction_sampler(name, brdf.clone(), &options, None);
            assert!(s.is_ok(), "{name}: {:?}", s.err());
        }
        let err = build_direction_sampler("nope", brdf, &options, None)
            .err()
            .map(|e| e.to_string());
        let err = err.unwrap_or_default();
        assert!(
            err.contains("nope") && err.contains("cosine") && err.contains("adaptive-paper"),
            "{err}"
        );
    }
}
