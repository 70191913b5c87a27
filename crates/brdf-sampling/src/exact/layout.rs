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
    /// tree's own walk).
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
        let tables = intervals.iter().map(|iv| LeafTable::of(&iv.tree)).collect();
        let iso = intervals
            .iter()
            .map(super::iso_record::IsoRecord::of)
            .collect();
        Self {
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
