//! Fresnel reflectance for unpolarised light.

/// Schlick's approximation `F(c) = f0 + (1 − f0)(1 − c)^5`, `c = cos` of the angle between the
/// light and the microfacet normal (Schlick 1994).
#[inline]
pub fn fresnel_schlick(f0: f64, cos: f64) -> f64 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (1.0 - f0) * m2 * m2 * m
}

/// Exact unpolarised Fresnel reflectance `(R_s + R_p)/2` of an interface from vacuum into a
/// medium of complex index `η = n + iκ` (κ = 0 for dielectrics), for `cos ∈ [0, 1]` the cosine
/// of the angle of incidence. Covers total internal reflection (κ = 0, n < 1). Result in `[0, 1]`.
pub fn fresnel_conductor(cos: f64, n: f64, kappa: f64) -> f64 {
    let c = cos.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = n * n - kappa * kappa - s2;
    let a2b2 = (t0 * t0 + 4.0 * n * n * kappa * kappa).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t1 = a2b2 + c2;
    let t2 = 2.0 * a * c;
    let rs = if t1 + t2 > 0.0 {
        (t1 - t2) / (t1 + t2)
    } else {
        1.0
    };
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = if t3 + t4 > 0.0 {
        rs * (t3 - t4) / (t3 + t4)
    } else {
        rs
    };
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}

/// Exact unpolarised Fresnel reflectance of a dielectric with relative index `eta`
/// (Cook & Torrance 1982, eq. for `F` with `g² = η² + c² − 1`); returns 1 under total internal
/// reflection.
pub fn fresnel_dielectric(cos: f64, eta: f64) -> f64 {
    let c = cos.clamp(0.0, 1.0);
    let g2 = eta * eta + c * c - 1.0;
    if g2 <= 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - c) / (g + c);
    let b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    (0.5 * a * a * (1.0 + b * b)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn normal_incidence_matches_closed_form() {
        let n: f64 = 1.5;
        let f0 = ((n - 1.0) / (n + 1.0)).powi(2);
        assert_relative_eq!(fresnel_dielectric(1.0, n), f0, epsilon = 1e-14);
        assert_relative_eq!(fresnel_conductor(1.0, n, 0.0), f0, epsilon = 1e-14);
        // Conductor at normal incidence: ((n-1)² + κ²)/((n+1)² + κ²).
        let (n, k): (f64, f64) = (0.2, 3.0);
        let expect = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert_relative_eq!(fresnel_conductor(1.0, n, k), expect, epsilon = 1e-12);
        assert_relative_eq!(fresnel_schlick(0.04, 1.0), 0.04, epsilon = 1e-15);
    }

    #[test]
    fn dielectric_and_conductor_formulas_agree() {
        for i in 0..=100 {
            let c = i as f64 / 100.0;
            for eta in [1.2, 1.5, 2.4] {
                assert_relative_eq!(
                    fresnel_dielectric(c, eta),
                    fresnel_conductor(c, eta, 0.0),
                    epsilon = 1e-12
                );
            }
        }
    }

    #[test]
    fn grazing_is_total_and_range_is_unit() {
        assert_relative_eq!(fresnel_dielectric(0.0, 1.5), 1.0, epsilon = 1e-12);
        assert_relative_eq!(fresnel_conductor(0.0, 0.2, 3.0), 1.0, epsilon = 1e-12);
        assert_eq!(fresnel_dielectric(0.1, 0.5), 1.0); // TIR
        for i in 0..=50 {
            let c = i as f64 / 50.0;
            let f = fresnel_conductor(c, 0.5, 0.0);
            assert!((0.0..=1.0).contains(&f));
        }
    }
}
