//! A run folder is not silently overwritten by a run of other inputs, and
//! the report says which parameter file (and yaw gyro) was flown; the demo
//! names the parameter file it flies.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};
use std::path::Path;

fn root() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn a_run_of_other_inputs_is_refused_without_force() {
    let d = tmpdir("refuse");
    let scenario = root().join("scenarios/demo.toml");
    let gyro = root().join("params/yaw-gyro.toml");
    let out = d.join("run");
    let (s, o) = (scenario.to_str().unwrap(), out.to_str().unwrap());
    let (ok, _, e) = helicon(&["sim", s, "--duration", "1", "--out", o]);
    assert!(ok, "{e}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("- parameters: the Bergen Industrial Twin (embedded); stock yaw gyro off"),
        "{report}"
    );
    // the same inputs again: fine
    let (ok, _, e) = helicon(&["sim", s, "--duration", "1", "--out", o]);
    assert!(ok, "{e}");
    // other parameters into the same folder: refused, the folder untouched
    let g = gyro.to_str().unwrap();
    let (ok, _, e) = helicon(&["sim", s, "--duration", "1", "--params", g, "--out", o]);
    assert!(!ok);
    assert!(
        e.contains("holds a run of other inputs") && e.contains("--force"),
        "{e}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("report.md")).unwrap(),
        report
    );
    // --force replaces it, and the report names the file and the gyro
    let (ok, _, e) = helicon(&[
        "sim",
        s,
        "--duration",
        "1",
        "--params",
        g,
        "--out",
        o,
        "--force",
    ]);
    assert!(ok, "{e}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("yaw-gyro.toml` over the Bergen Twin; stock yaw gyro on"),
        "{report}"
    );
    // and every figure's title names the parameter file
    for fig in ["outputs", "servos", "estimator", "inflow"] {
        let svg = std::fs::read_to_string(out.join(format!("{fig}.svg"))).unwrap();
        assert!(svg.contains("demo [yaw-gyro.toml]: "), "{fig}.svg");
    }
}

#[test]
fn the_demo_names_the_parameter_file() {
    let d = tmpdir("demo");
    let (ok, p, e) = helicon(&["params"]);
    assert!(ok, "{e}");
    let file = d.join("small.toml");
    std::fs::write(&file, p).unwrap();
    let out = d.join("demo");
    let (ok, so, e) = helicon(&[
        "demo",
        "--params",
        file.to_str().unwrap(),
        "--duration",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{e}");
    let first = so.lines().next().unwrap();
    assert!(!first.contains("Bergen Industrial Twin"), "{first}");
    assert!(first.contains("small.toml"), "{first}");
}
