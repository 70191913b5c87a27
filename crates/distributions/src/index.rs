//! Float ↔ index conversions for the sampling loops, with the results of the plain casts.
//!
//! On x86-64 `x as usize` (saturating, NaN → 0) compiles to ≈ 17 instructions and
//! `i as f64` from a `usize` to ≈ 6 (there is no unsigned 64-bit conversion before
//! AVX-512); the 32-bit and signed routes below take 7–10 and 1. A sampling trial makes a
//! handful of these conversions, so they were a measurable share of its instructions.

/// `(x as usize).min(last)`: the same index for every `x` (NaN and negatives give 0, values
/// above `last` give `last`), through a 32-bit conversion when `last` fits in `u32` (the
/// other branch is never taken by a table that fits in memory, and is predicted).
#[inline(always)]
pub fn floor_index(x: f64, last: usize) -> usize {
    match u32::try_from(last) {
        Ok(last) => (x as u32).min(last) as usize,
        Err(_) => (x as usize).min(last),
    }
}

/// `i as f64` for an index `i` (of a slice, so `i ≤ isize::MAX`): one signed conversion.
#[inline(always)]
pub fn index_to_f64(i: usize) -> f64 {
    i as i64 as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_index_is_the_saturating_cast() {
        let xs = [
            f64::NAN,
            f64::NEG_INFINITY,
            -1e300,
            -1.0,
            -0.0,
            0.0,
            0.5,
            1.0,
            1.0f64.next_down(),
            6.999_999,
            7.0,
            1e9,
            4_294_967_295.5,
            4_294_967_296.0,
            1e19,
            1e300,
            f64::INFINITY,
        ];
        for last in [
            0usize,
            1,
            7,
            1023,
            u32::MAX as usize,
            u32::MAX as usize + 1,
            usize::MAX,
        ] {
            for &x in &xs {
                assert_eq!(
                    floor_index(x, last),
                    (x as usize).min(last),
                    "x {x}, last {last}"
                );
            }
        }
    }

    #[test]
    fn index_to_f64_is_the_cast() {
        for i in [
            0usize,
            1,
            1023,
            u32::MAX as usize,
            1 << 53,
            (1 << 53) + 1,
            isize::MAX as usize,
        ] {
            assert_eq!(index_to_f64(i).to_bits(), (i as f64).to_bits());
        }
    }
}
