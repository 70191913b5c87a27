//! Building a [`FactoredSampler`]: the data matrix, the two-level factorisation, the
//! normalisation by bin measures and the term weights (baselines.md §A.2–§A.4).

use std::time::Instant;

use brdf::{Brdf, Vec3};
use nalgebra::DMatrix;
use partition_sampler::chunk_seed;
use rayon::prelude::*;

use crate::factored::grid::{OutgoingCells, PhiBins, ThetaBands, direction, incoming};
use crate::factored::nmf::{Nmf, NmfSettings, NmfStats, factorise};
use crate::factored::report::{FactoredError, FactoredReport};
use crate::factored::sampler::FactoredSampler;
use crate::options::FactoredOptions;

/// The data matrix `Y[o, p] = g(ωi(ωo, ωp) | ωo) = f_r(ωo, ωi) max(0, cos θi)` at the cell
/// centres (luminance for RGB BRDFs, which is what [`Brdf::eval`] returns). Rows are the
/// outgoing cells, columns `p = a·n_φp + b` the `(θp band a, φp bin b)` cells. Entries whose
/// `ωi` is below the horizon are true zeros (weight 1, baselines.md §A.2).
///
/// Errors: [`FactoredError::BadBrdfValue`] for a negative or non-finite BRDF value.
pub(crate) fn data_matrix(
    brdf: &dyn Brdf,
    options: &FactoredOptions,
    outgoing: &OutgoingCells,
    theta_p: &ThetaBands,
    phi_p: &PhiBins,
) -> Result<DMatrix<f64>, FactoredError> {
    let cols = theta_p.len() * phi_p.n;
    let columns: Vec<Vec3> = (0..cols)
        .map(|p| {
            let (a, b) = (p / phi_p.n, p % phi_p.n);
            direction(theta_p.centre(a).cos(), phi_p.centre(b))
        })
        .collect();
    let rows: Vec<Vec<f64>> = (0..outgoing.rows())
        .into_par_iter()
        .map(|o| {
            let wo = outgoing.centre(o);
            columns
                .iter()
                .map(|wp| {
                    let wi = incoming(options.reparam, &wo, wp);
                    if !(wi.z > 0.0) {
                        return Ok(0.0);
                    }
                    let value = brdf.eval(&wo, &wi) * wi.z;
                    if !(value >= 0.0 && value.is_finite()) {
                        return Err(FactoredError::BadBrdfValue {
                            value,
                            wo: [wo.x, wo.y, wo.z],
                            wi: [wi.x, wi.y, wi.z],
                        });
                    }
                    Ok(value)
                })
                .collect()
        })
        .collect::<Result<_, _>>()?;
    Ok(DMatrix::from_fn(outgoing.rows(), cols, |o, p| rows[o][p]))
}

/// The inner factorisation of `G_j` reshaped to `n_θp × n_φp`. An all-zero `G_j` (its outer
/// term carries no mass) gets zero factors and a trivial report.
fn inner_factorisation(
    z: &DMatrix<f64>,
    options: &FactoredOptions,
    j: usize,
) -> Result<Nmf, FactoredError> {
    if z.iter().all(|&v| v == 0.0) {
        let k = options.inner_terms;
        return Ok(Nmf {
            f: DMatrix::zeros(z.nrows(), k),
            g: DMatrix::zeros(k, z.ncols()),
            stats: NmfStats {
                iterations: 0,
                converged: true,
                cost: 0.0,
                relative_error: 0.0,
            },
            cost_history: vec![0.0],
        });
    }
    let settings = NmfSettings {
        rank: options.inner_terms,
        cost: options.cost,
        max_iterations: options.max_iterations,
        tolerance: options.tolerance,
        seed: chunk_seed(options.seed, j as u64 + 1),
    };
    Ok(factorise(z, None, &settings)?)
}

/// `x / Σ x·measure` and the CDF of `x·measure` (ending at exactly 1); uniform when the mass
/// is zero (such a term has zero weight everywhere).
fn normalised(x: &[f64], measure: impl Fn(usize) -> f64) -> (f64, Vec<f64>, Vec<f64>) {
    let mut cdf = Vec::with_capacity(x.len() + 1);
    cdf.push(0.0);
    let mut total = 0.0;
    for (i, v) in x.iter().enumerate() {
        total += v * measure(i);
        cdf.push(total);
    }
    if total > 0.0 {
        let bar = x.iter().map(|v| v / total).collect();
        let cdf = cdf.iter().map(|c| c / total).collect();
        (total, bar, cdf)
    } else {
        let volume: f64 = (0..x.len()).map(&measure).sum();
        let bar = vec![1.0 / volume; x.len()];
        let mut acc = 0.0;
        let mut cdf = vec![0.0];
        for i in 0..x.len() {
            acc += measure(i);
            cdf.push(acc / volume);
        }
        (0.0, bar, cdf)
    }
}

impl FactoredSampler {
    /// Tabulates `g = f_r cos θi` of `brdf`, factorises it in two levels and builds the
    /// sampling tables (baselines.md §A).
    ///
    /// Rows are `θo × φo` cells, or `θo` only for isotropic BRDFs when
    /// [`FactoredOptions::isotropic_rows`] is set (reported as
    /// [`FactoredReport::rows_theta_only`]). The result depends only on the options (seed
    /// included), not on the number of threads. A factorisation that hits the iteration cap
    /// is kept; the report says so and gives its residual.
    ///
    /// Errors: [`FactoredError`] for invalid options, a negative or non-finite BRDF value, or
    /// a BRDF that is zero on every cell.
    ///
    /// ```
    /// use baselines::{FactoredOptions, FactoredSampler};
    /// use brdf_sampling::DirectionSampler;
    /// use partition_sampler::UniformSequence;
    ///
    /// let brdf = brdf::parse_spec("phong:n=20")?;
    /// let options = FactoredOptions { max_iterations: 200, ..FactoredOptions::default() };
    /// let sampler = FactoredSampler::build(brdf.as_ref(), &options)?;
    /// println!("{}", sampler.report()); // fit, convergence, build time, bytes
    ///
    /// let wo = brdf::direction_from_angles(30.0, 0.0);
    /// let s = sampler.sample(&wo, &mut UniformSequence::new(&[0.5, 0.3, 0.7]));
    /// assert!((s.pdf - sampler.pdf(&wo, &s.wi)).abs() <= 1e-12 * s.pdf);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build(brdf: &dyn Brdf, options: &FactoredOptions) -> Result<Self, FactoredError> {
        options.validate()?;
        let start = Instant::now();
        let outgoing = OutgoingCells {
            n_theta: options.theta_o_cells,
            phi: PhiBins::new(options.phi_o_cells),
            theta_only: options.isotropic_rows && brdf.is_isotropic(),
        };
        let theta_p = ThetaBands::new(options.theta_p_cells);
        let phi_p = PhiBins::new(options.phi_p_cells);
        let y = data_matrix(brdf, options, &outgoing, &theta_p, &phi_p)?;

        let outer = factorise(
            &y,
            None,
            &NmfSettings {
                rank: options.outer_terms,
                cost: options.cost,
                max_iterations: options.max_iterations,
                tolerance: options.tolerance,
                seed: chunk_seed(options.seed, 0),
            },
        )?;
        let (n_theta, n_phi) = (theta_p.len(), phi_p.n);
        let inner: Vec<Nmf> = (0..options.outer_terms)
            .into_par_iter()
            .map(|j| {
                let z = DMatrix::from_fn(n_theta, n_phi, |a, b| outer.g[(j, a * n_phi + b)]);
                inner_factorisation(&z, options, j)
            })
            .collect::<Result<_, _>>()?;

        // Ĝ (J × N_p) from the inner factors, for the report.
        let g_hat = DMatrix::from_fn(options.outer_terms, n_theta * n_phi, |j, p| {
            let (a, b) = (p / n_phi, p % n_phi);
            (0..options.inner_terms)
                .map(|k| inner[j].f[(a, k)] * inner[j].g[(k, b)])
                .sum()
        });
        let g_norm = outer.g.norm();
        let inner_relative_error = if g_norm > 0.0 {
            (&outer.g - &g_hat).norm() / g_norm
        } else {
            0.0
        };
        let total_relative_error = (&y - &outer.f * &g_hat).norm() / y.norm();

        // Normalised factors and term masses, l = j·K + k.
        let terms = options.outer_terms * options.inner_terms;
        let (mut u_bar, mut u_cdf, mut v_bar, mut v_cdf) = (vec![], vec![], vec![], vec![]);
        let mut mass = vec![0.0; terms];
        for (j, nmf) in inner.iter().enumerate() {
            for k in 0..options.inner_terms {
                let u: Vec<f64> = nmf.f.column(k).iter().copied().collect();
                let v: Vec<f64> = nmf.g.row(k).iter().copied().collect();
                let (a_jk, ub, uc) = normalised(&u, |a| theta_p.measure[a]);
                let (b_jk, vb, vc) = normalised(&v, |_| phi_p.width);
                mass[j * options.inner_terms + k] = a_jk * b_jk;
                u_bar.extend(ub);
                u_cdf.extend(uc);
                v_bar.extend(vb);
                v_cdf.extend(vc);
            }
        }
        let mut weights = Vec::with_capacity(outgoing.rows() * terms);
        let mut weight_cdf = Vec::with_capacity(outgoing.rows() * (terms + 1));
        for o in 0..outgoing.rows() {
            let w: Vec<f64> = (0..terms)
                .map(|l| outer.f[(o, l / options.inner_terms)] * mass[l])
                .collect();
            let (_, wb, wc) = normalised(&w, |_| 1.0);
            weights.extend(wb);
            weight_cdf.extend(wc);
        }

        let mut sampler = FactoredSampler {
            outgoing,
            theta_p,
            phi_p,
            reparam: options.reparam,
            alpha: options.defensive_alpha,
            terms,
            weights,
            weight_cdf,
            u_bar,
            u_cdf,
            v_bar,
            v_cdf,
            report: FactoredReport {
                reparam: options.reparam,
                cost: options.cost,
                rows_theta_only: outgoing.theta_only,
                rows: y.nrows(),
                cols: y.ncols(),
                outer_terms: options.outer_terms,
                inner_terms: options.inner_terms,
                outer: outer.stats,
                inner: inner.iter().map(|n| n.stats).collect(),
                inner_relative_error,
                total_relative_error,
                defensive_alpha: options.defensive_alpha,
                build_seconds: 0.0,
                bytes: 0,
            },
        };
        sampler.report.bytes = brdf_sampling::DirectionSampler::bytes_used(&sampler);
        sampler.report.build_seconds = start.elapsed().as_secs_f64();
        Ok(sampler)
    }
}
