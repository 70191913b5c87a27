//! Splitting `N` samples over strata with probabilities `p_i` (seed 000 §3.6, seed 003 §3.3).
//!
//! Reusable for any stratified batch (quadtree leaves, SRBF lobes, …).

use crate::contract::UniformSource;
use crate::error::AllocationError;

/// How the remainder `R = N − Σ ⌊N p_i⌋` is distributed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AllocationMode {
    /// **Default, unbiased.** `n_i = ⌊N p_i⌋ + δ_i` with `δ_i ∈ {0, 1}` drawn by systematic
    /// sampling (one uniform) on the fractional parts `r_i = N p_i − ⌊N p_i⌋`, so that
    /// `E[n_i] = N p_i` exactly and `Σ n_i = N` always.
    #[default]
    RandomizedRemainder,
    /// Deterministic largest remainders (Hamilton's method; ties go to the lower index). Use
    /// the stratum weights `N p_i / n_i` ([`stratum_weights`]). Biased: `E[n_i] ≠ N p_i` in
    /// general, and a stratum with `N p_i < 1` may get no sample, so its mass is missed.
    Hamilton,
}

/// Splits `n` samples over strata with weights `weights` (probabilities up to a common
/// factor; they need not be normalised): returns `n_i` with `Σ n_i = n` and
/// `n_i ∈ {⌊n p_i⌋, ⌈n p_i⌉}`, `p_i = w_i / Σ w`.
///
/// Consumes one uniform from `u` in [`AllocationMode::RandomizedRemainder`] (none in
/// Hamilton mode, none when `n = 0`). Errors: a NaN / negative / infinite weight, or `n > 0`
/// with weights summing to zero.
pub fn allocate<U: UniformSource + ?Sized>(
    n: usize,
    weights: &[f64],
    mode: AllocationMode,
    u: &mut U,
) -> Result<Vec<usize>, AllocationError> {
    if let Some((index, &value)) = weights
        .iter()
        .enumerate()
        .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
    {
        return Err(AllocationError::InvalidWeight { index, value });
    }
    let mut counts = vec![0usize; weights.len()];
    if n == 0 {
        return Ok(counts);
    }
    let total: f64 = weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(AllocationError::ZeroTotal { n });
    }
    let nf = n as f64;
    // Expected counts, floors and fractional parts.
    let mut frac = vec![0.0f64; weights.len()];
    let mut assigned: u128 = 0;
    for ((c, r), &w) in counts.iter_mut().zip(frac.iter_mut()).zip(weights) {
        let e = nf * (w / total);
        let f = e.floor();
        // `as` saturates; f ≤ n up to rounding.
        *c = (f as usize).min(n);
        *r = (e - f).clamp(0.0, 1.0);
        assigned += *c as u128;
    }
    // Rounding with huge n can overshoot: take the excess back from the largest counts.
    while assigned > n as u128 {
        let Some(k) = (0..counts.len()).max_by_key(|&k| counts[k]) else {
            break;
        };
        let take = (assigned - n as u128).min(counts[k] as u128);
        counts[k] -= take as usize;
        assigned -= take;
    }
    let rem = (n as u128 - assigned) as usize;
    if rem == 0 {
        return Ok(counts);
    }
    match mode {
        AllocationMode::RandomizedRemainder => {
            distribute_systematic(&mut counts, &mut frac, weights, rem, u)
        }
        AllocationMode::Hamilton => distribute_largest(&mut counts, &frac, weights, rem),
    }
    Ok(counts)
}

/// Systematic sampling of `rem` extra units on the fractional parts rescaled to sum `rem`.
fn distribute_systematic<U: UniformSource + ?Sized>(
    counts: &mut [usize],
    frac: &mut [f64],
    weights: &[f64],
    rem: usize,
    u: &mut U,
) {
    let mut sum: f64 = frac.iter().sum();
    if sum.is_nan() || sum <= 0.0 {
        // Only reachable through rounding with huge n: fall back to the weights.
        frac.copy_from_slice(weights);
        sum = frac.iter().sum();
    }
    let scale = rem as f64 / sum;
    let start = u.next_uniform();
    // Points start, start + 1, …, start + rem − 1 on the cumulative scale [0, rem).
    let mut acc = 0.0f64;
    let mut next = 0usize; // index of the next point
    let last_positive = frac.iter().rposition(|&r| r > 0.0).unwrap_or(0);
    for (k, (c, &r)) in counts.iter_mut().zip(frac.iter()).enumerate() {
        acc = if k == last_positive {
            rem as f64
        } else {
            (acc + r * scale).min(rem as f64)
        };
        while next < rem && (next as f64 + start) < acc {
            *c += 1;
            next += 1;
        }
        if next == rem {
            break;
        }
    }
}

/// The `rem` largest fractional parts get one extra unit each (ties: lower index first).
fn distribute_largest(counts: &mut [usize], frac: &[f64], weights: &[f64], rem: usize) {
    let mut order: Vec<usize> = (0..counts.len()).filter(|&k| weights[k] > 0.0).collect();
    order.sort_by(|&a, &b| frac[b].total_cmp(&frac[a]).then(a.cmp(&b)));
    let mut left = rem;
    // With rounding, rem may exceed the number of strata: cycle.
    while left > 0 && !order.is_empty() {
        for &k in &order {
            if left == 0 {
                break;
            }
            counts[k] += 1;
            left -= 1;
        }
    }
}

/// Stratum weights `N p_i / n_i` for a split `counts` of `n` samples (0 where `n_i = 0`).
pub fn stratum_weights(n: usize, weights: &[f64], counts: &[usize]) -> Vec<f64> {
    let total: f64 = weights.iter().sum();
    weights
        .iter()
        .zip(counts)
        .map(|(&w, &c)| {
            if c == 0 || total.is_nan() || total <= 0.0 {
                0.0
            } else {
                n as f64 * (w / total) / c as f64
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::UniformSequence;

    #[test]
    fn hamilton_is_largest_remainder() {
        let mut u = UniformSequence::new(&[]);
        let c = allocate(10, &[0.33, 0.33, 0.34], AllocationMode::Hamilton, &mut u).unwrap();
        assert_eq!(c, vec![3, 3, 4]);
        let w = stratum_weights(10, &[0.33, 0.33, 0.34], &c);
        assert!((w[0] - 1.1).abs() < 1e-12 && (w[2] - 0.85).abs() < 1e-12);
    }

    #[test]
    fn systematic_extra_units_follow_the_uniform() {
        // N p = [0.5, 0.5]: one extra unit goes to stratum 0 when u < 0.5, else to stratum 1.
        for (u, expected) in [(0.2, vec![1, 0]), (0.7, vec![0, 1])] {
            let c = allocate(
                1,
                &[1.0, 1.0],
                AllocationMode::RandomizedRemainder,
                &mut UniformSequence::new(&[u]),
            )
            .unwrap();
            assert_eq!(c, expected, "u = {u}");
        }
    }

    #[test]
    fn typed_errors() {
        let mut u = UniformSequence::new(&[0.5]);
        assert!(matches!(
            allocate(3, &[1.0, f64::NAN], AllocationMode::default(), &mut u),
            Err(AllocationError::InvalidWeight { index: 1, .. })
        ));
        assert_eq!(
            allocate(3, &[0.0], AllocationMode::default(), &mut u),
            Err(AllocationError::ZeroTotal { n: 3 })
        );
        assert_eq!(
            allocate(0, &[0.0], AllocationMode::default(), &mut u),
            Ok(vec![0])
        );
    }
}
