//! A BRDF wrapper that counts evaluations on the calling thread: what the study's cost column,
//! `brdf-lab bench` and the samplers' tests count BRDF evaluations with.

use std::cell::Cell;
use std::sync::Arc;

use crate::{Brdf, Outgoing, Vec3};

thread_local! {
    static EVALUATIONS: Cell<u64> = const { Cell::new(0) };
}

/// Evaluations of every [`CountingBrdf`] made so far on the calling thread.
pub fn thread_evaluations() -> u64 {
    EVALUATIONS.with(Cell::get)
}

/// Forwards everything to the wrapped BRDF (its `prepare` too) and counts each `eval` /
/// `eval_rgb` / `eval_prepared` call in a
/// thread-local counter ([`thread_evaluations`]). Samplers are built on it, so the study
/// counts the BRDF evaluations a sampler makes per sample whatever the sampler is.
///
/// ```
/// use std::sync::Arc;
/// use brdf::{Brdf, CountingBrdf, direction_from_angles, parse_spec, thread_evaluations};
///
/// let counted = CountingBrdf(Arc::from(parse_spec("lambert")?));
/// let wo = direction_from_angles(10.0, 0.0);
/// let before = thread_evaluations();
/// let _ = counted.eval(&wo, &wo);
/// assert_eq!(thread_evaluations() - before, 1);
/// # Ok::<(), brdf::SpecError>(())
/// ```
pub struct CountingBrdf(pub Arc<dyn Brdf>);

impl Brdf for CountingBrdf {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        EVALUATIONS.with(|c| c.set(c.get() + 1));
        self.0.eval(wo, wi)
    }
    #[inline]
    fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        EVALUATIONS.with(|c| c.set(c.get() + 1));
        self.0.eval_rgb(wo, wi)
    }
    #[inline]
    fn eval_prepared(&self, q: &Outgoing, wi: &Vec3) -> f64 {
        EVALUATIONS.with(|c| c.set(c.get() + 1));
        self.0.eval_prepared(q, wi)
    }
    /// The wrapped model's run, each of its evaluations counted.
    fn prepare_run(&self, wo: &Vec3) -> Option<Box<dyn crate::PreparedRun + '_>> {
        self.0
            .prepare_run(wo)
            .map(|run| Box::new(CountedRun(run)) as Box<dyn crate::PreparedRun + '_>)
    }
    // `prepare` is forwarded too (no evaluation, not counted), so a sampler keeps the wrapped
    // model's prepared fast path.
    crate::brdf::forward_brdf_queries!(self => self.0);
}

/// A [`PreparedRun`](crate::PreparedRun) whose evaluations are counted like
/// [`CountingBrdf`]'s.
struct CountedRun<'a>(Box<dyn crate::PreparedRun + 'a>);

impl crate::PreparedRun for CountedRun<'_> {
    #[inline]
    fn eval(&self, wi: &Vec3) -> f64 {
        EVALUATIONS.with(|c| c.set(c.get() + 1));
        self.0.eval(wi)
    }
    /// The wrapped run's block (its lanes kept), each direction counted.
    #[inline]
    fn eval_block(&self, wi: &[Vec3], out: &mut [f64]) {
        let n = wi.len().min(out.len()) as u64;
        EVALUATIONS.with(|c| c.set(c.get() + n));
        self.0.eval_block(wi, out);
    }
    #[inline]
    fn prefers_blocks(&self) -> bool {
        self.0.prefers_blocks()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forwards_what_samplers_ask_of_the_brdf() {
        // The `analytic` sampler reads the model's lobes and format-specific samplers downcast
        // the BRDF: a wrapper that dropped either made those samplers refuse counted BRDFs.
        let phong = CountingBrdf(Arc::from(crate::parse_spec("phong:n=50").unwrap()));
        assert!(phong.analytic_lobes().is_some());
        assert_eq!(
            phong.analytic_lobes(),
            crate::parse_spec("phong:n=50").unwrap().analytic_lobes()
        );
        let inner = crate::parse_spec("lambert").unwrap();
        let lambert = CountingBrdf(Arc::from(crate::parse_spec("lambert").unwrap()));
        assert_eq!(lambert.as_any().is_some(), inner.as_any().is_some());
    }

    #[test]
    fn counts_each_evaluation_on_this_thread() {
        let b = CountingBrdf(Arc::from(crate::parse_spec("lambert").unwrap()));
        let wo = crate::direction_from_angles(10.0, 0.0);
        let before = thread_evaluations();
        let _ = b.eval(&wo, &wo);
        let _ = b.eval_rgb(&wo, &wo);
        assert_eq!(thread_evaluations() - before, 2);
        // The prepared route is counted once and gives the wrapped model's value.
        let phong = crate::parse_spec("phong:n=20").unwrap();
        let counted = CountingBrdf(Arc::from(crate::parse_spec("phong:n=20").unwrap()));
        let wi = crate::direction_from_angles(25.0, 180.0);
        let before = thread_evaluations();
        let q = counted.prepare(&wo);
        assert_eq!(counted.eval_prepared(&q, &wi), phong.eval(&wo, &wi));
        assert_eq!(thread_evaluations() - before, 1);
        let other = std::thread::spawn(thread_evaluations).join().unwrap();
        assert_eq!(other, 0);
    }
}
