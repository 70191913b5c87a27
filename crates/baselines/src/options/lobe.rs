//! Options of the lobe baselines (`lobe-sphere`, `lobe-hemisphere`; `analytic` has none).

use crate::lobe::LobeError;

/// Options of the cosine-lobe baselines.
///
/// The lobe `(n+1)/(2π)·max(0, ω_r·ω)^n` around the mirror direction is mixed with cosine
/// hemisphere sampling (weight `w`, see [`crate::LobeSampler`]). Per outgoing slice the exponent
/// `n` and the weight `w` are fitted to minimise the estimator's second moment; `exponent`
/// fixes `n` instead.
#[derive(Debug, Clone, PartialEq)]
pub struct LobeOptions {
    /// Fixed exponent for every slice (`--lobe-exponent`); `None` fits it per slice.
    pub exponent: Option<f64>,
    /// Number of outgoing polar-angle slices over `[0°, 90°)` (`--lobe-slices`).
    pub slices: usize,
    /// Number of outgoing azimuth slices for anisotropic BRDFs, over `[0, π)` when the BRDF is
    /// half-turn symmetric, else over `[0, 2π)`.
    pub phi_slices: usize,
    /// Smallest exponent the fit may choose.
    pub min_exponent: f64,
    /// Largest exponent the fit may choose.
    pub max_exponent: f64,
    /// Smallest weight of the defensive cosine component the fit may choose (it keeps the
    /// sampler unbiased where the lobe is zero).
    pub min_defensive: f64,
}

impl LobeOptions {
    /// Default number of θo slices.
    pub const DEFAULT_SLICES: usize = 16;
    /// Default number of φo slices (anisotropic BRDFs).
    pub const DEFAULT_PHI_SLICES: usize = 8;
    /// Default smallest fitted exponent.
    pub const DEFAULT_MIN_EXPONENT: f64 = 0.0;
    /// Default largest fitted exponent.
    pub const DEFAULT_MAX_EXPONENT: f64 = 1e4;
    /// Default smallest defensive weight.
    pub const DEFAULT_MIN_DEFENSIVE: f64 = 0.02;
    /// Largest exponent accepted anywhere (fixed or as a fit bound).
    pub const MAX_EXPONENT: f64 = 1e6;
    /// Largest number of slices along either axis.
    pub const MAX_SLICES: usize = 1024;

    /// Checks every field.
    ///
    /// Errors: [`LobeError::Exponent`] for an exponent or bound outside `[0, 10⁶]` (or bounds
    /// out of order), [`LobeError::Slices`] for a slice count outside `[1, 1024]`,
    /// [`LobeError::Defensive`] for a defensive weight outside `(0, 1]`.
    pub fn validate(&self) -> Result<(), LobeError> {
        let max = Self::MAX_EXPONENT;
        for (what, value) in [
            ("exponent", self.exponent),
            ("min_exponent", Some(self.min_exponent)),
            ("max_exponent", Some(self.max_exponent)),
        ] {
            if let Some(v) = value
                && !(v >= 0.0 && v <= max)
            {
                return Err(LobeError::Exponent {
                    what,
                    value: v,
                    max,
                });
            }
        }
        if !(self.min_exponent <= self.max_exponent) {
            return Err(LobeError::Exponent {
                what: "max_exponent (below min_exponent)",
                value: self.max_exponent,
                max,
            });
        }
        for (what, n) in [("slices", self.slices), ("phi_slices", self.phi_slices)] {
            if !(1..=Self::MAX_SLICES).contains(&n) {
                return Err(LobeError::Slices {
                    what,
                    value: n,
                    max: Self::MAX_SLICES,
                });
            }
        }
        if !(self.min_defensive > 0.0 && self.min_defensive <= 1.0) {
            return Err(LobeError::Defensive(self.min_defensive));
        }
        Ok(())
    }
}

impl Default for LobeOptions {
    fn default() -> Self {
        Self {
            exponent: None,
            slices: Self::DEFAULT_SLICES,
            phi_slices: Self::DEFAULT_PHI_SLICES,
            min_exponent: Self::DEFAULT_MIN_EXPONENT,
            max_exponent: Self::DEFAULT_MAX_EXPONENT,
            min_defensive: Self::DEFAULT_MIN_DEFENSIVE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_name_the_field() {
        assert!(LobeOptions::default().validate().is_ok());
        let bad = [
            LobeOptions {
                exponent: Some(-1.0),
                ..LobeOptions::default()
            },
            LobeOptions {
                exponent: Some(f64::NAN),
                ..LobeOptions::default()
            },
            LobeOptions {
                min_exponent: 10.0,
                max_exponent: 1.0,
                ..LobeOptions::default()
            },
            LobeOptions {
                slices: 0,
                ..LobeOptions::default()
            },
            LobeOptions {
                min_defensive: 0.0,
                ..LobeOptions::default()
            },
        ];
        for o in bad {
            assert!(o.validate().is_err(), "{o:?}");
        }
        let e = LobeOptions {
            slices: 0,
            ..LobeOptions::default()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("[1, 1024]"), "{e}");
    }
}
