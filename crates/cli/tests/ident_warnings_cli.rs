//! Identification that would give a wrong answer says so: `ident frf` on a
//! closed-loop flight without excitation warns that it measures the
//! controller, and is quiet on a flight with a sweep on the input; `ident
//! tf` marks the parameters its data cannot determine as not identifiable
//! (JSON `null` bounds and `"identifiable": false`, never a 0 % bound).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};
use std::path::Path;

fn root() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn frf_warns_on_closed_loop_data_without_excitation() {
    let d = tmpdir("noexc");
    let out = d.join("demo");
    let (ok, _, e) = helicon(&["demo", "--out", out.to_str().unwrap()]);
    assert!(ok, "{e}");
    let log = out.join("log.csv");
    let frf = d.join("frf");
    let (ok, so, se) = helicon(&[
        "ident",
        "frf",
        log.to_str().unwrap(),
        "--input",
        "S_lon",
        "--output",
        "q",
        "--out",
        frf.to_str().unwrap(),
    ]);
    assert!(ok, "{se}");
    assert!(
        se.contains("warning: `S_lon`: the logged excitation is zero throughout"),
        "{se}"
    );
    assert!(so.contains("excitation: `exc_lon` RMS 0.000e0"), "{so}");
    // the response is still written (a warning, not a refusal)
    assert!(frf.join("frf.csv").exists());
}

#[test]
fn frf_on_a_swept_input_is_quiet_and_tf_marks_what_it_cannot_determine() {
    let d = tmpdir("sweep");
    let run = d.join("run");
    let scenario = root().join("scenarios/ident-hover-sweep.toml");
    // the first 30 s hold the S_lon sweep (1 … 28 s)
    let (ok, _, e) = helicon(&[
        "sim",
        scenario.to_str().unwrap(),
        "--duration",
        "30",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(ok, "{e}");
    let frf = d.join("frf");
    let (ok, so, se) = helicon(&[
        "ident",
        "frf",
        run.join("log.csv").to_str().unwrap(),
        "--input",
        "S_lon",
        "--output",
        "q",
        "--omega-min",
        "1.5",
        "--omega-max",
        "25",
        "--points",
        "60",
        "--out",
        frf.to_str().unwrap(),
    ]);
    assert!(ok, "{se}");
    assert!(!se.contains("warning"), "{se}");
    assert!(so.contains("coherent with it"), "{so}");
    let csv = frf.join("frf.csv");
    let tf = |num: &str, dir: &str| {
        let out = d.join(dir);
        let (ok, so, se) = helicon(&[
            "ident",
            "tf",
            csv.to_str().unwrap(),
            "--output",
            "q",
            "--num",
            num,
            "--den",
            "2",
            "--delay",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{se}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("tf_q.json")).unwrap()).unwrap();
        (so, se, v)
    };
    // a numerator zero and a delay trade against each other on these data
    let (so, se, v) = tf("1", "tf1");
    assert!(so.contains("NOT IDENTIFIABLE"), "{so}");
    assert!(se.contains("not identifiable"), "{se}");
    let params = v["parameters"].as_array().unwrap();
    let b1 = params.iter().find(|p| p["name"] == "b1").unwrap();
    assert_eq!(b1["identifiable"], false, "{b1}");
    for p in params {
        // a bound is a positive number or null, never 0
        let cr = &p["cramer_rao_pct"];
        assert!(
            cr.is_null() || cr.as_f64().unwrap() > 0.0,
            "{}: {cr}",
            p["name"]
        );
        if p["identifiable"] == false {
            assert!(
                cr.is_null() || cr.as_f64().unwrap() >= 100.0,
                "{}: {cr}",
                p["name"]
            );
        }
    }
    // without the zero every parameter is determined
    let (so, se, v) = tf("0", "tf0");
    assert!(
        !so.contains("NOT IDENTIFIABLE") && !se.contains("warning"),
        "{so}{se}"
    );
    for p in v["parameters"].as_array().unwrap() {
        assert_eq!(p["identifiable"], true, "{p}");
        assert!(p["cramer_rao_pct"].as_f64().unwrap() > 0.0, "{p}");
    }
}
