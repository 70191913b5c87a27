//! The C allocator's thresholds, raised for the process by freeing one large block (glibc's
//! documented dynamic threshold; no `mallopt`, which is `unsafe`).
//!
//! glibc serves blocks above its mmap threshold by mappings of their own and hands the free
//! top of a heap back to the kernel above its trim threshold. Both start low (128 KiB) and
//! rise only when a mapped block is freed: the mmap threshold to that block's size (up to
//! 32 MiB on 64-bit hosts), the trim threshold to twice it (mallopt(3), "M_MMAP_THRESHOLD").
//! A build frees and allocates blocks of a few MiB per interval (image-map lattices and
//! cells, the envelope nodes' buffers and maps) on every rayon worker's heap: each freed heap
//! top went back to the kernel and the next interval's blocks faulted in zero-filled pages
//! again (`cc_ibiza_sunset`'s `adaptive-exact` build: 8–11·10⁴ minor faults for a 110 MB
//! peak, 0.2–0.3 s of system time, docs/benchmarks.md §28.4). [`raise_thresholds`] frees one
//! mapped block of [`PRIMING_BYTES`] first: the thresholds become ≈ 31 and 62 MiB, freed
//! blocks stay in the heaps for reuse, and the faults fall to the peak's own pages.
//! Elsewhere (another allocator) it is one untouched allocation, freed.

/// The block freed by [`raise_thresholds`]: 31 MiB, so that its mapped size (the request, a
/// header, rounded up to pages) stays within glibc's 32 MiB ceiling for the dynamic threshold.
pub(crate) const PRIMING_BYTES: usize = 31 << 20;

/// Allocates and frees one block of [`PRIMING_BYTES`] (never written: no page is touched).
pub(crate) fn raise_thresholds() {
    let block: Vec<u8> = Vec::with_capacity(PRIMING_BYTES);
    // Kept opaque so that the allocation is not optimised away.
    drop(std::hint::black_box(block));
}

#[cfg(all(test, target_os = "linux", target_env = "gnu"))]
mod tests {
    /// The process's minor page faults so far (`/proc/self/stat`, field 10).
    fn minor_faults() -> u64 {
        let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
        // Fields after the command name (in parentheses, which may hold spaces).
        let rest = &stat[stat.rfind(')').expect("stat") + 2..];
        rest.split(' ')
            .nth(7)
            .expect("minflt")
            .parse()
            .expect("minflt")
    }

    /// A build's pattern: six blocks of 4 MiB allocated, written and freed together, five
    /// rounds, on a thread of its own (its own heap). Unprimed, glibc's trim threshold is
    /// twice the largest mapped block freed (≈ 8 MiB), so the 24 MiB freed at the heap's top go
    /// back to the kernel every round and rounds 3–5 fault in ≈ 3 · 6 · 1024 pages again;
    /// primed, they are reused. Fails with `PRIMING_BYTES = 33 << 20` (above glibc's 32 MiB
    /// ceiling, the threshold then stays dynamic; tried: 18 336 faults), and without the
    /// priming call (tried: 18 336). (The process's other tests may raise the thresholds too:
    /// the break shows when this test runs alone.)
    #[test]
    fn freed_blocks_are_reused_without_faults() {
        super::raise_thresholds();
        let faults = std::thread::spawn(|| {
            let mut late = 0;
            for round in 0..5 {
                let before = minor_faults();
                let blocks: Vec<Vec<u8>> = (0..6).map(|k| vec![k as u8 + 1; 4 << 20]).collect();
                std::hint::black_box(&blocks);
                drop(blocks);
                if round >= 2 {
                    late += minor_faults() - before;
                }
            }
            late
        })
        .join()
        .expect("thread");
        // 3 rounds · 6 blocks · 1024 pages when trimmed; a few hundred for the rest of the
        // process (other tests run beside this one).
        assert!(
            faults < 3 * 6 * 1024 / 4,
            "{faults} minor faults in rounds 3–5"
        );
    }
}
