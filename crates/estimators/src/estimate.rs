//! [`Estimate`]: one estimator's result with its standard error and whether that standard
//! error can be trusted (tail share, the variance's own interval), and the running
//! [`Moments`] every estimator of this crate accumulates.

/// Largest share of the variance estimate that one sample's term may hold before the
/// estimate is flagged heavy-tailed, for `m` samples: `max(5 %, 5 ln m / m)`, the study's rule
/// (`study::dispersion::tail_threshold`): for Gaussian values the largest of `m` squared
/// deviations is about `2 ln m / m` of their sum, so the flag needs one value about 2.5× more
/// dominant than that, and never less than 5 % (the variance then rests on < 20 values).
pub fn tail_threshold(m: usize) -> f64 {
    let m = m.max(2) as f64;
    HEAVY_TAIL_SHARE.max(5.0 * m.ln() / m)
}

/// Floor of [`tail_threshold`].
pub const HEAVY_TAIL_SHARE: f64 = 0.05;

/// Relative half-width of the variance estimate's 95 % interval above which the estimate is
/// flagged heavy-tailed (the study's `UNCERTAIN_VARIANCE`): beyond it the standard error is
/// itself uncertain by more than ~25 %, so a z-score built on it is no yardstick.
pub const UNCERTAIN_VARIANCE: f64 = 0.5;

/// z-value of a two-sided 95 % normal interval.
const Z95: f64 = 1.959_963_984_540_054;

///   variance of the variance, from the sample kurtosis.
/// * [`Self::heavy_tailed`] — `tail_share > tail_threshold(N)` or
///   `variance_rel_ci95 > UNCERTAIN_VARIANCE`.
///
/// Neither can see a region that was never sampled (an estimator whose density is
/// effectively 0 where the integrand is not): that is a bias, caught only by a reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The estimator's name.
    pub estimator: String,
    /// The estimate of `L_r(ωo)`.
    pub estimate: f64,
    /// Its standard error.
    pub std_err: f64,
    /// Samples drawn.
    pub samples: usize,
    /// Wall time in seconds (sampling and evaluation; fits and sampler builds excluded).
    pub seconds: f64,
    /// Largest share of the variance estimate held by one sample (see the type's docs).
    pub tail_share: f64,
    /// Relative half-width of the variance estimate's 95 % interval (see the type's docs).
    pub variance_rel_ci95: f64,
    /// The standard error is no yardstick: `tail_share > tail_threshold(samples)` or
    /// `variance_rel_ci95 > UNCERTAIN_VARIANCE`.
    pub heavy_tailed: bool,
}

impl Estimate {
    /// Seconds per sample.
    pub fn seconds_per_sample(&self) -> f64 {
        self.seconds / self.samples.max(1) as f64
    }

    /// Variance × time, `σ²_per-sample · t_per-sample = std_err² · seconds` (lower is better).
    pub fn variance_time(&self) -> f64 {
        self.std_err * self.std_err * self.seconds
    }

    /// Why the standard error should not be trusted (`None` when it can be).
    pub fn warning(&self) -> Option<String> {
        if !self.heavy_tailed {
            return None;
        }
        let mut why = Vec::new();
        if self.tail_share > tail_threshold(self.samples) {
            why.push(format!(
                "one sample holds {:.0} % of the variance estimate",
                100.0 * self.tail_share
            ));
        }
        if self.variance_rel_ci95 > UNCERTAIN_VARIANCE {
            why.push(format!(
                "the variance's 95 % interval is ±{:.0} %",
                100.0 * self.variance_rel_ci95
            ));
        }
        Some(format!("heavy tail: {}", why.join(", ")))
    }

    /// An estimate from per-technique moments and their weights `a_t` in the variance
    /// estimate `V̂ = Σ_t a_t s²_t`; `estimate` and `samples` as given.
    pub(crate) fn from_parts(
        estimator: &str,
        estimate: f64,
        samples: usize,
        seconds: f64,
        parts: &[(&Moments, f64)],
    ) -> Self {
        let variance: f64 = parts.iter().map(|(m, a)| a * m.variance()).sum();
        let largest = parts
            .iter()
            .map(|(m, a)| a * m.largest_term())
            .fold(0.0, f64::max);
        let var_of_var: f64 = parts
            .iter()
            .map(|(m, a)| a * a * m.variance_of_variance())
            .sum();
        let (tail_share, variance_rel_ci95) = if variance > 0.0 {
            (largest / variance, Z95 * var_of_var.sqrt() / variance)
        } else {
            (0.0, 0.0)
        };
        let heavy_tailed =
            tail_share > tail_threshold(samples) || variance_rel_ci95 > UNCERTAIN_VARIANCE;
        Self {
            estimator: estimator.to_string(),
            estimate,
            std_err: variance.sqrt(),
            samples,
            seconds,
            tail_share,
            variance_rel_ci95,
            heavy_tailed,
        }
    }
}

/// Running moments of one technique's per-sample contributions: the sum (for the estimate),
/// the mean and the central moment sums `M₂ = Σ(y − ȳ)²`, `M₃`, `M₄` by the one-pass update
/// of Pébay (2008), and the extremes (the largest squared deviation is at one of them).
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct Moments {
    pub(crate) n: usize,
    pub(crate) sum: f64,
    mean: f64,
    m2: f64,
    m3: f64,
    m4: f64,
    min: f64,
    max: f64,
}

impl Moments {
    pub(crate) fn push(&mut self, y: f64) {
        let n1 = self.n as f64;
        self.n += 1;
        let n = self.n as f64;
        self.sum += y;
        let delta = y - self.mean;
        let dn = delta / n;
        let dn2 = dn * dn;
        let t = delta * dn * n1;
        self.mean += dn;
        self.m4 += t * dn2 * (n * n - 3.0 * n + 3.0) + 6.0 * dn2 * self.m2 - 4.0 * dn * self.m3;
        self.m3 += t * dn * (n - 2.0) - 3.0 * dn * self.m2;
        self.m2 += t;
        if self.n == 1 {
            (self.min, self.max) = (y, y);
        } else {
            self.min = self.min.min(y);
            self.max = self.max.max(y);
        }
    }
    pub(crate) fn mean(&self) -> f64 {
        self.sum / self.n.max(1) as f64
    }
    /// Unbiased sample variance of one contribution.
    pub(crate) fn variance(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        (self.m2 / (self.n - 1) as f64).max(0.0)
    }
    /// The largest single term `(y − ȳ)² / (n − 1)` of [`Self::variance`].
    pub(crate) fn largest_term(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        let d = (self.max - self.mean)
            .abs()
            .max((self.mean - self.min).abs());
        d * d / (self.n - 1) as f64
    }
    /// `(m₄ − m₂²)/n`, the delta-method variance of the sample variance.
    pub(crate) fn variance_of_variance(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        let n = self.n as f64;
        let (m2, m4) = (self.m2 / n, self.m4 / n);
        ((m4 - m2 * m2) / n).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_match_two_pass_formulas_and_flag_a_spike() {
        // Central moments by the one-pass update against the two-pass definitions.
        let ys: Vec<f64> = (0..1000)
            .map(|i| ((i * 37) % 101) as f64 * 0.01 + 5.0)
            .collect();
        let mut m = Moments::default();
        ys.iter().for_each(|&y| m.push(y));
        let n = ys.len() as f64;
        let mean = ys.iter().sum::<f64>() / n;
        let c = |p: i32| ys.iter().map(|y| (y - mean).powi(p)).sum::<f64>();
        assert!((m.m2 - c(2)).abs() < 1e-9 * c(2));
        assert!((m.m3 - c(3)).abs() < 1e-9 * c(2).powf(1.5));
        assert!((m.m4 - c(4)).abs() < 1e-9 * c(4));
        let largest = ys.iter().map(|y| (y - mean).powi(2)).fold(0.0, f64::max) / (n - 1.0);
        assert!((m.largest_term() - largest).abs() < 1e-12 * largest);
        let e = Estimate::from_parts("smooth", m.mean(), ys.len(), 0.0, &[(&m, 1.0 / n)]);
        assert!(!e.heavy_tailed && e.warning().is_none(), "{e:?}");
        // One value 1000× the others among 1000: it holds almost all of the variance.
        let mut spiky = Moments::default();
        (0..999).for_each(|_| spiky.push(1.0));
        spiky.push(1000.0);
        let e = Estimate::from_parts("spiky", spiky.mean(), 1000, 0.0, &[(&spiky, 1e-3)]);
        assert!(e.heavy_tailed && e.tail_share > 0.99, "{e:?}");
        assert!(e.warning().unwrap().starts_with("heavy tail"));
    }
}
