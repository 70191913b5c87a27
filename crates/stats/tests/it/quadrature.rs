//! Accuracy of the bin quadrature against analytic bin masses, and its determinism.

use crate::common;

use common::*;
use stats::{
    Binning, DiscBinning, QuadratureOptions, RectBinning, SphereBinning, expected_masses,
    expected_masses_with, integrate, integrate_bins,
};
use std::f64::consts::{PI, TAU};

/// Largest |error| of the expected counts in units of √max(E, 1).
fn worst_noise_fraction(masses: &[f64], exact: &[f64], n: f64) -> f64 {
    masses
        .iter()
        .zip(exact)
        .map(|(m, e)| (m - e).abs() * n / (n * e).max(1.0).sqrt())
        .fold(0.0, f64::max)
}

#[test]
fn product_density_masses_are_accurate_at_huge_sample_counts() {
    let bins = RectBinning::new(RECT_X, RECT_Y, 12, 9).unwrap();
    let exact: Vec<f64> = (0..bins.n_bins())
        .map(|b| {
            let (u, v) = bins.grid().cell(b).unwrap();
            (product_cdf_x(u[1]) - product_cdf_x(u[0]))
                * (product_cdf_y(v[1]) - product_cdf_y(v[0]))
        })
        .collect();
    for n in [1e4, 1e7, 1e10] {
        let masses = expected_masses(&product_pdf, &bins, n as u64);
        let worst = worst_noise_fraction(&masses, &exact, n);
        // Target is 0.01 √E; allow the estimate's slack but stay far below the noise.
        assert!(
            worst < 0.02,
            "N = {n}: error is {worst} of the Poisson noise"
        );
    }
}

/// A density that no fixed rule integrates exactly: a narrow lobe on the sphere.
/// The narrow-lobe case of the two tests below: a lobe of exponent 2000 about `(0.5, 1.0)`, a
/// 10 × 20 sphere binning and the tight quadrature options of its reference masses.
fn narrow_lobe_case() -> (Lobe, SphereBinning, QuadratureOptions) {
    let lobe = Lobe {
        axis: dir(0.5, 1.0),
        exponent: 2000.0,
    };
    let bins = SphereBinning::sphere(10, 20).unwrap();
    let tight = QuadratureOptions {
        accuracy: 1e-7,
        max_depth: 16,
        min_depth: 3,
        ..Default::default()
    };
    (lobe, bins, tight)
}

#[test]
fn lobe_masses_error_stays_below_the_noise_as_n_grows() {
    // Exponent 2000: the lobe (width ~0.02 rad) is much narrower than a bin, so refinement is needed.
    let (lobe, bins, tight) = narrow_lobe_case();
    let pdf = |d: [f64; 3]| lobe.pdf(d);
    let reference = expected_masses_with(&pdf, &bins, 1e12 as u64, &tight).unwrap();
    assert_eq!(reference.unconverged_bins, 0);
    assert!(
        (reference.total() - 1.0).abs() < 1e-11,
        "total {}",
        reference.total()
    );
    let mut evals = 0;
    for n in [1e4, 1e6, 1e8, 1e10] {
        let t = expected_masses_with(&pdf, &bins, n as u64, &QuadratureOptions::default()).unwrap();
        let worst = worst_noise_fraction(&t.masses, &reference.masses, n);
        assert!(
            worst < 0.02,
            "N = {n}: error is {worst} of the Poisson noise"
        );
        assert!(
            t.evaluations >= evals,
            "more samples must not mean less work"
        );
        evals = t.evaluations;
    }
}

#[test]
fn a_fixed_coarse_rule_would_not_be_accurate_enough() {
    // Sanity check of the premise: the same lobe on a 4 x 4 midpoint rule per bin is off by
    // more than √E at N = 1e9, so the test above is not trivially satisfied.
    let (lobe, bins, tight) = narrow_lobe_case();
    let pdf = |d: [f64; 3]| lobe.pdf(d);
    let reference = expected_masses_with(&pdf, &bins, 1e12 as u64, &tight).unwrap();
    let coarse: Vec<f64> = (0..bins.n_bins())
        .map(|b| {
            let (u, v) = bins.grid().cell(b).unwrap();
            let (du, dv) = ((u[1] - u[0]) / 4.0, (v[1] - v[0]) / 4.0);
            let mut s = 0.0;
            for i in 0..4 {
                for j in 0..4 {
                    let uv = [u[0] + (i as f64 + 0.5) * du, v[0] + (j as f64 + 0.5) * dv];
                    s += pdf(bins.point_at(uv)) * du * dv;
                }
            }
            s
        })
        .collect();
    assert!(worst_noise_fraction(&coarse, &reference.masses, 1e9) > 1.0);
}

#[test]
fn cosine_hemisphere_masses_match_closed_form() {
    let bins = SphereBinning::hemisphere(10, 20).unwrap();
    let masses = expected_masses(&cosine_pdf, &bins, 1_000_000);
    for (b, m) in masses.iter().enumerate() {
        let (u, v) = bins.grid().cell(b).unwrap();
        let exact = (u[1] * u[1] - u[0] * u[0]) / 2.0 * (v[1] - v[0]) / PI;
        assert!((m - exact).abs() < 1e-13, "bin {b}: {m} vs {exact}");
    }
}

#[test]
fn uniform_sphere_bins_have_equal_solid_angle() {
    let bins = SphereBinning::sphere(16, 32).unwrap();
    let masses = expected_masses(&|_| 1.0, &bins, 1_000_000);
    for m in masses {
        assert!((m - 4.0 * PI / 512.0).abs() < 1e-13);
    }
}

/// Area of `[x0, x1] × [y0, y1] ∩ disc`, by the antiderivative of the clipped chord length.
fn exact_clipped_area(u: [f64; 2], v: [f64; 2]) -> f64 {
    // ∫ max(0, min(v1, c) − max(v0, −c)) dx with c = √(1 − x²), by a very fine midpoint rule on
    // an analytic integrand would be circular; use the primitive of the arc instead:
    // area = A(x1) − A(x0), A(x) = ∫_{-1}^{x} clip(x') dx', split at the kinks.
    let arc = |x: f64| 0.5 * (x * (1.0 - x * x).sqrt() + x.asin());
    let mut kinks = vec![u[0].max(-1.0), u[1].min(1.0)];
    for y in v {
        if y.abs() < 1.0 {
            let x = (1.0 - y * y).sqrt();
            kinks.extend([-x, x]);
        }
    }
    let (a, b) = (u[0].max(-1.0), u[1].min(1.0));
    if a >= b {
        return 0.0;
    }
    kinks.retain(|&k| k >= a && k <= b);
    kinks.sort_by(f64::total_cmp);
    let mut area = 0.0;
    for w in kinks.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        if x1 <= x0 {
            continue;
        }
        let xm = 0.5 * (x0 + x1);
        let c = (1.0 - xm * xm).sqrt();
        // Upper edge integral.
        let up = if v[1] < c {
            v[1] * (x1 - x0)
        } else {
            arc(x1) - arc(x0)
        };
        let lo = if v[0] > -c {
            v[0] * (x1 - x0)
        } else {
            -(arc(x1) - arc(x0))
        };
        if up - lo > 0.0 {
            area += up - lo;
        }
    }
    area
}

#[test]
fn disc_cells_are_clipped_exactly() {
    for n in [3usize, 10, 17] {
        let bins = DiscBinning::new(n, n).unwrap();
        let masses = expected_masses(&uniform_disc_pdf, &bins, 1_000_000_000);
        let mut total = 0.0;
        for (b, m) in masses.iter().enumerate() {
            let (u, v) = bins.grid().cell(b).unwrap();
            let exact = exact_clipped_area(u, v) / PI;
            assert!(
                (m - exact).abs() < 1e-12,
                "n = {n}, bin {b}: {m} vs {exact}"
            );
            total += m;
        }
        assert!((total - 1.0).abs() < 1e-12);
    }
}

#[test]
fn disc_moments_of_a_smooth_density() {
    // p = (1 + x)/π on the disc: ∫ p = 1 and ∫ x p = ∫ x²/π = 1/4.
    let bins = DiscBinning::new(8, 8).unwrap();
    let opts = QuadratureOptions::default();
    let mass = integrate(&|p: [f64; 2]| (1.0 + p[0]) / PI, &bins, 1e-12, &opts).unwrap();
    let first = integrate(&|p: [f64; 2]| p[0] * (1.0 + p[0]) / PI, &bins, 1e-12, &opts).unwrap();
    assert!((mass.value - 1.0).abs() < 1e-11 && mass.converged);
    assert!((first.value - 0.25).abs() < 1e-11 && first.converged);
}

#[test]
fn a_discontinuity_inside_a_bin_is_resolved() {
    // Step at x = 0.3 (not a grid line): p = 0.5 below, 1.5 above... normalised on [0,1]².
    let step = |p: [f64; 2]| {
        if p[0] < 0.3 {
            0.5
        } else {
            1.0 + 0.5 * 0.3 / 0.7
        }
    };
    let bins = RectBinning::unit_square(4, 4).unwrap();
    let opts = QuadratureOptions {
        max_depth: 20,
        ..Default::default()
    };
    let t = expected_masses_with(&step, &bins, 100_000, &opts).unwrap();
    assert_eq!(t.unconverged_bins, 0);
    for (b, m) in t.masses.iter().enumerate() {
        let (u, v) = bins.grid().cell(b).unwrap();
        let below = (0.3f64.min(u[1]) - u[0]).max(0.0);
        let above = (u[1] - 0.3f64.max(u[0])).max(0.0);
        let exact = (0.5 * below + (1.0 + 0.5 * 0.3 / 0.7) * above) * (v[1] - v[0]);
        let e = 1e5 * exact;
        assert!(
            (m * 1e5 - e).abs() < 0.02 * e.sqrt(),
            "bin {b}: {} vs {e}",
            m * 1e5
        );
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let lobe = test_lobe();
    let pdf = |d: [f64; 3]| lobe.pdf(d);
    let bins = SphereBinning::sphere(10, 20).unwrap();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                expected_masses_with(&pdf, &bins, 1_000_000, &QuadratureOptions::default()).unwrap()
            })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn integrate_bins_meets_an_absolute_tolerance() {
    let bins = SphereBinning::hemisphere(5, 8).unwrap();
    let f = |d: [f64; 3]| d[2] * d[2]; // ∫ cos²θ dω over the hemisphere = 2π/3
    let t = integrate_bins(&f, &bins, 1e-10, &QuadratureOptions::default()).unwrap();
    assert!((t.total() - TAU / 3.0).abs() < 1e-10);
}

#[test]
fn bad_options_are_rejected() {
    let bins = RectBinning::unit_square(2, 2).unwrap();
    let f = |_: [f64; 2]| 1.0;
    for opts in [
        QuadratureOptions {
            order: 1,
            ..Default::default()
        },
        QuadratureOptions {
            max_depth: 31,
            ..Default::default()
        },
        QuadratureOptions {
            accuracy: f64::NAN,
            ..Default::default()
        },
        QuadratureOptions {
            rel_floor: 0.0,
            ..Default::default()
        },
    ] {
        assert!(expected_masses_with(&f, &bins, 10, &opts).is_err());
    }
    assert!(integrate_bins(&f, &bins, -1.0, &QuadratureOptions::default()).is_err());
}
