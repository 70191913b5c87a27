//! Vose's alias method: O(n) construction, O(1) draws of an index `i` with probability
//! `w_i / Σ w`.

/// Builds `(threshold, alias)` per entry for weights `w` (finite, ≥ 0, positive sum).
///
/// A draw takes `s = u · n`, `i = ⌊s⌋`, and returns `i` when `s − i < threshold[i]`, else
/// `alias[i]`. Deterministic for given weights.
pub fn build_alias(w: &[f64]) -> Vec<(f64, u32)> {
    let n = w.len();
    let total: f64 = w.iter().sum();
    let mut out = vec![(1.0f64, 0u32); n];
    if n == 0 || total.is_nan() || total <= 0.0 {
        return out;
    }
    let scale = n as f64 / total;
    let mut scaled: Vec<f64> = w.iter().map(|&x| x * scale).collect();
    let mut small: Vec<u32> = Vec::with_capacity(n);
    let mut large: Vec<u32> = Vec::with_capacity(n);
    for (i, &s) in scaled.iter().enumerate() {
        if s < 1.0 {
            small.push(i as u32)
        } else {
            large.push(i as u32)
        }
    }
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        let (su, lu) = (s as usize, l as usize);
        out[su] = (scaled[su], l);
        scaled[lu] = (scaled[lu] + scaled[su]) - 1.0;
        if scaled[lu] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // Leftovers hold (up to rounding) exactly one unit of mass each.
    for i in large.into_iter().chain(small) {
        out[i as usize] = (1.0, i);
    }
    // An entry of zero weight must never be returned: its own share is 0 and a leftover
    // self-alias is redirected to the heaviest entry.
    let best = w
        .iter()
        .enumerate()
        .fold(0usize, |b, (i, &x)| if x > w[b] { i } else { b });
    for (i, e) in out.iter_mut().enumerate() {
        if w[i] <= 0.0 {
            e.0 = 0.0;
            if e.1 as usize == i {
                e.1 = best as u32;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact probabilities implied by the table.
    fn implied(t: &[(f64, u32)]) -> Vec<f64> {
        let n = t.len() as f64;
        let mut p = vec![0.0; t.len()];
        for (i, &(th, a)) in t.iter().enumerate() {
            p[i] += th / n;
            p[a as usize] += (1.0 - th) / n;
        }
        p
    }

    #[test]
    fn reproduces_weights() {
        let w = [0.0, 1.0, 3.0, 0.5, 0.0, 10.0, 1e-9];
        let t = build_alias(&w);
        let p = implied(&t);
        let s: f64 = w.iter().sum();
        for (pi, wi) in p.iter().zip(w) {
            assert!((pi - wi / s).abs() < 1e-14, "{pi} vs {}", wi / s);
        }
        assert_eq!(p[0], 0.0);
        assert_eq!(p[4], 0.0);
    }
}
