//! Axis-aligned rectangles and the two sampling domains (a rectangle or the unit disc).

use serde::{Deserialize, Serialize};

use crate::contract::Point2;

/// An axis-aligned rectangle `[x0, x1] × [y0, y1]` of the plane.
///
/// A rectangle is *valid* when all four numbers are finite, `x0 < x1` and `y0 < y1`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rect {
    /// Lower x bound.
    pub x0: f64,
    /// Lower y bound.
    pub y0: f64,
    /// Upper x bound.
    pub x1: f64,
    /// Upper y bound.
    pub y1: f64,
}

impl Rect {
    /// The unit square `[0, 1]²` (image / environment-map coordinates).
    pub const UNIT: Rect = Rect {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
    };
    /// The square `[-1, 1]²` that contains the unit disc.
    pub const DISC_BOUNDS: Rect = Rect {
        x0: -1.0,
        y0: -1.0,
        x1: 1.0,
        y1: 1.0,
    };

    /// The rectangle `[x0, x1] × [y0, y1]` (not validated; see [`Rect::is_valid`]).
    pub const fn new(x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        Self { x0, y0, x1, y1 }
    }

    /// `x1 - x0`.
    #[inline]
    pub fn width(&self) -> f64 {
        self.x1 - self.x0
    }

    /// `y1 - y0`.
    #[inline]
    pub fn height(&self) -> f64 {
        self.y1 - self.y0
    }

    /// Lebesgue measure `max(0, w) · max(0, h)`.
    #[inline]
    pub fn area(&self) -> f64 {
        self.width().max(0.0) * self.height().max(0.0)
    }

    /// The centre `((x0 + x1)/2, (y0 + y1)/2)`.
    pub fn center(&self) -> Point2 {
        [0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1)]
    }

    /// The four quadrants around the centre, in the quadtree's child order (x first):
    /// `(lo, lo)`, `(hi, lo)`, `(lo, hi)`, `(hi, hi)`.
    pub fn quadrants(&self) -> [Rect; 4] {
        let [cx, cy] = self.center();
        [
            Rect::new(self.x0, self.y0, cx, cy),
            Rect::new(cx, self.y0, self.x1, cy),
            Rect::new(self.x0, cy, cx, self.y1),
            Rect::new(cx, cy, self.x1, self.y1),
        ]
    }

    /// Finite bounds with `x0 < x1` and `y0 < y1`.
    pub fn is_valid(&self) -> bool {
        self.x0.is_finite()
            && self.x1.is_finite()
            && self.y0.is_finite()
            && self.y1.is_finite()
            && self.x0 < self.x1
            && self.y0 < self.y1
    }

    /// Closed membership `x0 ≤ x ≤ x1 ∧ y0 ≤ y ≤ y1` (false for NaN coordinates).
    #[inline]
    pub fn contains(&self, p: Point2) -> bool {
        p[0] >= self.x0 && p[0] <= self.x1 && p[1] >= self.y0 && p[1] <= self.y1
    }

    /// Half-open membership `x0 ≤ x < x1 ∧ y0 ≤ y < y1` (how quadtree cells tile a domain).
    #[inline]
    pub fn contains_half_open(&self, p: Point2) -> bool {
        p[0] >= self.x0 && p[0] < self.x1 && p[1] >= self.y0 && p[1] < self.y1
    }

    /// The intersection, when it has positive area.
    pub fn intersect(&self, other: &Rect) -> Option<Rect> {
        let r = Rect {
            x0: self.x0.max(other.x0),
            y0: self.y0.max(other.y0),
            x1: self.x1.min(other.x1),
            y1: self.y1.min(other.y1),
        };
        (r.x0 < r.x1 && r.y0 < r.y1).then_some(r)
    }
}

/// The set on which a density lives and samples are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Domain {
    /// A rectangle, e.g. `[0, 1]²` for an environment map in `(u, v)` coordinates.
    Rect(Rect),
    /// The closed unit disc `x² + y² ≤ 1`, inside the square `[-1, 1]²` (the projected
    /// hemisphere: area on the disc equals projected solid angle).
    UnitDisc,
}

impl Domain {
    /// The rectangle the quadtree root covers: the rectangle itself, or `[-1, 1]²` for the disc.
    pub fn bounding_rect(&self) -> Rect {
        match self {
            Domain::Rect(r) => *r,
            Domain::UnitDisc => Rect::DISC_BOUNDS,
        }
    }

    /// Closed membership (false for NaN coordinates).
    #[inline]
    pub fn contains(&self, p: Point2) -> bool {
        match self {
            Domain::Rect(r) => r.contains(p),
            Domain::UnitDisc => p[0] * p[0] + p[1] * p[1] <= 1.0,
        }
    }

    /// `f(p)` where `p` is in the domain, else 0: the value at `p` of a density `f` restricted
    /// to the domain.
    #[inline]
    pub fn restrict(&self, p: Point2, f: impl FnOnce(Point2) -> f64) -> f64 {
        if self.contains(p) { f(p) } else { 0.0 }
    }

    /// Area of the domain (π for the disc).
    pub fn area(&self) -> f64 {
        match self {
            Domain::Rect(r) => r.area(),
            Domain::UnitDisc => std::f64::consts::PI,
        }
    }

    /// `true` when the bounding rectangle is valid (always for the disc).
    pub fn is_valid(&self) -> bool {
        match self {
            Domain::Rect(r) => r.is_valid(),
            Domain::UnitDisc => true,
        }
    }

    /// The rejection rectangle of a quadtree cell: the cell itself for a rectangular domain,
    /// the bounding box of `cell ∩ D` for the disc (seed 000, §3.8). `None` when the cell
    /// meets the domain in a set of zero area.
    pub fn rejection_rect(&self, cell: &Rect) -> Option<Rect> {
        match self {
            Domain::Rect(r) => cell.intersect(r),
            Domain::UnitDisc => disc_clip_bbox(cell),
        }
    }
}

/// Distance from 0 to the nearest point of `[a, b]`.
#[inline]
pub fn interval_min_abs(a: f64, b: f64) -> f64 {
    if a <= 0.0 && b >= 0.0 {
        0.0
    } else {
        a.abs().min(b.abs())
    }
}

/// Bounding box of `cell ∩ {x² + y² ≤ 1}`, widened outward by a few ulps (so rounding in
/// `sqrt` never cuts off part of the disc) and clipped to the cell. `None` for an empty or
/// zero-area intersection.
///
/// The x-extent is exact: `x` belongs to the projection iff `x ∈ [x0, x1]` and
/// `x² ≤ 1 − m_y²`, with `m_y` the smallest `|y|` on `[y0, y1]` (and symmetrically for y).
pub(crate) fn disc_clip_bbox(cell: &Rect) -> Option<Rect> {
    const WIDEN: f64 = 8.0 * f64::EPSILON;
    let my = interval_min_abs(cell.y0, cell.y1);
    let mx = interval_min_abs(cell.x0, cell.x1);
    let ry2 = 1.0 - my * my;
    let rx2 = 1.0 - mx * mx;
    if !(ry2 > 0.0 && rx2 > 0.0) {
        return None;
    }
    let sx = ry2.sqrt() + WIDEN;
    let sy = rx2.sqrt() + WIDEN;
    let r = Rect {
        x0: cell.x0.max(-sx),
        x1: cell.x1.min(sx),
        y0: cell.y0.max(-sy),
        y1: cell.y1.min(sy),
    };
    // The corner nearest the origin must be inside the disc for a positive-area intersection.
    if !(r.x0 < r.x1 && r.y0 < r.y1) || mx * mx + my * my >= 1.0 {
        return None;
    }
    Some(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_clip_of_corner_cell_is_shrunk() {
        let cell = Rect::new(0.5, 0.5, 1.0, 1.0);
        let r = disc_clip_bbox(&cell).unwrap();
        let s = (1.0f64 - 0.25).sqrt();
        assert!((r.x1 - s).abs() < 1e-12 && (r.y1 - s).abs() < 1e-12);
        assert_eq!(r.x0, 0.5);
        assert!(disc_clip_bbox(&Rect::new(0.8, 0.8, 1.0, 1.0)).is_none());
        let inner = Rect::new(-0.25, -0.25, 0.25, 0.25);
        assert_eq!(disc_clip_bbox(&inner), Some(inner));
    }

    #[test]
    fn rect_helpers() {
        let r = Rect::new(0.0, 0.0, 2.0, 1.0);
        assert_eq!(r.area(), 2.0);
        assert!(r.contains([2.0, 1.0]) && !r.contains_half_open([2.0, 0.5]));
        assert!(!r.contains([f64::NAN, 0.5]));
        assert!(!Rect::new(0.0, 0.0, 0.0, 1.0).is_valid());
    }

    #[test]
    fn restrict_is_zero_outside_the_domain() {
        let f = |p: Point2| 1.0 + p[0];
        assert_eq!(Domain::UnitDisc.restrict([0.5, 0.5], f), 1.5);
        assert_eq!(Domain::UnitDisc.restrict([0.9, 0.9], f), 0.0);
        assert_eq!(Domain::Rect(Rect::UNIT).restrict([1.0, 0.0], f), 2.0);
        assert_eq!(Domain::Rect(Rect::UNIT).restrict([f64::NAN, 0.5], f), 0.0);
    }

    #[test]
    fn quadrants_tile_the_rect_in_child_order() {
        let r = Rect::new(-1.0, 0.5, 3.0, 2.5);
        let q = r.quadrants();
        assert_eq!(q[0], Rect::new(-1.0, 0.5, 1.0, 1.5));
        assert_eq!(q[1], Rect::new(1.0, 0.5, 3.0, 1.5));
        assert_eq!(q[2], Rect::new(-1.0, 1.5, 1.0, 2.5));
        assert_eq!(q[3], Rect::new(1.0, 1.5, 3.0, 2.5));
        assert_eq!(q.iter().map(Rect::area).sum::<f64>(), r.area());
    }
}
