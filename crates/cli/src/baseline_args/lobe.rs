//! Flags of the cosine-lobe and analytic samplers.

use baselines::LobeOptions;
use clap::Args;

use crate::error::{CliError, CliResult};
use crate::values::{End, int, real};

/// Flags of the cosine-lobe and analytic samplers.
#[derive(Debug, Args, Clone, Default)]
#[command(next_help_heading = "Options of the lobe-sphere and lobe-hemisphere samplers")]
pub(crate) struct LobeArgs {
    /// Fixed exponent of the lobe-sphere / lobe-hemisphere samplers, in [0, 1e6] (default:
    /// fitted per outgoing slice by minimising the estimator's second moment).
    #[arg(long, value_name = "N", allow_hyphen_values = true,
          value_parser = real(End::Closed(0.0), End::Closed(LobeOptions::MAX_EXPONENT)))]
    pub(crate) lobe_exponent: Option<f64>,
    /// Number of outgoing θo slices of the lobe fit, in [1, 1024] (default 16).
    #[arg(long, value_name = "K", allow_negative_numbers = true,
          value_parser = int(1, LobeOptions::MAX_SLICES))]
    pub(crate) lobe_slices: Option<usize>,
}

impl LobeArgs {
    /// The options these flags select (exit 2 with the valid range when out of range).
    pub(crate) fn options(&self) -> CliResult<LobeOptions> {
        let mut o = LobeOptions::default();
        if let Some(n) = self.lobe_exponent {
            if !(0.0..=LobeOptions::MAX_EXPONENT).contains(&n) {
                return Err(CliError::input(format!(
                    "--lobe-exponent {n} is out of range: must lie in [0, {}]",
                    LobeOptions::MAX_EXPONENT
                )));
            }
            o.exponent = Some(n);
            o.max_exponent = o.max_exponent.max(n);
        }
        if let Some(k) = self.lobe_slices {
            if !(1..=LobeOptions::MAX_SLICES).contains(&k) {
                return Err(CliError::input(format!(
                    "--lobe-slices {k} is out of range: must lie in [1, {}]",
                    LobeOptions::MAX_SLICES
                )));
            }
            o.slices = k;
        }
        o.validate().map_err(CliError::input)?;
        Ok(o)
    }
}
