//! Compact leaf storage (32 bytes per leaf): the rejection rectangle in `f32` coordinates
//! (root-normalised, or the domain's own for dyadic roots; see [`Frame`]), the bound as an
//! `f32` times a per-tree power of two, and the alias entry.
//!
//! **Exactness.** The envelope scheme proposes a point uniformly in the rejection rectangle
//! `r_i` of a leaf chosen ∝ `area(r_i) · M_i` and accepts it with probability `f(x) / M_i`,
//! so a point `x` is proposed with density `Σ_{i : x ∈ r_i} M_i / Σ_j V_j`. The accepted
//! density is `f / ∫ f` exactly iff every point of the support lies in **exactly one** stored
//! rectangle (no two rectangles overlap in a set of positive area, and their union covers
//! `supp f ∩ D`) and every stored `M_i ≥ f` on its rectangle. The encoding below keeps all
//! three: each stored rectangle contains `cell ∩ D` (edges rounded outward) and lies inside
//! its own cell (edges clamped to the cell's, which are exact), and `M_i` is rounded up.
//! The alias weights are computed from the *stored* values ([`Leaf::area`], [`Leaf::bound`])
//! so that they are exactly the weights the sampler realises.

use serde::{Deserialize, Serialize};

use crate::rect::Rect;

/// Deepest level whose cell edges `k · 2^-d` (`0 ≤ k ≤ 2^d`) are all exact in `f32`.
pub(crate) const MAX_F32_EXACT_DEPTH: u32 = 24;

// Every cell edge must be exact in f32: the builder cannot go deeper than 24 levels.
const _: () = assert!(crate::limits::MAX_DEPTH_LIMIT <= MAX_F32_EXACT_DEPTH);

/// The affine map `x = origin + u · extent` (per axis, in `f64`) from stored leaf
/// coordinates to the domain; a function of the root rectangle only.
///
/// * In general the stored coordinates are root-normalised, `u = (x − root.x0) / root.width()`:
///   cell edges `k · 2^-d` (`d ≤ 24`) are exact in `f32`, and `origin + (k · 2^-d) · W`
///   reproduces the `f64` cell edges of `tree::cell_rect` bit for bit (both round the same
///   exact product once).
/// * Roots whose cell edges are themselves exact in `f32` — on both axes a power-of-two width
///   `W` with `x0 ∈ {0, −W/2}`, e.g. `[0, 1]²` (environment maps, where this *is* the
///   normalisation) and `[−1, 1]²` (the disc) — store domain coordinates: the frame is the
///   identity and the sampler skips the map (a measurable saving on the hot path).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Frame {
    /// Image of stored `(0, 0)`.
    pub(crate) origin: [f64; 2],
    /// Scale per axis.
    pub(crate) extent: [f64; 2],
}

impl Frame {
    /// The frame of a tree with root `root`.
    pub(crate) fn of_root(root: &Rect) -> Frame {
        let dyadic = |x0: f64, w: f64| {
            (2f64.powi(-100)..=2f64.powi(100)).contains(&w)
                && w == pow2_floor(w)
                && (x0 == 0.0 || x0 == -0.5 * w)
        };
        if dyadic(root.x0, root.width()) && dyadic(root.y0, root.height()) {
            Frame {
                origin: [0.0; 2],
                extent: [1.0; 2],
            }
        } else {
            Frame {
                origin: [root.x0, root.y0],
                extent: [root.width(), root.height()],
            }
        }
    }

    /// `origin = 0`, `extent = 1`: stored coordinates are domain coordinates.
    pub(crate) fn is_identity(&self) -> bool {
        self.origin == [0.0; 2] && self.extent == [1.0; 2]
    }

    /// Domain coordinate of stored coordinate `u` on `axis`: the sampler's arithmetic.
    #[inline(always)]
    pub(crate) fn domain_coord(&self, axis: usize, u: f64) -> f64 {
        self.origin[axis] + u * self.extent[axis]
    }

    /// The root in stored coordinates (`[0, 1]²`, or the root itself for the identity).
    pub(crate) fn stored_root(&self, root: &Rect) -> Rect {
        if self.is_identity() {
            *root
        } else {
            Rect::UNIT
        }
    }

    /// Stored edges of cell `i` at depth `d` on a root axis `[x0, x0 + w]`: `[i, i + 1] · 2^-d`
    /// normalised, or the cell's domain edges (computed as `tree::cell_rect` does) for the
    /// identity. Exact in `f32` for `d ≤ 24`.
    pub(crate) fn cell_edges(&self, x0: f64, w: f64, d: u32, i: u64) -> [f64; 2] {
        let step = 0.5f64.powi(d as i32);
        if self.is_identity() {
            let s = w * step;
            [x0 + i as f64 * s, x0 + (i + 1) as f64 * s]
        } else {
            [i as f64 * step, (i + 1) as f64 * step]
        }
    }
}

/// One sampleable leaf.
///
/// The rejection rectangle is `[u0, u0 + du] × [v0, v0 + dv]` in stored coordinates, mapped
/// to the domain by the tree's [`Frame`] in `f64`; `u0 + du` and `v0 + dv` are exact in
/// `f32`. Aligned to 32 bytes so a leaf never straddles a cache line.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[repr(C, align(32))]
pub(crate) struct Leaf {
    /// Lower x edge (stored coordinates).
    pub(crate) u0: f32,
    /// Lower y edge.
    pub(crate) v0: f32,
    /// Width (> 0).
    pub(crate) du: f32,
    /// Height (> 0).
    pub(crate) dv: f32,
    /// `M_i / bound_scale`, rounded up (see [`Leaf::bound`]).
    pub(crate) m: f32,
    /// Alias target.
    pub(crate) alias: u32,
    /// Alias threshold (kept in `f64`: the alias probabilities must match the weights).
    pub(crate) prob: f64,
}

impl Leaf {
    /// The bound `M_i` the sampler uses: `m · bound_scale`.
    #[inline(always)]
    pub(crate) fn bound(&self, bound_scale: f64) -> f64 {
        f64::from(self.m) * bound_scale
    }

    /// Area of the rejection rectangle in domain units, `(du · W) · (dv · H)` with
    /// `extent = [W, H]` the frame's scale: the Jacobian of the sampler's map.
    #[inline]
    pub(crate) fn area(&self, extent: [f64; 2]) -> f64 {
        (f64::from(self.du) * extent[0]) * (f64::from(self.dv) * extent[1])
    }

    /// `V_i = area · M_i` from the stored values.
    #[inline]
    pub(crate) fn volume(&self, extent: [f64; 2], bound_scale: f64) -> f64 {
        self.area(extent) * self.bound(bound_scale)
    }

    /// The rejection rectangle in stored coordinates, `[u0, u0 + du] × [v0, v0 + dv]`.
    pub(crate) fn stored_rect(&self) -> Rect {
        let (u0, v0) = (f64::from(self.u0), f64::from(self.v0));
        Rect {
            x0: u0,
            y0: v0,
            x1: u0 + f64::from(self.du),
            y1: v0 + f64::from(self.dv),
        }
    }

    /// The rejection rectangle in domain coordinates (the images of its stored corners).
    pub(crate) fn rect(&self, frame: &Frame) -> Rect {
        let r = self.stored_rect();
        Rect {
            x0: frame.domain_coord(0, r.x0),
            y0: frame.domain_coord(1, r.y0),
            x1: frame.domain_coord(0, r.x1),
            y1: frame.domain_coord(1, r.y1),
        }
    }

    /// Structural soundness: finite fields, positive extent and bound, rectangle inside
    /// `bounds` (the root in stored coordinates), alias target in range.
    pub(crate) fn is_sound(&self, n_leaves: usize, bound_scale: f64, bounds: &Rect) -> bool {
        let r = self.stored_rect();
        r.x0 >= bounds.x0
            && r.y0 >= bounds.y0
            && self.du > 0.0
            && self.dv > 0.0
            && r.x1 <= bounds.x1
            && r.y1 <= bounds.y1
            && self.m.is_finite()
            && self.m > 0.0
            && self.bound(bound_scale).is_finite()
            && (0.0..=1.0).contains(&self.prob)
            && (self.alias as usize) < n_leaves
    }
}

/// Encodes one axis of a rejection interval `[lo, hi]` (domain units) whose cell has the
/// stored edges `[c0, c1]` ([`Frame::cell_edges`], exact in `f32`) as `(a, da)`: the stored
/// interval `[a, a + da]`, with `a`, `da` and `a + da` exact in `f32`, whose image under
/// `u ↦ origin + u · extent` contains `[lo, hi]` (edges rounded outward) and which lies in
/// `[c0, c1]` (edges clamped to the cell's). Falls back to the whole cell when rounding leaves
/// no such interval. `[lo, hi]` must lie in the cell, as rejection rectangles do.
pub(crate) fn encode_axis(
    lo: f64,
    hi: f64,
    [c0, c1]: [f64; 2],
    origin: f64,
    extent: f64,
) -> (f32, f32) {
    let cell = (c0 as f32, (c1 - c0) as f32);
    if origin + c0 * extent == lo && origin + c1 * extent == hi {
        // The whole cell (most leaves): its edges map to `[lo, hi]` exactly.
        return cell;
    }
    if c0 >= 0.0 {
        encode_nonneg(lo, hi, [c0, c1], origin, extent).unwrap_or(cell)
    } else if c1 <= 0.0 {
        // A cell left of 0 (identity frame of a root `[−W/2, W/2]`): encode the mirror image
        // `[−hi, −lo]` in the mirrored cell `[−c1, −c0]` under the mirrored map
        // `u ↦ −origin + u · extent`, then mirror back (exact).
        encode_nonneg(-hi, -lo, [-c1, -c0], -origin, extent).map_or(cell, |(a, da)| (-(a + da), da))
    } else {
        // Only the root cell of such a frame straddles 0.
        cell
    }
}

/// [`encode_axis`] for a cell with `0 ≤ c0 < c1` and `c0 = 0` or `c0 ≥ c1 / 2` (dyadic edges
/// `j · s`, `(j + 1) · s`).
fn encode_nonneg(
    lo: f64,
    hi: f64,
    [c0, c1]: [f64; 2],
    origin: f64,
    extent: f64,
) -> Option<(f32, f32)> {
    let at = |u: f64| origin + u * extent;
    // Upper edge: the nearest f32, nudged up until its image reaches `hi`, at most the cell's.
    let mut u1 = ((hi - origin) / extent) as f32;
    for _ in 0..4 {
        if f64::from(u1) >= c1 || at(f64::from(u1)) >= hi {
            break;
        }
        u1 = u1.next_up();
    }
    let u1 = f64::from(u1).min(c1);
    let u1_32 = u1 as f32;
    // Lower edge: a multiple of the f32 spacing `g` at `u1` (so `u1 − u0 < 2^24 g` is exact in
    // f32), rounded down and nudged down until its image reaches `lo`, at least the cell's.
    // When it is clamped to `c0 < u1 / 2`, `c0 = 0`, so `u1 − c0 = u1` is exact too.
    let g = f64::from(u1_32.next_up() - u1_32);
    let mut u0 = (((lo - origin) / extent) / g).floor() * g;
    for _ in 0..4 {
        if u0 <= c0 || at(u0) <= lo {
            break;
        }
        u0 -= g;
    }
    let u0 = u0.max(c0);
    let (a, da) = (u0 as f32, (u1 - u0) as f32);
    let exact = f64::from(a) == u0 && f64::from(a) + f64::from(da) == u1;
    (exact && u0 < u1 && at(u0) <= lo && at(u1) >= hi).then_some((a, da))
}

/// `m / scale` rounded up to an `f32` `q` with `q · scale ≥ m` (computed as the sampler does).
/// `scale` must be a positive power of two with `m / scale ≤ 2`.
pub(crate) fn encode_bound(m: f64, scale: f64) -> f32 {
    let mut q = (m / scale) as f32;
    for _ in 0..4 {
        if f64::from(q) * scale >= m {
            return q;
        }
        q = q.next_up();
    }
    f32::MAX
}

/// The largest power of two `≤ x`, for finite `x > 0`.
pub(crate) fn pow2_floor(x: f64) -> f64 {
    let bits = x.to_bits();
    if x >= f64::MIN_POSITIVE {
        // Keep sign (0) and exponent, clear the mantissa.
        f64::from_bits(bits & 0xFFF0_0000_0000_0000)
    } else {
        // Subnormal: the highest set mantissa bit.
        f64::from_bits(1u64 << (63 - bits.leading_zeros()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_32_bytes() {
        assert_eq!(std::mem::size_of::<Leaf>(), 32);
        assert_eq!(std::mem::align_of::<Leaf>(), 32);
    }

    #[test]
    fn pow2_floor_cases() {
        assert_eq!(pow2_floor(1.0), 1.0);
        assert_eq!(pow2_floor(3.9), 2.0);
        assert_eq!(pow2_floor(0.3), 0.25);
        assert_eq!(pow2_floor(f64::MAX), 2f64.powi(1023));
        assert_eq!(pow2_floor(3e-320), f64::from_bits(1 << 12));
        assert_eq!(pow2_floor(f64::from_bits(1)), f64::from_bits(1));
    }

    #[test]
    fn bounds_round_up() {
        for &m in &[1.0, 0.1, 1.0 + 1e-12, 1e-300, 7.3e-42, 1e300] {
            let s = pow2_floor(m);
            let q = encode_bound(m, s);
            assert!(f64::from(q) * s >= m, "{m}");
            assert!(f64::from(q) * s <= m * (1.0 + 1.2e-7), "{m}");
        }
        // Far below the scale: rounded up to the smallest f32, still a bound.
        let q = encode_bound(1e-100, 1.0);
        assert!(q > 0.0 && f64::from(q) >= 1e-100);
    }

    #[test]
    fn frames_reproduce_cell_edges() {
        assert!(Frame::of_root(&Rect::UNIT).is_identity());
        assert!(Frame::of_root(&Rect::DISC_BOUNDS).is_identity());
        assert!(Frame::of_root(&Rect::new(-2.0, 0.0, 2.0, 0.5)).is_identity());
        for root in [
            Rect::new(0.1, -0.3, 0.4, 2.0),
            Rect::DISC_BOUNDS,
            Rect::new(-2.0, 0.0, 2.0, 0.5),
        ] {
            let f = Frame::of_root(&root);
            assert_eq!(f.is_identity(), root.x0 != 0.1);
            for (d, i) in [
                (0, 0),
                (3, 5),
                (24, (1 << 24) - 1),
                (17, 12345),
                (24, 1 << 23),
            ] {
                let c = crate::tree::cell_rect(&root, d, i, i);
                let [a, b] = f.cell_edges(root.x0, root.width(), d, i);
                let [p, q] = f.cell_edges(root.y0, root.height(), d, i);
                for e in [a, b, p, q] {
                    assert_eq!(f64::from(e as f32), e, "{root:?} {d} {i}");
                }
                assert_eq!([f.domain_coord(0, a), f.domain_coord(0, b)], [c.x0, c.x1]);
                assert_eq!([f.domain_coord(1, p), f.domain_coord(1, q)], [c.y0, c.y1]);
            }
        }
        assert_eq!(
            Frame::of_root(&Rect::new(0.1, 0.0, 0.4, 1.0)).cell_edges(0.1, 0.3, 3, 5),
            [0.625, 0.75]
        );
    }

    #[test]
    fn axis_is_outward_and_inside_the_cell() {
        // Normalised frame of [-1, 1]: cell 1 of depth 2 is [0.25, 0.5] (domain [-0.5, 0]).
        let (a, da) = encode_axis(-0.3, -0.1, [0.25, 0.5], -1.0, 2.0);
        let (lo, hi) = (-1.0 + f64::from(a) * 2.0, -1.0 + f64::from(a + da) * 2.0);
        assert!(lo <= -0.3 && hi >= -0.1 && lo >= -0.5 && hi <= 0.0);
        assert!(hi - lo < 0.2 + 1e-6);
        // The whole cell is encoded exactly.
        assert_eq!(encode_axis(-0.5, 0.0, [0.25, 0.5], -1.0, 2.0), (0.25, 0.25));
        // Identity frame, cell [-0.5, 0] left of 0: mirrored, still outward and inside.
        let (a, da) = encode_axis(-0.3, -1e-9, [-0.5, 0.0], 0.0, 1.0);
        let (lo, hi) = (f64::from(a), f64::from(a) + f64::from(da));
        assert!(lo <= -0.3 && hi >= -1e-9 && lo >= -0.5 && hi <= 0.0 && a + da == hi as f32);
        assert_eq!(encode_axis(-0.9, 0.7, [-1.0, 1.0], 0.0, 1.0), (-1.0, 2.0));
        // First cell with a lower edge far from the cell edge: u0 snaps to the spacing at u1.
        let (a, da) = encode_axis(0.1, 0.5, [0.0, 0.5], 0.0, 1.0);
        assert!(f64::from(a) <= 0.1 && f64::from(a) + f64::from(da) == 0.5 && a + da == 0.5);
    }
}
