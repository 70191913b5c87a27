//! Prints a few values and albedos of an RGL file (development probe).
//!
//! `rgl_probe FILE evals N THETA_DEG slice|blended`: only `N` evaluations at one prepared `ωo`
//! of elevation `THETA_DEG` and random `ωi` (fixed seed), through a [`brdf::measured::rgl::PreparedSlice`]
//! of that θo or through the two-slice tables; prints their sum (for instruction counts:
//! `valgrind --tool=cachegrind --cache-sim=no` at two `N`, the difference over the extra `N`).
//! `rgl_probe FILE evals N THETA_DEG block`: the same `N` directions through a caller-held run's
//! [`brdf::PreparedRun::eval_block`] (the RGL block in vector lanes), 64 per call.
//! `rgl_probe FILE blends N THETA_DEG`: only `N` caller-held runs ([`Brdf::prepare_run`]) at
//! that θo, one evaluation each (the cost of blending a slice, by the same difference).
use brdf::{Brdf, RglBrdf, Vec3, direction_from_angles, directional_albedo};

/// `N` evaluations at one θo through a run's block evaluation, 64 per call.
fn evals_block(b: &RglBrdf, n: usize, theta: f64) {
    let wo = direction_from_angles(theta, 0.0);
    let run = b.prepare_run(&wo).expect("a run above the horizon");
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut wis, mut out) = (Vec::with_capacity(64), vec![0.0; 64]);
    let mut acc = 0.0;
    let mut done = 0;
    while done < n {
        wis.clear();
        for _ in 0..64.min(n - done) {
            let z = 1.0 - uniform();
            let phi = std::f64::consts::TAU * uniform();
            let r = (1.0 - z * z).max(0.0).sqrt();
            wis.push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
        }
        run.eval_block(&wis, &mut out);
        acc += out[..wis.len()].iter().sum::<f64>();
        done += wis.len();
    }
    println!("{n} evaluations at θo {theta}° (block): sum {acc}");
}

/// `N` evaluations at one θo (see the module docs).
fn evals(b: &RglBrdf, n: usize, theta: f64, slice: bool) {
    let wo = direction_from_angles(theta, 0.0);
    let q = b.prepare(&wo);
    // A slice of another θo is never used: the two-slice path.
    let p = b.prepare_slice(&if slice {
        wo
    } else {
        direction_from_angles(theta + 7.0, 0.0)
    });
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut acc = 0.0;
    for _ in 0..n {
        let z = 1.0 - uniform();
        let phi = std::f64::consts::TAU * uniform();
        let r = (1.0 - z * z).max(0.0).sqrt();
        acc += b.eval_in_slice(&p, &q, &Vec3::new(r * phi.cos(), r * phi.sin(), z));
    }
    println!(
        "{n} evaluations at θo {theta}° ({}): sum {acc}",
        if slice { "slice" } else { "blended" }
    );
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "data/measured/rgl/paper_white_rgb.bsdf".into());
    let args: Vec<String> = std::env::args().collect();
    if args.get(2).map(String::as_str) == Some("blends") {
        let b = RglBrdf::load(std::path::Path::new(&path)).unwrap();
        let n: usize = args[3].parse().unwrap();
        let theta: f64 = args[4].parse().unwrap();
        let wi = direction_from_angles(20.0, 40.0);
        let mut acc = 0.0;
        for k in 0..n {
            // A new θo bit pattern per run (the blend is made again every time).
            let wo = direction_from_angles(theta + 1e-9 * k as f64, 0.0);
            acc += b.prepare_run(&wo).map_or(0.0, |r| r.eval(&wi));
        }
        println!("{n} runs at θo {theta}°: sum {acc}");
        return;
    }
    if args.get(2).map(String::as_str) == Some("evals") {
        let b = RglBrdf::load(std::path::Path::new(&path)).unwrap();
        let n = args[3].parse().unwrap();
        let theta = args[4].parse().unwrap();
        if args[5] == "block" {
            evals_block(&b, n, theta);
        } else {
            evals(&b, n, theta, args[5] == "slice");
        }
        return;
    }
    let t = std::time::Instant::now();
    let b = RglBrdf::load(std::path::Path::new(&path)).unwrap();
    println!(
        "load {:?} {} clamped {:?} iso {} mirror {}",
        t.elapsed(),
        b.description(),
        b.clamped(),
        b.is_isotropic(),
        b.is_mirror_symmetric()
    );
    for th in [0.0, 30.0, 60.0, 80.0] {
        let wo = direction_from_angles(th, 0.0);
        let a = directional_albedo(&b, &wo, 64, 128);
        let m = brdf::mirror(&wo);
        let wi = direction_from_angles(40.0, 120.0);
        let wi2 = direction_from_angles(40.0, -120.0);
        println!(
            "θo {th}: albedo {a:.4} f(mirror) {:?} f {:.5} f(mirrored) {:.5} recip {:.5}",
            b.eval_rgb(&wo, &m),
            b.eval(&wo, &wi),
            b.eval(&wo, &wi2),
            b.eval(&wi, &wo)
        );
    }
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    let wo = direction_from_angles(30.0, 0.0);
    for i in 0..1_000_000 {
        let a = i as f64 * 0.000_001;
        acc += b.eval(&wo, &direction_from_angles(80.0 * a, 360.0 * a * 37.0));
    }
    println!("1e6 evals: {:?} ({acc})", t.elapsed());
    for th in [0.0, 45.0, 80.0] {
        let wo = direction_from_angles(th, 0.0);
        for ti in [85.0, 89.0, 89.9, 89.999] {
            println!(
                "θo {th} θi {ti}: {:.5} {:.5}",
                b.eval(&wo, &direction_from_angles(ti, 180.0)),
                b.eval(&wo, &direction_from_angles(ti, 60.0))
            );
        }
    }
}
