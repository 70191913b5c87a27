//! Targets, estimands and references of the subjects: BRDF cases (directions and the disc),
//! environment maps and a synthetic grid.

use std::f64::consts::PI;
use std::sync::Arc;

use brdf::{Brdf, Vec3};
use envmap::EnvMap;
use stats::{DiscBinning, QuadratureOptions, StatsError, integrate};

use crate::domain::Domain;
use crate::references::{environment, projected_brdf};
use crate::subject::{Dir3, Estimand, Point2, Reference, SamplerUnderTest, ScalarFn, Subject};

/// References of one BRDF at one outgoing direction.
#[derive(Debug, Clone, PartialEq)]
pub struct BrdfReferences {
    /// Directional albedo.
    pub albedo: Reference,
    /// Reflected radiance under [`environment`].
    pub lit: Reference,
}

/// A direction subject for a BRDF: target `f_r cos θi`, one-sample estimand the directional
/// albedo, batch estimand the radiance reflected from [`environment`].
pub fn brdf_direction_subject(
    sampler: Arc<dyn SamplerUnderTest<Dir3>>,
    domain: Domain,
    brdf: Arc<dyn Brdf>,
    wo: Vec3,
    refs: &BrdfReferences,
) -> Subject<Dir3> {
    let b = Arc::clone(&brdf);
    let target: ScalarFn<Dir3> = Arc::new(move |w| projected_brdf(b.as_ref(), &wo, w));
    let b = Arc::clone(&brdf);
    let lit: ScalarFn<Dir3> =
        Arc::new(move |w| projected_brdf(b.as_ref(), &wo, w) * environment(w));
    brdf_subject(sampler, domain, target, lit, refs)
}

/// The subject of a BRDF case: one-sample estimand the albedo (the integral of `target`),
/// batch estimand the lit radiance (of `lit`), with their references.
fn brdf_subject<P>(
    sampler: Arc<dyn SamplerUnderTest<P>>,
    domain: Domain,
    target: ScalarFn<P>,
    lit: ScalarFn<P>,
    refs: &BrdfReferences,
) -> Subject<P> {
    Subject {
        sampler,
        domain,
        target: Arc::clone(&target),
        single: Estimand {
            label: "albedo".into(),
            integrand: target,
            reference: refs.albedo.clone(),
        },
        batch: Estimand {
            label: "lit".into(),
            integrand: lit,
            reference: refs.lit.clone(),
        },
    }
}

/// `h⁻¹(x, y) = (x, y, √(1 − x² − y²))`, or `None` on or outside the unit circle.
fn lift(p: Point2) -> Option<Dir3> {
    let z2 = 1.0 - p[0] * p[0] - p[1] * p[1];
    (z2 > 0.0).then(|| [p[0], p[1], z2.sqrt()])
}

/// A disc subject for a BRDF (pdf w.r.t. area on the disc, which is projected solid angle):
/// target `f_r(ωo, h⁻¹(x))`, whose integral over the disc is the directional albedo; batch
/// estimand `f_r(ωo, h⁻¹(x)) L(h⁻¹(x))`.
pub fn brdf_disc_subject(
    sampler: Arc<dyn SamplerUnderTest<Point2>>,
    brdf: Arc<dyn Brdf>,
    wo: Vec3,
    refs: &BrdfReferences,
) -> Subject<Point2> {
    let b = Arc::clone(&brdf);
    let target: ScalarFn<Point2> = Arc::new(move |p| match lift(p) {
        Some(w) => b.eval(&wo, &Vec3::new(w[0], w[1], w[2])),
        None => 0.0,
    });
    let b = Arc::clone(&brdf);
    let lit: ScalarFn<Point2> = Arc::new(move |p| match lift(p) {
        Some(w) => b.eval(&wo, &Vec3::new(w[0], w[1], w[2])) * environment(w),
        None => 0.0,
    });
    brdf_subject(sampler, Domain::Disc, target, lit, refs)
}

/// Deterministic test values on a `w × h` grid: smooth variation, about one cell in eleven set
/// to zero (holes in the support), and one cell 40 times brighter than the rest.
pub fn synthetic_values(w: usize, h: usize, salt: u64) -> Vec<f64> {
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (xf, yf) = (x as f64, y as f64);
            let k = (x as u64 * 7 + y as u64 * 3 + salt) % 11;
            let v = if k == 0 {
                0.0
            } else {
                0.2 + ((1.7 * xf + 0.3 * salt as f64).sin() + (2.3 * yf).cos()).powi(2)
            };
            out.push(v);
        }
    }
    if let Some(v) = out.get_mut((h / 4) * w + (2 * w) / 3) {
        *v = 40.0;
    }
    out
}

/// A small synthetic lat-long map (`16 × 8`, grey, with black pixels and one bright pixel).
///
/// # Errors
/// Never in practice (the values are valid).
pub fn synthetic_map() -> Result<EnvMap, envmap::EnvMapError> {
    let (w, h) = (16, 8);
    let rgb = synthetic_values(w, h, 5)
        .into_iter()
        .map(|v| [v as f32; 3])
        .collect();
    EnvMap::new(w, h, rgb)
}

/// The irradiance integrand at normal `+z` in `(u, v)` area measure:
/// `Y(u, v) · max(0, cos πv) · sin(πv) · 2π²` (`dω = 2π² sin(πv) du dv`).
fn irradiance_uv(lum: f64, v: f64) -> f64 {
    let (s, c) = (PI * v).sin_cos();
    lum * c.max(0.0) * s * 2.0 * PI * PI
}

/// `∫ max(0, cos πv) sin(πv) dv` over `[v0, v1]` (closed form `sin²(πv)/(2π)` up to `v = ½`).
fn cos_sin_integral(v0: f64, v1: f64) -> f64 {
    let (a, b) = (v0.min(0.5), v1.min(0.5));
    if b <= a {
        return 0.0;
    }
    ((PI * b).sin().powi(2) - (PI * a).sin().powi(2)) / (2.0 * PI)
}

/// A subject for an environment-map sampler on `[0, 1]²`: target `Y(pixel) sin(πv)` (the
/// density ∝ luminance per solid angle, in `(u, v)` area measure); both estimands are the
/// irradiance `E = ∫ L cos θ dω` at normal `+z`, whose reference is the exact sum over pixels
/// of `Y · 2π² Δu ∫ max(0, cos πv) sin(πv) dv`.
pub fn envmap_subject(sampler: Arc<dyn SamplerUnderTest<Point2>>, map: &EnvMap) -> Subject<Point2> {
    let (w, h) = (map.width(), map.height());
    let lum = Arc::new(map.luminance());
    let mut total = 0.0;
    for y in 0..h {
        let row = cos_sin_integral(y as f64 / h as f64, (y + 1) as f64 / h as f64);
        if row > 0.0 {
            let sum: f64 = lum[y * w..(y + 1) * w].iter().sum();
            total += sum * row * 2.0 * PI * PI / w as f64;
        }
    }
    let pixel = move |p: Point2| grid_cell(p, w, h);
    let l = Arc::clone(&lum);
    let target: ScalarFn<Point2> = Arc::new(move |p| match pixel(p) {
        Some(i) => l[i] * (PI * p[1]).sin(),
        None => 0.0,
    });
    let l = Arc::clone(&lum);
    let integrand: ScalarFn<Point2> = Arc::new(move |p| match pixel(p) {
        Some(i) => irradiance_uv(l[i], p[1]),
        None => 0.0,
    });
    let reference = Reference {
        value: total,
        abs_error: 1e-12 * total.abs(),
        rule: "exact: sum over pixels of Y * 2 pi^2 * du * [sin^2(pi v)/(2 pi)] over the row's upper-hemisphere part"
            .into(),
    };
    let est = Estimand {
        label: "irradiance".into(),
        integrand,
        reference,
    };
    unit_square_subject(sampler, target, est)
}

/// A subject for a sampler of the step function `values` (`w × h`, row-major, row 0 at
/// `y = 0`) on `[0, 1]²`: target the step function; both estimands `∫ f(x, y) (1 + x y) dx dy`,
/// exact per cell (`f · [Δx Δy + (x₁² − x₀²)(y₁² − y₀²)/4]`).
pub fn grid_subject(
    sampler: Arc<dyn SamplerUnderTest<Point2>>,
    w: usize,
    h: usize,
    values: Vec<f64>,
) -> Subject<Point2> {
    let values = Arc::new(values);
    let mut total = 0.0;
    for y in 0..h {
        for x in 0..w {
            let (x0, x1) = (x as f64 / w as f64, (x + 1) as f64 / w as f64);
            let (y0, y1) = (y as f64 / h as f64, (y + 1) as f64 / h as f64);
            let cell = (x1 - x0) * (y1 - y0) + (x1 * x1 - x0 * x0) * (y1 * y1 - y0 * y0) / 4.0;
            total += values[y * w + x] * cell;
        }
    }
    let cell = move |p: Point2| grid_cell(p, w, h);
    let v = Arc::clone(&values);
    let target: ScalarFn<Point2> = Arc::new(move |p| cell(p).map_or(0.0, |i| v[i]));
    let v = Arc::clone(&values);
    let integrand: ScalarFn<Point2> =
        Arc::new(move |p| cell(p).map_or(0.0, |i| v[i] * (1.0 + p[0] * p[1])));
    let est = Estimand {
        label: "weighted-mass".into(),
        integrand,
        reference: Reference {
            value: total,
            abs_error: 1e-12 * total,
            rule: "exact: sum over cells of f * [dx dy + (x1^2 - x0^2)(y1^2 - y0^2)/4]".into(),
        },
    };
    unit_square_subject(sampler, target, est)
}

/// `∫_D g dA` over the unit disc by adaptive quadrature (12 × 12 disc-clipped bins, order 8,
/// absolute tolerance 1e-10).
///
/// # Errors
/// Invalid quadrature settings (not expected).
pub fn disc_integral(g: &(dyn Fn(Point2) -> f64 + Sync)) -> Result<Reference, StatsError> {
    let bins = DiscBinning::new(12, 12)?;
    let opts = QuadratureOptions {
        order: 8,
        max_depth: 14,
        rel_floor: 1e-13,
        ..QuadratureOptions::default()
    };
    let r = integrate(g, &bins, 1e-10, &opts)?;
    Ok(Reference {
        value: r.value,
        abs_error: r.error_estimate.max(1e-10),
        rule: "adaptive Gauss-Legendre over the unit disc (stats::integrate, 12 x 12 clipped bins, order 8, tolerance 1e-10)"
            .into(),
    })
}

/// A subject on the unit square whose one estimand `est` serves both unbiasedness tests.
fn unit_square_subject(
    sampler: Arc<dyn SamplerUnderTest<Point2>>,
    target: ScalarFn<Point2>,
    est: Estimand<Point2>,
) -> Subject<Point2> {
    Subject {
        sampler,
        domain: Domain::UnitSquare,
        target,
        single: est.clone(),
        batch: est,
    }
}

/// The row-major index of the cell of a `w × h` grid on `[0, 1]²` that holds `p` (the last
/// row and column closed), or `None` outside the square.
fn grid_cell(p: Point2, w: usize, h: usize) -> Option<usize> {
    if !(p[0] >= 0.0 && p[0] <= 1.0 && p[1] >= 0.0 && p[1] <= 1.0) {
        return None;
    }
    let x = ((p[0] * w as f64) as usize).min(w - 1);
    let y = ((p[1] * h as f64) as usize).min(h - 1);
    Some(y * w + x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adapters::PlainPlanar;
    use approx::assert_relative_eq;
    use partition_sampler::{PiecewiseConstant2D, Rect};
    use stats::RectBinning;

    fn integrate_square(g: &(dyn Fn(Point2) -> f64 + Sync), nx: usize, ny: usize) -> f64 {
        let bins = RectBinning::unit_square(nx, ny).unwrap();
        let opts = QuadratureOptions {
            order: 8,
            ..QuadratureOptions::default()
        };
        integrate(g, &bins, 1e-11, &opts).unwrap().value
    }

    #[test]
    fn cos_sin_rows_sum_to_the_upper_hemisphere() {
        let total: f64 = (0..10)
            .map(|j| cos_sin_integral(j as f64 / 10.0, (j + 1) as f64 / 10.0))
            .sum();
        assert_relative_eq!(total, 1.0 / (2.0 * PI), epsilon = 1e-15);
    }

    #[test]
    fn closed_form_references_match_quadrature() {
        let map = synthetic_map().unwrap();
        let table = PiecewiseConstant2D::new(4, 2, vec![1.0; 8], Rect::UNIT).unwrap();
        let sampler: Arc<dyn SamplerUnderTest<Point2>> = Arc::new(PlainPlanar(table));
        let env = envmap_subject(Arc::clone(&sampler), &map);
        let q = integrate_square(env.single.integrand.as_ref(), 16, 8);
        assert_relative_eq!(env.single.reference.value, q, max_relative = 1e-9);

        let values = synthetic_values(16, 8, 2);
        let grid = grid_subject(sampler, 16, 8, values);
        let q = integrate_square(grid.single.integrand.as_ref(), 16, 8);
        assert_relative_eq!(grid.single.reference.value, q, max_relative = 1e-10);
    }

    #[test]
    fn synthetic_values_have_holes_and_a_peak() {
        let v = synthetic_values(16, 8, 5);
        assert!(v.contains(&0.0));
        assert!(v.iter().all(|&x| x >= 0.0 && x.is_finite()));
        assert_eq!(v.iter().copied().fold(0.0, f64::max), 40.0);
    }
}
