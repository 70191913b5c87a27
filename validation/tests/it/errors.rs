//! Bad input gives typed errors (the CLI maps them to exit code 2).

use validation::{ValidateConfig, ValidationError, run};

fn err(config: ValidateConfig) -> ValidationError {
    match run(&config, &|_| {}) {
        Err(e) => e,
        Ok(_) => panic!("expected an error"),
    }
}

fn quick() -> ValidateConfig {
    ValidateConfig {
        samplers: vec!["grid-cdf".into()],
        ..ValidateConfig::quick()
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let e = err(ValidateConfig {
        samplers: vec!["no-such-sampler".into()],
        ..quick()
    });
    assert!(matches!(
        e,
        ValidationError::Sampler(samplers::RegistryError::UnknownSampler { .. })
    ));
    assert!(
        e.to_string().contains("adaptive"),
        "lists known samplers: {e}"
    );

    let e = err(ValidateConfig {
        brdfs: vec!["phong:q=1".into()],
        ..quick()
    });
    assert!(matches!(e, ValidationError::Brdf { .. }));

    for bad in [90.0, -1.0, f64::NAN, 1e9] {
        let e = err(ValidateConfig {
            theta_o: vec![bad],
            ..quick()
        });
        assert!(matches!(e, ValidationError::BadAngle(_)), "{bad}");
    }
    let e = err(ValidateConfig {
        samples: Some(10),
        ..quick()
    });
    assert!(matches!(e, ValidationError::TooFewSamples { got: 10, .. }));
    for a in [0.0, 1.0, f64::NAN] {
        assert!(matches!(
            err(ValidateConfig {
                alpha: a,
                ..quick()
            }),
            ValidationError::BadAlpha(_)
        ));
    }
}
