//! The compact sampling table of one interval (issue 29 item 2): what the rejection walk
//! reads per trial — alias entry, rejection rectangle and bound — in one 32-byte record per
//! leaf, apart from the tree's build state (leaf integrals, nodes, the density provider).
//!
//! The records are derived from the interval's tree when its cell is assembled (built or
//! loaded; nothing new is saved): rectangle and bound are the tree's own stored `f32` values,
//! and the alias table is built from `V_i = (dx · dy) · M_i` of those values, the tree's own
//! selection weights. A draw therefore consumes the same uniforms and returns the same point
//! bits as [`QuadTreeSampler::sample_envelope_of`] (tested); it is that walk without the
//! tree's generality (frame map, descent tables, per-trial flags) and with its counters kept
//! in registers.

use distributions::alias::build_alias;
use distributions::index::{floor_index, index_to_f64};
use partition_sampler::{
    Audit, MAX_TRIALS_PER_SAMPLE, Point2, QuadTreeSampler, RegionStats, UniformSource,
};

/// One leaf as a trial reads it: `[x0, x0 + dx] × [y0, y0 + dy]` on the disc's square, its
/// bound `M_i` and its alias entry. 32 bytes, aligned to 32: never across a cache line.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
struct Entry {
    x0: f32,
    y0: f32,
    dx: f32,
    dy: f32,
    /// `M_i`.
    m: f32,
    /// Alias target.
    alias: u32,
    /// Alias threshold (`f64`: the pick probabilities are the weights' to rounding).
    prob: f64,
}

/// Sub-cells per axis of a leaf's thinning bounds ([`SubBounds`]).
pub(super) const SUB: usize = 4;

/// Sub-cells per leaf, `SUB²`.
pub(super) const SUB_CELLS: usize = SUB * SUB;

/// The thinning bound of a sub-cell whose code is `q` in a leaf of bound `m`:
/// `m · (q · fl(1/255))` (`m` itself at `q = 255`: `255 · fl(1/255) = 1` exactly). The build
/// stores the smallest `q` whose value is at least the sub-cell's image-map bound
/// ([`sub_code`]), so this, as computed here, is the bound.
#[inline(always)]
pub(super) fn sub_bound(m: f64, q: u8) -> f64 {
    m * sub_factor(q)
}

/// `q · fl(1/255)`: the factor of [`sub_bound`].
#[inline(always)]
pub(super) fn sub_factor(q: u8) -> f64 {
    f64::from(q) * (1.0 / 255.0)
}

/// The code of a sub-cell bound `b` in a leaf of bound `m`: the smallest `q` with
/// [`sub_bound`]`(m, q) ≥ b` (255, i.e. `m`, when `b ≥ m`, or `b` is not a number, or `m ≤ 0`).
pub(super) fn sub_code(m: f64, b: f64) -> u8 {
    if !(m > 0.0 && b < m) {
        return 255;
    }
    let mut q = ((b.max(0.0) / m) * 255.0).ceil().clamp(0.0, 255.0) as u8;
    while q < 255 && sub_bound(m, q) < b {
        q += 1;
    }
    while q > 0 && sub_bound(m, q - 1) >= b {
        q -= 1;
    }
    q
}

/// Per-leaf thinning bounds of one interval's tree (issue 29, docs/benchmarks.md §30.1, §30.6),
/// in `L ≥ 1` θo layers: the layers cut the θo range the bounds serve at the inner edges
/// `edges` (`L − 1` angles in radians, increasing); in layer `l` (`e_l ≤ θo ≤ e_{l+1}`, with the
/// interval's ends outside), leaf `i`'s rectangle is cut into `SUB × SUB` equal sub-cells,
/// sub-cell `(sx, sy)` (row-major by `sy`) holding the code `q` of `M_ils = m_i · q / 255`
/// ([`sub_bound`]), at least the leaf rule's bound over the sub-cell for every θo of the layer
/// (`safety ×` the largest image-map sample of the envelope of the layer's end nodes, the peak
/// track of the layer's θo and the rim band) and at most `M_i`. A trial at a point of sub-cell
/// `s` whose acceptance threshold `u₃·M_i` is at least `M_ils` is rejected without evaluating
/// `g`: `g ≤ M_ils` there, so it would have been rejected anyway — the same samples, the same
/// law; only the evaluations fall.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SubBounds {
    /// `L · leaves` code blocks, layer-major, each layer's in the tree's leaf order.
    pub(super) codes: Box<[[u8; SUB_CELLS]]>,
    /// The `L − 1` inner layer edges (radians, increasing; empty: one layer).
    pub(super) edges: Box<[f64]>,
    /// Per leaf (`L = 1` only; empty: none), the **served bound** `T_i ≥ M_i` the codes are
    /// relative to in place of `m_i = M_i` (docs/benchmarks.md §32.1: the rigorous sub-cell
    /// bounds of a one-layer interval, which may exceed the tree's image-map bound `M_i`): the
    /// sub-cell bound is `sub_bound(T_i, q)`, and the layer table's leaf bound `M_il` is taken
    /// from these ([`LeafTable::with_layer_tables`]).
    pub(super) tops: Box<[f32]>,
}

impl SubBounds {
    /// One layer's codes (`L = 1`).
    pub(super) fn single(codes: Box<[[u8; SUB_CELLS]]>) -> Self {
        Self {
            codes,
            edges: Box::new([]),
            tops: Box::new([]),
        }
    }

    /// The bounds with the served bounds `tops` (one per leaf, `L = 1`; empty: none).
    pub(super) fn with_tops(mut self, tops: Box<[f32]>) -> Self {
        self.tops = tops;
        self
    }

    /// The bound leaf `k`'s codes are relative to: `T_k` ([`SubBounds::tops`]) when the bounds
    /// have served bounds, else its tree bound `m` (`M_k`) (test support).
    #[cfg(test)]
    pub(super) fn leaf_base(&self, k: usize, m: f64) -> f64 {
        self.tops.get(k).map_or(m, |&t| f64::from(t))
    }

    /// The layer count `L = edges.len() + 1`.
    pub(super) fn layers(&self) -> usize {
        self.edges.len() + 1
    }
}

/// The layer serving `theta` among the inner edges `edges`: the number of edges strictly
/// below `theta` (at an edge, the lower layer: both layers' bounds hold there, each being
/// valid at its closed range's ends). `None` for a `theta` that is not a number.
#[inline]
pub(super) fn layer_of(edges: &[f64], theta: f64) -> Option<usize> {
    if theta.is_nan() {
        return None;
    }
    Some(edges.iter().filter(|&&e| theta > e).count())
}

/// The compact table of one interval's tree (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct LeafTable {
    entries: Box<[Entry]>,
    /// `entries.len()` as `f64`.
    n: f64,
    /// The leaves' thinning bound codes, [`SUB_CELLS`] per entry in order, layer after layer
    /// (empty: none).
    sub: Box<[u8]>,
    /// The inner θo edges of the layers ([`SubBounds::edges`]).
    edges: Box<[f64]>,
    /// The served bounds `T_i` of one layer's codes ([`SubBounds::tops`]) and those codes
    /// relative to them, kept where some `T_i > M_i` (empty otherwise: `sub` is relative to
    /// `M_i`) for [`LeafTable::with_layer_tables`]; `sub` then holds them re-expressed
    /// relative to `M_i` and capped at it (255).
    tops: Box<[f32]>,
    top_codes: Box<[u8]>,
    /// Per θo layer of the thinning bounds (`L ≥ 2`; empty: none, see
    /// [`LeafTable::with_layer_tables`]), the layer's own table over the same leaves: leaf
    /// bounds `M_il`, alias table and one layer of codes ([`LeafTable::serving`] picks it).
    layers: Box<[LeafTable]>,
}

/// The smallest `f32` at least `b` (`b` finite and non-negative): a layer table's leaf bound
/// `M_il` from the largest sub-cell bound of its leaf.
pub(super) fn f32_at_least(b: f64) -> f32 {
    let v = b as f32;
    if f64::from(v) < b { v.next_up() } else { v }
}

/// The θo whose layer serves a query with `cos θo = cos`: `acos(cos)` (the argument clamped
/// to `[−1, 1]`). The one rule of every path that picks a layer ([`LeafTable::serving_cos`],
/// the fixed-ωo wavefront's `theta`), so that they pick the same layer for the same query.
#[inline]
pub(super) fn query_theta(cos: f64) -> f64 {
    cos.clamp(-1.0, 1.0).acos()
}

impl LeafTable {
    /// The table of a disc tree with the identity frame (stored coordinates are the disc's),
    /// or `None` when a leaf's rectangle or bound is not exactly the `f32` values the walk
    /// reads, or there is no leaf of positive weight: the tree's own walk serves such an
    /// interval.
    pub(super) fn of<D: RegionStats>(tree: &QuadTreeSampler<D>) -> Option<Self> {
        let mut entries = Vec::with_capacity(tree.tree().leaves().len());
        for l in tree.tree().leaves() {
            let r = l.rect;
            let (x0, y0) = (r.x0 as f32, r.y0 as f32);
            let (dx, dy) = ((r.x1 - r.x0) as f32, (r.y1 - r.y0) as f32);
            let m = l.max_bound as f32;
            let exact = f64::from(x0) == r.x0
                && f64::from(y0) == r.y0
                && f64::from(x0) + f64::from(dx) == r.x1
                && f64::from(y0) + f64::from(dy) == r.y1
                && f64::from(m) == l.max_bound
                && m.is_finite();
            if !exact {
                return None;
            }
            entries.push(Entry {
                x0,
                y0,
                dx,
                dy,
                m,
                alias: 0,
                prob: 1.0,
            });
        }
        Self::of_entries(entries)
    }

    /// The table of `entries` (their alias fields rewritten): the alias table of the weights
    /// `V_i = (dx · dy) · M_i` of the records' `f32` values; `None` when their sum is not
    /// positive and finite. No thinning bounds.
    fn of_entries(mut entries: Vec<Entry>) -> Option<Self> {
        let weights: Vec<f64> = entries
            .iter()
            .map(|e| (f64::from(e.dx) * f64::from(e.dy)) * f64::from(e.m))
            .collect();
        let total: f64 = weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        for (e, (prob, alias)) in entries.iter_mut().zip(build_alias(&weights)) {
            e.prob = prob;
            e.alias = alias;
        }
        Some(Self {
            n: index_to_f64(entries.len()),
            entries: entries.into_boxed_slice(),
            sub: Box::new([]),
            edges: Box::new([]),
            tops: Box::new([]),
            top_codes: Box::new([]),
            layers: Box::new([]),
        })
    }

    /// The table with the leaves' thinning bounds `sub` (one per leaf in the tree's order);
    /// ignored (no thinning) unless there is exactly one per entry. Without layer tables
    /// ([`LeafTable::with_layer_tables`] makes them from these bounds).
    pub(super) fn with_sub_bounds(mut self, sub: Option<&SubBounds>) -> Self {
        self.layers = Box::new([]);
        let sub = sub.filter(|s| s.codes.len() == s.layers() * self.entries.len());
        self.sub = sub
            .map_or_else(Vec::new, |s| s.codes.as_flattened().to_vec())
            .into_boxed_slice();
        self.edges = sub
            .map_or_else(Vec::new, |s| s.edges.to_vec())
            .into_boxed_slice();
        (self.tops, self.top_codes) = (Box::new([]), Box::new([]));
        let tops = sub
            .map(|s| &*s.tops)
            .filter(|t| t.len() == self.entries.len() && self.edges.is_empty());
        if let Some(tops) = tops
            && tops.iter().zip(&self.entries).any(|(&t, e)| t != e.m)
        {
            // The codes relative to `T_i`; `sub` relative to `M_i`, capped at it.
            let capped: Vec<u8> = self
                .sub
                .chunks_exact(SUB_CELLS)
                .zip(tops.iter().zip(&self.entries))
                .flat_map(|(c, (&t, e))| {
                    let m = f64::from(e.m);
                    c.iter().map(move |&q| {
                        if t == e.m {
                            q
                        } else {
                            sub_code(m, sub_bound(f64::from(t), q))
                        }
                    })
                })
                .collect();
            self.top_codes = std::mem::replace(&mut self.sub, capped.into_boxed_slice());
            self.tops = tops.into();
        }
        self
    }

    /// The table with one **layer table** per θo layer of its thinning bounds when it has any
    /// (docs/benchmarks.md §31.1; `L = 1` as well, §31.5: the single layer's table then holds
    /// the leaf bounds tightened to the codes, e.g. §31.3's rigorous ones; without thinning
    /// bounds unchanged): layer `l`'s table has the same
    /// leaves (rectangles, order), the leaf bounds
    /// `M_il = ⌈max_s sub_bound(m_i, q_ils)⌉_f32` (the largest of leaf `i`'s sub-cell bounds in
    /// layer `l`, rounded up to an `f32`; `≤ m_i`), with `m_i = M_i`, or the served bound `T_i ≥
    /// M_i` of a one-layer interval's rigorous codes ([`SubBounds::tops`], docs/benchmarks.md
    /// §32.1: then `M_il` may exceed `M_i`, and bounds `g` on the whole leaf), its own alias
    /// table over `V_il = (dx · dy) · M_il` (a leaf with `M_il = 0` is never picked), and one
    /// layer of codes re-expressed relative to `M_il`: `q'_ils = sub_code(M_il, sub_bound(m_i,
    /// q_ils))`,
    /// the smallest whose bound `sub_bound(M_il, q')` is at least the layer's sub-cell bound.
    /// So wherever `g ≤ sub_bound(m_i, q_ils)` holds for a θo of the layer, `g ≤ M_il` and
    /// `g ≤ sub_bound(M_il, q'_ils)` hold too: envelope rejection under a layer table samples
    /// `g / ∫ g` exactly as under the interval's, with fewer trials (`Σ V_il ≤ Σ V_i`); the
    /// samples drawn are other ones (another alias table). Unchanged (no layer tables) when a
    /// layer's weights do not sum to a positive finite number.
    pub(super) fn with_layer_tables(mut self) -> Self {
        self.layers = Box::new([]);
        let (l_count, n) = (self.edges.len() + 1, self.entries.len());
        if self.sub.is_empty() || self.sub.len() != l_count * n * SUB_CELLS {
            return self;
        }
        let mut layers = Vec::with_capacity(l_count);
        // One layer with served bounds `T_i`: its codes relative to them.
        let (all, tops): (&[u8], &[f32]) = if self.top_codes.is_empty() {
            (&self.sub, &[])
        } else {
            (&self.top_codes, &self.tops)
        };
        for codes in all.chunks_exact(n * SUB_CELLS) {
            let mut entries = Vec::with_capacity(n);
            let mut sub = Vec::with_capacity(n * SUB_CELLS);
            for (k, (e, c)) in self
                .entries
                .iter()
                .zip(codes.chunks_exact(SUB_CELLS))
                .enumerate()
            {
                let base = tops.get(k).copied().unwrap_or(e.m);
                let m = f64::from(base);
                let top = c.iter().map(|&q| sub_bound(m, q)).fold(0.0, f64::max);
                let ml = f32_at_least(top);
                if ml == base {
                    // The same bound: the same codes (`sub_code(m, sub_bound(m, q)) = q`).
                    sub.extend_from_slice(c);
                } else {
                    sub.extend(c.iter().map(|&q| sub_code(f64::from(ml), sub_bound(m, q))));
                }
                entries.push(Entry { m: ml, ..*e });
            }
            let Some(mut t) = Self::of_entries(entries) else {
                return self;
            };
            t.sub = sub.into_boxed_slice();
            layers.push(t);
        }
        self.layers = layers.into_boxed_slice();
        self
    }

    /// The table a query at `theta` (θo, radians) draws from: the layer table of the layer
    /// serving `theta` ([`layer_of`]) when the table has layer tables, otherwise (and for a
    /// `theta` that is not a number) the table itself.
    #[inline]
    pub(super) fn serving(&self, theta: f64) -> &Self {
        if self.layers.is_empty() {
            return self;
        }
        self.serving_layer(theta).map_or(self, |l| &self.layers[l])
    }

    /// The index of the layer table [`LeafTable::serving`] picks at `theta`, `None` when it
    /// picks the table itself.
    #[inline]
    pub(super) fn serving_layer(&self, theta: f64) -> Option<usize> {
        layer_of(&self.edges, theta).filter(|&l| l < self.layers.len())
    }

    /// [`LeafTable::serving`] for a query with `cos θo = cos` (θo by [`query_theta`], computed
    /// only for a table with layer tables).
    #[inline]
    pub(super) fn serving_cos(&self, cos: f64) -> &Self {
        if self.layers.is_empty() {
            self
        } else {
            self.serving(query_theta(cos))
        }
    }

    /// The layer tables (empty: none; see [`LeafTable::with_layer_tables`]).
    pub(super) fn layer_tables(&self) -> &[LeafTable] {
        &self.layers
    }

    /// The offset of the codes of the layer serving `theta` (θo, radians) in the table's codes
    /// (`layer · entries · SUB_CELLS`, see [`layer_of`]); for a `theta` that is not a number,
    /// an offset past every code: [`LeafTable::code_factor`] then reads 1 (`M_i` itself).
    #[inline]
    pub(super) fn layer_base(&self, theta: f64) -> usize {
        layer_of(&self.edges, theta).map_or(usize::MAX / 2, |l| l * self.entries.len() * SUB_CELLS)
    }

    /// Leaf `k`'s record as `[x0, dx, y0, dy, M_i]` (test support).
    #[cfg(test)]
    pub(super) fn leaf_record(&self, k: usize) -> [f64; 5] {
        let e = &self.entries[k];
        [e.x0, e.dx, e.y0, e.dy, e.m].map(f64::from)
    }

    /// The first layer's code of leaf `k`'s sub-cell `s` (255 without codes; test support).
    #[cfg(test)]
    pub(super) fn code(&self, k: usize, s: usize) -> u8 {
        self.sub.get(k * SUB_CELLS + s).copied().unwrap_or(255)
    }

    /// The layer count of the thinning bounds (1 without any).
    #[cfg(test)]
    pub(super) fn layers(&self) -> usize {
        self.edges.len() + 1
    }

    /// Whether the table has thinning bounds.
    pub(super) fn thins(&self) -> bool {
        !self.sub.is_empty()
    }

    /// Bytes of the records.
    pub(super) fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + std::mem::size_of_val(&*self.entries)
            + std::mem::size_of_val(&*self.sub)
            + std::mem::size_of_val(&*self.edges)
            + std::mem::size_of_val(&*self.tops)
            + std::mem::size_of_val(&*self.top_codes)
            + self.layers.iter().map(Self::bytes_used).sum::<usize>()
    }

    /// One point of `g / ∫ g` on the disc by envelope rejection under the table's bounds
    /// (`g ≤ M_i` on leaf `i`; a trial above its bound is counted in `audit.violations`), and
    /// `g` there; `None` after [`MAX_TRIALS_PER_SAMPLE`] trials (counted as exhausted). Four
    /// uniforms per trial, in one [`UniformSource::next_uniform4_split`] call (a generator's
    /// two 64-bit words, 32 bits per uniform): the leaf pick, the point's two coordinates and
    /// the acceptance test. The law is the envelope rejection's with uniforms on the grid
    /// `k · 2⁻³²`: the pick `s = u₀ · n` (exact in `f64` for `n < 2²¹` leaves) gives each leaf
    /// its alias probability to within `n · 2⁻³²` relative, the accept test `u₃ · M_i < g`
    /// its probability `g / M_i` to within `2⁻³²`. `g` is called inside the unit circle only.
    #[inline]
    pub(super) fn draw<G, U>(&self, g: &G, u: &mut U, audit: &mut Audit) -> Option<(Point2, f64)>
    where
        G: Fn(Point2) -> f64,
        U: UniformSource + ?Sized,
    {
        let (mut trials, mut violations) = (0u64, 0u64);
        let found = loop {
            if trials >= MAX_TRIALS_PER_SAMPLE {
                audit.exhausted += 1;
                break None;
            }
            let us = u.next_uniform4_split();
            trials += 1;
            let Some(([x, y], m)) = self.propose(us) else {
                continue;
            };
            let f = g([x, y]);
            violations += u64::from(f > m);
            if us[3] * m < f {
                break Some(([x, y], f));
            }
        };
        audit.trials += trials;
        audit.violations += violations;
        audit.samples += 1;
        found
    }
}

impl LeafTable {
    /// One trial of [`LeafTable::draw`] from its four uniforms `us` (leaf pick, the point's two
    /// coordinates; `us[3]`, the acceptance test, is the caller's): the point and its leaf's
    /// bound `M_i`, or `None` when the point lies outside the unit circle (a trial that
    /// evaluates nothing). `draw`'s trial, shared with the batch path's wavefront.
    #[inline(always)]
    pub(super) fn propose(&self, us: [f64; 4]) -> Option<(Point2, f64)> {
        let last = self.entries.len() - 1;
        let s = us[0] * self.n;
        let i = floor_index(s, last);
        let first = &self.entries[i];
        let e = if s - index_to_f64(i) < first.prob {
            first
        } else {
            self.entries.get(first.alias as usize).unwrap_or(first)
        };
        let x = f64::from(e.x0) + us[1] * f64::from(e.dx);
        let y = f64::from(e.y0) + us[2] * f64::from(e.dy);
        (x * x + y * y < 1.0).then_some(([x, y], f64::from(e.m)))
    }

    /// The leaf [`LeafTable::propose`] picks from its first uniform `u0`, as
    /// `[x0, dx, y0, dy, M_i]` (the record's `f32` values, exactly): `propose`'s point is
    /// `(x0 + u₁·dx, y0 + u₂·dy)`, kept inside when `x² + y² < 1`. For the wavefront's trials
    /// in vector lanes (`exact/lanes.rs`), which do that arithmetic over many trials at once;
    /// the alias fallback is a select.
    #[inline(always)]
    pub(super) fn leaf_of(&self, u0: f64) -> [f64; 5] {
        self.leaf_at(u0).1
    }

    /// [`LeafTable::leaf_of`] with the leaf's index.
    #[inline(always)]
    pub(super) fn leaf_at(&self, u0: f64) -> (usize, [f64; 5]) {
        let entries = &*self.entries;
        let last = entries.len() - 1;
        let s = u0 * self.n;
        let i = floor_index(s, last);
        let first = &entries[i];
        let alias = first.alias as usize;
        // `entries.get(alias).unwrap_or(first)` as a select.
        let k = if s - index_to_f64(i) < first.prob || alias > last {
            i
        } else {
            alias
        };
        let k = k.min(last);
        let e = &entries[k];
        (k, [e.x0, e.dx, e.y0, e.dy, e.m].map(f64::from))
    }

    /// The thinning factor of a trial in leaf `k` ([`LeafTable::leaf_at`]) whose point's
    /// uniforms `(u₁, u₂)` fall in sub-cell `sub = ⌊SUB·u₂⌋·SUB + ⌊SUB·u₁⌋`: [`sub_factor`] of
    /// its code (1 without thinning bounds), so that `M_i ·` it is the trial's thinning bound
    /// [`sub_bound`]. (The point `x0 + u₁·dx` lies in that sub-cell up to the rounding of its
    /// sum.) `base`: the serving layer's offset, [`LeafTable::layer_base`].
    #[inline(always)]
    pub(super) fn code_factor(&self, base: usize, k: usize, sub: usize) -> f64 {
        sub_factor(
            self.sub
                .get(base.wrapping_add(k * SUB_CELLS + sub))
                .copied()
                .unwrap_or(255),
        )
    }
}

/// The test-only check that every interval's table draws what its tree draws.
#[cfg(test)]
pub(super) mod walks {
    use super::*;

    /// A generator whose every four-uniform call is its split trial: the tree's walk
    /// ([`UniformSource::next_uniform4`]) and the table's
    /// ([`UniformSource::next_uniform4_split`]) then read the same four values per trial.
    struct Split<R>(R);

    impl<R: rand::Rng> UniformSource for Split<R> {
        fn next_uniform(&mut self) -> f64 {
            self.0.next_uniform()
        }
        fn next_uniform4(&mut self) -> [f64; 4] {
            self.0.next_uniform4_split()
        }
        fn next_uniform4_split(&mut self) -> [f64; 4] {
            self.0.next_uniform4_split()
        }
    }

    /// Test support: every interval of `set` has a table, and its walk draws the very points of
    /// the interval tree's own walk given the same four uniforms per trial (same bits, same
    /// trial, violation and sample counts, the streams in step) for two test densities, one
    /// below most leaves' bounds and one above many (the violations counted alike); and from a
    /// plain generator the table's walk consumes two 64-bit words per trial. Returns the number
    /// of walks compared.
    pub(in crate::exact) fn assert_table_walks_match_trees(set: &super::super::ExactSet) -> usize {
        use partition_sampler::diagnostics::AuditedDraws;
        use rand::rngs::Xoshiro256PlusPlus;
        use rand::{Rng, SeedableRng};

        let mut checked = 0;
        for cell in &set.cells {
            assert_eq!(cell.tables.len(), cell.intervals.len());
            for (iv, table) in cell.intervals.iter().zip(&cell.tables) {
                let table = table.as_ref().expect("a table for every interval");
                let m0 = table
                    .entries
                    .iter()
                    .map(|e| f64::from(e.m))
                    .fold(0.0, f64::max);
                for scale in [0.06, 0.6] {
                    let g = |p: [f64; 2]| scale * m0 * (1.0 - 0.5 * p[0] * p[0]);
                    let (mut r1, mut r2) = (
                        Split(Xoshiro256PlusPlus::seed_from_u64(3)),
                        Split(Xoshiro256PlusPlus::seed_from_u64(3)),
                    );
                    let (mut a1, mut a2) = (Audit::default(), Audit::default());
                    for _ in 0..100 {
                        let want = iv.tree.sample_envelope_of(&g, &mut r1, &mut a1);
                        let got = table.draw(&g, &mut r2, &mut a2);
                        assert_eq!(got, want);
                    }
                    assert_eq!(a1, a2);
                    assert_eq!(r1.next_uniform(), r2.next_uniform());
                    // Two words per trial from a plain generator.
                    let mut r3 = Xoshiro256PlusPlus::seed_from_u64(3);
                    let mut a3 = Audit::default();
                    for _ in 0..100 {
                        table.draw(&g, &mut r3, &mut a3);
                    }
                    assert_eq!(a3, a2);
                    let mut r4 = Xoshiro256PlusPlus::seed_from_u64(3);
                    for _ in 0..2 * a3.trials {
                        r4.next_u64();
                    }
                    assert_eq!(r3.next_u64(), r4.next_u64());
                    checked += 1;
                }
            }
        }
        checked
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thinning codes: `sub_bound(m, sub_code(m, b))` is at least `b` and the smallest code
    /// that is (so the stored bound is the image map's rounded up by at most `m / 255`); `m`
    /// itself at 255, and 255 for `b ≥ m`, NaN or `m ≤ 0`. Fails with the code rounded to
    /// nearest (`.round()` and no correction loops: values below `b`).
    #[test]
    fn sub_codes_round_the_bound_up_by_at_most_one_step() {
        let mut checked = 0;
        for &m in &[1e-6f64, 0.37, 1.0, 3.3, 1234.5] {
            assert_eq!(sub_bound(m, 255), m);
            for k in 0..=2000 {
                let b = m * f64::from(k) / 2000.0;
                let q = sub_code(m, b);
                assert!(sub_bound(m, q) >= b, "m {m} b {b} q {q}");
                if q > 0 {
                    assert!(
                        sub_bound(m, q - 1) < b,
                        "m {m} b {b} q {q}: not the smallest"
                    );
                }
                assert!(sub_bound(m, q) - b <= m / 255.0 * (1.0 + 1e-12));
                checked += 1;
            }
            assert_eq!(sub_code(m, 2.0 * m), 255);
            assert_eq!(sub_code(m, f64::NAN), 255);
        }
        assert_eq!(sub_code(0.0, 0.0), 255);
        assert_eq!(sub_code(-1.0, 0.5), 255);
        assert_eq!(checked, 5 * 2001);
    }
}
