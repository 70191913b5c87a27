//! Every entry builds, names are unique, errors are typed and helpful, saved sets come back
//! as the entry that built them.

use std::collections::HashSet;
use std::sync::Arc;

use brdf_sampling::SetOptions;
use envmap::AdaptiveOptions;
use partition_sampler::{Rect, Sampler2D};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use samplers::{DirectionRequest, RegistryError, SAMPLERS, find};

fn brdf(spec: &str) -> Arc<dyn brdf::Brdf> {
    Arc::from(brdf::parse_spec(spec).expect("spec"))
}

fn small() -> SetOptions {
    SetOptions {
        slices: 3,
        ..SetOptions::default()
    }
}

#[test]
fn names_are_unique_and_every_kind_is_present() {
    let names: HashSet<&str> = SAMPLERS.iter().map(|e| e.name).collect();
    assert_eq!(names.len(), SAMPLERS.len());
    for kind in ["direction", "disc", "envmap", "grid"] {
        assert!(
            SAMPLERS.iter().any(|e| e.constructor.kind() == kind),
            "{kind}"
        );
    }
    for e in SAMPLERS {
        assert!(
            !e.summary.is_empty() && !e.summary.contains('\n'),
            "{}",
            e.name
        );
    }
}

#[test]
fn every_direction_sampler_builds_and_reports_consistent_pdfs() {
    let options = small();
    let wo = brdf::direction_from_angles(40.0, 10.0);
    let rgl = format!(
        "rgl:{}/../../data/measured/rgl/paper_white_rgb.bsdf",
        env!("CARGO_MANIFEST_DIR")
    );
    for e in SAMPLERS.iter().filter(|e| e.is_direction()) {
        // Format-specific samplers (rgl-native) get a BRDF of their format.
        let spec = if e.applicability(brdf("phong:n=20").as_ref()).is_ok() {
            "phong:n=20"
        } else {
            rgl.as_str()
        };
        assert_eq!(e.applicability(brdf(spec).as_ref()), Ok(()), "{}", e.name);
        let built = e
            .build_direction(&DirectionRequest::new(brdf(spec), &options).with_spec(spec))
            .unwrap_or_else(|err| panic!("{}: {err}", e.name));
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        for _ in 0..200 {
            let s = built.sampler.sample(&wo, &mut rng);
            assert!(s.pdf > 0.0, "{}", e.name);
            let p = built.pdf(&wo, &s.wi);
            assert!(
                (p - s.pdf).abs() <= 1e-9 * s.pdf,
                "{}: {p} vs {}",
                e.name,
                s.pdf
            );
        }
        assert_eq!(
            built.sampler.bytes_used() > 0,
            e.capabilities.needs_build,
            "{}",
            e.name
        );
        assert_eq!(
            built.set.is_some(),
            matches!(e.constructor, samplers::Constructor::AdaptiveSet { .. }),
            "{}",
            e.name
        );
    }
}

#[test]
fn planar_samplers_build_on_their_targets() {
    let sky = envmap::procedural_sky(64, 32).unwrap();
    let wo = brdf::direction_from_angles(30.0, 0.0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    for e in SAMPLERS {
        match e.constructor.kind() {
            "envmap" => {
                let s = e.build_envmap(&sky, &AdaptiveOptions::default()).unwrap();
                let x = s.sample_uv(&mut rng);
                assert!(x.pdf > 0.0, "{}", e.name);
            }
            "grid" => {
                let g = e
                    .build_grid(2, 2, vec![1.0, 2.0, 3.0, 4.0], Rect::UNIT)
                    .unwrap();
                assert!((g.pdf([0.75, 0.75]) - 1.6).abs() < 1e-12, "{}", e.name);
            }
            "disc" => {
                let d = e.build_disc(&brdf("lambert"), &wo).unwrap();
                let x = d.sample(&mut rng);
                assert!(x.pdf > 0.0, "{}", e.name);
            }
            _ => {}
        }
    }
}

#[test]
fn unknown_and_wrong_kind_names_are_typed_errors() {
    let err = find("adaptve").unwrap_err();
    assert!(matches!(
        &err,
        RegistryError::UnknownSampler {
            suggestion: Some("adaptive"),
            ..
        }
    ));
    let msg = err.to_string();
    for e in SAMPLERS {
        assert!(msg.contains(e.name), "{msg} lacks {}", e.name);
    }
    let options = small();
    let req = DirectionRequest::new(brdf("lambert"), &options);
    let err = samplers::build_direction("envmap-cdf", &req).unwrap_err();
    assert!(
        matches!(
            err,
            RegistryError::WrongKind {
                found: "envmap",
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("cosine"), "{err}");
    let bad = SetOptions {
        slices: 0,
        ..small()
    };
    let req = DirectionRequest::new(brdf("lambert"), &bad);
    assert!(matches!(
        samplers::build_direction("adaptive", &req),
        Err(RegistryError::Set(_))
    ));
}

#[test]
fn a_saved_set_comes_back_as_the_entry_that_built_it() {
    let options = small();
    for name in ["adaptive-paper", "adaptive-mixture"] {
        let req = DirectionRequest::new(brdf("phong:n=20"), &options).with_spec("phong:n=20");
        let built = samplers::build_direction(name, &req).unwrap();
        let bytes = built.set.as_ref().unwrap().to_bytes();
        let (entry, back) = samplers::load_set(&bytes, None).unwrap();
        assert_eq!(entry.name, name);
        let wo = brdf::direction_from_angles(20.0, 0.0);
        let wi = brdf::direction_from_angles(25.0, 180.0);
        assert_eq!(back.pdf(&wo, &wi), built.pdf(&wo, &wi));
        // The stored spec must match a given one.
        assert!(matches!(
            samplers::load_set(&bytes, Some((brdf("lambert"), "lambert"))),
            Err(RegistryError::SetFile(_))
        ));
    }
    assert!(matches!(
        samplers::load_set(b"nonsense", None),
        Err(RegistryError::SetFile(_))
    ));
}

#[test]
fn not_applicable_pairs_have_one_reason_and_builds_refuse_them_with_it() {
    let options = small();
    let not_applicable = |name: &str, spec: &str| {
        let e = samplers::find(name).expect("registered");
        let b = brdf(spec);
        let na = e.applicability(b.as_ref()).expect_err(name);
        assert_eq!(na.sampler, e.name);
        let err = e
            .build_direction(&DirectionRequest::new(b, &options))
            .expect_err("the build checks applicability first");
        assert!(
            matches!(&err, RegistryError::NotApplicable(x) if *x == na),
            "{err}"
        );
        na.reason
    };
    // A format-specific sampler given another kind of BRDF.
    assert!(not_applicable("rgl-native", "phong:n=20").contains("needs an RGL material"));
    // A model-specific sampler given a model it has nothing for.
    assert!(not_applicable("analytic", "oren-nayar").contains("has no analytic sampler"));
    // Every other pair applies: every direction sampler but rgl-native to phong, every one but
    // rgl-native and analytic to oren-nayar.
    for other in SAMPLERS.iter().filter(|x| x.is_direction()) {
        let phong = other.applicability(brdf("phong:n=20").as_ref());
        assert_eq!(phong.is_ok(), other.name != "rgl-native", "{}", other.name);
        let oren = other.applicability(brdf("oren-nayar").as_ref());
        assert_eq!(
            oren.is_ok(),
            !["rgl-native", "analytic"].contains(&other.name),
            "{}",
            other.name
        );
    }
}
