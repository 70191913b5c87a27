//! Model registry and the `SPEC` parser (`name` or `name:key=value,...`, or `merl:PATH`).

use crate::brdf::Brdf;
use crate::measured::cornell::{CornellBrdf, CornellError, Interpolation};
use crate::measured::rgl::{RglBrdf, RglError};
use crate::merl::{MerlBrdf, MerlError};
use crate::models::*;
use crate::params::{ParamDefault, ParamError, ParamInfo, Range};
use std::path::Path;
use thiserror::Error;

/// Whether a model is isotropic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isotropy {
    /// Isotropic for every parameter value.
    Always,
    /// Never isotropic.
    Never,
    /// Isotropic for some parameter values (e.g. `alpha_x = alpha_y`), including the defaults.
    WhenParamsEqual,
}

type BuildFn = fn(&[f64]) -> Result<Box<dyn Brdf>, ParamError>;

/// How a registry entry is built: from its resolved parameter values, or only from a spec
/// argument (`NAME:PATH` for a measured format, `NAME:material=NAME` for a preset model).
#[derive(Clone, Copy)]
enum Build {
    Values(BuildFn),
    File,
    Preset,
}

/// A registry entry: everything `brdf-lab list` prints about a model, and how to build it.
#[derive(Debug, Clone, Copy)]
pub struct ModelInfo {
    /// Registry key (kebab-case), the `name` of a spec.
    pub name: &'static str,
    /// Other accepted names (e.g. the seed papers' short names).
    pub aliases: &'static [&'static str],
    /// One-line description with the reference.
    pub summary: &'static str,
    /// Parameters in canonical order.
    pub params: &'static [ParamInfo],
    /// Isotropy of the model.
    pub isotropic: Isotropy,
    build: Build,
}

/// The kind of build only (a function pointer's address says nothing to a reader).
impl std::fmt::Debug for Build {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Build::Values(_) => "Values",
            Build::File => "File",
            Build::Preset => "Preset",
        })
    }
}

impl ModelInfo {
    /// The entry of a model built from numeric parameters (what [`registry_entry!`] declares).
    pub(crate) const fn values(
        name: &'static str,
        aliases: &'static [&'static str],
        isotropic: Isotropy,
        params: &'static [ParamInfo],
        build: BuildFn,
        summary: &'static str,
    ) -> Self {
        Self {
            name,
            aliases,
            summary,
            params,
            isotropic,
            build: Build::Values(build),
        }
    }

    /// The entry of a model built only from a spec argument, `Build::File` (`NAME:PATH`) or
    /// `Build::Preset` (`NAME:material=NAME`); building it from values is a constraint error.
    const fn argument(name: &'static str, build: Build, summary: &'static str) -> Self {
        Self {
            name,
            aliases: &[],
            summary,
            params: &[],
            isotropic: Isotropy::Always,
            build,
        }
    }

    /// Build from values in table order (defaults already resolved).
    fn build_values(&self, values: &[f64]) -> Result<Box<dyn Brdf>, ParamError> {
        match self.build {
            Build::Values(build) => build(values),
            Build::File => Err(ParamError::Constraint {
                model: self.name,
                message: format!("needs a file: use the spec `{}:PATH`", self.name),
            }),
            Build::Preset => Err(ParamError::Constraint {
                model: self.name,
                message: format!(
                    "needs a material: use the spec `{}:material=NAME`",
                    self.name
                ),
            }),
        }
    }

    /// Build the model from `(key, value)` pairs; omitted keys take their defaults. Same checks
    /// as [`parse_spec`] (unknown key, duplicate key, range, constraints).
    pub fn build(&self, values: &[(&str, f64)]) -> Result<Box<dyn Brdf>, SpecError> {
        let mut given: Vec<Option<f64>> = vec![None; self.params.len()];
        for &(key, value) in values {
            let Some(i) = self.params.iter().position(|p| p.key == key) else {
                return Err(SpecError::UnknownKey {
                    model: self.name.to_string(),
                    key: key.to_string(),
                    valid: self.valid_keys(),
                });
            };
            if given[i].is_some() {
                return Err(SpecError::DuplicateKey {
                    model: self.name.to_string(),
                    key: key.to_string(),
                });
            }
            let p = &self.params[i];
            if !value.is_finite() {
                return Err(SpecError::BadNumber {
                    model: self.name.to_string(),
                    key: key.to_string(),
                    value: value.to_string(),
                });
            }
            if !p.range.contains(value) {
                return Err(SpecError::OutOfRange {
                    model: self.name.to_string(),
                    key: key.to_string(),
                    value,
                    range: p.range,
                });
            }
            given[i] = Some(value);
        }
        let resolved = self.resolve(&given);
        self.build_values(&resolved).map_err(SpecError::Invalid)
    }

    /// The values in table order: `given[i]` where set, else the key's default (a `SameAs`
    /// default follows the other key's given value or its default).
    fn resolve(&self, given: &[Option<f64>]) -> Vec<f64> {
        let mut resolved = vec![f64::NAN; self.params.len()];
        for (i, p) in self.params.iter().enumerate() {
            resolved[i] = match (given[i], p.default) {
                (Some(v), _) => v,
                (None, ParamDefault::Value(v)) => v,
                (None, ParamDefault::SameAs(k)) => {
                    let j = self.params.iter().position(|q| q.key == k);
                    match j.map(|j| (given[j], self.params[j].default)) {
                        Some((Some(v), _)) | Some((None, ParamDefault::Value(v))) => v,
                        _ => f64::NAN,
                    }
                }
            };
        }
        resolved
    }

    /// Whether the model is built from a spec argument (a file path such as `merl:PATH` or a
    /// preset name) rather than from numeric parameters: such models have no defaults to
    /// build from.
    pub fn needs_argument(&self) -> bool {
        !matches!(self.build, Build::Values(_))
    }

    /// Comma-separated list of the valid keys.
    pub fn valid_keys(&self) -> String {
        if self.params.is_empty() {
            return "(none)".to_string();
        }
        self.params
            .iter()
            .map(|p| p.key)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Why a spec could not be turned into a BRDF.
#[derive(Debug, Error)]
pub enum SpecError {
    /// The spec is empty.
    #[error("empty BRDF spec (expected `name` or `name:key=value,...`)")]
    Empty,
    /// No model has this name.
    #[error("unknown BRDF model `{name}`; known models: {known}")]
    UnknownModel {
        /// The name given.
        name: String,
        /// All registry keys.
        known: String,
    },
    /// The model has no such parameter.
    #[error("{model}: unknown parameter `{key}`; valid keys: {valid}")]
    UnknownKey {
        /// Model name.
        model: String,
        /// The key given.
        key: String,
        /// The model's keys.
        valid: String,
    },
    /// A parameter item is not of the form `key=value`.
    #[error("{model}: malformed parameter `{item}` (expected key=value)")]
    Malformed {
        /// Model name.
        model: String,
        /// The offending item.
        item: String,
    },
    /// The value is not a finite number.
    #[error("{model}: parameter `{key}` = `{value}` is not a finite number")]
    BadNumber {
        /// Model name.
        model: String,
        /// Key.
        key: String,
        /// The text given.
        value: String,
    },
    /// The value is outside the allowed range.
    #[error("{model}: parameter `{key}` = {value} is outside the allowed range {range}")]
    OutOfRange {
        /// Model name.
        model: String,
        /// Key.
        key: String,
        /// Value given.
        value: f64,
        /// Allowed range.
        range: Range,
    },
    /// The same key appears twice.
    #[error("{model}: parameter `{key}` given more than once")]
    DuplicateKey {
        /// Model name.
        model: String,
        /// Key.
        key: String,
    },
    /// `merl` without a path.
    #[error("merl: missing file path (expected `merl:PATH`)")]
    MissingPath,
    /// A file format (`rgl`, …) without a path.
    #[error("{model}: missing file path (expected `{model}:PATH`)")]
    MissingFile {
        /// The format's name.
        model: &'static str,
    },
    /// A cross-parameter constraint failed in the model constructor.
    #[error(transparent)]
    Invalid(#[from] ParamError),
    /// The MERL file could not be loaded.
    #[error(transparent)]
    Merl(#[from] MerlError),
    /// A preset model (`sgd`, `abc`) without `material=NAME`.
    #[error(
        "{model}: missing material (expected `{model}:material=NAME`; `brdf-lab list` shows the names)"
    )]
    MissingMaterial {
        /// The model.
        model: &'static str,
    },
    /// No preset of that name.
    #[error("{model}: unknown material `{name}`{}", if suggestions.is_empty() { "; `brdf-lab list` shows the names".to_string() } else { format!("; close matches: {}", suggestions.join(", ")) })]
    UnknownMaterial {
        /// The model.
        model: &'static str,
        /// The name given.
        name: String,
        /// Close preset names, best first.
        suggestions: Vec<String>,
    },
    /// The Cornell file could not be loaded.
    #[error("{source}")]
    Cornell {
        /// The path given.
        path: String,
        /// The cause.
        source: CornellError,
    },
    /// The RGL file could not be loaded.
    #[error("{source}")]
    Rgl {
        /// The path given.
        path: String,
        /// The cause.
        source: RglError,
    },
}

/// A built model as the registry hands it out.
pub(crate) fn boxed<B: Brdf + 'static, E>(built: Result<B, E>) -> Result<Box<dyn Brdf>, E> {
    built.map(|m| Box::new(m) as Box<dyn Brdf>)
}

/// Declare a model's registry entry once, in the model's file: its name (and the `$NAME`
/// constant holding it), aliases, isotropy, parameter table, builder (from values in table
/// order) and one-line summary. `$INFO` then goes in the registry's list (one line a model).
///
/// `registry_entry! { INFO: NAME = "phong", ["modified-phong"], Always, PARAMS,
/// |v| Phong::from_values(v), "summary" }`
macro_rules! registry_entry {
    ($INFO:ident: $NAME:ident = $name:literal, [$($alias:literal),*], $iso:ident, $params:expr,
     $build:expr, $summary:literal $(,)?) => {
        pub(crate) const $NAME: &str = $name;
        pub(crate) const $INFO: $crate::registry::ModelInfo = $crate::registry::ModelInfo::values(
            $NAME,
            &[$($alias),*],
            $crate::registry::Isotropy::$iso,
            $params,
            |v| $crate::registry::boxed($build(v)),
            $summary,
        );
    };
}
pub(crate) use registry_entry;

/// The one declaration of a model built from its parameters alone: its parameters
/// ([`model_params!`](crate::params)), the scaffolding ([`model_common!`](crate::params)) and its registry entry
/// ([`registry_entry!`](crate::registry)) from one list:
///
/// ```text
/// model! {
///     /// Parameters of [`Phong`].
///     pub struct PhongParams in PARAMS for Phong {
///         n = [50.0] in Range::closed(0.0, 1e5), "specular exponent";
///     }
///     registry INFO: NAME = "phong", ["modified-phong"], Always, "summary for `list`";
/// }
/// ```
///
/// The model itself then writes its struct, `new` (with `params.validate(NAME)?`), `properties`
/// and its `Brdf` impl (with `brdf_properties!(NAME)`).
///
/// A model whose struct is its parameters plus constants derived from them (the usual case)
/// declares that struct in the same list instead of `for Model`: its `new` (validate, then the
/// `let`s and the fields in order, each field a local the later ones may use) is generated.
///
/// ```text
/// model! {
///     /// Parameters of [`Phong`].
///     pub struct PhongParams in PARAMS { n = [50.0] in Range::closed(0.0, 1e5), "…"; }
///     registry INFO: NAME = "phong", ["modified-phong"], Always, "summary for `list`";
///     /// Modified Phong BRDF.
///     pub struct Phong(params) {
///         let scale = (params.n + 2.0) / (2.0 * PI);
///         spec_scale: f64 = params.ks * scale,
///     }
/// }
/// ```
macro_rules! model {
    (
        $(#[$meta:meta])*
        pub struct $Params:ident in $TABLE:ident for $Model:ident { $($fields:tt)+ }
        registry $INFO:ident: $NAME:ident = $name:literal, [$($alias:literal),*], $iso:ident,
            $summary:literal;
    ) => {
        $crate::params::model_params! {
            $(#[$meta])*
            pub struct $Params in $TABLE { $($fields)+ }
        }
        $crate::params::model_common!($Model($Params));
        $crate::registry::registry_entry! {
            $INFO: $NAME = $name, [$($alias),*], $iso, $TABLE, $Model::from_values, $summary
        }
    };
    (
        $(#[$meta:meta])*
        pub struct $Params:ident in $TABLE:ident { $($fields:tt)+ }
        registry $INFO:ident: $NAME:ident = $name:literal, [$($alias:literal),*], $iso:ident,
            $summary:literal;
        $(#[$model_meta:meta])*
        pub struct $Model:ident($p:ident) { $($body:tt)+ }
    ) => {
        $crate::registry::model! {
            $(#[$meta])*
            pub struct $Params in $TABLE for $Model { $($fields)+ }
            registry $INFO: $NAME = $name, [$($alias),*], $iso, $summary;
        }
        $crate::registry::model!(
            @struct [$(#[$model_meta])*] $Model($p: $Params) $NAME [] $($body)+
        );
    };
    // The `let`s of the body, collected one by one before the fields.
    (@struct $attrs:tt $Model:ident($p:ident: $Params:ident) $NAME:ident [$($stmt:tt)*]
        let $local:pat = $value:expr; $($rest:tt)+
    ) => {
        $crate::registry::model!(
            @struct $attrs $Model($p: $Params) $NAME [$($stmt)* let $local = $value;] $($rest)+
        );
    };
    (@struct [$($attr:tt)*] $Model:ident($p:ident: $Params:ident) $NAME:ident [$($stmt:tt)*]
        $( $(#[$field_meta:meta])* $field:ident: $Field:ty = $init:expr ),+ $(,)?
    ) => {
        $($attr)*
        #[derive(Debug, Clone)]
        pub struct $Model {
            params: $Params,
            $( $(#[$field_meta])* $field: $Field, )+
        }

        impl $Model {
            /// Validate the parameters and build the model.
            pub fn new($p: $Params) -> Result<Self, $crate::params::ParamError> {
                $p.validate($NAME)?;
                $($stmt)*
                $( let $field: $Field = $init; )+
                Ok(Self { params: $p, $($field),+ })
            }
        }
    };
}
pub(crate) use model;

static MODELS: &[ModelInfo] = &[
    lambert::INFO,
    phong::INFO,
    blinn::INFO,
    lewis::INFO,
    lafortune::INFO,
    ward::INFO,
    ward::INFO_ORIGINAL,
    ashikhmin_shirley::INFO,
    cook_torrance::INFO,
    microfacet::INFO_BECKMANN,
    microfacet::INFO_GGX,
    oren_nayar::INFO,
    minnaert::INFO,
    strauss::INFO,
    schlick::INFO_DIFFUSE,
    schlick::INFO_SPECULAR,
    htsg::INFO,
    poulin_fournier::INFO,
    beard_maxwell::INFO,
    coupled::INFO,
    ModelInfo::argument(
        "merl",
        Build::File,
        "measured isotropic BRDF, spec `merl:PATH` (Matusik et al. 2003 binary format)",
    ),
    ModelInfo::argument(
        "rgl",
        Build::File,
        "measured isotropic RGB material of the RGL database, spec `rgl:PATH` (Dupuy & Jakob 2018 `.bsdf` tensor file)",
    ),
    ModelInfo::argument(
        "cornell",
        Build::File,
        "measured spectral material of Cornell PCG, spec `cornell:PATH[,interp=grid|knn]` (pbrt-v2 `.brdf` samples, CIE 1931 to RGB, k-nearest-neighbour interpolation in a reciprocal remapped space tabulated on a 64³ grid, trilinear between vertices (exact albedo); `interp=knn` evaluates the kNN interpolant at every query)",
    ),
    ModelInfo::argument(
        "sgd",
        Build::Preset,
        "Shifted Gamma Distribution model with the published fit of a MERL material, spec `sgd:material=NAME` (Bagher, Soler & Holzschuch 2012)",
    ),
    ModelInfo::argument(
        "abc",
        Build::Preset,
        "ABC model with the published fit of a MERL material, spec `abc:material=NAME` (Low, Kronander, Ynnerman & Unger 2012)",
    ),
];

/// The trimmed `PATH` of a `NAME:PATH` spec, or `missing` when there is none.
fn file_path(rest: Option<&str>, missing: SpecError) -> Result<&str, SpecError> {
    match rest.map(str::trim) {
        Some(path) if !path.is_empty() => Ok(path),
        _ => Err(missing),
    }
}

/// The preset names of a preset model (`sgd`, `abc`), `None` for other models.
pub fn preset_names(model: &str) -> Option<Vec<&'static str>> {
    match model {
        "sgd" => Some(sgd::FITS.names()),
        "abc" => Some(abc::FITS.names()),
        _ => None,
    }
}

/// `sgd:material=NAME` / `abc:material=NAME`.
fn parse_preset(model: &'static str, rest: Option<&str>) -> Result<Box<dyn Brdf>, SpecError> {
    let rest = rest.map(str::trim).unwrap_or("");
    if rest.is_empty() {
        return Err(SpecError::MissingMaterial { model });
    }
    let Some((key, name)) = rest.split_once('=') else {
        return Err(SpecError::Malformed {
            model: model.to_string(),
            item: rest.to_string(),
        });
    };
    if key.trim() != "material" {
        return Err(SpecError::UnknownKey {
            model: model.to_string(),
            key: key.trim().to_string(),
            valid: "material".to_string(),
        });
    }
    let name = name.trim();
    let built: Option<Box<dyn Brdf>> = match model {
        "sgd" => Sgd::preset(name).map(|b| Box::new(b) as Box<dyn Brdf>),
        _ => Abc::preset(name).map(|b| Box::new(b) as Box<dyn Brdf>),
    };
    built.ok_or_else(|| SpecError::UnknownMaterial {
        model,
        name: name.to_string(),
        suggestions: match model {
            "sgd" => sgd::FITS.close_matches(name),
            _ => abc::FITS.close_matches(name),
        },
    })
}

/// The 16 analytic models of the seed papers (seed 003 §1 and Table 2), by registry name.
pub const SEED_003_MODELS: [&str; 16] = [
    "ashikhmin-shirley",
    "beard-maxwell",
    "blinn",
    "coupled",
    "htsg",
    "lafortune",
    "lewis",
    "minnaert",
    "oren-nayar",
    "phong",
    "poulin-fournier",
    "schlick-diffuse",
    "schlick-specular",
    "strauss",
    "cook-torrance",
    "ward",
];

/// All registered models (analytic ones, then the measured formats), in listing order.
pub fn models() -> &'static [ModelInfo] {
    MODELS
}

/// Look a model up by name or alias (ASCII case-insensitive).
pub fn find_model(name: &str) -> Option<&'static ModelInfo> {
    MODELS.iter().find(|m| {
        m.name.eq_ignore_ascii_case(name) || m.aliases.iter().any(|a| a.eq_ignore_ascii_case(name))
    })
}

/// Parse a BRDF spec and build the model.
///
/// Grammar: `name` | `name:key=value(,key=value)*` | `merl:PATH` | `rgl:PATH` | `cornell:PATH` |
/// `cornell:PATH,interp=knn|grid` | `sgd:material=NAME` | `abc:material=NAME`. Whitespace around names,
/// keys and values is ignored; model names are case-insensitive; omitted keys take their
/// defaults. Errors are typed ([`SpecError`]): unknown model, unknown key (listing the valid
/// keys), malformed item, bad number, out-of-range value (stating the range), duplicate key,
/// constraint violations, MERL load failures.
pub fn parse_spec(spec: &str) -> Result<Box<dyn Brdf>, SpecError> {
    let spec = spec.trim();
    if spec.is_empty() {
        return Err(SpecError::Empty);
    }
    let (name, rest) = match spec.split_once(':') {
        Some((n, r)) => (n.trim(), Some(r)),
        None => (spec, None),
    };
    if name.eq_ignore_ascii_case("merl") {
        let path = file_path(rest, SpecError::MissingPath)?;
        return Ok(Box::new(MerlBrdf::load(Path::new(path))?));
    }
    if name.eq_ignore_ascii_case("rgl") {
        let path = file_path(rest, SpecError::MissingFile { model: "rgl" })?;
        return boxed(RglBrdf::load(Path::new(path))).map_err(|source| SpecError::Rgl {
            path: path.to_string(),
            source,
        });
    }
    if name.eq_ignore_ascii_case("cornell") {
        let path = file_path(rest, SpecError::MissingFile { model: "cornell" })?;
        // `cornell:PATH,interp=grid|knn` (the tabulated interpolant by default).
        let (path, interp) = match path.rsplit_once(",interp=") {
            Some((p, "knn")) => (p, Some(Interpolation::Knn)),
            Some((p, "grid")) => (p, Some(Interpolation::Grid)),
            Some((_, other)) => {
                return Err(SpecError::Malformed {
                    model: "cornell".to_string(),
                    item: format!("interp={other} (knn or grid)"),
                });
            }
            None => (path, None),
        };
        let b = CornellBrdf::load(Path::new(path)).map_err(|source| SpecError::Cornell {
            path: path.to_string(),
            source,
        })?;
        return Ok(Box::new(match interp {
            Some(i) => b.with_interpolation(i),
            None => b,
        }));
    }
    if name.eq_ignore_ascii_case("sgd") {
        return parse_preset("sgd", rest);
    }
    if name.eq_ignore_ascii_case("abc") {
        return parse_preset("abc", rest);
    }
    let Some(info) = find_model(name) else {
        return Err(SpecError::UnknownModel {
            name: name.to_string(),
            known: MODELS.iter().map(|m| m.name).collect::<Vec<_>>().join(", "),
        });
    };
    let mut values: Vec<(&str, f64)> = Vec::new();
    if let Some(rest) = rest {
        let rest = rest.trim();
        if !rest.is_empty() {
            for item in rest.split(',') {
                let Some((key, text)) = item.split_once('=') else {
                    return Err(SpecError::Malformed {
                        model: info.name.to_string(),
                        item: item.trim().to_string(),
                    });
                };
                let (key, text) = (key.trim(), text.trim());
                if key.is_empty() {
                    return Err(SpecError::Malformed {
                        model: info.name.to_string(),
                        item: item.trim().to_string(),
                    });
                }
                if !info.params.iter().any(|p| p.key == key) {
                    return Err(SpecError::UnknownKey {
                        model: info.name.to_string(),
                        key: key.to_string(),
                        valid: info.valid_keys(),
                    });
                }
                let value = match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => v,
                    _ => {
                        return Err(SpecError::BadNumber {
                            model: info.name.to_string(),
                            key: key.to_string(),
                            value: text.to_string(),
                        });
                    }
                };
                values.push((key, value));
            }
        }
    }
    info.build(&values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::Properties;

    /// Values just inside a range (closed ends, the midpoint) and just outside it (an open end
    /// itself, or one unit beyond a closed end).
    fn probes(r: Range) -> (Vec<f64>, Vec<f64>) {
        let (lo, hi) = (r.min.max(-1e3), r.max.min(1e3));
        let mut inside = vec![0.5 * (lo + hi)];
        let mut outside = Vec::new();
        if r.min_open {
            outside.push(r.min);
        } else {
            inside.push(r.min);
            outside.push(r.min - 1.0);
        }
        if r.max_open {
            outside.push(r.max);
        } else {
            inside.push(r.max);
            outside.push(r.max + 1.0);
        }
        (
            inside,
            outside.into_iter().filter(|x| x.is_finite()).collect(),
        )
    }

    /// Every parametric model's declared table (keys, ranges) is the one its constructor checks,
    /// and its declared flags agree with the registry's isotropy and with each other, at the
    /// defaults and with each parameter moved to the ends of its range.
    #[test]
    fn declared_ranges_and_flags_round_trip_through_the_registry() {
        for m in models().iter().filter(|m| !m.needs_argument()) {
            let defaults = m.resolve(&vec![None; m.params.len()]);
            let mut anisotropic_seen = false;
            let mut built = 0;
            for (i, p) in m.params.iter().enumerate() {
                let (inside, outside) = probes(p.range);
                for v in outside {
                    let mut values = defaults.clone();
                    values[i] = v;
                    match m.build_values(&values) {
                        Err(ParamError::OutOfRange {
                            model,
                            key,
                            value,
                            range,
                        }) => {
                            assert_eq!((model, key, range), (m.name, p.key, p.range));
                            assert_eq!(value.to_bits(), v.to_bits());
                        }
                        other => panic!(
                            "{} {}={v}: expected OutOfRange, got {:?}",
                            m.name,
                            p.key,
                            other.map(|b| b.name().to_string())
                        ),
                    }
                    let spec = format!("{}:{}={v:?}", m.name, p.key);
                    assert!(
                        matches!(parse_spec(&spec), Err(SpecError::OutOfRange { .. })),
                        "{spec}"
                    );
                }
                for v in inside {
                    let mut values = defaults.clone();
                    values[i] = v;
                    let b = match m.build_values(&values) {
                        Ok(b) => b,
                        // A cross-parameter constraint (e.g. Beard–Maxwell's R(0) > 0).
                        Err(ParamError::Constraint { .. }) => continue,
                        Err(e) => panic!("{} {}={v}: {e}", m.name, p.key),
                    };
                    built += 1;
                    assert_eq!(b.name(), m.name);
                    let f = Properties::of(&*b);
                    if f.contains(Properties::ISOTROPIC) {
                        assert!(f.contains(Properties::HALF_TURN_SYMMETRIC), "{}", m.name);
                    }
                    if f.contains(Properties::MIRROR_SYMMETRIC) {
                        assert!(f.contains(Properties::ISOTROPIC), "{}", m.name);
                    }
                    let iso = f.contains(Properties::ISOTROPIC);
                    anisotropic_seen |= !iso;
                    match m.isotropic {
                        Isotropy::Always => assert!(iso, "{} {}={v}", m.name, p.key),
                        Isotropy::Never => assert!(!iso, "{} {}={v}", m.name, p.key),
                        Isotropy::WhenParamsEqual => {}
                    }
                }
            }
            assert!(built > 0, "{}", m.name);
            let b = m
                .build_values(&defaults)
                .unwrap_or_else(|e| panic!("{}: {e}", m.name));
            let at_defaults = Properties::of(&*b).contains(Properties::ISOTROPIC);
            match m.isotropic {
                Isotropy::WhenParamsEqual => {
                    assert!(at_defaults && anisotropic_seen, "{}", m.name)
                }
                Isotropy::Always => assert!(at_defaults && !anisotropic_seen, "{}", m.name),
                Isotropy::Never => assert!(!at_defaults, "{}", m.name),
            }
        }
    }

    #[test]
    fn every_model_builds_from_defaults() {
        for m in models().iter().filter(|m| !m.needs_argument()) {
            let b = parse_spec(m.name).unwrap_or_else(|e| panic!("{}: {e}", m.name));
            assert_eq!(b.name(), m.name);
            match m.isotropic {
                Isotropy::Always | Isotropy::WhenParamsEqual => {
                    assert!(b.is_isotropic(), "{}", m.name)
                }
                Isotropy::Never => assert!(!b.is_isotropic(), "{}", m.name),
            }
            for a in m.aliases {
                assert_eq!(
                    parse_spec(a).map(|b| b.name().to_string()).ok().as_deref(),
                    Some(m.name)
                );
            }
        }
    }

    #[test]
    fn names_are_unique_kebab_case() {
        let mut all: Vec<&str> = Vec::new();
        for m in models() {
            assert!(
                m.name.chars().all(|c| c.is_ascii_lowercase() || c == '-'),
                "{}",
                m.name
            );
            all.push(m.name);
            all.extend(m.aliases.iter());
            for p in m.params {
                assert!(p.range.contains(match p.default {
                    ParamDefault::Value(v) => v,
                    ParamDefault::SameAs(k) => match m.params.iter().find(|q| q.key == k) {
                        Some(ParamInfo {
                            default: ParamDefault::Value(v),
                            ..
                        }) => *v,
                        _ => panic!("{}: bad SameAs", m.name),
                    },
                }));
            }
        }
        let n = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), n, "duplicate names or aliases");
    }
}
