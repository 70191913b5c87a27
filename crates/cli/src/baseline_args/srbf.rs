//! Flags of the SRBF fits (Tsai 2008): the `srbf` sampler and the `product` command.

use baselines::SrbfOptions;
use clap::Args;

use crate::error::{CliError, CliResult};

/// Flags of the SRBF fits and product sampling.
#[derive(Debug, Args, Clone)]
pub(crate) struct SrbfArgs {
    /// srbf: outgoing-angle slices θo (slice j fitted at (j+½)·90°/slices).
    #[arg(long = "srbf-slices", default_value_t = SrbfOptions::DEFAULT_SLICES)]
    pub(crate) srbf_slices: usize,
    /// srbf: azimuthal slices φo of anisotropic BRDFs.
    #[arg(long = "srbf-phi-slices", default_value_t = SrbfOptions::default().phi_slices)]
    pub(crate) srbf_phi_slices: usize,
    /// srbf: lobes per BRDF slice.
    #[arg(long = "srbf-lobes", default_value_t = SrbfOptions::default().brdf_lobes)]
    pub(crate) srbf_lobes: usize,
    /// srbf: bandwidth bounds of the BRDF lobes, `MIN,MAX` (0 < MIN < MAX).
    #[arg(long = "srbf-lambda", default_value = "0.5,20000", value_parser = parse_bounds, allow_hyphen_values = true)]
    pub(crate) srbf_lambda: (f64, f64),
    /// srbf: polar rows of each slice's hemisphere fit grid (4× as many azimuths).
    #[arg(long = "srbf-fit-rows", default_value_t = SrbfOptions::default().fit_rows)]
    pub(crate) srbf_fit_rows: usize,
    /// srbf: share of cosine-hemisphere sampling mixed into each slice's lobes, in [0, 1)
    /// (0 = the SRBF mixture alone).
    #[arg(long = "srbf-brdf-defensive", default_value_t = SrbfOptions::default().brdf_defensive)]
    pub(crate) srbf_brdf_defensive: f64,
    /// srbf: L-BFGS iteration cap per fit.
    #[arg(long = "srbf-max-iter", default_value_t = SrbfOptions::default().max_iter)]
    pub(crate) srbf_max_iter: usize,
    /// product: lobes of the environment map's fit.
    #[arg(long = "srbf-map-lobes", default_value_t = SrbfOptions::default().map_lobes)]
    pub(crate) srbf_map_lobes: usize,
    /// product: bandwidth bounds of the map's lobes, `MIN,MAX`.
    #[arg(long = "srbf-map-lambda", default_value = "0.5,5000", value_parser = parse_bounds, allow_hyphen_values = true)]
    pub(crate) srbf_map_lambda: (f64, f64),
    /// product: width of the box-filtered map that is fitted (height = width/2).
    #[arg(long = "srbf-map-fit-width", default_value_t = SrbfOptions::default().map_fit_width)]
    pub(crate) srbf_map_fit_width: usize,
    /// product: product lobes kept (largest masses).
    #[arg(long = "srbf-keep", default_value_t = SrbfOptions::default().product_lobes)]
    pub(crate) srbf_keep: usize,
    /// product: share of srbf-product's samples given to the BRDF slice's lobes, in [0, 1)
    /// (0 = Tsai's estimator as published).
    #[arg(long = "srbf-defensive", default_value_t = SrbfOptions::default().defensive)]
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
    /// The options these flags select (checked: exit 2 with the broken invariant).
    pub(crate) fn options(&self) -> CliResult<SrbfOptions> {
        let options = SrbfOptions {
            slices: self.srbf_slices,
            phi_slices: self.srbf_phi_slices,
            brdf_lobes: self.srbf_lobes,
            brdf_lambda: self.srbf_lambda,
            fit_rows: self.srbf_fit_rows,
            brdf_defensive: self.srbf_brdf_defensive,
            map_lobes: self.srbf_map_lobes,
            map_lambda: self.srbf_map_lambda,
            map_fit_width: self.srbf_map_fit_width,
            max_iter: self.srbf_max_iter,
            product_lobes: self.srbf_keep,
            defensive: self.srbf_defensive,
        };
        options.validate().map_err(CliError::input)?;
        Ok(options)
    }
}
