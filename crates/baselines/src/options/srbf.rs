//! Options of the SRBF baselines (Tsai et al. 2008): the `srbf` sampler and the product
//! estimator.

use crate::srbf::{FitSettings, ProductSettings, SrbfError};

/// Options of the SRBF fits and the product estimator (defaults: baselines.md §C.2 [D]).
#[derive(Debug, Clone, PartialEq)]
pub struct SrbfOptions {
    /// Outgoing-angle slices `θo` (isotropic BRDFs; slice `j` is fitted at
    /// `θ_j = (j + ½)·90°/slices`).
    pub slices: usize,
    /// Azimuthal slices `φo` of anisotropic BRDFs (a `slices × phi_slices` grid over
    /// `[0, 2π)`).
    pub phi_slices: usize,
    /// Lobes per BRDF slice `K_B`.
    pub brdf_lobes: usize,
    /// Bandwidth bounds `[λ_min, λ_max]` of the BRDF lobes.
    pub brdf_lambda: (f64, f64),
    /// Polar rows of the hemisphere grid each slice is fitted on (`4·rows` azimuths).
    pub fit_rows: usize,
    /// Share `ε ∈ [0, 1)` of cosine-hemisphere sampling mixed into the `srbf` sampler's slice
    /// mixtures (defensive; `0` = the SRBF mixture alone).
    pub brdf_defensive: f64,
    /// Lobes of the environment map `K_L`.
    pub map_lobes: usize,
    /// Bandwidth bounds of the map's lobes.
    pub map_lambda: (f64, f64),
    /// Width of the box-filtered copy of the map that is fitted (height = width / 2).
    pub map_fit_width: usize,
    /// Iteration cap per fit: Levenberg–Marquardt trial steps of each BRDF slice, L-BFGS
    /// iterations of the map. A safety net: the fits stop at their convergence tests (the 32
    /// slices of `phong:n=50` need 38–1337 steps; docs/benchmarks.md).
    pub max_iter: usize,
    /// Product lobes kept (largest masses) by the product estimator.
    pub product_lobes: usize,
    /// Share of the product estimator's samples given to the BRDF slice's lobes
    /// (defensive components, `[0, 1 − γ − β)` with `γ`, `β` = `ProductSettings::DEFAULT_COSINE`,
    /// `DEFAULT_LIGHT` the cosine and light components' shares; see
    /// `estimators::estimate_srbf_product`).
    pub defensive: f64,
}

impl Default for SrbfOptions {
    fn default() -> Self {
        Self {
            slices: Self::DEFAULT_SLICES,
            phi_slices: 8,
            brdf_lobes: 8,
            brdf_lambda: (0.5, 2e4),
            fit_rows: 32,
            brdf_defensive: 0.1,
            map_lobes: 64,
            map_lambda: (0.5, 5e3),
            map_fit_width: 128,
            max_iter: 2000,
            product_lobes: 32,
            defensive: 0.2,
        }
    }
}

impl SrbfOptions {
    /// Default number of `θo` slices.
    pub const DEFAULT_SLICES: usize = 32;
    /// Largest accepted slice count, fit grid and map width.
    pub const MAX_RESOLUTION: usize = 4096;

    /// Checks every option: lobe counts ≥ 1, `0 < λ_min < λ_max < ∞`, resolutions in
    /// `1..=MAX_RESOLUTION` (map width ≥ 2).
    pub fn validate(&self) -> Result<(), SrbfError> {
        self.brdf_settings().validate("per-slice")?;
        self.map_settings().validate("map")?;
        if self.product_lobes == 0 {
            return Err(SrbfError::ZeroLobes {
                what: "kept product",
            });
        }
        self.product_settings().validate()?;
        for (what, got, min) in [
            ("slices", self.slices, 1),
            ("phi slices", self.phi_slices, 1),
            ("fit rows", self.fit_rows, 1),
            ("map fit width", self.map_fit_width, 2),
        ] {
            if got < min || got > Self::MAX_RESOLUTION {
                return Err(SrbfError::BadResolution {
                    what,
                    max: Self::MAX_RESOLUTION,
                    got,
                });
            }
        }
        Ok(())
    }

    /// Fit settings of one BRDF slice.
    pub fn brdf_settings(&self) -> FitSettings {
        self.fit(self.brdf_lobes, self.brdf_lambda)
    }

    /// Fit settings of `lobes` lobes with bandwidths in `[λ_min, λ_max]`, at this iteration cap.
    fn fit(&self, lobes: usize, (lambda_min, lambda_max): (f64, f64)) -> FitSettings {
        FitSettings {
            lobes,
            lambda_min,
            lambda_max,
            max_iter: self.max_iter,
        }
    }

    /// Settings of the product estimator.
    pub fn product_settings(&self) -> ProductSettings {
        ProductSettings {
            keep: self.product_lobes,
            defensive: self.defensive,
            cosine: ProductSettings::DEFAULT_COSINE,
            light: ProductSettings::DEFAULT_LIGHT,
        }
    }

    /// Fit settings of the environment map.
    pub fn map_settings(&self) -> FitSettings {
        self.fit(self.map_lobes, self.map_lambda)
    }
}
