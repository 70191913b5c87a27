//! Exact distribution tests for direction samplers that declare where their pdf is piecewise
//! constant ([`PdfCells`]): tabulated and compressed CDFs, the factored sampler.
//!
//! The tests run in the declaration's coordinates `y` (the incident direction, or the half
//! vector `ωh`, a one-to-one map of `ωi`): the samples are mapped to `y`, and their density
//! there is `q(y) = p(ωi(y)) · |dωi/dy|` with `p` the sampler's **own** `pdf`. The declaration
//! only supplies the cell geometry: the constant of each cell is `q − w c` at the cell's
//! centre (`w c` the declared smooth cosine component, in `y`), and the `pdf-cells` test checks
//! that it is the same at four more points per cell and that the rows tile the upper
//! hemisphere of `y`. Then every χ² expected count, KS projection CDF and the normalisation
//! integral is an exact overlap sum ([`PiecewiseConstant`]) plus, for the smooth component
//! only, the usual adaptive quadrature — no refinement at the thousands of jumps.
//!
//! Testing `y = T(ωi)` against `q` is the same hypothesis as testing `ωi` against `p` (`T` is
//! one-to-one and `q` is `p` transported by `T`), so a wrong `pdf` is caught as before.

use std::f64::consts::{FRAC_1_PI, TAU};

use brdf::Vec3;
use brdf_sampling::{CellCoords, PdfCells};
use rayon::prelude::*;
use stats::{
    Axis, Binning, CellRow, PiecewiseConstant, SphereBinning, TabulatedCdf, TestOutcome,
    expected_masses_with, integrate, ks_onesample, project, projection_cdf,
};

use crate::domain::Domain;
use crate::outcomes::{chi_square, error_outcome, names};
use crate::plan::Plan;
use crate::subject::{Dir3, SamplerUnderTest};

/// The tests a subject with a declared structure runs instead of the quadrature-based ones.
pub(crate) trait ExactTests<P>: Sync {
    /// χ² of `points`, χ² of `batch_points`, and the KS projections onto both axes (named
    /// `ks_names`), in report order.
    fn distribution_tests(
        &self,
        points: &[P],
        batch_points: &[P],
        ks_names: [&str; 2],
        plan: &Plan,
        alpha: f64,
    ) -> Vec<TestOutcome>;

    /// Normalisation, then the check of the declaration itself.
    fn normalisation_tests(&self, plan: &Plan) -> Vec<TestOutcome>;
}

/// A direction sampler's pdf at one `ωo` as a [`PiecewiseConstant`] density in the coordinates
/// of its [`PdfCells`] declaration, plus the declared smooth cosine component.
pub(crate) struct CellModel<'a> {
    sampler: &'a dyn SamplerUnderTest<Dir3>,
    coords: CellCoords,
    cosine_weight: f64,
    binning: SphereBinning,
    /// The cell constants (or why they could not be formed).
    density: Result<PiecewiseConstant, String>,
    check: TestOutcome,
}

/// Name of the test that checks a [`PdfCells`] declaration against the sampler's pdf.
pub const PDF_CELLS: &str = "pdf-cells";

fn v3(d: Dir3) -> Vec3 {
    Vec3::new(d[0], d[1], d[2])
}

/// `y` of an incident direction in the coordinates `coords` (`None` where the map is
/// undefined: `ωi = −ωo` for the half vector).
pub(crate) fn declared_y(coords: &CellCoords, wi: Dir3) -> Option<Dir3> {
    match coords {
        CellCoords::Incident => Some(wi),
        CellCoords::HalfVector { wo } => {
            let s = v3(wi) + wo;
            let n = s.norm();
            if !(n > 1e-12) {
                return None;
            }
            let h = if s.z < 0.0 { -s / n } else { s / n };
            Some([h.x, h.y, h.z])
        }
    }
}

impl<'a> CellModel<'a> {
    /// The model of `sampler` (whose `pdf_cells` returned `cells`), binned like the plan's
    /// hemisphere.
    ///
    /// # Errors
    /// A binning the plan cannot build (zero bin counts).
    pub(crate) fn new(
        sampler: &'a dyn SamplerUnderTest<Dir3>,
        cells: PdfCells,
        plan: &Plan,
    ) -> Result<Self, String> {
        let binning = plan
            .resolution
            .sphere_binning(Domain::Hemisphere)
            .map_err(|e| e.to_string())?
            .ok_or("no hemisphere binning")?;
        let mut model = Self {
            sampler,
            coords: cells.coords,
            cosine_weight: cells.cosine_weight,
            binning,
            density: Err(String::new()),
            check: TestOutcome::deterministic(PDF_CELLS, f64::NAN, false, String::new()),
        };
        let (density, check) = model.constants(&cells, plan.pdf_rel_tol);
        model.density = density;
        model.check = check;
        Ok(model)
    }

    fn coords_name(&self) -> &'static str {
        match self.coords {
            CellCoords::Incident => "incident-direction",
            CellCoords::HalfVector { .. } => "half-vector",
        }
    }

    fn to_y(&self, wi: Dir3) -> Option<Dir3> {
        declared_y(&self.coords, wi)
    }

    /// The cell constants (the sampler's pdf minus the declared cosine component, w.r.t. the
    /// solid angle of `y`), or why they could not be formed.
    pub(crate) fn density(&self) -> Result<&PiecewiseConstant, String> {
        self.density.as_ref().map_err(Clone::clone)
    }

    /// `ωi` of `y` and the Jacobian `|dωi/dy|`.
    fn incident_of(&self, y: Dir3) -> (Dir3, f64) {
        match self.coords {
            CellCoords::Incident => (y, 1.0),
            CellCoords::HalfVector { wo } => {
                let h = v3(y);
                let c = wo.dot(&h);
                let wi = (2.0 * c * h - wo).normalize();
                ([wi.x, wi.y, wi.z], 4.0 * c.abs())
            }
        }
    }

    /// The sampler's pdf in `y` and the smooth part of it, `(q(y), w c(y))`.
    fn q_and_smooth(&self, y: Dir3) -> (f64, f64) {
        let (wi, jac) = self.incident_of(y);
        let q = self.sampler.pdf(wi) * jac;
        let s = self.cosine_weight * wi[2].max(0.0) * FRAC_1_PI * jac;
        (q, s)
    }

    /// The smooth part alone (zero when no cosine component is declared).
    fn smooth(&self, y: Dir3) -> f64 {
        if self.cosine_weight > 0.0 {
            self.q_and_smooth(y).1
        } else {
            0.0
        }
    }

    /// The cell constants from the sampler's pdf at the cell centres, and the check that they
    /// are constant (at the points `(¼, ¼)`, `(¼, ¾)`, `(¾, ¼)`, `(¾, ¾)` of each cell) and
    /// that the rows tile `cos θ_y ∈ [0, 1]`, `φ_y ∈ [0, 2π]`.
    fn constants(
        &self,
        cells: &PdfCells,
        rel_tol: f64,
    ) -> (Result<PiecewiseConstant, String>, TestOutcome) {
        let at = |z: f64, phi: f64| self.binning.point_at([z, phi]);
        let mut tiling: Vec<String> = Vec::new();
        let rows = &cells.rows;
        if !(self.cosine_weight >= 0.0 && self.cosine_weight <= 1.0) {
            tiling.push(format!(
                "cosine weight {} outside [0, 1]",
                self.cosine_weight
            ));
        }
        match (rows.first(), rows.last()) {
            (Some(f), Some(l)) if f.z[0] == 0.0 && l.z[1] == 1.0 => {}
            _ => tiling.push("rows do not start at cos θ = 0 and end at 1".into()),
        }
        if let Some(i) = rows.windows(2).position(|w| w[0].z[1] != w[1].z[0]) {
            tiling.push(format!("rows {i} and {} are not contiguous", i + 1));
        }
        if let Some(i) = rows
            .iter()
            .position(|r| r.phi_edges.first() != Some(&0.0) || r.phi_edges.last() != Some(&TAU))
        {
            tiling.push(format!("row {i}'s azimuth edges do not run from 0 to 2π"));
        }
        // Per row: the constants and the worst relative deviation (with its location).
        type RowCheck = (Vec<f64>, f64, Option<(f64, f64, f64, f64)>, usize);
        let checked: Vec<RowCheck> = rows
            .par_iter()
            .map(|r| {
                let (z0, z1) = (r.z[0], r.z[1]);
                let mut consts = Vec::with_capacity(r.phi_edges.len().saturating_sub(1));
                let (mut worst, mut where_, mut negative) = (0.0_f64, None, 0usize);
                for e in r.phi_edges.windows(2) {
                    let zc = 0.5 * (z0 + z1);
                    let pc = 0.5 * (e[0] + e[1]);
                    let (q, s) = self.q_and_smooth(at(zc, pc));
                    let c = q - s;
                    if !(c >= -rel_tol * q.abs() && c.is_finite()) {
                        negative += 1;
                    }
                    for (fz, fp) in [(0.25, 0.25), (0.25, 0.75), (0.75, 0.25), (0.75, 0.75)] {
                        let z = z0 + fz * (z1 - z0);
                        let phi = e[0] + fp * (e[1] - e[0]);
                        let (q2, s2) = self.q_and_smooth(at(z, phi));
                        let scale = q.abs().max(q2.abs());
                        let dev = if (q2 - s2) == c {
                            0.0
                        } else if scale > 0.0 {
                            ((q2 - s2) - c).abs() / scale
                        } else {
                            f64::INFINITY
                        };
                        if !(dev <= worst) {
                            worst = dev;
                            where_ = Some((z, phi, c, q2 - s2));
                        }
                    }
                    consts.push(c.max(0.0));
                }
                (consts, worst, where_, negative)
            })
            .collect();
        let mut worst = (0.0_f64, None);
        let mut negative = 0;
        let mut pc_rows = Vec::with_capacity(rows.len());
        for (r, (consts, w, at_, neg)) in rows.iter().zip(checked) {
            negative += neg;
            if !(w <= worst.0) {
                worst = (w, at_);
            }
            pc_rows.push(CellRow {
                u: r.z,
                v_edges: r.phi_edges.clone(),
                densities: consts,
            });
        }
        let density = PiecewiseConstant::new(pc_rows).map_err(|e| e.to_string());
        if let Err(e) = &density {
            tiling.push(e.clone());
        }
        let passed = tiling.is_empty() && negative == 0 && worst.0 <= rel_tol;
        let location = worst.1.map_or(String::new(), |(z, phi, c, v)| {
            format!(" at cos θ = {z:.6}, φ = {phi:.6} ({v:e} vs the cell's {c:e})")
        });
        let detail = format!(
            "{} cells in {} coordinates (cosine component weight {}): the pdf minus that component, taken at each cell's centre and checked at 4 more points per cell, deviates by at most {:.3e} relative{location} (tolerance {:e}); {} cells with a negative constant{}",
            cells.cells(),
            self.coords_name(),
            self.cosine_weight,
            worst.0,
            rel_tol,
            negative,
            if tiling.is_empty() {
                "; the rows tile the upper hemisphere".to_owned()
            } else {
                format!("; declaration invalid: {}", tiling.join("; "))
            }
        );
        let check = TestOutcome::deterministic(PDF_CELLS, worst.0, passed, detail);
        (density, check)
    }

    /// Points mapped to `y` (points where the map is undefined become NaN: outside the domain).
    fn ys(&self, points: &[Dir3]) -> Vec<Dir3> {
        points
            .par_iter()
            .map(|&p| self.to_y(p).unwrap_or([f64::NAN; 3]))
            .collect()
    }

    /// Bin masses: the cells' exact ones plus the smooth component's by quadrature.
    fn masses(&self, n: u64, plan: &Plan) -> Result<Vec<f64>, String> {
        let density = self.density.as_ref().map_err(Clone::clone)?;
        let mut masses = density.grid_masses(self.binning.grid());
        if self.cosine_weight > 0.0 {
            let smooth = |y: Dir3| self.smooth(y);
            let table = expected_masses_with(&smooth, &self.binning, n, &plan.quadrature)
                .map_err(|e| e.to_string())?;
            masses
                .iter_mut()
                .zip(&table.masses)
                .for_each(|(m, s)| *m += s);
        }
        Ok(masses)
    }

    fn ks(
        &self,
        ys: &[Dir3],
        axis: Axis,
        name: &str,
        plan: &Plan,
        alpha: f64,
    ) -> Result<TestOutcome, String> {
        let proj = project(&self.binning, ys, axis);
        if proj.outside > 0 {
            return Ok(TestOutcome::with_p_value(
                name,
                f64::INFINITY,
                0.0,
                alpha,
                format!("{} samples outside the domain", proj.outside),
            ));
        }
        let density = self.density.as_ref().map_err(Clone::clone)?;
        let cells_mass = density.total_mass();
        let cells_cdf = density.projection_cdf(axis).map_err(|e| e.to_string())?;
        let smooth: Option<TabulatedCdf> = if self.cosine_weight > 0.0 {
            let f = |y: Dir3| self.smooth(y);
            Some(
                projection_cdf(&self.binning, &f, axis, ys.len() as u64, &plan.quadrature)
                    .map_err(|e| e.to_string())?,
            )
        } else {
            None
        };
        let smooth_mass = smooth.as_ref().map_or(0.0, TabulatedCdf::total_mass);
        let total = cells_mass + smooth_mass;
        let cdf = |t: f64| {
            let s = smooth.as_ref().map_or(0.0, |c| smooth_mass * c.eval(t));
            ((cells_mass * cells_cdf.eval(t) + s) / total).clamp(0.0, 1.0)
        };
        let r = ks_onesample(&proj.values, &cdf).map_err(|e| e.to_string())?;
        let mut o = r.outcome(name, alpha);
        o.detail = format!(
            "in {} coordinates (exact cell CDF): {}",
            self.coords_name(),
            o.detail
        );
        Ok(o)
    }
}

impl ExactTests<Dir3> for CellModel<'_> {
    fn distribution_tests(
        &self,
        points: &[Dir3],
        batch_points: &[Dir3],
        ks_names: [&str; 2],
        plan: &Plan,
        alpha: f64,
    ) -> Vec<TestOutcome> {
        let (ys, batch_ys) = (self.ys(points), self.ys(batch_points));
        let n_max = points.len().max(batch_points.len()) as u64;
        let mut out = Vec::with_capacity(4);
        match self.masses(n_max, plan) {
            Ok(m) => {
                out.push(chi_square(names::CHI_SQUARE, &self.binning, &m, &ys, alpha));
                out.push(chi_square(
                    names::BATCH_CHI_SQUARE,
                    &self.binning,
                    &m,
                    &batch_ys,
                    alpha,
                ));
            }
            Err(e) => {
                out.push(error_outcome(names::CHI_SQUARE, &e));
                out.push(error_outcome(names::BATCH_CHI_SQUARE, &e));
            }
        }
        for (axis, name) in [Axis::U, Axis::V].into_iter().zip(ks_names) {
            out.push(
                self.ks(&ys, axis, name, plan, alpha)
                    .unwrap_or_else(|e| error_outcome(name, e)),
            );
        }
        out
    }

    fn normalisation_tests(&self, plan: &Plan) -> Vec<TestOutcome> {
        let tol = plan.normalisation_tolerance;
        let norm = match &self.density {
            Ok(d) => {
                let cells = d.total_mass();
                let smooth = if self.cosine_weight > 0.0 {
                    let f = |y: Dir3| self.smooth(y);
                    integrate(&f, &self.binning, 0.1 * tol, &plan.quadrature)
                        .map(|r| r.value)
                        .map_err(|e| e.to_string())
                } else {
                    Ok(0.0)
                };
                match smooth {
                    Ok(s) => {
                        let dev = (cells + s - 1.0).abs();
                        TestOutcome::deterministic(
                            names::NORMALISATION,
                            dev,
                            dev <= tol,
                            format!(
                                "integral = {:.10} in {} coordinates (cells {cells:.10} exact, cosine component {s:.10} by quadrature), expected 1, tolerance {tol:e}",
                                cells + s,
                                self.coords_name()
                            ),
                        )
                    }
                    Err(e) => error_outcome(names::NORMALISATION, e),
                }
            }
            Err(e) => error_outcome(names::NORMALISATION, e),
        };
        vec![norm, self.check.clone()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adapters::DirectionAtWo;
    use crate::mutants::{CosineHemisphere, RowScaledPdf};
    use crate::plan::Tier;
    use baselines::{CdfOptions, FactoredOptions, FactoredSampler, TabulatedCdf};
    use brdf::direction_from_angles;
    use brdf_sampling::{DirectionSampler, PdfCellRow, SamplerDiagnostics};
    use stats::QuadratureOptions;
    use std::sync::Arc;

    fn plan() -> Plan {
        Plan::new(Tier::Quick, 20_000)
    }

    fn small_tabulated() -> Arc<dyn DirectionSampler> {
        let brdf = brdf::parse_spec("phong:n=20").unwrap();
        let o = CdfOptions {
            slices: 4,
            n_z: 8,
            n_phi: 16,
            ..CdfOptions::default()
        };
        Arc::new(TabulatedCdf::build(brdf.as_ref(), &o).unwrap())
    }

    fn small_factored() -> Arc<dyn DirectionSampler> {
        let brdf = brdf::parse_spec("ggx:alpha=0.3").unwrap();
        let o = FactoredOptions {
            theta_o_cells: 4,
            phi_o_cells: 4,
            theta_p_cells: 8,
            phi_p_cells: 8,
            ..FactoredOptions::default()
        };
        Arc::new(FactoredSampler::build(brdf.as_ref(), &o).unwrap())
    }

    /// Bin masses of `sampler`'s pdf at `wo` in the model's `y` coordinates, by adaptive
    /// quadrature of `q(y)` (slow, small grids only).
    fn quadrature_masses(model: &CellModel<'_>) -> Vec<f64> {
        let q = |y: Dir3| model.q_and_smooth(y).0;
        let opts = QuadratureOptions {
            max_depth: 10,
            ..QuadratureOptions::default()
        };
        expected_masses_with(&q, &model.binning, 200_000, &opts)
            .unwrap()
            .masses
    }

    #[test]
    fn exact_cell_masses_match_quadrature_of_the_transported_pdf() {
        let mut p = plan();
        p.resolution.directions = [4, 8];
        for (sampler, theta) in [(small_tabulated(), 40.0), (small_factored(), 60.0)] {
            let wo = direction_from_angles(theta, 0.0);
            let at = DirectionAtWo::new(Arc::clone(&sampler), wo);
            let cells = sampler.pdf_cells(&wo).unwrap();
            let model = CellModel::new(&at, cells, &p).unwrap();
            assert!(model.check.passed, "{}", model.check.detail);
            let exact = model.masses(10_000_000, &p).unwrap();
            let quad = quadrature_masses(&model);
            let total: f64 = exact.iter().sum();
            assert!((total - 1.0).abs() < 1e-6, "{total}");
            let worst = exact
                .iter()
                .zip(&quad)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            // The quadrature refines at the jumps to its depth limit: agreement to ~1e-5 of
            // the mass (measured 1.1e-5 for the half vector), while a cell's mass is ~1e-2.
            assert!(worst < 1e-4, "{} worst {worst}", model.coords_name());
        }
    }

    #[test]
    fn correct_samples_pass_and_a_row_scaled_pdf_fails() {
        let p = plan();
        let wo = direction_from_angles(60.0, 0.0);
        let base = small_factored();
        let broken: Arc<dyn DirectionSampler> =
            Arc::new(RowScaledPdf::new(Arc::clone(&base), &wo, 2.0).unwrap());
        let mut p_values = Vec::new();
        for s in [base, broken] {
            let at = DirectionAtWo::new(Arc::clone(&s), wo);
            let model = CellModel::new(&at, s.pdf_cells(&wo).unwrap(), &p).unwrap();
            let pts: Vec<Dir3> = crate::case::draw(&at, 20_000, 5)
                .into_iter()
                .map(|x| x.0)
                .collect();
            let out = model.distribution_tests(&pts, &pts[..5000], ["u", "v"], &p, 0.01);
            let norm = model.normalisation_tests(&p);
            assert!(norm.iter().all(|o| o.passed), "{:?}", norm);
            p_values.push(out.iter().map(|o| o.p_value.unwrap()).collect::<Vec<_>>());
        }
        // Fixed seed: the correct sampler passes every test at 1e-3, the broken one fails the
        // χ² and the cos θ projection far below it.
        assert!(p_values[0].iter().all(|&q| q > 1e-3), "{:?}", p_values[0]);
        assert!(
            p_values[1][0] < 1e-6 && p_values[1][2] < 1e-6,
            "{:?}",
            p_values[1]
        );
    }

    #[test]
    fn declarations_hold_for_turned_slices_and_rows() {
        // An anisotropic BRDF (φ slices: the serving slice is turned by Δ ≠ 0) and an isotropic
        // factored sampler at φo ≠ 0 (its row frame is turned by φo).
        let brdf = brdf::parse_spec("ward:alpha_x=0.1,alpha_y=0.3").unwrap();
        let o = CdfOptions {
            anisotropic_slices: [4, 6],
            n_z: 8,
            n_phi: 16,
            ..CdfOptions::default()
        };
        let aniso: Arc<dyn DirectionSampler> =
            Arc::new(TabulatedCdf::build(brdf.as_ref(), &o).unwrap());
        for (s, wo) in [
            (aniso, direction_from_angles(40.0, 37.0)),
            (small_factored(), direction_from_angles(60.0, 37.0)),
        ] {
            let at = DirectionAtWo::new(Arc::clone(&s), wo);
            let model = CellModel::new(&at, s.pdf_cells(&wo).unwrap(), &plan()).unwrap();
            assert!(model.check.passed, "{}", model.check.detail);
            let norm = model.normalisation_tests(&plan());
            assert!(norm[0].passed, "{}", norm[0].detail);
        }
    }

    /// Cosine sampling that claims its pdf is constant on 4 × 4 cells.
    struct FalseCells;

    impl DirectionSampler for FalseCells {
        fn sample(
            &self,
            wo: &Vec3,
            u: &mut dyn partition_sampler::UniformSource,
        ) -> brdf_sampling::DirSample {
            CosineHemisphere.sample(wo, u)
        }
        fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            CosineHemisphere.pdf(wo, wi)
        }
        fn bytes_used(&self) -> usize {
            0
        }
    }

    impl SamplerDiagnostics for FalseCells {
        fn pdf_cells(&self, _wo: &Vec3) -> Option<PdfCells> {
            let edges: Vec<f64> = (0..=4).map(|k| k as f64 * TAU / 4.0).collect();
            Some(PdfCells {
                coords: CellCoords::Incident,
                rows: (0..4)
                    .map(|a| {
                        PdfCellRow::turned([a as f64 / 4.0, (a + 1) as f64 / 4.0], &edges, 0.0)
                    })
                    .collect(),
                cosine_weight: 0.0,
            })
        }
    }

    #[test]
    fn a_false_declaration_fails_the_cell_check() {
        let wo = direction_from_angles(30.0, 0.0);
        let at = DirectionAtWo::new(Arc::new(FalseCells), wo);
        let model = CellModel::new(&at, FalseCells.pdf_cells(&wo).unwrap(), &plan()).unwrap();
        assert!(!model.check.passed, "{}", model.check.detail);
        // The same cosine sampler declaring its true structure (none) is not checked at all;
        // declaring the cosine as the smooth component with constant-zero cells passes.
        let mut cells = FalseCells.pdf_cells(&wo).unwrap();
        cells.cosine_weight = 1.0;
        let model = CellModel::new(&at, cells, &plan()).unwrap();
        assert!(model.check.passed, "{}", model.check.detail);
        // Rows that leave a gap are rejected.
        let mut cells = FalseCells.pdf_cells(&wo).unwrap();
        cells.cosine_weight = 1.0;
        cells.rows.remove(1);
        let model = CellModel::new(&at, cells, &plan()).unwrap();
        assert!(!model.check.passed && model.check.detail.contains("contiguous"));
    }
}
