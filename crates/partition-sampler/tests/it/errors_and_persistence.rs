//! Bad inputs give typed errors; persistence rejects wrong versions, truncation and corruption;
//! parallel sampling does not depend on the thread count.

use partition_sampler::{
    AttachError, BuildError, DensityError, Domain, FORMAT_VERSION, MAX_DEPTH_LIMIT, PersistError,
    QuadTree, QuadTreeBuilder, QuadTreeSampler, Rect, SampledGridDensity, Sampler2D, SinPiRows,
    TabulatedDensity, UserBoundDensity,
};

fn tab() -> TabulatedDensity {
    TabulatedDensity::new(
        4,
        2,
        vec![1.0, 2.0, 3.0, 4.0, 0.0, 1.0, 9.0, 1.0],
        Rect::UNIT,
    )
    .unwrap()
}

#[test]
fn density_errors() {
    let e = TabulatedDensity::new(3, 1, vec![1.0, -2.0, f64::NAN], Rect::UNIT).unwrap_err();
    assert_eq!(
        e,
        DensityError::InvalidValue {
            index: 1,
            column: 1,
            row: 0,
            value: -2.0
        }
    );
    assert!(matches!(
        TabulatedDensity::new(1, 2, vec![1.0, f64::INFINITY], Rect::UNIT),
        Err(DensityError::InvalidValue {
            index: 1,
            row: 1,
            ..
        })
    ));
    assert_eq!(
        TabulatedDensity::new(2, 2, vec![0.0; 4], Rect::UNIT).unwrap_err(),
        DensityError::ZeroTotal
    );
    assert_eq!(
        TabulatedDensity::new(0, 0, vec![], Rect::UNIT).unwrap_err(),
        DensityError::EmptyGrid {
            width: 0,
            height: 0
        }
    );
    // A one-row map with all mass on a row factor that vanishes: zero total.
    #[derive(Debug)]
    struct Zero;
    impl partition_sampler::RowFactor for Zero {
        fn eval(&self, _t: f64) -> f64 {
            0.0
        }
        fn max_on(&self, _a: f64, _b: f64) -> f64 {
            0.0
        }
        fn integral(&self, _a: f64, _b: f64) -> f64 {
            0.0
        }
    }
    assert_eq!(
        tab().with_row_factor(Zero).unwrap_err(),
        DensityError::ZeroTotal
    );
    let nan_f = |_: [f64; 2]| f64::NAN;
    assert!(matches!(
        SampledGridDensity::new(nan_f, Domain::UnitDisc, 8),
        Err(DensityError::InvalidSample { .. })
    ));
    assert_eq!(
        SampledGridDensity::new(|_: [f64; 2]| 0.0, Domain::UnitDisc, 8).unwrap_err(),
        DensityError::ZeroTotal
    );
    assert_eq!(
        SampledGridDensity::new(|_: [f64; 2]| 1.0, Domain::UnitDisc, 0).unwrap_err(),
        DensityError::InvalidResolution(0)
    );
    let g = SampledGridDensity::new(|_: [f64; 2]| 1.0, Domain::UnitDisc, 8).unwrap();
    assert_eq!(
        g.with_safety_factor(0.9).unwrap_err(),
        DensityError::InvalidSafetyFactor(0.9)
    );
    assert!(matches!(
        UserBoundDensity::new(|_: [f64; 2]| 1.0, |_: &Rect| 1.0, Domain::UnitDisc, 3),
        Err(DensityError::InvalidQuadrature(3))
    ));
}

#[test]
fn builder_errors() {
    for bad in [0.5, f64::NAN, f64::INFINITY, -1.0] {
        let e = QuadTreeBuilder::new().n_max(bad).build(tab()).unwrap_err();
        assert!(matches!(e, BuildError::InvalidNMax(_)), "{e:?}");
    }
    assert_eq!(
        QuadTreeBuilder::new()
            .max_depth(MAX_DEPTH_LIMIT + 1)
            .build(tab())
            .unwrap_err(),
        BuildError::MaxDepthTooLarge(MAX_DEPTH_LIMIT + 1)
    );
    assert!(matches!(
        QuadTreeBuilder::new().min_leaf_size(f64::NAN).build(tab()),
        Err(BuildError::InvalidMinLeafSize(_))
    ));
    // A user bound returning NaN is caught while building.
    let d = UserBoundDensity::new(
        |_: [f64; 2]| 1.0,
        |_: &Rect| f64::NAN,
        Domain::Rect(Rect::UNIT),
        2,
    )
    .unwrap();
    assert!(matches!(
        QuadTreeBuilder::new().build(d),
        Err(BuildError::InvalidRegionEstimate { .. })
    ));
    // Zero bounds everywhere: nothing to sample.
    let d = UserBoundDensity::new(
        |_: [f64; 2]| 1.0,
        |_: &Rect| 0.0,
        Domain::Rect(Rect::UNIT),
        2,
    )
    .unwrap();
    assert_eq!(
        QuadTreeBuilder::new().build(d).unwrap_err(),
        BuildError::ZeroMass
    );
    // A compacted sampled density cannot build another tree.
    let g = SampledGridDensity::new(|_: [f64; 2]| 1.0, Domain::UnitDisc, 8)
        .unwrap()
        .compact();
    assert!(matches!(
        QuadTreeBuilder::new().build(g),
        Err(BuildError::InvalidRegionEstimate { .. })
    ));
}

#[test]
fn persistence_errors() {
    let s = QuadTreeBuilder::new().build(tab()).unwrap();
    let bytes = s.tree().to_bytes();
    assert_eq!(&bytes[..4], b"PSQT");
    assert_eq!(
        QuadTree::from_bytes(&bytes[..3]).unwrap_err(),
        PersistError::Truncated
    );
    assert_eq!(
        QuadTree::from_bytes(&bytes[..bytes.len() - 5]).unwrap_err(),
        PersistError::Truncated
    );
    let mut wrong = bytes.clone();
    wrong[4..8].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    assert_eq!(
        QuadTree::from_bytes(&wrong).unwrap_err(),
        PersistError::UnsupportedVersion {
            found: FORMAT_VERSION + 1,
            expected: FORMAT_VERSION
        }
    );
    // Trees of format 1 (f64 leaves, CDFs inside the nodes) are refused, not misread.
    assert_eq!(FORMAT_VERSION, 2);
    let mut v1 = bytes.clone();
    v1[4..8].copy_from_slice(&1u32.to_le_bytes());
    assert_eq!(
        QuadTree::from_bytes(&v1).unwrap_err(),
        PersistError::UnsupportedVersion {
            found: 1,
            expected: 2
        }
    );
    let mut magic = bytes.clone();
    magic[0] = b'X';
    assert_eq!(
        QuadTree::from_bytes(&magic).unwrap_err(),
        PersistError::BadMagic
    );
    // Flipping payload bytes never panics: it decodes to an error or to a valid tree.
    for k in 8..bytes.len() {
        let mut c = bytes.clone();
        c[k] ^= 0xA5;
        if let Ok(t) = QuadTree::from_bytes(&c) {
            let _ = QuadTreeSampler::from_parts(t, tab()).map(|s| s.pdf([0.3, 0.3]));
        }
    }
    // Re-attaching to a different density is refused.
    let other = TabulatedDensity::new(4, 2, vec![1.0; 8], Rect::UNIT).unwrap();
    assert!(matches!(
        QuadTreeSampler::from_parts(s.tree().clone(), other),
        Err(AttachError::ShapeMismatch { .. })
    ));
    let sin = tab().with_row_factor(SinPiRows).unwrap();
    assert!(matches!(
        QuadTreeSampler::from_parts(s.tree().clone(), sin),
        Err(AttachError::ShapeMismatch { .. })
    ));
    assert!(QuadTreeSampler::from_parts(s.tree().clone(), tab()).is_ok());
}

#[test]
fn parallel_output_is_independent_of_thread_count() {
    let d = tab().with_row_factor(SinPiRows).unwrap();
    let s = QuadTreeBuilder::new().build(d).unwrap();
    let n = 3 * partition_sampler::PAR_CHUNK + 17;
    let run = |threads: usize| distributions::on_threads(threads, || s.sample_par(n, 42)).unwrap();
    let one = run(1);
    let two = run(2);
    assert_eq!(one.len(), n);
    assert_eq!(one, two);
    assert_ne!(one, s.sample_par(n, 43));
    assert!(
        one.iter()
            .all(|x| Rect::UNIT.contains(x.point) && x.pdf > 0.0)
    );
    let st = s.stats();
    assert_eq!(st.samples, 2 * n as u64 + n as u64);
    assert!(st.measured_mean_trials.unwrap() >= 1.0);
}
