//! Reproducible parallel sampling, the one implementation every planar sampler uses: fixed
//! chunks of [`PAR_CHUNK`] samples, one `Xoshiro256PlusPlus` per chunk seeded by
//! [`chunk_seed`]`(seed, chunk)`, so the output depends only on `(n, seed)`.

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;

use crate::contract::{Sample2, Sampler2D};

/// Samples per chunk of [`sample_par`]; each chunk has its own generator.
pub const PAR_CHUNK: usize = 4096;

/// `f` run inside a new rayon pool of `threads` threads: how a caller checks that a parallel
/// result does not depend on the thread count (run it on 1 and on 2 threads, compare).
///
/// Errors: the pool cannot be built (e.g. the system refuses to start threads).
pub fn on_threads<T: Send>(
    threads: usize,
    f: impl FnOnce() -> T + Send,
) -> Result<T, rayon::ThreadPoolBuildError> {
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?
        .install(f))
}

/// CPU seconds (user + system) of the calling thread, from `/proc/thread-self/stat` (Linux;
/// clock ticks of 1/100 s); `None` where that file does not exist or does not parse. The cost
/// figure of a one-thread sampling loop to quote on a loaded machine.
pub fn thread_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.get(stat.rfind(')')? + 2..)?;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// SplitMix64 finaliser.
#[inline]
pub(crate) fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Seed of chunk `c` of a run seeded with `seed` (SplitMix64 mixing of both).
pub fn chunk_seed(seed: u64, c: u64) -> u64 {
    splitmix64(splitmix64(seed) ^ splitmix64(c.wrapping_add(0x632B_E59B_D9B4_E019)))
}

/// The generator of chunk `chunk` of a run seeded with `seed`: `Xoshiro256PlusPlus` seeded with
/// [`chunk_seed`]`(seed, chunk)`.
pub fn chunk_rng(seed: u64, chunk: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, chunk))
}

/// Draws `n` samples of `sampler` with rayon. Sample `k` comes from chunk `k / PAR_CHUNK`, whose
/// samples are drawn in order by [`Sampler2D::sample_into`] from [`chunk_rng`]`(seed, k /
/// PAR_CHUNK)`, so the output depends only on `(n, seed)`, never on the number of threads.
///
/// ```
/// use distributions::{PiecewiseConstant2D, Rect, sample_par};
/// let table = PiecewiseConstant2D::new(2, 1, vec![1.0, 3.0], Rect::UNIT).unwrap();
/// let batch = sample_par(&table, 10_000, 42);
/// assert_eq!(batch, sample_par(&table, 10_000, 42));
/// ```
pub fn sample_par<S: Sampler2D + ?Sized>(sampler: &S, n: usize, seed: u64) -> Vec<Sample2> {
    let mut out = vec![
        Sample2 {
            point: [0.0, 0.0],
            pdf: 0.0
        };
        n
    ];
    out.par_chunks_mut(PAR_CHUNK)
        .enumerate()
        .for_each(|(chunk, slot)| sampler.sample_into(&mut chunk_rng(seed, chunk as u64), slot));
    out
}

/// One part `K/N` of a run split over independent processes (`--shard K/N` of `brdf-lab study`
/// and `brdf-lab validate`): the items `i` of the full run (cells, cases; in its fixed order)
/// with `i mod N = K − 1`. Each item is seeded on its own (as [`chunk_seed`] seeds chunks), so a
/// shard gives the same results for its items as the whole run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// `K` of `K/N`, from 1.
    pub index: usize,
    /// `N` of `K/N`.
    pub count: usize,
}

/// `--shard` text that is not `K/N` with `1 ≤ K ≤ N`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--shard {0}: expected K/N with 1 <= K <= N")]
pub struct ShardError(pub String);

impl Shard {
    /// Parses `K/N` with `1 <= K <= N`.
    ///
    /// # Errors
    /// [`ShardError`] for anything else.
    pub fn parse(s: &str) -> Result<Self, ShardError> {
        let bad = || ShardError(s.to_string());
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if !(1..=count).contains(&index) {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// Whether item `i` of the full run belongs to this shard.
    pub fn contains(&self, i: usize) -> bool {
        i % self.count == self.index - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_threads_runs_inside_a_pool_of_that_size() {
        for threads in [1, 3] {
            let seen = on_threads(threads, rayon::current_num_threads).unwrap();
            assert_eq!(seen, threads);
        }
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn thread_cpu_seconds_reads_a_non_decreasing_clock_on_linux() {
        let before = thread_cpu_seconds().expect("/proc/thread-self/stat readable");
        let after = thread_cpu_seconds().unwrap();
        assert!(before >= 0.0 && after >= before, "{before} then {after}");
    }
}
