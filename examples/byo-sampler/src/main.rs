//! Bring your own sampler: a cos² lobe about the normal, validated and studied beside the
//! built-in samplers. `--broken`: its pdf is 2 % high where x > 0.5; the suite must reject it.
use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;
use samplers::{Capabilities, Registry, SamplerEntry, Support};
use std::{f64::consts::PI, sync::Arc};

/// pdf(ωi) = 3/(2π) cos²θi on the hemisphere (×1.02 where x > 0.5 when broken).
struct CosSquared(bool);

impl DirectionSampler for CosSquared {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let cos = (1.0 - u.next_uniform()).cbrt();
        let (sin, phi) = ((1.0 - cos * cos).max(0.0).sqrt(), 2.0 * PI * u.next_uniform());
        let wi = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
        DirSample { wi, pdf: self.pdf(wo, &wi) }
    }
    fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        let p = 1.5 / PI * wi.z.max(0.0).powi(2);
        if self.0 && wi.x > 0.5 { 1.02 * p } else { p }
    }
    fn bytes_used(&self) -> usize {
        0
    }
}
impl SamplerDiagnostics for CosSquared {} // no diagnostics: the defaults

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let broken = std::env::args().any(|a| a == "--broken");
    let registry = Registry::builtin().with(SamplerEntry::direction(
        "cos2",
        "cos² lobe about the normal",
        Capabilities { exact_pdf: true, anisotropic: true, ..Default::default() },
        Support::Hemisphere,
        move |_| Ok(Arc::new(CosSquared(broken))),
    ));
    let config = validation::ValidateConfig {
        samplers: vec!["cos2".into()],
        brdfs: vec!["lambert".into(), "phong:n=5".into()],
        theta_o: vec![30.0, 70.0],
        samples: Some(20_000),
        ..validation::ValidateConfig::quick()
    };
    let report = validation::run_with(&registry, &config, &|_| {})?;
    let failed: Vec<_> = report.failures().map(|t| format!("{} {}", t.brdf, t.test)).collect();
    println!("cos2 (broken: {broken}) passed: {}, failed tests: {failed:?}", report.passed);
    if !report.passed {
        std::process::exit(3);
    }
    let names = vec!["cosine".into(), "uniform".into(), "cos2".into()];
    let mut study = study::StudyConfig::new(names, vec!["phong:n=5".into()], vec![30.0], vec![]);
    (study.lights, study.n_grid, study.repetitions) = (vec!["sky".into()], vec![1, 16], 8);
    (study.variance_samples, study.timing_samples) = (2_000, 500);
    for c in study::StudyPlan::with_registry(study, vec![], &registry)?.run(None, &|_| {}).cells {
        let ns = c.timing.map(|t| t.estimator_ns);
        println!("{:>8}: variance/sample {:.3e}, ns/sample {ns:?}", c.sampler, c.variance.value);
    }
    Ok(())
}
