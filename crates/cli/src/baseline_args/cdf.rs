//! Flags of the tabulated and cascade CDFs.

use baselines::{CdfOptions, CdfOptionsError};
use clap::Args;

use crate::error::{CliError, CliResult};
use crate::values::{End, int, real};

/// Flags of the tabulated and cascade CDFs (`tabulated-cdf`, `cascade-cdf`).
#[derive(Debug, Args, Clone)]
#[command(next_help_heading = "Options of the tabulated-cdf and cascade-cdf samplers")]
pub(crate) struct CdfArgs {
    /// CDF baselines: outgoing θ slices of an isotropic BRDF (1 ..= 1024).
    #[arg(long, default_value_t = CdfOptions::DEFAULT_SLICES,
          value_parser = int(1, CdfOptions::MAX_SLICES), allow_negative_numbers = true)]
    pub(crate) cdf_slices: usize,
    /// CDF baselines: outgoing slices THETAxPHI of an anisotropic BRDF (each 1 ..= 1024).
    #[arg(long, value_name = "THETAxPHI", value_parser = parse_pair,
          default_value_t = Pair(CdfOptions::DEFAULT_ANISOTROPIC_SLICES))]
    pub(crate) cdf_anisotropic_slices: Pair,
    /// CDF baselines: fine cells NZxNPHI of each slice over (cosθ, φ) (each 1 ..= 16384).
    #[arg(long, value_name = "NZxNPHI", value_parser = parse_pair,
          default_value_t = Pair([CdfOptions::DEFAULT_N_Z, CdfOptions::DEFAULT_N_PHI]))]
    pub(crate) cdf_grid: Pair,
    /// CDF baselines: BRDF evaluations per cell and axis (1 ..= 16).
    #[arg(long, default_value_t = CdfOptions::DEFAULT_SUPERSAMPLING,
          value_parser = int(1, CdfOptions::MAX_SUPERSAMPLING), allow_negative_numbers = true)]
    pub(crate) cdf_supersampling: usize,
    /// cascade-cdf: Douglas–Peucker tolerance ε in CDF units, in (0, 1).
    #[arg(long, default_value_t = CdfOptions::DEFAULT_EPSILON,
          value_parser = real(End::Open(0.0), End::Open(1.0)), allow_hyphen_values = true)]
    pub(crate) epsilon: f64,
}

impl Default for CdfArgs {
    fn default() -> Self {
        let d = CdfOptions::default();
        Self {
            cdf_slices: d.slices,
            cdf_anisotropic_slices: Pair(d.anisotropic_slices),
            cdf_grid: Pair([d.n_z, d.n_phi]),
            cdf_supersampling: d.supersampling,
            epsilon: d.epsilon,
        }
    }
}

/// Two counts written `AxB`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Pair(pub(crate) [usize; 2]);

impl std::fmt::Display for Pair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.0[0], self.0[1])
    }
}

fn parse_pair(s: &str) -> Result<Pair, String> {
    let bad = || format!("`{s}`: expected two counts AxB, e.g. 256x512");
    let (a, b) = s.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    Ok(Pair([
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    ]))
}

impl CdfArgs {
    /// The options these flags select (exit 2 with the valid range on a value out of range).
    pub(crate) fn options(&self) -> CliResult<CdfOptions> {
        let options = CdfOptions {
            slices: self.cdf_slices,
            anisotropic_slices: self.cdf_anisotropic_slices.0,
            n_z: self.cdf_grid.0[0],
            n_phi: self.cdf_grid.0[1],
            supersampling: self.cdf_supersampling,
            epsilon: self.epsilon,
            ..CdfOptions::default()
        };
        options.validate().map_err(|e| {
            let flag = match e {
                CdfOptionsError::Slices { what: "slices", .. } => {
                    format!("--cdf-slices {}", self.cdf_slices)
                }
                CdfOptionsError::Slices { .. } => {
                    format!("--cdf-anisotropic-slices {}", self.cdf_anisotropic_slices)
                }
                CdfOptionsError::Grid { .. } => format!("--cdf-grid {}", self.cdf_grid),
                CdfOptionsError::Supersampling(_) => {
                    format!("--cdf-supersampling {}", self.cdf_supersampling)
                }
                CdfOptionsError::Epsilon(_) => format!("--epsilon {}", self.epsilon),
                _ => "CDF options".to_string(),
            };
            CliError::input(format!("{flag}: {e}"))
        })?;
        Ok(options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_library_defaults_and_bad_values_name_their_flag() {
        assert_eq!(CdfArgs::default().options().unwrap(), CdfOptions::default());
        assert_eq!(parse_pair("32x16"), Ok(Pair([32, 16])));
        assert!(parse_pair("32").is_err() && parse_pair("ax3").is_err());
        let e = CdfArgs {
            epsilon: 0.0,
            ..CdfArgs::default()
        }
        .options()
        .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().starts_with("--epsilon 0: "), "{e}");
        assert!(e.to_string().contains("(0, 1)"), "{e}");
        let e = CdfArgs {
            cdf_grid: Pair([0, 512]),
            ..CdfArgs::default()
        }
        .options()
        .unwrap_err();
        assert!(
            e.to_string().contains("--cdf-grid 0x512") && e.to_string().contains("1 ..= 16384"),
            "{e}"
        );
    }
}
