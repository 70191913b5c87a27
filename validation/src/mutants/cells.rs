//! The broken-pdf control of samplers that declare piecewise-constant cells
//! ([`brdf_sampling::PdfCells`]): the suite integrates their pdf cell by cell, and must still
//! see a pdf that is wrong on some cells.

use std::f64::consts::FRAC_1_PI;
use std::sync::Arc;

use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler, PdfCells, SamplerDiagnostics};
use partition_sampler::UniformSource;

use crate::adapters::DirectionAtWo;
use crate::cells::{CellModel, declared_y};
use crate::plan::{MIN_SAMPLES, Plan, Tier};

/// A correct cell-declaring sampler whose reported pdf, at one `ωo`, is `factor` times too high
/// on the declared row (band of `cos θ_y`) of largest mass and scaled down on every other row
/// so that it still integrates to 1. Only the part above the declared cosine component is
/// scaled, so the declaration stays true and the samples are unchanged: the pdf is
/// self-consistent and normalised, wrong in shape, and only the distribution tests can see it.
pub struct RowScaledPdf {
    base: Arc<dyn DirectionSampler>,
    cells: PdfCells,
    /// `cos θ_y` range of the scaled row.
    row: [f64; 2],
    factor: f64,
    /// Scale of the other rows.
    other: f64,
}

impl RowScaledPdf {
    /// The broken version of `base` at `wo` (the pdf of any other `ωo` is scaled the same way,
    /// which only makes sense at `wo`).
    ///
    /// # Errors
    /// A base that declares no cells at `wo`, or whose cells are not valid.
    pub fn new(base: Arc<dyn DirectionSampler>, wo: &Vec3, factor: f64) -> Result<Self, String> {
        let cells = base
            .pdf_cells(wo)
            .ok_or("the base sampler declares no pdf cells")?;
        let at_wo = DirectionAtWo::new(Arc::clone(&base), *wo);
        let plan = Plan::new(Tier::Quick, MIN_SAMPLES);
        let model = CellModel::new(&at_wo, cells.clone(), &plan)?;
        let density = model.density()?;
        let masses: Vec<f64> = density.rows().iter().map(|r| r.mass()).collect();
        let total: f64 = masses.iter().sum();
        let (i, m) = masses
            .iter()
            .copied()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or("no rows")?;
        if !(factor * m < total) {
            return Err(format!(
                "factor {factor} on a row of mass {m} cannot be compensated"
            ));
        }
        Ok(Self {
            row: density.rows()[i].u,
            base,
            cells,
            factor,
            other: (total - factor * m) / (total - m),
        })
    }

    fn scale(&self, wi: &Vec3) -> f64 {
        match declared_y(&self.cells.coords, [wi.x, wi.y, wi.z]) {
            Some(y) if y[2] >= self.row[0] && y[2] < self.row[1] => self.factor,
            _ => self.other,
        }
    }

    fn broken_pdf(&self, wi: &Vec3, pdf: f64) -> f64 {
        let smooth = self.cells.cosine_weight * wi.z.max(0.0) * FRAC_1_PI;
        smooth + (pdf - smooth) * self.scale(wi)
    }
}

impl DirectionSampler for RowScaledPdf {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let s = self.base.sample(wo, u);
        DirSample {
            wi: s.wi,
            pdf: self.broken_pdf(&s.wi, s.pdf),
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.broken_pdf(wi, self.base.pdf(wo, wi))
    }

    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for RowScaledPdf {
    fn pdf_cells(&self, wo: &Vec3) -> Option<PdfCells> {
        self.base.pdf_cells(wo)
    }
}
