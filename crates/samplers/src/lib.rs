//! The one registry of brdf-lab's samplers.
//!
//! Every sampler the project ships has exactly one [`SamplerEntry`] in [`SAMPLERS`]: its name
//! (as given to `--sampler`), a one-line description, its [`Capabilities`] and one
//! [`Constructor`]. The command line (`list`, `sample`, `eval`, `build`, `validate`, `envmap`),
//! the validation suite and the studies find samplers only here, so adding a sampler is one
//! entry. This crate is the lowest one that sees every sampler crate (`brdf-sampling`,
//! `baselines`, `envmap`, `partition-sampler`); nothing below it knows a sampler by name.
//!
//! Four kinds of samplers, by what they sample:
//! * **direction** samplers of a BRDF (pdf w.r.t. solid angle, the
//!   [`brdf_sampling::DirectionSampler`] shape) — the adaptive quadtree sets
//!   ([`Constructor::AdaptiveSet`]) and every other ([`Constructor::Direction`]);
//! * a **disc** sampler of `x ↦ f_r(ωo, h⁻¹(x))` on the unit disc for one `ωo` (pdf w.r.t. area);
//! * **environment-map** samplers (directions ∝ luminance per solid angle);
//! * **grid** samplers of a piecewise-constant table on a rectangle (pdf w.r.t. area).
//!
//! ```
//! use std::sync::Arc;
//! use brdf_sampling::{DirectionSampler, SetOptions};
//! use rand::SeedableRng;
//!
//! let brdf: Arc<dyn brdf::Brdf> = Arc::from(brdf::parse_spec("phong:n=20")?);
//! let options = SetOptions { slices: 6, ..SetOptions::default() };
//! let built = samplers::build_direction("adaptive", &samplers::DirectionRequest::new(brdf, &options))?;
//!
//! let wo = brdf::direction_from_angles(30.0, 0.0);
//! let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(1);
//! let s = built.sampler.sample(&wo, &mut rng);
//! assert!((built.sampler.pdf(&wo, &s.wi) - s.pdf).abs() <= 1e-9 * s.pdf);
//!
//! // Unknown names list every known one and suggest the closest.
//! let err = samplers::find("adaptve").unwrap_err().to_string();
//! assert!(err.contains("did you mean `adaptive`"), "{err}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod entries;
mod error;
pub mod options;
mod registry;
mod request;

pub use entries::{DISC_GRID, DISC_SAFETY, SAMPLERS, quadtree_disc_density};
pub use error::{NotApplicable, OptionError, RegistryError};
pub use options::{End, OptionKind, OptionSpec, options_from};
pub use registry::Registry;
pub use request::{BuiltDirection, DirectionRequest};

use std::sync::Arc;

use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, DiscBrdf, QuadTreeSet, Variant};
use envmap::{AdaptiveOptions, EnvMap, EnvMapSampler};
use partition_sampler::{QuadTreeSampler, Rect, SampledGridDensity};

/// Where a direction sampler's samples may land.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Support {
    /// The upper hemisphere Ω only.
    Hemisphere,
    /// The whole sphere: samples below the horizon are zero-contribution samples.
    Sphere,
}

/// What a sampler can do, for listings and for choosing what to run it on (all `false` by
/// default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Capabilities {
    /// The reported pdf is the exact density of the drawn samples (up to a declared numerical
    /// normaliser), so a poor fit costs variance, never bias.
    pub exact_pdf: bool,
    /// Has a stratified batch mode (`sample_batch` is not just independent draws).
    pub batch_mode: bool,
    /// Precomputes a structure per BRDF (or map); its build time and memory are reported.
    pub needs_build: bool,
    /// Works for anisotropic BRDFs.
    pub anisotropic: bool,
    /// Works for measured (tabulated) BRDF data.
    pub measured: bool,
}

impl Capabilities {
    /// Short flags for listings, e.g. `exact, batch, build, aniso, measured`.
    pub fn flags(&self) -> String {
        let flags = [
            (self.exact_pdf, "exact"),
            (self.batch_mode, "batch"),
            (self.needs_build, "build"),
            (self.anisotropic, "aniso"),
            (self.measured, "measured"),
        ];
        let on: Vec<&str> = flags.iter().filter(|f| f.0).map(|f| f.1).collect();
        on.join(", ")
    }
}

/// Builds a direction sampler (other than an adaptive set) for a request. Any error will do:
/// [`SamplerEntry::build_direction`] passes a [`RegistryError`] on as it is and wraps any other
/// as [`RegistryError::User`] with the entry's name.
pub type DirectionBuild = fn(&DirectionRequest<'_>) -> Result<BuiltDirection, UserError>;

/// Builds a direction sampler from a closure (an entry made at run time, e.g. by a crate outside
/// the workspace or by the Python bindings: see [`SamplerEntry::direction`]).
pub type SharedDirectionBuild =
    Arc<dyn Fn(&DirectionRequest<'_>) -> Result<BuiltDirection, RegistryError> + Send + Sync>;

/// The error a user's build closure may return ([`SamplerEntry::direction`]).
pub type UserError = Box<dyn std::error::Error + Send + Sync>;

/// The disc sampler of `x ↦ f_r(ωo, h⁻¹(x))` (pdf w.r.t. area on the unit disc).
pub type DiscSampler = QuadTreeSampler<SampledGridDensity<DiscBrdf>>;

/// Builds a disc sampler for a BRDF and an outgoing direction.
pub type DiscBuild = fn(&Arc<dyn Brdf>, &Vec3) -> Result<DiscSampler, RegistryError>;

/// Builds an environment-map sampler; `options` configure the adaptive ones (the entry sets
/// the scheme).
pub type EnvMapBuild = fn(&EnvMap, &AdaptiveOptions) -> Result<EnvMapSampler, RegistryError>;

/// The grid sampler of a piecewise-constant table (pdf w.r.t. area on its rectangle).
pub type GridSampler = partition_sampler::PiecewiseConstant2D;

/// Builds a grid sampler from `width × height` values (row-major, row 0 at `domain.y0`).
pub type GridBuild = fn(usize, usize, Vec<f64>, Rect) -> Result<GridSampler, RegistryError>;

/// How a registered sampler is built.
#[derive(Clone)]
pub enum Constructor {
    /// An adaptive quadtree set of `brdf-sampling` (a direction sampler on Ω that can be saved
    /// with `build --out` and loaded with `--set`).
    AdaptiveSet {
        /// The partition-sampler scheme of its trees.
        variant: Variant,
        /// Whether it mixes the two θ-neighbouring slices.
        mixture: bool,
    },
    /// Any other direction sampler of a BRDF.
    Direction {
        /// Where its samples may land.
        support: Support,
        /// Its constructor.
        build: DirectionBuild,
    },
    /// A direction sampler of a BRDF built by a closure (entries made at run time:
    /// [`SamplerEntry::direction`]); tested and studied exactly like [`Constructor::Direction`].
    SharedDirection {
        /// Where its samples may land.
        support: Support,
        /// Its constructor.
        build: SharedDirectionBuild,
    },
    /// A planar sampler on the unit disc for one `(BRDF, ωo)`.
    Disc(DiscBuild),
    /// A sampler of a lat-long environment map.
    EnvMap(EnvMapBuild),
    /// A sampler of a piecewise-constant grid.
    Grid(GridBuild),
}

impl Constructor {
    /// `direction`, `disc`, `envmap` or `grid`.
    pub fn kind(&self) -> &'static str {
        match self {
            Constructor::AdaptiveSet { .. }
            | Constructor::Direction { .. }
            | Constructor::SharedDirection { .. } => "direction",
            Constructor::Disc(_) => "disc",
            Constructor::EnvMap(_) => "envmap",
            Constructor::Grid(_) => "grid",
        }
    }

    /// Where a direction sampler's samples land (`None` for the planar kinds).
    pub fn support(&self) -> Option<Support> {
        match self {
            Constructor::AdaptiveSet { .. } => Some(Support::Hemisphere),
            Constructor::Direction { support, .. }
            | Constructor::SharedDirection { support, .. } => Some(*support),
            _ => None,
        }
    }
}

/// One registered sampler.
#[derive(Clone)]
pub struct SamplerEntry {
    /// The name given to `--sampler`.
    pub name: &'static str,
    /// One-line description.
    pub summary: &'static str,
    /// What it can do.
    pub capabilities: Capabilities,
    /// How it is built.
    pub constructor: Constructor,
    /// Its options (`--NAME VALUE` on the command line; each sets a field of
    /// [`baselines::BaselineOptions`]); empty for none.
    pub options: &'static [OptionSpec],
    /// Checks its options together once set (`Err((option name or "", reason))`), e.g. a
    /// bound below another; `None`: the ranges of [`Self::options`] say it all.
    pub check: Option<OptionCheck>,
    /// The BRDFs it applies to (`Err(reason)` for the others: a format- or model-specific
    /// sampler); `None`: every BRDF of its kind. See [`Self::applicability`].
    pub applies_to: Option<AppliesTo>,
    /// Its place in the studies' presets and their palette (`study::PREFERRED_SAMPLERS`, the
    /// plots' colour and marker): a stable index, unique over the registry; `None` keeps the
    /// sampler out of the presets.
    pub study: Option<u8>,
}

/// Checks a sampler's options together ([`SamplerEntry::check`]): `Err((option, reason))`,
/// `option` the option's name or `""` when the reason concerns several.
pub type OptionCheck = fn(&baselines::BaselineOptions) -> Result<(), (&'static str, String)>;

/// Whether a sampler applies to a BRDF ([`SamplerEntry::applies_to`]): `Err(reason)` when not.
pub type AppliesTo = fn(&dyn Brdf) -> Result<(), String>;

impl std::fmt::Debug for SamplerEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SamplerEntry")
            .field("name", &self.name)
            .field("kind", &self.constructor.kind())
            .field("capabilities", &self.capabilities)
            .finish_non_exhaustive()
    }
}

/// One builder of a sampler kind other than `direction`: the entry's constructor of that kind
/// called with the arguments, or [`RegistryError::WrongKind`] for an entry of another kind.
macro_rules! typed_builder {
    ($(#[$doc:meta])* $name:ident($($arg:ident: $ty:ty),*) -> $out:ty = $variant:ident, $kind:literal) => {
        $(#[$doc])*
        pub fn $name(&self, $($arg: $ty),*) -> Result<$out, RegistryError> {
            match &self.constructor {
                Constructor::$variant(build) => build($($arg),*),
                other => Err(self.wrong_kind($kind, other.kind())),
            }
        }
    };
}

impl SamplerEntry {
    /// A direction sampler of a BRDF built by `build` (a closure, so it may capture state, e.g.
    /// a Python object), to add to a [`Registry`] with [`Registry::with`]. `build` gets the
    /// request (the BRDF, the options) and returns the sampler or its own error
    /// ([`RegistryError::User`]).
    ///
    /// ```
    /// use std::sync::Arc;
    /// use samplers::{Capabilities, Registry, SamplerEntry, Support};
    ///
    /// // A new name for the registry's cosine sampler, built by a closure.
    /// let entry = SamplerEntry::direction(
    ///     "my-cosine",
    ///     "cosine-weighted hemisphere, wrapped",
    ///     Capabilities { exact_pdf: true, ..Capabilities::default() },
    ///     Support::Hemisphere,
    ///     |request| Ok(samplers::build_direction("cosine", request)?.sampler),
    /// );
    /// let registry = Registry::builtin().with(entry);
    /// assert!(registry.find("my-cosine")?.is_direction());
    /// assert!(samplers::find("my-cosine").is_err()); // the built-in registry is unchanged
    /// # Ok::<(), samplers::RegistryError>(())
    /// ```
    pub fn direction<F>(
        name: &'static str,
        summary: &'static str,
        capabilities: Capabilities,
        support: Support,
        build: F,
    ) -> Self
    where
        F: Fn(&DirectionRequest<'_>) -> Result<Arc<dyn DirectionSampler>, UserError>
            + Send
            + Sync
            + 'static,
    {
        Self {
            name,
            summary,
            capabilities,
            options: &[],
            check: None,
            applies_to: None,
            study: None,
            constructor: Constructor::SharedDirection {
                support,
                build: Arc::new(move |request: &DirectionRequest<'_>| {
                    build(request)
                        .map(BuiltDirection::plain)
                        .map_err(|source| RegistryError::User { name, source })
                }),
            },
        }
    }

    /// Whether this is a direction sampler of a BRDF.
    pub fn is_direction(&self) -> bool {
        self.constructor.kind() == "direction"
    }

    /// Builds this entry's direction sampler for `request`.
    ///
    /// Errors: [`RegistryError::WrongKind`] if the entry is not a direction sampler,
    /// [`RegistryError::NotApplicable`] if it does not apply to the BRDF
    /// ([`Self::applicability`]), or the sampler's own build error.
    pub fn build_direction(
        &self,
        request: &DirectionRequest<'_>,
    ) -> Result<BuiltDirection, RegistryError> {
        if self.is_direction() {
            self.applicability(request.brdf.as_ref())?;
        }
        match &self.constructor {
            &Constructor::AdaptiveSet { variant, mixture } => {
                let options = brdf_sampling::SetOptions {
                    mixture: request.options.mixture || mixture,
                    ..*request.options
                };
                let set = QuadTreeSet::build_with_progress(
                    Arc::clone(&request.brdf),
                    variant,
                    &options,
                    request.progress,
                )?
                .with_spec(request.spec_or_name());
                Ok(BuiltDirection::from_set(set))
            }
            Constructor::Direction { build, .. } => {
                build(request).map_err(|source| match source.downcast::<RegistryError>() {
                    Ok(e) => *e,
                    Err(source) => RegistryError::User {
                        name: self.name,
                        source,
                    },
                })
            }
            Constructor::SharedDirection { build, .. } => build(request),
            other => Err(self.wrong_kind("direction", other.kind())),
        }
    }

    /// Whether this entry's sampler applies to `brdf`: `Err` with the reason for a
    /// format-specific sampler given a BRDF of another kind (`rgl-native`) or a model-specific
    /// one given a model it has nothing for (`analytic`); `Ok` for every other pair. Builds
    /// check it first ([`RegistryError::NotApplicable`]); the validation suite and the studies
    /// call it to skip such pairs and report the reason instead of a failed build.
    pub fn applicability(&self, brdf: &dyn Brdf) -> Result<(), NotApplicable> {
        match self.applies_to {
            Some(applies) => applies(brdf).map_err(|reason| NotApplicable {
                sampler: self.name,
                reason,
            }),
            None => Ok(()),
        }
    }

    typed_builder!(
        /// Builds this entry's disc sampler of `f_r(ωo, h⁻¹(x))`.
        build_disc(brdf: &Arc<dyn Brdf>, wo: &Vec3) -> DiscSampler = Disc, "disc"
    );

    typed_builder!(
        /// Builds this entry's environment-map sampler (`options` for the adaptive ones).
        build_envmap(map: &EnvMap, options: &AdaptiveOptions) -> EnvMapSampler = EnvMap, "envmap"
    );

    typed_builder!(
        /// Builds this entry's grid sampler.
        build_grid(width: usize, height: usize, values: Vec<f64>, domain: Rect) -> GridSampler = Grid, "grid"
    );

    fn wrong_kind(&self, expected: &'static str, found: &'static str) -> RegistryError {
        RegistryError::WrongKind {
            name: self.name,
            expected,
            found,
            candidates: names_of_kind(expected),
        }
    }
}

/// The samplers of the studies' presets, in their order ([`SamplerEntry::study`]).
pub fn study_samplers() -> Vec<&'static str> {
    let mut ranked: Vec<(u8, &'static str)> = SAMPLERS
        .iter()
        .filter_map(|e| e.study.map(|i| (i, e.name)))
        .collect();
    ranked.sort_unstable();
    ranked.into_iter().map(|(_, name)| name).collect()
}

/// Every registered sampler, in listing order.
pub fn samplers() -> &'static [SamplerEntry] {
    SAMPLERS
}

/// The names of the samplers of one kind (`direction`, `disc`, `envmap`, `grid`), comma-separated.
pub fn names_of_kind(kind: &str) -> String {
    names_of_kind_in(SAMPLERS, kind)
}

pub(crate) fn names_of_kind_in(entries: &[SamplerEntry], kind: &str) -> String {
    entries
        .iter()
        .filter(|e| e.constructor.kind() == kind)
        .map(|e| e.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The sampler called `name` (surrounding spaces ignored).
///
/// Errors: [`RegistryError::UnknownSampler`] listing every name, with the closest as a
/// suggestion.
pub fn find(name: &str) -> Result<&'static SamplerEntry, RegistryError> {
    let name = name.trim();
    SAMPLERS
        .iter()
        .find(|e| e.name == name)
        .ok_or_else(|| RegistryError::UnknownSampler {
            name: name.to_string(),
            suggestion: closest(name),
            known: SAMPLERS
                .iter()
                .map(|e| e.name)
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// Builds the direction sampler `name` (see [`SamplerEntry::build_direction`]).
pub fn build_direction(
    name: &str,
    request: &DirectionRequest<'_>,
) -> Result<BuiltDirection, RegistryError> {
    find(name)?.build_direction(request)
}

/// Reads a sampler saved by `build --out` ([`QuadTreeSet::to_bytes`], or
/// [`brdf_sampling::ExactSet::to_bytes`] for `adaptive-exact`, told apart by the magic) back, re-attached to
/// `brdf` (the BRDF of the stored spec when `None`), with the registry entry it was built as.
///
/// Errors: [`RegistryError::SetFile`] for a bad file or a BRDF that does not match it,
/// [`RegistryError::Brdf`] when the stored spec no longer parses.
pub fn load_set(
    bytes: &[u8],
    brdf: Option<(Arc<dyn Brdf>, &str)>,
) -> Result<(&'static SamplerEntry, BuiltDirection), RegistryError> {
    let exact = brdf_sampling::ExactSet::is_stored(bytes);
    let stored = if exact {
        brdf_sampling::ExactSet::stored_spec(bytes)?
    } else {
        QuadTreeSet::stored_spec(bytes)?
    };
    let (brdf, spec) = match brdf {
        Some((b, s)) => (b, s.to_string()),
        None => {
            let b = brdf::parse_spec(&stored).map_err(|source| RegistryError::Brdf {
                spec: stored.clone(),
                source,
            })?;
            (Arc::from(b), stored)
        }
    };
    if exact {
        let set = brdf_sampling::ExactSet::from_bytes(bytes, brdf, &spec)?;
        let entry = find("adaptive-exact")?;
        return Ok((entry, BuiltDirection::from_exact(set)));
    }
    let set = QuadTreeSet::from_bytes(bytes, brdf, &spec)?;
    let (variant, mixture) = (set.variant(), set.options().mixture);
    let entry = SAMPLERS
        .iter()
        .find(|e| {
            matches!(e.constructor, Constructor::AdaptiveSet { variant: v, mixture: m }
                if v == variant && m == mixture)
        })
        .ok_or(RegistryError::UnregisteredSet { variant, mixture })?;
    Ok((entry, BuiltDirection::from_set(set)))
}

/// The registered name closest to `name` (edit distance ≤ 3, or a name containing it).
fn closest(name: &str) -> Option<&'static str> {
    closest_in(SAMPLERS, name)
}

/// The name in `entries` closest to `name` (edit distance ≤ 3, or a name containing it).
pub(crate) fn closest_in(entries: &[SamplerEntry], name: &str) -> Option<&'static str> {
    let best = entries
        .iter()
        .map(|e| (edit_distance(name, e.name), e.name))
        .min()?;
    if best.0 <= 3 {
        return Some(best.1);
    }
    entries
        .iter()
        .map(|e| e.name)
        .find(|n| !name.is_empty() && n.contains(name))
}

/// Levenshtein distance (for suggestions only), from `strsim`.
fn edit_distance(a: &str, b: &str) -> usize {
    strsim::levenshtein(a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distance_counts_single_edits() {
        assert_eq!(edit_distance("adaptve", "adaptive"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("cosine", "cosine"), 0);
    }

    #[test]
    fn flags_list_the_capabilities() {
        let c = Capabilities {
            exact_pdf: true,
            batch_mode: false,
            needs_build: true,
            anisotropic: false,
            measured: true,
        };
        assert_eq!(c.flags(), "exact, build, measured");
    }
}
