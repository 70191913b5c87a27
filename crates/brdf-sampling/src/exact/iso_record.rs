//! The per-interval record of the isotropic fast path ([`IsoRecord`], issue 29: the
//! per-query cost), apart from the fused sampling code that reads it so the cell layout can
//! hold one without depending on the sampler.

use super::interval::Interval;
use crate::disc::DiscMap;

/// Normaliser coefficients an [`IsoRecord`] holds inline (the default table has 9 nodes).
const ISO_TERMS: usize = 11;

/// What the isotropic fast path reads of one interval besides its sampling table, in one
/// 128-byte record on two adjacent cache lines (issue 29: a random `ωo` lands in a different
/// interval per query, and the [`Interval`]'s own fields — node range, series, map — lie on
/// several lines of a large struct and two heap blocks): the normaliser table's node range,
/// affine map and monomial coefficients (copies of the table's own values, so
/// [`IsoRecord::normaliser`] is bit for bit `Interval::normaliser`), and the disc map.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub(super) struct IsoRecord {
    /// `[lo, hi, centre, scale]`: the node range of `cos θo` and `x = (v − centre) · scale`.
    affine: [f64; 4],
    /// Coefficients of `A cos θo` in `x`, `power[..n]`, the rest zero ([`IsoRecord::normaliser`]
    /// runs all `ISO_TERMS` steps); `n = 0`: the interval's table is evaluated instead (a
    /// longer series, or Clenshaw's form).
    power: [f64; ISO_TERMS],
    n: u32,
    pub(super) map: DiscMap,
}

impl IsoRecord {
    /// The record of one interval of an isotropic (`cos θo`-table) cell.
    pub(super) fn of(iv: &Interval) -> Self {
        let t = &iv.table.theta;
        let (affine, power, n) = iv.table.inline_power::<ISO_TERMS>().unwrap_or((
            [t[t.len() - 1], t[0], 0.0, 0.0],
            [0.0; ISO_TERMS],
            0,
        ));
        Self {
            affine,
            power,
            n: n as u32,
            map: iv.map,
        }
    }

    /// `A(θo)` at `cos θo = cos` for a `cos θo` table: the variable clamped to the nodes,
    /// `A = (A cos θo)(v) / v`, bit for bit `Interval::normaliser` (the same operations on the
    /// same values).
    #[inline]
    pub(super) fn normaliser(&self, cos: f64, iv: &Interval) -> f64 {
        let [lo, hi, centre, scale] = self.affine;
        let v = cos.clamp(lo, hi);
        let n = self.n as usize;
        let p = if n > 0 && n <= ISO_TERMS {
            let x = ((v - centre) * scale).clamp(-1.0, 1.0);
            // All `ISO_TERMS` steps, a fixed trip count (no loop branch): the coefficients
            // past `n` are zero, and from `acc = +0` a step `acc · x + 0` gives `+0` again
            // (`±0 + 0 = +0`), so the first real step and all after it are the `n`-term
            // rule's, bit for bit.
            self.power.iter().rev().fold(0.0, |acc, &a| acc * x + a)
        } else {
            iv.table.eval(v, 0.0)
        };
        p / v
    }
}
