//! A BRDF whose support moves with θo: a slice built at `θ_j` serves every `θo` of its bin,
//! so its pdf must be positive where `f_r(ωo, ·) > 0` even when `f_r(ωo_j, ·) = 0` there
//! (the zero floor, `brdf_sampling::SUPPORT_FLOOR`). Without the floor the same set leaves a
//! part of the support uncovered (checked on the bare slice density).

use std::sync::Arc;

use brdf::{Brdf, Vec3, direction_from_angles, mirror};
use brdf_sampling::{DirectionSampler, DiscBrdf, QuadTreeSet, SUPPORT_FLOOR, SetOptions, Variant};
use partition_sampler::Density;

/// A flat lobe of half-angle ≈ 53° around the mirror direction, exactly 0 outside it.
struct Cone;

impl Brdf for Cone {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        if mirror(wo).dot(wi) > 0.6 { 1.0 } else { 0.0 }
    }
    fn is_isotropic(&self) -> bool {
        true
    }
}

/// Directions on a (θ, φ) grid of the upper hemisphere.
fn grid() -> impl Iterator<Item = Vec3> {
    (0..60).flat_map(|i| {
        (0..120).map(move |j| {
            direction_from_angles((i as f64 + 0.5) * 1.5, (j as f64 + 0.5) * 3.0 - 180.0)
        })
    })
}

#[test]
fn the_pdf_covers_the_support_of_every_outgoing_angle_of_a_slice() {
    // 9 slices: the one at 25° serves θo ∈ [20°, 30°).
    let opts = SetOptions {
        slices: 9,
        grid: 64,
        ..SetOptions::default().with_depth(4)
    };
    let brdf: Arc<dyn Brdf> = Arc::new(Cone);
    let set = QuadTreeSet::build(Arc::clone(&brdf), Variant::Adaptive, &opts).unwrap();
    let wo = direction_from_angles(29.0, 0.0);
    let slice_wo = direction_from_angles(25.0, 0.0);
    // The control: points where f(θo) > 0 but the slice's own f is 0 exist.
    let bare = DiscBrdf::new(Arc::clone(&brdf), slice_wo);
    let moved: Vec<Vec3> = grid()
        .filter(|wi| brdf.eval(&wo, wi) > 0.0 && bare.eval([wi.x, wi.y]) == 0.0)
        .collect();
    assert!(moved.len() > 10, "{} moved points", moved.len());
    // The set's pdf is positive on all of them, and on the whole support.
    for wi in grid().filter(|wi| brdf.eval(&wo, wi) > 0.0) {
        assert!(set.pdf(&wo, &wi) > 0.0, "pdf 0 at {wi:?}");
    }
    // Where f(θ_j) > 0 the pdf is proportional to f (the floor only fills the zeros): the
    // pdf ratio of two supported points at the slice's own angle is 1.
    let (a, b) = (mirror(&slice_wo), direction_from_angles(20.0, 170.0));
    let ratio = set.pdf(&slice_wo, &a) / a.z / (set.pdf(&slice_wo, &b) / b.z);
    assert!((ratio - 1.0).abs() < 1e-12, "ratio {ratio}");
    // Outside the support the floor is SUPPORT_FLOOR of the mean: far below the lobe.
    let off = direction_from_angles(80.0, 0.0);
    assert_eq!(brdf.eval(&slice_wo, &off), 0.0);
    let p_off = set.pdf(&slice_wo, &off) / off.z;
    let p_on = set.pdf(&slice_wo, &a) / a.z;
    assert!(
        p_off > 0.0 && p_off < 10.0 * SUPPORT_FLOOR * p_on,
        "{p_off} vs {p_on}"
    );
}
