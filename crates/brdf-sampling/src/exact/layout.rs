//! The azimuth cells of a set: θ strips, their intervals and the guided interval search.

use crate::layout::Turn;

use super::grid::{Grid, TableVar};
use super::interval::Interval;
use super::table::LeafTable;
use super::walk::TAN_HALF_MAX;

/// One azimuth cell: its centre and its intervals. The cell is cut into θ **strips** at every
/// interval's θ edges; a strip holds the intervals that cover it, ordered by δ (one, unless
/// the cell was split in azimuth there).
pub(super) struct Cell {
    pub(super) phi: f64,
    /// `(cos, sin)` of `phi`: a query's rotation from the cell's frame without trigonometry.
    pub(super) phi_turn: Turn,
    /// `tan h` of the cells' half-width `h` (the same for every cell of a set; 0 for isotropic
    /// sets): a query's offset `δ` lies in this cell when `|tan δ| ≤ tan h`
    /// ([`super::walk::cell_offset`]).
    pub(super) tan_half: f64,
    /// Upper θ edges of the strips (radians), increasing; the last is π/2.
    pub(super) upper: Vec<f64>,
    /// The same edges as search keys, increasing: `1 − cos θ` for anisotropic cells (a query
    /// is placed by its `cos θo` without `acos`, whatever the table variable; see
    /// [`Cell::search_key`]), otherwise the table variable's key ([`TableVar::key`]).
    pub(super) keys: Vec<f64>,
    /// Guide table over the keys `[0, range]`: `guide[g]` is the strip of the key
    /// `g · range / GUIDE_LEN`, where the search for any key of bucket `g` starts (see
    /// [`Cell::interval_of`]).
    pub(super) guide: Vec<u32>,
    pub(super) range: f64,
    /// The variable of [`Cell::keys`] ([`search_var`]).
    pub(super) search: TableVar,
    /// Strip `s` holds the intervals `members[strips[s]..strips[s + 1]]`; empty when every
    /// strip holds one interval, the strip's own index (no azimuth split in the cell).
    pub(super) strips: Vec<u32>,
    /// The strip search's keys of the upper δ edge of each strip entry (increasing within a
    /// strip): `tan δ` when the set's cells are narrow
    /// enough for [`super::walk::cell_offset`] (`tan h ≤` [`TAN_HALF_MAX`]: a query's `tan δ`
    /// is known before its `atan`), otherwise `δ` itself; see [`Cell::by_tan`].
    pub(super) delta_keys: Vec<f64>,
    /// Whether [`Cell::delta_keys`] hold `tan δ` (the strip search takes `tan δ` then).
    pub(super) by_tan: bool,
    /// The interval of each strip entry.
    pub(super) members: Vec<u32>,
    /// The intervals, ordered by θ, then δ.
    pub(super) intervals: Vec<Interval>,
    /// Per interval, the compact table its samples are drawn from ([`LeafTable`]; `None`: the
    /// tree's own walk); in isotropic cells with the θo layers' own tables
    /// ([`LeafTable::serving`]).
    pub(super) tables: Vec<Option<LeafTable>>,
    /// Per interval, what the isotropic fast path reads besides the table
    /// ([`IsoRecord`](super::iso_record::IsoRecord); unused by anisotropic cells).
    pub(super) iso: Vec<super::iso_record::IsoRecord>,
    /// Per interval of an anisotropic cell, what its queries read besides the table: the
    /// normaliser grid over the search keys and the disc map
    /// ([`AnisoRecord`](super::aniso_record::AnisoRecord); empty for isotropic cells).
    pub(super) aniso: Vec<super::aniso_record::AnisoRecord>,
    /// The normaliser patches of [`Cell::aniso`]'s records.
    pub(super) patches: Vec<super::aniso_record::Patch>,
    /// Anisotropic cells: the interval of a query straight from its keys where one interval
    /// covers a whole bucket ([`DirectIndex`]; `None` for isotropic cells).
    pub(super) direct: Option<DirectIndex>,
}

/// Buckets of a [`DirectIndex`] along the θ search key `1 − cos θo`.
pub(super) const DIRECT_THETA: usize = 256;
/// Buckets of a [`DirectIndex`] along the strip key (`tan δ` or `δ`): half of them on each
/// side of 0.
pub(super) const DIRECT_DELTA: usize = 8;
/// Buckets of a [`DirectIndex`] on each side of the strip key 0.
const DIRECT_SIDE: usize = DIRECT_DELTA / 2;
/// A [`DirectIndex`] entry whose bucket meets more than one interval.
const DIRECT_NONE: u8 = u8::MAX;

/// The interval of an anisotropic query by one table read instead of the guided θ search and
/// the strip's δ scan (issue 29: `locate_keys`'s cost on anisotropic Ward). A uniform grid of
/// [`DIRECT_THETA`] × [`DIRECT_DELTA`] buckets over the search key `k = 1 − cos θo ∈ [0,
/// range]` and the strip key `d ∈ [−h_d, h_d]` (`h_d = tan h` or `h`); bucket `(g, e)` holds
/// the keys with `⌊k · s_k⌋ = g` and, along the strip key, **by its sign and magnitude**:
/// `e = S + j` for `d > 0` and `e = S − 1 − j` for `d ≤ 0`, with `j = ⌊|d| · s_d⌋`
/// (`S` = [`DIRECT_SIDE`] buckets per side, `s_k = DIRECT_THETA / range`, `s_d = S / h_d`; the
/// first and last buckets of each axis extend to `∓∞`). The boundary at `d = 0` is a sign test,
/// exact and the search's own (a strip key on an edge belongs to the entry below it): an
/// azimuth split at `δ = 0` (the first halving of a cell, `tan 0 = 0`) lies between two
/// buckets instead of making both meet two intervals (docs/benchmarks.md §26.2).
/// [`Cell::interval_of`] is non-decreasing in `k` (its strip) and, within a strip, in `d`
/// (the entry), so a bucket whose two extreme corners — widened by a margin of 10⁻⁶ of a
/// bucket for the rounding of `k · s_k` and `|d| · s_d`, and at `d = 0` the keys `0` and the
/// smallest positive float — give the same strip and entry has that interval at every key inside: the
/// entry stores it (as `u8`); otherwise [`DIRECT_NONE`], and the query takes the search. The
/// result is the search's, exactly.
pub(super) struct DirectIndex {
    k_scale: f64,
    /// `s_d`: buckets per unit of `|d|`.
    d_scale: f64,
    entries: Box<[u8; DIRECT_THETA * DIRECT_DELTA]>,
}

/// An interval with its θ and δ numerators ([`Grid`]).
pub(super) type Placed = ([u64; 2], [u64; 2], Interval);

/// Buckets of a cell's guide table.
pub(super) const GUIDE_LEN: usize = 256;

impl Cell {
    /// The cell of centre `phi` tiled by `members` (θ numerators, δ numerators and interval,
    /// ordered by θ then δ; see [`Grid`]).
    pub(super) fn new(phi: f64, members: Vec<Placed>, grid: &Grid, var: TableVar) -> Self {
        let mut edges: Vec<u64> = members.iter().map(|(num, _, _)| num[1]).collect();
        edges.sort_unstable();
        edges.dedup();
        let upper: Vec<f64> = edges.iter().map(|&e| grid.edge(e)).collect();
        let search = search_var(var, grid.half);
        let mut keys: Vec<f64> = upper.iter().map(|&t| search.key(search.of(t))).collect();
        // Monotone despite rounding (the search needs sorted keys).
        for i in 1..keys.len() {
            keys[i] = keys[i].max(keys[i - 1]);
        }
        let range = search.key_range();
        let guide = interval_guide(&keys, range);
        let (mut strips, mut delta_upper, mut entries) = (vec![0u32], Vec::new(), Vec::new());
        let mut lower = 0u64;
        for &e in &edges {
            let mut strip: Vec<(u64, usize)> = members
                .iter()
                .enumerate()
                .filter(|(_, (num, _, _))| num[0] <= lower && num[1] >= e)
                .map(|(i, (_, dnum, _))| (dnum[1], i))
                .collect();
            strip.sort_unstable();
            for (d, i) in strip {
                delta_upper.push(grid.delta(d));
                entries.push(i as u32);
            }
            strips.push(entries.len() as u32);
            lower = e;
        }
        let plain = entries.len() == edges.len();
        let tan_half = grid.half.tan();
        let by_tan =
            grid.half > 0.0 && grid.half < std::f64::consts::FRAC_PI_2 && tan_half <= TAN_HALF_MAX;
        let delta_keys = delta_upper
            .iter()
            .map(|&d: &f64| if by_tan { d.tan() } else { d })
            .collect();
        let mut intervals: Vec<Interval> = members.into_iter().map(|(_, _, iv)| iv).collect();
        // Anisotropic cells: the normaliser refitted over the search keys (`aniso_record.rs`);
        // its difference from the table is part of the interval's declared error.
        let (mut aniso, mut patches) = (Vec::new(), Vec::new());
        if grid.half > 0.0 {
            for iv in &mut intervals {
                let (rec, err) = super::aniso_record::AnisoRecord::of(iv, by_tan, &mut patches);
                iv.norm_err += err;

                aniso.push(rec);
            }
        }
        // Isotropic cells: a table per θo layer of the thinning bounds as well
        // (`LeafTable::with_layer_tables`; every isotropic path draws from the layer serving the
        // query's θo). Anisotropic cells keep the interval's table (their paths do not pick
        // layers).
        let tables = intervals
            .iter()
            .map(|iv| {
                LeafTable::of(&iv.tree).map(|t| {
                    let t = t.with_sub_bounds(iv.sub_bounds.as_ref());
                    if grid.half > 0.0 {
                        t
                    } else {
                        t.with_layer_tables()
                    }
                })
            })
            .collect();
        let half_key = if by_tan { tan_half } else { grid.half };
        let iso = intervals
            .iter()
            .map(super::iso_record::IsoRecord::of)
            .collect();
        let mut cell = Self {
            phi,
            phi_turn: Turn::from_angle(phi),
            tan_half,
            upper,
            keys,
            guide,
            range,
            search,
            strips: if plain { Vec::new() } else { strips },
            delta_keys: if plain { Vec::new() } else { delta_keys },
            by_tan,
            members: if plain { Vec::new() } else { entries },
            intervals,
            tables,
            iso,
            aniso,
            patches,
            direct: None,
        };
        if grid.half > 0.0 && cell.intervals.len() < usize::from(DIRECT_NONE) {
            cell.direct = Some(cell.direct_index(half_key));
        }
        cell
    }

    /// The [`DirectIndex`] of this cell's search (strip keys in `[−half_key, half_key]`).
    fn direct_index(&self, half_key: f64) -> DirectIndex {
        let k_scale = DIRECT_THETA as f64 / self.range;
        let d_scale = DIRECT_SIDE as f64 / half_key;
        // Bucket `b` of `n` over `[lo, lo + n/scale]`: its keys, widened for rounding; the
        // end buckets reach to infinity (keys past the grid are clamped into them).
        let ends = |b: usize, n: usize, lo: f64, scale: f64| {
            let margin = 1e-6 / scale;
            let a = if b == 0 {
                f64::NEG_INFINITY
            } else {
                lo + b as f64 / scale - margin
            };
            let z = if b + 1 == n {
                f64::INFINITY
            } else {
                lo + (b + 1) as f64 / scale + margin
            };
            [a, z]
        };
        let mut entries = Box::new([DIRECT_NONE; DIRECT_THETA * DIRECT_DELTA]);
        for g in 0..DIRECT_THETA {
            let [k0, k1] = ends(g, DIRECT_THETA, 0.0, k_scale);
            for e in 0..DIRECT_DELTA {
                // `|d|` in bucket `j` of its side; the inner ends exact (the sign test): `d = 0`
                // with the negative side, as the search puts a key on an edge below it.
                let (d0, d1) = if e >= DIRECT_SIDE {
                    let [a, z] = ends(e - DIRECT_SIDE, DIRECT_SIDE, 0.0, d_scale);
                    (
                        if e == DIRECT_SIDE {
                            f64::from_bits(1)
                        } else {
                            a
                        },
                        z,
                    )
                } else {
                    let [a, z] = ends(DIRECT_SIDE - 1 - e, DIRECT_SIDE, 0.0, d_scale);
                    (-z, if e + 1 == DIRECT_SIDE { 0.0 } else { -a })
                };
                let (a, z) = (self.strip_entry(k0, d0), self.strip_entry(k1, d1));
                if a == z {
                    let iv = self.entry_interval(a.1);
                    if iv < usize::from(DIRECT_NONE) {
                        entries[g * DIRECT_DELTA + e] = iv as u8;
                    }
                }
            }
        }
        DirectIndex {
            k_scale,
            d_scale,
            entries,
        }
    }

    /// The interval of an anisotropic query: [`Cell::interval_of`]'s, from the
    /// [`DirectIndex`] when its bucket holds one interval (the search otherwise, and for
    /// cells without an index).
    #[inline]
    pub(super) fn interval_direct(&self, key: f64, dkey: f64) -> usize {
        if let Some(t) = &self.direct {
            // `as usize` saturates: negative keys (and NaN) go to bucket 0, past-the-end
            // keys are clamped into the last bucket.
            let g = ((key * t.k_scale) as usize).min(DIRECT_THETA - 1);
            let j = ((dkey.abs() * t.d_scale) as usize).min(DIRECT_SIDE - 1);
            let e = if dkey <= 0.0 {
                DIRECT_SIDE - 1 - j
            } else {
                DIRECT_SIDE + j
            };
            let iv = t.entries[g * DIRECT_DELTA + e];
            if iv != DIRECT_NONE {
                return usize::from(iv);
            }
        }
        self.interval_of(key, dkey)
    }

    /// Bytes of this cell's [`DirectIndex`] table (0 without one).
    pub(super) fn direct_bytes(&self) -> usize {
        self.direct
            .as_ref()
            .map_or(0, |t| std::mem::size_of_val(t.entries.as_ref()))
    }

    /// Share of this cell's [`DirectIndex`] buckets that hold one interval (0 without one).
    #[cfg(test)]
    pub(super) fn direct_share(&self) -> f64 {
        self.direct.as_ref().map_or(0.0, |t| {
            t.entries.iter().filter(|&&e| e != DIRECT_NONE).count() as f64 / t.entries.len() as f64
        })
    }

    /// The strip of `key` and the strip entry of `dkey` in it ([`Cell::interval_of`] in two
    /// steps; the entry is the strip itself in cells without azimuth splits).
    fn strip_entry(&self, key: f64, dkey: f64) -> (usize, usize) {
        let s = guided_interval(&self.keys, &self.guide, self.range, key);
        if self.strips.is_empty() {
            return (s, s);
        }
        let (mut j, last) = (self.strips[s] as usize, self.strips[s + 1] as usize - 1);
        while j < last && self.delta_keys[j] < dkey {
            j += 1;
        }
        (s, j)
    }

    /// The interval of a strip entry ([`Cell::strip_entry`]).
    fn entry_interval(&self, j: usize) -> usize {
        if self.strips.is_empty() {
            j
        } else {
            self.members[j] as usize
        }
    }

    /// The interval of the search key `key` ([`Cell::search_key`]) and azimuth key `dkey`:
    /// `tan δ` when [`Cell::by_tan`], otherwise the offset `δ` (the two order the strip's
    /// entries alike: `tan` is increasing on `|δ| ≤ h < π/2`).
    #[inline]
    pub(super) fn interval_of(&self, key: f64, dkey: f64) -> usize {
        let s = guided_interval(&self.keys, &self.guide, self.range, key);
        if self.strips.is_empty() {
            return s;
        }
        let (mut j, last) = (self.strips[s] as usize, self.strips[s + 1] as usize - 1);
        while j < last && self.delta_keys[j] < dkey {
            j += 1;
        }
        self.members[j] as usize
    }

    /// The θ search key of a query with `cos θo = cos` and table variable `v`: `1 − cos θo`
    /// for anisotropic cells (no `acos` on the way to the interval: the walk need not wait for
    /// it; [`search_var`]), otherwise the table variable's key ([`TableVar::key`]).
    #[inline]
    pub(super) fn search_key(&self, cos: f64, v: f64) -> f64 {
        match self.search {
            TableVar::Cos => 1.0 - cos,
            TableVar::Theta => v,
        }
    }

    /// The intervals of strip `s`, ordered by δ.
    pub(super) fn strip(&self, s: usize) -> Vec<usize> {
        if self.strips.is_empty() {
            return vec![s];
        }
        (self.strips[s]..self.strips[s + 1])
            .map(|j| self.members[j as usize] as usize)
            .collect()
    }

    /// Per strip, its intervals' azimuth edges (degrees, absolute).
    pub(super) fn phi_edges_deg(&self) -> Vec<Vec<f64>> {
        (0..self.upper.len())
            .map(|s| {
                let ivs = self.strip(s);
                let deg = |d: f64| (self.phi + d).to_degrees();
                let mut e = vec![deg(self.intervals[ivs[0]].delta[0])];
                e.extend(ivs.iter().map(|&i| deg(self.intervals[i].delta[1])));
                e
            })
            .collect()
    }
}

/// The variable a cell's θ search runs on: `cos θo` for anisotropic cells (`half > 0`), so
/// that a query needs no `acos` to find its interval, otherwise the table variable `var`.
pub(super) fn search_var(var: TableVar, half: f64) -> TableVar {
    if half > 0.0 { TableVar::Cos } else { var }
}

/// The guide table of the interval edges `upper` (increasing, not empty) over `[0, range]`:
/// entry `g` is the interval of `g · range / GUIDE_LEN`.
pub(super) fn interval_guide(upper: &[f64], range: f64) -> Vec<u32> {
    let step = range / GUIDE_LEN as f64;
    let last = upper.len().saturating_sub(1);
    (0..GUIDE_LEN)
        .map(|g| upper.partition_point(|&u| u < g as f64 * step).min(last) as u32)
        .collect()
}

/// The first interval whose upper edge is ≥ `x` (the last one when none is): the binary search
/// `upper.partition_point(|u| u < x)`, by a scan from the guide table's bucket of `x` (usually
/// zero or one step; down only if rounding put `x` in the bucket above its own).
#[inline]
pub(super) fn guided_interval(upper: &[f64], guide: &[u32], range: f64, x: f64) -> usize {
    let last = upper.len() - 1;
    let g = ((x * (GUIDE_LEN as f64 / range)) as usize).min(GUIDE_LEN - 1);
    let mut i = (guide[g] as usize).min(last);
    while i > 0 && upper[i - 1] >= x {
        i -= 1;
    }
    while i < last && upper[i] < x {
        i += 1;
    }
    i
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Test support: the [`DirectIndex`] of every anisotropic cell of `cells` gives
    /// [`Cell::interval_of`]'s interval — at random keys (also past both ends of each axis),
    /// at every strip edge and δ edge and their neighbouring floats, and at every bucket
    /// corner and its neighbouring floats — and serves most buckets. Returns the number of
    /// keys compared.
    pub(in crate::exact) fn assert_direct_is_the_search(cells: &[Cell], seed: u64) -> usize {
        use partition_sampler::UniformSource;
        use rand::SeedableRng;
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut checked = 0;
        for (k, c) in cells.iter().enumerate() {
            let t = c.direct.as_ref().expect("anisotropic cells have an index");
            assert_eq!(c.direct_bytes(), DIRECT_THETA * DIRECT_DELTA);
            let share = c.direct_share();
            assert!(share > 0.5, "cell {k}: {share} of the buckets served");
            let h = DIRECT_SIDE as f64 / t.d_scale;
            let near = |x: f64| [x.next_down(), x, x.next_up()];
            let mut ks: Vec<f64> = c.keys.iter().flat_map(|&x| near(x)).collect();
            ks.extend((0..=DIRECT_THETA).flat_map(|g| near(g as f64 / t.k_scale)));
            let mut ds: Vec<f64> = c.delta_keys.iter().flat_map(|&x| near(x)).collect();
            ds.extend(
                (0..=DIRECT_DELTA).flat_map(|e| near((e as f64 - DIRECT_SIDE as f64) / t.d_scale)),
            );
            ds.extend([0.0, -0.0, f64::from_bits(1), -f64::from_bits(1)]);
            let mut pairs: Vec<(f64, f64)> = Vec::new();
            for &x in &ks {
                pairs.push((x, h * (2.4 * rng.next_uniform() - 1.2)));
                for &d in &ds {
                    pairs.push((x, d));
                }
            }
            for &d in &ds {
                pairs.push((c.range * (1.02 * rng.next_uniform() - 0.01), d));
            }
            for _ in 0..20_000 {
                let x = c.range * (1.02 * rng.next_uniform() - 0.01);
                pairs.push((x, h * (2.4 * rng.next_uniform() - 1.2)));
            }
            for (x, d) in pairs {
                assert_eq!(
                    c.interval_direct(x, d),
                    c.interval_of(x, d),
                    "cell {k}: key {x:e}, strip key {d:e}"
                );
                checked += 1;
            }
        }
        checked
    }
}
