//! Tabulated projection CDFs against closed forms.

use crate::common;

use common::*;
use stats::{
    Axis, DiscBinning, QuadratureOptions, RectBinning, SphereBinning, StatsError, TabulatedCdf,
    project, projection_cdf,
};
use std::f64::consts::TAU;

fn max_error(cdf: &TabulatedCdf, exact: impl Fn(f64) -> f64, range: [f64; 2]) -> f64 {
    (0..=40_000)
        .map(|i| {
            let x = range[0] + (range[1] - range[0]) * i as f64 / 40_000.0;
            (cdf.eval(x) - exact(x)).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn disc_x_projection_matches_closed_form() {
    let bins = DiscBinning::new(10, 10).unwrap();
    let opts = QuadratureOptions::default();
    for n in [1_000u64, 1_000_000] {
        let cdf = projection_cdf(&bins, &uniform_disc_pdf, Axis::U, n, &opts).unwrap();
        let err = max_error(&cdf, disc_cdf_x, [-1.0, 1.0]);
        // Target accuracy is 0.01/√n; the KS noise scale is 1/√n.
        assert!(err < 0.01 / (n as f64).sqrt(), "n = {n}: {err}");
        assert!((cdf.total_mass() - 1.0).abs() < 1e-6);
    }
}

#[test]
fn hemisphere_projections_match_closed_forms() {
    let bins = SphereBinning::hemisphere(10, 20).unwrap();
    let opts = QuadratureOptions::default();
    let n = 1_000_000;
    let cos = projection_cdf(&bins, &cosine_pdf, Axis::U, n, &opts).unwrap();
    assert!(max_error(&cos, |u| u * u, [0.0, 1.0]) < 1e-5);
    let phi = projection_cdf(&bins, &cosine_pdf, Axis::V, n, &opts).unwrap();
    assert!(max_error(&phi, |p| p / TAU, [0.0, TAU]) < 1e-5);
}

#[test]
fn rect_projections_match_closed_forms() {
    let bins = RectBinning::new(RECT_X, RECT_Y, 6, 6).unwrap();
    let opts = QuadratureOptions::default();
    let n = 4_000_000;
    let x = projection_cdf(&bins, &product_pdf, Axis::U, n, &opts).unwrap();
    assert!(max_error(&x, product_cdf_x, RECT_X) < 0.01 / (n as f64).sqrt());
    let y = projection_cdf(&bins, &product_pdf, Axis::V, n, &opts).unwrap();
    assert!(max_error(&y, product_cdf_y, RECT_Y) < 0.01 / (n as f64).sqrt());
}

#[test]
fn a_narrow_feature_is_resolved() {
    // A 1D density with a spike of width 1e-3 centred exactly on a knot of the initial slabs.
    let w = 1e-3;
    let f =
        |x: f64| 0.5 + 0.5 * (-((x - 0.5) / w).powi(2)).exp() / (w * std::f64::consts::PI.sqrt());
    let exact = |x: f64| 0.5 * x + 0.25 * (1.0 + libm_erf((x - 0.5) / w));
    let n = 1_000_000;
    let cdf = TabulatedCdf::from_density(&f, [0.0, 1.0], n, &QuadratureOptions::default()).unwrap();
    let err = max_error(
        &cdf,
        |x| exact(x) / (0.5 + 0.25 * (1.0 + libm_erf(0.5 / w))),
        [0.0, 1.0],
    );
    assert!(err < 0.01 / (n as f64).sqrt(), "{err}");
}

fn libm_erf(x: f64) -> f64 {
    statrs::function::erf::erf(x)
}

#[test]
fn tabulated_cdf_validates_its_input() {
    assert!(matches!(
        TabulatedCdf::new(vec![0.0, 1.0, 0.5], vec![0.0, 0.5, 1.0]),
        Err(StatsError::NonMonotoneCdf { index: 2 })
    ));
    assert!(matches!(
        TabulatedCdf::new(vec![0.0, 1.0, 2.0], vec![0.0, 0.6, 0.5]),
        Err(StatsError::NonMonotoneCdf { index: 2 })
    ));
    assert!(TabulatedCdf::new(vec![0.0], vec![0.0]).is_err());
    assert!(TabulatedCdf::new(vec![0.0, 1.0], vec![0.0, 0.0]).is_err());
    let c = TabulatedCdf::new(vec![0.0, 1.0, 3.0], vec![0.0, 1.0, 2.0]).unwrap();
    assert_eq!(c.eval(-1.0), 0.0);
    assert_eq!(c.eval(0.5), 0.25);
    assert_eq!(c.eval(2.0), 0.75);
    assert_eq!(c.eval(5.0), 1.0);
    // A density that is negative somewhere is not a density.
    let neg = |x: f64| x - 0.5;
    assert!(
        TabulatedCdf::from_density(&neg, [0.0, 1.0], 100, &QuadratureOptions::default()).is_err()
    );
}

#[test]
fn projection_reports_points_outside_the_domain() {
    let bins = SphereBinning::hemisphere(4, 4).unwrap();
    let p = project(
        &bins,
        &[[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [f64::NAN, 0.0, 1.0]],
        Axis::U,
    );
    assert_eq!(p.values, vec![1.0]);
    assert_eq!(p.outside, 2);
}

#[test]
fn a_step_in_the_marginal_is_resolved() {
    // pdf = 0.5 for x < 0.3, c above (normalised on [0, 1]²); the x CDF has a kink at 0.3.
    let c = 1.0 + 0.5 * 0.3 / 0.7;
    let step = move |p: [f64; 2]| if p[0] < 0.3 { 0.5 } else { c };
    let exact = move |x: f64| {
        if x < 0.3 {
            0.5 * x
        } else {
            0.15 + c * (x - 0.3)
        }
    };
    let bins = RectBinning::unit_square(7, 7).unwrap();
    let n = 1_000_000;
    let cdf = projection_cdf(&bins, &step, Axis::U, n, &QuadratureOptions::default()).unwrap();
    assert!(max_error(&cdf, exact, [0.0, 1.0]) < 0.01 / (n as f64).sqrt());
}

#[test]
fn a_very_sharp_lobe_at_the_pole_is_resolved() {
    // Phong lobe around +z with exponent 2000: F(cos θ) = (cos θ)^2001 for cos θ > 0.
    let lobe = Lobe {
        axis: [0.0, 0.0, 1.0],
        exponent: 2000.0,
    };
    let bins = SphereBinning::sphere(10, 20).unwrap();
    for n in [10_000u64, 10_000_000] {
        let cdf = projection_cdf(
            &bins,
            &|d| lobe.pdf(d),
            Axis::U,
            n,
            &QuadratureOptions::default(),
        )
        .unwrap();
        let err = max_error(&cdf, |u| u.max(0.0).powf(2001.0), [-1.0, 1.0]);
        assert!(err < 0.01 / (n as f64).sqrt(), "n = {n}: {err}");
    }
}
