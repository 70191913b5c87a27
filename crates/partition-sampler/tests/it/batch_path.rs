//! The block path of `QuadTreeSampler::sample_into` (envelope scheme, alias leaf choice) must
//! return exactly the samples of the one-sample loop, consume exactly the same uniforms, and
//! count the same trials, violations and exhausted samples — on identity and mapped frames,
//! with wrong bounds and with samples abandoned at the trial cap.

use crate::common;

use common::*;
use partition_sampler::diagnostics::AuditedDraws;
use partition_sampler::{
    Audit, Domain, LeafChoice, QuadTreeBuilder, QuadTreeSampler, Rect, RegionStats, Sample2,
    SampledGridDensity, Sampler2D, Scheme, SinPiRows, TabulatedDensity, thread_trials,
};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{Rng, SeedableRng};

fn density(rect: Rect) -> TabulatedDensity<SinPiRows> {
    let (w, h) = (64, 32);
    sin_rows(w, h, sun_map(w, h, 40.0), rect)
}

/// `len` samples of one `sample_into` call from a generator seeded with `seed`, and that
/// generator after the call.
fn block_samples<S: Sampler2D>(s: &S, len: usize, seed: u64) -> (Vec<Sample2>, Xoshiro256PlusPlus) {
    let mut block = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut got = vec![
        Sample2 {
            point: [f64::NAN; 2],
            pdf: f64::NAN
        };
        len
    ];
    s.sample_into(&mut block, &mut got);
    (got, block)
}

/// `sample_into` against `len` calls of the one-sample path, from the same generator state:
/// same samples, same generator state after, same counts.
fn check_same<D: RegionStats>(s: &QuadTreeSampler<D>, len: usize, seed: u64) -> Audit {
    let mut one = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut audit = Audit::default();
    let expected: Vec<Sample2> = (0..len)
        .map(|_| s.sample_audited(&mut one, &mut audit))
        .collect();
    s.reset_stats();
    let trials_before = thread_trials();
    let (got, mut block) = block_samples(s, len, seed);
    // The calling thread's trial counter (`bench`'s trials per sample) moved by the same count.
    assert_eq!(
        thread_trials() - trials_before,
        audit.trials,
        "thread_trials"
    );
    assert_eq!(got, expected, "len {len}, seed {seed}");
    assert_eq!(block.next_u64(), one.next_u64(), "uniforms consumed differ");
    let st = s.stats();
    assert_eq!(st.samples, audit.samples);
    assert_eq!(st.bound_violations, audit.violations);
    assert_eq!(st.exhausted, audit.exhausted);
    assert_eq!(
        st.measured_mean_trials
            .map(|t| (t * st.samples as f64).round() as u64),
        (audit.samples > 0).then_some(audit.trials)
    );
    audit
}

const LENGTHS: [usize; 6] = [0, 1, 7, 64, 65, 3001];

#[test]
fn block_path_equals_one_sample_path_on_identity_frame() {
    let s = QuadTreeBuilder::new()
        .n_max(1.6)
        .build(density(Rect::UNIT))
        .unwrap();
    for (k, len) in LENGTHS.into_iter().enumerate() {
        check_same(&s, len, 100 + k as u64);
    }
}

#[test]
fn block_path_equals_one_sample_path_on_mapped_frame() {
    let s = QuadTreeBuilder::new()
        .build(density(Rect::new(-0.3, 1.0, 2.2, 1.7)))
        .unwrap();
    for (k, len) in LENGTHS.into_iter().enumerate() {
        check_same(&s, len, 200 + k as u64);
    }
}

#[test]
fn block_path_counts_the_same_violations() {
    let broken = Broken::new(density(Rect::UNIT), 0.5, 1.0);
    let s = QuadTreeBuilder::new().max_depth(3).build(broken).unwrap();
    let a = check_same(&s, 5000, 7);
    assert!(a.violations > 100, "{a:?}");
}

#[test]
fn block_path_abandons_samples_at_the_trial_cap_like_the_one_sample_path() {
    // Bounds 1e30 too high: acceptance probability ~1e-30, every sample hits the cap.
    let hopeless = Broken::new(density(Rect::UNIT), 1e30, 1.0);
    let s = QuadTreeBuilder::new().max_depth(2).build(hopeless).unwrap();
    let a = check_same(&s, 2, 9);
    assert_eq!(a.exhausted, 2, "{a:?}");
}

#[test]
fn other_schemes_and_leaf_choices_keep_the_one_sample_loop() {
    for (scheme, choice) in [
        (Scheme::Paper, LeafChoice::Alias),
        (Scheme::Envelope, LeafChoice::Descent),
        (Scheme::Paper, LeafChoice::Descent),
    ] {
        let s = QuadTreeBuilder::new()
            .scheme(scheme)
            .leaf_choice(choice)
            .build(density(Rect::UNIT))
            .unwrap();
        check_same(&s, 500, 3);
    }
    // The disc keeps the one-sample loop too.
    let lobe = QuadTreeBuilder::new()
        .build(SampledGridDensity::new(phong_lobe(30.0, 50.0), Domain::UnitDisc, 128).unwrap())
        .unwrap();
    check_same(&lobe, 500, 4);
}

#[test]
fn piecewise_constant_block_path_equals_one_sample_path() {
    use partition_sampler::PiecewiseConstant2D;
    let (w, h) = (97, 31);
    let mut vals = sun_map(w, h, 40.0);
    vals[5] = 0.0;
    vals[w * 3..w * 4].fill(0.0);
    let t = PiecewiseConstant2D::new(w, h, vals, Rect::new(-0.3, 1.0, 2.2, 1.7)).unwrap();
    for (k, len) in LENGTHS.into_iter().enumerate() {
        let mut one = Xoshiro256PlusPlus::seed_from_u64(300 + k as u64);
        let expected: Vec<Sample2> = (0..len).map(|_| t.sample(&mut one)).collect();
        let (got, mut block) = block_samples(&t, len, 300 + k as u64);
        assert_eq!(got, expected);
        assert_eq!(block.next_u64(), one.next_u64());
    }
}
