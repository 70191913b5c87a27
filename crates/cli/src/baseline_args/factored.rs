//! Flags of the Lawrence 2004 factorisation.

use baselines::{FactoredOptions, NmfCost, Reparam};
use clap::{Args, ValueEnum};

use crate::error::{CliError, CliResult};
use crate::values::{End, int, real, seed};

/// Flags of the Lawrence 2004 factorisation (`--sampler factored`); unset flags keep
/// `FactoredOptions`' defaults.
#[derive(Debug, Args, Clone, Default)]
#[command(next_help_heading = "Options of the factored sampler")]
pub(crate) struct FactoredArgs {
    /// Factored: outer terms J, in 1..=16 (default 3).
    #[arg(long = "factored-j", value_name = "J", value_parser = int(FactoredOptions::TERMS_RANGE.0, FactoredOptions::TERMS_RANGE.1), allow_negative_numbers = true)]
    factored_j: Option<usize>,
    /// Factored: inner terms K per outer term, in 1..=16 (default 2).
    #[arg(long = "factored-k", value_name = "K", value_parser = int(FactoredOptions::TERMS_RANGE.0, FactoredOptions::TERMS_RANGE.1), allow_negative_numbers = true)]
    factored_k: Option<usize>,
    /// Factored: NMF cost (default euclidean).
    #[arg(long = "factored-cost", value_enum)]
    factored_cost: Option<CostName>,
    /// Factored: parametrisation of ωi (default halfangle).
    #[arg(long = "factored-param", value_enum)]
    factored_param: Option<ParamName>,
    /// Factored: table cells `θo,φo,θp,φp`, each in 1..=1024 (default 16,32,32,16).
    #[arg(long = "factored-grid", value_name = "THO,PHO,THP,PHP", value_parser = parse_grid)]
    factored_grid: Option<[usize; 4]>,
    /// Factored: iteration cap of each factorisation, in 1..=1000000 (default 2000).
    #[arg(long = "factored-iterations", value_name = "N", value_parser = int(FactoredOptions::MAX_ITERATIONS_RANGE.0, FactoredOptions::MAX_ITERATIONS_RANGE.1), allow_negative_numbers = true)]
    factored_iterations: Option<usize>,
    /// Factored: stop at this relative cost change, in (0, 1) (default 1e-6).
    #[arg(long = "factored-tolerance", value_name = "TOL", value_parser = real(End::Open(0.0), End::Open(1.0)), allow_hyphen_values = true)]
    factored_tolerance: Option<f64>,
    /// Factored: seed of the initial factors (default 2004).
    #[arg(long = "factored-seed", value_name = "S", value_parser = seed, allow_negative_numbers = true)]
    factored_seed: Option<u64>,
    /// Factored: weight α of the defensive cosine component, in [0, 1] (default 0.05; 0 is
    /// the paper-pure sampler, which may leave support holes).
    #[arg(long = "factored-alpha", value_name = "ALPHA", value_parser = real(End::Closed(0.0), End::Closed(1.0)), allow_hyphen_values = true)]
    factored_alpha: Option<f64>,
    /// Factored: tabulate θo × φo rows even for isotropic BRDFs (default: θo only, turned by φo).
    #[arg(long = "factored-full-rows")]
    factored_full_rows: bool,
}

/// NMF costs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum CostName {
    /// Weighted squared Frobenius distance.
    Euclidean,
    /// Generalised Kullback–Leibler divergence.
    Kl,
}

/// Parametrisations of ωi.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ParamName {
    /// Half vector (with the 1/(4 ωi·ωh) Jacobian).
    Halfangle,
    /// ωi itself.
    Spherical,
}

fn parse_grid(s: &str) -> Result<[usize; 4], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let bad = || format!("`{s}`: expected four cell counts THO,PHO,THP,PHP, e.g. 16,32,32,16");
    if parts.len() != 4 {
        return Err(bad());
    }
    let mut out = [0; 4];
    for (o, p) in out.iter_mut().zip(parts) {
        *o = p.trim().parse().map_err(|_| bad())?;
    }
    Ok(out)
}

impl FactoredArgs {
    /// The options these flags select (exit 2 with the valid range when one is out of range).
    pub(crate) fn options(&self) -> CliResult<FactoredOptions> {
        let d = FactoredOptions::default();
        let [theta_o_cells, phi_o_cells, theta_p_cells, phi_p_cells] =
            self.factored_grid.unwrap_or([
                d.theta_o_cells,
                d.phi_o_cells,
                d.theta_p_cells,
                d.phi_p_cells,
            ]);
        let options = FactoredOptions {
            theta_o_cells,
            phi_o_cells,
            theta_p_cells,
            phi_p_cells,
            outer_terms: self.factored_j.unwrap_or(d.outer_terms),
            inner_terms: self.factored_k.unwrap_or(d.inner_terms),
            reparam: self.factored_param.map_or(d.reparam, |p| match p {
                ParamName::Halfangle => Reparam::HalfAngle,
                ParamName::Spherical => Reparam::Spherical,
            }),
            cost: self.factored_cost.map_or(d.cost, |c| match c {
                CostName::Euclidean => NmfCost::Euclidean,
                CostName::Kl => NmfCost::KullbackLeibler,
            }),
            max_iterations: self.factored_iterations.unwrap_or(d.max_iterations),
            tolerance: self.factored_tolerance.unwrap_or(d.tolerance),
            seed: self.factored_seed.unwrap_or(d.seed),
            defensive_alpha: self.factored_alpha.unwrap_or(d.defensive_alpha),
            isotropic_rows: !self.factored_full_rows,
        };
        options.validate().map_err(CliError::input)?;
        Ok(options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_ranges() {
        assert_eq!(
            FactoredArgs::default().options().unwrap(),
            FactoredOptions::default()
        );
        let zero_j = FactoredArgs {
            factored_j: Some(0),
            ..FactoredArgs::default()
        };
        let e = zero_j.options().unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("1..=16"), "{e}");
        let zero_grid = FactoredArgs {
            factored_grid: Some([16, 0, 32, 16]),
            ..FactoredArgs::default()
        };
        assert!(
            zero_grid
                .options()
                .unwrap_err()
                .to_string()
                .contains("1..=1024")
        );
        assert_eq!(parse_grid("8, 8,4,4"), Ok([8, 8, 4, 4]));
        assert!(parse_grid("8,8,4").is_err());
    }
}
