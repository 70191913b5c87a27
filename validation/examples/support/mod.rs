//! What the probing examples (`case_cost`, `ks_probe`) share: their command line
//! `SAMPLER BRDF THETA_O [SAMPLES]`, the sampler built for the BRDF at `θo` (`φo = 0`), the full
//! tier's plan and direction binning, and the sampler's declared singular directions graded
//! towards as the suite does. Each example uses a subset (`mod support;`).
#![allow(dead_code)]

use std::sync::Arc;

use brdf::{Vec3, direction_from_angles};
use brdf_sampling::DirectionSampler;
use stats::{Binning, SphereBinning};
use validation::{Plan, Tier, build_direction, direction_domain};

/// One direction sampler, BRDF and outgoing angle, from the command line: the `sampler` built
/// for the `brdf`, the outgoing direction `wo` (`θo` of the command line, `φo = 0`), the full
/// tier's `plan` for the samples asked for (`plan.samples`) and its `binning` of the sampler's
/// domain.
pub(crate) struct Probe {
    pub(crate) sampler: Arc<dyn DirectionSampler>,
    pub(crate) brdf: Arc<dyn brdf::Brdf>,
    pub(crate) wo: Vec3,
    pub(crate) plan: Plan,
    pub(crate) binning: SphereBinning,
}

impl Probe {
    /// Reads `SAMPLER BRDF THETA_O [SAMPLES]` (the usage line names `example`) and builds the
    /// sampler.
    pub(crate) fn from_args(example: &str, default_samples: usize) -> Result<Self, String> {
        let args: Vec<String> = std::env::args().skip(1).collect();
        let [sampler, spec, theta, rest @ ..] = args.as_slice() else {
            return Err(format!("usage: {example} SAMPLER BRDF THETA_O [SAMPLES]"));
        };
        let theta: f64 = theta.parse().map_err(|e| format!("THETA_O: {e}"))?;
        let samples: usize = match rest.first() {
            Some(s) => s.parse().map_err(|e| format!("SAMPLES: {e}"))?,
            None => default_samples,
        };
        let entry = samplers::find(sampler).map_err(|e| e.to_string())?;
        let domain = direction_domain(entry).ok_or("not a direction sampler")?;
        let brdf: Arc<dyn brdf::Brdf> =
            Arc::from(brdf::parse_spec(spec).map_err(|e| e.to_string())?);
        let plan = Plan::new(Tier::Full, samples);
        let binning = plan
            .resolution
            .sphere_binning(domain)
            .map_err(|e| e.to_string())?
            .ok_or("no direction binning")?;
        Ok(Self {
            sampler: build_direction(entry, &brdf).map_err(|e| e.to_string())?,
            brdf,
            wo: direction_from_angles(theta, 0.0),
            plan,
            binning,
        })
    }

    /// The sampler's declared singular directions as parameters of the binning, each with its
    /// copies shifted by `±2π` in `φ`, as the suite grades towards them; none with `PLAIN=1`
    /// (the quadrature before that declaration existed).
    pub(crate) fn singular(&self) -> Vec<[f64; 2]> {
        if std::env::var_os("PLAIN").is_some() {
            return Vec::new();
        }
        self.sampler
            .singular_directions(&self.wo)
            .iter()
            .filter_map(|d| self.binning.param_of(&[d.x, d.y, d.z]))
            .flat_map(|[u, v]| {
                [
                    [u, v],
                    [u, v - std::f64::consts::TAU],
                    [u, v + std::f64::consts::TAU],
                ]
            })
            .collect()
    }
}
