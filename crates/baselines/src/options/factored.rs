//! Options of the factored baseline (Lawrence, Rusinkiewicz, Ramamoorthi 2004).

/// How the incoming direction is parametrised in the factorisation's columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Reparam {
    /// `ωp = ωh = normalize(ωi + ωo)` (the paper's main choice: it aligns specular peaks across
    /// outgoing directions); the pdf carries the Jacobian `1/(4 ωi·ωh)` and samples may land
    /// below the horizon.
    #[default]
    HalfAngle,
    /// `ωp = ωi` in spherical coordinates of the upper hemisphere (no Jacobian).
    Spherical,
}

impl Reparam {
    /// `halfangle` or `spherical` (the paper's header names).
    pub fn name(&self) -> &'static str {
        match self {
            Reparam::HalfAngle => "halfangle",
            Reparam::Spherical => "spherical",
        }
    }
}

/// The cost the non-negative factorisation minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NmfCost {
    /// Weighted squared Frobenius distance `‖M⊙(Y − FG)‖²` (the default).
    #[default]
    Euclidean,
    /// Weighted generalised Kullback–Leibler divergence `Σ M (Y ln(Y/FG) − Y + FG)`.
    KullbackLeibler,
}

impl NmfCost {
    /// `euclidean` or `kl`.
    pub fn name(&self) -> &'static str {
        match self {
            NmfCost::Euclidean => "euclidean",
            NmfCost::KullbackLeibler => "kl",
        }
    }
}

/// Options of the factored baseline (baselines.md §A): table resolutions, the numbers of outer
/// (`J`) and inner (`K`) terms, the reparametrisation, the factorisation's cost and stopping
/// rule, its seed, and the defensive cosine mixture weight.
///
/// Defaults are the associated constants `DEFAULT_*` (baselines.md §A.7 and §A.3).
#[derive(Debug, Clone, PartialEq)]
pub struct FactoredOptions {
    /// Outgoing polar cells over `θo ∈ [0, π/2]` (rows of the data matrix).
    pub theta_o_cells: usize,
    /// Outgoing azimuth cells over `φo ∈ [0, 2π)` (unused for isotropic BRDFs when
    /// [`FactoredOptions::isotropic_rows`] is set).
    pub phi_o_cells: usize,
    /// Polar cells of the reparametrised direction over `θp ∈ [0, π/2]`.
    pub theta_p_cells: usize,
    /// Azimuth cells of the reparametrised direction over `φp ∈ [0, 2π)`.
    pub phi_p_cells: usize,
    /// Outer terms `J` (first factorisation `Y ≈ F G`).
    pub outer_terms: usize,
    /// Inner terms `K` (second factorisation of each `G_j` on the `(θp, φp)` grid).
    pub inner_terms: usize,
    /// Half-angle or spherical parametrisation of `ωi`.
    pub reparam: Reparam,
    /// The factorisation's cost.
    pub cost: NmfCost,
    /// Iteration cap of each factorisation (a factorisation that hits it is kept and its
    /// residual reported).
    pub max_iterations: usize,
    /// Stop when the relative change of the cost between two iterations is below this.
    pub tolerance: f64,
    /// Seed of the random initial factors (the result depends only on it, not on threads).
    pub seed: u64,
    /// Weight `α` of the defensive mixture `p = (1−α) p_fac + α cosθi/π` (a non-paper variant
    /// that guarantees `p > 0` wherever `g > 0`); `0` is the paper-pure sampler.
    pub defensive_alpha: f64,
    /// For isotropic BRDFs, tabulate rows over `θo` only (`φo = 0`) and rotate by `φo` at run
    /// time (baselines.md §A.7's variant); otherwise the full `θo × φo` table.
    pub isotropic_rows: bool,
}

impl FactoredOptions {
    /// Default outgoing polar cells (16).
    pub const DEFAULT_THETA_O_CELLS: usize = 16;
    /// Default outgoing azimuth cells (32).
    pub const DEFAULT_PHI_O_CELLS: usize = 32;
    /// Default polar cells of the reparametrised direction (32).
    pub const DEFAULT_THETA_P_CELLS: usize = 32;
    /// Default azimuth cells of the reparametrised direction (16).
    pub const DEFAULT_PHI_P_CELLS: usize = 16;
    /// Default outer terms `J` (3).
    pub const DEFAULT_OUTER_TERMS: usize = 3;
    /// Default inner terms `K` (2).
    pub const DEFAULT_INNER_TERMS: usize = 2;
    /// Default iteration cap (2000, baselines.md §A.3).
    pub const DEFAULT_MAX_ITERATIONS: usize = 2000;
    /// Default relative cost-change tolerance (1e-6).
    pub const DEFAULT_TOLERANCE: f64 = 1e-6;
    /// Default seed.
    pub const DEFAULT_SEED: u64 = 2004;
    /// Default defensive weight `α` (0.05).
    pub const DEFAULT_DEFENSIVE_ALPHA: f64 = 0.05;

    /// Valid range of each grid size.
    pub const GRID_RANGE: (usize, usize) = (1, 1024);
    /// Valid range of `J` and of `K`.
    pub const TERMS_RANGE: (usize, usize) = (1, 16);
    /// Valid range of the iteration cap.
    pub const MAX_ITERATIONS_RANGE: (usize, usize) = (1, 1_000_000);

    /// Checks every field against its range.
    ///
    /// Errors: [`FactoredOptionsError`] naming the field, its value and its valid range.
    pub fn validate(&self) -> Result<(), FactoredOptionsError> {
        let grids = [
            ("theta_o_cells", self.theta_o_cells),
            ("phi_o_cells", self.phi_o_cells),
            ("theta_p_cells", self.theta_p_cells),
            ("phi_p_cells", self.phi_p_cells),
        ];
        for (field, value) in grids {
            check_range(field, value, Self::GRID_RANGE)?;
        }
        check_range("outer_terms (J)", self.outer_terms, Self::TERMS_RANGE)?;
        check_range("inner_terms (K)", self.inner_terms, Self::TERMS_RANGE)?;
        check_range(
            "max_iterations",
            self.max_iterations,
            Self::MAX_ITERATIONS_RANGE,
        )?;
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(FactoredOptionsError::Tolerance(self.tolerance));
        }
        if !(self.defensive_alpha >= 0.0 && self.defensive_alpha <= 1.0) {
            return Err(FactoredOptionsError::DefensiveAlpha(self.defensive_alpha));
        }
        Ok(())
    }
}

fn check_range(
    field: &'static str,
    value: usize,
    (min, max): (usize, usize),
) -> Result<(), FactoredOptionsError> {
    if value < min || value > max {
        return Err(FactoredOptionsError::OutOfRange {
            field,
            value,
            min,
            max,
        });
    }
    Ok(())
}

impl Default for FactoredOptions {
    fn default() -> Self {
        Self {
            theta_o_cells: Self::DEFAULT_THETA_O_CELLS,
            phi_o_cells: Self::DEFAULT_PHI_O_CELLS,
            theta_p_cells: Self::DEFAULT_THETA_P_CELLS,
            phi_p_cells: Self::DEFAULT_PHI_P_CELLS,
            outer_terms: Self::DEFAULT_OUTER_TERMS,
            inner_terms: Self::DEFAULT_INNER_TERMS,
            reparam: Reparam::default(),
            cost: NmfCost::default(),
            max_iterations: Self::DEFAULT_MAX_ITERATIONS,
            tolerance: Self::DEFAULT_TOLERANCE,
            seed: Self::DEFAULT_SEED,
            defensive_alpha: Self::DEFAULT_DEFENSIVE_ALPHA,
            isotropic_rows: true,
        }
    }
}

/// A [`FactoredOptions`] field outside its valid range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FactoredOptionsError {
    /// A grid size, a term count or the iteration cap is outside its range.
    #[error("factored: {field} = {value} is out of range (valid: {min}..={max})")]
    OutOfRange {
        /// The field.
        field: &'static str,
        /// Its value.
        value: usize,
        /// Smallest valid value.
        min: usize,
        /// Largest valid value.
        max: usize,
    },
    /// The tolerance is not in `(0, 1)`.
    #[error("factored: tolerance = {0} is out of range (valid: 0 < tolerance < 1)")]
    Tolerance(f64),
    /// The defensive weight is not in `[0, 1]`.
    #[error("factored: defensive alpha = {0} is out of range (valid: 0 ≤ alpha ≤ 1)")]
    DefensiveAlpha(f64),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_zero_sizes_are_rejected_with_the_range() {
        assert_eq!(FactoredOptions::default().validate(), Ok(()));
        let zero_j = FactoredOptions {
            outer_terms: 0,
            ..FactoredOptions::default()
        };
        let msg = zero_j.validate().unwrap_err().to_string();
        assert!(msg.contains("J") && msg.contains("1..=16"), "{msg}");
        let zero_grid = FactoredOptions {
            phi_p_cells: 0,
            ..FactoredOptions::default()
        };
        assert!(matches!(
            zero_grid.validate(),
            Err(FactoredOptionsError::OutOfRange {
                field: "phi_p_cells",
                ..
            })
        ));
        for alpha in [-0.1, 1.5, f64::NAN] {
            let o = FactoredOptions {
                defensive_alpha: alpha,
                ..FactoredOptions::default()
            };
            assert!(o.validate().is_err(), "{alpha}");
        }
        for tol in [0.0, 1.0, f64::NAN] {
            let o = FactoredOptions {
                tolerance: tol,
                ..FactoredOptions::default()
            };
            assert!(o.validate().is_err(), "{tol}");
        }
    }
}
