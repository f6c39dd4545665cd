//! `helicon sensors shaker` (thesis Appendix A) and the sensor model with
//! vibration off: bit for bit what it was before the vibration chain.
#![allow(clippy::unwrap_used, clippy::panic)] // tests: a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use std::path::Path;
use std::process::{Command, Output};

fn helicon(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(args)
        .output()
        .unwrap()
}

fn no_panic(o: &Output) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
}

/// `helicon sensors simulate` without `[imu.vibration]` writes the log it
/// wrote before the vibration chain existed
/// (`tests/fixtures/scripted_sensors_no_vibration.csv`, recorded then).
#[test]
fn sensors_simulate_without_vibration_is_unchanged() {
    let o = helicon(&["sensors", "simulate", "--duration-s", "1", "--seed", "3"]);
    no_panic(&o);
    assert!(o.status.success());
    let out = String::from_utf8(o.stdout).unwrap();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/scripted_sensors_no_vibration.csv");
    let recorded = std::fs::read_to_string(fixture).unwrap();
    assert_eq!(out.lines().count(), recorded.lines().count());
    for (k, (a, b)) in out.lines().zip(recorded.lines()).enumerate() {
        assert_eq!(a, b, "line {} differs", k + 1);
    }
}

/// The shaker on the thesis's ±2 g part above the filter's cut-off: the
/// mean moves to the closed form, the output stays inside the range, the
/// summary says the saturation is hidden; the map holds the sweep.
#[test]
fn shaker_writes_the_hidden_saturation_case_and_map() {
    let d = tmpdir("shaker");
    let o = helicon(&[
        "sensors",
        "shaker",
        "--freq-hz",
        "287.3",
        "--amplitude-g",
        "2",
        "--ideal",
        "--sweep-freq-hz",
        "20,300",
        "--out",
        d.to_str().unwrap(),
    ]);
    no_panic(&o);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("HIDDEN saturation"));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap();
    let num = |k: &str| s[k].as_f64().unwrap();
    assert!(
        (num("mean_g") - num("closed_form_mean_g")).abs() < 1e-4,
        "{s}"
    );
    assert!(num("shift_g") > 0.2 && num("output_min_g") > -1.0, "{s}");
    assert_eq!(s["clipping_visible"], false);
    for f in [
        "shaker.csv",
        "shaker.png",
        "shaker.svg",
        "map.csv",
        "map.png",
        "map.svg",
    ] {
        assert!(d.join(f).is_file(), "{f} missing");
    }
    let map = std::fs::read_to_string(d.join("map.csv")).unwrap();
    assert_eq!(map.lines().count(), 1 + 2 * 17);
    // at 300 Hz and 3 g the saturation is hidden, at 0.5 g there is none
    let row = |f: &str, a: &str| {
        map.lines()
            .find(|l| l.starts_with(&format!("{f},{a},")))
            .unwrap()
            .to_string()
    };
    assert!(row("300", "3").ends_with(",1"));
    assert!(row("300", "0.5").ends_with(",0"));
}

#[test]
fn shaker_bad_arguments_are_errors() {
    let d = tmpdir("shaker_bad");
    let out = d.to_str().unwrap();
    for (args, needle) in [
        (vec!["--freq-hz", "0", "--amplitude-g", "1"], "freq_hz"),
        (vec!["--freq-hz", "NaN", "--amplitude-g", "1"], "freq_hz"),
        (vec!["--freq-hz", "1e9", "--amplitude-g", "1"], "freq_hz"),
        (vec!["--freq-hz", "100", "--amplitude-g", "-1"], "amplitude"),
        (
            vec!["--freq-hz", "100", "--amplitude-g", "inf"],
            "amplitude",
        ),
        (
            vec!["--freq-hz", "100", "--amplitude-g", "1", "--range-g", "0"],
            "range-g",
        ),
        (
            vec![
                "--freq-hz",
                "100",
                "--amplitude-g",
                "1",
                "--duration-s",
                "0.4",
            ],
            "settle_s",
        ),
        (
            vec![
                "--freq-hz",
                "100",
                "--amplitude-g",
                "1",
                "--sweep-freq-hz=-5",
            ],
            "freq_hz",
        ),
        (
            vec![
                "--freq-hz",
                "100",
                "--amplitude-g",
                "1",
                "--sweep-max-g",
                "NaN",
            ],
            "amplitude",
        ),
    ] {
        let mut a = vec!["sensors", "shaker", "--out", out];
        a.extend(args.iter());
        let o = helicon(&a);
        no_panic(&o);
        assert!(!o.status.success(), "{args:?} accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    // a sensor file with a bad stage names the file and field
    let cfg = d.join("s.toml");
    std::fs::write(&cfg, "[imu.accel_stage]\nfilter_cutoff_hz = 5000.0\n").unwrap();
    let o = helicon(&[
        "sensors",
        "shaker",
        "--freq-hz",
        "100",
        "--amplitude-g",
        "1",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out,
    ]);
    no_panic(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("imu.accel_stage.filter_cutoff_hz"),
        "{err}"
    );
}
