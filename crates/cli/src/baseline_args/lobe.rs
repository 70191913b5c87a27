//! Flags of the cosine-lobe and analytic samplers.

use baselines::LobeOptions;
use clap::Args;

use crate::error::CliResult;

/// Flags of the cosine-lobe and analytic samplers.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct LobeArgs {}

impl LobeArgs {
    /// The options these flags select.
    pub(crate) fn options(&self) -> CliResult<LobeOptions> {
        Ok(LobeOptions::default())
    }
}
