//! Flags of the Lawrence 2004 factorisation.

use baselines::FactoredOptions;
use clap::Args;

use crate::error::CliResult;

/// Flags of the Lawrence 2004 factorisation.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct FactoredArgs {}

impl FactoredArgs {
    /// The options these flags select.
    pub(crate) fn options(&self) -> CliResult<FactoredOptions> {
        Ok(FactoredOptions::default())
    }
}
