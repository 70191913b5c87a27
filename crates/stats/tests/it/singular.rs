//! Projection CDFs of a density with a wedge singularity, against its closed-form marginal.

use stats::{
    Axis, QuadratureOptions, RectBinning, TabulatedCdf, projection_cdf,
    projection_cdf_with_singularities,
};

const U0: f64 = 0.618_034;
const V0: f64 = 0.413_7;
const APERTURE: f64 = 1e-3;

/// Standard logistic density `e^{−|x|} / (1 + e^{−|x|})²` (integral 1 over ℝ).
fn logistic(x: f64) -> f64 {
    let e = (-x.abs()).exp();
    e / ((1.0 + e) * (1.0 + e))
}

/// On `[0, 1]²`: `½ + ½ · g((v − v₀)/w)/w` with `w = α |u − u₀|` — along each line `u = t` a
/// spike of width `α |t − u₀|` at `v₀` holding mass `½` (up to `e^{−400}`), so the `u`
/// marginal is 1 and `F(u) = u`; the `v` marginal is `½ + ½ · (spike's mass density)`, whose
/// CDF is `½ v + ½ ∫₀¹ G((v − v₀)/(α|u − u₀|)) du` (`G` the logistic CDF), `≈ ½ v + ½ [v ≥ v₀]`
/// away from `v₀`.
fn wedge_pdf(p: [f64; 2]) -> f64 {
    let w = APERTURE * (p[0] - U0).abs();
    if w == 0.0 {
        return 0.5;
    }
    0.5 + 0.5 * logistic((p[1] - V0) / w) / w
}

fn max_error(cdf: &TabulatedCdf, exact: impl Fn(f64) -> f64, skip: impl Fn(f64) -> bool) -> f64 {
    (0..=20_000)
        .map(|i| i as f64 / 20_000.0)
        .filter(|x| !skip(*x))
        .map(|x| (cdf.eval(x) - exact(x)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_wedge_singularity_needs_the_graded_split() {
    let bins = RectBinning::unit_square(8, 8).unwrap();
    let opts = QuadratureOptions::default();
    let n = 1_000_000u64;
    let tol = opts.accuracy / (n as f64).sqrt();
    // Without the declaration the line integrals miss most spikes: the test must see it.
    let plain = projection_cdf(&bins, &wedge_pdf, Axis::U, n, &opts).unwrap();
    let plain_err = max_error(&plain, |u| u, |_| false);
    assert!(plain_err > 100.0 * tol, "plain error {plain_err:e}");
    // With it, the u marginal is exact within the target accuracy.
    let graded =
        projection_cdf_with_singularities(&bins, &wedge_pdf, Axis::U, n, &opts, &[[U0, V0]])
            .unwrap();
    let graded_err = max_error(&graded, |u| u, |_| false);
    assert!(
        graded_err < tol,
        "graded error {graded_err:e} (plain {plain_err:e})"
    );
    // The v projection (a jump of ½ at v₀, smeared over ≈ α; checked away from it): its lines
    // cross the wedge, which the plain rule already resolves; the grading must not spoil it.
    let step = |x: f64| 0.5 * x + if x > V0 { 0.5 } else { 0.0 };
    let away = |x: f64| (x - V0).abs() < 0.01;
    let v = projection_cdf_with_singularities(&bins, &wedge_pdf, Axis::V, n, &opts, &[[U0, V0]])
        .unwrap();
    let v_err = max_error(&v, step, away);
    assert!(v_err < tol, "v error {v_err:e}");
}
