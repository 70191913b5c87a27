//! Parameter descriptions (key, default, allowed range) shared by the model constructors and the
//! spec parser, and the typed error for invalid parameters.

use std::fmt;
use thiserror::Error;

/// Allowed interval of a real parameter. Bounds may be open or closed; `±∞` means unbounded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// Whether `min` itself is excluded.
    pub min_open: bool,
    /// Whether `max` itself is excluded.
    pub max_open: bool,
}

impl Range {
    /// Closed interval `[min, max]`.
    pub const fn closed(min: f64, max: f64) -> Self {
        Self {
            min,
            max,
            min_open: false,
            max_open: false,
        }
    }

    /// Half-open interval `(min, max]`.
    pub const fn left_open(min: f64, max: f64) -> Self {
        Self {
            min,
            max,
            min_open: true,
            max_open: false,
        }
    }

    /// True when `x` is finite and inside the interval (NaN is never inside).
    pub fn contains(&self, x: f64) -> bool {
        if !x.is_finite() {
            return false;
        }
        let lo = if self.min_open {
            x > self.min
        } else {
            x >= self.min
        };
        let hi = if self.max_open {
            x < self.max
        } else {
            x <= self.max
        };
        lo && hi
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}{}, {}{}",
            if self.min_open { '(' } else { '[' },
            self.min,
            self.max,
            if self.max_open { ')' } else { ']' }
        )
    }
}

/// Default value of a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParamDefault {
    /// A fixed number.
    Value(f64),
    /// The (possibly user-given) value of another key of the same model, e.g. `alpha_y = alpha`.
    SameAs(&'static str),
}

impl fmt::Display for ParamDefault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamDefault::Value(v) => write!(f, "{v}"),
            ParamDefault::SameAs(k) => write!(f, "={k}"),
        }
    }
}

/// One model parameter as listed by `brdf-lab list` and accepted in a spec.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamInfo {
    /// Spec key (snake_case).
    pub key: &'static str,
    /// Default when the key is omitted.
    pub default: ParamDefault,
    /// Allowed values.
    pub range: Range,
    /// One-line meaning, with units.
    pub doc: &'static str,
}

/// A model parameter outside its allowed range, or a violated cross-parameter constraint.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ParamError {
    /// A single parameter lies outside its allowed range (or is NaN/∞).
    #[error("{model}: parameter `{key}` = {value} is outside the allowed range {range}")]
    OutOfRange {
        /// Model name.
        model: &'static str,
        /// Parameter key.
        key: &'static str,
        /// Offending value.
        value: f64,
        /// Allowed range.
        range: Range,
    },
    /// A constraint linking several parameters is violated.
    #[error("{model}: {message}")]
    Constraint {
        /// Model name.
        model: &'static str,
        /// Which invariant is broken.
        message: String,
    },
}

/// Check `values[i]` against `params[i].range` for every `i`.
pub(crate) fn validate(
    model: &'static str,
    params: &[ParamInfo],
    values: &[f64],
) -> Result<(), ParamError> {
    for (p, &v) in params.iter().zip(values) {
        if !p.range.contains(v) {
            return Err(ParamError::OutOfRange {
                model,
                key: p.key,
                value: v,
                range: p.range,
            });
        }
    }
    Ok(())
}

/// Check one value by key (used when a struct field is validated individually).
pub(crate) fn validate_key(
    model: &'static str,
    params: &[ParamInfo],
    key: &str,
    value: f64,
) -> Result<(), ParamError> {
    match params.iter().find(|p| p.key == key) {
        Some(p) if !p.range.contains(value) => Err(ParamError::OutOfRange {
            model,
            key: p.key,
            value,
            range: p.range,
        }),
        _ => Ok(()),
    }
}

/// Resolve the defaults of a parameter table into a fixed-size array (in table order).
pub(crate) fn defaults<const N: usize>(params: &[ParamInfo]) -> [f64; N] {
    let mut out = [f64::NAN; N];
    // Two passes so `SameAs` may point forwards or backwards.
    for (slot, p) in out.iter_mut().zip(params) {
        if let ParamDefault::Value(v) = p.default {
            *slot = v;
        }
    }
    for i in 0..N.min(params.len()) {
        if let ParamDefault::SameAs(k) = params[i].default
            && let Some(j) = params.iter().position(|q| q.key == k)
        {
            out[i] = out[j];
        }
    }
    out
}

/// Shorthand for a `ParamInfo` with a fixed default.
pub(crate) const fn param(
    key: &'static str,
    default: f64,
    range: Range,
    doc: &'static str,
) -> ParamInfo {
    ParamInfo {
        key,
        default: ParamDefault::Value(default),
        range,
        doc,
    }
}

/// Declare a model's parameters once: the spec table (`$TABLE`, in canonical order), the
/// parameter struct (one `f64` field a key), its `Default` (the table's defaults), and the
/// conversions the constructors and the registry use (`values`, `from_values`, `validate`).
///
/// A field reads `name [as "key"] = [default] in range, "doc";` where `default` is a number or
/// `same_as other_key`; the spec key is the field name unless `as "key"` gives another. The
/// field's doc comment is generated from the same key, doc string, default and range (extra
/// `///` lines before a field are appended to it).
macro_rules! model_params {
    (
        $(#[$meta:meta])*
        pub struct $Params:ident in $TABLE:ident {
            $(
                $(#[$fmeta:meta])*
                $field:ident $(as $key:literal)? = [$($def:tt)+] in $range:expr, $doc:literal;
            )+
        }
    ) => {
        pub(crate) const $TABLE: &[$crate::params::ParamInfo] = &[
            $(
                $crate::params::ParamInfo {
                    key: $crate::params::model_params!(@key $field $($key)?),
                    default: $crate::params::model_params!(@default $($def)+),
                    range: $range,
                    doc: $doc,
                },
            )+
        ];

        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub struct $Params {
            $(
                #[doc = concat!(
                    "Key `", $crate::params::model_params!(@key $field $($key)?), "`: ", $doc,
                    " (default `", stringify!($($def)+), "`, allowed `", stringify!($range), "`)."
                )]
                $(#[$fmeta])*
                pub $field: f64,
            )+
        }

        impl Default for $Params {
            fn default() -> Self {
                let [$($field),+] = $crate::params::defaults($TABLE);
                Self { $($field),+ }
            }
        }

        #[allow(dead_code)]
        impl $Params {
            /// The values in table order.
            pub(crate) fn values(&self) -> [f64; $TABLE.len()] {
                [$(self.$field),+]
            }

            /// From values in table order; missing ones become NaN, which validation rejects.
            pub(crate) fn from_values(v: &[f64]) -> Self {
                let [$($field),+] = $crate::params::take(v);
                Self { $($field),+ }
            }

            /// Check every value against the table's range, reporting errors as `model`.
            pub(crate) fn validate(&self, model: &'static str) -> Result<(), $crate::params::ParamError> {
                $crate::params::validate(model, $TABLE, &self.values())
            }
        }
    };
    (@key $field:ident) => { stringify!($field) };
    (@key $field:ident $key:literal) => { $key };
    (@default same_as $other:ident) => {
        $crate::params::ParamDefault::SameAs(stringify!($other))
    };
    (@default $v:expr) => { $crate::params::ParamDefault::Value($v) };
}
pub(crate) use model_params;

/// The scaffolding every parametric model shares, from its parameter struct: `params()`,
/// `from_values` (the registry's builder) and `Default` (built from the default parameters).
/// Models with a variant argument (`Ward`'s normalisation, `Microfacet`'s distribution) name
/// it, with its default when the model has a `Default`:
/// `model_common!(Ward(WardParams, norm: WardNormalisation = …))`.
macro_rules! model_common {
    ($Model:ident($Params:ident)) => {
        $crate::params::model_common!(@impl $Model($Params));
        $crate::params::default_from!($Model = Self::new($Params::default()));
    };
    ($Model:ident($Params:ident, $arg:ident : $Arg:ty = $arg_default:expr)) => {
        $crate::params::model_common!(@impl $Model($Params, $arg: $Arg));
        $crate::params::default_from!($Model = Self::new($Params::default(), $arg_default));
    };
    ($Model:ident($Params:ident, $arg:ident : $Arg:ty)) => {
        $crate::params::model_common!(@impl $Model($Params, $arg: $Arg));
    };
    (@impl $Model:ident($Params:ident $(, $arg:ident : $Arg:ty)?)) => {
        impl $Model {
            /// The parameters this model was built with.
            pub fn params(&self) -> &$Params {
                &self.params
            }

            #[allow(dead_code)]
            pub(crate) fn from_values(
                v: &[f64]
                $(, $arg: $Arg)?
            ) -> Result<Self, $crate::params::ParamError> {
                Self::new($Params::from_values(v) $(, $arg)?)
            }
        }
    };
}
pub(crate) use model_common;

/// `impl Default for $Model` from a constructor call on built-in defaults
/// (`default_from!(Model = Self::new(…))`), unwrapped by [`expect_default`].
macro_rules! default_from {
    ($Model:ident = $build:expr) => {
        impl Default for $Model {
            fn default() -> Self {
                $crate::params::expect_default($build)
            }
        }
    };
}
pub(crate) use default_from;

/// Unwrap a model built from its built-in defaults. The defaults are constants checked by the
/// unit tests, so an error here is a bug in this crate, never a consequence of user input.
pub(crate) fn expect_default<T>(r: Result<T, ParamError>) -> T {
    match r {
        Ok(v) => v,
        Err(e) => panic!("built-in default parameters are invalid: {e}"),
    }
}

/// Copy the first `N` values (missing ones become NaN, which validation rejects).
pub(crate) fn take<const N: usize>(v: &[f64]) -> [f64; N] {
    let mut out = [f64::NAN; N];
    for (o, x) in out.iter_mut().zip(v) {
        *o = *x;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_membership_and_display() {
        let r = Range::left_open(0.0, 1.0);
        assert!(!r.contains(0.0));
        assert!(r.contains(1.0));
        assert!(!r.contains(f64::NAN));
        assert!(!r.contains(f64::INFINITY));
        assert_eq!(r.to_string(), "(0, 1]");
        assert_eq!(Range::closed(0.0, 2.5).to_string(), "[0, 2.5]");
    }

    #[test]
    fn defaults_resolve_same_as() {
        const P: &[ParamInfo] = &[
            ParamInfo {
                key: "b",
                default: ParamDefault::SameAs("a"),
                range: Range::closed(0.0, 1.0),
                doc: "",
            },
            param("a", 0.25, Range::closed(0.0, 1.0), ""),
        ];
        assert_eq!(defaults::<2>(P), [0.25, 0.25]);
        assert!(validate("m", P, &[0.5, 2.0]).is_err());
        assert!(validate("m", P, &[0.5, 0.5]).is_ok());
    }
}
