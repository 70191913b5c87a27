//! Energy plausibility: does a BRDF reflect more energy than it receives?
//!
//! A physically plausible BRDF has a directional albedo `ρ(ωo) = ∫_Ω f_r cos θi dσ ≤ 1`.
//! Models accept parameter combinations that break it (`phong:ks=0.9,kd=0.9`: ρ = 1.8 at
//! normal incidence); [`energy_warnings`] finds them numerically, generically for any
//! [`Brdf`], at the outgoing angles [`CHECK_ANGLES_DEG`], per RGB channel
//! ([`Brdf::eval_rgb`]; grey models have three equal channels).
//!
//! The albedo is integrated by a globally adaptive rule that does not false-alarm on sharp
//! lobes (a fixed grid can overshoot when a node lands on a narrow peak): equal-area polar
//! coordinates `(u, ψ)`, `ωi = (u√(2 − u²) cos φ, u√(2 − u²) sin φ, 1 − u²)` with
//! `φ = φ_mirror + ψ`, so `f_r cos θi dσ = 2u(1 − u²) f_r du dψ` and the mirror direction sits on
//! the line `ψ = 0` at `u = √(1 − cos θo)`; pieces get tensor Gauss–Legendre rules of orders 8
//! and 5, the piece where they disagree most is split into quadrants, and the pieces around
//! the mirror direction start refined down to `2⁻¹⁰` of the domain. A warning needs the
//! albedo to exceed `1 + ALBEDO_TOLERANCE` by more than the estimated error.

use std::collections::BinaryHeap;
use std::f64::consts::PI;

use crate::brdf::Brdf;
use crate::geometry::{Vec3, direction_from_angles};
use crate::quadrature::{ErrorEstimate, GaussLegendre, WorstFirst};

/// Relative excess over 1 that is tolerated (quadrature and model rounding).
pub const ALBEDO_TOLERANCE: f64 = 0.01;

/// Outgoing polar angles (degrees) at which [`energy_warnings`] checks the albedo.
pub const CHECK_ANGLES_DEG: [f64; 4] = [0.0, 30.0, 60.0, 80.0];

/// Evaluation budget of one [`adaptive_albedo_rgb`] call.
const BUDGET: u64 = 400_000;

/// [`adaptive_albedo_rgb`] stops once its summed error estimate is below this (absolute,
/// per channel).
const TOL: f64 = 1e-5;

/// [`energy_warnings`]' rule stops at this summed error estimate (absolute, per channel): a
/// tenth of [`ALBEDO_TOLERANCE`], ample to tell an albedo above `1 + ALBEDO_TOLERANCE` (the
/// warning needs the excess to exceed the estimate), at a small part of [`TOL`]'s work on a
/// measured file (the check runs before every CLI command).
const WARNING_TOL: f64 = ALBEDO_TOLERANCE / 10.0;

/// Initial uniform split of the domain (`2^k × 2^(k+1)` pieces).
const INITIAL_DEPTH: u32 = 3;

/// Depth to which pieces near the mirror direction are split initially.
const MIRROR_DEPTH: u32 = 10;

const CHANNELS: [&str; 3] = ["red", "green", "blue"];

/// Warnings (one line each, no trailing period) for every RGB channel of `brdf` whose
/// directional albedo exceeds `1 + ALBEDO_TOLERANCE` (beyond the quadrature's error estimate)
/// at one of [`CHECK_ANGLES_DEG`] (`φo = 0`); empty for a plausible BRDF.
///
/// ```
/// let phong = brdf::parse_spec("phong:ks=0.9,kd=0.9")?;
/// let w = brdf::energy_warnings(phong.as_ref());
/// assert_eq!(w.len(), 1);
/// assert!(w[0].contains("1.800"), "{}", w[0]);
/// assert!(brdf::energy_warnings(brdf::parse_spec("phong")?.as_ref()).is_empty());
/// # Ok::<(), brdf::SpecError>(())
/// ```
pub fn energy_warnings(brdf: &dyn Brdf) -> Vec<String> {
    // (worst albedo, its angle, angles exceeding) per channel.
    let mut worst: [(f64, f64, Vec<f64>); 3] = Default::default();
    // The angles' albedos on threads of their own (a serial ~0.3 s of the CLI's `build` on an
    // RGL file before its parallel build), read back in the angles' order: the same
    // warnings as one after the other.
    // An angle whose thread cannot be started is integrated on the calling thread.
    let albedo_at = |t: f64| albedo_to(brdf, &direction_from_angles(t, 0.0), WARNING_TOL);
    let albedos: Vec<([f64; 3], [f64; 3])> = std::thread::scope(|s| {
        let handles: Vec<_> = CHECK_ANGLES_DEG
            .iter()
            .map(|&t| {
                (
                    t,
                    std::thread::Builder::new().spawn_scoped(s, move || albedo_at(t)),
                )
            })
            .collect();
        handles
            .into_iter()
            .map(|(t, h)| match h {
                Ok(h) => h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)),
                Err(_) => albedo_at(t),
            })
            .collect()
    });
    for (&t, &(value, err)) in CHECK_ANGLES_DEG.iter().zip(&albedos) {
        for c in 0..3 {
            if value[c] - err[c] > 1.0 + ALBEDO_TOLERANCE {
                let w = &mut worst[c];
                if value[c] > w.0 {
                    (w.0, w.1) = (value[c], t);
                }
                w.2.push(t);
            }
        }
    }
    let grey = worst[0] == worst[1] && worst[1] == worst[2];
    let mut out = Vec::new();
    for (c, (value, angle, angles)) in worst.iter().enumerate() {
        if angles.is_empty() || (grey && c > 0) {
            continue;
        }
        let channel = if grey {
            String::new()
        } else {
            format!(" of the {} channel", CHANNELS[c])
        };
        let list: Vec<String> = angles.iter().map(|a| format!("{a}°")).collect();
        out.push(format!(
            "directional albedo{channel} {value:.3} at θo = {angle}° (> {} at θo = {}): the BRDF reflects more energy than it receives; check its parameters",
            1.0 + ALBEDO_TOLERANCE,
            list.join(", ")
        ));
    }
    out
}

/// One piece of the adaptive rule.
struct Piece {
    u: [f64; 2],
    psi: [f64; 2],
    value: [f64; 3],
    err: [f64; 3],
}

impl ErrorEstimate for Piece {
    /// The worst channel's error.
    fn error_estimate(&self) -> f64 {
        self.err.iter().fold(0.0, |a: f64, &b| a.max(b))
    }
}

/// The directional albedo of each RGB channel of `brdf` at `wo` (unit, above the horizon)
/// and its estimated absolute error, by the adaptive rule of the module docs.
pub fn adaptive_albedo_rgb(brdf: &dyn Brdf, wo: &Vec3) -> ([f64; 3], [f64; 3]) {
    albedo_to(brdf, wo, TOL)
}

/// [`adaptive_albedo_rgb`] stopping once the summed error estimate of every channel is at
/// most `tol` (or at the evaluation budget).
fn albedo_to(brdf: &dyn Brdf, wo: &Vec3, tol: f64) -> ([f64; 3], [f64; 3]) {
    let hi = GaussLegendre::new(8);
    let lo = GaussLegendre::new(5);
    // Isotropic: rotate ωo to φo = 0; mirror-symmetric then: ψ ↦ −ψ symmetric, integrate ψ ≤ 0.
    let iso = brdf.is_isotropic();
    let wo = if iso {
        Vec3::new(wo.x.hypot(wo.y), 0.0, wo.z)
    } else {
        *wo
    };
    let half = iso && brdf.is_mirror_symmetric();
    let factor = if half { 2.0 } else { 1.0 };
    let phi_m = (-wo.y).atan2(-wo.x);
    let u_m = (1.0 - wo.z).max(0.0).sqrt();
    let evals = std::cell::Cell::new(0u64);
    let eval = |u: f64, psi: f64| -> [f64; 3] {
        evals.set(evals.get() + 1);
        let z = 1.0 - u * u;
        let s = u * (2.0 - u * u).sqrt();
        let (sp, cp) = (phi_m + psi).sin_cos();
        let wi = Vec3::new(s * cp, s * sp, z);
        let w = 2.0 * u * z;
        let f = brdf.eval_rgb(&wo, &wi);
        [w * f[0], w * f[1], w * f[2]]
    };
    let rule = |rule: &GaussLegendre, u: [f64; 2], psi: [f64; 2]| -> [f64; 3] {
        let (cu, hu) = (0.5 * (u[0] + u[1]), 0.5 * (u[1] - u[0]));
        let (cp, hp) = (0.5 * (psi[0] + psi[1]), 0.5 * (psi[1] - psi[0]));
        let mut sum = [0.0; 3];
        for (x, wx) in rule.nodes().iter().zip(rule.weights()) {
            for (y, wy) in rule.nodes().iter().zip(rule.weights()) {
                let v = eval(cu + hu * x, cp + hp * y);
                for c in 0..3 {
                    sum[c] += wx * wy * v[c];
                }
            }
        }
        sum.map(|s| s * hu * hp)
    };
    let piece = |u: [f64; 2], psi: [f64; 2]| {
        let value = rule(&hi, u, psi);
        let low = rule(&lo, u, psi);
        WorstFirst(Piece {
            u,
            psi,
            value,
            err: [0, 1, 2].map(|c| (value[c] - low[c]).abs()),
        })
    };
    let psi_max = if half { 0.0 } else { PI };
    let mut rects = Vec::new();
    initial([0.0, 1.0], [-PI, psi_max], 0, [u_m, 0.0], &mut rects);
    let mut heap: BinaryHeap<WorstFirst<Piece>> =
        rects.into_iter().map(|(u, p)| piece(u, p)).collect();
    let total_err = |heap: &BinaryHeap<WorstFirst<Piece>>| {
        let mut e = [0.0; 3];
        for p in heap.iter() {
            add3(&mut e, &p.err);
        }
        e
    };
    loop {
        let e = total_err(&heap);
        let done = e.iter().all(|&x| factor * x <= tol);
        if done || evals.get() >= BUDGET {
            break;
        }
        let Some(worst) = heap.pop() else { break };
        let (um, pm) = (
            0.5 * (worst.u[0] + worst.u[1]),
            0.5 * (worst.psi[0] + worst.psi[1]),
        );
        for (u, p) in [
            ([worst.u[0], um], [worst.psi[0], pm]),
            ([um, worst.u[1]], [worst.psi[0], pm]),
            ([worst.u[0], um], [pm, worst.psi[1]]),
            ([um, worst.u[1]], [pm, worst.psi[1]]),
        ] {
            heap.push(piece(u, p));
        }
    }
    let mut value = [0.0; 3];
    for p in heap.iter() {
        add3(&mut value, &p.value);
    }
    let err = total_err(&heap);
    (value.map(|v| factor * v), err.map(|e| factor * e))
}

/// `a += b` per channel.
fn add3(a: &mut [f64; 3], b: &[f64; 3]) {
    for (x, y) in a.iter_mut().zip(b) {
        *x += y;
    }
}

/// The initial partition: uniform to `INITIAL_DEPTH`, pieces within one piece size of `peak`
/// (in `(u, ψ/π)` units) split to `MIRROR_DEPTH`.
fn initial(
    u: [f64; 2],
    psi: [f64; 2],
    depth: u32,
    peak: [f64; 2],
    out: &mut Vec<([f64; 2], [f64; 2])>,
) {
    let (du, dp) = (u[1] - u[0], psi[1] - psi[0]);
    let near = peak[0] > u[0] - du
        && peak[0] < u[1] + du
        && peak[1] > psi[0] - dp
        && peak[1] < psi[1] + dp;
    if depth < INITIAL_DEPTH || (depth < MIRROR_DEPTH && near) {
        let (um, pm) = (0.5 * (u[0] + u[1]), 0.5 * (psi[0] + psi[1]));
        for (a, b) in [
            ([u[0], um], [psi[0], pm]),
            ([um, u[1]], [psi[0], pm]),
            ([u[0], um], [pm, psi[1]]),
            ([um, u[1]], [pm, psi[1]]),
        ] {
            initial(a, b, depth + 1, peak, out);
        }
    } else {
        out.push((u, psi));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse_spec;

    #[test]
    fn no_false_alarm_on_conserving_models_and_sharp_lobes() {
        for m in crate::models() {
            let Ok(b) = parse_spec(m.name) else { continue };
            if b.conserves_energy() {
                assert!(energy_warnings(b.as_ref()).is_empty(), "{}", m.name);
            }
        }
        for spec in [
            "lambert:rho=1",
            "phong:n=100000,ks=1,kd=0",
            "blinn:n=100000,ks=1,kd=0",
            "ggx:alpha=0.001",
            "beckmann:alpha=0.001",
            "ggx:alpha=0.001,alpha_y=0.3",
        ] {
            let b = parse_spec(spec).expect(spec);
            assert!(b.conserves_energy(), "{spec}");
            assert!(energy_warnings(b.as_ref()).is_empty(), "{spec}");
        }
        // The sharpest Phong lobe integrates to exactly ks at normal incidence.
        let b = parse_spec("phong:n=100000,ks=1,kd=0").expect("spec");
        let (v, e) = adaptive_albedo_rgb(b.as_ref(), &direction_from_angles(0.0, 0.0));
        assert!((v[0] - 1.0).abs() < 1e-4 && e[0] < 1e-4, "{v:?} {e:?}");
    }

    #[test]
    fn implausible_parameters_are_reported() {
        let b = parse_spec("phong:ks=0.9,kd=0.9").expect("spec");
        let w = energy_warnings(b.as_ref());
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("1.800 at θo = 0°") && !w[0].contains("channel"),
            "{w:?}"
        );
        // Albedo 1.005 at normal incidence is inside the tolerance, 1.02 is not.
        let b = parse_spec("phong:ks=0.5,kd=0.505").expect("spec");
        assert!(energy_warnings(b.as_ref()).is_empty());
        let b = parse_spec("phong:ks=0.5,kd=0.52").expect("spec");
        let w = energy_warnings(b.as_ref());
        assert!(w.len() == 1 && w[0].contains("1.020 at θo = 0°"), "{w:?}");
    }

    /// Red reflects 1.2, green and blue 0.5: only red is reported.
    struct Reddish;
    impl Brdf for Reddish {
        fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            crate::luminance(self.eval_rgb(wo, wi))
        }
        fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
            if wo.z > 0.0 && wi.z > 0.0 {
                [1.2 / PI, 0.5 / PI, 0.5 / PI]
            } else {
                [0.0; 3]
            }
        }
    }

    #[test]
    fn rgb_channels_are_checked_separately() {
        let w = energy_warnings(&Reddish);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("red channel 1.200"), "{w:?}");
        // Its luminance (0.66) alone would not have been reported.
        assert!(crate::luminance([1.2, 0.5, 0.5]) < 1.0);
    }
}
