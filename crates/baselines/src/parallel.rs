//! Reproducible parallel sampling: fixed chunks, one generator per chunk, the same chunking
//! and seeding as `partition_sampler::QuadTreeSampler::sample_par`.

use partition_sampler::{Sample2, Sampler2D};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;

/// Number of samples drawn with one generator in [`sample_par`] (`partition_sampler::PAR_CHUNK`).
pub const CHUNK: usize = partition_sampler::PAR_CHUNK;

/// The generator of chunk `chunk` of a run seeded with `seed`: `Xoshiro256PlusPlus` seeded with
/// `partition_sampler::chunk_seed(seed, chunk)` (SplitMix64 mixing of both).
pub fn chunk_rng(seed: u64, chunk: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(partition_sampler::chunk_seed(seed, chunk))
}

/// Draws `n` samples of `sampler` with rayon. Sample `k` comes from chunk `k / CHUNK`, whose
/// generator is [`chunk_rng`]`(seed, k / CHUNK)`, so the output depends only on `(n, seed)`,
/// never on the number of threads.
pub fn sample_par<S: Sampler2D + ?Sized>(sampler: &S, n: usize, seed: u64) -> Vec<Sample2> {
    let mut out = vec![
        Sample2 {
            point: [0.0, 0.0],
            pdf: 0.0
        };
        n
    ];
    out.par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(chunk, slot)| {
            let mut rng = chunk_rng(seed, chunk as u64);
            for s in slot {
                *s = sampler.sample(&mut rng);
            }
        });
    out
}
