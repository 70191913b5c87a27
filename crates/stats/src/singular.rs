//! Breakpoints graded towards declared singular points of a density.
//!
//! Some densities have an integrable point singularity whose neighbourhood is a *wedge*: near a
//! point `(u₀, v₀)` of the parameter plane the density along the line `u = t` is a spike of
//! width `w ≈ α |t − u₀|` around `v = v₀` (and height `∝ 1/|t − u₀|`, so every line still has a
//! finite integral). The half-vector samplers' solid-angle pdf `p_h(h) / (4 |ωo·h|)` near
//! `ωi = −ωo` is one: `|ωo·h| = |ωo + ωi| / 2 → 0`. An adaptive Gauss–Legendre rule on pieces
//! that are much wider than `w` and do not have `v₀` as an end point can miss the spike
//! entirely — the coarse estimate and the two halves' sum agree (both ≈ 0) and the piece is
//! accepted — so the line integral, and with it the projection CDF, loses the spike's mass.
//!
//! The cure is a graded mesh: split at `v₀` and add breakpoints `v₀ ± d·2^{−k}`, `k = 0, 1, …`,
//! from the uniform piece width `d` down to a floor `δ`. Each piece `[v₀ + d 2^{−k−1},
//! v₀ + d 2^{−k}]` has a length comparable with its distance to `v₀`, so any spike centred at
//! `v₀` of width `w ≥ δ` is spread over `O(1)` pieces of its own size, where the Gauss rule
//! sees it and the adaptive error estimate is meaningful; and the scale-invariant shape of a
//! `1/r`-type singularity means every graded piece is equally easy (the same relative
//! variation), so the cost is `O(log(d/δ))` pieces. Below `δ` the innermost pieces are still
//! integrated (adaptively), nothing is dropped. The projection CDF grades the line integrals in
//! the other coordinate with `δ` proportional to the distance `|t − u₀|` of the line from the
//! singular point (the wedge's width scales with it). Its knots are not graded: the marginal
//! `f(t)` is at worst log-singular at `u₀` (the line through the point may have an infinite
//! integral), which its adaptive slab halving already resolves.

/// Floor of the grading as a fraction of the distance of a line from the singular point:
/// resolves wedges whose aperture `α` (width / distance) is above about `2⁻¹⁴`.
pub(crate) const LINE_FLOOR_FRACTION: f64 = 1.0 / 65_536.0;

/// Absolute floor of the grading as a fraction of the range's length (the line through the
/// singular point itself).
pub(crate) const ABSOLUTE_FLOOR_FRACTION: f64 = 1e-12;

/// Sorted breakpoints of `range`: its ends, `pieces` equal pieces, and for each `(c, δ)` in
/// `centres` (the centre `c` itself if `with_centre`) `c ± d·2^{−k}` for `d` = the equal piece width down to `δ`
/// (those strictly inside the range). A centre outside the range grades towards the nearer end
/// if it is within `d` of it (pass the shifted copies `c ± period` for a periodic axis).
pub(crate) fn graded_breaks(
    range: [f64; 2],
    pieces: usize,
    centres: &[(f64, f64)],
    with_centre: bool,
) -> Vec<f64> {
    let [a, b] = range;
    let pieces = pieces.max(1);
    let d = (b - a) / pieces as f64;
    let mut out: Vec<f64> = (0..=pieces)
        .map(|i| {
            if i == pieces {
                b
            } else {
                a + (b - a) * (i as f64 / pieces as f64)
            }
        })
        .collect();
    let floor_min = ABSOLUTE_FLOOR_FRACTION * (b - a);
    for &(c, floor) in centres {
        if !(c.is_finite() && c > a - d && c < b + d) {
            continue;
        }
        let floor = if floor.is_finite() {
            floor.max(floor_min)
        } else {
            d
        };
        if with_centre {
            out.push(c);
        }
        let mut step = d;
        while step >= floor {
            out.push(c - step);
            out.push(c + step);
            step *= 0.5;
        }
    }
    out.retain(|x| *x >= a && *x <= b);
    out.sort_by(f64::total_cmp);
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn breaks_are_sorted_inside_and_graded_towards_the_centre() {
        let br = graded_breaks([0.0, 1.0], 4, &[(0.3, 1e-3)], true);
        assert_eq!(br.first(), Some(&0.0));
        assert_eq!(br.last(), Some(&1.0));
        assert!(br.windows(2).all(|w| w[0] < w[1]));
        assert!(br.contains(&0.3));
        // The pieces next to the centre are no wider than the floor's double.
        let i = br.iter().position(|x| *x == 0.3).unwrap();
        assert!(br[i + 1] - br[i] < 2e-3 && br[i] - br[i - 1] < 2e-3);
        // Without centres: just the equal pieces.
        assert_eq!(graded_breaks([0.0, 1.0], 4, &[], true).len(), 5);
        // A centre far outside adds nothing.
        assert_eq!(graded_breaks([0.0, 1.0], 4, &[(3.0, 1e-3)], true).len(), 5);
    }
}
