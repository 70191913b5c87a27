//! Integration tests of the piecewise-constant CDF samplers.

use approx::assert_relative_eq;
use partition_sampler::{
    InvertibleSampler2D, PiecewiseConstant1D, PiecewiseConstant2D, PiecewiseConstantError, Point2,
    Rect, Sample2, Sampler2D, UniformSource,
};
use proptest::prelude::*;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Significance level of every chi-square test in this file.
const ALPHA: f64 = 1e-3;

/// Binned chi-square goodness of fit ([`stats::chi_square_gof`]): cells whose expected count is
/// below 5 are pooled; a sample in a cell of zero expected mass is an immediate failure (p = 0).
fn chi_square_p(observed: &[u64], probabilities: &[f64]) -> f64 {
    let n = observed.iter().sum::<u64>() as f64;
    let expected: Vec<f64> = probabilities.iter().map(|p| p * n).collect();
    let test = stats::chi_square_gof(observed, &expected, stats::DEFAULT_MIN_EXPECTED);
    test.expect("too few cells for a chi-square test").p_value
}

const UNIT: Rect = Rect {
    x0: 0.0,
    y0: 0.0,
    x1: 1.0,
    y1: 1.0,
};

/// A small grid with zero cells, a zero row and a dominant cell.
fn test_grid() -> (usize, usize, Vec<f64>) {
    let (w, h) = (7, 5);
    let mut v: Vec<f64> = (0..w * h).map(|i| ((i * 37) % 11) as f64 * 0.3).collect();
    for x in &mut v[2 * w..3 * w] {
        *x = 0.0; // an empty row
    }
    v[4 * w + 3] = 40.0; // a bright cell
    (w, h, v)
}

/// Bins samples of `s` on a `w × h` grid over `domain`.
fn histogram<S: Sampler2D>(
    s: &S,
    w: usize,
    h: usize,
    domain: Rect,
    n: usize,
    seed: u64,
) -> Vec<u64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut counts = vec![0u64; w * h];
    for _ in 0..n {
        let p = s.sample(&mut rng).point;
        let c = (((p[0] - domain.x0) / (domain.x1 - domain.x0) * w as f64) as usize).min(w - 1);
        let r = (((p[1] - domain.y0) / (domain.y1 - domain.y0) * h as f64) as usize).min(h - 1);
        counts[r * w + c] += 1;
    }
    counts
}

fn masses(v: &[f64]) -> Vec<f64> {
    let s: f64 = v.iter().sum();
    v.iter().map(|x| x / s).collect()
}

#[test]
fn chi_square_matches_exact_cell_masses() {
    let (w, h, v) = test_grid();
    let domain = Rect {
        x0: -1.0,
        y0: 2.0,
        x1: 3.0,
        y1: 2.5,
    };
    let t = PiecewiseConstant2D::new(w, h, v.clone(), domain).unwrap();
    let counts = histogram(&t, w, h, domain, 200_000, 1);
    let p = chi_square_p(&counts, &masses(&v));
    assert!(p > ALPHA, "p = {p}");
}

/// A table built from slightly wrong values (one cell 10% too heavy).
struct Perturbed(PiecewiseConstant2D);

impl Sampler2D for Perturbed {
    fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2 {
        self.0.sample(u)
    }
    fn pdf(&self, p: Point2) -> f64 {
        self.0.pdf(p)
    }
    fn bytes_used(&self) -> usize {
        0
    }
}

#[test]
fn chi_square_rejects_a_broken_table() {
    let (w, h, v) = test_grid();
    let mut wrong = v.clone();
    wrong[w + 2] *= 1.25;
    let broken = Perturbed(PiecewiseConstant2D::new(w, h, wrong, UNIT).unwrap());
    let counts = histogram(&broken, w, h, UNIT, 200_000, 1);
    let p = chi_square_p(&counts, &masses(&v));
    assert!(
        p < ALPHA,
        "a 25% error in one cell went undetected: p = {p}"
    );
}

#[test]
fn chi_square_rejects_uniform_columns() {
    // A broken variant that ignores the conditional CDF (uniform column inside the chosen row).
    struct UniformColumns(PiecewiseConstant2D);
    impl Sampler2D for UniformColumns {
        fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2 {
            let mut s = self.0.sample(u);
            s.point[0] = u.next_uniform();
            s
        }
        fn pdf(&self, p: Point2) -> f64 {
            self.0.pdf(p)
        }
        fn bytes_used(&self) -> usize {
            0
        }
    }
    let (w, h, v) = test_grid();
    let broken = UniformColumns(PiecewiseConstant2D::new(w, h, v.clone(), UNIT).unwrap());
    let counts = histogram(&broken, w, h, UNIT, 50_000, 3);
    assert!(chi_square_p(&counts, &masses(&v)) < ALPHA);
}

#[test]
fn sample_pdf_equals_pdf_at_point_and_integrates_to_one() {
    let (w, h, v) = test_grid();
    let domain = Rect {
        x0: 0.0,
        y0: 0.0,
        x1: 2.0,
        y1: 0.5,
    };
    let t = PiecewiseConstant2D::new(w, h, v, domain).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
    for _ in 0..10_000 {
        let s = t.sample(&mut rng);
        assert!(s.pdf > 0.0);
        assert_eq!(s.pdf, t.pdf(s.point));
    }
    // Midpoint quadrature of the pdf over the domain (exact for a step function on the grid).
    let (nx, ny) = (w * 4, h * 4);
    let area = 2.0 * 0.5 / (nx * ny) as f64;
    let mut total = 0.0;
    for j in 0..ny {
        for i in 0..nx {
            total += t.pdf([
                (i as f64 + 0.5) * 2.0 / nx as f64,
                (j as f64 + 0.5) * 0.5 / ny as f64,
            ]) * area;
        }
    }
    assert_relative_eq!(total, 1.0, epsilon = 1e-12);
    assert_eq!(t.pdf([-0.1, 0.2]), 0.0);
    assert_eq!(t.pdf([f64::NAN, 0.2]), 0.0);
    let mass: f64 = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| t.cell_mass(c, r))
        .sum();
    assert_relative_eq!(mass, 1.0, epsilon = 1e-12);
}

#[test]
fn sample_square_consumes_exactly_two_uniforms() {
    let (w, h, v) = test_grid();
    let t = PiecewiseConstant2D::new(w, h, v, UNIT).unwrap();
    let u = [0.3, 0.8, 0.1, 0.6];
    let mut seq = partition_sampler::UniformSequence::new(&u);
    let a = t.sample(&mut seq);
    assert_eq!(seq.consumed(), 2);
    assert_eq!(a, t.sample_square([0.3, 0.8]));
}

#[test]
fn extreme_uniforms_stay_inside_the_support() {
    let (w, h, v) = test_grid();
    let t = PiecewiseConstant2D::new(w, h, v, UNIT).unwrap();
    for u in [
        [0.0, 0.0],
        [1.0, 1.0],
        [f64::NAN, 2.0],
        [-3.0, 0.999_999_999_999],
        [1.0 - 1e-17, 0.0],
    ] {
        let s = t.sample_square(u);
        assert!(s.pdf > 0.0, "{u:?} -> {s:?}");
        assert!(
            (0.0..1.0).contains(&s.point[0]) && (0.0..1.0).contains(&s.point[1]),
            "{s:?}"
        );
        assert_eq!(t.pdf(s.point), s.pdf);
    }
}

#[test]
fn construction_errors_are_typed() {
    let err = |w, h, v: Vec<f64>| PiecewiseConstant2D::new(w, h, v, UNIT).unwrap_err();
    assert_eq!(
        err(0, 3, vec![]),
        PiecewiseConstantError::Empty {
            width: 0,
            height: 3
        }
    );
    assert_eq!(
        err(2, 2, vec![1.0; 3]),
        PiecewiseConstantError::SizeMismatch {
            width: 2,
            height: 2,
            expected: 4,
            got: 3
        }
    );
    assert!(matches!(
        err(2, 2, vec![1.0, 1.0, f64::NAN, 1.0]),
        PiecewiseConstantError::NonFinite {
            column: 0,
            row: 1,
            ..
        }
    ));
    assert!(matches!(
        err(2, 2, vec![1.0, f64::INFINITY, 1.0, 1.0]),
        PiecewiseConstantError::NonFinite {
            column: 1,
            row: 0,
            ..
        }
    ));
    assert_eq!(
        err(2, 2, vec![1.0, 1.0, 1.0, -0.5]),
        PiecewiseConstantError::Negative {
            column: 1,
            row: 1,
            value: -0.5
        }
    );
    assert_eq!(err(2, 2, vec![0.0; 4]), PiecewiseConstantError::AllZero);
    assert_eq!(
        err(2, 2, vec![f64::MAX; 4]),
        PiecewiseConstantError::TotalNotFinite
    );
    assert!(matches!(
        PiecewiseConstant2D::new(
            1,
            1,
            vec![1.0],
            Rect {
                x0: 1.0,
                y0: 0.0,
                x1: 1.0,
                y1: 1.0
            }
        ),
        Err(PiecewiseConstantError::InvalidDomain { .. })
    ));
    assert!(matches!(
        PiecewiseConstant2D::new(
            1,
            1,
            vec![1.0],
            Rect {
                x0: 0.0,
                y0: f64::NAN,
                x1: 1.0,
                y1: 1.0
            }
        ),
        Err(PiecewiseConstantError::InvalidDomain { .. })
    ));
    assert_eq!(
        PiecewiseConstant1D::new(vec![], 0.0, 1.0).unwrap_err(),
        PiecewiseConstantError::EmptyInterval
    );
    assert_eq!(
        PiecewiseConstant1D::new(vec![0.0, 0.0], 0.0, 1.0).unwrap_err(),
        PiecewiseConstantError::AllZero
    );
    assert!(matches!(
        PiecewiseConstant1D::new(vec![1.0, -1.0], 0.0, 1.0),
        Err(PiecewiseConstantError::NegativeValue { index: 1, .. })
    ));
    assert!(matches!(
        PiecewiseConstant1D::new(vec![1.0, f64::NAN], 0.0, 1.0),
        Err(PiecewiseConstantError::NonFiniteValue { index: 1, .. })
    ));
    assert_eq!(
        PiecewiseConstant1D::new(vec![1.0], 2.0, 1.0).unwrap_err(),
        PiecewiseConstantError::InvalidInterval { min: 2.0, max: 1.0 }
    );
    assert_eq!(
        PiecewiseConstant1D::new(vec![1.0], 2.0, 1.0)
            .unwrap_err()
            .to_string(),
        "invalid interval [2, 1]: need finite min < max"
    );
}

#[test]
fn serde_round_trip_and_validation() {
    let (w, h, v) = test_grid();
    let t = PiecewiseConstant2D::new(w, h, v, UNIT).unwrap();
    let json = serde_json::to_string(&t).unwrap();
    let back: PiecewiseConstant2D = serde_json::from_str(&json).unwrap();
    assert_eq!(back, t);
    // Tampered data is re-validated, not trusted.
    let bad = json.replacen("\"width\":7", "\"width\":6", 1);
    assert!(serde_json::from_str::<PiecewiseConstant2D>(&bad).is_err());
    let bad = json.replacen("\"version\":1", "\"version\":99", 1);
    assert!(serde_json::from_str::<PiecewiseConstant2D>(&bad).is_err());

    let d = PiecewiseConstant1D::new(vec![1.0, 0.0, 2.0], -1.0, 1.0).unwrap();
    let back: PiecewiseConstant1D =
        serde_json::from_str(&serde_json::to_string(&d).unwrap()).unwrap();
    assert_eq!(back, d);
}

#[test]
fn bytes_used_counts_the_tables() {
    let t = PiecewiseConstant2D::new(8, 4, vec![1.0; 32], UNIT).unwrap();
    let floats = 32 + 4 * 9 + 5;
    assert!(t.bytes_used() >= floats * 8);
    assert!(t.bytes_used() < floats * 8 + 512);
}

#[test]
fn one_d_chi_square_and_pdf() {
    let v = vec![0.5, 0.0, 3.0, 1.0, 0.25, 2.0];
    let d = PiecewiseConstant1D::new(v.clone(), 1.0, 4.0).unwrap();
    assert_relative_eq!(d.integral(), 6.75 * 0.5);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    let mut counts = vec![0u64; v.len()];
    for _ in 0..100_000 {
        let s = d.sample(rng.next_uniform());
        assert_eq!(s.index, ((s.x - 1.0) / 0.5) as usize);
        assert_eq!(s.pdf, d.pdf(s.x));
        counts[s.index] += 1;
    }
    assert!(chi_square_p(&counts, &masses(&v)) > ALPHA);
    assert_eq!(d.pdf(0.99), 0.0);
    assert_eq!(d.invert(1.6), None); // zero-density cell
}

fn grid_strategy() -> impl Strategy<Value = (usize, usize, Vec<f64>)> {
    (1usize..9, 1usize..9).prop_flat_map(|(w, h)| {
        let cell = prop_oneof![1 => Just(0.0), 4 => 1e-6f64..1e3];
        (Just(w), Just(h), proptest::collection::vec(cell, w * h))
            .prop_filter("needs mass", |(_, _, v)| v.iter().any(|&x| x > 0.0))
    })
}

proptest! {
    #[test]
    fn invert_after_sample_is_identity((w, h, v) in grid_strategy(), u0 in 0.0f64..1.0, u1 in 0.0f64..1.0) {
        let t = PiecewiseConstant2D::new(w, h, v, Rect { x0: -2.0, y0: 1.0, x1: 3.0, y1: 1.5 }).unwrap();
        let s = t.sample_square([u0, u1]);
        prop_assert!(s.pdf > 0.0);
        let u = t.invert(s.point).unwrap();
        prop_assert!((u[0] - u0).abs() < 1e-9 && (u[1] - u1).abs() < 1e-9, "{:?} vs {:?}", u, [u0, u1]);
    }

    #[test]
    fn sample_after_invert_is_identity((w, h, v) in grid_strategy(), x in 0.0f64..1.0, y in 0.0f64..1.0) {
        let t = PiecewiseConstant2D::new(w, h, v, UNIT).unwrap();
        if let Some(u) = t.invert([x, y]) {
            let p = t.sample_square(u).point;
            prop_assert!((p[0] - x).abs() < 1e-9 && (p[1] - y).abs() < 1e-9, "{:?} vs {:?}", p, [x, y]);
        } else {
            prop_assert_eq!(t.pdf([x, y]), 0.0);
        }
    }

    #[test]
    fn one_d_round_trip(v in proptest::collection::vec(0.0f64..10.0, 1..20), u in 0.0f64..1.0) {
        prop_assume!(v.iter().any(|&x| x > 0.0));
        let d = PiecewiseConstant1D::new(v, -1.0, 2.0).unwrap();
        let s = d.sample(u);
        prop_assert!(s.pdf > 0.0 && (-1.0..2.0).contains(&s.x));
        prop_assert!((d.invert(s.x).unwrap() - u).abs() < 1e-9);
    }
}
