//! Flags of the `product` command only ([`SrbfProductArgs`]): the SRBF fit of the environment
//! map and the product estimator (Tsai 2008); the `srbf` sampler's own flags come with its
//! registry entry. Their ranges are checked by [`SrbfOptions::validate`] (exit 2 with the
//! broken invariant, one line: `product`'s tests rely on that message), not by clap.

use baselines::SrbfOptions;
use clap::Args;

use crate::error::{CliError, CliResult};

/// Flags of `product` only: the environment map's SRBF fit and the product estimator.
#[derive(Debug, Args, Clone)]
#[command(next_help_heading = "Options of the srbf-product estimator")]
pub(crate) struct SrbfProductArgs {
    /// product: lobes of the environment map's fit.
    #[arg(long = "srbf-map-lobes", default_value_t = SrbfOptions::default().map_lobes, allow_negative_numbers = true)]
    pub(crate) srbf_map_lobes: usize,
    /// product: bandwidth bounds of the map's lobes, `MIN,MAX` (0 < MIN < MAX, finite).
    #[arg(long = "srbf-map-lambda", default_value = "0.5,5000", value_parser = parse_bounds, allow_hyphen_values = true)]
    pub(crate) srbf_map_lambda: (f64, f64),
    /// product: width of the box-filtered map that is fitted (height = width/2).
    #[arg(long = "srbf-map-fit-width", default_value_t = SrbfOptions::default().map_fit_width, allow_negative_numbers = true)]
    pub(crate) srbf_map_fit_width: usize,
    /// product: product lobes kept (largest masses).
    #[arg(long = "srbf-keep", default_value_t = SrbfOptions::default().product_lobes, allow_negative_numbers = true)]
    pub(crate) srbf_keep: usize,
    /// product: share of srbf-product's samples given to the BRDF slice's lobes, in [0, 0.8)
    /// (0 = Tsai's estimator as published).
    #[arg(long = "srbf-defensive", default_value_t = SrbfOptions::default().defensive, allow_hyphen_values = true)]
    pub(crate) srbf_defensive: f64,
}

impl Default for SrbfProductArgs {
    fn default() -> Self {
        let d = SrbfOptions::default();
        Self {
            srbf_map_lobes: d.map_lobes,
            srbf_map_lambda: d.map_lambda,
            srbf_map_fit_width: d.map_fit_width,
            srbf_keep: d.product_lobes,
            srbf_defensive: d.defensive,
        }
    }
}

fn parse_bounds(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("`{s}`: expected MIN,MAX"))?;
    let parse = |t: &str| t.trim().parse::<f64>().map_err(|e| format!("`{t}`: {e}"));
    Ok((parse(a)?, parse(b)?))
}

impl SrbfProductArgs {
    /// Sets `product`'s own fields of `options` (the map fit and the product estimator) and
    /// checks them all (exit 2 with the broken invariant, one line).
    pub(crate) fn apply(&self, options: &mut SrbfOptions) -> CliResult<()> {
        options.map_lobes = self.srbf_map_lobes;
        options.map_lambda = self.srbf_map_lambda;
        options.map_fit_width = self.srbf_map_fit_width;
        options.product_lobes = self.srbf_keep;
        options.defensive = self.srbf_defensive;
        options.validate().map_err(CliError::input)
    }
}
