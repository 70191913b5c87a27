//! Rigorous leaf bounds of an RGL material's envelope trees (issue 29, docs/benchmarks.md
//! §29.2): the image map's integrals with [`RglBrdf::f_cos_bound`]'s bound in place of the
//! sampled rule `safety_factor ×` the largest image-map sample.
//!
//! The query density of an isotropic interval `[θa, θb]` at a disc point `p` is `g(p) =
//! Y(ωo, ωi(p)) · J(p)` with `Y` the material's `f_r · cos θi` (luminance), `ωo = (sin θo, 0,
//! cos θo)` and `J = 2` on the equal-area map (`dσ = 2 dA`) or `1/cos θi` on the projected map
//! ([`crate::exact`]'s `QueryDensity`). Over a leaf rectangle `R`, the box of `ωi(R)` is
//! bounded by interval arithmetic on the map, and `sup_{R, θo} g ≤ max_k B(θ-piece k, box) ·
//! sup_R J`, with `B` the material's bound over a piece of the θo range (the range cut into
//! pieces at most [`THETA_PIECE`] wide: the half vector's box grows with the width) and the
//! rectangle cut into [`SUB_RECTS`]² parts. A rectangle touching the rim of the projected map
//! (`J` unbounded) keeps the sampled rule.

use brdf::RglBrdf;
use brdf::measured::rgl::DirectionBox;
use partition_sampler::{
    Density, DensityShape, Domain, IntegralSource, Point2, Rect, RegionEstimate, RegionStats,
};

use crate::disc::DiscMap;
use crate::image_map::SliceImageMap;

/// Widest piece of the θo range a bound is taken over (radians).
pub(crate) const THETA_PIECE: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Largest number of times a rectangle is cut in four by [`RglLeafBound::bound`].
pub(crate) const REFINE_DEPTH: u32 = 3;

/// A part is refined while its bound exceeds the image map's largest sample by this factor.
pub(crate) const REFINE_SLACK: f64 = 1.03;

/// The rigorous bound of an RGL material's query densities over an isotropic interval (see
/// the module docs): `bound(R) ≥ sup g_θo(p)` over `p ∈ R ∩ disc` and `θo ∈ [θa, θb]`.
pub(crate) struct RglLeafBound {
    rgl: RglBrdf,
    /// The pieces of the interval's θo range.
    pieces: Vec<[f64; 2]>,
    map: DiscMap,
}

impl RglLeafBound {
    /// The bound of `rgl` over `θo ∈ [ta, tb]` on `map`, with θo pieces at most `piece` wide
    /// and rectangles cut `sub × sub`.
    pub(crate) fn new(rgl: RglBrdf, ta: f64, tb: f64, map: DiscMap, piece: f64) -> Self {
        let n = (((tb - ta) / piece).ceil() as usize).clamp(1, 10_000);
        let pieces = (0..n)
            .map(|k| {
                let a = ta + (tb - ta) * k as f64 / n as f64;
                let b = if k + 1 == n {
                    tb
                } else {
                    ta + (tb - ta) * (k + 1) as f64 / n as f64
                };
                [a, b]
            })
            .collect();
        Self { rgl, pieces, map }
    }

    /// The bound over `cell ∩ disc` for every θo of the interval; `+∞` where none is known
    /// (the projected map's rim). Refined where loose: a part whose bound exceeds `target` is
    /// cut in four and bounded as the largest of its quarters' (each a bound over a subset,
    /// the smaller of the two kept), at most `depth` times — branch and bound; `target`
    /// steers the effort only, the result is a bound whatever it is.
    pub(crate) fn bound(&self, cell: &Rect, target: f64, depth: u32) -> f64 {
        self.refine([cell.x0, cell.x1], [cell.y0, cell.y1], target, depth)
    }

    fn refine(&self, x: [f64; 2], y: [f64; 2], target: f64, depth: u32) -> f64 {
        let b = self.part(x, y);
        if !(b > target) || depth == 0 || !b.is_finite() {
            return b;
        }
        let (xm, ym) = (0.5 * (x[0] + x[1]), 0.5 * (y[0] + y[1]));
        let mut quarters = 0.0f64;
        for xs in [[x[0], xm], [xm, x[1]]] {
            for ys in [[y[0], ym], [ym, y[1]]] {
                quarters = quarters.max(self.refine(xs, ys, target, depth - 1));
            }
        }
        b.min(quarters)
    }

    /// The bound over one part `x × y` of a rectangle.
    fn part(&self, x: [f64; 2], y: [f64; 2]) -> f64 {
        let Some((wi, jacobian)) = direction_box(self.map, x, y) else {
            return 0.0;
        };
        if !jacobian.is_finite() {
            return f64::INFINITY;
        }
        let b = self
            .pieces
            .iter()
            .map(|&p| self.rgl.f_cos_bound(p, &wi))
            .fold(0.0f64, f64::max);
        b * jacobian * brdf::measured::rgl::BOUND_MARGIN
    }
}

/// An interval's image map whose region bounds are [`RglLeafBound`]'s; integrals, cell sizes
/// and shape are the image map's.
pub(crate) struct RglBoundedMap<'a> {
    image: SliceImageMap<'a>,
    bound: RglLeafBound,
    depth: u32,
}

impl<'a> RglBoundedMap<'a> {
    /// `image` with the rigorous bounds of `rgl` over `θo ∈ [ta, tb]` on `map`.
    pub(crate) fn new(
        image: SliceImageMap<'a>,
        rgl: RglBrdf,
        ta: f64,
        tb: f64,
        map: DiscMap,
    ) -> Self {
        Self {
            image,
            bound: RglLeafBound::new(rgl, ta, tb, map, THETA_PIECE),
            depth: REFINE_DEPTH,
        }
    }
}

/// The box of `ωi` over the disc points of `x × y` (clipped to the closed unit disc) on `map`,
/// and the largest `dσ/dA · cos θi` factor `J` there (2 equal-area, `1/min cos θi` projected,
/// `+∞` at the rim); `None` when the part misses the open disc.
fn direction_box(map: DiscMap, x: [f64; 2], y: [f64; 2]) -> Option<(DirectionBox, f64)> {
    let pad = brdf::measured::rgl::BOUND_PAD;
    let near = |r: [f64; 2]| {
        if r[0] <= 0.0 && r[1] >= 0.0 {
            0.0
        } else {
            r[0].abs().min(r[1].abs())
        }
    };
    let far = |r: [f64; 2]| r[0].abs().max(r[1].abs());
    let r2_lo = near(x).powi(2) + near(y).powi(2);
    if !(r2_lo < 1.0) {
        return None;
    }
    let r2 = [
        (r2_lo - pad).max(0.0),
        (far(x).powi(2) + far(y).powi(2) + pad).min(1.0),
    ];
    let x = [x[0].max(-1.0) - pad, x[1].min(1.0) + pad];
    let y = [y[0].max(-1.0) - pad, y[1].min(1.0) + pad];
    match map {
        DiscMap::Projected => {
            let z = [(1.0 - r2[1]).max(0.0).sqrt(), (1.0 - r2[0]).sqrt()];
            let j = if z[0] > pad {
                1.0 / (z[0] - pad)
            } else {
                f64::INFINITY
            };
            Some((
                DirectionBox {
                    x,
                    y,
                    z: [z[0] - pad, z[1] + pad],
                },
                j,
            ))
        }
        DiscMap::EqualArea => {
            // ωi = (p s, 1 − r²) with s = √(2 − r²) ∈ [1, √2].
            let s = [(2.0 - r2[1]).sqrt() - pad, (2.0 - r2[0]).sqrt() + pad];
            let scale = |r: [f64; 2]| {
                let v = [r[0] * s[0], r[0] * s[1], r[1] * s[0], r[1] * s[1]];
                [
                    v.iter().copied().fold(f64::INFINITY, f64::min) - pad,
                    v.iter().copied().fold(f64::NEG_INFINITY, f64::max) + pad,
                ]
            };
            Some((
                DirectionBox {
                    x: scale(x),
                    y: scale(y),
                    z: [1.0 - r2[1] - pad, 1.0 - r2[0] + pad],
                },
                2.0,
            ))
        }
    }
}

impl Density for RglBoundedMap<'_> {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        self.image.eval(p)
    }
}

impl RegionStats for RglBoundedMap<'_> {
    fn domain(&self) -> Domain {
        self.image.domain()
    }

    fn region(&self, cell: &Rect) -> RegionEstimate {
        let mut est = self.image.region(cell);
        // The image map's largest sample over the cell, a value of the envelope (≤ the sup of
        // the query densities there): refine the bound while above it by more than
        // REFINE_SLACK.
        let target = self.image.largest_sample(cell) * REFINE_SLACK;
        let bound = self.bound.bound(cell, target, self.depth);
        if bound.is_finite() {
            est.max_bound = bound;
        }
        est
    }

    fn integral_source(&self) -> IntegralSource {
        self.image.integral_source()
    }

    fn total_rel_err(&self) -> Option<f64> {
        self.image.total_rel_err()
    }

    fn min_cell_size(&self) -> Option<[f64; 2]> {
        self.image.min_cell_size()
    }

    fn shape(&self) -> DensityShape {
        self.image.shape()
    }

    fn bytes_used(&self) -> usize {
        self.image.bytes_used() + 16 * self.bound.pieces.capacity()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::density::QueryDensity;
    use brdf::direction_from_radians;

    #[test]
    /// The leaf bound holds over 16 × 16 cells of the disc at four θo ranges of paper_white (13²
    /// points × 5 θo per cell); prints `Σ bound / Σ max` per range.
    fn leaf_bounds_hold_on_the_disc() {
        let Some(rgl) = crate::exact::tests::paper_white_fixture() else {
            return;
        };
        for &(a, b) in &[(0.0, 15.0), (27.67, 30.0), (59.27, 61.6), (79.02, 80.35)] {
            let (ta, tb) = (f64::to_radians(a), f64::to_radians(b));
            let lb = RglLeafBound::new(rgl.clone(), ta, tb, DiscMap::EqualArea, THETA_PIECE);
            let n = 16;
            let (mut sum_b, mut sum_m, mut worst) = (0.0, 0.0, 0.0f64);
            for j in 0..n {
                for i in 0..n {
                    let h = 2.0 / n as f64;
                    let cell = Rect::new(
                        -1.0 + h * i as f64,
                        -1.0 + h * j as f64,
                        -1.0 + h * (i + 1) as f64,
                        -1.0 + h * (j + 1) as f64,
                    );
                    let bound = lb.bound(&cell, 0.0, 1);
                    let mut m = 0.0f64;
                    for k in 0..=4 {
                        let t = ta + (tb - ta) * k as f64 / 4.0;
                        let g = QueryDensity::new(
                            &rgl,
                            direction_from_radians(t, 0.0),
                            0.0,
                            DiscMap::EqualArea,
                        );
                        for q in 0..=12 {
                            for r in 0..=12 {
                                let p =
                                    [cell.x0 + h * q as f64 / 12.0, cell.y0 + h * r as f64 / 12.0];
                                m = m.max(g.at(p));
                            }
                        }
                    }
                    if m > 0.0 {
                        sum_b += bound;
                        sum_m += m;
                        worst = worst.max(m / bound);
                    }
                }
            }
            eprintln!(
                "[{a}, {b}]: Σ bound / Σ max {:.4}, worst max/bound {worst:.4}",
                sum_b / sum_m
            );
        }
    }
}
