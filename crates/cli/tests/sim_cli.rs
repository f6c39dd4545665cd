//! End-to-end tests of `helicon sim` and `helicon demo`: the run folder,
//! the printed outcome, a divergence (exit 0, printed clearly) and bad
//! scenarios (non-zero exit, the file and the field named, never a panic).
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use std::path::Path;
use std::process::{Command, Output};

fn helicon_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_helicon"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn no_panic(o: &Output) {
    let err = text(&o.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
}

const SHORT: &str = r#"
name = "cli-short"
duration_s = 0.5
[[reference]]
t_s = 0.1
output = "psi"
value = 0.3
[log]
decimation = 2
"#;

#[test]
fn sim_writes_the_run_folder_default_and_explicit() {
    let d = tmpdir("ok");
    std::fs::write(d.join("short.toml"), SHORT).unwrap();
    // default folder: out/<scenario name>
    let o = helicon_in(&d, &["sim", "short.toml"]);
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains("outcome: COMPLETED"), "{out}");
    assert!(out.contains("psi"), "{out}");
    assert!(out.contains("out/cli-short"), "{out}");
    let run = d.join("out").join("cli-short");
    for f in [
        "log.csv",
        "summary.json",
        "gains.json",
        "scenario.toml",
        "report.md",
        "outputs.png",
        "outputs.svg",
        "servos.png",
        "inflow.svg",
    ] {
        assert!(run.join(f).exists(), "{f} missing");
    }
    let log = std::fs::read_to_string(run.join("log.csv")).unwrap();
    // 0.5 s at 400 Hz = 201 samples, every 2nd: 101 rows + header
    assert_eq!(log.lines().count(), 102);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["outcome"], "completed");

    // --out elsewhere; the copied scenario flies again from the run folder
    let o = helicon_in(
        &d,
        &["sim", "out/cli-short/scenario.toml", "--out", "again"],
    );
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v2: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("again/summary.json")).unwrap())
            .unwrap();
    assert_eq!(v2["metrics"], v["metrics"], "same scenario, same result");
}

#[test]
fn a_divergence_is_a_result_exit_zero() {
    let d = tmpdir("diverge");
    std::fs::write(
        d.join("falls.toml"),
        "name = \"falls\"\nduration_s = 2.0\n[initial]\nvn = 6.0\n[controller]\nfeedback = false\n[plant]\nmax_attitude_rad = 0.1\n",
    )
    .unwrap();
    let o = helicon_in(&d, &["sim", "falls.toml", "--out", "r"]);
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains("DIVERGED"), "{out}");
    assert!(out.contains("attitude"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("r/summary.json")).unwrap()).unwrap();
    assert_eq!(v["outcome"], "diverged");
}

#[test]
fn bad_scenarios_name_the_file_and_the_field() {
    let d = tmpdir("bad");
    for (file, body, field) in [
        ("neg.toml", "duration_s = -1.0\n", "duration_s"),
        (
            "unknown.toml",
            "duration_s = 1.0\n[controller]\nrhoo = 3.0\n",
            "rhoo",
        ),
        (
            "ref.toml",
            "duration_s = 1.0\n[[reference]]\nt_s = 0.5\noutput = \"vx\"\nvalue = 1.0\n",
            "reference[0].output",
        ),
        (
            "dec.toml",
            "duration_s = 1.0\n[log]\ndecimation = 0\n",
            "log.decimation",
        ),
    ] {
        std::fs::write(d.join(file), body).unwrap();
        let o = helicon_in(&d, &["sim", file, "--out", "x"]);
        no_panic(&o);
        assert!(!o.status.success(), "{file} accepted");
        let err = text(&o.stderr);
        assert!(err.contains(file), "{file}: {err}");
        assert!(err.contains(field), "{file}: {err}");
    }
    let o = helicon_in(&d, &["sim", "missing.toml"]);
    no_panic(&o);
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("missing.toml"));
    // a gains file that does not exist is bad input too
    std::fs::write(
        d.join("gains.toml"),
        "duration_s = 1.0\n[controller]\ngains_file = \"nope.json\"\n",
    )
    .unwrap();
    let o = helicon_in(&d, &["sim", "gains.toml", "--out", "x"]);
    no_panic(&o);
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("nope.json"), "{}", text(&o.stderr));
}

#[test]
fn demo_flies_closed_loop_and_writes_plots() {
    let d = tmpdir("demo");
    let o = helicon_in(&d, &["demo", "--duration", "3", "--out", "demo"]);
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    for s in [
        "hover trim",
        "unstable open-loop poles",
        "closed-loop flight",
        "outcome: COMPLETED",
        "vn = 2 m/s at 1 s",
        "report:",
    ] {
        assert!(out.contains(s), "`{s}` not in {out}");
    }
    for f in [
        "log.csv",
        "summary.json",
        "outputs.png",
        "wind.png",
        "report.md",
    ] {
        assert!(d.join("demo").join(f).exists(), "{f}");
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("demo/summary.json")).unwrap())
            .unwrap();
    assert_eq!(v["scenario"], "demo");
    assert_eq!(v["preset"], "physical");
    // the 2 m/s north step at 1 s is being tracked after 2 s
    let vn_max = v["metrics"]["vn"]["max_abs_error"].as_f64().unwrap();
    assert!(vn_max <= 2.1, "{vn_max}");
    assert!(v["metrics"]["vn"]["rms_error"].as_f64().unwrap() < 1.2);
}

#[test]
fn a_scenario_with_cases_flies_each_into_its_folder() {
    let d = tmpdir("cases");
    std::fs::write(
        d.join("two.toml"),
        "name = \"two\"\nduration_s = 0.3\n[[case]]\nname = \"yaw\"\ninitial = { psi = 0.2 }\n\
         [[case]]\nname = \"north\"\ninitial = { vn = 0.5 }\n",
    )
    .unwrap();
    let o = helicon_in(&d, &["sim", "two.toml"]);
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("2 cases flown, 2 completed, 0 diverged"),
        "{out}"
    );
    let run = d.join("out/two");
    for case in ["yaw", "north"] {
        for f in [
            "log.csv",
            "summary.json",
            "gains.json",
            "report.md",
            "outputs.png",
        ] {
            assert!(run.join(case).join(f).exists(), "{case}/{f}");
        }
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(run.join(case).join("summary.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(s["scenario"], format!("two-{case}"));
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["scenario"], "two");
    assert_eq!(v["cases"]["yaw"]["outcome"], "completed");
    assert_eq!(v["cases"]["north"]["outcome"], "completed");
    // each case flew its own initial condition
    assert_eq!(
        v["cases"]["yaw"]["metrics"]["psi"]["max_abs_error"]
            .as_f64()
            .unwrap(),
        0.2
    );
    // (the NED velocity goes through a body rotation and back: within an ulp)
    let vn = v["cases"]["north"]["metrics"]["vn"]["max_abs_error"]
        .as_f64()
        .unwrap();
    assert!((vn - 0.5).abs() < 1e-12, "{vn}");
    let report = std::fs::read_to_string(run.join("report.md")).unwrap();
    assert!(
        report.contains("[yaw/report.md](yaw/report.md)"),
        "{report}"
    );
}

#[test]
fn sim_with_log_sensors_writes_the_sensor_log_that_fuse_replays() {
    let d = tmpdir("sim_sensors");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let demo = std::fs::read_to_string(root.join("scenarios/demo.toml")).unwrap();
    assert!(demo.contains("[log]\n"), "demo.toml has a [log] section");
    let scenario = d.join("sensed.toml");
    std::fs::write(
        &scenario,
        demo.replace("[log]\n", "[log]\nsensors = true\n"),
    )
    .unwrap();
    let out = d.join("run");
    let o = helicon_in(
        &d,
        &[
            "sim",
            scenario.to_str().unwrap(),
            "--duration",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let log = out.join("sensors.csv");
    let body = std::fs::read_to_string(&log).unwrap();
    assert!(
        body.starts_with("# helicon sensor log v2"),
        "{}",
        &body[..80]
    );
    // one frame per controller sample: 2 s at 400 Hz, both ends
    let rows = body.lines().filter(|l| !l.starts_with('#')).count() - 1;
    assert_eq!(rows, 801, "data rows");
    let fused = d.join("fused");
    let o = helicon_in(
        &d,
        &[
            "fuse",
            log.to_str().unwrap(),
            "--out",
            fused.to_str().unwrap(),
        ],
    );
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // without the key, no sensor log
    let plain = d.join("plain");
    let o = helicon_in(
        &d,
        &[
            "sim",
            root.join("scenarios/demo.toml").to_str().unwrap(),
            "--duration",
            "1",
            "--out",
            plain.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!plain.join("sensors.csv").exists());
}
