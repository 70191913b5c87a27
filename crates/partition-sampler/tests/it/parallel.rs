//! Reproducibility of the generic parallel batch sampler [`partition_sampler::sample_par`].

use distributions::on_threads;
use partition_sampler::{PAR_CHUNK as CHUNK, PiecewiseConstant2D, Rect, Sampler2D};

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
    let one = on_threads(1, || t.sample_par(n, 11)).unwrap();
    let two = on_threads(2, || t.sample_par(n, 11)).unwrap();
    assert_eq!(one, two);
    assert_eq!(one.len(), n);
    assert_ne!(one, t.sample_par(n, 12));
}

#[test]
fn chunk_k_uses_generator_k() {
    let t = table();
    let batch = t.sample_par(2 * CHUNK, 5);
    let mut rng = partition_sampler::chunk_rng(5, 1);
    for s in &batch[CHUNK..CHUNK + 10] {
        assert_eq!(*s, t.sample(&mut rng));
    }
    // Chunks are not copies of each other.
    assert_ne!(batch[0], batch[CHUNK]);
}

#[test]
fn every_sampler_shares_the_generic_function() {
    let t = table();
    assert_eq!(
        t.sample_par(CHUNK + 3, 9),
        partition_sampler::sample_par(&t, CHUNK + 3, 9)
    );

    let v: Vec<f64> = (0..64).map(|i| 1.0 + (i % 7) as f64).collect();
    let d = partition_sampler::TabulatedDensity::new(8, 8, v, Rect::UNIT).unwrap();
    let q = partition_sampler::QuadTreeBuilder::new().build(d).unwrap();
    let batch = q.sample_par(CHUNK + 3, 9);
    assert_eq!(batch, partition_sampler::sample_par(&q, CHUNK + 3, 9));
    // Chunk 1 is drawn in order from generator 1, as one-sample calls would draw it.
    let mut rng = partition_sampler::chunk_rng(9, 1);
    for s in &batch[CHUNK..] {
        assert_eq!(*s, q.sample(&mut rng));
    }
    // The trial counters saw both batches (counted once per chunk) and the 3 single draws.
    assert_eq!(q.stats().samples, 2 * (CHUNK as u64 + 3) + 3);
}
