//! The options a sampler entry carries ([`OptionSpec`]): name, help, range and the field of
//! [`BaselineOptions`] each one sets. The command line builds its sampler flags from them
//! (`--NAME VALUE`), says which samplers a flag configures, and reports a value out of range
//! with the range; [`options_from`] turns `(name, text)` pairs into checked options.

use baselines::BaselineOptions;

use crate::{OptionError, RegistryError, SamplerEntry};

/// One end of a real interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum End {
    /// The end belongs to the interval.
    Closed(f64),
    /// The end does not belong to the interval.
    Open(f64),
    /// No bound on this side (finite values only).
    None,
}

/// The values an option takes, and the field of [`BaselineOptions`] a value sets.
#[derive(Debug, Clone, Copy)]
pub enum OptionKind {
    /// An integer in `min ..= max`.
    Int {
        /// Smallest value.
        min: u64,
        /// Largest value.
        max: u64,
        /// Sets the field.
        set: fn(&mut BaselineOptions, u64),
    },
    /// A finite real in the interval `(lo, hi)` (ends open or closed).
    Real {
        /// Lower end.
        lo: End,
        /// Upper end.
        hi: End,
        /// Sets the field.
        set: fn(&mut BaselineOptions, f64),
    },
    /// `N` integers in `min ..= max` written with `sep` between them (`16x32`, `4,4,8,4`).
    Ints {
        /// How many.
        count: usize,
        /// The separator (`x` also accepts `X`).
        sep: char,
        /// Smallest value of each.
        min: u64,
        /// Largest value of each.
        max: u64,
        /// Sets the field (`count` values).
        set: fn(&mut BaselineOptions, &[u64]),
    },
    /// Two finite reals `A,B` (checked together by the entry's [`SamplerEntry::check`]).
    RealPair {
        /// Sets the field.
        set: fn(&mut BaselineOptions, (f64, f64)),
    },
    /// One of a few names.
    Choice {
        /// The names, in help order.
        names: &'static [&'static str],
        /// Sets the field from the index of the name.
        set: fn(&mut BaselineOptions, usize),
    },
    /// A flag without a value: given means on.
    Switch {
        /// Sets the field.
        set: fn(&mut BaselineOptions),
    },
}

/// One option of a sampler entry (`--NAME VALUE` on the command line).
#[derive(Debug, Clone, Copy)]
pub struct OptionSpec {
    /// Its name (the flag without `--`), unique over the registry unless two entries share
    /// the very same option (e.g. the two CDF baselines).
    pub name: &'static str,
    /// What the value looks like in help (`N`, `NZxNPHI`); empty for a switch.
    pub value_name: &'static str,
    /// One-line help, with the range and the default.
    pub help: &'static str,
    /// Its values and the field it sets.
    pub kind: OptionKind,
}

/// The message of a real interval, e.g. `must be a finite number in [0, 90)`.
pub fn real_range(lo: End, hi: End) -> String {
    let bound = |e: End| match e {
        End::Closed(x) | End::Open(x) => x.to_string(),
        End::None => "±∞".to_string(),
    };
    match (lo, hi) {
        (End::None, End::None) => "must be a finite number".to_string(),
        (End::Closed(a), End::None) => format!("must be a finite number ≥ {a}"),
        (End::Open(a), End::None) => format!("must be a finite number > {a}"),
        (End::None, End::Closed(b)) => format!("must be a finite number ≤ {b}"),
        (End::None, End::Open(b)) => format!("must be a finite number < {b}"),
        (a, b) => {
            let left = match a {
                End::Closed(a) => format!("[{a}"),
                End::Open(_) | End::None => format!("({}", bound(a)),
            };
            let right = match b {
                End::Closed(b) => format!("{b}]"),
                End::Open(_) | End::None => format!("{})", bound(b)),
            };
            format!("must be a finite number in {left}, {right}")
        }
    }
}

/// Parses a finite real in the interval; the error is [`real_range`]'s message.
pub fn parse_real(s: &str, lo: End, hi: End) -> Result<f64, String> {
    let range = || real_range(lo, hi);
    let v: f64 = s.trim().parse().map_err(|_| range())?;
    let above = match lo {
        End::Closed(a) => v >= a,
        End::Open(a) => v > a,
        End::None => true,
    };
    let below = match hi {
        End::Closed(b) => v <= b,
        End::Open(b) => v < b,
        End::None => true,
    };
    if v.is_finite() && above && below {
        Ok(v)
    } else {
        Err(range())
    }
}

/// Parses an integer in `min ..= max`; the error names the range (`must be an integer in
/// 1 ..= 16`), also for a negative or non-integer value.
pub fn parse_int(s: &str, min: u64, max: u64) -> Result<u64, String> {
    let message = || format!("must be an integer in {min} ..= {max}");
    let v: i128 = s.trim().parse().map_err(|_| message())?;
    if v < i128::from(min) || v > i128::from(max) {
        return Err(message());
    }
    u64::try_from(v).map_err(|_| message())
}

impl OptionSpec {
    /// Parses `text` and sets the option's field of `options`.
    ///
    /// Errors: the reason, with the valid range (one line).
    pub fn apply(&self, text: &str, options: &mut BaselineOptions) -> Result<(), String> {
        match self.kind {
            OptionKind::Int { min, max, set } => set(options, parse_int(text, min, max)?),
            OptionKind::Real { lo, hi, set } => set(options, parse_real(text, lo, hi)?),
            OptionKind::Ints {
                count,
                sep,
                min,
                max,
                set,
            } => {
                let bad = || {
                    format!(
                        "expected {count} integers separated by `{sep}`, each in {min} ..= {max}"
                    )
                };
                let parts: Vec<&str> = if sep == 'x' {
                    text.split(['x', 'X']).collect()
                } else {
                    text.split(sep).collect()
                };
                if parts.len() != count {
                    return Err(bad());
                }
                let values = parts
                    .iter()
                    .map(|p| parse_int(p, min, max).map_err(|_| bad()))
                    .collect::<Result<Vec<u64>, String>>()?;
                set(options, &values);
            }
            OptionKind::RealPair { set } => {
                let bad = || "expected two finite numbers A,B".to_string();
                let (a, b) = text.split_once(',').ok_or_else(bad)?;
                let a = parse_real(a, End::None, End::None).map_err(|_| bad())?;
                let b = parse_real(b, End::None, End::None).map_err(|_| bad())?;
                set(options, (a, b));
            }
            OptionKind::Choice { names, set } => {
                let i = names
                    .iter()
                    .position(|n| *n == text.trim())
                    .ok_or_else(|| format!("expected one of {}", names.join(", ")))?;
                set(options, i);
            }
            OptionKind::Switch { set } => set(options),
        }
        Ok(())
    }

    /// Whether the option takes a value (every kind but [`OptionKind::Switch`]).
    pub fn takes_value(&self) -> bool {
        !matches!(self.kind, OptionKind::Switch { .. })
    }
}

/// The entries of `entries` whose options include the option called `name`, in listing order.
pub fn entries_with_option<'a>(
    entries: &'a [SamplerEntry],
    name: &str,
) -> impl Iterator<Item = &'a SamplerEntry> {
    let name = name.to_string();
    entries
        .iter()
        .filter(move |e| e.options.iter().any(|o| o.name == name))
}

/// Every distinct option of `entries` (by name, first occurrence), in listing order.
pub fn all_options(entries: &[SamplerEntry]) -> Vec<&'static OptionSpec> {
    let mut out: Vec<&'static OptionSpec> = Vec::new();
    for e in entries {
        for o in e.options {
            if !out.iter().any(|x| x.name == o.name) {
                out.push(o);
            }
        }
    }
    out
}

/// The baseline options of the `(name, text)` pairs given (the defaults for the rest), each
/// parsed by its entry's [`OptionSpec`], then every entry's [`SamplerEntry::check`] run.
///
/// Errors: [`RegistryError::Option`] naming the sampler, the option, the value and the reason
/// (unknown option: the known ones).
pub fn options_from(
    entries: &'static [SamplerEntry],
    given: &[(String, String)],
) -> Result<BaselineOptions, RegistryError> {
    let mut options = BaselineOptions::default();
    for (name, text) in given {
        let found = entries.iter().find_map(|e| {
            e.options
                .iter()
                .find(|o| o.name == name)
                .map(|o| (e.name, o))
        });
        let Some((sampler, spec)) = found else {
            let known: Vec<&str> = all_options(entries).iter().map(|o| o.name).collect();
            return Err(OptionError {
                sampler: "",
                option: "",
                value: text.clone(),
                reason: format!("unknown option `{name}`; options: {}", known.join(", ")),
            }
            .into());
        };
        spec.apply(text, &mut options)
            .map_err(|reason| OptionError {
                sampler,
                option: spec.name,
                value: text.clone(),
                reason,
            })?;
    }
    for e in entries {
        if let Some(check) = e.check {
            check(&options).map_err(|(option, reason)| OptionError {
                sampler: e.name,
                option,
                value: given
                    .iter()
                    .find(|(n, _)| n == option)
                    .map(|(_, t)| t.clone())
                    .unwrap_or_default(),
                reason,
            })?;
        }
    }
    Ok(options)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_named_in_the_message() {
        assert_eq!(parse_int("16", 1, 16), Ok(16));
        assert_eq!(
            parse_int("-3", 1, 16),
            Err("must be an integer in 1 ..= 16".into())
        );
        assert!(parse_int("17", 1, 16).is_err() && parse_int("2.5", 1, 16).is_err());
        assert_eq!(parse_real(" 0.5", End::Open(0.0), End::Open(1.0)), Ok(0.5));
        for bad in ["0", "1", "NaN", "inf", "x"] {
            assert_eq!(
                parse_real(bad, End::Open(0.0), End::Open(1.0)),
                Err("must be a finite number in (0, 1)".into()),
                "{bad}"
            );
        }
        assert_eq!(
            real_range(End::Closed(1.0), End::None),
            "must be a finite number ≥ 1"
        );
        assert_eq!(
            real_range(End::None, End::Open(2.0)),
            "must be a finite number < 2"
        );
        assert_eq!(
            real_range(End::Open(0.0), End::None),
            "must be a finite number > 0"
        );
    }

    use crate::{RegistryError, SAMPLERS};

    fn from(name: &str, text: &str) -> Result<BaselineOptions, RegistryError> {
        options_from(SAMPLERS, &[(name.to_string(), text.to_string())])
    }

    fn option_error(name: &str, text: &str) -> OptionError {
        match from(name, text) {
            Err(RegistryError::Option(e)) => e,
            other => panic!("{name} {text}: expected an option error, got {other:?}"),
        }
    }

    /// The error of `--name text`, which must name the option, the value and `sampler`.
    fn located(name: &str, text: &str, sampler: &str) -> OptionError {
        let e = option_error(name, text);
        assert_eq!(
            (e.sampler, e.option, e.value.as_str()),
            (sampler, name, text)
        );
        e
    }

    #[test]
    fn no_option_given_is_the_defaults() {
        assert_eq!(
            options_from(SAMPLERS, &[]).ok(),
            Some(BaselineOptions::default())
        );
    }

    /// Every option sets something: among a few valid values of its kind, one changes the
    /// defaults (a spec whose setter does nothing, or sets another family, fails here).
    #[test]
    fn every_option_sets_its_field() {
        for o in all_options(SAMPLERS) {
            let candidates: Vec<String> = match o.kind {
                OptionKind::Int { min, max, .. } => vec![min.to_string(), max.to_string()],
                OptionKind::Real { .. } => ["0.5", "0.25", "1", "7"].map(String::from).to_vec(),
                OptionKind::Ints {
                    count,
                    sep,
                    min,
                    max,
                    ..
                } => [min, max]
                    .map(|v| vec![v.to_string(); count].join(&sep.to_string()))
                    .to_vec(),
                OptionKind::RealPair { .. } => vec!["1,2".to_string()],
                OptionKind::Choice { names, .. } => names.iter().map(|n| n.to_string()).collect(),
                OptionKind::Switch { .. } => vec![String::new()],
            };
            let changes = candidates.iter().any(|t| {
                let mut options = BaselineOptions::default();
                o.apply(t, &mut options).is_ok() && options != BaselineOptions::default()
            });
            assert!(changes, "option `{}` changes nothing", o.name);
        }
    }

    #[test]
    fn shared_options_are_one_spec_and_entries_name_theirs() {
        for e in SAMPLERS {
            for o in e.options {
                let first = all_options(SAMPLERS)
                    .into_iter()
                    .find(|x| x.name == o.name)
                    .expect("listed");
                assert_eq!((first.help, first.value_name), (o.help, o.value_name));
                assert!(!o.help.is_empty() && !o.help.contains('\n'), "{}", o.name);
            }
        }
        let names: Vec<&str> = entries_with_option(SAMPLERS, "cdf-grid")
            .map(|e| e.name)
            .collect();
        assert_eq!(names, ["tabulated-cdf", "cascade-cdf"]);
    }

    #[test]
    fn values_out_of_range_are_typed_errors_naming_sampler_option_and_range() {
        let e = located("factored-j", "0", "factored");
        assert_eq!(e.reason, "must be an integer in 1 ..= 16");
        assert_eq!(
            e.to_string(),
            "sampler `factored`: option `factored-j` = 0: must be an integer in 1 ..= 16"
        );
        let e = option_error("epsilon", "1");
        assert_eq!((e.sampler, e.option), ("cascade-cdf", "epsilon"));
        assert!(e.reason.contains("(0, 1)"), "{e}");
        let e = option_error("cdf-grid", "0x512");
        assert!(e.reason.contains("1 ..= 16384"), "{e}");
        assert!(option_error("cdf-grid", "16").reason.contains("2 integers"));
        let e = option_error("factored-cost", "l1");
        assert!(e.reason.contains("euclidean, kl"), "{e}");
        let e = option_error("lobe-exponent", "NaN");
        assert!(e.reason.contains("[0, 1000000]"), "{e}");
        let e = option_error("no-such-option", "1");
        assert!(e.reason.contains("unknown option `no-such-option`"), "{e}");
        assert!(e.reason.contains("lobe-slices"), "{e}");
    }

    #[test]
    fn the_entries_checks_name_the_option_when_they_can() {
        located("srbf-max-iter", "0", "srbf");
        let e = option_error("srbf-lambda", "5,1");
        assert_eq!((e.sampler, e.option), ("srbf", ""));
        assert!(e.reason.contains("bandwidth bounds"), "{e}");
        let e = option_error("srbf-lobes", "0");
        assert!(e.reason.contains("lobe count must be at least 1"), "{e}");
    }

    #[test]
    fn values_in_range_set_the_typed_options() {
        let o = options_from(
            SAMPLERS,
            &[
                ("lobe-exponent".into(), "2e5".into()),
                ("cdf-grid".into(), "16X32".into()),
                ("factored-grid".into(), "4, 4,8,4".into()),
                ("factored-cost".into(), "kl".into()),
                ("factored-full-rows".into(), String::new()),
                ("srbf-lambda".into(), "1,300".into()),
            ],
        )
        .expect("valid");
        assert_eq!(o.lobe.exponent, Some(2e5));
        assert_eq!(
            o.lobe.max_exponent, 2e5,
            "the fit bound follows a fixed exponent"
        );
        assert_eq!((o.cdf.n_z, o.cdf.n_phi), (16, 32));
        let f = &o.factored;
        let grid = [
            f.theta_o_cells,
            f.phi_o_cells,
            f.theta_p_cells,
            f.phi_p_cells,
        ];
        assert_eq!(grid, [4, 4, 8, 4]);
        assert_eq!(f.cost, baselines::NmfCost::KullbackLeibler);
        assert!(!f.isotropic_rows);
        assert_eq!(o.srbf.brdf_lambda, (1.0, 300.0));
    }

    #[test]
    fn study_indices_are_unique_and_give_the_presets_order() {
        let mut seen = std::collections::HashSet::new();
        for e in SAMPLERS.iter().filter(|e| e.study.is_some()) {
            assert!(seen.insert(e.study), "{}: study index used twice", e.name);
            assert!(
                e.is_direction(),
                "{}: only direction samplers are studied",
                e.name
            );
        }
        let order = crate::study_samplers();
        assert_eq!(order.len(), seen.len());
        assert_eq!(&order[..2], ["uniform", "cosine"]);
        assert_eq!(order.last(), Some(&"adaptive-paper-mixture"));
    }
}
