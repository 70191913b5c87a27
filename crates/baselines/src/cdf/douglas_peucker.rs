//! Douglas–Peucker simplification of a 1D CDF with the vertical (L∞) distance
//! (baselines.md §B.3), and the compressed piecewise-linear CDF it gives.

use super::linear;

/// Indices of the points of `cdf` (values at the uniform grid `x_k = k`, `k = 0..n`) that
/// Douglas–Peucker keeps with tolerance `epsilon`, in increasing order.
///
/// Between two kept points `i < j`, the interior point farthest from the chord in the
/// **vertical** distance `|C_k − (C_i + (C_j − C_i)(k − i)/(j − i))|` is kept if that distance
/// exceeds `epsilon`, and both halves are simplified in turn. Both endpoints are always kept,
/// so the piecewise-linear interpolant `C̃` of the kept points satisfies `|C̃ − C| ≤ ε` at every
/// original point (hence everywhere, both being linear in between), and it is non-decreasing
/// whenever `C` is (it interpolates a subsequence).
///
/// Fewer than two points are returned as they are.
pub fn douglas_peucker(cdf: &[f64], epsilon: f64) -> Vec<u32> {
    let n = cdf.len();
    if n < 2 {
        return (0..n as u32).collect();
    }
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j - i < 2 {
            continue;
        }
        let (ci, cj) = (cdf[i], cdf[j]);
        let step = (cj - ci) / (j - i) as f64;
        let mut far = (0.0, i);
        for (k, &c) in cdf.iter().enumerate().take(j).skip(i + 1) {
            let d = (c - (ci + step * (k - i) as f64)).abs();
            if d > far.0 {
                far = (d, k);
            }
        }
        if far.0 > epsilon {
            keep[far.1] = true;
            stack.push((far.1, j));
            stack.push((i, far.1));
        }
    }
    keep.iter()
        .enumerate()
        .filter(|k| *k.1)
        .map(|(k, _)| k as u32)
        .collect()
}

/// A CDF on the grid axis `[0, n]` compressed by [`douglas_peucker`]: the kept points
/// `(x_m, C_m)` and the piecewise-linear CDF through them (baselines.md §B.4).
///
/// Its density w.r.t. the grid coordinate is the slope of the segment containing the point;
/// sampling inverts the linear pieces. Zero-mass segments are never drawn.
///
/// ```
/// use baselines::cdf::CompressedCdf;
/// // A CDF of 4 cells with masses 0.1, 0.1, 0.4, 0.4.
/// let cdf = [0.0, 0.1, 0.2, 0.6, 1.0];
/// let c = CompressedCdf::new(&cdf, 0.01);
/// assert_eq!(c.xs(), &[0, 2, 4]); // the two linear pieces remain
/// let (t, pdf) = c.sample(0.5);
/// assert!((c.pdf(t) - pdf).abs() < 1e-15 && (pdf - 0.4).abs() < 1e-12);
/// assert!((c.cdf_at(t) - 0.5).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct CompressedCdf {
    xs: Vec<u32>,
    cs: Vec<f64>,
}

impl CompressedCdf {
    /// Simplifies `cdf` (values at `x_k = k`, `cdf[0] = 0`, last = 1, non-decreasing, at least
    /// two points) with tolerance `epsilon`.
    pub fn new(cdf: &[f64], epsilon: f64) -> Self {
        let xs = douglas_peucker(cdf, epsilon);
        let cs = xs.iter().map(|&x| cdf[x as usize]).collect();
        Self { xs, cs }
    }

    /// Grid coordinates of the kept points.
    pub fn xs(&self) -> &[u32] {
        &self.xs
    }

    /// CDF values of the kept points.
    pub fn cs(&self) -> &[f64] {
        &self.cs
    }

    /// Number of kept points.
    pub fn len(&self) -> usize {
        self.xs.len()
    }

    /// `true` when no point is kept (never for a CDF of at least two points).
    pub fn is_empty(&self) -> bool {
        self.xs.is_empty()
    }

    /// Warps `u ∈ [0, 1)` to a grid coordinate and its density (the slope of its segment).
    pub fn sample(&self, u: f64) -> (f64, f64) {
        let d = linear::draw(&self.xs, &self.cs, u);
        (d.t, d.slope)
    }

    /// Density at grid coordinate `t` (clamped to the axis).
    pub fn pdf(&self, t: f64) -> f64 {
        linear::density(&self.xs, &self.cs, t)
    }

    /// `C̃(t)`: the compressed CDF at grid coordinate `t` (the `u` that [`Self::sample`] maps
    /// to `t`, where the density is positive).
    pub fn cdf_at(&self, t: f64) -> f64 {
        linear::cdf_at(&self.xs, &self.cs, t)
    }

    /// Heap and inline bytes (4 per grid coordinate, 8 per CDF value).
    pub fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>() + self.xs.len() * 4 + self.cs.len() * 8
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A normalised CDF from non-negative masses (some exactly zero).
    fn cdf_of(masses: &[f64]) -> Vec<f64> {
        let mut cdf = vec![0.0; masses.len() + 1];
        linear::fill_cdf(masses, &mut cdf);
        cdf
    }

    fn masses() -> impl Strategy<Value = Vec<f64>> {
        prop::collection::vec(
            prop_oneof![Just(0.0), 0.0..1.0, 0.0..1e-3, 10.0..100.0],
            1..300,
        )
    }

    #[test]
    fn a_linear_cdf_keeps_only_its_endpoints_and_a_step_keeps_its_corners() {
        let lin: Vec<f64> = (0..=10).map(|k| k as f64 / 10.0).collect();
        assert_eq!(douglas_peucker(&lin, 1e-9), vec![0, 10]);
        let step = cdf_of(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        assert_eq!(douglas_peucker(&step, 1e-3), vec![0, 3, 4, 6]);
        assert_eq!(douglas_peucker(&[0.0], 0.1), vec![0]);
    }

    proptest! {
        #[test]
        fn kept_points_bound_the_error_and_stay_monotone(m in masses(), e in 1e-5f64..0.2) {
            let cdf = cdf_of(&m);
            let c = CompressedCdf::new(&cdf, e);
            let n = (cdf.len() - 1) as u32;
            prop_assert_eq!(c.xs()[0], 0);
            prop_assert_eq!(*c.xs().last().unwrap(), n);
            prop_assert!(c.xs().windows(2).all(|w| w[0] < w[1]));
            prop_assert!(c.cs().windows(2).all(|w| w[0] <= w[1]));
            for (k, &ck) in cdf.iter().enumerate() {
                let d = (c.cdf_at(k as f64) - ck).abs();
                prop_assert!(d <= e + 1e-12, "|C̃ − C| = {} > ε = {} at {}", d, e, k);
            }
            // Densities are non-negative and integrate to 1.
            let total: f64 = c.xs().windows(2).map(|w| {
                let p = c.pdf(0.5 * (f64::from(w[0]) + f64::from(w[1])));
                assert!(p >= 0.0);
                p * f64::from(w[1] - w[0])
            }).sum();
            prop_assert!((total - 1.0).abs() < 1e-12);
        }

        #[test]
        fn sample_inverts_the_cdf_and_agrees_with_pdf(
            m in masses(), e in 1e-5f64..0.2, u in 1e-6f64..1.0
        ) {
            let c = CompressedCdf::new(&cdf_of(&m), e);
            let (t, p) = c.sample(u);
            prop_assert!(t > 0.0 && t < m.len() as f64);
            prop_assert!(p > 0.0, "a zero-mass segment was drawn");
            prop_assert_eq!(c.pdf(t), p);
            prop_assert!((c.cdf_at(t) - u).abs() < 1e-9, "C̃(t) = {} ≠ u = {}", c.cdf_at(t), u);
        }
    }
}
