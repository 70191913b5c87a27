//! Special functions needed by the microfacet and wave-optics models.

/// Complementary error function `erfc(x) = 1 − erf(x)`, relative error below 1.2·10⁻⁷ for all
/// real `x` (Chebyshev fit of `erfc(x)·exp(x²)`, Press et al., *Numerical Recipes*, §6.2).
///
/// The error is *relative*, so the tail `erfc(x) ~ e^{-x²}/(x√π)` stays accurate for large `x`,
/// which the Smith Λ functions rely on.
#[inline]
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// Error function `erf(x) = 1 − erfc(x)` (absolute error below 1.2·10⁻⁷).
#[inline]
pub fn erf(x: f64) -> f64 {
    1.0 - erfc(x)
}

/// `1/√π`.
pub(crate) const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;

/// Smith Λ for the Beckmann distribution: `Λ(a) = (e^{−a²}/(a√π) − erfc(a)) / 2`, where
/// `a = 1/(α tanθ)`. Clamped to `≥ 0` (the exact Λ is non-negative; the clamp only removes
/// rounding noise for large `a`).
#[inline]
pub(crate) fn beckmann_lambda(a: f64) -> f64 {
    if !(a > 0.0) {
        // Grazing (tanθ = ∞): Λ → ∞.
        return f64::INFINITY;
    }
    if a > 26.0 {
        // e^{-a²} underflows; Λ is below 1e-290.
        return 0.0;
    }
    (0.5 * ((-a * a).exp() * FRAC_1_SQRT_PI / a - erfc(a))).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent high-accuracy erfc: Taylor series of erf for |x| < 2, Lentz continued
    /// fraction for x ≥ 2.
    fn erfc_reference(x: f64) -> f64 {
        if x < 0.0 {
            return 2.0 - erfc_reference(-x);
        }
        if x < 2.0 {
            let mut sum = 0.0;
            let mut term = x; // x^{2n+1}/n!
            let mut n = 0.0;
            loop {
                let add = term / (2.0 * n + 1.0);
                sum += add;
                if add.abs() < 1e-18 {
                    break;
                }
                n += 1.0;
                term *= -x * x / n;
            }
            1.0 - 2.0 * FRAC_1_SQRT_PI * sum
        } else {
            // erfc(x) = e^{-x²}/√π · 1/(x + (1/2)/(x + 1/(x + (3/2)/(x + ...))))
            let tiny = 1e-300;
            let mut f = x;
            let mut c = x;
            let mut d = 0.0;
            for k in 1..200 {
                let a = k as f64 / 2.0;
                d = x + a * d;
                if d.abs() < tiny {
                    d = tiny;
                }
                c = x + a / c;
                if c.abs() < tiny {
                    c = tiny;
                }
                d = 1.0 / d;
                let delta = c * d;
                f *= delta;
                if (delta - 1.0).abs() < 1e-16 {
                    break;
                }
            }
            (-x * x).exp() * FRAC_1_SQRT_PI / f
        }
    }

    #[test]
    fn erfc_matches_reference_in_relative_error() {
        let mut x = -5.0;
        while x <= 25.0 {
            let r = erfc_reference(x);
            let e = erfc(x);
            assert!(((e - r) / r).abs() < 1.3e-7, "x={x} erfc={e} ref={r}");
            x += 0.01;
        }
    }

    #[test]
    fn erfc_known_values() {
        assert!((erfc(0.0) - 1.0).abs() < 1.3e-7);
        assert!((erf(1.0) - 0.842_700_792_949_714_9).abs() < 1.3e-7);
        assert!((erfc(3.0) / 2.209_049_699_858_544e-5 - 1.0).abs() < 1.3e-7);
    }

    #[test]
    fn beckmann_lambda_limits() {
        assert_eq!(beckmann_lambda(30.0), 0.0);
        assert!(beckmann_lambda(0.0).is_infinite());
        // Monotone decreasing in a.
        let mut prev = f64::INFINITY;
        let mut a = 0.05;
        while a < 10.0 {
            let l = beckmann_lambda(a);
            assert!(l <= prev + 1e-12 && l >= 0.0, "a={a}");
            prev = l;
            a += 0.05;
        }
    }
}
