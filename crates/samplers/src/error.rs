//! The registry's typed error.

use brdf_sampling::Variant;

/// Why a registered sampler does not apply to a BRDF (e.g. `analytic` for a model without an
/// analytic sampler, `rgl-native` for a BRDF that is not an RGL material): not a failure of
/// the sampler or of its build, so suites and studies skip the pair and report `reason`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("sampler `{sampler}` does not apply to this BRDF: {reason}")]
pub struct NotApplicable {
    /// The sampler's registered name.
    pub sampler: &'static str,
    /// Why, in one line.
    pub reason: String,
}

/// A sampler could not be found or built.
#[derive(Debug, thiserror::Error)]
pub enum RegistryError {
    /// No sampler has this name.
    #[error("unknown sampler `{name}`{}; known samplers: {known}",
        suggestion.map(|s| format!(" (did you mean `{s}`?)")).unwrap_or_default())]
    UnknownSampler {
        /// The name given.
        name: String,
        /// The closest registered name, if one is close.
        suggestion: Option<&'static str>,
        /// Every registered name, comma-separated.
        known: String,
    },
    /// The sampler exists but samples something else (e.g. an environment-map sampler asked
    /// to sample a BRDF).
    #[error(
        "sampler `{name}` is a {found} sampler, not a {expected} sampler; {expected} samplers: {candidates}"
    )]
    WrongKind {
        /// The name given.
        name: &'static str,
        /// The kind the caller needs.
        expected: &'static str,
        /// The entry's kind.
        found: &'static str,
        /// The names of the expected kind.
        candidates: String,
    },
    /// A sampler could not be built: its own error (a built-in baseline's, e.g. no analytic
    /// sampler for the model, or that of a closure added at run time with
    /// [`crate::SamplerEntry::direction`]).
    #[error("sampler `{name}`: {source}")]
    User {
        /// The sampler's registered name.
        name: &'static str,
        /// Its build closure's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A saved set's variant and mixture flag match no registered sampler.
    #[error("the saved set ({variant:?}, mixture {mixture}) matches no registered sampler")]
    UnregisteredSet {
        /// Its variant.
        variant: Variant,
        /// Its mixture flag.
        mixture: bool,
    },
    /// The sampler does not apply to the BRDF ([`crate::SamplerEntry::applicability`]).
    #[error(transparent)]
    NotApplicable(#[from] NotApplicable),
    /// A BRDF spec (e.g. the one stored in a set file) does not parse.
    #[error("BRDF spec `{spec}`: {source}")]
    Brdf {
        /// The spec.
        spec: String,
        /// The cause.
        source: brdf::SpecError,
    },
    /// Building an adaptive quadtree set failed.
    #[error(transparent)]
    Set(#[from] brdf_sampling::SetError),
    /// Building the exact interval-bounded set failed.
    #[error(transparent)]
    Exact(#[from] brdf_sampling::ExactError),
    /// A set file could not be read back.
    #[error(transparent)]
    SetFile(#[from] brdf_sampling::SetFileError),
    /// A sampled density could not be set up.
    #[error(transparent)]
    Density(#[from] partition_sampler::DensityError),
    /// A quadtree could not be built.
    #[error(transparent)]
    Tree(#[from] partition_sampler::BuildError),
    /// An environment-map sampler could not be built.
    #[error(transparent)]
    EnvMap(#[from] envmap::EnvMapError),
    /// A grid sampler could not be built.
    #[error(transparent)]
    Grid(#[from] partition_sampler::PiecewiseConstantError),
    /// The projected-disc sampler (`quadtree-disc`) was asked to sample a BRDF that grows
    /// without bound at the horizon ([`brdf::Brdf::bounded_at_horizon`] `= false`): its disc
    /// density `f_r(ωo, h⁻¹(x))` is unbounded near the rim, so no finite leaf bound holds there.
    #[error(
        "sampler `quadtree-disc` samples f_r on the projected disc with finite leaf bounds, but `{brdf}` grows without bound at the horizon (f_r ~ 1/cos θi), so the leaves at the rim cannot be bounded; use `adaptive` (equal-area slices) instead"
    )]
    UnboundedOnDisc {
        /// The BRDF's name.
        brdf: String,
    },
    /// A sampler option is out of its range or fails its sampler's check
    /// ([`crate::options_from`]).
    #[error(transparent)]
    Option(#[from] OptionError),
}

/// An option value out of its range, or options that fail their sampler's check.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("sampler `{sampler}`: option `{option}`{}: {reason}",
    if value.is_empty() { String::new() } else { format!(" = {value}") })]
pub struct OptionError {
    /// The sampler the option belongs to.
    pub sampler: &'static str,
    /// The option's name (empty when the check concerns the options together).
    pub option: &'static str,
    /// The value given (empty when not known).
    pub value: String,
    /// Why, in one line (with the valid range).
    pub reason: String,
}
