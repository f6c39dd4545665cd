//! Typed errors instead of silent NaN/inf: parameter magnitudes, output
//! finiteness, the thesis inflow iteration count, and parameter-file errors
//! with their line numbers.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::model::check_output;
use helicon_model::params::descriptors;
use helicon_model::state::{State, ix};
use helicon_model::{InflowMode, Input, Model, ModelError, ParamError, Params, Preset};
use nalgebra::Vector3;
use proptest::prelude::*;

fn hover_state() -> (State, Input) {
    let mut x = State::zeros();
    x[ix::PHI] = 0.0573;
    x[ix::A0] = 0.016;
    x[ix::THETA0] = 0.1295;
    x[ix::THETA_TR] = 0.1114;
    (x, Input::new(0.185, 0.0, 0.0, 0.159))
}

#[test]
fn mass_1e308_is_rejected_where_it_enters() {
    // Today's regression: `helicon eval --params` with mass_kg = 1e308 printed
    // `null` derivatives with exit 0.
    let e = Params::from_toml_str("[body]\nmass_kg = 1e308\n", "heavy.toml").unwrap_err();
    assert_eq!(
        e.to_string(),
        "heavy.toml:2: key `body.mass_kg` = 1e308 is invalid: must be within +-1e6 \
         (mass range; beyond it the model's products overflow)"
    );
    // the tiny end of a divisor
    let e = Params::from_toml_str("[body]\nmass_kg = 1e-300\n", "h.toml").unwrap_err();
    assert!(e.to_string().contains("must be >= 1e-3 (mass range"), "{e}");
    // one key per family, beyond its range
    for (text, key) in [
        ("[main_rotor]\nradius_m = 1e5\n", "main_rotor.radius_m"),
        (
            "[main_rotor]\nomega_rad_s = 1e-9\n",
            "main_rotor.omega_rad_s",
        ),
        ("[main_rotor]\nblades = 1e9\n", "main_rotor.blades"),
        ("[main_rotor]\ntwist_rad = 7.0\n", "main_rotor.twist_rad"),
        ("[body]\nixx_kg_m2 = 1e13\n", "body.ixx_kg_m2"),
        ("[fuselage]\narea_x_m2 = 1e7\n", "fuselage.area_x_m2"),
        ("[environment]\nrho_kg_m3 = 1e5\n", "environment.rho_kg_m3"),
        ("[control]\nsample_time_s = 1e-9\n", "control.sample_time_s"),
        ("[servo.tail]\ns_max = 1e7\n", "servo.tail.s_max"),
    ] {
        let e = Params::from_toml_str(text, "h.toml").unwrap_err();
        assert!(
            matches!(&e, ParamError::Invalid { key: k, line: Some(2), .. } if k == key),
            "{e}"
        );
    }
    // in-memory parameters built past the file checks: the model still
    // evaluates, and the output check names what became non-finite
    let mut p = Params::bergen_twin();
    p.body.mass_kg = 1e308;
    assert!(p.validate("memory").is_err());
    let model = Model::new(p, Preset::Physical.options());
    let (x, u) = hover_state();
    let (xd, aux) = model.derivative(&x, &u, &Vector3::zeros()).unwrap();
    match check_output(&xd, &aux) {
        Err(ModelError::NonFiniteOutput { name, value, .. }) => {
            assert!(!value.is_finite());
            assert!(["u", "v", "w"].contains(&name), "{name}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn every_family_admits_the_bergen_twin_and_every_unit_has_a_family() {
    for d in descriptors() {
        assert!(
            helicon_model::params::magnitude(d.unit).is_some(),
            "{}.{} unit {}",
            d.section,
            d.key,
            d.unit
        );
    }
    Params::bergen_twin().validate("embedded").unwrap();
}

#[test]
fn zero_thesis_inflow_iterations_is_a_typed_error_in_the_derivative() {
    let model = Model::bergen_twin(Preset::Thesis);
    let (x, u) = hover_state();
    let mode = InflowMode::ThesisIteration {
        lambda_mr_in: -0.0415,
        lambda_tr_in: -0.0468,
        iterations: 0,
    };
    assert!(matches!(
        model.derivative_with(&x, &u, &Vector3::zeros(), mode),
        Err(ModelError::ZeroInflowIterations)
    ));
    let one = InflowMode::thesis_iteration(-0.0415, -0.0468, 1).unwrap();
    assert!(
        model
            .derivative_with(&x, &u, &Vector3::zeros(), one)
            .is_ok()
    );
}

#[test]
fn parameter_errors_carry_the_line_of_the_key() {
    let text = "# my helicopter\n\n[body]\n# heavier\nmass_kg = -1.0\n";
    let e = Params::from_toml_str(text, "heli.toml").unwrap_err();
    assert_eq!(e.line(), Some(5));
    assert_eq!(
        e.to_string(),
        "heli.toml:5: key `body.mass_kg` = -1.0 is invalid: must be > 0"
    );
    // unknown key, wrong type
    let e = Params::from_toml_str("[body]\nmass_kg = 3.0\nmas_kg = 1.0\n", "h.toml").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("h.toml:3: unknown key `body.mas_kg`"),
        "{e}"
    );
    let e = Params::from_toml_str("\n[body]\n\nmass_kg = \"heavy\"\n", "h.toml").unwrap_err();
    assert!(
        matches!(e, ParamError::WrongType { line: Some(4), .. }),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("h.toml:4: key `body.mass_kg` must be a number")
    );
    // nested section, dotted key and inline table
    let e =
        Params::from_toml_str("[servo.tail]\nzeta = 0.7\ngain_rad = 0\n", "h.toml").unwrap_err();
    assert_eq!(e.line(), Some(3), "{e}");
    let e =
        Params::from_toml_str("body.mass_kg = 2.0\nbody.ixx_kg_m2 = -3\n", "h.toml").unwrap_err();
    assert_eq!(e.line(), Some(2), "{e}");
    let e = Params::from_toml_str("x = 1\nbody = { mass_kg = 1.0 }\n", "h.toml").unwrap_err();
    assert_eq!(e.line(), Some(1), "{e}");
    let e = Params::from_toml_str("\nbody = { mass_kg = 0.0 }\n", "h.toml").unwrap_err();
    assert_eq!(e.line(), Some(2), "{e}");
    // a cross-key rule names its key and the line of the key the file set
    let e = Params::from_toml_str("[servo.collective]\n\ns_max = -0.2\n", "h.toml").unwrap_err();
    assert!(
        e.to_string().starts_with(
            "h.toml:3: key `servo.collective.s_min` = -0.1 is invalid: must be < s_max"
        ),
        "{e}"
    );
    // from a file: the path and the line
    let dir = std::env::temp_dir().join(format!("helicon-params-line-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("p.toml");
    std::fs::write(&f, "[main_rotor]\nradius_m = 1.0\nhinge_offset_m = 2.0\n").unwrap();
    let e = Params::from_file(&f).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!(
            "{}:3: key `main_rotor.hinge_offset_m`",
            f.display()
        )),
        "{e}"
    );
    // syntax errors keep the parser's line and column
    let e = Params::from_toml_str("[body\n", "h.toml").unwrap_err();
    assert!(
        matches!(e, ParamError::Syntax { .. }) && e.to_string().contains("line 1"),
        "{e}"
    );
}

/// A TOML value: extreme and ordinary numbers, or other types.
fn value_text() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| format!("{v:?}")),
        (-320i32..320, any::<bool>())
            .prop_map(|(e, neg)| format!("{}1e{e}", if neg { "-" } else { "" })),
        (-10.0f64..10.0).prop_map(|v| format!("{v:?}")),
        any::<i64>().prop_map(|v| v.to_string()),
        Just("nan".to_string()),
        Just("-inf".to_string()),
        Just("\"text\"".to_string()),
        Just("true".to_string()),
        Just("[1.0, 2.0]".to_string()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    /// Random and extreme values in a parameter file never panic: they
    /// validate or give a typed error; parameters that validate give a
    /// finite derivative (or a typed model error) at hover.
    #[test]
    fn random_parameter_files_validate_or_give_a_typed_error(
        entries in proptest::collection::vec((0usize..80, value_text()), 0..8)
    ) {
        let names: Vec<String> = descriptors()
            .map(|d| format!("{}.{}", d.section, d.key))
            .collect();
        let mut text = String::new();
        for (i, v) in &entries {
            let key = names.get(*i).map_or("body.unknown_key", String::as_str);
            text.push_str(&format!("{key} = {v}\n"));
        }
        match Params::from_toml_str(&text, "p.toml") {
            Ok(p) => {
                prop_assert!(p.validate("p.toml").is_ok());
                for preset in [Preset::Physical, Preset::Thesis] {
                    let model = Model::new(p, preset.options());
                    let (x, u) = hover_state();
                    if let Ok((xd, aux)) = model.derivative(&x, &u, &Vector3::zeros()) {
                        prop_assert!(check_output(&xd, &aux).is_ok(), "{text}");
                    }
                }
            }
            Err(e) => {
                let s = e.to_string();
                prop_assert!(s.starts_with("p.toml"), "{s}");
                if let ParamError::Invalid { line, .. }
                | ParamError::UnknownKey { line, .. }
                | ParamError::WrongType { line, .. } = &e
                {
                    prop_assert!(line.is_some(), "{s}\n{text}");
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]
    /// The family ranges keep the derivative finite: every key at once at an
    /// end of its range (or nominal), the model at hover gives finite outputs
    /// or a typed error — never NaN/inf passed on as a result.
    #[test]
    fn parameters_at_the_ends_of_their_ranges_keep_the_derivative_finite(
        picks in proptest::collection::vec(0u8..4, 77)
    ) {
        use helicon_model::params::{Rule, magnitude};
        let mut p = Params::bergen_twin();
        for (d, pick) in descriptors().zip(&picks) {
            let m = magnitude(d.unit).unwrap();
            let nominal = *(d.field)(&mut p);
            let low = match d.rule {
                Rule::Positive => m.min_positive,
                Rule::NonNegative => 0.0,
                Rule::Count => 1.0,
                Rule::Finite => -m.max_abs,
                Rule::Flag => 0.0,
            };
            *(d.field)(&mut p) = match pick {
                0 => low,
                1 => m.max_abs,
                _ => nominal,
            };
        }
        // keep the cross-key rules (e < R, Ri < Ro, S_min < S_max)
        let nominal = Params::bergen_twin();
        if p.main_rotor.hinge_offset_m >= p.main_rotor.radius_m {
            p.main_rotor.hinge_offset_m = 0.0;
        }
        if p.stabilizer_bar.inner_radius_m >= p.stabilizer_bar.outer_radius_m {
            p.stabilizer_bar.inner_radius_m = 0.0;
        }
        for (s, n) in p.servos.iter_mut().zip(&nominal.servos) {
            if s.s_min > s.s_max {
                std::mem::swap(&mut s.s_min, &mut s.s_max);
            } else if s.s_min == s.s_max {
                (s.s_min, s.s_max) = (n.s_min, n.s_max);
            }
        }
        prop_assert!(p.validate("ends").is_ok(), "{}", p.to_toml());
        {
            for preset in [Preset::Physical, Preset::Thesis] {
                let model = Model::new(p, preset.options());
                let (x, u) = hover_state();
                if let Ok((xd, aux)) = model.derivative(&x, &u, &Vector3::zeros()) {
                    let r = check_output(&xd, &aux);
                    prop_assert!(r.is_ok(), "{r:?}\n{}", p.to_toml());
                }
            }
        }
    }
}
