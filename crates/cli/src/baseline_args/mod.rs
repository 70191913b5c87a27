//! Command-line options of the BRDF baselines, one clap group per family, flattened into the
//! set options of `sample`, `eval` and `build`. Each family's flags fill its
//! `baselines::*Options`; out-of-range values are exit 2 with the valid range.

mod cdf;
mod factored;
mod lobe;
pub(crate) mod srbf;

use baselines::BaselineOptions;
use clap::Args;

use crate::error::CliResult;

/// Options of every baseline family.
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
    /// The baseline options these flags select (checked: exit 2 on a value out of range).
    pub(crate) fn options(&self) -> CliResult<BaselineOptions> {
        Ok(BaselineOptions {
            lobe: self.lobe.options()?,
            cdf: self.cdf.options()?,
            factored: self.factored.options()?,
            srbf: self.srbf.options()?,
        })
    }
}
