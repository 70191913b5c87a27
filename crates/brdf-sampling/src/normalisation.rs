//! Per-slice normalisation by Gauss–Legendre quadrature on the tree's own leaves.
//!
//! The envelope scheme samples exactly `∝ f` whatever the leaf integrals are; only the reported
//! pdf `f / Î` depends on `Î`. The image map's `Î` (midpoint rule on `grid²` cells, boundary
//! cells on a sub-grid) is off by up to ~1 % for lobes that are narrow compared with a fine
//! cell — grazing Beard–Maxwell and Cook–Torrance slices in the all-model validation. The tree
//! itself is an adaptive partition that resolves those lobes, so integrating `f` over every
//! sampleable leaf with a tensor Gauss–Legendre rule of order [`HIGH_ORDER`] gives a far better
//! `Î`. Leaves crossed by the circle are integrated exactly over `rect ∩ disc` as iterated
//! integrals (x outer, the chord `|y| ≤ √(1 − x²)` inner), with the outer interval split where
//! the circle crosses the rectangle's top or bottom edge and the outer variable `x = sin t`, so
//! every piece has a smooth integrand (the disc's area to 1e-10 instead of 9e-4).
//! The rule is globally adaptive (the piece where orders [`HIGH_ORDER`] and [`LOW_ORDER`]
//! disagree most is split into quadrants, within [`EVALUATION_BUDGET`]); the summed
//! disagreement is the reported error estimate. The set keeps whichever of this and the
//! grid's integral has the smaller estimated error. The graded variant ([`Grading::Graded`],
//! used by the exact sampler's normaliser tables) starts every piece with orders 5 and 3 and
//! raises only the worst pieces to order 8 before splitting them.

use brdf::quadrature::{ErrorEstimate, GaussLegendre, WorstFirst};
use partition_sampler::{Density, LeafInfo, Rect};

/// Order of the reported integral.
pub(crate) const HIGH_ORDER: usize = 8;
/// Order of the comparison integral for the error estimate.
pub(crate) const LOW_ORDER: usize = 5;
/// Order of the first, cheap comparison of the graded rule ([`Grading::Graded`]).
pub(crate) const FIRST_ORDER: usize = 3;

/// How the adaptive rule treats a new piece.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Grading {
    /// Orders [`HIGH_ORDER`] and [`LOW_ORDER`] at once (89 evaluations per tensor piece).
    Fixed,
    /// Orders [`LOW_ORDER`] and [`FIRST_ORDER`] first (34 evaluations); the piece of largest
    /// disagreement is raised to [`HIGH_ORDER`] (64 more, compared with its [`LOW_ORDER`]
    /// value) before it is split. Smooth pieces stop at the cheap pair, whose disagreement
    /// (the order-3 error) bounds the order-5 value's error conservatively.
    Graded,
}

/// `∫_{rect ∩ D} f dA` by the iterated rule (see the module docs).
#[cfg_attr(not(test), allow(dead_code))]
fn integrate_leaf(f: &dyn Density, rect: &Rect, rule: &GaussLegendre) -> f64 {
    integrate_leaf_counted(f, rect, rule).0
}

/// [`integrate_leaf`] and the evaluations of `f` it made (counted here, so the adaptive rule
/// adds them once per piece instead of once per evaluation: the same calls of `f` in the same
/// order, the same value bit for bit).
fn integrate_leaf_counted(f: &dyn Density, rect: &Rect, rule: &GaussLegendre) -> (f64, u64) {
    let chord = |x: f64| (1.0 - x * x).max(0.0).sqrt();
    let count = std::cell::Cell::new(0u64);
    let inner = |x: f64| {
        let half = chord(x);
        let (ya, yb) = (rect.y0.max(-half), rect.y1.min(half));
        if yb > ya {
            rule.integrate(ya, yb, |y| {
                count.set(count.get() + 1);
                f.eval([x, y])
            })
        } else {
            0.0
        }
    };
    // Outer breakpoints: where the circle meets the lines y = y0 and y = y1 inside the rect.
    let mut cuts = vec![rect.x0, rect.x1];
    for y in [rect.y0, rect.y1] {
        if y.abs() < 1.0 {
            let x = chord(y);
            for c in [-x, x] {
                if c > rect.x0 && c < rect.x1 {
                    cuts.push(c);
                }
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    // Outer variable x = sin t: the chord √(1 − x²) = cos t is smooth in t even where the
    // circle is vertical (x → ±1), where a rule in x converges like h^1.5 only.
    let value = cuts
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].max(-1.0), w[1].min(1.0));
            if b > a {
                rule.integrate(a.asin(), b.asin(), |t| inner(t.sin()) * t.cos())
            } else {
                0.0
            }
        })
        .sum();
    (value, count.get())
}

/// Evaluation budget of one slice's adaptive rule (under a tenth of its image map).
pub(crate) const EVALUATION_BUDGET: u64 = 16_000;

/// The rule stops once the summed disagreement is at most `TOL · scale`.
pub(crate) const TOL: f64 = 1e-5;

/// One piece of the adaptive rule.
struct Piece {
    /// Index of the leaf the piece belongs to.
    leaf: usize,
    rect: Rect,
    value: f64,
    err: f64,
    /// The value is of order [`HIGH_ORDER`] (else [`LOW_ORDER`], graded rule).
    high: bool,
}

impl ErrorEstimate for Piece {
    fn error_estimate(&self) -> f64 {
        self.err
    }
}

/// `(Î, relative error estimate)` of `f` over the union of `leaves` (their rejection rectangles
/// contain `cell ∩ D` and lie in their cells, so `f`, zero off the disc, integrates to the same
/// value over them).
///
/// Globally adaptive: every leaf is integrated with orders [`HIGH_ORDER`] and [`LOW_ORDER`];
/// while the summed disagreement `Σ |I_high − I_low|` exceeds `TOL · scale` (`scale`: e.g. the
/// grid's `Î`) and fewer than [`EVALUATION_BUDGET`] evaluations were spent, the piece with the
/// largest disagreement is split into quadrants (kinks such as Oren–Nayar's
/// `max(0, cos Δφ)` cross leaves, and a Gauss rule converges slowly across them). The error
/// estimate is the final `Σ |I_high − I_low| / Î` (conservative: it is the low order's error).
/// (This is [`Grading::Fixed`]; see [`Grading::Graded`] for the cheaper start.)
///
/// With `mirror` (`f(x, −y) = f(x, y)`), the leaves are clipped to the half `y ≤ 0` and the
/// result doubled: `∫_D f = 2 ∫_{D ∩ {y ≤ 0}} f`.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn leaf_quadrature(
    f: &dyn Density,
    leaves: impl Iterator<Item = LeafInfo>,
    scale: f64,
    mirror: bool,
) -> (f64, f64) {
    let q = per_leaf_quadrature(f, leaves, scale, mirror, Grading::Fixed);
    (q.total, q.rel_err)
}

/// [`leaf_quadrature`] with the integral of every leaf (storage order).
pub(crate) struct LeafIntegrals {
    /// `Î`.
    pub(crate) total: f64,
    /// Relative error estimate of `Î`.
    pub(crate) rel_err: f64,
    /// Absolute error estimate of `Î` (`Σ |I_high − I_low|`).
    pub(crate) abs_err: f64,
    /// `√(Σ (I_high − I_low)²)` over the pieces (see [`LeafIntegrals::declared_rel_err`]).
    pub(crate) rms_err: f64,
    /// `∫_{leaf i} f` (with `mirror`: over the leaf's part in `y ≤ 0` only).
    pub(crate) per_leaf: Vec<f64>,
    /// Evaluations of `f` spent.
    pub(crate) evaluations: u64,
}

/// Standard deviations of the declared error ([`LeafIntegrals::declared_rel_err`]).
pub(crate) const DECLARED_SIGMAS: f64 = 3.0;

impl LeafIntegrals {
    /// The relative error a sampler normalised with `Î` declares (issue 27): the smaller of
    /// [`LeafIntegrals::rel_err`] (`Σ |I_high − I_low| / Î`, a worst case: every piece's
    /// error at the lower order's size, all of one sign) and [`DECLARED_SIGMAS`] ×
    /// `√(Σ (I_high − I_low)²) / Î`: the pieces' errors taken as independent, each at most
    /// its disagreement (the value is the higher order's), and summed in quadrature.
    ///
    /// Why. On tabulated data (the MERL layout's nearest-bin lookup, the Cornell interpolant)
    /// every piece is crossed by the table's edges and the pieces' errors have random signs:
    /// on the MERL layout of `phong:n=50` at θo = 40.5° the worst case declares 3.9e-3 for a
    /// normaliser off by less than 1e-4 (midpoint rule on 2048 × 4096 cells), so a check whose
    /// tolerance is that declared error passes a pdf 1 % off. One piece alone still declares
    /// 3 × its disagreement; a smooth integrand's higher-order value is far better than its
    /// disagreement anyway.
    pub(crate) fn declared_rel_err(&self) -> f64 {
        if !(self.total > 0.0) {
            return f64::INFINITY;
        }
        self.rel_err
            .min(DECLARED_SIGMAS * self.rms_err / self.total)
    }
}

/// See [`leaf_quadrature`]; also returns each leaf's integral. [`Grading::Graded`] reaches the
/// same target with fewer evaluations where the integrand is smooth on most leaves.
pub(crate) fn per_leaf_quadrature(
    f: &dyn Density,
    leaves: impl Iterator<Item = LeafInfo>,
    scale: f64,
    mirror: bool,
    grading: Grading,
) -> LeafIntegrals {
    adaptive_quadrature(f, leaves, TOL * scale, mirror, EVALUATION_BUDGET, grading)
}

/// The rule of [`per_leaf_quadrature`] with an absolute target `abs_tol` for the summed
/// disagreement and an evaluation `budget` (the albedo reference uses a larger one).
pub(crate) fn adaptive_quadrature(
    f: &dyn Density,
    leaves: impl Iterator<Item = LeafInfo>,
    abs_tol: f64,
    mirror: bool,
    budget: u64,
    grading: Grading,
) -> LeafIntegrals {
    let factor = if mirror { 2.0 } else { 1.0 };
    let (hi, lo, first) = (
        GaussLegendre::new(HIGH_ORDER),
        GaussLegendre::new(LOW_ORDER),
        GaussLegendre::new(FIRST_ORDER),
    );
    let evals = std::sync::atomic::AtomicU64::new(0);
    // Evaluations counted per piece (one atomic add per piece, not per evaluation).
    let counted = |rect: &Rect, rule: &GaussLegendre| {
        let (value, n) = integrate_leaf_counted(f, rect, rule);
        evals.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        value
    };
    let piece = |leaf: usize, rect: Rect| {
        let low = counted(&rect, &lo);
        let (value, other, high) = match grading {
            Grading::Fixed => (counted(&rect, &hi), low, true),
            Grading::Graded => (low, counted(&rect, &first), false),
        };
        WorstFirst(Piece {
            leaf,
            rect,
            value,
            err: (value - other).abs(),
            high,
        })
    };
    let mut n_leaves = 0;
    // Leaves crossing the plane of incidence y = 0 are cut there: isotropic models have kinks
    // in the azimuth difference (functions of |φi − φo|) exactly on it, where a Gauss rule
    // converges slowly and its two orders can agree on a wrong value (schlick-diffuse at
    // θo = 0.5°: 1e-4 off with an estimate of 1e-6 on the uncut single leaf).
    let mut heap: std::collections::BinaryHeap<WorstFirst<Piece>> = leaves
        .enumerate()
        .inspect(|_| n_leaves += 1)
        .flat_map(|(i, l)| {
            let r = l.rect;
            let lower = (r.y0 < 0.0).then(|| Rect::new(r.x0, r.y0, r.x1, r.y1.min(0.0)));
            let upper = (!mirror && r.y1 > 0.0).then(|| Rect::new(r.x0, r.y0.max(0.0), r.x1, r.y1));
            [lower, upper].into_iter().flatten().map(move |q| (i, q))
        })
        .map(|(i, r)| piece(i, r))
        .collect();
    let mut err: f64 = heap.iter().map(|p| p.err).sum();
    while factor * err > abs_tol && evals.load(std::sync::atomic::Ordering::Relaxed) < budget {
        let Some(WorstFirst(worst)) = heap.pop() else {
            break;
        };
        err -= worst.err;
        if !worst.high {
            // Raise the order before splitting: the order-5 value becomes the comparison.
            let value = counted(&worst.rect, &hi);
            let p = Piece {
                value,
                err: (value - worst.value).abs(),
                high: true,
                ..worst
            };
            err += p.err;
            heap.push(WorstFirst(p));
            continue;
        }
        for q in worst.rect.quadrants() {
            let p = piece(worst.leaf, q);
            err += p.err;
            heap.push(p);
        }
    }
    // The heap's storage order depends only on the sequence of pushes: a fixed summation order.
    let pieces = heap.into_vec();
    let total: f64 = factor * pieces.iter().map(|p| p.value).sum::<f64>();
    let err: f64 = factor * pieces.iter().map(|p| p.err).sum::<f64>();
    let rms_err = factor * pieces.iter().map(|p| p.err * p.err).sum::<f64>().sqrt();
    let rel_err = if total > 0.0 {
        err / total
    } else {
        f64::INFINITY
    };
    let mut per_leaf = vec![0.0; n_leaves];
    for p in &pieces {
        per_leaf[p.leaf] += p.value;
    }
    LeafIntegrals {
        total,
        rel_err,
        abs_err: err,
        rms_err,
        per_leaf,
        evaluations: evals.into_inner(),
    }
}

/// Orders of the cylinder rule ([`cylinder_quadrature`]): a cheap pair, then the high order.
const CYLINDER_ORDERS: [usize; 3] = [FIRST_ORDER, LOW_ORDER, HIGH_ORDER];

/// Cells per axis and side of the cylinder rule's first partition.
const CYLINDER_CELLS: usize = 4;

/// One piece of the cylinder rule: a rectangle in `(t, u)` on the side `sign` of `y = 0`.
struct CylinderPiece {
    sign: f64,
    rect: Rect,
    value: f64,
    err: f64,
    high: bool,
}

impl ErrorEstimate for CylinderPiece {
    fn error_estimate(&self) -> f64 {
        self.err
    }
}

/// `∫_D f dA` over the whole disc in "cylinder" coordinates `(t, u)`: `x = sin t`,
/// `y = ± cos t · cos u²` (`t ∈ [−π/2, π/2]`, `u ∈ [0, √(π/2)]`, one map for each side of
/// `y = 0`), so that `z = cos t · sin u²` and the angle of `ωi` in the `(y, z)` plane is
/// `ψ = atan2(y, z) = ±(π/2 − u²)`; `dA = 2u sin(u²) cos²t dt du`.
///
/// Why: a density smooth in `(x, y, z)` stays smooth in `(t, u)`, and so does one that
/// behaves like `√(cos ψ)` or `√z` at the horizon (`√(sin u²) ≈ u`); one whose kinks lie on
/// surfaces `ψ = const` (masking onsets of a surface of parallel cylinders along `x`) has
/// them on lines `u = const`. poulin-fournier has both (docs/benchmarks.md §19.9): the leaf
/// rule in `(x, y)` ran to its budget at every normaliser node (35 000 – 720 000 evaluations
/// to reach [`TOL`] at θo = 10° – 89°), this rule reaches it in 5 000 – 12 000.
///
/// Globally adaptive like [`adaptive_quadrature`] with [`Grading::Graded`] (orders 5 and 3
/// per piece, the worst raised to order 8, then split into quadrants), from
/// [`CYLINDER_CELLS`]² cells per side, until the summed disagreement is at most `abs_tol`
/// or `budget` evaluations were spent. With `mirror` (`f(x, −y) = f(x, y)`) only the side
/// `y ≤ 0` is integrated, and doubled. `per_leaf` holds the one total.
///
/// Not used by the build yet: unlike the leaf rule it does not start from the tree's leaves,
/// so a lobe narrower than its first cells could go unseen (both orders ≈ 0 there); and like
/// the leaf rule, a kink within a sliver at a piece's edge can be missed by both orders
/// (`√(cos ψ) + ½ max(0, ψ − 40°)`: the kink at `u = 0.934`, 0.006 inside a first cell's
/// edge, leaves a 1.3·10⁻⁵ error that no tolerance removes).
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn cylinder_quadrature(
    f: &dyn Density,
    abs_tol: f64,
    mirror: bool,
    budget: u64,
) -> LeafIntegrals {
    use std::f64::consts::FRAC_PI_2;
    let factor = if mirror { 2.0 } else { 1.0 };
    let rules = CYLINDER_ORDERS.map(GaussLegendre::new);
    let evals = std::cell::Cell::new(0u64);
    let tensor = |rule: &GaussLegendre, sign: f64, r: &Rect| {
        rule.integrate(r.x0, r.x1, |t| {
            let (st, ct) = t.sin_cos();
            ct * ct
                * rule.integrate(r.y0, r.y1, |u| {
                    evals.set(evals.get() + 1);
                    let (su, cu) = (u * u).sin_cos();
                    f.eval([st, sign * ct * cu]) * 2.0 * u * su
                })
        })
    };
    let piece = |sign: f64, rect: Rect| {
        let value = tensor(&rules[1], sign, &rect);
        let err = (value - tensor(&rules[0], sign, &rect)).abs();
        WorstFirst(CylinderPiece {
            sign,
            rect,
            value,
            err,
            high: false,
        })
    };
    let (dt, du) = (
        2.0 * FRAC_PI_2 / CYLINDER_CELLS as f64,
        FRAC_PI_2.sqrt() / CYLINDER_CELLS as f64,
    );
    let signs: &[f64] = if mirror { &[-1.0] } else { &[-1.0, 1.0] };
    let mut heap: std::collections::BinaryHeap<WorstFirst<CylinderPiece>> = signs
        .iter()
        .flat_map(|&sign| {
            (0..CYLINDER_CELLS * CYLINDER_CELLS).map(move |k| {
                let (i, j) = ((k % CYLINDER_CELLS) as f64, (k / CYLINDER_CELLS) as f64);
                let t0 = -FRAC_PI_2 + dt * i;
                (sign, Rect::new(t0, du * j, t0 + dt, du * (j + 1.0)))
            })
        })
        .map(|(sign, rect)| piece(sign, rect))
        .collect();
    let mut err: f64 = heap.iter().map(|p| p.err).sum();
    while factor * err > abs_tol && evals.get() < budget {
        let Some(WorstFirst(worst)) = heap.pop() else {
            break;
        };
        err -= worst.err;
        if !worst.high {
            let value = tensor(&rules[2], worst.sign, &worst.rect);
            let p = CylinderPiece {
                value,
                err: (value - worst.value).abs(),
                high: true,
                ..worst
            };
            err += p.err;
            heap.push(WorstFirst(p));
            continue;
        }
        for q in worst.rect.quadrants() {
            let p = piece(worst.sign, q);
            err += p.err;
            heap.push(p);
        }
    }
    let pieces = heap.into_vec();
    let total = factor * pieces.iter().map(|p| p.value).sum::<f64>();
    let abs_err = factor * pieces.iter().map(|p| p.err).sum::<f64>();
    let rms_err = factor * pieces.iter().map(|p| p.err * p.err).sum::<f64>().sqrt();
    LeafIntegrals {
        total,
        rel_err: if total > 0.0 {
            abs_err / total
        } else {
            f64::INFINITY
        },
        abs_err,
        rms_err,
        per_leaf: vec![total],
        evaluations: evals.get(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn leaf(x0: f64, y0: f64, x1: f64, y1: f64) -> LeafInfo {
        LeafInfo {
            rect: Rect::new(x0, y0, x1, y1),
            max_bound: 1.0,
            integral: 0.0,
            volume: 0.0,
        }
    }

    #[test]
    fn disc_area_and_a_smooth_moment_are_exact() {
        let inside = |p: [f64; 2]| f64::from(u8::from(p[0] * p[0] + p[1] * p[1] < 1.0));
        // Four quadrants, each crossed by the circle: area π.
        let q = [
            leaf(-1.0, -1.0, 0.0, 0.0),
            leaf(0.0, -1.0, 1.0, 0.0),
            leaf(-1.0, 0.0, 0.0, 1.0),
            leaf(0.0, 0.0, 1.0, 1.0),
        ];
        let (a, _) = leaf_quadrature(&inside, q.iter().copied(), 1.0, false);
        assert_relative_eq!(a, std::f64::consts::PI, max_relative = 1e-9);
        // Mirrored: the lower half, doubled.
        let (a, _) = leaf_quadrature(&inside, q.iter().copied(), 1.0, true);
        assert_relative_eq!(a, std::f64::consts::PI, max_relative = 1e-9);
        // One leaf over the whole square (Lambert's tree): the vertical tangents at x = ±1.
        let (a, _) = leaf_quadrature(
            &inside,
            [leaf(-1.0, -1.0, 1.0, 1.0)].into_iter(),
            1.0,
            false,
        );
        assert_relative_eq!(a, std::f64::consts::PI, max_relative = 1e-9);
        // ∫_D (1 − r²) dA = π/2 on a 4 × 4 partition of the square.
        let g = |p: [f64; 2]| {
            let r2 = p[0] * p[0] + p[1] * p[1];
            if r2 < 1.0 { 1.0 - r2 } else { 0.0 }
        };
        let cells: Vec<LeafInfo> = (0..16)
            .map(|k| {
                let (i, j) = ((k % 4) as f64, (k / 4) as f64);
                leaf(
                    -1.0 + 0.5 * i,
                    -1.0 + 0.5 * j,
                    -0.5 + 0.5 * i,
                    -0.5 + 0.5 * j,
                )
            })
            .collect();
        let (v, err) = leaf_quadrature(&g, cells.iter().copied(), 1.0, false);
        assert_relative_eq!(v, std::f64::consts::FRAC_PI_2, max_relative = 1e-5);
        assert!(err < 1e-3, "{err}");
    }

    #[test]
    fn the_graded_rule_meets_the_target_with_fewer_evaluations() {
        // A 16 × 16 partition of the square, leaves as small as a tree's.
        let h = 0.125;
        let cells: Vec<LeafInfo> = (0..256)
            .map(|k| {
                let (x, y) = (-1.0 + h * (k % 16) as f64, -1.0 + h * (k / 16) as f64);
                leaf(x, y, x + h, y + h)
            })
            .collect();
        let run = |g: &dyn Density, tol, grading| {
            adaptive_quadrature(g, cells.iter().copied(), tol, false, 1_000_000, grading)
        };
        // ∫_D (1 − r²) dA = π/2 to 1e-6 (the target of a normaliser): the cheap pair does.
        let smooth = |p: [f64; 2]| (1.0 - p[0] * p[0] - p[1] * p[1]).max(0.0);
        // A Gaussian of σ = 0.02 far inside the disc: 2πσ²; its cells are raised and split.
        let s = 0.02f64;
        let peak = |p: [f64; 2]| {
            let (dx, dy) = (p[0] - 0.3, p[1] - 0.2);
            (-(dx * dx + dy * dy) / (2.0 * s * s)).exp()
        };
        let cases: [(&dyn Density, f64, f64); 2] = [
            (&smooth, std::f64::consts::FRAC_PI_2, 1e-6),
            (&peak, 2.0 * std::f64::consts::PI * s * s, 1e-9),
        ];
        for (k, (g, exact, tol)) in cases.into_iter().enumerate() {
            let fixed = run(g, tol, Grading::Fixed);
            let graded = run(g, tol, Grading::Graded);
            for q in [&fixed, &graded] {
                let err = (q.total - exact).abs();
                assert!(q.abs_err <= tol, "case {k}: estimate {}", q.abs_err);
                assert!(
                    err <= q.abs_err.max(1e-14),
                    "case {k}: {err} > {}",
                    q.abs_err
                );
            }
            if k == 0 {
                assert!(
                    graded.evaluations < fixed.evaluations / 2,
                    "{} vs {}",
                    graded.evaluations,
                    fixed.evaluations
                );
            }
        }
    }

    /// `√(cos ψ)` (`ψ = atan2(y, z)`, the angle of `ωi` in the `(y, z)` plane): poulin-fournier's
    /// behaviour at the horizon (`∝ √z` near the circle; docs/benchmarks.md §19.9). With
    /// `x = sin t`, `y = cos t sin ψ`: `∫_D g = (π/2) ∫ cos^{3/2} ψ dψ
    /// = (π/2) √π Γ(5/4) / Γ(7/4)`.
    #[test]
    fn the_cylinder_rule_resolves_a_square_root_at_the_horizon() {
        use statrs::function::gamma::gamma;
        let g = |p: [f64; 2]| {
            let r2 = p[0] * p[0] + p[1] * p[1];
            if r2 < 1.0 {
                let z = (1.0 - r2).sqrt();
                (z / p[1].hypot(z)).sqrt()
            } else {
                0.0
            }
        };
        let pi = std::f64::consts::PI;
        let exact = 0.5 * pi * pi.sqrt() * gamma(1.25) / gamma(1.75);
        let tol = TOL * exact;
        let cyl = cylinder_quadrature(&g, tol, false, EVALUATION_BUDGET);
        let err = (cyl.total - exact).abs();
        assert!(
            cyl.abs_err <= tol && err <= cyl.abs_err && cyl.evaluations < EVALUATION_BUDGET,
            "cylinder rule: estimate {:e}, error {err:e}, {} evaluations",
            cyl.abs_err,
            cyl.evaluations
        );
        // Mirror-symmetric in y: half the disc, doubled, within the same target.
        let sym = |p: [f64; 2]| g([p[0], -p[1].abs()]);
        let half = cylinder_quadrature(&sym, tol, true, EVALUATION_BUDGET);
        let full = cylinder_quadrature(&sym, tol, false, EVALUATION_BUDGET);
        assert!((half.total - full.total).abs() <= half.abs_err + full.abs_err);
        // The graded leaf rule on a 16 × 16 partition does not reach the target within the
        // same budget: the √ at the circle crosses its pieces.
        let step = 0.125;
        let cells: Vec<LeafInfo> = (0..256)
            .map(|k| {
                let (x, y) = (-1.0 + step * (k % 16) as f64, -1.0 + step * (k / 16) as f64);
                leaf(x, y, x + step, y + step)
            })
            .collect();
        let q = adaptive_quadrature(
            &g,
            cells.iter().copied(),
            tol,
            false,
            EVALUATION_BUDGET,
            Grading::Graded,
        );
        assert!(
            q.abs_err > tol,
            "leaf rule: {:e} in {}",
            q.abs_err,
            q.evaluations
        );
    }

    #[test]
    fn kinks_are_resolved_by_splitting() {
        // max(0, x − 0.1) on the disc, one leaf: the kink at x = 0.1 crosses it.
        let g = |p: [f64; 2]| {
            if p[0] * p[0] + p[1] * p[1] < 1.0 {
                (p[0] - 0.1).max(0.0)
            } else {
                0.0
            }
        };
        // ∫_{0.1}^{1} (x − 0.1) · 2√(1 − x²) dx, by a fine midpoint sum.
        let n = 2_000_000;
        let h = 0.9 / n as f64;
        let exact: f64 = (0..n)
            .map(|k| {
                let x = 0.1 + (k as f64 + 0.5) * h;
                (x - 0.1) * 2.0 * (1.0 - x * x).sqrt() * h
            })
            .sum();
        let (v, err) = leaf_quadrature(&g, [leaf(-1.0, -1.0, 1.0, 1.0)].into_iter(), 1.0, false);
        assert_relative_eq!(v, exact, max_relative = 5e-5);
        assert!(err < 1e-3 && err >= (v / exact - 1.0).abs(), "{err}");
        // Without splitting, the same rule is far off.
        let hi = GaussLegendre::new(HIGH_ORDER);
        let one = integrate_leaf(&g, &Rect::new(-1.0, -1.0, 1.0, 1.0), &hi);
        assert!(one.is_finite());
        assert!((one / exact - 1.0).abs() > 10.0 * (v / exact - 1.0).abs());
    }

    #[test]
    fn a_narrow_peak_inside_one_leaf_beats_the_midpoint_rule() {
        // Gaussian of σ = 0.004 in a 0.03-wide leaf: a 4-point midpoint rule is off by
        // −70 %, the order-8 rule by < 2e-3.
        let s = 0.004f64;
        let g = |p: [f64; 2]| {
            let (dx, dy) = (p[0] - 0.3, p[1] - 0.2);
            (-(dx * dx + dy * dy) / (2.0 * s * s)).exp()
        };
        // Exact integral over the leaf (±3.75 σ): 2π σ² erf(3.75/√2)².
        let e = statrs::function::erf::erf(0.015 / (s * std::f64::consts::SQRT_2));
        let exact = 2.0 * std::f64::consts::PI * s * s * e * e;
        let (v, _) = leaf_quadrature(
            &g,
            [leaf(0.285, 0.185, 0.315, 0.215)].into_iter(),
            1e-4,
            false,
        );
        assert_relative_eq!(v, exact, max_relative = 2e-3);
        let midpoint: f64 = [
            [0.2925, 0.1925],
            [0.3075, 0.1925],
            [0.2925, 0.2075],
            [0.3075, 0.2075],
        ]
        .iter()
        .map(|&p| g(p) * 0.015 * 0.015)
        .sum();
        assert!(
            (midpoint / exact - 1.0).abs() > 0.1,
            "{midpoint} vs {exact}"
        );
    }
}
