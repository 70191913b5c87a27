//! A study run whole, run as two shards (one BRDF each) and merged, and run on one or two threads gives the
//! same numbers (timings excepted).

use study::{Shard, StudyConfig, StudyPlan, StudyResults};

fn tiny() -> StudyConfig {
    let mut c = StudyConfig::new(
        vec!["uniform".into(), "cosine".into(), "adaptive-paper".into()],
        vec!["phong:n=20".into(), "lambert".into()],
        vec![30.0, 60.0],
        vec!["area:theta=30,phi=180,radius=10".into()],
    );
    c.n_grid = vec![1, 16, 64];
    c.repetitions = 4;
    c.variance_samples = 200;
    c.timing_samples = 16;
    c.timing_repeats = 1;
    c.slices = 6;
    c.seed = 7;
    c
}

fn run(shard: Option<Shard>, threads: usize) -> StudyResults {
    let plan = StudyPlan::new(tiny(), vec!["a note".into()]).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| plan.run(shard, &|_| {}))
}

#[test]
fn one_run_equals_two_merged_shards_and_any_thread_count() {
    let whole = run(None, 2);
    // 3 samplers (adaptive-paper twice: one-sample and batch) × 2 BRDFs × 2 angles.
    assert_eq!(whole.cells.len(), 16);
    assert!(whole.cells.iter().all(|c| c.ok() && c.timing.is_some()));
    // Two shards, one BRDF each: each builds only its own BRDF's samplers, so the two
    // shards' builds are disjoint and together the whole run's (N shards cost ≈ 1/N).
    let plan = StudyPlan::new(tiny(), Vec::new()).unwrap();
    let shard = |k| Some(Shard { index: k, count: 2 });
    assert_eq!(plan.shard_brdfs(shard(1)), ["phong:n=20"]);
    assert_eq!(plan.shard_brdfs(shard(2)), ["lambert"]);
    let (b1, b2) = (plan.shard_builds(shard(1)), plan.shard_builds(shard(2)));
    assert_eq!(b1.len(), 3);
    assert_eq!(b2.len(), 3);
    assert!(b1.iter().all(|(_, b)| *b == "phong:n=20"));
    assert!(b2.iter().all(|(_, b)| *b == "lambert"));
    let (mut union, mut all) = ([b1, b2].concat(), plan.shard_builds(None));
    union.sort_unstable();
    all.sort_unstable();
    assert_eq!(union, all);
    let shards: Vec<StudyResults> = (1..=2).map(|k| run(shard(k), 1)).collect();
    for (s, brdf) in shards.iter().zip(["phong:n=20", "lambert"]) {
        assert_eq!(s.cells.len(), 8);
        assert!(s.cells.iter().all(|c| c.brdf == brdf));
    }
    // Through JSON, as `study merge` reads them.
    let reread: Vec<StudyResults> = shards
        .iter()
        .map(|s| StudyResults::from_json(&s.to_json(), "shard").unwrap())
        .collect();
    let merged = StudyResults::merge(reread).unwrap();
    let (m, w) = (merged.without_timing(), whole.without_timing());
    for (a, b) in m.cells.iter().zip(&w.cells) {
        assert_eq!(a, b, "cell {}", a.index);
    }
    assert_eq!(m, w);
    assert_eq!(
        merged.without_timing().to_json(),
        whole.without_timing().to_json()
    );
    assert_eq!(run(None, 1).without_timing(), whole.without_timing());
    // Rankings: one per comparison (BRDF × θo), made on the whole grid only.
    assert!(shards.iter().all(|s| s.rankings.is_empty()));
    assert_eq!(whole.rankings.len(), 4);
    assert_eq!(merged.rankings.len(), 4);
    assert_eq!(merged.runs.len(), 2);
    // The merged rankings and report are the single run's: given the single run's timings
    // (the only measured numbers), the merged results rank and report exactly as it does.
    let mut same = merged.clone();
    for (c, w) in same.cells.iter_mut().zip(&whole.cells) {
        c.timing = w.timing;
    }
    same.runs = whole.runs.clone();
    same.rankings = study::rankings(&same);
    assert_eq!(same.rankings, whole.rankings);
    assert_eq!(same, whole);
    let assets = study::ReportAssets::default();
    assert_eq!(
        study::report_markdown(&same, &assets),
        study::report_markdown(&whole, &assets)
    );
    let json: serde_json::Value = serde_json::from_str(&whole.to_json()).unwrap();
    for r in json["rankings"].as_array().unwrap() {
        for key in [
            "brdf",
            "theta_o",
            "light",
            "estimator",
            "best",
            "tied",
            "worse",
        ] {
            assert!(r.get(key).is_some(), "missing {key}");
        }
        let named = 1 + r["tied"].as_array().unwrap().len() + r["worse"].as_array().unwrap().len();
        assert_eq!(named, r["entries"].as_array().unwrap().len());
    }
    // Timings are the only difference a rerun may show.
    assert_ne!(whole.cells[2].timing, None);
}

#[test]
fn merge_refuses_incomplete_or_repeated_shards() {
    let a = run(Some(Shard { index: 1, count: 2 }), 1);
    let err = StudyResults::merge(vec![a.clone()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("missing shards: 2/2"), "{err}");
    let err = StudyResults::merge(vec![a.clone(), a.clone()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("given twice"), "{err}");
    // Three shards of two BRDFs: shard 3 has no cell, but a merge without it is refused.
    let (s1, s2) = (
        run(Some(Shard { index: 1, count: 3 }), 1),
        run(Some(Shard { index: 2, count: 3 }), 1),
    );
    assert_eq!(s1.cells.len() + s2.cells.len(), 16);
    let err = StudyResults::merge(vec![s1.clone(), s2.clone()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("missing shards: 3/3"), "{err}");
    let s3 = run(Some(Shard { index: 3, count: 3 }), 1);
    assert!(s3.cells.is_empty());
    assert_eq!(
        StudyResults::merge(vec![s1, s2, s3]).unwrap().cells.len(),
        16
    );
    let mut other = run(Some(Shard { index: 2, count: 2 }), 1);
    other.config.seed += 1;
    let err = StudyResults::merge(vec![a, other]).unwrap_err().to_string();
    assert!(err.contains("different study configurations"), "{err}");
}

#[test]
fn results_are_plausible_and_the_csv_has_one_row_per_n() {
    let r = run(None, 2);
    for c in &r.cells {
        assert!(c.reference.value > 0.0 && c.reference.abs_err < 1e-3 * c.reference.value);
        assert_eq!(c.errors.len(), 3);
        assert!(c.variance.value.is_finite());
    }
    // The adaptive sampler beats uniform sampling of a glossy Phong lobe lit by a disc at
    // the mirror direction (θo = 30°): lower per-sample variance.
    let var = |s: &str| {
        r.cells
            .iter()
            .find(|c| c.sampler == s && c.brdf == "phong:n=20" && c.theta_o_deg == 30.0)
            .unwrap()
            .variance
            .value
    };
    assert!(var("adaptive-paper") < var("uniform"));
    let csv = r.to_csv();
    assert_eq!(csv.lines().count(), 1 + 16 * 3);
    assert!(csv.contains("\"phong:n=20\"") || csv.contains(",phong:n=20,"));
    assert!(csv.lines().next().unwrap().contains("efficiency[timing]"));
}

#[test]
fn bad_names_are_refused_before_any_work() {
    for (field, value) in [("sampler", "nope"), ("brdf", "nope"), ("light", "nope")] {
        let mut c = tiny();
        match field {
            "sampler" => c.samplers.push(value.into()),
            "brdf" => c.brdfs.push(value.into()),
            _ => c.lights.push(value.into()),
        }
        assert!(StudyPlan::new(c, Vec::new()).is_err(), "{field}");
    }
    // An environment-map sampler is not a direction sampler.
    let mut c = tiny();
    c.samplers.push("envmap-cdf".into());
    let err = StudyPlan::new(c, Vec::new()).unwrap_err().to_string();
    assert!(err.contains("not a direction sampler"), "{err}");
}
