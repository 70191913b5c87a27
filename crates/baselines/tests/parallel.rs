//! Reproducibility of the parallel batch sampler.

use baselines::parallel::CHUNK;
use partition_sampler::Sampler2D;
use partition_sampler::{PiecewiseConstant2D, Rect};

fn table() -> PiecewiseConstant2D {
    let v: Vec<f64> = (0..64).map(|i| (i % 5) as f64).collect();
    PiecewiseConstant2D::new(
        8,
        8,
        v,
        Rect {
            x0: 0.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
        },
    )
    .unwrap()
}

#[test]
fn result_does_not_depend_on_thread_count() {
    let t = table();
    let n = 3 * CHUNK + 17;
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| t.sample_par(n, 11));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| t.sample_par(n, 11));
    assert_eq!(one, two);
    assert_eq!(one.len(), n);
    assert_ne!(one, t.sample_par(n, 12));
}

#[test]
fn chunk_k_uses_generator_k() {
    let t = table();
    let batch = t.sample_par(2 * CHUNK, 5);
    let mut rng = baselines::parallel::chunk_rng(5, 1);
    for s in &batch[CHUNK..CHUNK + 10] {
        assert_eq!(*s, t.sample(&mut rng));
    }
    // Chunks are not copies of each other.
    assert_ne!(batch[0], batch[CHUNK]);
}
