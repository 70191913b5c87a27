//! Colour science shared by every brdf-lab crate: the one luminance formula.
//!
//! Colours are **linear** RGB with Rec. 709 / sRGB primaries and D65 white (no transfer curve:
//! MERL reflectances and HDR/EXR/PFM radiances are linear already). RGB quantities are sampled
//! proportionally to their luminance `Y` ([`luminance`]).
//!
//! It also holds the CIE 1931 spectral-to-RGB conversion of measured spectral BRDFs
//! ([`spectral`]), so that every crate converts colour the same way. It depends on nothing.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod spectral;

pub use spectral::{SpectrumToRgb, WavelengthError, cie1931};

/// Rec. 709 / sRGB luminance weights of linear R, G and B: `Y = 0.2126 R + 0.7152 G + 0.0722 B`
/// (the `Y` row of the linear-sRGB-to-CIE-XYZ matrix; the weights sum to 1).
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B` of a linear RGB triple with Rec. 709 / sRGB
/// primaries ([`LUMINANCE_WEIGHTS`]).
///
/// ```
/// use colour::luminance;
/// assert_eq!(luminance([1.0, 1.0, 1.0]), 1.0); // white has unit luminance
/// assert_eq!(luminance([0.0, 1.0, 0.0]), 0.7152); // green dominates
/// assert_eq!(luminance([0.0, 0.0, 2.0]), 0.1444);
/// ```
#[inline]
pub fn luminance(rgb: [f64; 3]) -> f64 {
    LUMINANCE_WEIGHTS[0] * rgb[0] + LUMINANCE_WEIGHTS[1] * rgb[1] + LUMINANCE_WEIGHTS[2] * rgb[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_luminance_is_linear() {
        assert!((LUMINANCE_WEIGHTS.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(luminance([0.0; 3]), 0.0);
        assert_eq!(luminance([1.0, 0.0, 0.0]), 0.2126);
        assert_eq!(luminance([0.0, 0.0, 1.0]), 0.0722);
        let (a, b) = ([0.3, 0.5, 0.9], [1.5, 0.25, 0.0]);
        let sum = luminance([a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
        assert!((sum - luminance(a) - luminance(b)).abs() < 1e-15);
        assert!(
            (luminance([2.0 * a[0], 2.0 * a[1], 2.0 * a[2]]) - 2.0 * luminance(a)).abs() < 1e-15
        );
    }
}
