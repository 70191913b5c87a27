//! The wavefront's trials in vector lanes (issue 29; docs/benchmarks.md §26.3, §27.5): one
//! pass over a block of pending samples makes each sample's next trial — its four uniforms
//! from its own SplitMix64 stream, the leaf pick, the point and its bound
//! ([`LeafTable::leaf_of`], `propose`'s arithmetic without branches), the acceptance
//! threshold `u₃·M_i` and the trial's direction on the disc map — in structure-of-arrays
//! form, in groups of 16 whose arithmetic the compiler keeps in vector registers (the 64-bit
//! multiplies, the points, the map's square root; the leaf records are read lane by lane). Dispatched at run time by `pulp` (AVX-512
//! as `V4`, AVX2 + FMA as `V3`, else the baseline), as `brdf`'s RGL lanes: integer
//! arithmetic, exact conversions and the same floating-point operations in the same order
//! (Rust never contracts `a·b + c`), so every level gives the bits of the one-sample draw
//! ([`LeafTable::draw`] from the sample's stream; tested in `batch.rs`).
//!
//! [`LeafTable::draw`]: super::table::LeafTable::draw

use brdf::Vec3;

use super::table::LeafTable;
use crate::disc::DiscMap;

/// SplitMix64's increment `γ`.
pub(super) const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64's output function (Steele, Lea & Flood 2014): a bijection of `u64` whose
/// outputs at the states `key + k·γ` are SplitMix64's stream.
#[inline(always)]
pub(super) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A SplitMix64 output as a uniform on `[0, 1)`: its top 53 bits times `2⁻⁵³` (as
/// `UniformSource` for a generator). The bits fit in an `i64`, so the signed conversion (one
/// instruction) gives the value of the unsigned one.
#[inline(always)]
pub(super) fn unit(z: u64) -> f64 {
    ((z >> 11) as i64) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// One block's trials, entry `j` for the pending sample `j` of the block: the point `(x, y)`
/// on the disc's square, its leaf's bound `M_i`, the thinning bound `M_is ≤ M_i` of its
/// sub-cell (`M_i ·` [`LeafTable::code_factor`]; written by a thinning pass only, [`trials`] on a table with
/// thinning bounds), the acceptance threshold `u₃·M_i`, whether the point lies inside the unit
/// circle (`x² + y² < 1`: else the trial evaluates nothing) and, inside, its direction
/// `map.to_direction((x, y))`.
pub(super) struct Trials {
    pub(super) x: Vec<f64>,
    pub(super) y: Vec<f64>,
    pub(super) bound: Vec<f64>,
    pub(super) cap: Vec<f64>,
    pub(super) threshold: Vec<f64>,
    pub(super) inside: Vec<bool>,
    pub(super) dir: Vec<Vec3>,
}

impl Trials {
    /// Room for blocks of up to `wave` samples (rounded up to whole groups of [`LANES`]).
    pub(super) fn new(wave: usize) -> Self {
        let wave = wave.div_ceil(LANES) * LANES;
        Self {
            x: vec![0.0; wave],
            y: vec![0.0; wave],
            bound: vec![0.0; wave],
            cap: vec![0.0; wave],
            threshold: vec![0.0; wave],
            inside: vec![false; wave],
            dir: vec![Vec3::zeros(); wave],
        }
    }

    /// The largest block these arrays take (a multiple of [`LANES`]).
    pub(super) fn room(&self) -> usize {
        self.x.len()
    }
}

/// `DiscMap::Projected.to_direction`'s arithmetic: `(x, y, √(1 − x² − y²))` (0 where the
/// radicand is not positive).
#[inline(always)]
fn projected(x: f64, y: f64) -> Vec3 {
    let z2 = 1.0 - x * x - y * y;
    Vec3::new(x, y, if z2 > 0.0 { z2.sqrt() } else { 0.0 })
}

/// `DiscMap::EqualArea.to_direction`'s arithmetic: `r² = min(x² + y², 1)`,
/// `(x·√(2 − r²), y·√(2 − r²), 1 − r²)`.
#[inline(always)]
fn equal_area(x: f64, y: f64) -> Vec3 {
    let r2 = (x * x + y * y).min(1.0);
    let s = (2.0 - r2).sqrt();
    Vec3::new(x * s, y * s, 1.0 - r2)
}

/// Trials per structure-of-arrays group of [`pass`].
const LANES: usize = 16;

/// The next trial's four uniforms of a SplitMix64 stream at `state` (advanced by four steps):
/// `u_k = unit(mix64(state + (k + 1)·γ))`, `k = 0..3`, as [`LeafTable::draw`] reads them from
/// a generator's four outputs.
///
/// [`LeafTable::draw`]: super::table::LeafTable::draw
///
/// Also the trial's thinning sub-cell `⌊SUB·u₂⌋·SUB + ⌊SUB·u₁⌋` ([`LeafTable::code_factor`])
/// from the outputs' top bits: `u = (z >> 11)·2⁻⁵³`, so `⌊4u⌋ = z >> 62` (`SUB` = 4).
#[inline(always)]
fn four_outputs(state: &mut u64) -> ([f64; 4], usize) {
    let s1 = state.wrapping_add(GOLDEN_GAMMA);
    let s2 = s1.wrapping_add(GOLDEN_GAMMA);
    let s3 = s2.wrapping_add(GOLDEN_GAMMA);
    let s4 = s3.wrapping_add(GOLDEN_GAMMA);
    *state = s4;
    let (z1, z2) = (mix64(s2), mix64(s3));
    let sub = (z1 >> 62) | ((z2 >> 62) << 2);
    (
        [unit(mix64(s1)), unit(z1), unit(z2), unit(mix64(s4))],
        sub as usize,
    )
}

/// The pass of [`trials`] / [`trials_split`] for one trial's uniforms `uniforms` (advancing a
/// stream state: [`four_outputs`] or [`split_trial`]) and one disc map's direction `to_dir`,
/// in groups of [`LANES`]: the uniforms (vector lanes), the leaf records read lane by lane
/// ([`LeafTable::leaf_of`]), then the points, thresholds and directions (vector lanes),
/// written in place (`t`'s room is a multiple of [`LANES`]; a last, partial group fills its
/// group whole, the entries past `state.len()` meaning nothing). With `THIN`, also each
/// trial's thinning bound (`M_i ·` [`LeafTable::code_factor`], the codes of the layer at offset
/// `base`) in `t.cap`, and `inside` then
/// also requires the threshold below it (the trial's candidate flag).
#[inline(always)]
fn pass<const THIN: bool, U: Fn(&mut u64) -> ([f64; 4], usize), D: Fn(f64, f64) -> Vec3>(
    table: &LeafTable,
    base: usize,
    state: &mut [u64],
    t: &mut Trials,
    uniforms: U,
    to_dir: D,
) {
    let z = [0.0; LANES];
    let groups = state
        .chunks_mut(LANES)
        .zip(t.x.chunks_exact_mut(LANES))
        .zip(t.y.chunks_exact_mut(LANES))
        .zip(t.bound.chunks_exact_mut(LANES))
        .zip(t.cap.chunks_exact_mut(LANES))
        .zip(t.threshold.chunks_exact_mut(LANES))
        .zip(t.inside.chunks_exact_mut(LANES))
        .zip(t.dir.chunks_exact_mut(LANES));
    for (((((((st, xs), ys), ms), cs), th), ok), dir) in groups {
        let n = st.len();
        let mut s0 = [0u64; LANES];
        for (a, b) in s0.iter_mut().zip(st.iter()) {
            *a = *b;
        }
        let (mut u0, mut u1, mut u2, mut u3) = (z, z, z, z);
        let mut sub = [0usize; LANES];
        for j in 0..LANES {
            let ([a, b, c, d], s) = uniforms(&mut s0[j]);
            u0[j] = a;
            u1[j] = b;
            u2[j] = c;
            u3[j] = d;
            sub[j] = s;
        }
        st.copy_from_slice(&s0[..n]);
        let mut leaf = [[0.0; 5]; LANES];
        if THIN {
            let mut factor = [0.0; LANES];
            for j in 0..LANES {
                let (k, l) = table.leaf_at(u0[j]);
                leaf[j] = l;
                factor[j] = table.code_factor(base, k, sub[j]);
            }
            for j in 0..LANES {
                cs[j] = leaf[j][4] * factor[j];
            }
        } else {
            for j in 0..LANES {
                leaf[j] = table.leaf_of(u0[j]);
            }
        }
        for j in 0..LANES {
            let [x0, dx, y0, dy, m] = leaf[j];
            let x = x0 + u1[j] * dx;
            let y = y0 + u2[j] * dy;
            xs[j] = x;
            ys[j] = y;
            ms[j] = m;
            th[j] = u3[j] * m;
            let inside = x * x + y * y < 1.0;
            // With thinning, a trial at or above its sub-cell's bound is no candidate.
            ok[j] = if THIN {
                inside & (th[j] < cs[j])
            } else {
                inside
            };
            dir[j] = to_dir(x, y);
        }
    }
}

/// [`pass`] as a `pulp` operation (inlined into, and compiled for, each instruction set):
/// split trials ([`split_trial`]) when `split`, else [`four_outputs`]; thinning bounds when
/// `thin` (with [`four_outputs`] only).
struct Pass<'a> {
    table: &'a LeafTable,
    map: DiscMap,
    split: bool,
    thin: bool,
    /// The serving layer's codes ([`LeafTable::layer_base`]).
    base: usize,
    state: &'a mut [u64],
    t: &'a mut Trials,
}

impl pulp::WithSimd for Pass<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self {
            table,
            map,
            split,
            thin,
            base,
            state,
            t,
        } = self;
        match (map, split, thin) {
            (DiscMap::Projected, false, false) => {
                pass::<false, _, _>(table, base, state, t, four_outputs, projected)
            }
            (DiscMap::EqualArea, false, false) => {
                pass::<false, _, _>(table, base, state, t, four_outputs, equal_area)
            }
            (DiscMap::Projected, false, true) => {
                pass::<true, _, _>(table, base, state, t, four_outputs, projected)
            }
            (DiscMap::EqualArea, false, true) => {
                pass::<true, _, _>(table, base, state, t, four_outputs, equal_area)
            }
            (DiscMap::Projected, true, _) => {
                pass::<false, _, _>(table, base, state, t, split_trial_pass, projected)
            }
            (DiscMap::EqualArea, true, _) => {
                pass::<false, _, _>(table, base, state, t, split_trial_pass, equal_area)
            }
        }
    }
}

/// The next trial of every pending sample of a block whose stream states are `state` (at
/// most `t`'s room; each advances by four steps): `t`'s entries `0..state.len()`, the
/// uniforms of trial `u_k = unit(mix64(state + (k + 1)·γ))`, `k = 0..3`, as
/// [`LeafTable::draw`] reads them from the sample's stream, the point and bound
/// [`LeafTable::propose`]'s; when the table has thinning bounds, each trial's
/// thinning bound in `t.cap` too (`inside`: the candidate flag), from the codes of the θo layer
/// at offset `base` ([`LeafTable::layer_base`]). Dispatched at run time (`pulp`); the same bits
/// on every level.
///
/// [`LeafTable::draw`]: super::table::LeafTable::draw
/// [`LeafTable::propose`]: super::table::LeafTable::propose
pub(super) fn trials(
    arch: pulp::Arch,
    table: &LeafTable,
    map: DiscMap,
    thin: bool,
    base: usize,
    state: &mut [u64],
    t: &mut Trials,
) {
    arch.dispatch(Pass {
        table,
        map,
        split: false,
        thin: thin && table.thins(),
        base,
        state,
        t,
    });
}

/// The streams' first states of a wavefront of `state.len()` samples keyed by `seed`:
/// `state[i] = mix64(seed ⊕ mix64(i))` (the stream of sample `i`, `batch.rs`'s `Stream::of`).
#[inline(always)]
fn keys_soa(seed: u64, state: &mut [u64]) {
    for (i, s) in state.iter_mut().enumerate() {
        *s = mix64(seed ^ mix64(i as u64));
    }
}

/// [`keys_soa`] as a `pulp` operation.
struct Keys<'a> {
    seed: u64,
    state: &'a mut [u64],
}

impl pulp::WithSimd for Keys<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        keys_soa(self.seed, self.state);
    }
}

/// [`keys_soa`] dispatched at run time (`pulp`); integer arithmetic, the same bits on every
/// level.
pub(super) fn keys(arch: pulp::Arch, seed: u64, state: &mut [u64]) {
    arch.dispatch(Keys { seed, state });
}

/// `k · 2⁻³²` for the 32-bit `k` (exact; as `distributions`' split trials make it). The bits
/// fit in an `i64`, so the signed conversion gives the unsigned one's value.
#[inline(always)]
fn half_unit(k: u64) -> f64 {
    (k as i64) as f64 * (1.0 / (1u64 << 32) as f64)
}

/// The next **split** trial of a SplitMix64 stream at `state` (advanced by two steps): the
/// halves of its next two outputs `w₀, w₁`, `[hi(w₀), lo(w₀), hi(w₁), lo(w₁)] · 2⁻³²` — what
/// `UniformSource::next_uniform4_split` makes of a generator's two words, the uniforms of
/// [`LeafTable::draw`] (the random-ωo wavefront's, `wave_iso.rs`).
///
/// [`LeafTable::draw`]: super::table::LeafTable::draw
#[inline(always)]
pub(super) fn split_trial(state: &mut u64) -> [f64; 4] {
    let s1 = state.wrapping_add(GOLDEN_GAMMA);
    let s2 = s1.wrapping_add(GOLDEN_GAMMA);
    *state = s2;
    let (w0, w1) = (mix64(s1), mix64(s2));
    [
        half_unit(w0 >> 32),
        half_unit(w0 & 0xffff_ffff),
        half_unit(w1 >> 32),
        half_unit(w1 & 0xffff_ffff),
    ]
}

/// [`split_trial`] in [`pass`]'s form (no thinning sub-cell).
#[inline(always)]
fn split_trial_pass(state: &mut u64) -> ([f64; 4], usize) {
    (split_trial(state), 0)
}

/// [`trials`] with split trials: entry `j`'s uniforms are [`split_trial`] of `state[j]`
/// (advanced by two steps), as [`LeafTable::draw`] reads them from the stream through
/// `next_uniform4_split`; the point and bound [`LeafTable::propose`]'s. Dispatched at run time
/// (`pulp`); the same bits on every level.
///
/// [`LeafTable::draw`]: super::table::LeafTable::draw
/// [`LeafTable::propose`]: super::table::LeafTable::propose
pub(super) fn trials_split(
    arch: pulp::Arch,
    table: &LeafTable,
    map: DiscMap,
    state: &mut [u64],
    t: &mut Trials,
) {
    arch.dispatch(Pass {
        table,
        map,
        split: true,
        thin: false,
        base: 0,
        state,
        t,
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::table::SUB;

    /// `four_outputs`' thinning sub-cell is `⌊SUB·u₂⌋·SUB + ⌊SUB·u₁⌋` of its own uniforms (the
    /// top bits of the outputs), on 10⁵ stream states. Fails with the two halves swapped
    /// (`(z2 >> 62) | ((z1 >> 62) << 2)`).
    #[test]
    fn thinning_sub_cell_is_the_uniforms_floor() {
        assert_eq!(SUB, 4, "the top-two-bits rule is for 4 × 4 sub-cells");
        let mut state = 0x1234_5678_9abc_def0u64;
        let mut seen = [0u32; 16];
        for _ in 0..100_000 {
            let ([_, u1, u2, _], sub) = four_outputs(&mut state);
            let want =
                ((u2 * SUB as f64).floor() as usize) * SUB + (u1 * SUB as f64).floor() as usize;
            assert_eq!(sub, want, "u1 {u1} u2 {u2}");
            seen[sub] += 1;
        }
        assert!(seen.iter().all(|&n| n > 5_000), "{seen:?}");
    }
}
