//! Command-line options of the BRDF baselines, one clap group per family: [`BaselineArgs`]
//! (flattened into `sample`, `eval` and `build`) holds the options of the samplers, and
//! [`ProductBaselineArgs`] adds `product`'s own (the map fit and the product estimator). Each
//! family's flags fill its `baselines::*Options`; a value out of range is a usage error naming
//! the range (exit 2). [`APPLIES_TO`] says which samplers each option configures.

mod cdf;
mod factored;
mod lobe;
pub(crate) mod srbf;

use baselines::BaselineOptions;
use clap::Args;

use crate::error::CliResult;

/// Options of every baseline sampler family.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct BaselineArgs {
    #[command(flatten)]
    pub(crate) lobe: lobe::LobeArgs,
    #[command(flatten)]
    pub(crate) cdf: cdf::CdfArgs,
    #[command(flatten)]
    pub(crate) factored: factored::FactoredArgs,
    #[command(flatten)]
    pub(crate) srbf: srbf::SrbfArgs,
}

impl BaselineArgs {
    /// The baseline options these flags select (the product-only SRBF options at their
    /// defaults); checked: exit 2 on a value out of range.
    pub(crate) fn options(&self) -> CliResult<BaselineOptions> {
        self.options_with(None)
    }

    fn options_with(&self, product: Option<&srbf::SrbfProductArgs>) -> CliResult<BaselineOptions> {
        Ok(BaselineOptions {
            lobe: self.lobe.options()?,
            cdf: self.cdf.options()?,
            factored: self.factored.options()?,
            srbf: self.srbf.options(product)?,
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
        self.samplers.options_with(Some(&self.product))
    }
}

/// The samplers each sampler option configures: (clap ids of the options, sampler names).
/// An option given with another sampler would do nothing, so `sample`, `eval` and `build`
/// refuse it ([`crate::brdf_args::check_options_apply`]). Ids are the field names; the flag is
/// `--` and the id with `-` for `_`.
pub(crate) const APPLIES_TO: &[(&[&str], &[&str])] = &[
    (
        &[
            "slices",
            "n_max",
            "max_depth",
            "grid",
            "disc_map",
            "equal_area_from",
        ],
        &[
            "adaptive",
            "adaptive-paper",
            "adaptive-mixture",
            "adaptive-paper-mixture",
            "adaptive-exact",
        ],
    ),
    (
        &["lobe_exponent", "lobe_slices"],
        &["lobe-sphere", "lobe-hemisphere"],
    ),
    (
        &[
            "cdf_slices",
            "cdf_anisotropic_slices",
            "cdf_grid",
            "cdf_supersampling",
        ],
        &["tabulated-cdf", "cascade-cdf"],
    ),
    (&["epsilon"], &["cascade-cdf"]),
    (
        &[
            "factored_j",
            "factored_k",
            "factored_cost",
            "factored_param",
            "factored_grid",
            "factored_iterations",
            "factored_tolerance",
            "factored_seed",
            "factored_alpha",
            "factored_full_rows",
        ],
        &["factored"],
    ),
    (
        &[
            "srbf_slices",
            "srbf_phi_slices",
            "srbf_lobes",
            "srbf_lambda",
            "srbf_fit_rows",
            "srbf_brdf_defensive",
            "srbf_max_iter",
        ],
        &["srbf"],
    ),
];
