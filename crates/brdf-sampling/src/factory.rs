//! Building samplers by name (for the command line and the validation suite).

use std::sync::Arc;

use brdf::Brdf;

use crate::direction_sampler::DirectionSampler;
use crate::error::SamplerError;
use crate::options::SetOptions;
use crate::set::{Progress, QuadTreeSet, Variant};

/// Sampler names this crate builds: the two variants, each with the optional two-slice mixture.
pub const SAMPLER_NAMES: &[&str] = &[
    "adaptive",
    "adaptive-paper",
    "adaptive-mixture",
    "adaptive-paper-mixture",
];

/// The variant and mixture flag of a sampler name, if this crate knows it.
pub fn parse_sampler_name(name: &str) -> Option<(Variant, bool)> {
    match name.trim() {
        "adaptive" => Some((Variant::Adaptive, false)),
        "adaptive-paper" => Some((Variant::Paper, false)),
        "adaptive-mixture" => Some((Variant::Adaptive, true)),
        "adaptive-paper-mixture" => Some((Variant::Paper, true)),
        _ => None,
    }
}

/// Builds the sampler `name` for `brdf`.
///
/// `adaptive` / `adaptive-paper` use `options` as given (so `options.mixture = true` gives the
/// mixture); the `…-mixture` names force the mixture on. Errors:
/// [`SamplerError::UnknownSampler`] (listing [`SAMPLER_NAMES`]), invalid options, or a slice
/// that cannot be built.
pub fn build_sampler(
    name: &str,
    brdf: Arc<dyn Brdf>,
    options: &SetOptions,
) -> Result<Box<dyn DirectionSampler>, SamplerError> {
    build_sampler_with_progress(name, brdf, options, None)
}

/// [`build_sampler`] reporting `(slices done, total)` while building.
pub fn build_sampler_with_progress(
    name: &str,
    brdf: Arc<dyn Brdf>,
    options: &SetOptions,
    progress: Option<Progress<'_>>,
) -> Result<Box<dyn DirectionSampler>, SamplerError> {
    Ok(Box::new(build_set(name, brdf, options, progress)?))
}

/// Like [`build_sampler_with_progress`] but returns the concrete [`QuadTreeSet`] (for reports
/// and persistence).
pub fn build_set(
    name: &str,
    brdf: Arc<dyn Brdf>,
    options: &SetOptions,
    progress: Option<Progress<'_>>,
) -> Result<QuadTreeSet, SamplerError> {
    let Some((variant, mixture)) = parse_sampler_name(name) else {
        return Err(SamplerError::UnknownSampler {
            name: name.to_string(),
            known: SAMPLER_NAMES.iter().map(|s| s.to_string()).collect(),
        });
    };
    let mut opts = *options;
    opts.mixture |= mixture;
    Ok(QuadTreeSet::build_with_progress(
        brdf, variant, &opts, progress,
    )?)
}
