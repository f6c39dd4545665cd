//! Runs `helicon ident servo-bench`, `helicon ident servo` and `helicon
//! ident ground` as a user would: a simulated bench test of the Bergen
//! Twin's collective servo identified back (servo.json with the estimates,
//! their standard errors and the parameter keys), a log that never reaches
//! the rate limit reported as such, every ground experiment's template run,
//! and hostile logs and readings refused with the file, line and column.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};

fn json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn bench_test_identified_back_within_its_standard_errors() {
    let d = tmpdir("bench");
    let csv = d.join("bench.csv");
    let (ok, _, err) = helicon(&[
        "ident",
        "servo-bench",
        "--seed",
        "3",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let out = d.join("out");
    let (ok, stdout, err) = helicon(&[
        "ident",
        "servo",
        csv.to_str().unwrap(),
        "--command",
        "command",
        "--position",
        "position_rad",
        "--s-min",
        "-0.1",
        "--s-max",
        "0.3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("rate limit ="), "{stdout}");
    let j = json(&out.join("servo.json"));
    for (k, truth) in [("gain_rad", 0.7), ("omega_n_rad_s", 100.0), ("zeta", 0.85)] {
        let (v, se) = (
            j[k]["value"].as_f64().unwrap(),
            j[k]["std_error"].as_f64().unwrap(),
        );
        assert!((v - truth).abs() < 3.0 * se, "{k}: {v} ± {se}");
        assert!(se < 0.01 * truth, "{k}: se {se}");
        assert_eq!(
            j["params_keys"][k].as_str().unwrap(),
            format!("servo.collective.{k}")
        );
    }
    assert_eq!(j["rate_limit"]["status"], "identified");
    let rl = &j["rate_limit"]["rate_max_rad_s"];
    assert!((rl["value"].as_f64().unwrap() - 5.0).abs() < 3.0 * rl["std_error"].as_f64().unwrap());
    // the residual is the bench's 2 mrad noise
    let rms = j["residual_rms_rad"].as_f64().unwrap();
    assert!((rms - 0.002).abs() < 2e-4, "{rms}");
    assert!(j["frequency_check"]["points"].as_u64().unwrap() > 10);
    // the snippet is a parameter file `helicon params` loads
    let snippet = d.join("servo.toml");
    std::fs::write(&snippet, j["params_toml"].as_str().unwrap()).unwrap();
    let (ok, params, err) = helicon(&["params", "--params", snippet.to_str().unwrap()]);
    assert!(ok, "{err}");
    let want = format!("zeta = {}", j["zeta"]["value"].as_f64().unwrap());
    assert!(params.contains(&want), "{params}");
    assert!(out.join("servo.png").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_log_without_the_rate_limit_says_so() {
    let d = tmpdir("nolimit");
    let csv = d.join("bench.csv");
    // steps only, then keep the first 0.1–0.25 steps (before the half-range ones)
    let (ok, _, err) = helicon(&[
        "ident",
        "servo-bench",
        "--no-sweep",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    // 9 levels of 0.3 s at 400 Hz: the middle and the 0.1 and 0.25 steps
    let cut: String = text
        .lines()
        .take(2 + 9 * 120)
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&csv, cut).unwrap();
    let out = d.join("out");
    let (ok, stdout, err) = helicon(&[
        "ident",
        "servo",
        csv.to_str().unwrap(),
        "--command",
        "command",
        "--position",
        "position_rad",
        "--channel",
        "tail",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("not reached"), "{stdout}");
    let j = json(&out.join("servo.json"));
    assert_eq!(j["rate_limit"]["status"], "not_reached");
    let lb = j["rate_limit"]["lower_bound_rad_s"].as_f64().unwrap();
    assert!(lb > 0.5 && lb < 5.0, "{lb}");
    assert_eq!(j["params_keys"]["zeta"], "servo.tail.zeta");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn hostile_servo_logs_are_refused() {
    let d = tmpdir("hostile");
    let write = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let servo = |log: &str, extra: &[&str]| {
        let out = d.join("o");
        let mut a = vec![
            "ident",
            "servo",
            log,
            "--command",
            "c",
            "--position",
            "p",
            "--out",
            out.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        helicon(&a)
    };
    let mut rows = String::from("t_s,c,p\n");
    for k in 0..100 {
        rows.push_str(&format!("{},{},{}\n", k as f64 * 0.01, (k / 20) % 2, 0.0));
    }
    let nan = write("nan.csv", &rows.replace("0.3,1,0", "0.3,1,NaN"));
    let (ok, _, err) = servo(&nan, &[]);
    assert!(
        !ok && err.contains("nan.csv") && err.contains("`p`"),
        "{err}"
    );
    let empty = write("empty.csv", "");
    let (ok, _, err) = servo(&empty, &[]);
    assert!(!ok && err.contains("empty.csv"), "{err}");
    let short = write("short.csv", "t_s,c,p\n0,0,0\n0.01,1,0\n");
    let (ok, _, err) = servo(&short, &[]);
    assert!(!ok && err.contains("short.csv"), "{err}");
    let back = write("back.csv", &rows.replace("0.3,1,0", "0.2,1,0"));
    let (ok, _, err) = servo(&back, &[]);
    assert!(!ok && err.contains("does not increase"), "{err}");
    let nocol = write("nocol.csv", &rows.replace("t_s,c,p", "t_s,c,q"));
    let (ok, _, err) = servo(&nocol, &[]);
    assert!(!ok && err.contains("no column `p`"), "{err}");
    let flat = write("flat.csv", &rows.replace(",1,", ",0,"));
    let (ok, _, err) = servo(&flat, &[]);
    assert!(!ok && err.contains("constant"), "{err}");
    let good = write("good.csv", &rows);
    let (ok, _, err) = servo(&good, &["--channel", "rotor"]);
    assert!(!ok && err.contains("--channel rotor"), "{err}");
    let (ok, _, err) = servo(&good, &["--s-min", "1", "--s-max", "0"]);
    assert!(!ok && err.contains("s_min"), "{err}");
    let (ok, _, err) = servo(&good, &["--substeps", "0"]);
    assert!(!ok && err.contains("substeps"), "{err}");
    let (ok, _, err) = helicon(&[
        "ident",
        "servo-bench",
        "--noise-rad",
        "nan",
        "--out",
        "x.csv",
    ]);
    assert!(!ok && err.contains("--noise-rad"), "{err}");
    let (ok, _, err) = helicon(&["ident", "servo-bench", "--hold-s", "-1", "--out", "x.csv"]);
    assert!(!ok && err.contains("hold_s"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ground_templates_run_and_hostile_readings_name_line_and_column() {
    let d = tmpdir("ground");
    let out = d.join("out");
    for kind in [
        "rotor-drag",
        "main-lift-slope",
        "tail-lift-slope",
        "blade-spring",
        "bell-gain",
        "hiller-gain",
        "tail-fin-loss",
        "stabilizer-lift-slope",
    ] {
        let (ok, template, err) = helicon(&["ident", "ground", kind, "--template"]);
        assert!(ok, "{err}");
        let p = d.join(format!("{kind}.csv"));
        std::fs::write(&p, &template).unwrap();
        let (ok, stdout, err) = helicon(&[
            "ident",
            "ground",
            kind,
            p.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{kind}: {err}");
        let stem = format!("ground_{}", kind.replace('-', "_"));
        let j = json(&out.join(format!("{stem}.json")));
        let (v, se) = (
            j["value"].as_f64().unwrap(),
            j["std_error"].as_f64().unwrap(),
        );
        // the templates are Bergen Twin readings: its value within 5 %
        let truth = match kind {
            "rotor-drag" => 0.008,
            "main-lift-slope" | "tail-lift-slope" => 6.0,
            "stabilizer-lift-slope" => 2.6,
            "blade-spring" => 200.0,
            "bell-gain" => 0.2,
            "hiller-gain" => 0.8,
            _ => 0.2,
        };
        assert!((v - truth).abs() < 0.05 * truth, "{kind}: {v} ± {se}");
        assert!(se.is_finite() && se >= 0.0);
        let key = j["key"].as_str().unwrap();
        assert!(stdout.contains(key), "{stdout}");
        let (sec, name) = key.split_once('.').unwrap();
        assert!(
            j["params_toml"]
                .as_str()
                .unwrap()
                .starts_with(&format!("[{sec}]\n{name} = "))
        );
        assert!(out.join(format!("{stem}.png")).exists());
        let snippet = d.join(format!("{stem}.toml"));
        std::fs::write(&snippet, j["params_toml"].as_str().unwrap()).unwrap();
        let (ok, params, err) = helicon(&["params", "--params", snippet.to_str().unwrap()]);
        assert!(ok, "{kind}: {err}");
        assert!(
            params.contains(&format!("{name} = {v}"))
                || params.contains(&format!("{name} = {v:?}")),
            "{kind}: {params}"
        );
    }
    let bad = d.join("bad.csv");
    std::fs::write(
        &bad,
        "# thrust test\npitch_rad,thrust_n\n-0.1,-98\n0.1,-90\n",
    )
    .unwrap();
    let (ok, _, err) = helicon(&[
        "ident",
        "ground",
        "main-lift-slope",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("bad.csv: line 4") && err.contains("`thrust_n` = -90"),
        "{err}"
    );
    std::fs::write(&bad, "pitch_rad,thrust_n\n-0.1,-98\n-0.2,oops\n").unwrap();
    let (ok, _, err) = helicon(&[
        "ident",
        "ground",
        "main-lift-slope",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("line 3, column `thrust_n`"), "{err}");
    let (ok, _, err) = helicon(&["ident", "ground", "rotor-speed", "--template"]);
    assert!(!ok && err.contains("unknown ground experiment"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}
