//! Kolmogorov–Smirnov tests: one-sample against a CDF, two-sample between two samples.
//!
//! p-values (all `P(D ≥ d)` under the null hypothesis of continuous distributions):
//! - **one-sample, n ≤ 140**: exact, by the Marsaglia–Tsang–Wang (2003) matrix-power formula
//!   for `P(D_n < d)` (with rescaling, so no overflow); when `n d² ≥ 18` or `d ≥ ½` (p below
//!   ~1e-15, or the region where it is exact) by Smirnov's one-sided formula doubled;
//! - **one-sample, n > 140**: the Kolmogorov limit distribution with Stephens' (1970)
//!   small-sample correction, `p = Q_K((√n + 0.12 + 0.11/√n) d)`;
//! - **two-sample**: exact, by a lattice-path recursion over the interleavings whose empirical
//!   CDFs stay within `d`, restricted to the band it can visit (about `2 d n m` cells, so exact
//!   up to `n = m ≈ 10⁴–10⁵`); beyond [`KS_EXACT_MAX_CELLS`] cells,
//!   `Q_K((√nₑ + 0.12 + 0.11/√nₑ) d)` with `nₑ = nm/(n+m)`. The discreteness of `D` makes
//!   every asymptotic formula 5–20 % off in `p` at `n, m ~ 100`, hence the exact range; at the
//!   sizes where the asymptotic branch is used the lattice step `1/n` is negligible.
//!
//! statrs 0.19 has `ks_onesample`/`ks_twosample`, but they expose p-values only through data,
//! their asymptotic branch has no small-sample correction and never terminates when `D = 0`
//! (possible in the two-sample test), and the exact one-sample branch stops at n = 170; they
//! serve as an independent reference in this crate's tests.

use serde::{Deserialize, Serialize};
use statrs::function::factorial::ln_factorial;

use crate::error::StatsError;
use crate::outcome::TestOutcome;

/// Largest one-sample size with an exact p-value.
pub const KS_EXACT_MAX_N: usize = 140;
/// Largest two-sample lattice band (cells visited, about `2 d n m`) computed exactly.
pub const KS_EXACT_MAX_CELLS: usize = 50_000_000;

/// How a KS p-value was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum KsMethod {
    /// Exact finite-sample distribution.
    Exact,
    /// Smirnov's one-sided formula doubled (exact for `d ≥ ½`, otherwise used only when
    /// `p < 1e-15`, where it is accurate to relative order `p`).
    SmirnovTail,
    /// Kolmogorov limit distribution with Stephens' correction.
    Asymptotic,
}

/// Result of a KS test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KsResult {
    /// `D = sup |F_n − F|` (one-sample) or `sup |F_n − G_m|` (two-sample).
    pub statistic: f64,
    /// `P(D ≥ statistic)` under the null hypothesis.
    pub p_value: f64,
    /// Size of the (first) sample.
    pub n: usize,
    /// Size of the second sample (two-sample test only).
    pub m: Option<usize>,
    /// How the p-value was computed.
    pub method: KsMethod,
}

impl KsResult {
    /// One-line summary.
    pub fn summary(&self) -> String {
        match self.m {
            Some(m) => format!(
                "D = {:.5}, n = {}, m = {}, p = {:.4e} ({:?})",
                self.statistic, self.n, m, self.p_value, self.method
            ),
            None => format!(
                "D = {:.5}, n = {}, p = {:.4e} ({:?})",
                self.statistic, self.n, self.p_value, self.method
            ),
        }
    }

    /// The uniform [`TestOutcome`] at significance level `alpha` (passed iff `p ≥ alpha`).
    pub fn outcome(&self, name: &str, alpha: f64) -> TestOutcome {
        TestOutcome::with_p_value(name, self.statistic, self.p_value, alpha, self.summary())
    }
}

/// Kolmogorov distribution function `P(K ≤ x)`, `K = sup |B(t)|` of the Brownian bridge
/// (the limit of `√n D_n`).
///
/// Uses `√(2π)/x Σ_{k≥1} exp(−(2k−1)²π²/(8x²))` for `x < 1` and
/// `1 − 2 Σ_{k≥1} (−1)^{k−1} exp(−2k²x²)` otherwise; both converge fast on their ranges.
pub fn kolmogorov_cdf(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 0.0;
    }
    if x < 1.0 {
        let c = std::f64::consts::PI * std::f64::consts::PI / (8.0 * x * x);
        let mut s = 0.0;
        for k in 1..100 {
            let j = (2 * k - 1) as f64;
            let term = (-j * j * c).exp();
            s += term;
            if term <= 1e-17 * s {
                break;
            }
        }
        ((2.0 * std::f64::consts::PI).sqrt() / x * s).clamp(0.0, 1.0)
    } else {
        1.0 - kolmogorov_sf(x)
    }
}

/// Kolmogorov survival function `P(K > x)` (accurate in the far tail, no cancellation).
pub fn kolmogorov_sf(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x < 1.0 {
        return 1.0 - kolmogorov_cdf(x);
    }
    let mut s = 0.0;
    let mut sign = 1.0;
    for k in 1..100 {
        let kf = k as f64;
        let term = (-2.0 * kf * kf * x * x).exp();
        s += sign * term;
        sign = -sign;
        if term <= 1e-17 * s.abs() {
            break;
        }
    }
    (2.0 * s).clamp(0.0, 1.0)
}

/// Stephens' small-sample correction of the Kolmogorov argument: `(√n + 0.12 + 0.11/√n) d`.
fn stephens(d: f64, n: f64) -> f64 {
    let r = n.sqrt();
    (r + 0.12 + 0.11 / r) * d
}

/// `P(D_n ≥ d)` for the one-sample two-sided statistic with `n` samples (see the module docs
/// for the method used).
pub fn ks_onesample_p_value(d: f64, n: usize) -> f64 {
    onesample_p(d, n).0
}

fn onesample_p(d: f64, n: usize) -> (f64, KsMethod) {
    if d.is_nan() || n == 0 {
        return (f64::NAN, KsMethod::Exact);
    }
    if d <= 0.0 {
        return (1.0, KsMethod::Exact);
    }
    if d >= 1.0 {
        return (0.0, KsMethod::Exact);
    }
    let nf = n as f64;
    if n <= KS_EXACT_MAX_N {
        if d >= 0.5 || nf * d * d >= 18.0 {
            return ((2.0 * smirnov_sf(d, n)).min(1.0), KsMethod::SmirnovTail);
        }
        let p = 1.0 - mtw_cdf(d, n);
        return (p.clamp(0.0, 1.0), KsMethod::Exact);
    }
    (kolmogorov_sf(stephens(d, nf)), KsMethod::Asymptotic)
}

/// `P(D_n < d)` by Marsaglia, Tsang & Wang (2003): with `n d = k − h` (`k` integer,
/// `0 ≤ h < 1`) and `m = 2k − 1`, `P = n!/nⁿ · (Hⁿ)_{k,k}` for an `m × m` matrix `H`.
fn mtw_cdf(d: f64, n: usize) -> f64 {
    let nd = n as f64 * d;
    let k = (nd.ceil() as usize).max(1);
    let h = k as f64 - nd;
    let m = 2 * k - 1;
    let mut hm = vec![0.0; m * m];
    let fact: Vec<f64> = (0..=m).map(|i| ln_factorial(i as u64).exp()).collect();
    for i in 0..m {
        for j in 0..m {
            if i + 1 >= j {
                hm[i * m + j] = 1.0;
            }
        }
    }
    for i in 0..m {
        hm[i * m] -= h.powi(i as i32 + 1);
        hm[(m - 1) * m + i] -= h.powi((m - i) as i32);
    }
    if 2.0 * h - 1.0 > 0.0 {
        hm[(m - 1) * m] += (2.0 * h - 1.0).powi(m as i32);
    }
    for i in 0..m {
        for j in 0..m {
            if i + 1 > j {
                hm[i * m + j] /= fact[i + 1 - j];
            }
        }
    }
    let (q, ln_scale) = mat_pow(&hm, m, n);
    let v = q[(k - 1) * m + (k - 1)];
    if !(v > 0.0) {
        return 0.0;
    }
    let nf = n as f64;
    let ln_p = v.ln() + ln_scale + ln_factorial(n as u64) - nf * nf.ln();
    ln_p.exp().clamp(0.0, 1.0)
}

fn mat_mul(a: &[f64], b: &[f64], m: usize) -> Vec<f64> {
    let mut c = vec![0.0; m * m];
    for i in 0..m {
        for l in 0..m {
            let ail = a[i * m + l];
            if ail == 0.0 {
                continue;
            }
            let (row_b, row_c) = (&b[l * m..(l + 1) * m], &mut c[i * m..(i + 1) * m]);
            for (cj, bj) in row_c.iter_mut().zip(row_b) {
                *cj += ail * bj;
            }
        }
    }
    c
}

/// Rescales a matrix to unit max-norm, returning the log of the factor taken out.
fn normalise(a: &mut [f64]) -> f64 {
    let s = a.iter().fold(0.0_f64, |acc, x| acc.max(x.abs()));
    if s > 0.0 && s.is_finite() {
        a.iter_mut().for_each(|x| *x /= s);
        s.ln()
    } else {
        0.0
    }
}

/// `A^p = Q · exp(ln_scale)` by repeated squaring with rescaling.
fn mat_pow(a: &[f64], m: usize, p: usize) -> (Vec<f64>, f64) {
    if p == 1 {
        return (a.to_vec(), 0.0);
    }
    let (half, s) = mat_pow(a, m, p / 2);
    let mut q = mat_mul(&half, &half, m);
    let mut ln_scale = 2.0 * s;
    if p % 2 == 1 {
        q = mat_mul(&q, a, m);
    }
    ln_scale += normalise(&mut q);
    (q, ln_scale)
}

/// Smirnov's exact one-sided tail `P(D⁺_n ≥ d) = d Σ_{j=0}^{⌊n(1−d)⌋} C(n,j) (d + j/n)^{j−1} (1 − d − j/n)^{n−j}`.
fn smirnov_sf(d: f64, n: usize) -> f64 {
    let nf = n as f64;
    let jmax = (nf * (1.0 - d)).floor().max(0.0) as usize;
    let lnf_n = ln_factorial(n as u64);
    let mut s = 0.0;
    for j in 0..=jmax.min(n) {
        let jf = j as f64;
        let a = d + jf / nf;
        let b = 1.0 - d - jf / nf;
        let ln_b = if n == j {
            0.0
        } else if b > 0.0 {
            (n - j) as f64 * b.ln()
        } else {
            continue;
        };
        let ln_term = lnf_n - ln_factorial(j as u64) - ln_factorial((n - j) as u64)
            + (jf - 1.0) * a.ln()
            + ln_b;
        s += ln_term.exp();
    }
    (d * s).clamp(0.0, 1.0)
}

/// `P(D_{n,m} ≥ d)` for the two-sample two-sided statistic (see the module docs).
pub fn ks_twosample_p_value(d: f64, n: usize, m: usize) -> f64 {
    twosample_p(d, n, m).0
}

fn twosample_p(d: f64, n: usize, m: usize) -> (f64, KsMethod) {
    if d.is_nan() || n == 0 || m == 0 {
        return (f64::NAN, KsMethod::Exact);
    }
    if d <= 0.0 {
        return (1.0, KsMethod::Exact);
    }
    if d > 1.0 {
        return (0.0, KsMethod::Exact);
    }
    let (n, m) = (n.min(m), n.max(m));
    let nm = n as f64 * m as f64;
    // D·n·m is an integer for any achievable D; t = the smallest integer ≥ d·n·m (up to rounding).
    let t = (d * nm - 1e-9 * nm).ceil().max(1.0);
    let band_cells = (n as f64 + 1.0) * (2.0 * t / n as f64 + 2.0);
    if band_cells <= KS_EXACT_MAX_CELLS as f64 {
        return (
            (1.0 - lattice_inside(n, m, t as i64)).clamp(0.0, 1.0),
            KsMethod::Exact,
        );
    }
    let ne = nm / (n + m) as f64;
    (kolmogorov_sf(stephens(d, ne)), KsMethod::Asymptotic)
}

/// Probability that a uniformly random interleaving of `n` and `m` items keeps
/// `|i m − j n| < t` at every prefix (`i` items of the first sample, `j` of the second).
///
/// Forward recursion over the lattice, restricted to the band `|i m − j n| < t` (cost
/// `O(n + t)` cells): from `(i, j)` the next item comes from the first sample with probability
/// `(n − i)/(n + m − i − j)`.
fn lattice_inside(n: usize, m: usize, t: i64) -> f64 {
    let (ni, mi) = (n as i64, m as i64);
    // j range of row i inside the band: i m − t < j n < i m + t.
    let band = |i: i64| {
        let lo = (i * mi - t).div_euclid(ni) + 1;
        let hi = (i * mi + t - 1).div_euclid(ni);
        (lo.max(0), hi.min(mi))
    };
    let mut prob = vec![0.0_f64; m + 1];
    let mut prev = (0i64, -1i64);
    for i in 0..=ni {
        let (lo, hi) = band(i);
        // Clear entries that left the band (row i − 1 values at j < lo).
        for j in prev.0..lo.min(prev.1 + 1) {
            prob[j as usize] = 0.0;
        }
        for j in lo..=hi {
            let ju = j as usize;
            let v = if i == 0 && j == 0 {
                1.0
            } else {
                let rem = (ni + mi - i - j + 1) as f64;
                let from_left = if i > 0 && j >= prev.0 && j <= prev.1 {
                    prob[ju] * (ni - i + 1) as f64 / rem
                } else {
                    0.0
                };
                let from_below = if j > lo {
                    prob[ju - 1] * (mi - j + 1) as f64 / rem
                } else {
                    0.0
                };
                from_left + from_below
            };
            prob[ju] = v;
        }
        prev = (lo, hi);
        if lo > hi {
            return 0.0;
        }
    }
    if prev.1 == mi { prob[m] } else { 0.0 }
}

fn check_finite(x: &[f64]) -> Result<(), StatsError> {
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(StatsError::NonFiniteSample { index }),
        None => Ok(()),
    }
}

/// `D_n = sup_x |F_n(x) − F(x)|` of `samples` against the CDF `cdf`.
///
/// # Errors
/// Empty or non-finite samples, or a CDF value outside `[0, 1]`.
pub fn ks_statistic(samples: &[f64], cdf: &dyn Fn(f64) -> f64) -> Result<f64, StatsError> {
    if samples.is_empty() {
        return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
    }
    check_finite(samples)?;
    let mut x = samples.to_vec();
    x.sort_by(f64::total_cmp);
    let nf = x.len() as f64;
    let mut d = 0.0_f64;
    for (i, &xi) in x.iter().enumerate() {
        let f = cdf(xi);
        if !(0.0..=1.0).contains(&f) {
            return Err(StatsError::InvalidCdfValue { x: xi, value: f });
        }
        d = d.max((i + 1) as f64 / nf - f).max(f - i as f64 / nf);
    }
    Ok(d)
}

/// One-sample two-sided KS test of `samples` against the continuous CDF `cdf`.
///
/// # Errors
/// Empty or non-finite samples, or a CDF value outside `[0, 1]`.
pub fn ks_onesample(samples: &[f64], cdf: &dyn Fn(f64) -> f64) -> Result<KsResult, StatsError> {
    let statistic = ks_statistic(samples, cdf)?;
    let (p_value, method) = onesample_p(statistic, samples.len());
    Ok(KsResult {
        statistic,
        p_value,
        n: samples.len(),
        m: None,
        method,
    })
}

/// Two-sample two-sided KS test: are `a` and `b` drawn from the same continuous distribution?
/// `D = sup_x |F_a(x) − F_b(x)|`, ties handled by stepping past all equal values at once.
///
/// # Errors
/// An empty or non-finite sample.
pub fn ks_twosample(a: &[f64], b: &[f64]) -> Result<KsResult, StatsError> {
    for s in [a, b] {
        if s.is_empty() {
            return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
        }
        check_finite(s)?;
    }
    let (mut x, mut y) = (a.to_vec(), b.to_vec());
    x.sort_by(f64::total_cmp);
    y.sort_by(f64::total_cmp);
    let (n, m) = (x.len(), y.len());
    let (mut i, mut j) = (0usize, 0usize);
    let mut best: u128 = 0;
    while i < n && j < m {
        let v = x[i].min(y[j]);
        while i < n && x[i] == v {
            i += 1;
        }
        while j < m && y[j] == v {
            j += 1;
        }
        let diff = (i as i128 * m as i128 - j as i128 * n as i128).unsigned_abs();
        best = best.max(diff);
    }
    let statistic = best as f64 / (n as f64 * m as f64);
    let (p_value, method) = twosample_p(statistic, n, m);
    Ok(KsResult {
        statistic,
        p_value,
        n,
        m: Some(m),
        method,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn the_two_series_agree_where_they_meet() {
        // Jacobi's theta identity makes both forms equal everywhere; check around the switch.
        for x in [0.7, 0.9, 1.0, 1.1, 1.4] {
            let c = std::f64::consts::PI * std::f64::consts::PI / (8.0 * x * x);
            let theta: f64 = (1..50)
                .map(|k| (-((2 * k - 1) as f64).powi(2) * c).exp())
                .sum::<f64>()
                * (2.0 * std::f64::consts::PI).sqrt()
                / x;
            let alt: f64 = 1.0
                - 2.0
                    * (1..50)
                        .map(|k| {
                            let s = if k % 2 == 1 { 1.0 } else { -1.0 };
                            s * (-2.0 * (k * k) as f64 * x * x).exp()
                        })
                        .sum::<f64>();
            assert_relative_eq!(theta, alt, max_relative = 1e-13);
            assert_relative_eq!(kolmogorov_cdf(x), alt, max_relative = 1e-13);
        }
    }

    #[test]
    fn mtw_matches_the_n1_closed_form() {
        // D_1 = max(U, 1 − U): P(D_1 < d) = 2d − 1 on [½, 1].
        for d in [0.55, 0.7, 0.9] {
            assert_relative_eq!(mtw_cdf(d, 1), 2.0 * d - 1.0, max_relative = 1e-12);
        }
    }

    #[test]
    fn lattice_matches_a_hand_count() {
        // n = m = 1: interleavings "ab" and "ba" both have D = 1, so P(D < 1) = 0, P(D < 2) = 1
        // in units of 1/(nm).
        assert_eq!(lattice_inside(1, 1, 1), 0.0);
        assert_relative_eq!(lattice_inside(1, 1, 2), 1.0);
        // n = 1, m = 2: "abb" (D·nm = 2), "bab" (1), "bba" (2).
        assert_relative_eq!(lattice_inside(1, 2, 2), 1.0 / 3.0);
        assert_relative_eq!(lattice_inside(1, 2, 3), 1.0);
    }
}
