//! Tabulated projection CDFs against closed forms.

mod common;

use common::*;
use stats::{
    Axis, DiscBinning, QuadratureOptions, RectBinning, SphereBinning, StatsError, TabulatedCdf,
    project, projection_cdf,
};
use std::f64::consts::TAU;

fn max_error(cdf: &TabulatedCdf, exact: impl Fn(f64) -> f64, range: [f64; 2]) -> f64 {
    (0..=4000)
        .map(|i| {
            let x = range[0] + (range[1] - range[0]) * i as f64 / 4000.0;
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
    let f = |x: f64| 0.5 + 0.5 * (-((x - 0.5) / w).powi(2)).exp() / (w * std::f64::consts::PI.sqrt());
    let exact = |x: f64| 0.5 * x + 0.25 * (1.0 + libm_erf((x - 0.5) / w));
    let n = 1_000_000;
    let cdf = TabulatedCdf::from_density(&f, [0.0, 1.0], n, &QuadratureOptions::default()).unwrap();
    let err = max_error(&cdf, |x| exact(x) / (0.5 + 0.25 * (1.0 + libm_erf(0.5 / w))), [0.0, 1.0]);
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
    assert!(TabulatedCdf::from_density(&neg, [0.0, 1.0], 100, &QuadratureOptions::default()).is_err());
}

#[test]
fn projection_reports_points_outside_the_domain() {
    let bins = SphereBinning::hemisphere(4, 4).unwrap();
    let p = project(&bins, &[[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [f64::NAN, 0.0, 1.0]], Axis::U);
    assert_eq!(p.values, vec![1.0]);
    assert_eq!(p.outside, 2);
}
