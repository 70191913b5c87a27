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
    beckmann_lambda_with_erfc(a, erfc(a))
}

/// [`beckmann_lambda`] given `erfc_a = erfc(a)` already computed by the caller (same value,
/// saves one `erfc` when the caller needs `erfc(a)` too).
#[inline]
pub(crate) fn beckmann_lambda_with_erfc(a: f64, erfc_a: f64) -> f64 {
    if !(a > 0.0) {
        // Grazing (tanθ = ∞): Λ → ∞.
        return f64::INFINITY;
    }
    if a > 26.0 {
        // e^{-a²} underflows; Λ is below 1e-290.
        return 0.0;
    }
    (0.5 * ((-a * a).exp() * FRAC_1_SQRT_PI / a - erfc_a)).max(0.0)
}

/// `ln Γ(x) − ln Γ(y)` for `x, y ≥ 1/2`, without the cancellation of subtracting two large
/// `ln Γ` values (relative accuracy ~10⁻¹⁵ of the difference plus 10⁻¹⁵ absolute, also for
/// `x, y ~ 10⁴`).
pub(crate) fn ln_gamma_diff(x: f64, y: f64) -> f64 {
    let (_, ax) = lanczos(x);
    let (ty, ay) = lanczos(y);
    // (x − ½) ln tx − (y − ½) ln ty − (tx − ty), with tx − ty = x − y.
    let d = x - y;
    (x - 0.5) * (d / ty).ln_1p() + d * ty.ln() - d + (ax / ay).ln()
}

/// Lanczos decomposition (g = 7, 9 terms; relative error of `Γ` below 10⁻¹⁴)
/// `Γ(x) = √(2π) t^{x−1/2} e^{−t} A(x)` for `x ≥ 1/2`: returns `(t, A)` with `t = x + 6.5`.
fn lanczos(x: f64) -> (f64, f64) {
    const COEFFS: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let z = x - 1.0;
    let mut a = COEFFS[0];
    for (i, c) in COEFFS.iter().enumerate().skip(1) {
        a += c / (z + i as f64);
    }
    (z + 7.5, a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// `ln Γ(x)` for `x > 0` (Lanczos approximation, g = 7, 9 terms; relative error of `Γ` below
    /// 10⁻¹⁴ over the range used here).
    fn ln_gamma(x: f64) -> f64 {
        if x < 0.5 {
            // Reflection Γ(x)Γ(1−x) = π/sin(πx).
            return (PI / (PI * x).sin()).abs().ln() - ln_gamma(1.0 - x);
        }
        let (t, series) = lanczos(x);
        0.5 * (2.0 * PI).ln() + (x - 0.5) * t.ln() - t + series.ln()
    }

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
    fn ln_gamma_matches_factorials_and_half_integers() {
        let mut ln_fact = 0.0f64;
        for k in 1..=170u32 {
            ln_fact += f64::from(k).ln();
            let g = ln_gamma(f64::from(k) + 1.0);
            assert!((g - ln_fact).abs() <= 1e-13 * ln_fact.max(1.0), "k={k}");
        }
        // Γ(1/2) = √π, Γ(3/2) = √π/2.
        assert!((ln_gamma(0.5) - 0.5 * PI.ln()).abs() < 1e-14);
        assert!((ln_gamma(1.5) - (0.5 * PI.ln() - 2f64.ln())).abs() < 1e-14);
        // Γ(x+1) = x Γ(x) for non-integers, including large x.
        for x in [0.3, 2.7, 19.5, 1234.25, 9999.5] {
            let d = ln_gamma(x + 1.0) - ln_gamma(x) - f64::ln(x);
            assert!(d.abs() < 1e-12 * ln_gamma(x + 1.0).abs().max(1.0), "x={x}");
        }
    }

    #[test]
    fn ln_gamma_diff_is_accurate_for_large_arguments() {
        // Small arguments: agrees with the difference of ln Γ.
        for (x, y) in [(1.0, 1.5), (3.2, 7.9), (20.0, 20.5)] {
            let d = ln_gamma_diff(x, y) - (ln_gamma(x) - ln_gamma(y));
            assert!(d.abs() < 1e-14, "({x}, {y}): {d}");
        }
        // Γ(n+1)/Γ(n+3/2) = n^{−1/2} (1 − 3/(8n) + 25/(128 n²) + O(n⁻³)).
        for n in [1e3, 1e4, 1e5] {
            let expect = -0.5 * f64::ln(n) + (-3.0 / (8.0 * n) + 25.0 / (128.0 * n * n)).ln_1p();
            let d = ln_gamma_diff(n + 1.0, n + 1.5) - expect;
            assert!(d.abs() < 1e-14 + 1.0 / n.powi(3), "n={n}: {d}");
        }
        // Γ(x+1)/Γ(y+1) = (x/y) Γ(x)/Γ(y) exactly.
        for (x, y) in [(10_000.25, 10_000.75), (512.0, 498.5)] {
            let d = ln_gamma_diff(x + 1.0, y + 1.0) - ln_gamma_diff(x, y) - (x / y).ln();
            assert!(d.abs() < 1e-14, "({x}, {y}): {d}");
        }
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
