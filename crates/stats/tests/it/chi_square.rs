//! Chi-square p-values, pooling rules and input validation.

use proptest::prelude::*;
use stats::{DEFAULT_MIN_EXPECTED, StatsError, chi_square_gof, chi_square_sf};

#[test]
fn p_values_match_published_quantiles() {
    // Upper quantiles of the chi-square distribution (standard tables).
    for (x, dof, p) in [
        (3.841459, 1usize, 0.05),
        (6.634897, 1, 0.01),
        (18.307038, 10, 0.05),
        (23.209251, 10, 0.01),
        (124.342113, 100, 0.05),
        (135.806723, 100, 0.01),
    ] {
        assert!(
            (chi_square_sf(x, dof) - p).abs() < 1e-6,
            "dof {dof}: {}",
            chi_square_sf(x, dof)
        );
    }
    // dof = 2 has the closed form exp(−x/2).
    assert!((chi_square_sf(7.0, 2) - (-3.5f64).exp()).abs() < 1e-14);
    assert!(chi_square_sf(1.0, 0).is_nan());
}

#[test]
fn low_cells_pool_and_a_small_pool_merges_into_the_smallest_cell() {
    // E = [50, 1, 2, 20, 30]: cells 1 and 2 pool to E = 3 < 5, merged into cell 3 (E = 20).
    let r = chi_square_gof(&[48, 3, 1, 18, 30], &[50.0, 1.0, 2.0, 20.0, 30.0], 5.0).unwrap();
    assert_eq!((r.cells, r.pooled_cells, r.dof), (3, 2, 2));
    let x2 = 4.0 / 50.0 + (22.0 - 23.0f64).powi(2) / 23.0 + 0.0;
    assert!((r.statistic - x2).abs() < 1e-12);
    assert_eq!(r.zero_mass_samples, 0);
}

#[test]
fn zero_expected_with_observations_is_an_immediate_rejection() {
    let r = chi_square_gof(&[10, 10, 1], &[10.0, 10.0, 0.0], DEFAULT_MIN_EXPECTED).unwrap();
    assert_eq!(r.p_value, 0.0);
    assert!(r.statistic.is_infinite());
    assert_eq!(r.zero_mass_samples, 1);
    assert!(
        r.summary()
            .contains("samples where the pdf integrates to zero")
    );
    assert!(!r.outcome("chi2", 1e-9).passed);
    // Empty zero-expected cells are simply ignored.
    let r = chi_square_gof(&[10, 10, 0], &[10.0, 10.0, 0.0], DEFAULT_MIN_EXPECTED).unwrap();
    assert_eq!((r.cells, r.p_value), (2, 1.0));
}

#[test]
fn invalid_inputs_are_errors() {
    assert!(matches!(
        chi_square_gof(&[1, 2], &[1.0], 5.0),
        Err(StatsError::LengthMismatch { .. })
    ));
    assert!(matches!(
        chi_square_gof(&[1, 2], &[1.0, -1.0], 5.0),
        Err(StatsError::InvalidExpected { index: 1, .. })
    ));
    assert!(matches!(
        chi_square_gof(&[1, 2], &[f64::NAN, 1.0], 5.0),
        Err(StatsError::InvalidExpected { index: 0, .. })
    ));
    assert!(matches!(
        chi_square_gof(&[1, 2], &[1.0, 1.0], 0.0),
        Err(StatsError::InvalidMinExpected(_))
    ));
    assert!(matches!(
        chi_square_gof(&[10], &[10.0], 5.0),
        Err(StatsError::TooFewCells { cells: 1 })
    ));
    // Everything pooled into one cell: nothing to test.
    assert!(matches!(
        chi_square_gof(&[1, 2], &[1.0, 2.0], 5.0),
        Err(StatsError::TooFewCells { .. })
    ));
}

proptest! {
    #[test]
    fn pooling_conserves_counts_and_bounds_the_p_value(
        cells in prop::collection::vec((0u64..200, 0.0f64..120.0), 2..60)
    ) {
        let observed: Vec<u64> = cells.iter().map(|c| c.0).collect();
        let expected: Vec<f64> = cells.iter().map(|c| c.1).collect();
        match chi_square_gof(&observed, &expected, 5.0) {
            Ok(r) => {
                prop_assert!(r.statistic >= 0.0);
                prop_assert!((0.0..=1.0).contains(&r.p_value));
                prop_assert!(r.zero_mass_samples > 0 || r.dof + 1 == r.cells);
                let low = expected.iter().filter(|&&e| e > 0.0 && e < 5.0).count();
                prop_assert_eq!(r.pooled_cells, low);
                let kept = expected.iter().filter(|&&e| e >= 5.0).count();
                prop_assert!(r.cells == kept || r.cells == kept + 1);
            }
            Err(StatsError::TooFewCells { cells }) => prop_assert!(cells < 2),
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }
}
