//! Directional albedo `∫ f_r cosθi dσ(ωi)` by composite Gauss–Legendre (θ) × trapezoid (φ)
//! quadrature. Every estimate is computed at two resolutions and the test requires them to agree,
//! so an under-resolved integral fails instead of passing silently.

use brdf::models::{Microfacet, MicrofacetParams};
use brdf::{
    Brdf, direction_from_angles, directional_albedo, parse_spec, projected_hemisphere_integral,
};
use std::f64::consts::PI;

/// Albedo at (panels, phi) and at twice both; panics if they disagree by more than `conv`.
fn albedo(b: &dyn Brdf, theta_deg: f64, panels: usize, phi: usize, conv: f64) -> f64 {
    let wo = direction_from_angles(theta_deg, 30.0);
    let lo = directional_albedo(b, &wo, panels, phi);
    let hi = directional_albedo(b, &wo, 2 * panels, 2 * phi);
    assert!(
        (hi - lo).abs() <= conv,
        "{} at θo={theta_deg}: quadrature not converged ({lo} vs {hi})",
        b.name()
    );
    hi
}

/// Largest albedo over the angles.
fn max_albedo(spec: &str, angles: &[f64], panels: usize, phi: usize) -> f64 {
    let b = parse_spec(spec).unwrap();
    angles
        .iter()
        .map(|&t| albedo(b.as_ref(), t, panels, phi, 1e-3))
        .fold(0.0, f64::max)
}

const TOL: f64 = 2e-3;

#[test]
fn energy_conserving_models_have_albedo_at_most_one() {
    // (spec, angles, θ panels, φ points); sharper lobes get finer grids.
    let cases: &[(&str, &[f64], usize, usize)] = &[
        ("lambert", &[0.0, 60.0, 85.0], 4, 16),
        (
            "phong:n=50,ks=0.7,kd=0.3",
            &[0.0, 30.0, 60.0, 80.0],
            32,
            256,
        ),
        ("phong:n=1,ks=1,kd=0", &[0.0, 45.0, 80.0], 16, 64),
        ("phong:n=400,ks=1,kd=0", &[0.0, 30.0, 60.0, 75.0], 64, 768),
        ("blinn:n=100,ks=1,kd=0", &[0.0, 30.0, 60.0, 75.0], 32, 384),
        ("blinn:n=5,ks=1,kd=0", &[0.0, 40.0, 80.0], 16, 128),
        ("lewis:n=50,ks=1,kd=0", &[0.0, 40.0, 75.0], 32, 256),
        ("lafortune:kd=0,ks=1", &[0.0, 40.0, 70.0], 32, 256),
        (
            "lafortune:kd=0.2,ks=0.8,cx=-0.9,cy=-1,cz=1",
            &[0.0, 40.0, 70.0],
            32,
            256,
        ),
        ("ward:rho_s=1,rho_d=0", &[0.0, 30.0, 60.0, 75.0], 48, 512),
        (
            "ward:rho_s=1,rho_d=0,alpha_x=0.6",
            &[0.0, 40.0, 70.0, 80.0],
            16,
            128,
        ),
        (
            "ward:rho_s=0.7,rho_d=0.3,alpha_x=0.08,alpha_y=0.3",
            &[0.0, 40.0, 70.0],
            64,
            768,
        ),
        (
            "ashikhmin-shirley:rs=1,rd=0",
            &[0.0, 30.0, 60.0, 75.0],
            48,
            512,
        ),
        (
            "ashikhmin-shirley:rs=0.3,rd=1,nu=10,nv=1000",
            &[0.0, 40.0, 70.0],
            64,
            768,
        ),
        (
            "ashikhmin-shirley:rs=0.05,rd=1,nu=1",
            &[0.0, 40.0, 80.0],
            16,
            64,
        ),
        (
            "cook-torrance:ks=1,kd=0,ior=100,m=0.2",
            &[0.0, 30.0, 60.0, 75.0],
            48,
            512,
        ),
        ("cook-torrance", &[0.0, 45.0, 75.0], 48, 512),
        ("beckmann", &[0.0, 30.0, 60.0, 75.0], 48, 512),
        ("beckmann:alpha=0.8", &[0.0, 40.0, 80.0], 16, 128),
        ("ggx", &[0.0, 30.0, 60.0, 75.0], 48, 512),
        ("ggx:alpha=0.08,alpha_y=0.4", &[0.0, 40.0, 70.0], 64, 768),
        ("minnaert:k=1.5,rho=1", &[0.0, 40.0, 80.0], 16, 64),
        ("oren-nayar:sigma=0,rho=1", &[0.0, 80.0], 4, 16),
        ("poulin-fournier", &[0.0, 40.0, 70.0], 16, 128),
        (
            "poulin-fournier:ks=1,kd=0,n=50",
            &[0.0, 40.0, 70.0],
            24,
            192,
        ),
        ("coupled", &[0.0, 40.0, 75.0], 48, 512),
        ("coupled:kd=1,f0=0.3,m=0.1", &[0.0, 40.0, 70.0], 64, 768),
    ];
    for &(spec, angles, panels, phi) in cases {
        let b = parse_spec(spec).unwrap();
        assert!(
            b.conserves_energy(),
            "{spec} should report conserves_energy()"
        );
        let a = max_albedo(spec, angles, panels, phi);
        assert!(a <= 1.0 + TOL, "{spec}: max albedo {a} > 1");
        assert!(a > 0.0);
    }
}

/// The same check flags models that are known to exceed 1 (the test has power).
#[test]
fn albedo_check_detects_energy_gain() {
    for (spec, angle, panels, phi) in [
        ("minnaert:k=0.5,rho=0.8", 80.0, 16, 64),
        ("schlick-specular:c=1,r=0.5", 85.0, 32, 256),
        ("beard-maxwell", 80.0, 64, 512),
        ("phong:n=20,ks=0.8,kd=0.5", 0.0, 16, 128),
    ] {
        let b = parse_spec(spec).unwrap();
        assert!(!b.conserves_energy(), "{spec}");
        let a = max_albedo(spec, &[angle], panels, phi);
        assert!(a > 1.0 + 10.0 * TOL, "{spec}: albedo {a} unexpectedly ≤ 1");
    }
}

#[test]
fn closed_form_albedos() {
    // Lambert: ρ at every angle.
    let l = parse_spec("lambert:rho=0.63").unwrap();
    for t in [0.0, 50.0, 89.0] {
        assert!((albedo(l.as_ref(), t, 4, 16, 1e-12) - 0.63).abs() < 1e-12);
    }
    // Phong and Blinn: exactly kd + ks at normal incidence.
    for spec in [
        "phong:n=50,ks=0.6,kd=0.25",
        "blinn:n=80,ks=0.6,kd=0.25",
        "blinn:n=3,ks=0.6,kd=0.25",
    ] {
        let b = parse_spec(spec).unwrap();
        let a = albedo(b.as_ref(), 0.0, 48, 64, 1e-7);
        assert!((a - 0.85).abs() < 1e-6, "{spec}: {a}");
    }
    // Lewis: the lobe integrates to ks over solid angle (no cosine) at normal incidence.
    let lw = parse_spec("lewis:n=40,ks=0.7,kd=0").unwrap();
    let wo = direction_from_angles(0.0, 0.0);
    let s = projected_hemisphere_integral(64, 64, |wi| lw.eval(&wo, wi) / wi.z);
    assert!((s - 0.7).abs() < 1e-6, "lewis: {s}");
    // Minnaert: ρ cos^{k−1}θo.
    for k in [0.5, 1.5] {
        let m = parse_spec(&format!("minnaert:k={k},rho=0.8")).unwrap();
        for t in [0.0f64, 30.0, 70.0] {
            let expect = 0.8 * t.to_radians().cos().powf(k - 1.0);
            let a = albedo(m.as_ref(), t, 64, 16, 1e-4);
            assert!(
                (a - expect).abs() < 2e-4 * expect,
                "minnaert k={k} θ={t}: {a} vs {expect}"
            );
        }
    }
    // Coupled with kd = 1: total albedo a + (1 − a) = 1 at every angle.
    let c = parse_spec("coupled:kd=1,f0=1,m=0.5").unwrap();
    for t in [0.0, 45.0, 75.0] {
        let a = albedo(c.as_ref(), t, 32, 256, 1e-4);
        assert!((a - 1.0).abs() < 2e-4, "coupled θ={t}: {a}");
    }
}

/// `∫ D(m) cosθm dσ(m) = 1` and the Smith projected-area identity
/// `∫ D(m) max(0, ω·m) dσ(m) = (1 + Λ(ω)) cosθ` check `D` and `Λ` independently of `f_r`.
#[test]
fn microfacet_distribution_and_lambda_identities() {
    for (ax, ay) in [(0.3, 0.3), (0.15, 0.5), (0.9, 0.4)] {
        for m in [
            Microfacet::ggx(MicrofacetParams {
                alpha_x: ax,
                alpha_y: ay,
                f0: 1.0,
            })
            .unwrap(),
            Microfacet::beckmann(MicrofacetParams {
                alpha_x: ax,
                alpha_y: ay,
                f0: 1.0,
            })
            .unwrap(),
        ] {
            // GGX has long tails: integrate finely.
            let norm = projected_hemisphere_integral(256, 512, |h| m.d(h));
            assert!(
                (norm - 1.0).abs() < 2e-4,
                "{} ({ax},{ay}) ∫D cos = {norm}",
                m.name()
            );
            for (t, p) in [(30.0, 10.0), (60.0, 100.0), (80.0, 45.0)] {
                let w = direction_from_angles(t, p);
                let lhs =
                    projected_hemisphere_integral(256, 512, |h| m.d(h) * w.dot(h).max(0.0) / h.z);
                let rhs = (1.0 + m.lambda(&w)) * w.z;
                assert!(
                    (lhs - rhs).abs() < 1e-3 * rhs,
                    "{} ({ax},{ay}) θ={t}: {lhs} vs {rhs}",
                    m.name()
                );
            }
        }
    }
    // Sanity of the constant: D(n) = 1/(π αx αy) for both distributions.
    let g = Microfacet::ggx(MicrofacetParams {
        alpha_x: 0.2,
        alpha_y: 0.4,
        f0: 1.0,
    })
    .unwrap();
    let n = brdf::Vec3::new(0.0, 0.0, 1.0);
    assert!((g.d(&n) - 1.0 / (PI * 0.08)).abs() < 1e-12);
}
