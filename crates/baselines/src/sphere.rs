//! Uniform directions on the whole sphere (a scratch baseline: below-horizon samples
//! contribute zero).

use std::f64::consts::{PI, TAU};

use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler};
use partition_sampler::UniformSource;

/// Uniform directions on S²: `p(ωi) = 1/(4π)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct UniformSphere;

impl DirectionSampler for UniformSphere {
    fn sample(&self, _wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let z = 1.0 - 2.0 * u.next_uniform();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = TAU * u.next_uniform();
        DirSample {
            wi: Vec3::new(r * phi.cos(), r * phi.sin(), z),
            pdf: 1.0 / (4.0 * PI),
        }
    }
    fn pdf(&self, _wo: &Vec3, _wi: &Vec3) -> f64 {
        1.0 / (4.0 * PI)
    }
    fn bytes_used(&self) -> usize {
        0
    }
}
