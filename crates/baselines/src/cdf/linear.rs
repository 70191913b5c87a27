//! Piecewise-linear CDFs on a grid axis and their inversion (shared by the uncompressed and
//! the compressed tables).
//!
//! A CDF is given by points `(x_m, C_m)`, `m = 0..k`, with grid coordinates
//! `0 = x_0 < x_1 < … < x_k = n`, `C_0 = 0`, `C_k = 1`, `C` non-decreasing, and is linear in
//! between. Its density (w.r.t. the grid coordinate) is the slope of the segment,
//! `(C_{m+1} − C_m) / (x_{m+1} − x_m)`. The uncompressed CDF has `x_m = m` (every cell edge).

use distributions::clamp_unit;

/// The normalised running sum of cell masses (a zero-mass row gets the uniform CDF,
/// baselines.md §B.5): the planar CDFs' own routine.
pub(crate) use distributions::fill_cdf;

/// The segment `m` with `C_m ≤ u < C_{m+1}` for `u ∈ [0, 1)` and the position `du ∈ [0, 1)` of
/// `u` inside it (the planar CDFs' cell search; the segment found always has positive mass).
pub(crate) use distributions::find_cell as find_segment;

/// The segment `m` with `x_m ≤ t < x_{m+1}` (clamped to the first and last segment).
#[inline]
pub(crate) fn segment_of(xs: &[u32], t: f64) -> usize {
    let k = xs.len() - 1;
    xs[1..k].partition_point(|&x| f64::from(x) <= t)
}

/// A point drawn from a piecewise-linear CDF: grid coordinate, segment and slope.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Draw {
    /// Grid coordinate `t ∈ [x_m, x_{m+1})`.
    pub(crate) t: f64,
    /// The segment `m`.
    pub(crate) segment: usize,
    /// Density w.r.t. the grid coordinate.
    pub(crate) slope: f64,
}

/// Inverts the CDF `(xs, cs)` at `u` (clamped to `[0, 1)`): `t = x_m + du (x_{m+1} − x_m)`.
/// The point is nudged to the segment's midpoint in the (probability ~10⁻¹⁶) event that
/// rounding put it outside `[x_m, x_{m+1})` or at 0, so [`segment_of`] finds the same segment
/// and `t > 0`.
#[inline]
pub(crate) fn draw(xs: &[u32], cs: &[f64], u: f64) -> Draw {
    let (m, du) = find_segment(cs, clamp_unit(u));
    let (x0, x1) = (f64::from(xs[m]), f64::from(xs[m + 1]));
    let mut t = x0 + du * (x1 - x0);
    if !(t > 0.0 && t >= x0 && t < x1) {
        t = 0.5 * (x0 + x1);
    }
    Draw {
        t,
        segment: m,
        slope: slope(xs, cs, m),
    }
}

/// [`draw`] on the uncompressed axis `x_m = m` (every cell edge kept, `xs` implicit); the
/// segment is found from `guide` ([`distributions::fill_guide`] of `cs`), which gives the
/// binary search's segment exactly.
#[inline]
pub(crate) fn draw_uniform(cs: &[f64], guide: &[u32], u: f64) -> Draw {
    let (m, du) = distributions::find_cell_guided(cs, guide, clamp_unit(u));
    let x0 = m as f64;
    let mut t = x0 + du;
    if !(t > 0.0 && t >= x0 && t < x0 + 1.0) {
        t = x0 + 0.5;
    }
    Draw {
        t,
        segment: m,
        slope: cs[m + 1] - cs[m],
    }
}

/// The cell `m` with `m ≤ t < m + 1` of an axis of `n` cells (clamped).
#[inline]
pub(crate) fn cell_of(t: f64, n: usize) -> usize {
    (t.max(0.0) as usize).min(n - 1)
}

/// Maps a drawn grid coordinate `t` to the caller's variable with `to`, and checks with
/// `locate` (the lookup `pdf` uses) that the value falls back into segment `m` and is
/// positive; otherwise returns `to` of the segment's midpoint `mid` (a ~10⁻¹⁶-probability
/// rounding event). So the pdf reported with a sample is always the one `pdf` computes.
#[inline]
pub(crate) fn settle(
    t: f64,
    m: usize,
    mid: f64,
    to: impl Fn(f64) -> f64,
    locate: impl Fn(f64) -> usize,
) -> f64 {
    let v = to(t);
    if v > 0.0 && locate(v) == m {
        v
    } else {
        to(mid)
    }
}

/// [`draw`] from the kept points `(xs, cs)`, [`settle`]d into the caller's variable: `to` maps
/// a grid coordinate to it and `from` back (the lookup `pdf` uses). Returns the value and the
/// drawn segment's density w.r.t. the grid coordinate.
#[inline]
pub(crate) fn draw_settled(
    xs: &[u32],
    cs: &[f64],
    u: f64,
    to: impl Fn(f64) -> f64,
    from: impl Fn(f64) -> f64,
) -> (f64, f64) {
    let d = draw(xs, cs, u);
    let m = d.segment;
    let mid = 0.5 * (f64::from(xs[m]) + f64::from(xs[m + 1]));
    let v = settle(d.t, m, mid, to, |v| segment_of(xs, from(v)));
    (v, d.slope)
}

/// Slope of segment `m`.
#[inline]
pub(crate) fn slope(xs: &[u32], cs: &[f64], m: usize) -> f64 {
    (cs[m + 1] - cs[m]) / f64::from(xs[m + 1] - xs[m])
}

/// Density at grid coordinate `t` (w.r.t. the grid coordinate), `t` clamped to the axis.
#[inline]
pub(crate) fn density(xs: &[u32], cs: &[f64], t: f64) -> f64 {
    slope(xs, cs, segment_of(xs, t))
}

/// `C̃(t)`, the CDF at grid coordinate `t` (linear inside a segment; 0 below, 1 above).
#[inline]
pub(crate) fn cdf_at(xs: &[u32], cs: &[f64], t: f64) -> f64 {
    let last = f64::from(xs[xs.len() - 1]);
    if !(t > 0.0) {
        return 0.0;
    }
    if t >= last {
        return 1.0;
    }
    let m = segment_of(xs, t);
    cs[m] + (t - f64::from(xs[m])) * slope(xs, cs, m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_cdf_is_normalised_and_a_zero_row_is_uniform() {
        let mut cdf = vec![0.0; 5];
        assert_eq!(fill_cdf(&[1.0, 0.0, 2.0, 1.0], &mut cdf), 4.0);
        assert_eq!(cdf, vec![0.0, 0.25, 0.25, 0.75, 1.0]);
        fill_cdf(&[0.0; 4], &mut cdf);
        assert_eq!(cdf, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    }

    #[test]
    fn draw_skips_zero_mass_segments_and_density_matches() {
        let xs = [0, 1, 2, 3, 4];
        let cs = [0.0, 0.25, 0.25, 0.75, 1.0];
        let d = draw(&xs, &cs, 0.25);
        assert_eq!(d.segment, 2);
        assert_eq!(d.t, 2.0);
        assert_eq!(density(&xs, &cs, d.t), d.slope);
        let d = draw(&xs, &cs, 1.0);
        assert_eq!(d.segment, 3);
        assert!(d.t < 4.0);
        // u = 0 would give t = 0 (the horizon for the z axis): nudged into the segment.
        let d = draw(&xs, &cs, 0.0);
        assert_eq!((d.segment, d.t), (0, 0.5));
        assert_eq!(cdf_at(&xs, &cs, 2.5), 0.5);
        assert_eq!(cdf_at(&xs, &cs, -1.0), 0.0);
        assert_eq!(cdf_at(&xs, &cs, 9.0), 1.0);
    }
}
