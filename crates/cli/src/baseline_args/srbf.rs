//! Flags of the SRBF fits (Tsai 2008): the `srbf` sampler's ([`SrbfArgs`]) and those of the
//! `product` command only ([`SrbfProductArgs`]). Their ranges are checked by
//! [`SrbfOptions::validate`] (exit 2 with the broken invariant, one line: `product`'s tests
//! rely on that message), not by clap.

use baselines::SrbfOptions;
use clap::Args;

use crate::error::{CliError, CliResult};

/// Flags of the `srbf` sampler's fits (`sample`, `eval`, `build`, and `product`).
#[derive(Debug, Args, Clone)]
#[command(next_help_heading = "Options of the srbf sampler")]
pub(crate) struct SrbfArgs {
    /// srbf: outgoing-angle slices θo (slice j fitted at (j+½)·90°/slices).
    #[arg(long = "srbf-slices", default_value_t = SrbfOptions::DEFAULT_SLICES, allow_negative_numbers = true)]
    pub(crate) srbf_slices: usize,
    /// srbf: azimuthal slices φo of anisotropic BRDFs.
    #[arg(long = "srbf-phi-slices", default_value_t = SrbfOptions::default().phi_slices, allow_negative_numbers = true)]
    pub(crate) srbf_phi_slices: usize,
    /// srbf: lobes per BRDF slice.
    #[arg(long = "srbf-lobes", default_value_t = SrbfOptions::default().brdf_lobes, allow_negative_numbers = true)]
    pub(crate) srbf_lobes: usize,
    /// srbf: bandwidth bounds of the BRDF lobes, `MIN,MAX` (0 < MIN < MAX, finite).
    #[arg(long = "srbf-lambda", default_value = "0.5,20000", value_parser = parse_bounds, allow_hyphen_values = true)]
    pub(crate) srbf_lambda: (f64, f64),
    /// srbf: polar rows of each slice's hemisphere fit grid (4× as many azimuths).
    #[arg(long = "srbf-fit-rows", default_value_t = SrbfOptions::default().fit_rows, allow_negative_numbers = true)]
    pub(crate) srbf_fit_rows: usize,
    /// srbf: share of cosine-hemisphere sampling mixed into each slice's lobes, in [0, 1)
    /// (0 = the SRBF mixture alone).
    #[arg(long = "srbf-brdf-defensive", default_value_t = SrbfOptions::default().brdf_defensive, allow_hyphen_values = true)]
    pub(crate) srbf_brdf_defensive: f64,
    /// srbf: iteration cap per fit (Levenberg–Marquardt steps per BRDF slice, L-BFGS iterations of the map; a fit that reaches it unconverged is warned about).
    #[arg(long = "srbf-max-iter", default_value_t = SrbfOptions::default().max_iter, allow_negative_numbers = true)]
    pub(crate) srbf_max_iter: usize,
}

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

impl Default for SrbfArgs {
    fn default() -> Self {
        let d = SrbfOptions::default();
        Self {
            srbf_slices: d.slices,
            srbf_phi_slices: d.phi_slices,
            srbf_lobes: d.brdf_lobes,
            srbf_lambda: d.brdf_lambda,
            srbf_fit_rows: d.fit_rows,
            srbf_brdf_defensive: d.brdf_defensive,
            srbf_max_iter: d.max_iter,
        }
    }
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

impl SrbfArgs {
    /// The options these flags select, with `product`'s own (`product`: the map fit and the
    /// product estimator; `None`: their defaults). Checked: exit 2 with the broken invariant.
    pub(crate) fn options(&self, product: Option<&SrbfProductArgs>) -> CliResult<SrbfOptions> {
        if self.srbf_max_iter == 0 {
            return Err(CliError::input(
                "--srbf-max-iter 0: the fit iteration cap must be at least 1",
            ));
        }
        let defaults = SrbfProductArgs::default();
        let p = product.unwrap_or(&defaults);
        let options = SrbfOptions {
            slices: self.srbf_slices,
            phi_slices: self.srbf_phi_slices,
            brdf_lobes: self.srbf_lobes,
            brdf_lambda: self.srbf_lambda,
            fit_rows: self.srbf_fit_rows,
            brdf_defensive: self.srbf_brdf_defensive,
            map_lobes: p.srbf_map_lobes,
            map_lambda: p.srbf_map_lambda,
            map_fit_width: p.srbf_map_fit_width,
            max_iter: self.srbf_max_iter,
            product_lobes: p.srbf_keep,
            defensive: p.srbf_defensive,
        };
        options.validate().map_err(CliError::input)?;
        Ok(options)
    }
}
