//! Cosine-lobe baselines: the lobe `(n+1)/(2π)·max(0, ω_r·ω)^n` around the mirror direction
//! with an exponent fitted per outgoing slice ([`LobeSampler`], `lobe-sphere` and
//! `lobe-hemisphere`), and the models' own analytic samplers ([`crate::AnalyticSampler`]).

mod analytic;
mod cosine_lobe;
mod fit;
mod sampler;

pub use analytic::AnalyticSampler;
pub use cosine_lobe::{above_horizon_mass, lobe_density, sample_lobe};
pub use sampler::{LobeFit, LobeSampler, LobeSupport, MAX_LOBE_TRIALS};

/// Why a lobe or analytic baseline could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LobeError {
    /// An exponent (fixed, or a fit bound) outside its range.
    #[error("lobe {what} = {value} is out of range: must lie in [0, {max}]")]
    Exponent {
        /// Which field.
        what: &'static str,
        /// The value given.
        value: f64,
        /// The largest accepted value.
        max: f64,
    },
    /// A slice count outside its range.
    #[error("lobe {what} = {value} is out of range: must lie in [1, {max}]")]
    Slices {
        /// Which field.
        what: &'static str,
        /// The value given.
        value: usize,
        /// The largest accepted value.
        max: usize,
    },
    /// The smallest defensive weight is outside `(0, 1]`.
    #[error("lobe min_defensive = {0} is out of range: must lie in (0, 1]")]
    Defensive(f64),
    /// The BRDF model has no standard analytic importance sampler.
    #[error(
        "BRDF model `{model}` has no analytic sampler (analytic samplers exist for lambert, phong, blinn, lewis, ward, ward-original, cook-torrance, beckmann, ggx)"
    )]
    NoAnalyticSampler {
        /// The model's name.
        model: String,
    },
    /// The model's analytic description is invalid (negative weight, bad exponent or roughness).
    #[error("BRDF model `{model}`: invalid analytic lobe description: {reason}")]
    BadAnalyticLobes {
        /// The model's name.
        model: String,
        /// What is wrong.
        reason: String,
    },
}
