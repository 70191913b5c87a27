//! `build_sampler` by name, option validation and the progress hook.

mod common;

use std::sync::Mutex;

use brdf_sampling::{
    DiscMap, DiscMapPolicy, OptionsError, SAMPLER_NAMES, SamplerError, SetError, SetOptions,
    build_sampler, build_sampler_with_progress, build_set,
};
use common::*;

#[test]
fn known_names_build_and_report_their_name() {
    let opts = SetOptions {
        slices: 3,
        ..test_options()
    };
    for name in SAMPLER_NAMES {
        let s = build_sampler(name, brdf("lambert"), &opts).unwrap();
        assert_eq!(s.name(), *name);
        assert!(s.bytes_used() > 0);
    }
    // `options.mixture` turns the mixture on for the plain name too.
    let s = build_sampler(
        "adaptive",
        brdf("lambert"),
        &SetOptions {
            mixture: true,
            ..opts
        },
    )
    .unwrap();
    assert_eq!(s.name(), "adaptive-mixture");
}

#[test]
fn unknown_names_and_bad_options_are_typed_errors() {
    let err = build_sampler("cosine", brdf("lambert"), &test_options())
        .err()
        .unwrap();
    match &err {
        SamplerError::UnknownSampler { name, known } => {
            assert_eq!(name, "cosine");
            assert_eq!(known.len(), SAMPLER_NAMES.len());
            assert!(known.iter().any(|k| k == "adaptive"));
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains("adaptive-paper"));
    let bad = SetOptions {
        n_max: 0.5,
        ..test_options()
    };
    assert!(matches!(
        build_sampler("adaptive", brdf("lambert"), &bad)
            .err()
            .unwrap(),
        SamplerError::Build(SetError::Options(OptionsError::InvalidNMax(_)))
    ));
}

#[test]
fn progress_reports_every_slice() {
    let seen = Mutex::new(Vec::new());
    let cb = |done: usize, total: usize| seen.lock().unwrap().push((done, total));
    let opts = SetOptions {
        slices: 7,
        ..test_options()
    };
    let s = build_sampler_with_progress("adaptive-paper", brdf("phong:n=20"), &opts, Some(&cb))
        .unwrap();
    assert_eq!(s.name(), "adaptive-paper");
    let mut v = seen.into_inner().unwrap();
    v.sort_unstable();
    assert_eq!(v, (1..=7).map(|d| (d, 7)).collect::<Vec<_>>());
}

#[test]
fn build_is_deterministic_across_thread_counts() {
    let opts = SetOptions {
        slices: 5,
        ..test_options()
    };
    let a = build_set("adaptive", brdf("ggx:alpha=0.1"), &opts, None)
        .unwrap()
        .to_bytes();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| {
        build_set("adaptive", brdf("ggx:alpha=0.1"), &opts, None)
            .unwrap()
            .to_bytes()
    });
    assert_eq!(a, b);
}

#[test]
fn report_counts_structure_and_evaluations() {
    let set = build(
        "phong:n=50",
        brdf_sampling::Variant::Adaptive,
        &test_options(),
    );
    let r = set.report();
    assert_eq!(r.trees, 9);
    assert!(r.leaves >= 9 && r.nodes >= r.leaves && r.max_depth <= test_options().max_depth);
    assert!(
        r.expected_mean_trials >= 1.0 && r.expected_mean_trials <= r.worst_expected_mean_trials
    );
    // The papers' variant evaluates the dense image map (every corner and centre: more than
    // 256² per slice); the refined, mirrored map of the adaptive variant far fewer.
    let dense = build("phong:n=50", brdf_sampling::Variant::Paper, &test_options())
        .report()
        .grid_evaluations;
    assert!(dense as usize > 9 * 256 * 256, "{dense}");
    assert!(
        r.grid_evaluations > 0 && r.grid_evaluations * 3 < dense,
        "{r}"
    );
    assert!(r.memory_bytes > 0 && r.measured_mean_trials.is_none());
    let cost = set.measure_cost(2000, 1);
    assert_eq!(cost.samples, 9 * 2000);
    // Every evaluation is a trial inside the disc, every sample needs at least one.
    assert!(cost.evaluations >= cost.samples && cost.evaluations <= cost.trials);
    let r = set.report_with_cost(100, 2);
    assert_eq!(r.samples, 9 * 2100);
    assert!(r.evaluations_per_sample.unwrap() >= 1.0);
    assert!(format!("{r}").contains("phong"));
}

#[test]
fn grazing_slices_are_refined() {
    let base = SetOptions {
        slices: 18,
        refine_levels: 0,
        disc_map: DiscMapPolicy::Projected,
        ..SetOptions::default()
    };
    let plain = build("ashikhmin-shirley", brdf_sampling::Variant::Adaptive, &base).report();
    let refined = build(
        "ashikhmin-shirley",
        brdf_sampling::Variant::Adaptive,
        &SetOptions {
            refine_levels: 2,
            ..base
        },
    )
    .report();
    assert_eq!(plain.max_depth, base.max_depth);
    assert!(refined.max_depth > base.max_depth, "{refined}");
    assert!(
        refined.worst_expected_mean_trials < 0.5 * plain.worst_expected_mean_trials,
        "{} vs {}",
        refined.worst_expected_mean_trials,
        plain.worst_expected_mean_trials
    );
    assert!(refined.grid_evaluations > plain.grid_evaluations);
}

#[test]
fn auto_disc_map_switches_at_grazing_and_for_unbounded_models() {
    let opts = SetOptions {
        slices: 18,
        ..SetOptions::default()
    };
    // Bounded model: slices with θo ≥ 80° (centres 82.5°, 87.5°) are equal-area.
    let phong = build("phong:n=50", brdf_sampling::Variant::Adaptive, &opts);
    let maps: Vec<DiscMap> = (0..phong.len())
        .map(|i| phong.tree(i).unwrap().density().map())
        .collect();
    assert_eq!(maps.iter().filter(|m| **m == DiscMap::EqualArea).count(), 2);
    assert_eq!(maps[17], DiscMap::EqualArea);
    assert_eq!(maps[15], DiscMap::Projected);
    // Unbounded model (1/cos θi): on the projected disc no finite leaf bound exists and the
    // rejection volume explodes near the rim; the equal-area disc keeps it near n_max.
    let auto = build("strauss", brdf_sampling::Variant::Adaptive, &opts).report();
    let projected = build(
        "strauss",
        brdf_sampling::Variant::Adaptive,
        &SetOptions {
            disc_map: DiscMapPolicy::Projected,
            ..opts
        },
    )
    .report();
    assert_eq!(auto.equal_area_trees, 18);
    assert_eq!(projected.equal_area_trees, 0);
    assert!(auto.worst_expected_mean_trials < 2.5, "{auto}");
    assert!(projected.worst_expected_mean_trials > 10.0, "{projected}");
}
