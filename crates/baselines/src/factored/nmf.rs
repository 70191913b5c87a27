//! Weighted non-negative matrix factorisation by Lee–Seung multiplicative updates
//! (Lee & Seung 2001; weighted form as in Guillamet et al. 2003; baselines.md §A.3).
//!
//! `Y ≈ F G` with `Y ∈ ℝ₊^{n×m}`, `F ∈ ℝ₊^{n×r}`, `G ∈ ℝ₊^{r×m}` and a non-negative weight
//! mask `M` (`None` = all ones). Updates, with `⊙`/`⊘` element-wise and [`EPSILON`] added to
//! every denominator:
//! * Euclidean, cost `‖M⊙(Y − FG)‖²`:
//!   `G ← G ⊙ [Fᵀ(M⊙Y)] ⊘ [Fᵀ(M⊙FG)]`, then `F ← F ⊙ [(M⊙Y)Gᵀ] ⊘ [(M⊙FG)Gᵀ]`;
//! * Kullback–Leibler, cost `Σ M (Y ln(Y/FG) − Y + FG)`:
//!   `G ← G ⊙ [Fᵀ(M⊙Y⊘FG)] ⊘ [FᵀM]`, then `F ← F ⊙ [(M⊙Y⊘FG)Gᵀ] ⊘ [MGᵀ]`.
//!
//! Both costs are non-increasing under these updates (the Lee–Seung auxiliary-function
//! argument). The initial factors are seeded uniform in `(0, 1]·s` with
//! `s = √(mean(M⊙Y)/r)`, so that `FG` starts at the data's scale; never exact zeros, which
//! multiplicative updates could not leave. The loop stops when the relative change of the
//! cost falls below the tolerance or at the iteration cap; a capped run is kept and reports
//! `converged = false` with its residual. Matrix products are nalgebra's (`DMatrix`), which
//! are deterministic, so the result depends only on the seed.

use nalgebra::DMatrix;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::options::NmfCost;

/// Added to every denominator of the updates (baselines.md §A.3).
pub const EPSILON: f64 = 1e-12;

/// Settings of one factorisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NmfSettings {
    /// Inner dimension `r` of `F G` (≥ 1).
    pub rank: usize,
    /// The cost minimised.
    pub cost: NmfCost,
    /// Iteration cap (≥ 1).
    pub max_iterations: usize,
    /// Stop when `|c_{k−1} − c_k| ≤ tolerance · c_{k−1}`.
    pub tolerance: f64,
    /// Seed of the initial factors.
    pub seed: u64,
}

/// How a factorisation ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NmfStats {
    /// Iterations run (each updates `G` then `F`).
    pub iterations: usize,
    /// Whether the relative cost change fell below the tolerance before the cap.
    pub converged: bool,
    /// The final cost (of [`NmfSettings::cost`]).
    pub cost: f64,
    /// Relative approximation error `‖M⊙(Y − FG)‖_F / ‖M⊙Y‖_F` (Frobenius, for either cost).
    pub relative_error: f64,
}

/// A factorisation `Y ≈ F G`.
#[derive(Debug, Clone, PartialEq)]
pub struct Nmf {
    /// `n × r`, non-negative.
    pub f: DMatrix<f64>,
    /// `r × m`, non-negative.
    pub g: DMatrix<f64>,
    /// How it ended.
    pub stats: NmfStats,
    /// The cost before the first update and after each iteration (`iterations + 1` values).
    pub cost_history: Vec<f64>,
}

/// Why a factorisation could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NmfError {
    /// The mask's shape differs from the data's.
    #[error("mask is {mask_rows}×{mask_cols} but the data are {rows}×{cols}")]
    MaskShape {
        /// Data rows.
        rows: usize,
        /// Data columns.
        cols: usize,
        /// Mask rows.
        mask_rows: usize,
        /// Mask columns.
        mask_cols: usize,
    },
    /// An entry of the data or of the mask is negative, NaN or infinite.
    #[error("entry ({row}, {col}) of the {what} is {value}, not a finite value ≥ 0")]
    BadEntry {
        /// `data` or `mask`.
        what: &'static str,
        /// Its row.
        row: usize,
        /// Its column.
        col: usize,
        /// Its value.
        value: f64,
    },
    /// Every weighted entry is zero: there is nothing to factorise.
    #[error("the weighted data are all zero")]
    ZeroData,
    /// The rank or the iteration cap is zero, or the tolerance is not in (0, 1).
    #[error(
        "invalid settings: rank {rank}, max iterations {max_iterations}, tolerance {tolerance}"
    )]
    Settings {
        /// The rank.
        rank: usize,
        /// The iteration cap.
        max_iterations: usize,
        /// The tolerance.
        tolerance: f64,
    },
}

/// Factorises `y ≈ F G` under the weight `mask` (`None`: all ones).
///
/// Errors: [`NmfError`] for a mask of the wrong shape, negative or non-finite entries,
/// all-zero weighted data or invalid settings. Not converging is not an error: see
/// [`NmfStats::converged`].
pub fn factorise(
    y: &DMatrix<f64>,
    mask: Option<&DMatrix<f64>>,
    settings: &NmfSettings,
) -> Result<Nmf, NmfError> {
    check(y, mask, settings)?;
    let (n, m) = y.shape();
    let r = settings.rank;
    let weighted = |x: &DMatrix<f64>| match mask {
        Some(w) => x.component_mul(w),
        None => x.clone(),
    };
    let my = weighted(y);
    let weight_total = mask.map_or((n * m) as f64, |w| w.sum());
    let mean = my.sum() / weight_total;
    if !(mean > 0.0) {
        return Err(NmfError::ZeroData);
    }
    let scale = (mean / r as f64).sqrt();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(settings.seed);
    // (0, 1]: 1 − [0, 1).
    let mut f = DMatrix::from_fn(n, r, |_, _| (1.0 - rng.random::<f64>()) * scale);
    let mut g = DMatrix::from_fn(r, m, |_, _| (1.0 - rng.random::<f64>()) * scale);

    let mut p = &f * &g;
    let mut cost = cost_of(settings.cost, y, mask, &p);
    let mut history = vec![cost];
    let mut converged = false;
    let mut iterations = 0;
    // The KL denominators FᵀM and MGᵀ need the mask as a matrix.
    let kl_weight = match settings.cost {
        NmfCost::KullbackLeibler => mask
            .cloned()
            .unwrap_or_else(|| DMatrix::from_element(n, m, 1.0)),
        NmfCost::Euclidean => DMatrix::zeros(0, 0),
    };
    while iterations < settings.max_iterations {
        iterations += 1;
        match settings.cost {
            NmfCost::Euclidean => {
                let num = f.transpose() * &my;
                let den = f.transpose() * weighted(&p);
                apply(&mut g, &num, &den);
                p = &f * &g;
                let num = &my * g.transpose();
                let den = weighted(&p) * g.transpose();
                apply(&mut f, &num, &den);
            }
            NmfCost::KullbackLeibler => {
                let w = &kl_weight;
                let ratio = my.zip_map(&p, |a, b| a / (b + EPSILON));
                let num = f.transpose() * &ratio;
                let den = f.transpose() * w;
                apply(&mut g, &num, &den);
                p = &f * &g;
                let ratio = my.zip_map(&p, |a, b| a / (b + EPSILON));
                let num = &ratio * g.transpose();
                let den = w * g.transpose();
                apply(&mut f, &num, &den);
            }
        }
        p = &f * &g;
        let next = cost_of(settings.cost, y, mask, &p);
        history.push(next);
        let change = (cost - next).abs();
        cost = next;
        if change <= settings.tolerance * history[history.len() - 2].abs() {
            converged = true;
            break;
        }
    }
    let relative_error = weighted(&(y - &p)).norm() / my.norm();
    Ok(Nmf {
        f,
        g,
        stats: NmfStats {
            iterations,
            converged,
            cost,
            relative_error,
        },
        cost_history: history,
    })
}

fn check(y: &DMatrix<f64>, mask: Option<&DMatrix<f64>>, s: &NmfSettings) -> Result<(), NmfError> {
    if s.rank == 0 || s.max_iterations == 0 || !(s.tolerance > 0.0 && s.tolerance < 1.0) {
        return Err(NmfError::Settings {
            rank: s.rank,
            max_iterations: s.max_iterations,
            tolerance: s.tolerance,
        });
    }
    let mut matrices = vec![("data", y)];
    if let Some(w) = mask {
        if w.shape() != y.shape() {
            return Err(NmfError::MaskShape {
                rows: y.nrows(),
                cols: y.ncols(),
                mask_rows: w.nrows(),
                mask_cols: w.ncols(),
            });
        }
        matrices.push(("mask", w));
    }
    for (what, x) in matrices {
        for c in 0..x.ncols() {
            for r in 0..x.nrows() {
                let value = x[(r, c)];
                if !(value >= 0.0 && value.is_finite()) {
                    return Err(NmfError::BadEntry {
                        what,
                        row: r,
                        col: c,
                        value,
                    });
                }
            }
        }
    }
    Ok(())
}

/// `x ← x ⊙ num ⊘ (den + ε)`.
fn apply(x: &mut DMatrix<f64>, num: &DMatrix<f64>, den: &DMatrix<f64>) {
    for ((v, a), b) in x.iter_mut().zip(num.iter()).zip(den.iter()) {
        *v *= a / (b + EPSILON);
    }
}

/// The cost of the approximation `p` of `y` under `mask`.
fn cost_of(cost: NmfCost, y: &DMatrix<f64>, mask: Option<&DMatrix<f64>>, p: &DMatrix<f64>) -> f64 {
    let weight = |i: usize| mask.map_or(1.0, |w| w[i]);
    let mut total = 0.0;
    for (i, (&a, &b)) in y.iter().zip(p.iter()).enumerate() {
        let w = weight(i);
        if w == 0.0 {
            continue;
        }
        total += w * match cost {
            NmfCost::Euclidean => (a - b) * (a - b),
            NmfCost::KullbackLeibler => {
                if a > 0.0 {
                    a * (a / (b + EPSILON)).ln() - a + b
                } else {
                    b
                }
            }
        };
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(rank: usize, cost: NmfCost) -> NmfSettings {
        NmfSettings {
            rank,
            cost,
            max_iterations: 3000,
            tolerance: 1e-12,
            seed: 5,
        }
    }

    /// A random non-negative rank-`r` matrix `A B`.
    fn low_rank(n: usize, m: usize, r: usize, seed: u64) -> DMatrix<f64> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let a = DMatrix::from_fn(n, r, |_, _| rng.random::<f64>());
        let b = DMatrix::from_fn(r, m, |_, _| rng.random::<f64>());
        a * b
    }

    #[test]
    fn costs_never_increase() {
        // Lee–Seung: each multiplicative update does not increase its cost. Noisy data so the
        // factorisation is not exact and the costs keep moving.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
        let y = low_rank(30, 20, 3, 1).map(|v| v + 0.3 * rng.random::<f64>());
        let mask = DMatrix::from_fn(30, 20, |r, c| if (r * 7 + c) % 5 == 0 { 0.0 } else { 1.0 });
        for cost in [NmfCost::Euclidean, NmfCost::KullbackLeibler] {
            for m in [None, Some(&mask)] {
                let out = factorise(&y, m, &settings(2, cost)).unwrap();
                assert!(out.cost_history.len() > 10);
                for w in out.cost_history.windows(2) {
                    assert!(w[1] <= w[0] * (1.0 + 1e-12), "{cost:?} {} > {}", w[1], w[0]);
                }
                assert!(out.cost_history.last() < out.cost_history.first());
            }
        }
    }

    #[test]
    fn recovers_an_exact_low_rank_matrix() {
        let y = low_rank(24, 18, 3, 2);
        for cost in [NmfCost::Euclidean, NmfCost::KullbackLeibler] {
            let out = factorise(&y, None, &settings(3, cost)).unwrap();
            assert!(
                out.stats.relative_error < 1e-3,
                "{cost:?}: {}",
                out.stats.relative_error
            );
            assert!(out.f.iter().chain(out.g.iter()).all(|&v| v >= 0.0));
        }
        // Rank 1 cannot represent it: a real residual is reported.
        let out = factorise(&y, None, &settings(1, NmfCost::Euclidean)).unwrap();
        assert!(out.stats.relative_error > 1e-2);
    }

    #[test]
    fn masked_entries_do_not_matter() {
        // Garbage under a zero weight leaves the factorisation unchanged.
        let y = low_rank(12, 10, 2, 3);
        let mask = DMatrix::from_fn(12, 10, |r, c| if r == c { 0.0 } else { 1.0 });
        let mut garbage = y.clone();
        for i in 0..10 {
            garbage[(i, i)] = 1e3;
        }
        let a = factorise(&y, Some(&mask), &settings(2, NmfCost::Euclidean)).unwrap();
        let b = factorise(&garbage, Some(&mask), &settings(2, NmfCost::Euclidean)).unwrap();
        assert_eq!(a.f, b.f);
        assert_eq!(a.g, b.g);
    }

    #[test]
    fn iteration_cap_is_reported_not_an_error() {
        let y = low_rank(12, 10, 3, 4);
        let s = NmfSettings {
            max_iterations: 3,
            ..settings(2, NmfCost::Euclidean)
        };
        let out = factorise(&y, None, &s).unwrap();
        assert_eq!(out.stats.iterations, 3);
        assert!(!out.stats.converged);
        assert!(out.stats.relative_error > 0.0);
    }

    #[test]
    fn same_seed_same_result_and_bad_input_is_an_error() {
        let y = low_rank(8, 6, 2, 5);
        let s = settings(2, NmfCost::Euclidean);
        assert_eq!(
            factorise(&y, None, &s).unwrap(),
            factorise(&y, None, &s).unwrap()
        );
        let mut bad = y.clone();
        bad[(1, 2)] = -1.0;
        assert!(matches!(
            factorise(&bad, None, &s),
            Err(NmfError::BadEntry { row: 1, col: 2, .. })
        ));
        assert_eq!(
            factorise(&DMatrix::zeros(3, 3), None, &s),
            Err(NmfError::ZeroData)
        );
        assert!(factorise(&y, None, &NmfSettings { rank: 0, ..s }).is_err());
    }
}
