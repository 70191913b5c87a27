//! Build options of a quadtree set, with validation and measured defaults.

use partition_sampler::{BuildError, LeafChoice, Refinement, Scheme, TreeParams};
use serde::{Deserialize, Serialize};

use crate::disc::DiscMap;

/// Which of the two partition-sampler schemes the trees of a set use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Variant {
    /// `adaptive` (default): [`Scheme::Envelope`] with [`LeafChoice::Alias`]. Exact: accepted
    /// points have density `f / ∫ f` whenever the leaf bounds hold, whatever the error of the
    /// grid integrals; mean trials `Σ V_i / Σ I_i ≤ n_max`.
    #[default]
    Adaptive,
    /// `adaptive-paper`: the papers' variant — leaf chosen ∝ `I_i` by the per-node CDF descent
    /// (seed 003 Algorithm 1), rejection repeated inside the leaf. Its true density is
    /// `(I_i / Î) f / ∫_leaf f`, equal to the reported `f / Î` only when the grid integrals
    /// `I_i` are exact. `sample_batch` uses the papers' batch split (seed 000 §3.6) with the
    /// randomized remainder.
    Paper,
}

impl Variant {
    pub(crate) fn scheme(&self) -> Scheme {
        match self {
            Variant::Adaptive => Scheme::Envelope,
            Variant::Paper => Scheme::Paper,
        }
    }

    pub(crate) fn leaf_choice(&self) -> LeafChoice {
        match self {
            Variant::Adaptive => LeafChoice::Alias,
            Variant::Paper => LeafChoice::Descent,
        }
    }
}

/// Which [`DiscMap`] the slices of a set use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DiscMapPolicy {
    /// **Default.** The papers' [`DiscMap::Projected`] for slices with
    /// `θo < `[`SetOptions::equal_area_from_deg`], [`DiscMap::EqualArea`] above (grazing lobes
    /// are squeezed against the rim of the projected disc, `dθ/dr = 1/cos θ`), and
    /// [`DiscMap::EqualArea`] for every slice of a BRDF that is unbounded at the horizon
    /// ([`brdf::Brdf::bounded_at_horizon`] is `false`): its projected density `f_r` has no
    /// finite leaf bound.
    #[default]
    Auto,
    /// Every slice on the projected disc (the papers' method, whatever the BRDF).
    Projected,
    /// Every slice on the equal-area disc.
    EqualArea,
}

impl DiscMapPolicy {
    /// The map of the slice of `brdf` at outgoing polar angle `theta_o_deg`, with `Auto`
    /// switching to equal-area at `equal_area_from_deg`.
    pub fn map_for(
        self,
        brdf: &dyn brdf::Brdf,
        theta_o_deg: f64,
        equal_area_from_deg: f64,
    ) -> DiscMap {
        match self {
            DiscMapPolicy::Projected => DiscMap::Projected,
            DiscMapPolicy::EqualArea => DiscMap::EqualArea,
            DiscMapPolicy::Auto
                if brdf.bounded_at_horizon() && theta_o_deg < equal_area_from_deg =>
            {
                DiscMap::Projected
            }
            DiscMapPolicy::Auto => DiscMap::EqualArea,
        }
    }

    /// Parses `auto`, `projected` or `equal-area`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "auto" => Some(DiscMapPolicy::Auto),
            "projected" => Some(DiscMapPolicy::Projected),
            "equal-area" => Some(DiscMapPolicy::EqualArea),
            _ => None,
        }
    }
}

/// Options of a [`crate::QuadTreeSet`].
///
/// Slices: isotropic BRDFs use `slices` outgoing polar angles at bin centres
/// `θ_j = (j + ½) · 90° / slices`; anisotropic ones use `anisotropic_slices = [nθ, nφ]`, the
/// same θ centres times azimuths `φ_k = k · 360° / nφ`. The trees' split parameters are the
/// partition sampler's own [`TreeParams`] (`tree`), with the defaults measured for BRDF sets
/// ([`SetOptions::DEFAULT_N_MAX`], [`SetOptions::DEFAULT_MAX_DEPTH`],
/// [`SetOptions::DEFAULT_VOLUME_TOLERANCE`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SetOptions {
    /// θ slices for isotropic BRDFs (default [`SetOptions::DEFAULT_SLICES`]).
    pub slices: usize,
    /// `[θ, φ]` slices for anisotropic BRDFs (default
    /// [`SetOptions::DEFAULT_ANISOTROPIC_SLICES`]).
    pub anisotropic_slices: [usize; 2],
    /// Split parameters of every slice's tree: a cell is split while `n_max · I_i / V_i < 1`,
    /// `depth < max_depth` (which must satisfy `2^(max_depth + 1) ≤ grid`: the image map is
    /// finer than the deepest leaf) and `V_i > volume_tolerance · I_root`. `tree.scheme` and
    /// `tree.leaf_choice` are set by the set's [`crate::Variant`] when it is built.
    pub tree: TreeParams,
    /// Image-map resolution per axis over `[-1, 1]²`, a power of two (default
    /// [`SetOptions::DEFAULT_GRID`]).
    pub grid: usize,
    /// Leaf bounds are `safety_factor ×` the sampled maxima (default
    /// [`partition_sampler::DEFAULT_SAFETY_FACTOR`]; must be ≥ 1).
    pub safety_factor: f64,
    /// Leaf bounds are the image-map maxima over the leaf grown by this many fine cells on
    /// every side (default 0). Piecewise-constant data need 1 (a fine cell can straddle a bin
    /// that none of its sample points hits): BRDFs named `merl` always get at least 1 (measured
    /// on a tabulated Phong: 0 violations instead of ~8000 per 10⁶ probes at θo ≥ 65°).
    pub bound_dilation: u32,
    /// Extra depth levels a slice may get when its expected trials exceed
    /// `refine_threshold` (default [`SetOptions::DEFAULT_REFINE_LEVELS`]): the slice is rebuilt
    /// with `max_depth + 1` and a grid twice as fine, at most `⌈slices/10⌉` slices (the worst
    /// ones) per level. This targets the grazing slices, where lobes are squeezed against the
    /// rim.
    pub refine_levels: u32,
    /// Expected trials per sample above which a slice is refined (default
    /// [`SetOptions::DEFAULT_REFINE_THRESHOLD`]).
    pub refine_threshold: f64,
    /// Sample the mixture of the two θ-neighbouring slices (linear weights in θ) instead of the
    /// nearest slice (default `false`).
    pub mixture: bool,
    /// Hemisphere-to-disc map of the slices (default [`DiscMapPolicy::Auto`]).
    pub disc_map: DiscMapPolicy,
    /// Outgoing polar angle (degrees) from which [`DiscMapPolicy::Auto`] uses the equal-area
    /// map (default [`SetOptions::DEFAULT_EQUAL_AREA_FROM_DEG`]; 90 = never for bounded BRDFs).
    pub equal_area_from_deg: f64,
    /// Curvature-driven refinement of the adaptive variant's image map (default
    /// `Some(Refinement::default())`: blocks from 32 × 32 down to the grid, 3 % excess);
    /// `None` = the dense image map. The papers' variant always uses the dense map, whose
    /// cell integrals are its leaf probabilities (seed 000 §3.7).
    pub grid_refinement: Option<Refinement>,
    /// Use the BRDF's declared symmetries (default `true`): an isotropic slice of a
    /// [`brdf::Brdf::is_mirror_symmetric`] BRDF evaluates its half `y ≤ 0` and mirrors it (a
    /// probe checks the declaration on every slice); an anisotropic
    /// [`brdf::Brdf::is_half_turn_symmetric`] BRDF stores its (even) `anisotropic_slices[1]`
    /// azimuths over `[0, π)` only, halving the trees at the same azimuth step.
    pub symmetries: bool,
}

impl SetOptions {
    /// Default number of θ slices for isotropic BRDFs (the papers used 60 and 90).
    pub const DEFAULT_SLICES: usize = 90;

    /// Default `[θ, φ]` slice grid for anisotropic BRDFs: 32 × 16 = 512 trees (θ step 2.8°,
    /// φ step 22.5°), 256 for a half-turn-symmetric BRDF (see [`SetOptions::symmetries`]).
    pub const DEFAULT_ANISOTROPIC_SLICES: [usize; 2] = [32, 16];

    /// Default split threshold `n_max` of BRDF sets: 1.8 rather than the generic
    /// [`TreeParams::DEFAULT_N_MAX`] = 2, chosen by measurement (docs/benchmarks.md §3: over
    /// the 18 fast analytic models, 1.47 BRDF evaluations per sample and 393 KiB per 90-slice
    /// set, against 1.52 and 343 KiB at the papers' `n_max = 2`).
    pub const DEFAULT_N_MAX: f64 = 1.8;

    /// Default maximum tree depth of BRDF sets (root = 0): leaves no smaller than `2/2⁷` of
    /// the disc's square, matching the default image map ([`SetOptions::DEFAULT_GRID`] =
    /// `2^(7 + 1)`). The generic [`TreeParams::DEFAULT_MAX_DEPTH`] = 12 serves tabulated data.
    pub const DEFAULT_MAX_DEPTH: u32 = 7;

    /// Default volume tolerance of BRDF sets: cells whose rejection volume is at most this
    /// fraction of the total integral are not split (each such leaf can add at most this many
    /// trials per sample). 2 % (measured: against 1 %, −29 % memory for +2 % evaluations per
    /// sample), against the generic [`TreeParams::DEFAULT_VOLUME_TOLERANCE`] = 1e-6.
    pub const DEFAULT_VOLUME_TOLERANCE: f64 = 2e-2;

    /// Default resolution (cells per axis) of the sampled image map: `2^(max_depth + 1)`, so
    /// the deepest leaf covers at least 2 × 2 fine cells.
    pub const DEFAULT_GRID: usize = 256;

    /// Default [`SetOptions::refine_levels`].
    pub const DEFAULT_REFINE_LEVELS: u32 = 2;

    /// Default [`SetOptions::refine_threshold`].
    pub const DEFAULT_REFINE_THRESHOLD: f64 = 3.0;

    /// Default [`SetOptions::equal_area_from_deg`].
    pub const DEFAULT_EQUAL_AREA_FROM_DEG: f64 = 80.0;

    /// Largest accepted slice count per axis.
    pub const MAX_SLICES: usize = 4096;

    /// Largest accepted grid resolution (the image map holds about `21 grid²` bytes per slice
    /// while a slice is being built).
    pub const MAX_GRID: usize = 4096;

    /// The deepest `max_depth` the image map of resolution `grid` supports:
    /// `log2(grid) − 1` (`2^(max_depth + 1) ≤ grid`), e.g. 7 at the default grid 256.
    pub fn max_depth_for_grid(grid: usize) -> u32 {
        grid.max(2).ilog2() - 1
    }
}

impl Default for SetOptions {
    fn default() -> Self {
        Self {
            slices: Self::DEFAULT_SLICES,
            anisotropic_slices: Self::DEFAULT_ANISOTROPIC_SLICES,
            tree: TreeParams {
                n_max: Self::DEFAULT_N_MAX,
                max_depth: Self::DEFAULT_MAX_DEPTH,
                volume_tolerance: Self::DEFAULT_VOLUME_TOLERANCE,
                ..TreeParams::default()
            },
            grid: Self::DEFAULT_GRID,
            safety_factor: partition_sampler::DEFAULT_SAFETY_FACTOR,
            bound_dilation: 0,
            refine_levels: Self::DEFAULT_REFINE_LEVELS,
            refine_threshold: Self::DEFAULT_REFINE_THRESHOLD,
            mixture: false,
            disc_map: DiscMapPolicy::Auto,
            equal_area_from_deg: Self::DEFAULT_EQUAL_AREA_FROM_DEG,
            grid_refinement: Some(Refinement::default()),
            symmetries: true,
        }
    }
}

/// An invalid [`SetOptions`] field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptionsError {
    /// A slice count is 0 or above [`SetOptions::MAX_SLICES`].
    #[error("{what} = {value} must be in 1 ..= {max}", max = SetOptions::MAX_SLICES)]
    InvalidSlices {
        /// Which count.
        what: &'static str,
        /// The value.
        value: usize,
    },
    /// The tree parameters are invalid (`n_max`, `max_depth`, tolerances).
    #[error("tree parameters: {0}")]
    Tree(BuildError),
    /// The grid must be a power of two in `4 ..= MAX_GRID`.
    #[error("grid = {0} must be a power of two in 4 ..= {max}", max = SetOptions::MAX_GRID)]
    InvalidGrid(usize),
    /// The image map must be finer than the deepest leaf: `2^(max_depth + 1) ≤ grid`.
    #[error(
        "max_depth = {max_depth} needs an image map of at least 2^(max_depth + 1) cells per axis, got grid = {grid} (its deepest is max_depth = {deepest})",
        deepest = SetOptions::max_depth_for_grid(*grid)
    )]
    GridTooCoarse {
        /// The maximum depth.
        max_depth: u32,
        /// The grid resolution.
        grid: usize,
    },
    /// The safety factor must be finite and ≥ 1.
    #[error("safety_factor = {0} must be finite and ≥ 1")]
    InvalidSafetyFactor(f64),
    /// The equal-area switch angle must be in `[0, 90]` degrees.
    #[error("equal_area_from_deg = {0} must be in [0, 90] degrees")]
    InvalidEqualAreaAngle(f64),
    /// The image-map refinement needs a power-of-two `coarsest ≥ 2` (clamped to the grid) and
    /// a finite tolerance `≥ 0`.
    #[error(
        "grid refinement: coarsest {coarsest} must be a power of two ≥ 2 and tolerance {tolerance} finite and ≥ 0"
    )]
    InvalidGridRefinement {
        /// The coarsest resolution.
        coarsest: usize,
        /// The tolerance.
        tolerance: f64,
    },
    /// Refinement would need a grid above [`SetOptions::MAX_GRID`] or a threshold that is not
    /// finite ≥ 1.
    #[error(
        "refinement: grid {grid} · 2^{levels} exceeds {max}, or threshold {threshold} is not finite and ≥ 1",
        max = SetOptions::MAX_GRID
    )]
    InvalidRefinement {
        /// The grid.
        grid: usize,
        /// `refine_levels`.
        levels: u32,
        /// `refine_threshold`.
        threshold: f64,
    },
}

/// The first of the slice counts of a sliced sampler's options (`slices` for isotropic
/// BRDFs, `anisotropic_slices` = `[θ, φ]`) outside `1 ..= max`, named as the options' errors
/// name it (`slices`, `anisotropic θ slices`, `anisotropic φ slices`); `None` when all fit.
pub fn bad_slice_count(
    slices: usize,
    anisotropic_slices: [usize; 2],
    max: usize,
) -> Option<(&'static str, usize)> {
    [
        ("slices", slices),
        ("anisotropic θ slices", anisotropic_slices[0]),
        ("anisotropic φ slices", anisotropic_slices[1]),
    ]
    .into_iter()
    .find(|&(_, value)| !(1..=max).contains(&value))
}

impl SetOptions {
    /// Checks every field (see [`OptionsError`]).
    pub fn validate(&self) -> Result<(), OptionsError> {
        if let Some((what, value)) =
            bad_slice_count(self.slices, self.anisotropic_slices, Self::MAX_SLICES)
        {
            return Err(OptionsError::InvalidSlices { what, value });
        }
        self.tree.validate().map_err(OptionsError::Tree)?;
        if !(self.grid.is_power_of_two() && (4..=Self::MAX_GRID).contains(&self.grid)) {
            return Err(OptionsError::InvalidGrid(self.grid));
        }
        let max_depth = self.tree.max_depth;
        let finest = 1u64.checked_shl(max_depth + 1).unwrap_or(u64::MAX);
        if max_depth > 30 || finest > self.grid as u64 {
            return Err(OptionsError::GridTooCoarse {
                max_depth,
                grid: self.grid,
            });
        }
        if !(self.safety_factor.is_finite() && self.safety_factor >= 1.0) {
            return Err(OptionsError::InvalidSafetyFactor(self.safety_factor));
        }
        if !(0.0..=90.0).contains(&self.equal_area_from_deg) {
            return Err(OptionsError::InvalidEqualAreaAngle(
                self.equal_area_from_deg,
            ));
        }
        if let Some(r) = self.grid_refinement
            && !(r.coarsest.is_power_of_two()
                && r.coarsest >= 2
                && r.tolerance.is_finite()
                && r.tolerance >= 0.0)
        {
            return Err(OptionsError::InvalidGridRefinement {
                coarsest: r.coarsest,
                tolerance: r.tolerance,
            });
        }
        let finest_grid = (self.grid as u64)
            .checked_shl(self.refine_levels.min(40))
            .unwrap_or(u64::MAX);
        if self.refine_levels > 12
            || finest_grid > Self::MAX_GRID as u64
            || !(self.refine_threshold.is_finite() && self.refine_threshold >= 1.0)
        {
            return Err(OptionsError::InvalidRefinement {
                grid: self.grid,
                levels: self.refine_levels,
                threshold: self.refine_threshold,
            });
        }
        Ok(())
    }

    /// The dilation used for `brdf`: [`SetOptions::bound_dilation`], at least 1 for the
    /// discontinuous measured data (`merl`'s bins, `cornell`'s nearest-neighbour blend).
    pub fn dilation_for(&self, brdf: &dyn brdf::Brdf) -> u32 {
        if matches!(brdf.name(), "merl" | "cornell") {
            self.bound_dilation.max(1)
        } else {
            self.bound_dilation
        }
    }

    /// The options with `max_depth` and the matching grid `2^(max_depth + 1)`.
    pub fn with_depth(mut self, max_depth: u32) -> Self {
        self.tree.max_depth = max_depth;
        self.grid = 1usize.checked_shl(max_depth + 1).unwrap_or(0);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_errors_are_typed() {
        assert_eq!(SetOptions::default().validate(), Ok(()));
        let o = SetOptions::default();
        let bad = |f: fn(&mut SetOptions)| {
            let mut x = o;
            f(&mut x);
            x.validate().unwrap_err()
        };
        assert!(matches!(
            bad(|o| o.slices = 0),
            OptionsError::InvalidSlices { .. }
        ));
        assert!(matches!(
            bad(|o| o.anisotropic_slices[1] = 0),
            OptionsError::InvalidSlices { .. }
        ));
        assert!(matches!(
            bad(|o| o.tree.n_max = f64::NAN),
            OptionsError::Tree(BuildError::InvalidNMax(_))
        ));
        assert!(matches!(
            bad(|o| o.tree.n_max = 0.5),
            OptionsError::Tree(BuildError::InvalidNMax(_))
        ));
        assert!(matches!(
            bad(|o| o.grid = 100),
            OptionsError::InvalidGrid(100)
        ));
        assert!(matches!(
            bad(|o| o.tree.max_depth = 8),
            OptionsError::GridTooCoarse { .. }
        ));
        assert!(matches!(
            bad(|o| o.tree.max_depth = 99),
            OptionsError::Tree(BuildError::MaxDepthTooLarge(99))
        ));
        assert!(matches!(
            bad(|o| o.safety_factor = 0.9),
            OptionsError::InvalidSafetyFactor(_)
        ));
        assert!(matches!(
            bad(|o| o.tree.volume_tolerance = -1.0),
            OptionsError::Tree(BuildError::InvalidVolumeTolerance(_))
        ));
        assert!(matches!(
            bad(|o| o.refine_levels = 5),
            OptionsError::InvalidRefinement { .. }
        ));
        assert!(matches!(
            bad(|o| o.refine_threshold = f64::NAN),
            OptionsError::InvalidRefinement { .. }
        ));
        assert!(matches!(
            bad(|o| o.equal_area_from_deg = f64::NAN),
            OptionsError::InvalidEqualAreaAngle(_)
        ));
        assert_eq!(SetOptions::default().with_depth(5).grid, 64);
        assert_eq!(SetOptions::default().with_depth(5).validate(), Ok(()));
        assert_eq!(SetOptions::max_depth_for_grid(SetOptions::DEFAULT_GRID), 7);
        let msg = bad(|o| o.tree.max_depth = 8).to_string();
        assert!(msg.contains("deepest is max_depth = 7"), "{msg}");
    }
}
