//! Settings of the SRBF product estimator (Tsai et al. 2008, baselines.md §C.4): the share of
//! each component of its mixture. The estimator itself, like every estimator of reflected
//! radiance (BRDF, light, MIS), lives in the `estimators` crate; the settings stay here beside
//! the fits' options ([`crate::SrbfOptions::product_settings`]).

use super::SrbfError;

/// Settings of the SRBF product estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProductSettings {
    /// Product lobes kept (largest masses `I_m`), ≥ 1.
    pub keep: usize,
    /// Share `δ ∈ [0, 1)` of the samples given to the BRDF slice's own lobes (the `srbf`
    /// mixture) as defensive components of the same balance-heuristic mixture [D]. `0` drops
    /// them; see `estimators::estimate_srbf_product` for why the default is not 0.
    pub defensive: f64,
    /// Share `γ ∈ (0, 1)` of the samples drawn from `cos⁺θ/π` on the local hemisphere, the
    /// component that bounds the mixture's density below wherever the integrand can be
    /// non-zero (see `estimators::estimate_srbf_product`).
    pub cosine: f64,
    /// Share `β ∈ [0, 1)` of the samples drawn from the map sampler given to
    /// `estimators::estimate_srbf_product` (light sampling as one more component of the mixture); `δ + γ
    /// + β < 1`.
    pub light: f64,
}

impl ProductSettings {
    /// Default cosine share `γ`.
    pub const DEFAULT_COSINE: f64 = 0.1;
    /// Default light share `β`.
    pub const DEFAULT_LIGHT: f64 = 0.1;

    /// Checks `keep ≥ 1`, `δ ∈ [0, 1)`, `γ ∈ (0, 1)`, `β ∈ [0, 1)` and `δ + γ + β < 1`.
    pub fn validate(&self) -> Result<(), SrbfError> {
        if self.keep == 0 {
            return Err(SrbfError::ZeroLobes {
                what: "kept product",
            });
        }
        if !((0.0..1.0).contains(&self.defensive)) {
            return Err(SrbfError::BadDefensive {
                value: self.defensive,
            });
        }
        if !(self.cosine > 0.0
            && self.cosine < 1.0
            && (0.0..1.0).contains(&self.light)
            && self.defensive + self.cosine + self.light < 1.0)
        {
            return Err(SrbfError::BadCosineShare {
                cosine: self.cosine,
                light: self.light,
                defensive: self.defensive,
            });
        }
        Ok(())
    }
}

impl Default for ProductSettings {
    fn default() -> Self {
        Self {
            keep: 32,
            defensive: 0.2,
            cosine: Self::DEFAULT_COSINE,
            light: Self::DEFAULT_LIGHT,
        }
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_refuse_a_mixture_without_a_positive_cosine_share() {
        for (cosine, defensive, light) in [
            (0.0, 0.2, 0.1),
            (-0.1, 0.2, 0.1),
            (f64::NAN, 0.2, 0.1),
            (0.5, 0.5, 0.0),
            (1.0, 0.0, 0.0),
            (0.1, 0.2, 0.7),
            (0.1, 0.2, -0.1),
        ] {
            let s = ProductSettings {
                keep: 4,
                defensive,
                cosine,
                light,
            };
            assert!(
                matches!(s.validate(), Err(SrbfError::BadCosineShare { .. })),
                "{cosine} {defensive} {light}"
            );
        }
        assert!(ProductSettings::default().validate().is_ok());
    }
}
