//! Seeds: every case derives its generators from the master seed and its own label, so a case
//! gives the same samples whatever else runs and however many threads run it.

pub use partition_sampler::chunk_seed;

/// 64-bit FNV-1a hash of a label.
pub fn label_hash(label: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in label.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The seed of the case `label` in a run with master seed `seed`.
pub fn case_seed(seed: u64, label: &str) -> u64 {
    chunk_seed(seed, label_hash(label))
}

/// The seed of stream `stream` (1 = one-sample draws, 2 = batches) of a case.
pub fn stream_seed(case_seed: u64, stream: u64) -> u64 {
    chunk_seed(case_seed, stream.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_are_fnv1a_and_seeds_separate_labels() {
        assert_eq!(label_hash(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(label_hash("a"), 0xaf63_dc4c_8601_ec8c);
        assert_ne!(case_seed(1, "a|b"), case_seed(1, "a|c"));
        assert_ne!(case_seed(1, "a"), case_seed(2, "a"));
        assert_ne!(stream_seed(5, 1), stream_seed(5, 2));
    }
}
