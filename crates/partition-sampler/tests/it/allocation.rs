//! Batch allocation: Σ n_i = N always (proptest), E[n_i] = N p_i for the randomised remainder
//! (z-tests with Bonferroni correction, α = 0.01) and the documented bias of Hamilton's split.

use crate::common;

use common::ALPHA;
use partition_sampler::{AllocationMode, UniformSequence, allocate, stratum_weights};
use proptest::prelude::*;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use statrs::distribution::{ContinuousCDF, Normal};

proptest! {
    #[test]
    fn counts_sum_to_n(
        weights in prop::collection::vec(prop_oneof![Just(0.0), 0.0f64..1.0, 1e-9f64..1e-6, 1.0f64..1e6], 1..40),
        n in prop_oneof![Just(0usize), 1usize..100, 100usize..1_000_000, Just(usize::MAX / 3), Just(usize::MAX)],
        u in 0.0f64..1.0,
    ) {
        let total: f64 = weights.iter().sum();
        prop_assume!(total > 0.0 || n == 0);
        for mode in [AllocationMode::RandomizedRemainder, AllocationMode::Hamilton] {
            let c = allocate(n, &weights, mode, &mut UniformSequence::new(&[u])).unwrap();
            prop_assert_eq!(c.len(), weights.len());
            prop_assert_eq!(c.iter().map(|&k| k as u128).sum::<u128>(), n as u128);
            if n < 1 << 40 && total > 0.0 {
                for (&k, &w) in c.iter().zip(&weights) {
                    let e = n as f64 * w / total;
                    prop_assert!((k as f64) >= e.floor() - 1e-6 && (k as f64) <= e.ceil() + 1e-6, "{} vs {}", k, e);
                }
            }
        }
    }
}

/// Largest |z| of the per-stratum mean counts against N p_i over `reps` allocations.
fn max_z(n: usize, p: &[f64], mode: AllocationMode, reps: usize, seed: u64) -> (f64, f64) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut sum = vec![0.0f64; p.len()];
    for _ in 0..reps {
        for (s, c) in sum.iter_mut().zip(allocate(n, p, mode, &mut rng).unwrap()) {
            *s += c as f64;
        }
    }
    let mut worst = 0.0f64;
    for (s, &pi) in sum.iter().zip(p) {
        let e = n as f64 * pi;
        let r = e - e.floor();
        // n_i − ⌊N p_i⌋ is Bernoulli(r): sd of the mean sqrt(r(1−r)/reps); floor at a tiny sd
        // so a deterministic mismatch still shows as a huge z.
        let sd = (r * (1.0 - r) / reps as f64).sqrt().max(1e-9);
        worst = worst.max(((s / reps as f64) - e).abs() / sd);
    }
    // Bonferroni critical value for α over all strata.
    let crit = Normal::standard().inverse_cdf(1.0 - ALPHA / (2.0 * p.len() as f64));
    (worst, crit)
}

fn probabilities() -> Vec<f64> {
    let w = [0.013, 0.2, 0.031, 0.0, 0.11, 0.4, 0.07, 0.006, 0.17];
    let t: f64 = w.iter().sum();
    w.iter().map(|x| x / t).collect()
}

#[test]
fn randomized_remainder_is_unbiased() {
    let p = probabilities();
    for (n, seed) in [(1usize, 1u64), (13, 2), (100, 3)] {
        let (z, crit) = max_z(n, &p, AllocationMode::RandomizedRemainder, 20_000, seed);
        assert!(z < crit, "N = {n}: max |z| = {z} ≥ {crit}");
    }
}

#[test]
fn hamilton_is_biased_and_the_test_sees_it() {
    let p = probabilities();
    let (z, crit) = max_z(13, &p, AllocationMode::Hamilton, 20_000, 4);
    assert!(
        z > crit,
        "the unbiasedness test cannot detect Hamilton's bias: {z} ≤ {crit}"
    );
    // Strata with N p_i < 1 can get nothing.
    let c = allocate(
        13,
        &p,
        AllocationMode::Hamilton,
        &mut UniformSequence::new(&[]),
    )
    .unwrap();
    assert_eq!(c[7], 0);
    let w = stratum_weights(13, &p, &c);
    assert_eq!(w[7], 0.0);
    for k in 0..p.len() {
        if c[k] > 0 {
            assert!((w[k] * c[k] as f64 - 13.0 * p[k]).abs() < 1e-12);
        }
    }
}
