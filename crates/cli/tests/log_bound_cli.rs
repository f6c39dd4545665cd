//! `helicon sim` bounds its `log.csv`: the size is estimated before the
//! flight; above `--max-log-bytes` the log is thinned to fit (said on
//! stderr, the summary unchanged) or the flight is refused
//! (`--no-log-decimation`, or a `--log-rate` that does not fit), naming
//! how to get what the user wants. `--log-rate` thins on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use std::path::{Path, PathBuf};

fn demo() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/demo.toml")
        .display()
        .to_string()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

fn out(d: &Path, name: &str) -> PathBuf {
    d.join(name)
}

/// The demo flown for a day would write about 13 GB at its log rate
/// (100 Hz): refused before flying with --no-log-decimation, the message
/// naming the estimate, the limit and the way out; nothing is flown.
#[test]
fn a_day_of_the_demo_is_refused_without_decimation() {
    let d = common::tmpdir("day_refused");
    let o = out(&d, "day");
    let t0 = std::time::Instant::now();
    let (ok, _, err) = common::helicon(&[
        "sim",
        &demo(),
        "--duration",
        "86400",
        "--no-log-decimation",
        "--out",
        o.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("--max-log-bytes 1000000000"), "{err}");
    assert!(err.contains("--log-rate HZ"), "{err}");
    assert!(err.contains("8640001 rows at 100 Hz"), "{err}");
    let gb: f64 = err
        .split("about ")
        .nth(1)
        .and_then(|s| s.split(" GB").next())
        .unwrap()
        .parse()
        .unwrap();
    eprintln!(
        "a day of the demo at 100 Hz: about {gb} GB; refused in {:?}",
        t0.elapsed()
    );
    assert!((12.0..15.0).contains(&gb), "{gb}");
    assert!(!o.join("log.csv").exists());
    // a --log-rate that does not fit is refused too (the user's rate is not overridden)
    let (ok, _, err) = common::helicon(&[
        "sim",
        &demo(),
        "--duration",
        "86400",
        "--log-rate",
        "50",
        "--out",
        o.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("Hz fits"), "{err}");
}

/// Over a small limit the log is thinned to fit, with a warning; the
/// summary is the full-rate flight's; `--log-rate` gives the rows asked.
#[test]
fn over_the_limit_the_log_is_thinned_and_the_summary_kept() {
    let d = common::tmpdir("thinned");
    let full = out(&d, "full");
    let thin = out(&d, "thin");
    let rate = out(&d, "rate");
    let (ok, _, err) = common::helicon(&[
        "sim",
        &demo(),
        "--duration",
        "30",
        "--out",
        full.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(!err.contains("warning"), "{err}");
    let full_bytes = std::fs::metadata(full.join("log.csv")).unwrap().len();
    let limit = 400_000u64;
    assert!(full_bytes > 4 * limit);
    let (ok, _, err) = common::helicon(&[
        "sim",
        &demo(),
        "--duration",
        "30",
        "--max-log-bytes",
        &limit.to_string(),
        "--out",
        thin.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("warning: log.csv of this flight would be about"),
        "{err}"
    );
    assert!(
        err.contains("--log-rate HZ") && err.contains("--max-log-bytes"),
        "{err}"
    );
    let thin_bytes = std::fs::metadata(thin.join("log.csv")).unwrap().len();
    eprintln!("full {full_bytes} bytes, thinned to {thin_bytes} (limit {limit})");
    assert!(
        thin_bytes <= limit && thin_bytes > limit / 2,
        "{thin_bytes}"
    );
    let (a, b) = (summary(&full), summary(&thin));
    assert_eq!(a, b, "the summary uses every sample either way");
    // the log still spans the flight, first and last sample
    let t = helicon_sim::log_csv::read_log_csv(&thin.join("log.csv")).unwrap();
    assert_eq!(t.time_s()[0], 0.0);
    assert!((t.time_s().last().unwrap() - 30.0).abs() < 1e-9);

    let (ok, _, err) = common::helicon(&[
        "sim",
        &demo(),
        "--duration",
        "30",
        "--log-rate",
        "10",
        "--out",
        rate.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let t = helicon_sim::log_csv::read_log_csv(&rate.join("log.csv")).unwrap();
    assert_eq!(t.rows(), 301);
    assert!((t.time_s()[1] - 0.1).abs() < 1e-9);
    assert_eq!(summary(&rate), a);
    for bad in ["0", "-1", "nan", "101"] {
        let (ok, _, err) = common::helicon(&[
            "sim",
            &demo(),
            "--duration",
            "1",
            "--log-rate",
            bad,
            "--out",
            rate.to_str().unwrap(),
            "--force",
        ]);
        assert!(!ok && err.contains("--log-rate"), "{bad}: {err}");
    }
}

/// `helicon sitl`: the on-board log's size estimated before flying against
/// the `flight.ulg` written (within 3 %); an on-board log over the limit
/// is refused (it is never thinned); `--log-rate` thins `log.csv`.
#[test]
fn sitl_estimates_its_onboard_log_and_thins_its_truth_log() {
    let d = common::tmpdir("sitl_bound");
    let o = out(&d, "sitl");
    let (ok, _, err) = common::helicon(&[
        "sitl",
        &demo(),
        "--duration",
        "4",
        "--log-rate",
        "10",
        "--out",
        o.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let mut s = helicon_sim::scenario::Scenario::from_file(Path::new(&demo())).unwrap();
    s.duration_s = 4.0;
    let est = helicon_sitl::estimate_ulog_bytes(&s, 0.0025, false);
    let bytes = std::fs::metadata(o.join("flight.ulg")).unwrap().len();
    let e = (est as f64 - bytes as f64) / bytes as f64;
    eprintln!(
        "flight.ulg of 4 s: {bytes} bytes written, {est} estimated ({:+.2} %)",
        100.0 * e
    );
    assert!(e.abs() < 0.03, "{e}");
    let t = helicon_sim::log_csv::read_log_csv(&o.join("log.csv")).unwrap();
    assert_eq!(t.rows(), 41);
    let (ok, _, err) = common::helicon(&[
        "sitl",
        &demo(),
        "--duration",
        "86400",
        "--max-log-bytes",
        "1000000000",
        "--out",
        out(&d, "day").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("flight.ulg") && err.contains("--max-log-bytes 1000000000"),
        "{err}"
    );
    assert!(!out(&d, "day").join("flight.ulg").exists());
}

/// The run's one-line summary says the size of the `log.csv` it wrote,
/// and a lower `--log-rate` writes a smaller one.
#[test]
fn the_summary_says_the_log_size() {
    let d = common::tmpdir("log_size");
    let size_said = |name: &str, extra: &[&str]| {
        let o = out(&d, name);
        let mut args = vec!["sim", "--duration", "4", "--out", o.to_str().unwrap()];
        let scenario = demo();
        args.insert(1, &scenario);
        args.extend_from_slice(extra);
        let (ok, text, err) = common::helicon(&args);
        assert!(ok, "{err}");
        let line = text
            .lines()
            .find(|l| l.starts_with("wrote log.csv ("))
            .unwrap_or_else(|| panic!("no summary line: {text}"));
        let bytes = std::fs::metadata(o.join("log.csv")).unwrap().len();
        let kb = format!("{:.0} kB", bytes as f64 / 1e3);
        assert!(
            line.contains(&format!(" rows, {kb}), ")),
            "{line} (file: {bytes} bytes)"
        );
        bytes
    };
    let full = size_said("full", &[]);
    let thin = size_said("thin", &["--log-rate", "10"]);
    assert!(thin * 5 < full, "{thin} vs {full}");
}

/// The limit as a scenario key: `[log] max_bytes` thins the log as
/// `--max-log-bytes` does, named in the warning; the option overrides it;
/// 0 is refused naming the key.
#[test]
fn the_scenario_key_limits_the_log_and_the_option_overrides_it() {
    let d = common::tmpdir("log_key");
    let text = std::fs::read_to_string(demo()).unwrap();
    assert!(text.contains("decimation = 4\n"));
    let limit = 400_000u64;
    let keyed = d.join("keyed.toml");
    std::fs::write(
        &keyed,
        text.replace(
            "decimation = 4\n",
            &format!("decimation = 4\nmax_bytes = {limit}\n"),
        ),
    )
    .unwrap();
    let thin = out(&d, "thin");
    let (ok, _, err) = common::helicon(&[
        "sim",
        keyed.to_str().unwrap(),
        "--duration",
        "30",
        "--out",
        thin.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("over [log] max_bytes = 400000 of scenario `demo`"),
        "{err}"
    );
    let thin_bytes = std::fs::metadata(thin.join("log.csv")).unwrap().len();
    assert!(
        thin_bytes <= limit && thin_bytes > limit / 2,
        "{thin_bytes}"
    );
    // the option overrides the key: the full-rate log
    let full = out(&d, "full");
    let (ok, _, err) = common::helicon(&[
        "sim",
        keyed.to_str().unwrap(),
        "--duration",
        "30",
        "--max-log-bytes",
        "1000000000",
        "--out",
        full.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(!err.contains("warning"), "{err}");
    assert!(std::fs::metadata(full.join("log.csv")).unwrap().len() > 4 * limit);
    let zero = d.join("zero.toml");
    std::fs::write(
        &zero,
        text.replace("decimation = 4\n", "decimation = 4\nmax_bytes = 0\n"),
    )
    .unwrap();
    let z = out(&d, "zero");
    let (ok, _, err) =
        common::helicon(&["sim", zero.to_str().unwrap(), "--out", z.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains("log.max_bytes") && err.contains(">= 1"),
        "{err}"
    );
}
