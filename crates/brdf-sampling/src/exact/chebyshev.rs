//! Chebyshev–Lobatto tables of a smooth function of one or two angles: the normaliser
//! `A(θo, δ) = ∫ f_r(ωo, ωi) cos θi dσ(ωi)` of one interval of the exact sampler.
//!
//! # Math
//! On `[a, b]` the `n` Chebyshev–Lobatto nodes are `t_j = (a + b)/2 + (b − a)/2 · cos(π j/(n − 1))`,
//! `j = 0 … n − 1` (both ends included). The interpolating polynomial of degree `n − 1` is
//! evaluated by the barycentric formula of the second kind,
//! `p(t) = Σ_j (w_j / (t − t_j)) v_j / Σ_j w_j / (t − t_j)` with `w_j = (−1)^j`, halved at both
//! ends (stable for any `n`). Its Chebyshev coefficients `c_k` (a type-I discrete cosine
//! transform of the values) decay geometrically for an analytic function; the interpolation error
//! is estimated by the last two, `|c_{n−1}| + |c_{n−2}|`. A two-angle table is the tensor
//! product (θ outer, δ inner).

/// The `n` Chebyshev–Lobatto nodes of `[a, b]` (`n ≥ 1`; a single node is the midpoint).
pub(crate) fn lobatto_nodes(a: f64, b: f64, n: usize) -> Vec<f64> {
    if n <= 1 || b <= a {
        return vec![0.5 * (a + b); n.max(1)];
    }
    let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
    (0..n)
        .map(|j| {
            // Exact ends: the nodes must include a and b themselves.
            if j == 0 {
                b
            } else if j == n - 1 {
                a
            } else {
                c + h * (std::f64::consts::PI * j as f64 / (n - 1) as f64).cos()
            }
        })
        .collect()
}

/// Barycentric interpolation at `t` of `values` given at `lobatto_nodes(a, b, n)`.
pub(crate) fn interpolate(nodes: &[f64], values: &[f64], t: f64) -> f64 {
    let n = nodes.len();
    if n == 1 {
        return values[0];
    }
    let (mut num, mut den) = (0.0, 0.0);
    for j in 0..n {
        let d = t - nodes[j];
        if d == 0.0 {
            return values[j];
        }
        let mut w = if j % 2 == 0 { 1.0 } else { -1.0 };
        if j == 0 || j == n - 1 {
            w *= 0.5;
        }
        let q = w / d;
        num += q * values[j];
        den += q;
    }
    num / den
}

/// `|c_{n−1}| + |c_{n−2}|` of the values at the Lobatto nodes (0 for fewer than 3 nodes, where
/// there is no tail to look at).
pub(crate) fn tail_estimate(values: &[f64]) -> f64 {
    let n = values.len();
    if n < 3 {
        return 0.0;
    }
    let m = (n - 1) as f64;
    let coeff = |k: usize| {
        let mut s = 0.0;
        for (j, v) in values.iter().enumerate() {
            let w = if j == 0 || j == n - 1 { 0.5 } else { 1.0 };
            s += w * v * (std::f64::consts::PI * (j * k) as f64 / m).cos();
        }
        let c = 2.0 * s / m;
        if k == n - 1 { 0.5 * c } else { c }
    };
    coeff(n - 1).abs() + coeff(n - 2).abs()
}

/// The Chebyshev series `p(x) = Σ_k b_k T_k(x)` of the polynomial interpolating `values` at
/// the Lobatto nodes `x_j = cos(π j/m)`, `m = n − 1` (the order of [`lobatto_nodes`], mapped
/// to `[−1, 1]`): `b_k = (2/m) Σ''_j v_j cos(π j k/m)`, halved for `k = 0` and `k = m`
/// (`Σ''`: first and last terms halved; a type-I discrete cosine transform).
pub(crate) fn chebyshev_series(values: &[f64]) -> Vec<f64> {
    let n = values.len();
    if n < 2 {
        return values.to_vec();
    }
    let m = (n - 1) as f64;
    (0..n)
        .map(|k| {
            let mut s = 0.0;
            for (j, v) in values.iter().enumerate() {
                let w = if j == 0 || j == n - 1 { 0.5 } else { 1.0 };
                s += w * v * (std::f64::consts::PI * (j * k) as f64 / m).cos();
            }
            let b = 2.0 * s / m;
            if k == 0 || k == n - 1 { 0.5 * b } else { b }
        })
        .collect()
}

/// Trailing coefficients below rounding noise dropped: while their summed magnitude stays
/// within [`TRIM_REL`] of the largest value, `|T_k| ≤ 1` bounds the change of the series by that
/// much (a constant or linear normaliser then costs one or two terms per query, not `n`).
fn trimmed(mut series: Vec<f64>, values: &[f64]) -> Vec<f64> {
    let limit = TRIM_REL * values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut dropped = 0.0;
    while series.len() > 1 {
        let last = series[series.len() - 1].abs();
        if dropped + last > limit {
            break;
        }
        dropped += last;
        series.pop();
    }
    series
}

/// Relative size of the coefficients [`trimmed`] may drop (rounding noise of the values).
const TRIM_REL: f64 = 1e-13;

/// `Σ_k b_k T_k(x)` by Clenshaw's recurrence (`2n` multiply-adds, no division).
#[inline]
pub(crate) fn clenshaw(series: &[f64], x: f64) -> f64 {
    let (mut y1, mut y2) = (0.0, 0.0);
    for &b in series.iter().skip(1).rev() {
        let y = 2.0 * x * y1 - y2 + b;
        y2 = y1;
        y1 = y;
    }
    x * y1 - y2 + series.first().copied().unwrap_or(0.0)
}

/// A tensor Chebyshev–Lobatto table over `θ ∈ [θ_a, θ_b]` × `δ ∈ [−h, h]` (one δ node when the
/// BRDF is isotropic).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChebyshevTable {
    pub(crate) theta: Vec<f64>,
    pub(crate) delta: Vec<f64>,
    /// `values[i · delta.len() + k]` at `(theta[i], delta[k])`.
    pub(crate) values: Vec<f64>,
    /// One δ node: the θ interpolant as a Chebyshev series ([`chebyshev_series`]), evaluated by
    /// Clenshaw's recurrence (the same polynomial as the barycentric formula, without its
    /// `n` divisions per query); empty otherwise.
    series: Vec<f64>,
    /// `(θ_a + θ_b)/2` and `2/(θ_b − θ_a)` (0 for a one-point interval): `x = (θ − centre)·scale`.
    centre: f64,
    scale: f64,
}

impl ChebyshevTable {
    /// The table of `values` (`values[i · delta.len() + k]` at `(theta[i], delta[k])`, nodes
    /// from [`lobatto_nodes`]).
    pub(crate) fn new(theta: Vec<f64>, delta: Vec<f64>, values: Vec<f64>) -> Self {
        let (lo, hi) = (theta[theta.len() - 1], theta[0]);
        let series = if delta.len() == 1 {
            trimmed(chebyshev_series(&values), &values)
        } else {
            Vec::new()
        };
        Self {
            series,
            centre: 0.5 * (lo + hi),
            scale: if hi > lo { 2.0 / (hi - lo) } else { 0.0 },
            theta,
            delta,
            values,
        }
    }

    /// The interpolant at `(θ, δ)` (arguments outside the box are clamped to it).
    pub(crate) fn eval(&self, theta: f64, delta: f64) -> f64 {
        let nd = self.delta.len();
        let (lo, hi) = (self.theta[self.theta.len() - 1], self.theta[0]);
        let t = theta.clamp(lo, hi);
        if nd == 1 {
            let x = ((t - self.centre) * self.scale).clamp(-1.0, 1.0);
            return clenshaw(&self.series, x);
        }
        let (dlo, dhi) = (self.delta[nd - 1], self.delta[0]);
        let d = delta.clamp(dlo, dhi);
        let mut rows = [0.0f64; 32];
        let n = self.theta.len().min(32);
        for (i, r) in rows.iter_mut().enumerate().take(n) {
            *r = interpolate(&self.delta, &self.values[i * nd..(i + 1) * nd], d);
        }
        interpolate(&self.theta[..n], &rows[..n], t)
    }

    /// Relative interpolation-error estimate: the larger of [`Self::rel_tail_theta`] and
    /// [`Self::rel_tail_delta`].
    pub(crate) fn rel_tail(&self) -> f64 {
        self.rel_tail_theta().max(self.rel_tail_delta())
    }

    fn scale(&self) -> f64 {
        self.values.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// The largest Chebyshev tail along θ (over the δ nodes), over the largest value.
    pub(crate) fn rel_tail_theta(&self) -> f64 {
        let nd = self.delta.len();
        let scale = self.scale();
        if !(scale > 0.0) {
            return 0.0;
        }
        (0..nd)
            .map(|k| {
                let col: Vec<f64> = (0..self.theta.len())
                    .map(|i| self.values[i * nd + k])
                    .collect();
                tail_estimate(&col)
            })
            .fold(0.0, f64::max)
            / scale
    }

    /// The largest Chebyshev tail along δ (over the θ nodes), over the largest value.
    pub(crate) fn rel_tail_delta(&self) -> f64 {
        let nd = self.delta.len();
        let scale = self.scale();
        if !(scale > 0.0) {
            return 0.0;
        }
        (0..self.theta.len())
            .map(|i| tail_estimate(&self.values[i * nd..(i + 1) * nd]))
            .fold(0.0, f64::max)
            / scale
    }

    /// Bytes held.
    pub(crate) fn bytes_used(&self) -> usize {
        8 * (self.theta.capacity() + self.delta.capacity() + self.values.capacity())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A linear function's series keeps two terms (the rest is rounding noise, dropped), and
    /// still interpolates; a quartic keeps its five.
    #[test]
    fn trailing_noise_coefficients_are_dropped() {
        let nodes = lobatto_nodes(0.2, 0.9, 9);
        let linear: Vec<f64> = nodes.iter().map(|t| 3.0 - 2.0 * t).collect();
        let table = ChebyshevTable::new(nodes.clone(), vec![0.0], linear);
        assert!(table.series.len() <= 2, "{:?}", table.series);
        assert!((table.eval(0.37, 0.0) - (3.0 - 2.0 * 0.37)).abs() < 1e-14);
        let quartic: Vec<f64> = nodes.iter().map(|t| 1.0 + t.powi(4)).collect();
        let table = ChebyshevTable::new(nodes, vec![0.0], quartic);
        assert_eq!(table.series.len(), 5, "{:?}", table.series);
        assert!((table.eval(0.37, 0.0) - (1.0 + 0.37f64.powi(4))).abs() < 1e-14);
    }

    #[test]
    fn nine_nodes_interpolate_a_smooth_function_to_1e9() {
        let f = |t: f64| (1.0 + t).ln() * t.cos();
        let nodes = lobatto_nodes(0.2, 0.5, 9);
        let values: Vec<f64> = nodes.iter().map(|&t| f(t)).collect();
        for k in 0..=50 {
            let t = 0.2 + 0.3 * k as f64 / 50.0;
            assert!((interpolate(&nodes, &values, t) - f(t)).abs() < 1e-9);
        }
        // The tail estimate is small for it and large for a kink.
        assert!(tail_estimate(&values) < 1e-8);
        let kinked: Vec<f64> = nodes.iter().map(|&t| (t - 0.33).abs()).collect();
        assert!(tail_estimate(&kinked) > 1e-4);
    }

    proptest! {
        /// Interpolation reproduces the values at the nodes and every polynomial of degree < n.
        #[test]
        fn reproduces_polynomials(a in -2.0f64..2.0, w in 0.01f64..3.0, n in 2usize..12,
                                  c in proptest::collection::vec(-1.0f64..1.0, 1..12),
                                  s in 0.0f64..1.0) {
            let b = a + w;
            let deg = c.len().min(n) ;
            let p = |t: f64| c[..deg].iter().rev().fold(0.0, |acc, ci| acc * t + ci);
            let nodes = lobatto_nodes(a, b, n);
            let values: Vec<f64> = nodes.iter().map(|&t| p(t)).collect();
            let t = a + s * w;
            let scale = 1.0 + values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            prop_assert!((interpolate(&nodes, &values, t) - p(t)).abs() <= 1e-8 * scale * 10f64.powi(deg as i32 / 3));
            prop_assert_eq!(interpolate(&nodes, &values, nodes[n / 2]), values[n / 2]);
        }
    }

    proptest! {
        /// The Clenshaw series of a one-angle table is the barycentric interpolant.
        #[test]
        fn series_is_the_interpolant(a in -2.0f64..2.0, w in 0.01f64..3.0, n in 1usize..18,
                                     v in proptest::collection::vec(0.1f64..10.0, 18),
                                     s in 0.0f64..1.0) {
            let nodes = lobatto_nodes(a, a + w, n);
            let values = v[..n].to_vec();
            let table = ChebyshevTable::new(nodes.clone(), vec![0.0], values.clone());
            let t = a + s * w;
            let exact = interpolate(&nodes, &values, t);
            prop_assert!((table.eval(t, 0.0) - exact).abs() <= 1e-12 * 10.0 * n as f64,
                "{} vs {}", table.eval(t, 0.0), exact);
            for (j, &x) in nodes.iter().enumerate() {
                prop_assert!((table.eval(x, 0.0) - values[j]).abs() <= 1e-12 * 10.0 * n as f64);
            }
        }
    }

    #[test]
    fn tensor_table_interpolates_both_angles() {
        let f = |t: f64, d: f64| (t.cos() + 0.3) * (1.0 + 0.2 * (2.0 * d).cos());
        let theta = lobatto_nodes(0.1, 0.4, 9);
        let delta = lobatto_nodes(-0.2, 0.2, 7);
        let values = theta
            .iter()
            .flat_map(|&t| delta.iter().map(move |&d| f(t, d)))
            .collect();
        let table = ChebyshevTable::new(theta, delta, values);
        for (t, d) in [(0.1, 0.0), (0.27, -0.13), (0.4, 0.2), (0.33, 0.05)] {
            assert!((table.eval(t, d) - f(t, d)).abs() < 1e-10, "{t} {d}");
        }
        assert!(table.rel_tail() < 1e-7);
    }
}
