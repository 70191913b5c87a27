//! Runs every test of the suite on one subject.

use std::sync::{Mutex, RwLock};

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};
use stats::{
    Axis, Binning, MarginalMemo, TestOutcome, expected_masses_with, ks_projection_test_with_memo,
    ks_projection_test_with_singularities, mean_variance, normalisation, pdf_consistency,
    support_coverage, two_sided_z,
};

use crate::cells::{CellModel, ExactTests};
pub use crate::outcomes::names;
pub(crate) use crate::outcomes::{chi_square, error_outcome, skipped_outcome};
use crate::plan::Plan;
use crate::seeding::{chunk_seed, stream_seed};
use crate::subject::{AnySubject, Reference, SamplerUnderTest, Subject};

/// One-sample draws per generator chunk (each chunk has its own generator).
pub const DRAW_CHUNK: usize = 4096;

/// The unbiasedness tests allow a systematic relative error of this many times the sampler's
/// declared normaliser error ([`SamplerUnderTest::normaliser_rel_err`], e.g. a Richardson
/// estimate, which is an estimate, not a bound).
pub const DECLARED_ERROR_FACTOR: f64 = 3.0;

/// A point whose coordinates key the batched pdf cache ([`BatchedPdf`]).
pub(crate) trait PointKey: Copy {
    /// The bit patterns of the coordinates (unused ones 0).
    fn key(&self) -> [u64; 3];
}

impl PointKey for [f64; 2] {
    fn key(&self) -> [u64; 3] {
        [self[0].to_bits(), self[1].to_bits(), 0]
    }
}

impl PointKey for [f64; 3] {
    fn key(&self) -> [u64; 3] {
        [self[0].to_bits(), self[1].to_bits(), self[2].to_bits()]
    }
}

/// A pdf as the quadratures take it.
type PdfFn<'f, P> = dyn Fn(P) -> f64 + Sync + 'f;

/// Most passes of a quadrature over batched pdf values before falling back to single queries
/// (a safety net: every pass but the last evaluates at least one new point, and a run of the
/// suite's quadratures on the broken twin of `validation/tests/it/byo.rs` takes at most a few
/// hundred passes).
const MAX_BATCH_PASSES: usize = 4096;

/// The pdf of a sampler that prefers batched queries
/// ([`SamplerUnderTest::prefers_batches`], e.g. one written in Python), served to the suite's
/// quadratures (which ask one point at a time) from values evaluated in batches, level by
/// level: a quadrature is run with the values known so far and NaN for the others (whose
/// points are recorded); the recorded points are evaluated in one
/// [`SamplerUnderTest::pdf_many`] call, and the quadrature is run again, until a pass asks for
/// no unknown point. The quadratures of `stats` stop refining a cell (or slab) whose estimate
/// is not finite, so a pass records exactly the next refinement level of every cell still
/// refining (all cells of one level in one batched call), never the speculative levels below
/// an unknown value that a finite stand-in (e.g. 0) would trigger. The last pass saw the
/// sampler's own value at every point it asked for, so its result is exactly (bit for bit) the
/// one of single queries. Samplers that do not prefer batches are queried directly.
pub(crate) struct BatchedPdf<'a, P> {
    sampler: &'a dyn SamplerUnderTest<P>,
    values: RwLock<FxHashMap<[u64; 3], f64>>,
}

impl<'a, P: PointKey + Send + Sync> BatchedPdf<'a, P> {
    pub(crate) fn new(sampler: &'a dyn SamplerUnderTest<P>) -> Self {
        Self {
            sampler,
            values: Default::default(),
        }
    }

    /// `f` run with the sampler's pdf (see the type's documentation).
    pub(crate) fn run<R>(&self, f: &dyn Fn(&PdfFn<'_, P>) -> R) -> R {
        if !self.sampler.prefers_batches() {
            return f(&|p| self.sampler.pdf(p));
        }
        for _ in 0..MAX_BATCH_PASSES {
            // The known values are read-only during a pass: one read lock for the whole pass,
            // none per query.
            let missing: Mutex<(FxHashSet<[u64; 3]>, Vec<P>)> = Mutex::default();
            let r = {
                let Ok(values) = self.values.read() else {
                    break;
                };
                let lookup = |p: P| -> f64 {
                    let key = p.key();
                    if let Some(&v) = values.get(&key) {
                        return v;
                    }
                    if let Ok(mut m) = missing.lock()
                        && m.0.insert(key)
                    {
                        m.1.push(p);
                    }
                    f64::NAN
                };
                f(&lookup)
            };
            let points = match missing.into_inner() {
                Ok(m) => m.1,
                Err(_) => break,
            };
            if points.is_empty() {
                return r;
            }
            let got = self.sampler.pdf_many(&points);
            let Ok(mut values) = self.values.write() else {
                break;
            };
            for (p, v) in points.iter().zip(got) {
                values.insert(p.key(), v);
            }
        }
        f(&|p| self.sampler.pdf(p))
    }
}

fn renamed(mut o: TestOutcome, name: &str) -> TestOutcome {
    o.name = name.to_owned();
    o
}

/// Runs every test of the suite on one subject with case seed `seed` (see
/// [`crate::seeding::case_seed`]) and returns the outcomes in report order. p-values are raw:
/// each outcome's `passed` uses a placeholder level of 0.01; [`crate::run`] re-judges them
/// with the Šidák level of the whole run.
pub fn run_case(subject: &AnySubject, plan: &Plan, seed: u64) -> Vec<TestOutcome> {
    match subject {
        AnySubject::Direction(s) => match plan.resolution.sphere_binning(s.domain) {
            Ok(Some(b)) => match s.sampler.pdf_cells() {
                None => run_subject(s, &b, plan, seed, None),
                Some(cells) => match CellModel::new(s.sampler.as_ref(), cells, plan) {
                    Ok(model) => run_subject(s, &b, plan, seed, Some(&model)),
                    Err(e) => vec![error_outcome(names::BUILD, e)],
                },
            },
            Ok(None) => vec![error_outcome(
                names::BUILD,
                "direction subject on a planar domain",
            )],
            Err(e) => vec![error_outcome(names::BUILD, e)],
        },
        AnySubject::Planar(s) => match plan.resolution.planar_binning(s.domain) {
            Ok(Some(b)) => run_subject(s, b.as_ref(), plan, seed, None),
            Ok(None) => vec![error_outcome(
                names::BUILD,
                "planar subject on a direction domain",
            )],
            Err(e) => vec![error_outcome(names::BUILD, e)],
        },
    }
}

/// `n` one-sample draws in fixed chunks of [`DRAW_CHUNK`], chunk `c` with its own generator
/// seeded from `(seed, c)`: the result depends only on `(n, seed)`, not on the thread count.
pub fn draw<P: Copy + Send>(
    sampler: &dyn SamplerUnderTest<P>,
    n: usize,
    seed: u64,
) -> Vec<(P, f64)> {
    let chunks: Vec<Vec<(P, f64)>> = (0..n.div_ceil(DRAW_CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, c as u64));
            let len = DRAW_CHUNK.min(n - c * DRAW_CHUNK);
            sampler.sample_many(len, &mut rng)
        })
        .collect();
    chunks.concat()
}

/// `k` batches of `size` draws, batch `b` with its own generator seeded from `(seed, b)`.
pub fn draw_batches<P: Copy + Send>(
    sampler: &dyn SamplerUnderTest<P>,
    size: usize,
    k: usize,
    seed: u64,
) -> Vec<Vec<(P, f64)>> {
    (0..k)
        .into_par_iter()
        .map(|b| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, b as u64));
            sampler.sample_batch(size, &mut rng)
        })
        .collect()
}

/// `g(x) / pdf(x)`: 0 where `g = 0` (whatever the pdf), `+∞` where `g > 0` but the pdf is not.
fn estimate(g: f64, pdf: f64) -> f64 {
    if g == 0.0 {
        0.0
    } else if pdf > 0.0 {
        g / pdf
    } else {
        f64::INFINITY
    }
}

/// Two-sided z-test of `mean(values)` against `reference`, the standard error combined with a
/// systematic term `√((allowance · |ref|)² + ref.abs_error²)`; judged at `alpha`.
pub fn z_test(
    name: &str,
    values: &[f64],
    reference: &Reference,
    allowance: f64,
    alpha: f64,
) -> TestOutcome {
    if values.len() < 2 {
        return error_outcome(
            name,
            format!("need at least 2 values, got {}", values.len()),
        );
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return TestOutcome::with_p_value(
            name,
            f64::INFINITY,
            0.0,
            alpha,
            format!(
                "estimator value {i} is not finite ({}): a sample landed where the integrand is positive but the pdf is not",
                values[i]
            ),
        );
    }
    let (mean, var) = mean_variance(values);
    let se = (var / values.len() as f64).sqrt();
    let sys = ((allowance * reference.value).powi(2) + reference.abs_error.powi(2)).sqrt();
    let total = (se * se + sys * sys)
        .sqrt()
        .max(1e-12 * mean.abs().max(reference.value.abs()));
    let (z, p) = two_sided_z(mean, reference.value, total);
    let detail = format!(
        "mean {mean:.8e} vs reference {:.8e} (rel. dev. {:.2e}); standard error {se:.3e}, systematic allowance {sys:.3e}; z = {z:.3}, n = {}",
        reference.value,
        (mean - reference.value) / reference.value.abs().max(f64::MIN_POSITIVE),
        values.len()
    );
    TestOutcome::with_p_value(name, z, p, alpha, detail)
}

/// Parameter coordinates of the declared singular points inside the domain, each with copies
/// shifted by `±` the `v` range (so a point near the seam of a periodic `φ` is graded towards
/// from both sides; copies beyond one piece of the range are ignored by the grading).
fn singular_params<P: Copy + Send + Sync>(
    binning: &dyn Binning<Point = P>,
    points: &[P],
) -> Vec<[f64; 2]> {
    let v = binning.grid().v_range();
    let period = v[1] - v[0];
    points
        .iter()
        .filter_map(|p| binning.param_of(p))
        .flat_map(|[a, b]| [[a, b], [a, b - period], [a, b + period]])
        .collect()
}

/// Every test of the suite on `s` (binned by `binning`), in report order. p-values are judged
/// at a placeholder level here; the run re-judges them with the Šidák level.
///
/// With `exact` (a sampler that declares where its pdf is piecewise constant), the χ², KS and
/// normalisation tests are its exact versions, followed by the check of the declaration
/// ([`crate::cells`]); otherwise they integrate the pdf by adaptive quadrature.
pub(crate) fn run_subject<P: PointKey + Send + Sync + 'static>(
    s: &Subject<P>,
    binning: &dyn Binning<Point = P>,
    plan: &Plan,
    seed: u64,
    exact: Option<&dyn ExactTests<P>>,
) -> Vec<TestOutcome> {
    let alpha = 0.01;
    let sampler = s.sampler.as_ref();
    let violations_before = sampler.bound_violations();
    let singles = draw(sampler, plan.samples, stream_seed(seed, 1));
    let batches = draw_batches(sampler, plan.batch_size, plan.batches, stream_seed(seed, 2));
    let violations_after = sampler.bound_violations();

    let batched = BatchedPdf::new(sampler);
    let points: Vec<P> = singles.iter().map(|s| s.0).collect();
    let batch_points: Vec<P> = batches.iter().flatten().map(|s| s.0).collect();
    let opts = &plan.quadrature;
    let mut out = Vec::with_capacity(11);

    let axis_names = s.domain.axis_names();
    if let Some(exact) = exact {
        out.extend(exact.distribution_tests(&points, &batch_points, axis_names, plan, alpha));
    } else {
        let n_max = points.len().max(batch_points.len()) as u64;
        match batched.run(&|pdf| expected_masses_with(pdf, binning, n_max, opts)) {
            Ok(table) => {
                out.push(chi_square(
                    names::CHI_SQUARE,
                    binning,
                    &table.masses,
                    &points,
                    alpha,
                ));
                out.push(chi_square(
                    names::BATCH_CHI_SQUARE,
                    binning,
                    &table.masses,
                    &batch_points,
                    alpha,
                ));
            }
            Err(e) => {
                out.push(error_outcome(names::CHI_SQUARE, &e));
                out.push(error_outcome(names::BATCH_CHI_SQUARE, &e));
            }
        }
        let singular = singular_params(binning, &sampler.singular_points());
        for (axis, name) in [Axis::U, Axis::V].into_iter().zip(axis_names) {
            // The marginals of the projection CDF finished in one batched pass are kept for
            // the next (each pass then refines only those still refining).
            let memo = MarginalMemo::default();
            out.push(
                match batched.run(&|pdf| {
                    if sampler.prefers_batches() {
                        ks_projection_test_with_memo(
                            binning, pdf, &points, axis, alpha, opts, &singular, &memo,
                        )
                    } else {
                        ks_projection_test_with_singularities(
                            binning, pdf, &points, axis, alpha, opts, &singular,
                        )
                    }
                }) {
                    Ok(o) => renamed(o, name),
                    Err(e) => error_outcome(name, e),
                },
            );
        }
    }
    let all: Vec<(P, f64)> = singles
        .iter()
        .chain(batches.iter().flatten())
        .copied()
        .collect();
    // The pdfs re-evaluated in one call (a sampler may batch them), checked by sample index.
    let again = sampler.pdf_many(&all.iter().map(|s| s.0).collect::<Vec<P>>());
    let indexed: Vec<(usize, f64)> = all.iter().enumerate().map(|(i, s)| (i, s.1)).collect();
    let again_at = |i: usize| again[i];
    out.push(
        match pdf_consistency(&indexed, &again_at, plan.pdf_rel_tol) {
            Ok(o) => renamed(o, names::PDF_CONSISTENCY),
            Err(e) => error_outcome(names::PDF_CONSISTENCY, e),
        },
    );
    match exact {
        Some(exact) => out.extend(exact.normalisation_tests(plan)),
        None => out.push(
            match batched
                .run(&|pdf| normalisation(binning, pdf, 1.0, plan.normalisation_tolerance, opts))
            {
                Ok(o) => renamed(o, names::NORMALISATION),
                Err(e) => error_outcome(names::NORMALISATION, e),
            },
        ),
    }
    let target = s.target.as_ref();
    out.push(
        match batched
            .run(&|pdf| support_coverage(binning, target, pdf, plan.support_resolution, opts))
        {
            Ok(o) => renamed(o, names::SUPPORT),
            Err(e) => error_outcome(names::SUPPORT, e),
        },
    );

    // The estimator's bias may reach the normaliser's error: allow the larger of the plan's
    // allowance and DECLARED_ERROR_FACTOR times the sampler's own estimate.
    let declared = sampler.normaliser_rel_err();
    let allowance = declared.map_or(plan.unbiasedness_allowance, |d| {
        plan.unbiasedness_allowance.max(DECLARED_ERROR_FACTOR * d)
    });
    let g = s.single.integrand.as_ref();
    let values: Vec<f64> = singles.iter().map(|&(p, q)| estimate(g(p), q)).collect();
    let mut o = z_test(
        names::UNBIASEDNESS,
        &values,
        &s.single.reference,
        allowance,
        alpha,
    );
    o.detail = format!("estimand {}: {}", s.single.label, o.detail);
    out.push(o);

    let short: Vec<(usize, usize)> = batches
        .iter()
        .enumerate()
        .filter(|(_, b)| b.len() != plan.batch_size)
        .map(|(i, b)| (i, b.len()))
        .collect();
    out.push(TestOutcome::deterministic(
        names::BATCH_SIZE,
        short.len() as f64,
        short.is_empty(),
        match short.first() {
            None => format!(
                "all {} batches returned {} samples",
                batches.len(),
                plan.batch_size
            ),
            Some(&(i, len)) => format!(
                "{} of {} batches returned a number of samples other than {} (first: batch {i} with {len})",
                short.len(),
                batches.len(),
                plan.batch_size
            ),
        },
    ));

    let g = s.batch.integrand.as_ref();
    let b = plan.batch_size as f64;
    let means: Vec<f64> = batches
        .iter()
        .map(|batch| batch.iter().map(|&(p, q)| estimate(g(p), q)).sum::<f64>() / b)
        .collect();
    let mut o = z_test(
        names::BATCH_UNBIASEDNESS,
        &means,
        &s.batch.reference,
        allowance,
        alpha,
    );
    o.detail = format!(
        "estimand {}, {} batches of {}: {}",
        s.batch.label,
        batches.len(),
        plan.batch_size,
        o.detail
    );
    out.push(o);

    if let (Some(before), Some(after)) = (violations_before, violations_after) {
        let v = after.saturating_sub(before);
        out.push(TestOutcome::deterministic(
            names::BOUND_AUDIT,
            v as f64,
            v == 0,
            format!(
                "{v} rejection trials with f > M_i while drawing {} + {} samples",
                points.len(),
                batch_points.len()
            ),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adapters::DirectionAtWo;
    use crate::mutants::CosineHemisphere;
    use std::sync::Arc;

    fn reference(value: f64) -> Reference {
        Reference {
            value,
            abs_error: 0.0,
            rule: "test".into(),
        }
    }

    #[test]
    fn z_test_accepts_the_truth_and_rejects_a_shift() {
        let values: Vec<f64> = (0..1000)
            .map(|i| 1.0 + ((i % 7) as f64 - 3.0) * 0.1)
            .collect();
        let ok = z_test("u", &values, &reference(1.0), 0.0, 0.01);
        assert!(ok.passed && ok.p_value.is_some_and(|p| p > 0.9));
        // Standard error ≈ 0.2/√1000 ≈ 0.0063: a shift of 0.1 is 15 standard errors.
        let bad = z_test("u", &values, &reference(1.1), 0.0, 0.01);
        assert!(!bad.passed && bad.p_value.is_some_and(|p| p < 1e-20));
        let inf = z_test("u", &[1.0, f64::INFINITY], &reference(1.0), 0.0, 0.01);
        assert_eq!(inf.p_value, Some(0.0));
        assert!(!z_test("u", &[1.0], &reference(1.0), 0.0, 0.01).passed);
    }

    #[test]
    fn z_test_allowance_covers_a_declared_systematic_error() {
        // A zero-variance estimator 1e-5 (relative) off its reference.
        let values = vec![1.0 + 1e-5; 100];
        assert!(!z_test("u", &values, &reference(1.0), 0.0, 0.01).passed);
        assert!(z_test("u", &values, &reference(1.0), 1e-4, 0.01).passed);
    }

    #[test]
    fn estimates_treat_zero_integrands_and_missing_pdfs() {
        assert_eq!(estimate(0.0, 0.0), 0.0);
        assert_eq!(estimate(2.0, 4.0), 0.5);
        assert!(estimate(1.0, 0.0).is_infinite());
    }

    #[test]
    fn draws_depend_only_on_seed_and_extend_as_prefixes() {
        let s = DirectionAtWo::new(Arc::new(CosineHemisphere), brdf::Vec3::new(0.0, 0.0, 1.0));
        let a = draw(&s, 5000, 9);
        let b = draw(&s, 9000, 9);
        assert_eq!(a.as_slice(), &b[..5000]);
        assert_ne!(a, draw(&s, 5000, 10));
        let k = draw_batches(&s, 16, 4, 3);
        assert_eq!(k.len(), 4);
        assert!(k.iter().all(|b| b.len() == 16));
        assert_eq!(k, draw_batches(&s, 16, 4, 3));
    }
}
