//! The two densities of an exact-sampler interval, both on the unit disc of the interval's
//! [`DiscMap`]: the query density at one outgoing direction, and the envelope over the
//! interval that the tree is built from.

use std::sync::{Arc, Mutex};

use brdf::measured::rgl::PreparedSlice;
use brdf::{Brdf, Outgoing, RglBrdf, Vec3, rotate_z};
use partition_sampler::{Density, Point2};
use rustc_hash::FxHashMap;

use crate::disc::{DirectionBlock, DiscMap, count_evaluations};
use crate::layout::Turn;

/// The disc density of `f_r(ωo, R_rot ·) cos θi` at one outgoing direction:
/// `g(x) = f_r(ωo, R_rot h⁻¹(x))` (projected map) or `2 f_r(ωo, R_rot h_e⁻¹(x)) cos θi`
/// (equal-area map), 0 off the open disc. `R_rot` is the rotation about the normal by `rot`
/// (the tree's frame is the interval's azimuth; isotropic BRDFs use `ωo` at φ = 0 and
/// `rot = 0`). Its integral over the disc is the directional albedo at `ωo`. Every evaluation is
/// counted in [`crate::disc::thread_evaluations`].
#[derive(Clone, Copy)]
pub(crate) struct QueryDensity<'a> {
    brdf: &'a dyn Brdf,
    /// `ωo` as the BRDF prepared it ([`Brdf::prepare`]).
    wo: Outgoing,
    /// `(sin, cos)` of `rot`; `None` for no rotation.
    rot: Option<(f64, f64)>,
    map: DiscMap,
}

impl<'a> QueryDensity<'a> {
    /// The density of `brdf` at `wo` in a frame turned by `rot`. An isotropic BRDF is evaluated
    /// at `R_{−rot} ωo` instead (the same value, `f(ωo, R ωi) = f(R⁻¹ωo, ωi)`), which saves
    /// the rotation of every trial point.
    pub(crate) fn new(brdf: &'a dyn Brdf, wo: Vec3, rot: f64, map: DiscMap) -> Self {
        Self::in_frame(brdf, brdf.is_isotropic(), &wo, Turn::from_angle(rot), map)
    }

    /// [`QueryDensity::new`] for the rotation `turn` held as `(cos, sin)`: an isotropic BRDF
    /// (`isotropic`: `brdf.is_isotropic()`, known to the caller) is evaluated at `R_{−turn} ωo`
    /// (no trigonometry), an anisotropic one rotates the trial points.
    #[inline]
    pub(crate) fn in_frame(
        brdf: &'a dyn Brdf,
        isotropic: bool,
        wo: &Vec3,
        turn: Turn,
        map: DiscMap,
    ) -> Self {
        let (wo, rot) = if turn == Turn::IDENTITY {
            (*wo, None)
        } else if isotropic {
            (turn.undo(wo), None)
        } else {
            (*wo, Some((turn.sin, turn.cos)))
        };
        Self {
            brdf,
            wo: brdf.prepare(&wo),
            rot,
            map,
        }
    }

    #[inline]
    pub(crate) fn at(&self, p: Point2) -> f64 {
        let r2 = p[0] * p[0] + p[1] * p[1];
        if !(r2 < 1.0) {
            return 0.0;
        }
        count_evaluations(1);
        let v = self.map.to_direction(p);
        let wi = match self.rot {
            None => v,
            Some((s, c)) => Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z),
        };
        let f = self.brdf.eval_prepared(&self.wo, &wi);
        match self.map {
            DiscMap::Projected => f,
            DiscMap::EqualArea => 2.0 * v.z * f,
        }
    }
}

impl Density for QueryDensity<'_> {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        self.at(p)
    }
}

/// Values `f_r(ωo_n, R_{δ_n} ωi)` of one node, keyed by the bits of `ωi` (exact: a hit
/// returns the value the BRDF gives for that very direction).
type ValueMap = FxHashMap<[u64; 3], f64>;

/// Every value known for one bound node: the maps of the builds that evaluated it, largest
/// first, shared (not copied) between an interval and its descendants. A map no other
/// `NodeValues` shares goes back to [`MAP_POOL`] when this one is dropped.
#[derive(Clone, Default)]
pub(crate) struct NodeValues {
    layers: Vec<Arc<ValueMap>>,
}

impl Drop for NodeValues {
    fn drop(&mut self) {
        for layer in self.layers.drain(..) {
            if let Ok(map) = Arc::try_unwrap(layer) {
                MAP_POOL.give(map);
            }
        }
    }
}

/// Freed storage kept for the next interval's nodes, instead of handing it back to the
/// allocator (which returned the pages of a freed heap top to the kernel: the next interval's
/// buffers and maps then faulted in zero-filled pages again, ≈ 7·10⁴ minor faults and
/// 0.2–0.3 s of system time on `cc_ibiza_sunset`'s build, docs/benchmarks.md §28.4). Holds
/// at most `max` items, emptied (their capacity kept); an item taken is the smallest one of
/// at least the capacity asked for, else the largest (which then grows). Only storage is
/// reused: an item is empty when taken, so no value passes from one build to another.
struct Pool<T> {
    items: Mutex<Vec<T>>,
    max: usize,
}

/// Storage [`Pool`] can keep: emptied, and its capacity read.
trait Reusable: Default {
    fn empty(&mut self);
    fn room(&self) -> usize;
}

impl<T> Reusable for Vec<T> {
    fn empty(&mut self) {
        self.clear();
    }
    fn room(&self) -> usize {
        self.capacity()
    }
}

impl Reusable for ValueMap {
    fn empty(&mut self) {
        self.clear();
    }
    fn room(&self) -> usize {
        self.capacity()
    }
}

impl<T: Reusable> Pool<T> {
    const fn new(max: usize) -> Self {
        Self {
            items: Mutex::new(Vec::new()),
            max,
        }
    }

    /// An empty item, of capacity at least `room` when the pool has one (the smallest such),
    /// else the pool's largest, else a new one.
    fn take(&self, room: usize) -> T {
        let Ok(mut items) = self.items.lock() else {
            return T::default();
        };
        let pick = items
            .iter()
            .enumerate()
            .filter(|(_, t)| t.room() >= room)
            .min_by_key(|(_, t)| t.room())
            .or_else(|| items.iter().enumerate().max_by_key(|(_, t)| t.room()))
            .map(|(k, _)| k);
        pick.map(|k| items.swap_remove(k)).unwrap_or_default()
    }

    /// The empty item of largest capacity the pool has, else a new one.
    fn take_largest(&self) -> T {
        self.take(usize::MAX)
    }

    /// Keeps `item`'s storage (emptied) unless it has none or the pool is full.
    fn give(&self, mut item: T) {
        if item.room() == 0 {
            return;
        }
        item.empty();
        if let Ok(mut items) = self.items.lock()
            && items.len() < self.max
        {
            items.push(item);
        }
    }
}

/// The caching nodes' per-worker buffers ([`FreshBuffer`]): an interval of ≈ 5–9 caching
/// nodes holds `threads + 1` buffers each.
static BUFFER_POOL: Pool<Vec<([u64; 3], f64)>> = Pool::new(48);

/// The nodes' value maps ([`EnvelopeNode::into_values`]), freed with the last
/// [`NodeValues`] that shares them.
static MAP_POOL: Pool<ValueMap> = Pool::new(32);

impl NodeValues {
    #[inline]
    fn get(&self, key: &[u64; 3]) -> Option<f64> {
        self.layers.iter().find_map(|m| m.get(key).copied())
    }

    /// How many values the layers hold (a test's view).
    #[cfg(test)]
    pub(crate) fn known(&self) -> usize {
        self.layers.iter().map(|m| m.len()).sum()
    }
}

/// The identity of a bound node within its azimuth cell: `θ_n = (π/2) · num / den` with the
/// set-wide denominator, and the bits of `δ_n`. A split interval's children compute their
/// shared nodes with the same `num` (see `exact::Grid`), hence the same `ωo_n` bits.
pub(crate) type NodeKey = (u64, u64);

/// Directions per block of [`IntervalEnvelope::eval_block`] (the image map's lattice asks
/// for 64 points at a time).
pub(crate) const ENVELOPE_BLOCK: usize = 64;

/// Directions per group of the RGL block evaluation's vector lanes (`measured/rgl/lanes.rs`
/// pads a shorter group to this many).
const LANES_GROUP: usize = 16;

/// A tail of fewer misses than this (after the full groups) is evaluated one by one
/// (`eval_in_slice`, the same values): ≈ 460 instructions per padded lane against ≈ 660 per
/// scalar evaluation (AVX2, docs/benchmarks.md §25.3, §27.4).
const LANES_MIN_TAIL: usize = 8;

/// One thread's fresh values, on a cache line of its own (the image map evaluates in
/// parallel; each worker appends to its own buffer, uncontended).
/// Its storage comes from [`BUFFER_POOL`] at the first value ([`FreshBuffer::keep`]) and goes
/// back there.
#[repr(align(128))]
#[derive(Default)]
struct FreshBuffer(Mutex<Vec<([u64; 3], f64)>>);

impl FreshBuffer {
    /// Appends `values` to the buffer of this worker (the pool's largest storage when it has
    /// none yet).
    fn keep(&self, values: impl Iterator<Item = ([u64; 3], f64)>) {
        if let Ok(mut b) = self.0.lock() {
            if b.capacity() == 0 {
                *b = BUFFER_POOL.take_largest();
            }
            b.extend(values);
        }
    }

    /// Its values, leaving it empty.
    fn take(&mut self) -> Vec<([u64; 3], f64)> {
        std::mem::take(self.0.get_mut().unwrap_or_else(|e| e.into_inner()))
    }
}

impl Drop for FreshBuffer {
    fn drop(&mut self) {
        BUFFER_POOL.give(self.take());
    }
}

/// One bound node of an [`IntervalEnvelope`].
pub(crate) struct EnvelopeNode {
    pub(crate) key: NodeKey,
    /// The node's `ωo`, prepared by the interval's BRDF.
    pub(crate) wo: Outgoing,
    pub(crate) delta: f64,
    /// Values this node already had in the interval's parent (same node, same lattice).
    inherited: Option<Arc<NodeValues>>,
    /// The RGL material's θo slice blended at this node ([`RglBrdf::prepare_slice`]), for an
    /// envelope that evaluates through it ([`IntervalEnvelope::new`]).
    slice: Option<PreparedSlice>,
    /// Values evaluated by this build, kept for the children when caching is on: one buffer
    /// per worker thread and one for callers outside the pool.
    fresh: Option<Vec<FreshBuffer>>,
}

impl EnvelopeNode {
    /// A node at `wo` turned by `delta`; `cache`: keep the values this build evaluates.
    pub(crate) fn new(
        key: NodeKey,
        wo: Outgoing,
        delta: f64,
        inherited: Option<Arc<NodeValues>>,
        cache: bool,
    ) -> Self {
        Self {
            key,
            wo,
            delta,
            inherited,
            slice: None,
            fresh: cache.then(|| {
                (0..=rayon::current_num_threads())
                    .map(|_| FreshBuffer::default())
                    .collect()
            }),
        }
    }

    fn value(&self, brdf: &dyn Brdf, rgl: Option<&RglBrdf>, wi: &Vec3) -> f64 {
        let key = [wi.x.to_bits(), wi.y.to_bits(), wi.z.to_bits()];
        if let Some(v) = self.inherited.as_ref().and_then(|m| m.get(&key)) {
            return v;
        }
        let w = if self.delta == 0.0 {
            *wi
        } else {
            rotate_z(wi, self.delta)
        };
        let v = match (rgl, &self.slice) {
            // `eval_prepared`'s value bit for bit, read from the one blended slice.
            (Some(rgl), Some(slice)) => rgl.eval_in_slice(slice, &self.wo, &w),
            _ => brdf.eval_prepared(&self.wo, &w),
        };
        if let Some(buffers) = &self.fresh {
            let worker = rayon::current_thread_index().map_or(0, |i| i + 1);
            if let Some(b) = buffers.get(worker) {
                b.keep(std::iter::once((key, v)));
            }
        }
        v
    }

    /// `out[k] =` [`value`](Self::value)`(wi[k])` for every `k` (`wi.len() ≤`
    /// [`ENVELOPE_BLOCK`], `out` as long), bit for bit: the inherited values looked up, the
    /// misses evaluated together — for an RGL node with its slice in vector lanes
    /// ([`RglBrdf::eval_block_in_slice`], `eval_in_slice` bit for bit) — and kept with one
    /// lock of the worker's buffer per block.
    fn values_block(&self, brdf: &dyn Brdf, rgl: Option<&RglBrdf>, wi: &[Vec3], out: &mut [f64]) {
        debug_assert!(wi.len() <= ENVELOPE_BLOCK && out.len() == wi.len());
        let mut slot = [0usize; ENVELOPE_BLOCK];
        let mut turned = [Vec3::new(0.0, 0.0, 0.0); ENVELOPE_BLOCK];
        let mut m = 0;
        for (k, w) in wi.iter().enumerate() {
            let key = [w.x.to_bits(), w.y.to_bits(), w.z.to_bits()];
            if let Some(v) = self.inherited.as_ref().and_then(|n| n.get(&key)) {
                out[k] = v;
                continue;
            }
            slot[m] = k;
            turned[m] = if self.delta == 0.0 {
                *w
            } else {
                rotate_z(w, self.delta)
            };
            m += 1;
        }
        if m == 0 {
            return;
        }
        let mut fresh = [0.0f64; ENVELOPE_BLOCK];
        match (rgl, &self.slice) {
            (Some(rgl), Some(slice)) => {
                // The lanes evaluate groups of `LANES_GROUP`, padded: a short tail (the few
                // misses of a node whose values are mostly inherited) costs less one by one.
                let tail = m % LANES_GROUP;
                let lanes = if tail < LANES_MIN_TAIL { m - tail } else { m };
                rgl.eval_block_in_slice(slice, &self.wo, &turned[..lanes], &mut fresh[..lanes]);
                for (v, w) in fresh[lanes..m].iter_mut().zip(&turned[lanes..m]) {
                    *v = rgl.eval_in_slice(slice, &self.wo, w);
                }
            }
            _ => {
                for (v, w) in fresh[..m].iter_mut().zip(&turned[..m]) {
                    *v = brdf.eval_prepared(&self.wo, w);
                }
            }
        }
        for (&k, &v) in slot[..m].iter().zip(&fresh[..m]) {
            out[k] = v;
        }
        if let Some(buffers) = &self.fresh {
            let worker = rayon::current_thread_index().map_or(0, |i| i + 1);
            if let Some(b) = buffers.get(worker) {
                b.keep(slot[..m].iter().zip(&fresh[..m]).map(|(&k, &v)| {
                    let w = &wi[k];
                    ([w.x.to_bits(), w.y.to_bits(), w.z.to_bits()], v)
                }));
            }
        }
    }

    /// Whether this node keeps the values it evaluates.
    pub(crate) fn caches(&self) -> bool {
        self.fresh.is_some()
    }

    /// The BRDF evaluations this node made and kept (0 for a node that does not cache): one
    /// entry of its buffers per evaluation.
    fn fresh_evaluations(&self) -> u64 {
        self.fresh.as_ref().map_or(0, |buffers| {
            buffers
                .iter()
                .map(|b| b.0.lock().map_or(0, |v| v.len() as u64))
                .sum()
        })
    }

    /// Every value known for this node (inherited and fresh), for the children.
    pub(crate) fn into_values(self) -> (NodeKey, Arc<NodeValues>) {
        let mut values = self.inherited.map(Arc::unwrap_or_clone).unwrap_or_default();
        let mut buffers: Vec<FreshBuffer> = self.fresh.unwrap_or_default();
        let len = buffers
            .iter_mut()
            .map(|b| b.0.get_mut().map_or(0, |v| v.len()))
            .sum();
        // A map from the pool (emptied; its capacity grown to `len` if short).
        let mut fresh = MAP_POOL.take(len);
        fresh.reserve(len);
        for b in &mut buffers {
            // The buffer's storage goes back to the pool when `buffers` is dropped.
            if let Ok(v) = b.0.get_mut() {
                fresh.extend(v.drain(..));
            }
        }
        drop(buffers);
        if !fresh.is_empty() {
            values.layers.push(Arc::new(fresh));
            values.layers.sort_by_key(|m| std::cmp::Reverse(m.len()));
        } else {
            MAP_POOL.give(fresh);
        }
        (self.key, Arc::new(values))
    }
}

/// The envelope of an interval as a BRDF of the incident direction only:
/// `F(ωi) = max_n f_r(ωo_n, R_{δ_n} ωi)` over the interval's bound nodes
/// `(θ_n, φ_k + δ_n)` (the outgoing argument of [`Brdf::eval`] is ignored). Wrapped in a
/// [`crate::DiscBrdf`] it is the density the interval's tree is built from, with the set's image
/// map, rim band, safety factor and audit. Node values the parent interval already evaluated
/// are looked up instead of evaluated again (bit-identical: same node, same `ωi`).
pub(crate) struct IntervalEnvelope {
    pub(crate) brdf: Arc<dyn Brdf>,
    /// `brdf` itself when it is an RGL material whose nodes carry their blended slices: the
    /// nodes are evaluated through [`RglBrdf::eval_in_slice`] (the same values).
    rgl: Option<RglBrdf>,
    pub(crate) nodes: Vec<EnvelopeNode>,
}

impl IntervalEnvelope {
    /// The envelope `max_n f_r(ωo_n, R_{δ_n} ·)` of `brdf` over `nodes`. With `slices`, an RGL
    /// material (`brdf` itself, see [`rgl_itself`]) blends each node's θo slice once
    /// ([`RglBrdf::prepare_slice`], ≈ 3.4·10⁴ table entries) and evaluates the node there:
    /// `eval_prepared`'s values bit for bit (the format's contract, tested in `brdf`), at
    /// ≈ 3/4 of its cost, so the envelope and the tree built on it do not change.
    pub(crate) fn new(brdf: Arc<dyn Brdf>, mut nodes: Vec<EnvelopeNode>, slices: bool) -> Self {
        let rgl = if slices { rgl_itself(&brdf) } else { None };
        if let Some(rgl) = &rgl {
            for node in &mut nodes {
                node.slice = Some(rgl.prepare_slice(node.wo.wo()));
            }
        }
        Self { brdf, rgl, nodes }
    }

    /// `out[k] = F(wi[k])` ([`Brdf::eval`] of the envelope) for `k < min(wi.len(), out.len())`,
    /// bit for bit: node by node over blocks of [`ENVELOPE_BLOCK`] directions (each node's
    /// misses evaluated together, [`EnvelopeNode::values_block`]), the max taken in node
    /// order as `eval` takes it. What the image map's lattice calls through
    /// [`DiscBrdf`](crate::DiscBrdf)'s `eval_block` ([`DirectionBlock`]).
    pub(crate) fn eval_block(&self, wi: &[Vec3], out: &mut [f64]) {
        let mut node = [0.0f64; ENVELOPE_BLOCK];
        for (wi, out) in wi
            .chunks(ENVELOPE_BLOCK)
            .zip(out.chunks_mut(ENVELOPE_BLOCK))
        {
            let n = wi.len().min(out.len());
            let (wi, out) = (&wi[..n], &mut out[..n]);
            out.fill(0.0);
            for nd in &self.nodes {
                nd.values_block(self.brdf.as_ref(), self.rgl.as_ref(), wi, &mut node[..n]);
                for (m, &v) in out.iter_mut().zip(&node[..n]) {
                    *m = m.max(v);
                }
            }
        }
    }

    /// BRDF evaluations made by the nodes that cache (their misses, one kept value each; the
    /// other nodes' are counted by the image map's counter). Counted from the nodes' buffers
    /// rather than by a shared atomic counter, which the image map's workers contended for at
    /// every miss.
    pub(crate) fn evaluations(&self) -> u64 {
        self.nodes.iter().map(EnvelopeNode::fresh_evaluations).sum()
    }
}

impl DirectionBlock for IntervalEnvelope {
    #[inline]
    fn eval_directions(&self, wi: &[Vec3], out: &mut [f64]) {
        self.eval_block(wi, out);
    }
}

/// The RGL material `brdf` is, when it is one itself: not a wrapper that forwards `as_any`
/// (such as [`brdf::CountingBrdf`], whose evaluations must go through it to be counted; a
/// wrapped material keeps the two-slice path, with the same values).
pub(crate) fn rgl_itself(brdf: &Arc<dyn Brdf>) -> Option<RglBrdf> {
    let rgl = brdf.as_any()?.downcast_ref::<RglBrdf>()?;
    let same = std::ptr::addr_eq(Arc::as_ptr(brdf), rgl as *const RglBrdf);
    same.then(|| rgl.clone())
}

impl Brdf for IntervalEnvelope {
    fn eval(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        self.nodes.iter().fold(0.0f64, |m, node| {
            m.max(node.value(self.brdf.as_ref(), self.rgl.as_ref(), wi))
        })
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Every node lies in the xz-plane (isotropic layouts): the max of even functions of y
        // is even.
        self.brdf.is_mirror_symmetric()
            && self
                .nodes
                .iter()
                .all(|n| n.wo.wo().y == 0.0 && n.delta == 0.0)
    }
    fn bounded_at_horizon(&self) -> bool {
        self.brdf.bounded_at_horizon()
    }
    fn name(&self) -> &str {
        "interval-envelope"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::{CountingBrdf, direction_from_radians};

    /// A BRDF that counts its evaluations on every thread (the thread-local count of
    /// [`CountingBrdf`] cannot be summed over a pool's workers).
    struct Tally {
        inner: Arc<dyn Brdf>,
        calls: std::sync::atomic::AtomicU64,
    }

    impl Brdf for Tally {
        fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            self.calls
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.inner.eval(wo, wi)
        }
        fn name(&self) -> &str {
            "tally"
        }
    }

    /// The storage pools of the node buffers and maps (docs/benchmarks.md §28.4): an item
    /// taken is empty whatever was given back, the smallest of at least the room asked for
    /// (else the largest), and a full pool keeps no more. Fails when `give` keeps an item
    /// without emptying it (tried: the taken buffer holds the given values).
    #[test]
    fn pooled_storage_comes_back_empty_and_best_fitting() {
        let pool: Pool<Vec<([u64; 3], f64)>> = Pool::new(2);
        let filled = |n: usize| -> Vec<([u64; 3], f64)> {
            let mut v = Vec::with_capacity(n);
            v.extend((0..n as u64).map(|k| ([k, k, k], k as f64)));
            v
        };
        pool.give(filled(100));
        pool.give(filled(1000));
        pool.give(filled(10)); // full: not kept
        pool.give(Vec::new()); // no storage: not kept
        let a = pool.take(50);
        assert!(a.is_empty() && a.capacity() >= 100 && a.capacity() < 1000);
        let b = pool.take_largest();
        assert!(b.is_empty() && b.capacity() >= 1000);
        assert_eq!(pool.take(1).capacity(), 0, "the pool is empty");
        let mut maps: Pool<ValueMap> = Pool::new(1);
        let mut m = ValueMap::default();
        m.insert([1, 2, 3], 4.0);
        maps.give(m);
        let m = maps.take(0);
        assert!(m.is_empty() && m.capacity() >= 1);
        maps.max = 0;
        maps.give(m);
        assert_eq!(maps.take(0).capacity(), 0, "a pool of 0 keeps nothing");
    }

    /// Issue 29 (docs/benchmarks.md §26.5): [`IntervalEnvelope::evaluations`], counted from the
    /// caching nodes' buffers instead of a shared atomic counter, is every evaluation the
    /// caching nodes made, also when the image map's workers evaluate in parallel (each worker
    /// appends to its own buffer), and none of the lookups the inherited values answer. A
    /// count from one buffer only (tried: the buffer of the calling thread) misses the pool's
    /// evaluations and fails.
    #[test]
    fn envelope_evaluations_are_the_caching_nodes_misses_on_every_worker() {
        let tally = Arc::new(Tally {
            inner: Arc::from(brdf::parse_spec("phong:n=40").unwrap()),
            calls: std::sync::atomic::AtomicU64::new(0),
        });
        let brdf: Arc<dyn Brdf> = tally.clone();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let dirs: Vec<Vec3> = (0..3000u32)
            .map(|k| {
                let t = 1.5 * ((k as f64 + 0.5) / 3000.0).sqrt();
                direction_from_radians(t, 2.399_963 * k as f64)
            })
            .collect();
        let node = |k: u64, deg: f64, inherited: Option<Arc<NodeValues>>, cache: bool| {
            let wo = direction_from_radians(deg.to_radians(), 0.0);
            EnvelopeNode::new((k, 0), brdf.prepare(&wo), 0.0, inherited, cache)
        };
        let wo = Vec3::new(0.0, 0.0, 1.0);
        // Every worker of the pool evaluates its share of `points` (`broadcast`: each worker
        // runs once, whatever the scheduling), the calling thread (outside the pool) the rest.
        let spread = |env: &IntervalEnvelope, points: &[Vec3]| {
            let n = points.len();
            pool.broadcast(|w| {
                for wi in &points[w.index() * n / 4..(w.index() + 1) * n / 4] {
                    env.eval(&wo, wi);
                }
            });
            for wi in &points[3 * n / 4..] {
                env.eval(&wo, wi);
            }
        };
        // A parent with two caching nodes and one that does not cache.
        let parent = pool.install(|| {
            IntervalEnvelope::new(
                Arc::clone(&brdf),
                vec![
                    node(0, 20.0, None, true),
                    node(1, 25.0, None, true),
                    node(2, 30.0, None, false),
                ],
                true,
            )
        });
        spread(&parent, &dirs);
        let calls = tally.calls.load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(calls, 3 * dirs.len() as u64);
        assert_eq!(parent.evaluations(), 2 * dirs.len() as u64);
        let workers = parent.nodes[0]
            .fresh
            .as_ref()
            .unwrap()
            .iter()
            .filter(|b| b.0.lock().is_ok_and(|v| !v.is_empty()))
            .count();
        assert_eq!(workers, 4, "buffers written");
        // A child inherits node 1's values: its lookups are not evaluations, its fresh node's
        // misses are, and only the directions the parent did not see miss.
        let values: Vec<_> = parent
            .nodes
            .into_iter()
            .filter(|n| n.caches())
            .map(EnvelopeNode::into_values)
            .collect();
        let inherited = values
            .iter()
            .find(|(k, _)| k.0 == 1)
            .map(|(_, v)| Arc::clone(v));
        let before = tally.calls.load(std::sync::atomic::Ordering::Relaxed);
        let child = pool.install(|| {
            IntervalEnvelope::new(
                Arc::clone(&brdf),
                vec![node(1, 25.0, inherited, true), node(3, 22.5, None, true)],
                true,
            )
        });
        let more: Vec<Vec3> = dirs
            .iter()
            .copied()
            .chain((0..500u32).map(|k| direction_from_radians(0.1 + 0.002 * k as f64, 0.5)))
            .collect();
        spread(&child, &more);
        let made = tally.calls.load(std::sync::atomic::Ordering::Relaxed) - before;
        assert_eq!(made, (dirs.len() + 500 + 500) as u64);
        assert_eq!(child.evaluations(), made);
    }

    /// Issue 29 (docs/benchmarks.md §25.4): an envelope whose RGL nodes carry their blended
    /// slices gives every node's value of the two-slice path bit for bit (and so the same
    /// tree), at 2 000 incident directions over the hemisphere; a wrapped material (the
    /// counting wrapper of the counted builds) keeps the two-slice path.
    #[test]
    fn envelope_slices_change_nothing_but_the_cost() {
        let Some(rgl) = super::super::tests::paper_white_fixture() else {
            return;
        };
        let brdf: Arc<dyn Brdf> = Arc::new(rgl);
        let counted: Arc<dyn Brdf> = Arc::new(CountingBrdf(Arc::clone(&brdf)));
        assert!(rgl_itself(&brdf).is_some());
        assert!(rgl_itself(&counted).is_none());
        let nodes = || -> Vec<EnvelopeNode> {
            [20.0f64, 21.5, 23.0, 24.5, 26.0, 88.9]
                .iter()
                .enumerate()
                .map(|(k, deg)| {
                    let wo = direction_from_radians(deg.to_radians(), 0.0);
                    EnvelopeNode::new((k as u64, 0), brdf.prepare(&wo), 0.0, None, false)
                })
                .collect()
        };
        let fast = IntervalEnvelope::new(Arc::clone(&brdf), nodes(), true);
        let slow = IntervalEnvelope::new(Arc::clone(&brdf), nodes(), false);
        assert!(fast.nodes.iter().all(|n| n.slice.is_some()));
        assert!(fast.rgl.is_some() && slow.rgl.is_none());
        let wrapped = IntervalEnvelope::new(counted, nodes(), true);
        assert!(wrapped.rgl.is_none() && wrapped.nodes.iter().all(|n| n.slice.is_none()));
        let mut positive = 0;
        for k in 0..2000u32 {
            let t = (std::f64::consts::FRAC_PI_2 - 1e-4) * ((k as f64 + 0.5) / 2000.0).sqrt();
            let wi = direction_from_radians(t, 2.399_963 * k as f64);
            for (a, b) in fast.nodes.iter().zip(&slow.nodes) {
                let (va, vb) = (
                    a.value(brdf.as_ref(), fast.rgl.as_ref(), &wi),
                    b.value(brdf.as_ref(), None, &wi),
                );
                assert_eq!(va.to_bits(), vb.to_bits(), "θi {t}: {va} vs {vb}");
                positive += usize::from(va > 0.0);
            }
            let wo = Vec3::new(0.0, 0.0, 1.0);
            assert_eq!(fast.eval(&wo, &wi).to_bits(), slow.eval(&wo, &wi).to_bits());
        }
        assert!(positive > 6000, "{positive} positive values");
    }

    /// Issue 29 (docs/benchmarks.md §27.4): the envelope evaluated in blocks (each node's
    /// misses together; RGL nodes in vector lanes at their slices) is `eval` bit for bit —
    /// with inherited values, caching and non-caching nodes, a turned node (`δ ≠ 0`) and a
    /// node whose slice does not hold its blend —, keeps the same fresh values (same count,
    /// same map), and the disc density built on it (`DiscBrdf::with_blocks`, both maps, a zero
    /// floor, points on and outside the circle) is its `eval` bit for bit.
    #[test]
    fn envelope_blocks_are_eval_bit_for_bit() {
        use crate::disc::{DiscBrdf, DiscMap};
        use partition_sampler::Density;
        let Some(rgl) = super::super::tests::paper_white_fixture() else {
            return;
        };
        let brdf: Arc<dyn Brdf> = Arc::new(rgl);
        let dirs: Vec<Vec3> = (0..3001u32)
            .map(|k| {
                let t = (std::f64::consts::FRAC_PI_2 - 1e-4) * ((k as f64 + 0.5) / 3001.0).sqrt();
                direction_from_radians(t, 2.399_963 * k as f64)
            })
            .collect();
        let make = |inherited: Option<Arc<NodeValues>>| -> IntervalEnvelope {
            let nodes = [(20.0f64, 0.0), (23.0, 0.0), (26.0, 0.3), (88.9, 0.0)]
                .iter()
                .enumerate()
                .map(|(k, &(deg, delta))| {
                    let wo = direction_from_radians(deg.to_radians(), 0.0);
                    let inh = if k == 1 { inherited.clone() } else { None };
                    EnvelopeNode::new((k as u64, 0), brdf.prepare(&wo), delta, inh, k != 2)
                })
                .collect();
            let mut env = IntervalEnvelope::new(Arc::clone(&brdf), nodes, true);
            // The last node's slice is another angle's: `eval_in_slice` falls back to the
            // two-slice tables, and so must the block.
            let other = env
                .rgl
                .as_ref()
                .unwrap()
                .prepare_slice(&direction_from_radians(0.5, 0.0));
            env.nodes[3].slice = Some(other);
            env
        };
        // A parent evaluated pointwise hands node 1's values (of every other direction) down.
        let parent = make(None);
        let wo = Vec3::new(0.0, 0.0, 1.0);
        for wi in dirs.iter().step_by(2) {
            parent.eval(&wo, wi);
        }
        let inherited = parent
            .nodes
            .into_iter()
            .map(EnvelopeNode::into_values)
            .find(|(k, _)| k.0 == 1)
            .map(|(_, v)| v);
        let (pointwise, block) = (make(inherited.clone()), make(inherited));
        let want: Vec<f64> = dirs.iter().map(|wi| pointwise.eval(&wo, wi)).collect();
        let mut got = vec![f64::NAN; dirs.len()];
        // Blocks of every length up to two full blocks and a partial one.
        let mut at = 0;
        for len in (1..=ENVELOPE_BLOCK).chain([2 * ENVELOPE_BLOCK + 7]).cycle() {
            if at == dirs.len() {
                break;
            }
            let end = (at + len).min(dirs.len());
            block.eval_block(&dirs[at..end], &mut got[at..end]);
            at = end;
        }
        let mut positive = 0;
        for (k, (a, b)) in got.iter().zip(&want).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "{k}: {a} vs {b}");
            positive += usize::from(*a > 0.0);
        }
        assert!(positive > 2500, "{positive}");
        assert_eq!(block.evaluations(), pointwise.evaluations());
        assert!(block.evaluations() > 0);
        let maps = |env: IntervalEnvelope| -> Vec<Vec<(u64, u64, u64, u64)>> {
            env.nodes
                .into_iter()
                .filter(|n| n.caches())
                .map(|n| {
                    let (_, v) = n.into_values();
                    let mut all: Vec<_> = v
                        .layers
                        .iter()
                        .flat_map(|m| m.iter().map(|(k, v)| (k[0], k[1], k[2], v.to_bits())))
                        .collect();
                    all.sort_unstable();
                    all
                })
                .collect()
        };
        // The disc density on an envelope, pointwise and by blocks.
        let env = Arc::new(make(None));
        let points: Vec<Point2> = (0..2500u32)
            .map(|k| {
                let r = 1.02 * ((k as f64 + 0.5) / 2500.0).sqrt();
                let a = 2.399_963 * k as f64;
                [r * a.cos(), r * a.sin()]
            })
            .chain([[1.0, 0.0], [0.0, -1.0], [0.6, 0.8]])
            .collect();
        for map in [DiscMap::Projected, DiscMap::EqualArea] {
            let plain = DiscBrdf::with_map(Arc::clone(&env) as Arc<dyn Brdf>, wo, map)
                .with_zero_floor(1e-3);
            let fast = plain
                .clone()
                .with_blocks(Arc::clone(&env) as Arc<dyn DirectionBlock>);
            let mut out = vec![f64::NAN; points.len()];
            fast.eval_block(&points, &mut out);
            for (p, v) in points.iter().zip(&out) {
                assert_eq!(v.to_bits(), plain.eval(*p).to_bits(), "{map:?} {p:?}");
            }
        }
        assert_eq!(maps(block), maps(pointwise));
    }
}

/// The rejection-volume survey of an RGL set at a fixed θo (issue 29, docs/benchmarks.md
/// §30.1): `RGL_FILE=… [THETAS="30 60"] cargo test --release -p brdf-sampling --lib
/// rejection_volume_survey -- --ignored --nocapture`.
#[cfg(test)]
mod survey {
    use std::sync::Arc;

    use brdf::Brdf;

    use super::QueryDensity;
    use crate::exact::{ExactOptions, ExactSet};

    /// Splits the evaluations per sample of the interval serving θo, `Σ M_i·|leaf_i ∩ disc| / A`,
    /// into (c) the bound rule (`M_i` against the largest sampled envelope `F` over the leaf: the
    /// safety factor 1.1 and the image map's own maxima), (b) the θo range (`max F` against
    /// `max g` over each leaf, `g` at this θo), (a) the leaf resolution (`Σ max_leaf g · a / ∫g`),
    /// and (d) the limits that stopped the leaves (depth, volume floor); and predicts the
    /// evaluations with sub-cell bounds `min(M_i, 1.1 · max F over the sub-cell)` (s × s per leaf),
    /// and with θo layers: the interval cut into L equal θo layers, `F_L` the max of `f` at the
    /// layer's two ends, leaf bounds `min(M_i, 1.1 · max F_L)` (`L` leaf tables: trials and
    /// evaluations) and 4 × 4 sub-cell bounds per layer (thinning: evaluations).
    /// Points: a k × k midpoint grid per leaf (k = 16).
    #[test]
    #[ignore = "survey: needs RGL_FILE"]
    fn rejection_volume_survey() {
        let path = std::env::var("RGL_FILE").expect("RGL_FILE");
        let brdf: Arc<dyn Brdf> =
            Arc::new(brdf::RglBrdf::load(std::path::Path::new(&path)).expect("an RGL file"));
        let opts = ExactOptions::default();
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None).expect("a set");
        let r = set.report();
        println!(
            "{path}: {} intervals, {} leaves, worst trials {:.3}",
            set.len(),
            r.leaves,
            r.worst_trials
        );
        let thetas: Vec<f64> = std::env::var("THETAS")
            .unwrap_or_else(|_| "30 60".into())
            .split_whitespace()
            .map(|s| s.parse().expect("a number"))
            .collect();
        // The set's own rule and its variants (docs §31.3), same trees: the codes differ.
        let variant = |growth: f64, rigorous: bool| ExactOptions {
            thinning_growth: growth,
            thinning_rigorous: rigorous,
            ..opts
        };
        let area_of = |w: f64, h: f64| w * h / 16.0;
        let variants: Vec<(&str, ExactSet)> = [
            ("grown 1 (§30.7)", variant(1.0, false)),
            ("grown 0 (§30.1)", variant(0.0, false)),
            ("grown 1 + rigorous", variant(1.0, true)),
            ("default", opts),
        ]
        .into_iter()
        .map(|(n, o)| {
            (
                n,
                ExactSet::build(Arc::clone(&brdf), &o, None).expect("a set"),
            )
        })
        .collect();
        let k = 16usize;
        let subs = [2usize, 4, 8];
        let safety = opts.set.safety_factor;
        let params = crate::exact::envelope_tree_params(&opts.set, brdf.as_ref());
        let max_depth = params.max_depth;
        for t in thetas {
            let wo = brdf::direction_from_angles(t, 0.0);
            let q = set.locate(&wo).expect("served");
            let iv = set.interval(&q);
            let a = set.normaliser_of(&q);
            let g = QueryDensity::new(brdf.as_ref(), wo, 0.0, iv.map);
            let [ta, tb] = iv.theta;
            let nodes: Vec<QueryDensity> = (0..=2)
                .map(|n| {
                    let th = ta + (tb - ta) * f64::from(n) / 2.0;
                    let w = brdf::direction_from_radians(th, 0.0);
                    QueryDensity::new(brdf.as_ref(), w, 0.0, iv.map)
                })
                .collect();
            let (mut evals, mut m_f, mut m_g, mut int_g, mut int_f) = (0.0, 0.0, 0.0, 0.0, 0.0);
            let (mut v_deep, mut v_floor) = (0.0, 0.0);
            let mut sub_evals = [0.0f64; 3];
            // θo layers: L = 2 and 4; the query's layer and its two ends.
            let layers = [2usize, 4];
            let ends: Vec<[QueryDensity; 2]> = layers
                .iter()
                .map(|&l| {
                    let j = (((t.to_radians() - ta) / (tb - ta) * l as f64).floor() as usize)
                        .min(l - 1);
                    [j, j + 1].map(|e| {
                        let th = ta + (tb - ta) * e as f64 / l as f64;
                        let w = brdf::direction_from_radians(th, 0.0);
                        QueryDensity::new(brdf.as_ref(), w, 0.0, iv.map)
                    })
                })
                .collect();
            let (mut layer_leaf, mut layer_sub) = ([0.0f64; 2], [0.0f64; 2]);
            let mut above = 0u64;
            let leaves: Vec<_> = iv.tree.tree().leaves().collect();
            let root_w = 2.0f64;
            let floor = params.volume_tolerance * leaves.iter().map(|l| l.integral).sum::<f64>();
            for l in &leaves {
                let r = l.rect;
                let (w, h) = (r.x1 - r.x0, r.y1 - r.y0);
                let area = w * h;
                let mut fv = vec![0.0f64; k * k];
                let mut fl = vec![[0.0f64; 2]; k * k];
                let (mut mf, mut mg, mut sf, mut sg, mut inside) = (0.0f64, 0.0f64, 0.0, 0.0, 0);
                for i in 0..k {
                    for j in 0..k {
                        let x = r.x0 + w * (i as f64 + 0.5) / k as f64;
                        let y = r.y0 + h * (j as f64 + 0.5) / k as f64;
                        if x * x + y * y >= 1.0 {
                            continue;
                        }
                        inside += 1;
                        let gq = g.at([x, y]);
                        let ge = nodes.iter().map(|n| n.at([x, y])).fold(0.0, f64::max);
                        above += u64::from(gq > l.max_bound);
                        fv[i * k + j] = ge;
                        for (li, e) in ends.iter().enumerate() {
                            fl[i * k + j][li] = e[0].at([x, y]).max(e[1].at([x, y]));
                        }
                        mf = mf.max(ge);
                        mg = mg.max(gq);
                        sf += ge;
                        sg += gq;
                    }
                }
                let frac = inside as f64 / (k * k) as f64;
                let vol = l.max_bound * area * frac;
                evals += vol;
                m_f += mf * area * frac;
                m_g += mg * area * frac;
                int_f += sf / (k * k) as f64 * area;
                int_g += sg / (k * k) as f64 * area;
                let depth = (root_w / w).log2().round() as u32;
                if depth >= max_depth {
                    v_deep += vol;
                } else if l.volume <= floor {
                    v_floor += vol;
                }
                for li in 0..layers.len() {
                    let ml = fl.iter().map(|v| v[li]).fold(0.0, f64::max);
                    layer_leaf[li] += (safety * ml).min(l.max_bound) * area * frac;
                    let per = k / 4;
                    for sx in 0..4 {
                        for sy in 0..4 {
                            let (mut ms, mut ins) = (0.0f64, 0);
                            for i in sx * per..(sx + 1) * per {
                                for j in sy * per..(sy + 1) * per {
                                    let x = r.x0 + w * (i as f64 + 0.5) / k as f64;
                                    let y = r.y0 + h * (j as f64 + 0.5) / k as f64;
                                    if x * x + y * y < 1.0 {
                                        ins += 1;
                                        ms = ms.max(fl[i * k + j][li]);
                                    }
                                }
                            }
                            layer_sub[li] += (safety * ms).min(l.max_bound) * area / 16.0
                                * ins as f64
                                / (per * per) as f64;
                        }
                    }
                }
                for (si, &s) in subs.iter().enumerate() {
                    let per = k / s;
                    for sx in 0..s {
                        for sy in 0..s {
                            let mut ms = 0.0f64;
                            let mut ins = 0;
                            for i in sx * per..(sx + 1) * per {
                                for j in sy * per..(sy + 1) * per {
                                    let x = r.x0 + w * (i as f64 + 0.5) / k as f64;
                                    let y = r.y0 + h * (j as f64 + 0.5) / k as f64;
                                    if x * x + y * y < 1.0 {
                                        ins += 1;
                                        ms = ms.max(fv[i * k + j]);
                                    }
                                }
                            }
                            let bound = (safety * ms).min(l.max_bound);
                            sub_evals[si] +=
                                bound * area / (s * s) as f64 * ins as f64 / (per * per) as f64;
                        }
                    }
                }
            }
            println!(
                "θo {t}: interval [{:.2}, {:.2}]°, {} leaves; evaluations/sample ΣMa/A {:.3} = \
                 (c) bound/maxF {:.3} × (b) maxF/maxg {:.3} × (a) Σmaxg·a/∫g {:.3} × ∫g/A {:.3}; \
                 ∫F/∫g {:.3}; Σmax F·a/∫F {:.3}; volume share at max depth {} {:.3}, at the \
                 volume floor {:.3}; sub-cell bounds 2²/4²/8²: {:.3} / {:.3} / {:.3}; points above M_i {above}",
                ta.to_degrees(),
                tb.to_degrees(),
                leaves.len(),
                evals / a,
                evals / m_f,
                m_f / m_g,
                m_g / int_g,
                int_g / a,
                int_f / int_g,
                m_f / int_f,
                max_depth,
                v_deep / evals,
                v_floor / evals,
                sub_evals[0] / a,
                sub_evals[1] / a,
                sub_evals[2] / a,
            );
            println!(
                "    θo layers 2 / 4: leaf bounds per layer {:.3} / {:.3}; 4 × 4 sub-cell bounds per layer {:.3} / {:.3}",
                layer_leaf[0] / a,
                layer_leaf[1] / a,
                layer_sub[0] / a,
                layer_sub[1] / a,
            );
            // The stored codes (docs §31.3): `Σ M_is·|s ∩ disc| / A` of the set's layer serving
            // θo, for the rule variants built above (same trees), and the floor `Σ max_s g ·
            // |s ∩ disc| / A` of exact sub-cell bounds at this θo (4 × 4 points per sub-cell);
            // points above each variant's codes.
            let mut floor = 0.0;
            let mut per = vec![(0.0f64, 0u64); variants.len()];
            for (vi, (_, vset)) in variants.iter().enumerate() {
                let viv = vset.interval(&vset.locate(&wo).expect("served"));
                let sub = viv.sub_bounds.as_ref().expect("codes");
                let layer = crate::exact::table::layer_of(
                    &sub.edges,
                    t.to_radians().min(crate::exact::THETA_TOP_DEG.to_radians()),
                )
                .unwrap_or(0);
                let vleaves: Vec<_> = viv.tree.tree().leaves().collect();
                let base = layer * vleaves.len();
                for (li, l) in vleaves.iter().enumerate() {
                    let r = l.rect;
                    let (w, h) = (r.x1 - r.x0, r.y1 - r.y0);
                    for s in 0..16 {
                        let (sx, sy) = (s % 4, s / 4);
                        let m = crate::exact::table::sub_bound(
                            sub.leaf_base(li, l.max_bound),
                            sub.codes[base + li][s],
                        );
                        let (mut ins, mut mg) = (0, 0.0f64);
                        for i in 0..4 {
                            for j in 0..4 {
                                let x = r.x0 + w * (sx as f64 + (i as f64 + 0.5) / 4.0) / 4.0;
                                let y = r.y0 + h * (sy as f64 + (j as f64 + 0.5) / 4.0) / 4.0;
                                if x * x + y * y < 1.0 {
                                    ins += 1;
                                    let gv = g.at([x, y]);
                                    mg = mg.max(gv);
                                    per[vi].1 += u64::from(gv > m);
                                }
                            }
                        }
                        let frac = area_of(w, h) * ins as f64 / 16.0;
                        per[vi].0 += m * frac;
                        if vi == 0 {
                            floor += mg * frac;
                        }
                    }
                }
            }
            let text: Vec<String> = variants
                .iter()
                .zip(&per)
                .map(|((name, _), (e, n))| format!("{name} {:.3} ({n} above)", e / a))
                .collect();
            println!(
                "    stored codes of the layer serving θo: {}; exact 4 × 4 sub-cell maxima at θo {:.3}",
                text.join(", "),
                floor / a
            );
        }
    }
}
