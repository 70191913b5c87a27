//! Trial and bound-violation accounting without shared writes on the hot path.
//!
//! Callers that want exact local numbers use an [`Audit`] (plain integers, merged with
//! [`crate::diagnostics::AuditedDraws::record_audit`]). Batch and parallel calls count locally and flush
//! once per call or chunk (relaxed atomics). The plain one-sample `sample()` adds its trial
//! count to a thread-local buffer that is flushed every [`FLUSH_EVERY`] samples, when the
//! thread switches to another sampler, when [`crate::QuadTreeSampler::stats`] is called from
//! that thread, and at thread exit; a bound violation is flushed immediately.

use std::cell::{Cell, RefCell};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// How many plain `sample()` calls a thread buffers before flushing its counts.
pub const FLUSH_EVERY: u64 = 4096;

/// Local counts of a sampling run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Audit {
    /// Rejection trials (points drawn in a rejection rectangle).
    pub trials: u64,
    /// Samples returned.
    pub samples: u64,
    /// Trials where `f(x) > M_i` (the leaf bound was wrong).
    pub violations: u64,
    /// Samples returned with pdf 0 because the trial cap was hit (see
    /// [`crate::MAX_TRIALS_PER_SAMPLE`]).
    pub exhausted: u64,
}

impl Audit {
    /// Adds `other` into `self`.
    pub fn merge(&mut self, other: &Audit) {
        self.trials += other.trials;
        self.samples += other.samples;
        self.violations += other.violations;
        self.exhausted += other.exhausted;
    }
}

thread_local! {
    /// Rejection trials recorded on this thread (read by cost measurements).
    static THREAD_TRIALS: Cell<u64> = const { Cell::new(0) };
}

/// Rejection trials (proposals, accepted or not) recorded on the calling thread so far by
/// the samplers' counters: a monotone counter whose difference over a sequential run, divided
/// by the samples returned, is the run's mean trials per sample. Samplers that make one
/// proposal per sample record nothing.
pub fn thread_trials() -> u64 {
    THREAD_TRIALS.with(Cell::get)
}

/// Adds `n` trials to the calling thread's [`thread_trials`] (for a rejection sampler that
/// keeps no [`Audit`]; this crate's samplers count through their audits).
#[inline]
pub fn count_trials(n: u64) {
    THREAD_TRIALS.with(|c| c.set(c.get() + n));
}

/// Shared counters of one sampler.
#[derive(Debug, Default)]
pub(crate) struct Counters {
    trials: AtomicU64,
    samples: AtomicU64,
    violations: AtomicU64,
    exhausted: AtomicU64,
}

impl Counters {
    /// Adds a run's counts made on the calling thread, also into [`thread_trials`].
    pub(crate) fn record(&self, a: &Audit) {
        count_trials(a.trials);
        self.add(a);
    }

    pub(crate) fn add(&self, a: &Audit) {
        if a.trials > 0 {
            self.trials.fetch_add(a.trials, Relaxed);
        }
        if a.samples > 0 {
            self.samples.fetch_add(a.samples, Relaxed);
        }
        if a.violations > 0 {
            self.violations.fetch_add(a.violations, Relaxed);
        }
        if a.exhausted > 0 {
            self.exhausted.fetch_add(a.exhausted, Relaxed);
        }
    }

    pub(crate) fn snapshot(&self) -> Audit {
        Audit {
            trials: self.trials.load(Relaxed),
            samples: self.samples.load(Relaxed),
            violations: self.violations.load(Relaxed),
            exhausted: self.exhausted.load(Relaxed),
        }
    }

    pub(crate) fn reset(&self) {
        self.trials.store(0, Relaxed);
        self.samples.store(0, Relaxed);
        self.violations.store(0, Relaxed);
        self.exhausted.store(0, Relaxed);
    }
}

/// A thread's buffered counts for the sampler it used last. The fast path touches only the
/// `Cell`s; `id` is the address of the target's counters, which cannot be reused while
/// `target` keeps them alive.
struct Pending {
    id: Cell<usize>,
    trials: Cell<u64>,
    samples: Cell<u64>,
    target: RefCell<Option<Arc<Counters>>>,
}

impl Pending {
    fn flush(&self) {
        if let Ok(t) = self.target.try_borrow()
            && let Some(t) = t.as_ref()
        {
            t.add(&Audit {
                trials: self.trials.get(),
                samples: self.samples.get(),
                violations: 0,
                exhausted: 0,
            });
        }
        self.trials.set(0);
        self.samples.set(0);
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        self.flush();
    }
}

thread_local! {
    static PENDING: Pending = const {
        Pending { id: Cell::new(0), trials: Cell::new(0), samples: Cell::new(0), target: RefCell::new(None) }
    };
}

/// Buffers one plain sample's counts (violations and exhaustion go straight to `counters`).
#[inline]
pub(crate) fn record_one(counters: &Arc<Counters>, a: &Audit) {
    count_trials(a.trials);
    if a.violations > 0 || a.exhausted > 0 {
        counters.add(&Audit {
            trials: 0,
            samples: 0,
            violations: a.violations,
            exhausted: a.exhausted,
        });
    }
    let _ = PENDING.try_with(|p| {
        let id = Arc::as_ptr(counters) as usize;
        if p.id.get() != id {
            p.flush();
            let Ok(mut t) = p.target.try_borrow_mut() else {
                return;
            };
            *t = Some(Arc::clone(counters));
            p.id.set(id);
        }
        p.trials.set(p.trials.get() + a.trials);
        let s = p.samples.get() + a.samples;
        p.samples.set(s);
        if s >= FLUSH_EVERY {
            p.flush();
        }
    });
}

/// Flushes the calling thread's buffer if it belongs to `counters`.
pub(crate) fn flush_local(counters: &Arc<Counters>) {
    let _ = PENDING.try_with(|p| {
        if p.id.get() == Arc::as_ptr(counters) as usize {
            p.flush();
        }
    });
}

/// Shared counters of a sampler made of several samplers (e.g. a set of quadtrees, one per
/// outgoing angle), fed with [`Audit`]s the way [`crate::QuadTreeSampler::sample`] feeds its
/// own: a thread-local buffer for trials and samples (flushed every [`FLUSH_EVERY`] records,
/// when the thread records into other counters, by [`AuditCounters::snapshot`] and at thread
/// exit), violations and exhausted samples added at once. Recording into one set's counters
/// from draws of many trees avoids a buffer flush at every switch of tree.
#[derive(Debug, Default)]
pub struct AuditCounters(Arc<Counters>);

impl AuditCounters {
    /// Zeroed counters.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the counts of one sample (or of several).
    #[inline]
    pub fn record(&self, a: &Audit) {
        record_one(&self.0, a);
    }

    /// The counts so far (flushes the calling thread's buffer first).
    pub fn snapshot(&self) -> Audit {
        flush_local(&self.0);
        self.0.snapshot()
    }

    /// Zeroes the counters (and the calling thread's buffer).
    pub fn reset(&self) {
        flush_local(&self.0);
        self.0.reset();
    }
}
