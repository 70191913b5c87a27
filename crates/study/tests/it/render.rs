//! The sphere renderer: exact where it must be, reproducible for any thread count.

use study::{RenderConfig, StudyConfig, StudyPlan};

fn plan(light: &str) -> StudyPlan {
    let mut c = StudyConfig::new(
        vec!["uniform".into(), "cosine".into(), "adaptive".into()],
        vec!["lambert".into(), "phong:n=20".into()],
        vec![30.0],
        vec![light.into()],
    );
    c.slices = 8;
    StudyPlan::new(c, Vec::new()).unwrap()
}

fn cfg() -> RenderConfig {
    RenderConfig {
        sphere_px: 12,
        spp: 8,
        reference_spp: 32,
        light: 0,
        seed: 5,
        mis: true,
    }
}

#[test]
fn constant_light_lambert_is_exact_for_cosine_sampling() {
    let r = plan("constant:radiance=2").render(&cfg(), &|_| {}).unwrap();
    // Left sphere (Lambert, albedo 0.8): every lit pixel is 2 × 0.8 for an exact sampler.
    let w = r.reference.width;
    let lit: Vec<usize> = (0..r.reference.rgb.len())
        .filter(|i| i % w < 12 && r.reference.rgb[*i][0] > 0.0)
        .collect();
    assert!(lit.len() > 50);
    // The equal-samples image of a sampler.
    let equal_samples = |sampler: &str| {
        r.images
            .iter()
            .find(|i| i.sampler == sampler && i.kind == "equal samples")
            .unwrap()
    };
    let cosine = equal_samples("cosine");
    for &i in &lit {
        assert!((cosine.rgb[i][1] - 1.6).abs() < 1e-9, "{:?}", cosine.rgb[i]);
    }
    // Nothing to sample under a constant light: no MIS images.
    assert!(r.images.iter().all(|i| !i.kind.starts_with("MIS")));
    assert!(r.mis_light.is_none());
    // Uniform sampling is not exact.
    let uniform = equal_samples("uniform");
    assert!(lit.iter().any(|&i| (uniform.rgb[i][1] - 1.6).abs() > 1e-3));
    // The adaptive sampler is ∝ f·cos on the Lambert sphere whatever the slice (all slices
    // are the same there), up to its numerical normaliser: exact in every pixel frame — a
    // check of the renderer's frames and of the estimator.
    let adaptive = equal_samples("adaptive");
    for &i in &lit {
        assert!(
            (adaptive.rgb[i][1] - 1.6).abs() < 1e-3 * 1.6,
            "{:?}",
            adaptive.rgb[i]
        );
    }
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    let p = plan("area:theta=30,phi=180,radius=10");
    let render_on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| p.render(&cfg(), &|_| {}).unwrap())
    };
    let (one, two) = (render_on(1), render_on(2));
    assert_eq!(one.reference.rgb, two.reference.rgb);
    let equal_samples = |r: &study::Render| -> Vec<Vec<[f64; 3]>> {
        r.images
            .iter()
            .filter(|i| i.kind == "equal samples" || i.kind == "MIS equal samples")
            .map(|i| i.rgb.clone())
            .collect()
    };
    assert_eq!(equal_samples(&one).len(), 6);
    assert_eq!(equal_samples(&one), equal_samples(&two));
    assert!(
        one.images
            .iter()
            .all(|i| i.rel_error.is_some_and(f64::is_finite))
    );
}

/// The sphere sheet of some of a study's BRDFs (`render_subset`, what `brdf-lab study` draws
/// with the samplers its statistics built) equals the render of a study of those BRDFs alone;
/// a BRDF outside the study is refused.
#[test]
fn a_subset_of_the_study_renders_as_a_study_of_the_subset() {
    let light = "area:theta=30,phi=180,radius=10";
    let both = plan(light);
    let sub = both
        .render_subset(&cfg(), &["phong:n=20".to_string()], &|_| {})
        .unwrap();
    let mut c = both.config().clone();
    c.brdfs = vec!["phong:n=20".into()];
    let alone = StudyPlan::new(c, Vec::new())
        .unwrap()
        .render(&cfg(), &|_| {})
        .unwrap();
    assert_eq!(sub.brdfs, alone.brdfs);
    assert_eq!(sub.reference.width, 12);
    assert_eq!(sub.reference.rgb, alone.reference.rgb);
    let equal_samples = |r: &study::Render| -> Vec<(String, Vec<[f64; 3]>)> {
        r.images
            .iter()
            .filter(|i| i.kind == "equal samples")
            .map(|i| (i.sampler.clone(), i.rgb.clone()))
            .collect()
    };
    assert_eq!(equal_samples(&sub).len(), 3);
    assert_eq!(equal_samples(&sub), equal_samples(&alone));
    assert!(
        both.render_subset(&cfg(), &["ward".to_string()], &|_| {})
            .is_err()
    );
}

/// The MIS images under an area light: two per sampler (`MIS equal samples` at the config's
/// spp, `MIS equal time`), and the equal-time MIS budget comes from each sampler's measured
/// time per **MIS** pixel sample: `spp × t_adaptive / t_MIS` pairs, `t_adaptive` the budget
/// (the `adaptive` sampler's BRDF-sampling time). Rounding the BRDF-only time instead would
/// give another count for at least one sampler (MIS does both samplings, so its time is
/// larger), which the test requires, so a budget taken from the wrong time fails.
#[test]
fn mis_images_get_their_equal_time_budget_from_the_mis_time() {
    let p = plan("area:theta=30,phi=180,radius=10");
    let mut c = cfg();
    c.spp = 16;
    let r = p.render(&c, &|_| {}).unwrap();
    assert!(r.mis_light.as_deref().is_some_and(|m| m.contains("cone")));
    let adaptive = r
        .sample_costs
        .iter()
        .find(|c| c.sampler == "adaptive")
        .unwrap();
    assert_eq!(r.budget_ns, adaptive.coherent_ns);
    let mut differs = false;
    for cost in &r.sample_costs {
        let mis_ns = cost.mis_ns.unwrap();
        assert!(mis_ns > 0.0 && cost.coherent_ns > 0.0);
        let image = |kind: &str| {
            r.images
                .iter()
                .find(|i| i.sampler == cost.sampler && i.kind == kind)
                .unwrap_or_else(|| panic!("no {kind} image of {}", cost.sampler))
        };
        assert_eq!(image("MIS equal samples").spp, 16);
        let equal_time = image("MIS equal time");
        assert_eq!(
            equal_time.spp,
            study::equal_time_spp(16, r.budget_ns, mis_ns),
            "{}: {mis_ns:.0} ns per MIS sample, budget {:.0} ns",
            cost.sampler,
            r.budget_ns
        );
        assert!(equal_time.rel_error.is_some_and(f64::is_finite));
        differs |= equal_time.spp != study::equal_time_spp(16, r.budget_ns, cost.coherent_ns);
        assert_eq!(
            image("equal time").spp,
            study::equal_time_spp(16, r.budget_ns, cost.coherent_ns)
        );
    }
    assert!(differs, "the MIS and BRDF-only times give the same budgets");
    let md = r.markdown(&[]);
    assert!(md.contains("| sampler | ns / MIS sample † |"), "{md}");
    assert!(md.contains("At equal time, BRDF only: best **"), "{md}");
    assert!(md.contains("; with MIS: best **"), "{md}");
}
