//! Spectra to linear RGB with the CIE 1931 2° standard observer.
//!
//! **Colour matching functions.** `x̄, ȳ, z̄` are evaluated with the multi-lobe piecewise-Gaussian
//! fit of Wyman, Sloan & Shirley (2013, "Simple Analytic Approximations to the CIE XYZ Color
//! Matching Functions", JCGT 2(2)): each function is a sum of lobes
//! `a · exp(−½ ((λ − μ)/σ)²)` with `σ = σ₁` below `μ` and `σ₂` above. The fit is within about
//! 1 % of the CIE table's peak values over the visible range (this replaces embedding the
//! 471-row CIE table; no maintained crate with the table was found suitable).
//!
//! **Conversion.** A spectrum `s(λ)` sampled at increasing wavelengths is integrated with the
//! trapezoid rule against the CMFs and normalised by `∫ȳ` over the same wavelengths, so a
//! constant spectrum `s ≡ c` has `Y = c` (reflectance-like quantities keep their scale);
//! the white point is moved from equal energy (a flat reflectance spectrum) to D65 by XYZ
//! scaling (`X·0.95047`, `Z·1.08883`), so flat spectra come out grey; then
//! `XYZ → linear Rec. 709 / sRGB` by the standard matrix. The result's
//! [`luminance`](crate::luminance) equals `Y` up to the matrix's rounding.

/// `(a, μ, σ₁, σ₂)` lobes of `x̄` (nm).
const X_LOBES: [(f64, f64, f64, f64); 3] = [
    (1.056, 599.8, 37.9, 31.0),
    (0.362, 442.0, 16.0, 26.7),
    (-0.065, 501.1, 20.4, 26.2),
];
/// Lobes of `ȳ`.
const Y_LOBES: [(f64, f64, f64, f64); 2] = [(0.821, 568.8, 46.9, 40.5), (0.286, 530.9, 16.3, 31.1)];
/// Lobes of `z̄`.
const Z_LOBES: [(f64, f64, f64, f64); 2] = [(1.217, 437.0, 11.8, 36.0), (0.681, 459.0, 26.0, 13.8)];

/// Linear sRGB from CIE XYZ (Rec. 709 primaries, D65 white), rows R, G, B.
pub const XYZ_TO_LINEAR_SRGB: [[f64; 3]; 3] = [
    [3.240_454_2, -1.537_138_5, -0.498_531_4],
    [-0.969_266_0, 1.876_010_8, 0.041_556_0],
    [0.055_643_4, -0.204_025_9, 1.057_225_2],
];

/// CIE XYZ of the D65 white point with `Y = 1`.
pub const D65_WHITE: [f64; 3] = [0.950_47, 1.0, 1.088_83];

fn lobes(lambda: f64, l: &[(f64, f64, f64, f64)]) -> f64 {
    l.iter()
        .map(|&(a, mu, s1, s2)| {
            let t = (lambda - mu) / if lambda < mu { s1 } else { s2 };
            a * (-0.5 * t * t).exp()
        })
        .sum()
}

/// `(x̄, ȳ, z̄)` of the CIE 1931 2° observer at `lambda` nm (the analytic fit above).
pub fn cie1931(lambda: f64) -> [f64; 3] {
    [
        lobes(lambda, &X_LOBES),
        lobes(lambda, &Y_LOBES),
        lobes(lambda, &Z_LOBES),
    ]
}

/// Precomputed trapezoid weights of a wavelength list: `w_k[c] = cmf_c(λ_k) · Δλ_k / ∫ȳ`.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumToRgb {
    weights: Vec<[f64; 3]>,
}

/// Why a wavelength list cannot be converted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WavelengthError {
    /// Fewer than two wavelengths.
    TooFew,
    /// Not finite or not strictly increasing.
    NotIncreasing,
    /// `∫ȳ` over the list is below 1e-9 (every wavelength outside the visible range).
    Invisible,
}

impl SpectrumToRgb {
    /// Weights for spectra sampled at `wavelengths` (nm, strictly increasing, at least 2).
    pub fn new(wavelengths: &[f64]) -> Result<Self, WavelengthError> {
        if wavelengths.len() < 2 {
            return Err(WavelengthError::TooFew);
        }
        if !wavelengths.iter().all(|l| l.is_finite())
            || wavelengths.windows(2).any(|w| !(w[1] > w[0]))
        {
            return Err(WavelengthError::NotIncreasing);
        }
        let n = wavelengths.len();
        let mut weights: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let lo = if k > 0 {
                    wavelengths[k - 1]
                } else {
                    wavelengths[k]
                };
                let hi = if k + 1 < n {
                    wavelengths[k + 1]
                } else {
                    wavelengths[k]
                };
                let dl = 0.5 * (hi - lo);
                cie1931(wavelengths[k]).map(|c| c * dl)
            })
            .collect();
        let y_total: f64 = weights.iter().map(|w| w[1]).sum();
        if !(y_total > 1e-9) {
            return Err(WavelengthError::Invisible);
        }
        for w in &mut weights {
            *w = w.map(|c| c / y_total);
        }
        Ok(Self { weights })
    }

    /// CIE XYZ of a spectrum sampled at the wavelengths (`Y` = 1 for a constant 1).
    pub fn xyz(&self, spectrum: &[f64]) -> [f64; 3] {
        let mut xyz = [0.0; 3];
        for (w, s) in self.weights.iter().zip(spectrum) {
            for c in 0..3 {
                xyz[c] += w[c] * s;
            }
        }
        xyz
    }

    /// Linear sRGB of a spectrum sampled at the wavelengths.
    pub fn rgb(&self, spectrum: &[f64]) -> [f64; 3] {
        let [x, y, z] = self.xyz(spectrum);
        let xyz = [x * D65_WHITE[0], y, z * D65_WHITE[2]];
        XYZ_TO_LINEAR_SRGB.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Known properties of the CIE 1931 observer: `ȳ` peaks near 555 nm at about 1, the three
    /// integrals over 380–780 nm are equal (equal-energy white is at x = y = 1/3) and ≈ 106.9.
    #[test]
    fn the_fit_has_the_observers_landmarks() {
        let y555 = cie1931(555.0)[1];
        assert!((y555 - 1.0).abs() < 0.02, "{y555}");
        let mut ints = [0.0; 3];
        for k in 0..4000 {
            let l = 380.0 + 0.1 * (k as f64 + 0.5);
            let c = cie1931(l);
            for i in 0..3 {
                ints[i] += 0.1 * c[i];
            }
        }
        for i in 0..3 {
            assert!((ints[i] - 106.86).abs() < 2.0, "{ints:?}");
        }
        let sum: f64 = ints.iter().sum();
        assert!(
            (ints[0] / sum - 1.0 / 3.0).abs() < 0.01 && (ints[1] / sum - 1.0 / 3.0).abs() < 0.01
        );
    }

    #[test]
    fn flat_spectra_are_grey_with_their_value_as_luminance() {
        let wl: Vec<f64> = (0..31).map(|k| 400.0 + 10.0 * k as f64).collect();
        let c = SpectrumToRgb::new(&wl).expect("valid");
        let rgb = c.rgb(&[0.5; 31]);
        assert!((crate::luminance(rgb) - 0.5).abs() < 1e-3, "{rgb:?}");
        // A flat spectrum is grey (within the fit's accuracy).
        assert!(rgb.iter().all(|v| (v - 0.5).abs() < 0.02), "{rgb:?}");
        // A spectrum concentrated at long wavelengths is red.
        let red: Vec<f64> = wl
            .iter()
            .map(|&l| if l >= 620.0 { 1.0 } else { 0.0 })
            .collect();
        let r = c.rgb(&red);
        assert!(r[0] > 5.0 * r[1].abs() && r[0] > 5.0 * r[2].abs(), "{r:?}");
        assert_eq!(SpectrumToRgb::new(&[500.0]), Err(WavelengthError::TooFew));
        assert_eq!(
            SpectrumToRgb::new(&[500.0, 400.0]),
            Err(WavelengthError::NotIncreasing)
        );
        assert_eq!(
            SpectrumToRgb::new(&[1000.0, 1100.0]),
            Err(WavelengthError::Invisible)
        );
    }
}
