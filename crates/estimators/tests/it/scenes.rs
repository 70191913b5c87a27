//! Scenes shared by the integration tests and the `product_bias` example (which includes this
//! file): the adversarial maps of issue 27 and a [`ProductScene`] from angles.

use brdf::Brdf;
use envmap::EnvMap;
use estimators::{LocalFrame, ProductScene};

/// Dim deterministic noise in `[0.05, 0.25)` (a hash of the pixel index).
pub(crate) fn noise(i: usize) -> f32 {
    let mut x = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (0.05 + 0.2 * ((x >> 11) as f64 / (1u64 << 53) as f64)) as f32
}

/// A `w × h` map of noise with `bright(x, y)` pixels set to that radiance.
pub(crate) fn map(w: usize, h: usize, bright: impl Fn(usize, usize) -> Option<f32>) -> EnvMap {
    let rgb = (0..w * h)
        .map(|i| [bright(i % w, i / w).unwrap_or_else(|| noise(i)); 3])
        .collect();
    EnvMap::new(w, h, rgb).unwrap()
}

/// A 3-pixel column of radiance 300 centred on pixel `xc` (wrapping at the seam), over the
/// rows whose centre `v` is in `[v0, v1]`.
pub(crate) fn column(w: usize, h: usize, xc: usize, v0: f64, v1: f64) -> EnvMap {
    map(w, h, |x, y| {
        let dx = (x + w - xc) % w;
        let v = (y as f64 + 0.5) / h as f64;
        ((dx <= 1 || dx == w - 1) && (v0..=v1).contains(&v)).then_some(300.0)
    })
}

/// The scene of `brdf` under `map` in the frame of `normal` (tangent turned by `rotation`
/// radians) seen from `(θo, φo)` in degrees.
pub(crate) fn scene<'a>(
    brdf: &'a dyn Brdf,
    map: &'a EnvMap,
    normal: [f64; 3],
    rotation: f64,
    [theta_o, phi_o]: [f64; 2],
) -> ProductScene<'a> {
    let frame = LocalFrame::new(normal, rotation).unwrap();
    ProductScene::new(
        brdf,
        map,
        frame,
        brdf::direction_from_angles(theta_o, phi_o),
    )
    .unwrap()
}
