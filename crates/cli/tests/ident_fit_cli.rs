//! Runs `helicon ident demo` (short: the hover flight alone, no verification
//! flight) and `helicon ident fit` on its IDENT.toml as a user
//! would: the outputs exist, report.json has the documented fields, the
//! identified file loads as `--params`; bad inputs are refused naming the
//! file and field.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};

#[test]
fn demo_then_fit_write_the_documented_outputs() {
    let d = tmpdir("demo");
    let out = d.join("demo");
    let (ok, stdout, stderr) = helicon(&[
        "ident",
        "demo",
        "--flights",
        "hover",
        "--no-verify",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    for f in [
        "IDENT.toml",
        "start.toml",
        "identified.toml",
        "report.json",
        "report.md",
        "flights/hover/log.csv",
        "bode_hover_meas_p_S_lat.png",
        "ground/rotor-drag.csv",
        "ground/main-lift-slope.csv",
        "ground/tail-lift-slope.csv",
        "ground/blade-spring.csv",
    ] {
        assert!(out.join(f).exists(), "{f} missing:\n{stdout}");
    }
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let params = r["parameters"].as_array().unwrap();
    // the demo's ten, less the tail lift slope kept at its ground value
    // (in the report's `ground` section)
    assert_eq!(params.len(), 9);
    assert!(
        r["ground"]
            .as_array()
            .unwrap()
            .iter()
            .any(|g| g["key"] == "tail_rotor.lift_slope_per_rad")
    );
    for p in params {
        for k in [
            "key",
            "start",
            "identified",
            "change_pct",
            "cramer_rao_pct",
            "insensitivity_pct",
            "identifiable",
            "reason",
        ] {
            assert!(p.get(k).is_some(), "{k} missing in {p}");
        }
    }
    let lift = params
        .iter()
        .find(|p| p["key"] == "main_rotor.lift_slope_per_rad")
        .unwrap();
    assert!(lift["identifiable"].as_bool().unwrap(), "{lift}");
    // truth-a: 5.4; the hover flight alone gets within 10 %
    let v = lift["identified"].as_f64().unwrap();
    assert!((v - 5.4).abs() < 0.54, "{v}");
    // the start holds the ground-measured values, already near the data's
    // noise floor: the cost falls, not by orders of magnitude
    let (c0, c1) = (
        r["cost_start"].as_f64().unwrap(),
        r["cost_identified"].as_f64().unwrap(),
    );
    println!("cost {c0} -> {c1}");
    assert!(c1 < c0, "cost {c0} -> {c1}");
    let costs = r["costs"].as_array().unwrap();
    // the four cyclic responses, meas_r/S_tr and w/S_col (issue 15); the
    // hover heave keeps about 9 coherent points of the 40 (with 20 points it
    // keeps 2, fewer than min_points, and is left out with a note)
    assert_eq!(costs.len(), 6, "{stdout}");
    assert!(
        costs
            .iter()
            .all(|c| c["operating_point"] == "hover" && c["start"].as_f64().is_some())
    );
    // the ground section: each measured value, in start.toml, within 5
    // standard errors of truth-a's value (Cd 0.0096, main lift slope 5.4,
    // spring 240; the tail lift slope is the Bergen Twin's 6.0)
    let ground = r["ground"].as_array().unwrap();
    assert_eq!(ground.len(), 4, "{ground:?}");
    let start = helicon_model::Params::from_file(&out.join("start.toml")).unwrap();
    for g in ground {
        let (key, v, se) = (
            g["key"].as_str().unwrap(),
            g["value"].as_f64().unwrap(),
            g["std_error"].as_f64().unwrap(),
        );
        assert!(g["kind"].is_string() && out.join(g["file"].as_str().unwrap()).exists());
        let want = match key {
            "main_rotor.drag_coefficient" => 0.0096,
            "main_rotor.lift_slope_per_rad" => 5.4,
            "tail_rotor.lift_slope_per_rad" => 6.0,
            "main_rotor.spring_n_m_per_rad" => 240.0,
            k => panic!("unexpected ground key {k}"),
        };
        assert!(se > 0.0 && (v - want).abs() < 5.0 * se, "{key}: {v} ± {se}");
        let d = helicon_paramid::keys::find(key).unwrap();
        assert_eq!(
            helicon_paramid::keys::get(&start, d),
            v,
            "{key} in start.toml"
        );
    }
    let tm = &r["truth_model_cost"];
    assert!(
        tm["identified"].as_f64().unwrap() < tm["start"].as_f64().unwrap(),
        "{tm}"
    );
    assert!(stdout.contains("ground measurements") && stdout.contains("truth's own model"));
    // the identified file is a parameter file: `helicon trim --params` takes it
    let (ok, stdout, stderr) = helicon(&[
        "trim",
        "--params",
        out.join("identified.toml").to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    // the same IDENT.toml through `ident fit` gives the same identified values
    let out2 = d.join("fit");
    let (ok, stdout, stderr) = helicon(&[
        "ident",
        "fit",
        out.join("IDENT.toml").to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let r2: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out2.join("report.json")).unwrap()).unwrap();
    for (a, b) in params.iter().zip(r2["parameters"].as_array().unwrap()) {
        assert_eq!(a["identified"], b["identified"]);
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_inputs_name_the_file_and_field() {
    let d = tmpdir("bad");
    let ident = d.join("IDENT.toml");
    std::fs::write(
        &ident,
        "[[operating_point]]\nname = \"hover\"\nlog = \"missing.csv\"\n[[response]]\ninput = \"S_lon\"\noutput = \"q\"\nomega_min_rad_s = 1.0\nomega_max_rad_s = 20.0\n[[parameter]]\nkey = \"body.iyy_kg_m2\"\nmin = 0.3\nmax = 0.5\n",
    )
    .unwrap();
    let (ok, _, stderr) = helicon(&[
        "ident",
        "fit",
        ident.to_str().unwrap(),
        "--out",
        d.join("o").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("IDENT.toml") && stderr.contains("parameter[0].min"),
        "{stderr}"
    );
    let (ok, _, stderr) = helicon(&[
        "ident",
        "demo",
        "--flights",
        "cruise",
        "--out",
        d.join("o").to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("--flights"), "{stderr}");
    let truth = d.join("truth.toml");
    std::fs::write(&truth, "[body]\nixx_kg_m2 = -1.0\n").unwrap();
    let (ok, _, stderr) = helicon(&[
        "ident",
        "demo",
        "--truth",
        truth.to_str().unwrap(),
        "--out",
        d.join("o").to_str().unwrap(),
    ]);
    assert!(
        !ok && stderr.contains("truth.toml") && stderr.contains("body.ixx_kg_m2"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
