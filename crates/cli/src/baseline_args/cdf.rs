//! Flags of the tabulated and cascade CDFs.

use baselines::CdfOptions;
use clap::Args;

use crate::error::CliResult;

/// Flags of the tabulated and cascade CDFs.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct CdfArgs {}

impl CdfArgs {
    /// The options these flags select.
    pub(crate) fn options(&self) -> CliResult<CdfOptions> {
        Ok(CdfOptions::default())
    }
}
