//! Command-line options of the BRDF baselines, built from the registry: every option of every
//! sampler entry ([`samplers::OptionSpec`]) is a flag `--NAME VALUE` of `sample`, `eval`,
//! `build`, `bench` and `product` ([`BaselineArgs`]), with the entry's help and range (a value
//! out of range is a usage error naming the range, exit 2), under the heading of the samplers
//! it configures; [`applies_to`] says which. [`ProductBaselineArgs`] adds `product`'s own
//! options (the map fit and the product estimator, [`srbf::SrbfProductArgs`]). A new sampler
//! brings its flags with its entry: nothing here names a sampler.

pub(crate) mod srbf;

use std::sync::OnceLock;

use baselines::BaselineOptions;
use clap::builder::{PossibleValuesParser, ValueParser};
use clap::parser::ValueSource;
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};
use samplers::options::{all_options, entries_with_option};
use samplers::{OptionKind, OptionSpec, SAMPLERS};

use crate::error::{CliError, CliResult};

/// The options of every baseline sampler given on the command line: `(name, text)` pairs
/// (a switch's text is empty), turned into checked options by [`BaselineArgs::options`].
#[derive(Debug, Clone, Default)]
pub(crate) struct BaselineArgs {
    given: Vec<(String, String)>,
}

/// The names of the samplers configured by the option `name`, in listing order.
fn sampler_names(name: &str) -> Vec<&'static str> {
    entries_with_option(SAMPLERS, name)
        .map(|e| e.name)
        .collect()
}

/// The help heading of each option, `Options of the lobe-sphere and lobe-hemisphere samplers`
/// (made once: clap keeps `&'static str`s).
fn heading(name: &str) -> &'static str {
    static HEADINGS: OnceLock<Vec<(&'static str, String)>> = OnceLock::new();
    let headings = HEADINGS.get_or_init(|| {
        all_options(SAMPLERS)
            .into_iter()
            .map(|o| {
                let names = sampler_names(o.name);
                let heading = match names.split_last() {
                    Some((last, [])) => format!("Options of the {last} sampler"),
                    Some((last, rest)) => {
                        format!("Options of the {} and {last} samplers", rest.join(", "))
                    }
                    None => "Options of the samplers".to_string(),
                };
                (o.name, heading)
            })
            .collect()
    });
    headings
        .iter()
        .find(|(n, _)| *n == name)
        .map_or("Options of the samplers", |(_, h)| h.as_str())
}

/// The clap argument of one option (its id is its name).
fn arg(spec: &'static OptionSpec) -> Arg {
    let arg = Arg::new(spec.name)
        .long(spec.name)
        .help(spec.help)
        .help_heading(heading(spec.name));
    match spec.kind {
        OptionKind::Switch { .. } => arg.action(ArgAction::SetTrue),
        OptionKind::Choice { names, .. } => arg
            .value_name(spec.value_name)
            .value_parser(PossibleValuesParser::new(names)),
        _ => arg
            .value_name(spec.value_name)
            .allow_hyphen_values(true)
            .value_parser(ValueParser::new(move |s: &str| {
                spec.apply(s, &mut BaselineOptions::default())
                    .map(|()| s.to_string())
            })),
    }
}

impl Args for BaselineArgs {
    fn augment_args(cmd: Command) -> Command {
        all_options(SAMPLERS)
            .into_iter()
            .fold(cmd, |c, o| c.arg(arg(o)))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for BaselineArgs {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Vec::new();
        for o in all_options(SAMPLERS) {
            if matches.value_source(o.name) != Some(ValueSource::CommandLine) {
                continue;
            }
            let text = if o.takes_value() {
                matches
                    .get_one::<String>(o.name)
                    .cloned()
                    .unwrap_or_default()
            } else {
                String::new()
            };
            given.push((o.name.to_string(), text));
        }
        Ok(Self { given })
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl BaselineArgs {
    /// The baseline options these flags select (the product-only SRBF options at their
    /// defaults); checked by the entries: exit 2 with the option and the reason.
    pub(crate) fn options(&self) -> CliResult<BaselineOptions> {
        samplers::options_from(SAMPLERS, &self.given).map_err(|e| match e {
            samplers::RegistryError::Option(o) if !o.option.is_empty() => {
                CliError::input(format!("--{} {}: {}", o.option, o.value, o.reason))
            }
            samplers::RegistryError::Option(o) => {
                CliError::input(format!("{} options: {}", o.sampler, o.reason))
            }
            other => CliError::input(other),
        })
    }
}

/// The options of `product`: every baseline sampler's, and the SRBF product estimator's.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct ProductBaselineArgs {
    #[command(flatten)]
    pub(crate) samplers: BaselineArgs,
    #[command(flatten)]
    pub(crate) product: srbf::SrbfProductArgs,
}

impl ProductBaselineArgs {
    /// The baseline options these flags select; checked: exit 2 on a value out of range.
    pub(crate) fn options(&self) -> CliResult<BaselineOptions> {
        let mut options = self.samplers.options()?;
        self.product.apply(&mut options.srbf)?;
        Ok(options)
    }
}

/// The samplers each sampler option configures: (clap ids of the options, sampler names),
/// the adaptive sets' first, then one row per entry option ([`samplers::SamplerEntry::options`]).
/// An option given with another sampler would do nothing, so `sample`, `eval` and `build`
/// refuse it ([`crate::brdf_args::check_options_apply`]). The flag is `--` and the id with `-`
/// for `_`.
pub(crate) fn applies_to() -> Vec<(Vec<&'static str>, Vec<&'static str>)> {
    let adaptive = SAMPLERS
        .iter()
        .filter(|e| {
            matches!(e.constructor, samplers::Constructor::AdaptiveSet { .. })
                || e.name == "adaptive-exact"
        })
        .map(|e| e.name)
        .collect();
    let mut rows = vec![(SET_OPTION_IDS.to_vec(), adaptive)];
    for o in all_options(SAMPLERS) {
        rows.push((vec![o.name], sampler_names(o.name)));
    }
    rows
}

/// The ids of the set options, which `--set FILE` conflicts with (the stored ones apply).
pub(crate) const SET_OPTION_IDS: [&str; 6] = [
    "slices",
    "n_max",
    "max_depth",
    "grid",
    "disc_map",
    "equal_area_from",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_library_defaults_and_bad_values_name_their_flag() {
        assert_eq!(
            BaselineArgs::default().options().unwrap(),
            BaselineOptions::default()
        );
        let with = |name: &str, text: &str| BaselineArgs {
            given: vec![(name.to_string(), text.to_string())],
        };
        let e = with("srbf-max-iter", "0").options().unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert_eq!(
            e.to_string(),
            "--srbf-max-iter 0: the fit iteration cap must be at least 1"
        );
        let e = with("cdf-grid", "0x512").options().unwrap_err();
        assert!(
            e.to_string().starts_with("--cdf-grid 0x512: ")
                && e.to_string().contains("1 ..= 16384"),
            "{e}"
        );
        let e = with("srbf-lambda", "5,1")
            .options()
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("srbf options: "), "{e}");
    }

    #[test]
    fn every_entry_option_is_a_flag_with_its_samplers() {
        let rows = applies_to();
        let find = |id: &str| rows.iter().find(|r| r.0.contains(&id)).map(|r| r.1.clone());
        assert_eq!(find("epsilon"), Some(vec!["cascade-cdf"]));
        assert_eq!(find("cdf-grid"), Some(vec!["tabulated-cdf", "cascade-cdf"]));
        assert_eq!(find("n_max").map(|n| n.len()), Some(5));
        let cmd = BaselineArgs::augment_args(Command::new("t"));
        for o in all_options(SAMPLERS) {
            assert!(
                cmd.get_arguments().any(|a| a.get_long() == Some(o.name)),
                "{}",
                o.name
            );
        }
    }
}
