//! The refined image map (`GridOptions::refinement`) and the mirrored one (`mirror_y`): same
//! integrals and bounds as the dense map for far fewer evaluations; a peak hidden between the
//! coarse stencil's points escapes the refinement unless the caller focuses on it.

use partition_sampler::{
    DensityError, Domain, GridOptions, Point2, Rect, Refinement, RegionStats, SampledGridDensity,
};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

const N: usize = 256;

fn refined() -> GridOptions {
    GridOptions {
        refinement: Some(Refinement::default()),
        mirror_y: false,
        focus: None,
    }
}

/// A broad slope plus a narrow peak (σ = 0.02) at (0.31, −0.17): value 5 at the peak.
fn peaked(p: Point2) -> f64 {
    let (dx, dy) = (p[0] - 0.31, p[1] + 0.17);
    1.0 + 0.5 * p[0] + 4.0 * (-(dx * dx + dy * dy) / (2.0 * 0.02 * 0.02)).exp()
}

/// `∫_D peaked` (the peak lies well inside the disc): π + 4 · 2πσ².
fn peaked_integral() -> f64 {
    std::f64::consts::PI + 4.0 * std::f64::consts::TAU * 0.02 * 0.02
}

/// Largest `f(p) / bound(p)` over random points, `bound` the region bound of the fine cell
/// containing `p`.
fn worst_bound_ratio(d: &SampledGridDensity<fn(Point2) -> f64>, f: fn(Point2) -> f64) -> f64 {
    worst_bound_ratio_near(d, f, [0.31, -0.17])
}

/// [`worst_bound_ratio`] with the dense probes around `centre`.
fn worst_bound_ratio_near(
    d: &SampledGridDensity<fn(Point2) -> f64>,
    f: fn(Point2) -> f64,
    centre: Point2,
) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let h = 2.0 / N as f64;
    let mut worst = 0.0f64;
    let mut probe = |p: Point2| {
        if p[0] * p[0] + p[1] * p[1] > 1.0 {
            return;
        }
        let (i, j) = (((p[0] + 1.0) / h).floor(), ((p[1] + 1.0) / h).floor());
        let cell = Rect::new(
            -1.0 + i * h,
            -1.0 + j * h,
            -1.0 + (i + 1.0) * h,
            -1.0 + (j + 1.0) * h,
        );
        worst = worst.max(f(p) / d.region(&cell).max_bound);
    };
    for _ in 0..200_000 {
        probe([rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)]);
    }
    // Densely around the peak.
    for _ in 0..50_000 {
        probe([
            centre[0] + rng.random_range(-0.06..0.06),
            centre[1] + rng.random_range(-0.06..0.06),
        ]);
    }
    worst
}

#[test]
fn refined_map_keeps_integrals_and_bounds_for_fewer_evaluations() {
    let f: fn(Point2) -> f64 = peaked;
    let dense = SampledGridDensity::new(f, Domain::UnitDisc, N).unwrap();
    let fine = SampledGridDensity::with_options(f, Domain::UnitDisc, N, &refined()).unwrap();
    let exact = peaked_integral();
    let err = |d: &SampledGridDensity<_>| (d.total_integral() - exact).abs() / exact;
    assert!(err(&dense) < 2e-4, "dense {}", err(&dense));
    assert!(err(&fine) < 2e-4, "refined {}", err(&fine));
    assert!(
        fine.evaluations() * 3 < dense.evaluations(),
        "refined {} vs dense {}",
        fine.evaluations(),
        dense.evaluations()
    );
    // Bounds (safety 1.1 included) hold everywhere, also on the peak.
    let worst = worst_bound_ratio(&fine, f);
    assert!(worst <= 1.0, "f exceeds its bound by {worst}");
    assert!(worst > 0.8, "bounds unexpectedly loose: {worst}");
}

/// A narrow peak (σ = 0.008, height 4) on a fine-lattice point midway between the coarse
/// stencil's points (spacing 1/32 of the width): the stencil sees 2 % of it.
fn hidden(p: Point2) -> f64 {
    let (dx, dy) = (p[0] - HIDDEN[0], p[1] - HIDDEN[1]);
    1.0 + 0.5 * p[0] + 4.0 * (-(dx * dx + dy * dy) / (2.0 * 0.008 * 0.008)).exp()
}

/// `(−1 + 41.5 · 2/64, −1 + 26.5 · 2/64)`: midway between stencil points in both axes, and a
/// corner of the 256² fine lattice.
const HIDDEN: Point2 = [0.296875, -0.171875];

#[test]
fn a_peak_between_coarse_points_needs_the_focus() {
    // Negative control: the refinement alone keeps the blocks around the hidden peak coarse
    // and its bounds fail; the dense map and the refined map focused on the peak bound it.
    let f: fn(Point2) -> f64 = hidden;
    let worst = |o: &GridOptions| {
        let d = SampledGridDensity::with_options(f, Domain::UnitDisc, N, o).unwrap();
        worst_bound_ratio_near(&d, f, HIDDEN)
    };
    assert!(worst(&refined()) > 2.0);
    assert!(worst(&GridOptions::default()) <= 1.0);
    let focused = GridOptions {
        focus: Some(HIDDEN),
        ..refined()
    };
    assert!(worst(&focused) <= 1.0);
}

#[test]
fn mirrored_map_equals_the_full_one_for_half_the_evaluations() {
    // Exactly symmetric in floating point: y enters squared.
    let f = |p: Point2| (-(p[0] - 0.2).powi(2) - 3.0 * p[1] * p[1]).exp() + 0.1;
    for base in [GridOptions::default(), refined()] {
        let full = SampledGridDensity::with_options(f, Domain::UnitDisc, N, &base).unwrap();
        let half = SampledGridDensity::with_options(
            f,
            Domain::UnitDisc,
            N,
            &GridOptions {
                mirror_y: true,
                ..base
            },
        )
        .unwrap();
        assert_eq!(full.total_integral(), half.total_integral());
        for cell in [
            Rect::new(-0.5, 0.25, 0.0, 0.75),
            Rect::new(0.0, -0.75, 0.5, -0.25),
        ] {
            assert_eq!(full.region(&cell), half.region(&cell));
        }
        let (a, b) = (full.evaluations(), half.evaluations());
        assert!(b * 2 <= a + a / 20 && b * 2 >= a - a / 20, "{b} vs {a}");
    }
}

#[test]
fn invalid_refinement_and_mirror_are_typed_errors() {
    let f = |_: Point2| 1.0;
    let bad = |coarsest, tolerance| GridOptions {
        refinement: Some(Refinement {
            coarsest,
            tolerance,
        }),
        mirror_y: false,
        focus: None,
    };
    for o in [bad(3, 0.01), bad(1, 0.01), bad(32, f64::NAN), bad(32, -1.0)] {
        assert!(matches!(
            SampledGridDensity::with_options(f, Domain::UnitDisc, N, &o),
            Err(DensityError::InvalidRefinement { .. })
        ));
    }
    // n not a power of two.
    assert!(matches!(
        SampledGridDensity::with_options(f, Domain::UnitDisc, 96, &refined()),
        Err(DensityError::InvalidRefinement { .. })
    ));
    let mirror = GridOptions {
        refinement: None,
        mirror_y: true,
        focus: None,
    };
    assert!(matches!(
        SampledGridDensity::with_options(f, Domain::UnitDisc, 33, &mirror),
        Err(DensityError::InvalidMirror { .. })
    ));
    let off_centre = Domain::Rect(Rect::new(0.0, 0.0, 1.0, 1.0));
    assert!(matches!(
        SampledGridDensity::with_options(f, off_centre, 32, &mirror),
        Err(DensityError::InvalidMirror { .. })
    ));
    // A NaN found by the refined map is reported like the dense map's.
    let nan = |p: Point2| if p[0] > 0.5 { f64::NAN } else { 1.0 };
    assert!(matches!(
        SampledGridDensity::with_options(nan, Domain::UnitDisc, 64, &refined()),
        Err(DensityError::InvalidSample { .. })
    ));
}
