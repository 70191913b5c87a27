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

/// Barycentric interpolation at `t` of `values` given at `lobatto_nodes(a, b, n)` (the
/// tables evaluate the same polynomial by its Chebyshev series; kept as the tests' reference).
#[cfg(test)]
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

/// `Σ_k Σ_l c[k · nd + l] T_k(x) T_l(y)`: Clenshaw's recurrence along `x` (θ) for all `l`
/// at once — the `nd` recurrences side by side over contiguous rows `c[k · nd ..]`, the
/// table's own order — then along `y` (δ). The δ node counts the build makes (5, 9 and 17:
/// Lobatto-nested doublings of [`ExactOptions::DEFAULT_PHI_NORMALISER_NODES`]) are compiled
/// for their length, so the rows stay in registers with no bounds checks; other counts (at
/// most 32) take the general loop.
///
/// [`ExactOptions::DEFAULT_PHI_NORMALISER_NODES`]: super::ExactOptions::DEFAULT_PHI_NORMALISER_NODES
#[inline]
fn tensor_clenshaw(c: &[f64], nd: usize, x: f64, y: f64) -> f64 {
    match nd {
        5 => tensor_clenshaw_of::<5>(c, x, y),
        9 => tensor_clenshaw_of::<9>(c, x, y),
        17 => tensor_clenshaw_of::<17>(c, x, y),
        _ => tensor_clenshaw_any(c, nd, x, y),
    }
}

/// [`tensor_clenshaw`] for `ND` δ coefficients per θ row.
#[inline]
fn tensor_clenshaw_of<const ND: usize>(c: &[f64], x: f64, y: f64) -> f64 {
    let (rows, _) = c.as_chunks::<ND>();
    let Some((first, rest)) = rows.split_first() else {
        return 0.0;
    };
    let x2 = 2.0 * x;
    let (mut b1, mut b2) = ([0.0f64; ND], [0.0f64; ND]);
    for row in rest.iter().rev() {
        for l in 0..ND {
            let v = x2 * b1[l] - b2[l] + row[l];
            b2[l] = b1[l];
            b1[l] = v;
        }
    }
    let mut col = [0.0f64; ND];
    for l in 0..ND {
        col[l] = x * b1[l] - b2[l] + first[l];
    }
    clenshaw(&col, y)
}

/// [`tensor_clenshaw`] for any `nd` (at most 32 are read).
fn tensor_clenshaw_any(c: &[f64], nd: usize, x: f64, y: f64) -> f64 {
    const MAX: usize = 32;
    let nd = nd.clamp(1, MAX);
    let mut rows = c.chunks_exact(nd);
    let Some(first) = rows.next() else {
        return 0.0;
    };
    let x2 = 2.0 * x;
    let (mut b1, mut b2) = ([0.0f64; MAX], [0.0f64; MAX]);
    let (b1, b2) = (&mut b1[..nd], &mut b2[..nd]);
    for row in rows.rev() {
        for ((p1, p2), &r) in b1.iter_mut().zip(b2.iter_mut()).zip(row) {
            let v = x2 * *p1 - *p2 + r;
            *p2 = *p1;
            *p1 = v;
        }
    }
    let mut col = [0.0f64; MAX];
    for (((o, &p1), &p2), &r) in col.iter_mut().zip(b1.iter()).zip(b2.iter()).zip(first) {
        *o = x * p1 - p2 + r;
    }
    clenshaw(&col[..nd], y)
}

/// A tensor Chebyshev–Lobatto table over `θ ∈ [θ_a, θ_b]` × `δ ∈ [−h, h]` (one δ node when the
/// BRDF is isotropic).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChebyshevTable {
    pub(crate) theta: Vec<f64>,
    pub(crate) delta: Vec<f64>,
    /// `values[i · delta.len() + k]` at `(theta[i], delta[k])`.
    pub(crate) values: Vec<f64>,
    /// The interpolant as a Chebyshev series ([`chebyshev_series`]), evaluated by Clenshaw's
    /// recurrence (the same polynomial as the barycentric formula, without its divisions per
    /// query). One δ node: the θ series, trimmed ([`trimmed`]). Several: the tensor series,
    /// `series[k · delta.len() + l]` the coefficient of `T_k(x) T_l(y)`, untrimmed.
    series: Vec<f64>,
    /// `(θ_a + θ_b)/2` and `2/(θ_b − θ_a)` (0 for a one-point interval): `x = (θ − centre)·scale`.
    centre: f64,
    scale: f64,
    /// The same for δ: `y = (δ − delta_centre)·delta_scale`.
    delta_centre: f64,
    delta_scale: f64,
    /// One δ node: the trimmed series in the monomial basis, `p(x) = Σ_i power[i] xⁱ`, kept
    /// only where the conversion is well conditioned ([`monomial_of`]); empty otherwise.
    /// Several: the tensor series in the monomial basis, `power[i · delta.len() + j]` of
    /// `xⁱ yʲ`, on the same condition ([`tensor_monomial_of`]).
    power: Vec<f64>,
}

/// Bound on the conditioning of [`monomial_of`] accepted: `Σ_k |b_k| ‖T_k‖₁ ≤ POWER_COND ·
/// min |v|`, so Horner's rule in the monomial basis (rounding `≤ 2n ε Σ|a_i|` on `[−1, 1]`)
/// stays within ≈ `2n · 64 · ε ≈ 5·10⁻¹³` of the Chebyshev form, relative to the smallest value.
const POWER_COND: f64 = 64.0;

/// The monomial coefficients `a_i` of `Σ_k b_k T_k(x)` (`series`), or `None` when the
/// conversion would lose more than [`POWER_COND`] · ε relative to `min_abs` (the smallest
/// value the polynomial interpolates). `T_k`'s coefficients are integers, exact in `f64` for
/// the ≤ 32 terms of a table.
fn monomial_of(series: &[f64], min_abs: f64) -> Option<Vec<f64>> {
    let n = series.len();
    let mut out = vec![0.0; n];
    let (mut prev, mut cur) = (vec![0.0; n], vec![0.0; n]);
    let mut cond = 0.0;
    for (k, &b) in series.iter().enumerate() {
        // cur = T_k: T_0 = 1, T_1 = x, T_k = 2x T_{k−1} − T_{k−2}.
        let next: Vec<f64> = match k {
            0 => {
                let mut t = vec![0.0; n];
                t[0] = 1.0;
                t
            }
            1 => {
                let mut t = vec![0.0; n];
                t[1] = 1.0;
                t
            }
            _ => (0..n)
                .map(|i| if i > 0 { 2.0 * cur[i - 1] } else { 0.0 } - prev[i])
                .collect(),
        };
        prev = std::mem::replace(&mut cur, next);
        cond += b.abs() * cur.iter().map(|c| c.abs()).sum::<f64>();
        for (o, c) in out.iter_mut().zip(&cur) {
            *o += b * c;
        }
    }
    (cond <= POWER_COND * min_abs).then_some(out)
}

/// The monomial coefficients of `T_0 … T_{n−1}`: row `k` holds `T_k`'s (integers, exact in
/// `f64` for `n ≤ 32`).
fn chebyshev_monomials(n: usize) -> Vec<Vec<f64>> {
    let mut t: Vec<Vec<f64>> = Vec::with_capacity(n);
    for k in 0..n {
        let mut row = vec![0.0; n];
        match k {
            0 => row[0] = 1.0,
            1 => row[1] = 1.0,
            _ => {
                for (i, r) in row.iter_mut().enumerate() {
                    let up = if i > 0 { 2.0 * t[k - 1][i - 1] } else { 0.0 };
                    *r = up - t[k - 2][i];
                }
            }
        }
        t.push(row);
    }
    t
}

/// The monomial coefficients `a[i · nd + j]` (of `xⁱ yʲ`) of the tensor series `series`
/// (`series[k · nd + l]` of `T_k(x) T_l(y)`), or `None` when the conversion would lose more
/// than [`POWER_COND`] · ε relative to `min_abs`: `Σ_{k,l} |b_kl| ‖T_k‖₁ ‖T_l‖₁` bounds
/// `Σ |a_ij|`, hence Horner's rounding on `[−1, 1]²`, as [`monomial_of`]'s criterion does for one
/// variable (issue 29: two Horner passes cost fewer operations per coefficient than the
/// tensor Clenshaw recurrence).
fn tensor_monomial_of(series: &[f64], nd: usize, min_abs: f64) -> Option<Vec<f64>> {
    let nt = series.len() / nd;
    let (tx, ty) = (chebyshev_monomials(nt), chebyshev_monomials(nd));
    let norm = |row: &Vec<f64>| row.iter().map(|c| c.abs()).sum::<f64>();
    let (nx, ny): (Vec<f64>, Vec<f64>) =
        (tx.iter().map(norm).collect(), ty.iter().map(norm).collect());
    let mut cond = 0.0;
    for k in 0..nt {
        for l in 0..nd {
            cond += series[k * nd + l].abs() * nx[k] * ny[l];
        }
    }
    if !(cond <= POWER_COND * min_abs) {
        return None;
    }
    Some(tensor_monomial(series, nd))
}

/// The monomial coefficients `a[i · nd + j]` (of `xⁱ yʲ`) of the tensor series `series`
/// (`series[k · nd + l]` of `T_k(x) T_l(y)`), whatever the conditioning (the caller checks the
/// result: the anisotropic records' bicubic patches, `aniso_record.rs`).
pub(super) fn tensor_monomial(series: &[f64], nd: usize) -> Vec<f64> {
    let nt = series.len() / nd;
    let (tx, ty) = (chebyshev_monomials(nt), chebyshev_monomials(nd));
    // Along y for every θ coefficient k, then along x.
    let mut half = vec![0.0; nt * nd];
    for k in 0..nt {
        for (l, tl) in ty.iter().enumerate() {
            let b = series[k * nd + l];
            for (j, &c) in tl.iter().enumerate() {
                half[k * nd + j] += b * c;
            }
        }
    }
    let mut out = vec![0.0; nt * nd];
    for (k, tk) in tx.iter().enumerate() {
        for (i, &c) in tk.iter().enumerate() {
            for j in 0..nd {
                out[i * nd + j] += c * half[k * nd + j];
            }
        }
    }
    out
}

/// `Σ_i Σ_j a[i · nd + j] xⁱ yʲ`: Horner's rule along `x` for all `j` side by side over the
/// contiguous rows, then along `y`; the δ node counts the build makes (5, 9, 17) compiled for
/// their length, as [`tensor_clenshaw`].
#[inline]
fn tensor_horner(a: &[f64], nd: usize, x: f64, y: f64) -> f64 {
    match nd {
        5 => tensor_horner_of::<5>(a, x, y),
        9 => tensor_horner_of::<9>(a, x, y),
        17 => tensor_horner_of::<17>(a, x, y),
        _ => tensor_horner_any(a, nd, x, y),
    }
}

/// [`tensor_horner`] for `ND` δ coefficients per θ row.
#[inline]
fn tensor_horner_of<const ND: usize>(a: &[f64], x: f64, y: f64) -> f64 {
    let (rows, _) = a.as_chunks::<ND>();
    let mut acc = [0.0f64; ND];
    for row in rows.iter().rev() {
        for l in 0..ND {
            acc[l] = acc[l] * x + row[l];
        }
    }
    acc.iter().rev().fold(0.0, |s, &c| s * y + c)
}

/// [`tensor_horner`] for any `nd` (at most 32 are read).
fn tensor_horner_any(a: &[f64], nd: usize, x: f64, y: f64) -> f64 {
    const MAX: usize = 32;
    let nd = nd.clamp(1, MAX);
    let mut acc = [0.0f64; MAX];
    let acc = &mut acc[..nd];
    for row in a.chunks_exact(nd).rev() {
        for (s, &r) in acc.iter_mut().zip(row) {
            *s = *s * x + r;
        }
    }
    acc.iter().rev().fold(0.0, |s, &c| s * y + c)
}

/// The tensor Chebyshev series of `values` (`values[i · nd + k]` at the Lobatto nodes `i` of
/// θ and `k` of δ): [`chebyshev_series`] along δ for every θ node, then along θ for every δ
/// coefficient; `out[k · nd + l]` multiplies `T_k(x) T_l(y)`.
pub(super) fn tensor_series(values: &[f64], nd: usize) -> Vec<f64> {
    let nt = values.len() / nd;
    let rows: Vec<Vec<f64>> = (0..nt)
        .map(|i| chebyshev_series(&values[i * nd..(i + 1) * nd]))
        .collect();
    let mut out = vec![0.0; nt * nd];
    for l in 0..nd {
        let col: Vec<f64> = rows.iter().map(|r| r[l]).collect();
        for (k, c) in chebyshev_series(&col).into_iter().enumerate() {
            out[k * nd + l] = c;
        }
    }
    out
}

impl ChebyshevTable {
    /// The table of `values` (`values[i · delta.len() + k]` at `(theta[i], delta[k])`, nodes
    /// from [`lobatto_nodes`]).
    pub(crate) fn new(theta: Vec<f64>, delta: Vec<f64>, values: Vec<f64>) -> Self {
        let (lo, hi) = (theta[theta.len() - 1], theta[0]);
        let (dlo, dhi) = (delta[delta.len() - 1], delta[0]);
        let series = if delta.len() == 1 {
            trimmed(chebyshev_series(&values), &values)
        } else {
            tensor_series(&values, delta.len())
        };
        let min_abs = values.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()));
        let power = if delta.len() == 1 {
            monomial_of(&series, min_abs)
        } else {
            tensor_monomial_of(&series, delta.len(), min_abs)
        }
        .unwrap_or_default();
        Self {
            power,
            series,
            centre: 0.5 * (lo + hi),
            scale: if hi > lo { 2.0 / (hi - lo) } else { 0.0 },
            delta_centre: 0.5 * (dlo + dhi),
            delta_scale: if dhi > dlo { 2.0 / (dhi - dlo) } else { 0.0 },
            theta,
            delta,
            values,
        }
    }

    /// A one-variable table as `(lo, hi, centre, scale, power)` when its monomial form
    /// ([`Self::power`]) was kept and has at most `N` coefficients (padded with zeros, which
    /// [`Self::eval`]'s Horner loop never reads): `eval(t, _)` is then
    /// `power[..len]` by Horner's rule at `x = ((t − centre) · scale).clamp(−1, 1)`, and
    /// `[lo, hi]` the node range. `None` for tensor tables, Clenshaw's form or longer series.
    pub(crate) fn inline_power<const N: usize>(&self) -> Option<([f64; 4], [f64; N], usize)> {
        let n = self.power.len();
        if self.delta.len() != 1 || n == 0 || n > N {
            return None;
        }
        let mut power = [0.0; N];
        power[..n].copy_from_slice(&self.power);
        let range = [self.theta[self.theta.len() - 1], self.theta[0]];
        Some(([range[0], range[1], self.centre, self.scale], power, n))
    }

    /// The interpolant at `(θ, δ)` (arguments outside the box are clamped to it). One δ node:
    /// Horner's rule on [`Self::power`] when it was kept, else Clenshaw's recurrence; a tensor
    /// table: [`tensor_horner`] on [`Self::power`] when it was kept, else [`tensor_clenshaw`],
    /// out of line.
    #[inline]
    pub(crate) fn eval(&self, theta: f64, delta: f64) -> f64 {
        let x = ((theta - self.centre) * self.scale).clamp(-1.0, 1.0);
        if self.delta.len() == 1 {
            if !self.power.is_empty() {
                return self.power.iter().rev().fold(0.0, |acc, &a| acc * x + a);
            }
            return clenshaw(&self.series, x);
        }
        self.eval_tensor(x, delta)
    }

    #[inline(never)]
    fn eval_tensor(&self, x: f64, delta: f64) -> f64 {
        let y = ((delta - self.delta_centre) * self.delta_scale).clamp(-1.0, 1.0);
        if !self.power.is_empty() {
            return tensor_horner(&self.power, self.delta.len(), x, y);
        }
        tensor_clenshaw(&self.series, self.delta.len(), x, y)
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
        8 * (self.theta.capacity()
            + self.delta.capacity()
            + self.values.capacity()
            + self.series.capacity()
            + self.power.capacity())
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

    /// A smooth normaliser-like table takes the monomial (Horner) path and agrees with the
    /// Chebyshev form and with the barycentric interpolant to 1e-13 relative; a table of wild
    /// values keeps the Chebyshev form.
    #[test]
    fn monomial_form_is_the_same_polynomial_where_kept() {
        let f = |c: f64| (0.3 + c).powf(1.7) * (1.0 + 0.2 * c * c);
        let nodes = lobatto_nodes(0.05, 0.9, 9);
        let values: Vec<f64> = nodes.iter().map(|&c| f(c)).collect();
        let table = ChebyshevTable::new(nodes.clone(), vec![0.0], values.clone());
        assert!(!table.power.is_empty(), "smooth table: monomial form kept");
        for k in 0..=200 {
            let t = 0.05 + 0.85 * k as f64 / 200.0;
            let x = ((t - table.centre) * table.scale).clamp(-1.0, 1.0);
            let (horner, cheb) = (table.eval(t, 0.0), clenshaw(&table.series, x));
            assert!(
                (horner - cheb).abs() <= 1e-13 * cheb.abs(),
                "{t}: {horner} vs {cheb}"
            );
            let bary = interpolate(&nodes, &values, t);
            assert!(
                (horner - bary).abs() <= 1e-13 * bary.abs(),
                "{t}: {horner} vs {bary}"
            );
        }
        let wild: Vec<f64> = (0..17)
            .map(|j| if j % 2 == 0 { 10.0 } else { 0.1 })
            .collect();
        let table = ChebyshevTable::new(lobatto_nodes(0.0, 1.0, 17), vec![0.0], wild);
        assert!(
            table.power.is_empty(),
            "ill-conditioned: Chebyshev form kept"
        );
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

    proptest! {
        /// The tensor series of a two-angle table is the tensor barycentric interpolant (δ rows
        /// first, then θ) at any point of the box, and the value at every node.
        #[test]
        fn tensor_series_is_the_tensor_interpolant(a in -1.0f64..1.0, w in 0.01f64..2.0,
                                                   h in 0.01f64..1.0,
                                                   nt in 2usize..12, nd in 2usize..19,
                                                   v in proptest::collection::vec(0.1f64..10.0, 12 * 18),
                                                   s in 0.0f64..1.0, r in 0.0f64..1.0) {
            let theta = lobatto_nodes(a, a + w, nt);
            let delta = lobatto_nodes(-h, h, nd);
            let values = v[..nt * nd].to_vec();
            let table = ChebyshevTable::new(theta.clone(), delta.clone(), values.clone());
            let reference = |t: f64, d: f64| {
                let rows: Vec<f64> = (0..nt)
                    .map(|i| interpolate(&delta, &values[i * nd..(i + 1) * nd], d))
                    .collect();
                interpolate(&theta, &rows, t)
            };
            let (t, d) = (a + s * w, -h + 2.0 * h * r);
            let tol = 1e-12 * 10.0 * (nt * nd) as f64;
            prop_assert!((table.eval(t, d) - reference(t, d)).abs() <= tol,
                "{} vs {}", table.eval(t, d), reference(t, d));
            for (i, &ti) in theta.iter().enumerate() {
                for (k, &dk) in delta.iter().enumerate() {
                    prop_assert!((table.eval(ti, dk) - values[i * nd + k]).abs() <= tol);
                }
            }
        }
    }

    /// The δ lengths compiled for their size (5, 9, 17) do the general loop's arithmetic in
    /// its order: the same bits.
    #[test]
    fn compiled_delta_lengths_are_the_general_loop() {
        for nd in [5, 9, 17] {
            for nt in [1, 2, 9, 13] {
                let c: Vec<f64> = (0..nt * nd)
                    .map(|i| ((i * 7919 % 97) as f64 - 48.0) / (1.0 + i as f64))
                    .collect();
                for (x, y) in [(-1.0, -1.0), (0.3, -0.7), (1.0, 1.0), (-0.2, 0.9)] {
                    let (a, b) = (
                        tensor_clenshaw(&c, nd, x, y),
                        tensor_clenshaw_any(&c, nd, x, y),
                    );
                    assert_eq!(a.to_bits(), b.to_bits(), "{nd} {nt} {x} {y}: {a} vs {b}");
                }
            }
        }
    }

    /// A smooth normaliser-like tensor table (9 θ × 5, 9 and 7 δ nodes) takes the monomial
    /// (Horner) path and agrees with the tensor Clenshaw form and the tensor barycentric
    /// interpolant to 1e-13 relative over its box; a table of wild values keeps the Chebyshev
    /// form. The compiled δ lengths are the general loop, bit for bit.
    #[test]
    fn tensor_monomial_form_is_the_same_polynomial_where_kept() {
        let f = |t: f64, d: f64| (0.3 + t.cos()).powf(1.7) * (1.0 + 0.2 * (2.0 * d + 0.3).cos());
        for nd in [5, 7, 9] {
            let theta = lobatto_nodes(0.1, 0.6, 9);
            let delta = lobatto_nodes(-0.2, 0.2, nd);
            let values: Vec<f64> = theta
                .iter()
                .flat_map(|&t| delta.iter().map(move |&d| f(t, d)))
                .collect();
            let table = ChebyshevTable::new(theta.clone(), delta.clone(), values.clone());
            assert_eq!(
                table.power.len(),
                9 * nd,
                "smooth table: monomial form kept"
            );
            for k in 0..=40 {
                for m in 0..=10 {
                    let (t, d) = (0.1 + 0.5 * k as f64 / 40.0, -0.2 + 0.4 * m as f64 / 10.0);
                    let x = ((t - table.centre) * table.scale).clamp(-1.0, 1.0);
                    let y = ((d - table.delta_centre) * table.delta_scale).clamp(-1.0, 1.0);
                    let (horner, cheb) =
                        (table.eval(t, d), tensor_clenshaw(&table.series, nd, x, y));
                    assert!(
                        (horner - cheb).abs() <= 1e-13 * cheb.abs(),
                        "{t} {d}: {horner} vs {cheb}"
                    );
                    let rows: Vec<f64> = (0..9)
                        .map(|i| interpolate(&delta, &values[i * nd..(i + 1) * nd], d))
                        .collect();
                    let bary = interpolate(&theta, &rows, t);
                    assert!(
                        (horner - bary).abs() <= 1e-13 * bary.abs(),
                        "{t} {d}: {horner} vs {bary}"
                    );
                    assert_eq!(
                        tensor_horner(&table.power, nd, x, y).to_bits(),
                        tensor_horner_any(&table.power, nd, x, y).to_bits()
                    );
                }
            }
        }
        let wild: Vec<f64> = (0..9 * 5)
            .map(|j| if j % 2 == 0 { 10.0 } else { 0.1 })
            .collect();
        let table = ChebyshevTable::new(
            lobatto_nodes(0.0, 1.0, 9),
            lobatto_nodes(-0.2, 0.2, 5),
            wild,
        );
        assert!(
            table.power.is_empty(),
            "ill-conditioned: Chebyshev form kept"
        );
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
