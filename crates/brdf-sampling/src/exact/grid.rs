//! Exact interval edges and bound nodes ([`Grid`]), the initial breaks at the BRDF's kinks in
//! θo, and the table variable ([`TableVar`]).

use brdf::Brdf;

/// The variable of an interval's normaliser table and of its search.
///
/// Isotropic BRDFs use `v = cos θo`: `A` is then an even function of `θo` (`ωo` at `−θo` is
/// `ωo` at `θo` turned by π), hence a smooth function of `cos θo` up to normal incidence, and
/// a query needs no `acos` — unless the BRDF is a table linear in θo or depends on `sin θo`
/// (Cornell data) (see [`table_var`]). Anisotropic cells keep `v = θo` (without half-turn symmetry `A`
/// is not even in `θo` at a fixed azimuth, and `cos θo` would put a square-root singularity at
/// normal incidence).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum TableVar {
    Cos,
    Theta,
}

impl TableVar {
    /// `v` of the outgoing polar angle `θ`.
    pub(super) fn of(self, theta: f64) -> f64 {
        match self {
            Self::Cos => theta.cos(),
            Self::Theta => theta,
        }
    }
    /// `θ` of `v`.
    pub(super) fn theta(self, v: f64) -> f64 {
        match self {
            Self::Cos => v.clamp(-1.0, 1.0).acos(),
            Self::Theta => v,
        }
    }
    /// `cos θ` of `v`.
    #[inline]
    pub(super) fn cos(self, v: f64) -> f64 {
        match self {
            Self::Cos => v,
            Self::Theta => cos_not_speculated(v),
        }
    }
    /// The search key of `v`, increasing with θ over `[0, key_range]`: `1 − cos θ` or `θ`.
    #[inline]
    pub(super) fn key(self, v: f64) -> f64 {
        match self {
            Self::Cos => 1.0 - v,
            Self::Theta => v,
        }
    }
    pub(super) fn key_range(self) -> f64 {
        match self {
            Self::Cos => 1.0,
            Self::Theta => std::f64::consts::FRAC_PI_2,
        }
    }
}

/// `cos v` behind a call the optimiser cannot hoist: inlined, `libm`'s `cos` (which it treats
/// as pure) was computed on every query of an isotropic set and the result discarded (5 % of
/// the sampling loop of `ward` in `perf`).
#[inline(never)]
pub(super) fn cos_not_speculated(v: f64) -> f64 {
    v.cos()
}

/// Exact interval edges and bound nodes: a θ numerator `num` over `2^EDGE_BITS` (or a node's
/// `k` over `m · 2^EDGE_BITS`) names a point of the initial interval `i = ⌊num / 2^EDGE_BITS⌋`,
/// at the fraction `rem / 2^EDGE_BITS` of it. One rational for every point of the set, so that
/// a node shared by a split interval and its children is the same rational, hence the same
/// `f64` (one correctly rounded quotient) and the same `ωo` bits.
///
/// The initial intervals are uniform (`θ = (π/2) · num / den`, `den = n0 · 2^EDGE_BITS`), or,
/// when the BRDF has kinks in θo ([`theta_kinks`]), cut at those kinks as well
/// (`θ = b_i + (b_{i+1} − b_i) · rem / 2^EDGE_BITS` over the breaks `b`): every interval is then
/// a range where `A(θo)` is smooth, and its Chebyshev table converges.
#[derive(Debug, Clone, Copy)]
pub(super) struct Grid {
    /// Denominator of the interval edges: `initial intervals · 2^EDGE_BITS`.
    pub(super) den: u64,
    /// `bound_nodes − 1`: node `n` of `[a, b]` is `(a·m + (b − a)·n) / (den·m)`.
    pub(super) m: u64,
    /// Half-width of the azimuth cells (0: isotropic); `δ = h · (2 · num / 2^EDGE_BITS − 1)`.
    pub(super) half: f64,
    /// The initial intervals' edges (radians, `breaks[0..=n0]`) when they are not uniform.
    pub(super) breaks: Option<[f64; MAX_BREAKS + 1]>,
}

/// Halvings an initial interval can take (far below any useful `min_width_deg`).
pub(super) const EDGE_BITS: u32 = 40;

/// Most initial intervals a set can start from when they are cut at the BRDF's kinks (a BRDF
/// with more kinks than fit keeps the uniform intervals).
pub(super) const MAX_BREAKS: usize = 128;

impl Grid {
    /// The θ of the rational `k / (m · 2^EDGE_BITS)` (in initial intervals).
    pub(super) fn angle(&self, k: u64, m: u64) -> f64 {
        match &self.breaks {
            None => std::f64::consts::FRAC_PI_2 * (k as f64 / (self.den * m) as f64),
            Some(b) => {
                let unit = m << EDGE_BITS;
                let n0 = (self.den >> EDGE_BITS) as usize;
                let (i, rem) = ((k / unit) as usize, k % unit);
                if i >= n0 {
                    b[n0]
                } else if rem == 0 {
                    b[i]
                } else {
                    b[i] + (b[i + 1] - b[i]) * (rem as f64 / unit as f64)
                }
            }
        }
    }
    pub(super) fn edge(&self, num: u64) -> f64 {
        self.angle(num, 1)
    }
    /// The azimuth offset of the numerator `num` (over `2^EDGE_BITS`).
    pub(super) fn delta(&self, num: u64) -> f64 {
        self.delta_of(num, 1)
    }
    /// The azimuth offset of `num / (2^EDGE_BITS · m)`: one correctly rounded quotient, so
    /// equal rationals give the same bits.
    pub(super) fn delta_of(&self, num: u64, m: u64) -> f64 {
        self.half * (2.0 * (num as f64 / ((1u64 << EDGE_BITS) * m) as f64) - 1.0)
    }
    /// Numerator (over `den · m`) and angle of bound node `n` of the interval `num`.
    pub(super) fn node(&self, num: [u64; 2], n: u64) -> (u64, f64) {
        let k = num[0] * self.m + (num[1] - num[0]) * n;
        (k, self.angle(k, self.m))
    }
}

/// Outgoing polar angles (radians, inside `(0, π/2)`, increasing) where `A(θo)` is known to
/// have a kink: the θo slices of an RGL table, which is linear in θo between them
/// ([`brdf::RglBrdf::theta_slices`]). Empty for every other BRDF.
pub(crate) fn theta_kinks(brdf: &dyn Brdf) -> Vec<f64> {
    let Some(rgl) = brdf
        .as_any()
        .and_then(|a| a.downcast_ref::<brdf::RglBrdf>())
    else {
        return Vec::new();
    };
    let eps = 1e-6;
    let mut k: Vec<f64> = rgl
        .theta_kinks() // the slices, and σ's nodes above the last one (issue 27)
        .into_iter()
        .filter(|t| t.is_finite() && *t > eps && *t < std::f64::consts::FRAC_PI_2 - eps)
        .collect();
    k.sort_by(f64::total_cmp);
    k.dedup_by(|a, b| (*a - *b).abs() <= eps);
    k
}

/// Uniform edges closer to a kink than this (degrees) are dropped: the kink replaces them.
pub(super) const KINK_MERGE_DEG: f64 = 2.0;

/// The initial intervals' edges: `n0` uniform ones, cut at the `kinks` too (a uniform edge
/// within [`KINK_MERGE_DEG`] of a kink gives way to it); `None` without kinks, or with more
/// than [`MAX_BREAKS`] intervals.
pub(super) fn initial_breaks(n0: usize, kinks: &[f64]) -> Option<Vec<f64>> {
    if kinks.is_empty() {
        return None;
    }
    let merge = KINK_MERGE_DEG.to_radians();
    let mut b: Vec<f64> = (0..=n0)
        .map(|i| std::f64::consts::FRAC_PI_2 * (i as f64 / n0 as f64))
        .filter(|&t| {
            let end = t == 0.0 || t == std::f64::consts::FRAC_PI_2;
            end || kinks.iter().all(|k| (k - t).abs() >= merge)
        })
        .collect();
    b.extend_from_slice(kinks);
    b.sort_by(f64::total_cmp);
    b.dedup();
    (b.len() <= MAX_BREAKS + 1).then_some(b)
}

/// The table variable of a set (`isotropic`: the BRDF's, i.e. one azimuth cell; `tabulated`:
/// the BRDF has kinks in θo, [`theta_kinks`]). A table interpolated linearly in θo (RGL) makes
/// `A` a function of `|θo|` with a kink at normal incidence, i.e. a square root of `1 − cos θo`:
/// its sets keep `v = θo` (on `cc_ibiza_sunset` the `cos θo` table was 4e-4 off at 1.1°).
pub(super) fn table_var(isotropic: bool, tabulated: bool) -> TableVar {
    if isotropic && !tabulated {
        TableVar::Cos
    } else {
        TableVar::Theta
    }
}
