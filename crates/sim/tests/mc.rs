//! Monte Carlo campaigns: determinism across threads and shards, resume,
//! file errors, and the sampling of dispersions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use helicon_sim::mc::{Campaign, McError, RunOptions, Shard, merge, percentile, reason_class, run};
use std::path::{Path, PathBuf};

/// 8 short runs with sensors, fusion and estimator in the loop, wind, and
/// a few dispersions (one wide enough that some runs fail).
const SMALL: &str = r#"
name = "small"
runs = 8
seed = 11
trace_rate_hz = 20.0

[scenario]
name = "small-scenario"
preset = "thesis"
duration_s = 1.0
[[scenario.reference]]
t_s = 0.2
output = "vn"
value = 0.5
[scenario.controller]
input_max = [0.1, 0.7, 0.7, 0.04]
fusion = true
[scenario.wind]
seed = 3
[scenario.wind.thesis]
max_gust_m_s = 0.5

[[dispersion]]
param = "body.mass_kg"
distribution = "normal"
kind = "relative"
sigma = 0.1

[[dispersion]]
param = "servo.tail.omega_n_rad_s"
distribution = "uniform"
kind = "relative"
half_width = 0.2

[[dispersion]]
param = "geometry.kappa_h_m"
distribution = "normal"
kind = "absolute"
sigma = 0.01
"#;

/// A fresh temporary folder, removed when dropped.
struct Tmp(PathBuf);

impl Drop for Tmp {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

impl std::ops::Deref for Tmp {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

fn tmp(name: &str) -> Tmp {
    let d = std::env::temp_dir().join(format!("helicon-mc-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    Tmp(d)
}

fn small() -> Campaign {
    Campaign::from_toml_str(SMALL, "small.toml", None).unwrap()
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}

#[test]
fn one_and_two_threads_give_identical_runs_csv() {
    let c = small();
    let (a, b) = (tmp("t1"), tmp("t2"));
    let ra = run(
        &c,
        &RunOptions {
            threads: Some(1),
            ..Default::default()
        },
        &a,
        None,
    )
    .unwrap();
    let rb = run(
        &c,
        &RunOptions {
            threads: Some(2),
            ..Default::default()
        },
        &b,
        None,
    )
    .unwrap();
    assert_eq!(ra.flown, 8);
    assert_eq!(rb.flown, 8);
    let csv = read(&a.join("runs.csv"));
    assert_eq!(csv, read(&b.join("runs.csv")));
    assert_eq!(read(&a.join("traces.csv")), read(&b.join("traces.csv")));
    // one header + one row per run, in index order
    let idx: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(idx, ["0", "1", "2", "3", "4", "5", "6", "7"]);
    // the runs really differ (dispersed values and seeds)
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_ne!(rows[0].split(',').nth(1), rows[1].split(',').nth(1));
    for f in ["stats.json", "stats.md", "campaign.toml", "manifest.json"] {
        assert!(a.join(f).exists(), "{f}");
    }
    assert!(!a.join("runs.partial.csv").exists());
}

#[test]
fn two_shards_merged_equal_the_unsharded_campaign() {
    let c = small();
    let (full, s0, s1, merged) = (tmp("full"), tmp("s0"), tmp("s1"), tmp("merged"));
    run(&c, &RunOptions::default(), &full, None).unwrap();
    let r0 = run(
        &c,
        &RunOptions {
            shard: Some("0/2".parse().unwrap()),
            ..Default::default()
        },
        &s0,
        None,
    )
    .unwrap();
    run(
        &c,
        &RunOptions {
            shard: Some(Shard { k: 1, m: 2 }),
            threads: Some(1),
            ..Default::default()
        },
        &s1,
        None,
    )
    .unwrap();
    assert_eq!(r0.flown, 4);
    // shard 0 holds the even indices
    let shard0 = read(&s0.join("runs.csv"));
    assert!(
        shard0
            .lines()
            .skip(1)
            .all(|l| l.split(',').next().unwrap().parse::<usize>().unwrap() % 2 == 0)
    );
    merge(&[s0.to_path_buf(), s1.to_path_buf()], &merged).unwrap();
    for f in ["runs.csv", "traces.csv", "stats.json", "stats.md"] {
        assert_eq!(read(&full.join(f)), read(&merged.join(f)), "{f}");
    }
    // a folder of another campaign is refused
    let other =
        Campaign::from_toml_str(&SMALL.replace("seed = 11", "seed = 12"), "o.toml", None).unwrap();
    let od = tmp("other");
    run(
        &other,
        &RunOptions {
            runs: Some(1),
            ..Default::default()
        },
        &od,
        None,
    )
    .unwrap();
    let e = merge(&[s0.to_path_buf(), od.to_path_buf()], &tmp("bad-merge")).unwrap_err();
    assert!(matches!(e, McError::Mismatch { .. }), "{e}");
    // and so is running a different campaign into an existing folder
    let e = run(&c, &RunOptions::default(), &od, None).unwrap_err();
    assert!(matches!(e, McError::Mismatch { .. }), "{e}");
}

#[test]
fn rerun_skips_finished_runs() {
    let c = small();
    let (d, full) = (tmp("resume"), tmp("resume-full"));
    let first = run(
        &c,
        &RunOptions {
            runs: Some(3),
            ..Default::default()
        },
        &d,
        None,
    )
    .unwrap();
    assert_eq!((first.flown, first.skipped), (3, 0));
    // an interrupted run leaves a partial file: rows of finished runs,
    // maybe a torn last line; simulate one finished run 5 and a torn row
    let row5 = {
        run(&c, &RunOptions::default(), &full, None).unwrap();
        read(&full.join("runs.csv"))
            .lines()
            .find(|l| l.starts_with("5,"))
            .unwrap()
            .to_string()
    };
    std::fs::write(d.join("runs.partial.csv"), format!("{row5}\n6,123,45")).unwrap();
    let second = run(&c, &RunOptions::default(), &d, None).unwrap();
    assert_eq!((second.flown, second.skipped), (4, 4));
    assert_eq!(read(&d.join("runs.csv")), read(&full.join("runs.csv")));
    let third = run(&c, &RunOptions::default(), &d, None).unwrap();
    assert_eq!((third.flown, third.skipped), (0, 8));
    assert_eq!(third.stats.runs, 8);
}

#[test]
fn bad_campaign_files_name_the_file_and_field() {
    let cases = [
        (
            SMALL.replace("body.mass_kg", "body.mas_kg"),
            "dispersion[0].param",
        ),
        (
            SMALL.replace("half_width = 0.2", "sigma = 0.2"),
            "dispersion[1]",
        ),
        (
            SMALL.replace("sigma = 0.01", "sigma = -0.01"),
            "dispersion[2].sigma",
        ),
        (
            SMALL.replace("distribution = \"normal\"", "distribution = \"gauss\""),
            "distribution",
        ),
        (SMALL.replace("runs = 8", "runz = 8"), "runz"),
        (
            SMALL.replace("duration_s = 1.0", "duration_s = -1.0"),
            "duration_s",
        ),
    ];
    for (text, field) in cases {
        let e = Campaign::from_toml_str(&text, "bad.toml", None).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("bad.toml"), "{msg}");
        assert!(msg.contains(field), "{field}: {msg}");
    }
    let e = Campaign::from_file(Path::new("/nonexistent/campaign.toml")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/campaign.toml"), "{e}");
    // a scenario path that does not exist names that path
    let text = "runs = 2\nseed = 1\nscenario = \"missing-scenario.toml\"\n";
    let e = Campaign::from_toml_str(text, "c.toml", Some(Path::new("/tmp/x"))).unwrap_err();
    assert!(e.to_string().contains("missing-scenario.toml"), "{e}");
}

#[test]
fn dispersion_draws_have_the_configured_statistics() {
    let c = Campaign::from_toml_str(
        &SMALL.replace("sigma = 0.1\n", "sigma = 0.1\ntruncate_sigma = 0.0\n"),
        "s.toml",
        None,
    )
    .unwrap();
    let n = 20_000;
    let draws: Vec<_> = (0..n).map(|i| c.draw(i)).collect();
    let stats = |j: usize| {
        let v: Vec<f64> = draws.iter().map(|d| d.values[j]).collect();
        let m = v.iter().sum::<f64>() / n as f64;
        let s = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        (m, s, lo, hi)
    };
    // mass: normal, 10 % relative around 14 kg: mean 14 ± 3·σ/√n, σ 1.4 within 2 %
    let (m, s, ..) = stats(0);
    assert!((m - 14.0).abs() < 3.0 * 1.4 / (n as f64).sqrt(), "{m}");
    assert!((s / 1.4 - 1.0).abs() < 0.02, "{s}");
    // tail servo ωn: uniform 100·(1 ± 0.2): std 20/√3, within the bounds
    let (m, s, lo, hi) = stats(1);
    assert!((m - 100.0).abs() < 3.0 * 11.55 / (n as f64).sqrt(), "{m}");
    assert!((s / (20.0 / 3f64.sqrt()) - 1.0).abs() < 0.02, "{s}");
    assert!(
        lo >= 80.0 && hi < 120.0 && lo < 80.5 && hi > 119.5,
        "{lo} {hi}"
    );
    // κh: absolute normal σ = 1 cm around 0, truncated at 3σ (default)
    let (m, s, lo, hi) = stats(2);
    assert!(m.abs() < 3.0 * 0.01 / (n as f64).sqrt(), "{m}");
    assert!((s / 0.01 - 1.0).abs() < 0.03, "{s}");
    assert!(lo >= -0.03 && hi <= 0.03, "{lo} {hi}");
    // the dispersed parameter really is set in the run's params
    assert_eq!(draws[7].params.body.mass_kg, draws[7].values[0]);
    assert_eq!(draws[7].params.servos[3].omega_n_rad_s, draws[7].values[1]);
    // a run's draws depend only on its index, and seeds differ between runs
    let again = c.draw(12_345);
    assert_eq!(again.values, draws[12_345].values);
    assert_eq!(again.wind_seed, draws[12_345].wind_seed);
    assert_ne!(draws[0].wind_seed, draws[1].wind_seed);
    assert_ne!(draws[0].wind_seed, draws[0].sensor_seed);
}

#[test]
fn a_draw_breaking_a_parameter_rule_is_recorded_invalid() {
    // mass 14 kg ± 100 kg absolute: about 45 % of the draws are negative
    let text = SMALL.replace(
        "kind = \"relative\"\nsigma = 0.1",
        "kind = \"absolute\"\nsigma = 100.0\ntruncate_sigma = 0.0",
    );
    let c = Campaign::from_toml_str(&text, "inv.toml", None).unwrap();
    let d = tmp("invalid");
    let r = run(&c, &RunOptions::default(), &d, None).unwrap();
    let csv = read(&d.join("runs.csv"));
    let invalid = csv.lines().filter(|l| l.contains(",invalid,")).count();
    let negative = (0..8).filter(|&i| c.draw(i).values[0] <= 0.0).count();
    assert!(negative > 0, "the seed should give some negative masses");
    assert_eq!(invalid, negative);
    assert!(csv.contains("invalid draw: body.mass_kg"), "{csv}");
    assert!(r.stats.failed >= invalid);
    assert!(
        r.stats
            .reasons
            .keys()
            .any(|k| k.starts_with("invalid: invalid draw")),
        "{:?}",
        r.stats.reasons
    );
}

#[test]
fn percentiles_and_reason_classes() {
    let v = [1.0, 2.0, 3.0, 4.0, 5.0];
    assert_eq!(percentile(&v, 0.5), Some(3.0));
    assert_eq!(percentile(&v, 0.05), Some(1.2));
    assert_eq!(percentile(&v, 0.95), Some(4.8));
    assert_eq!(percentile(&[], 0.5), None);
    assert_eq!(
        reason_class(
            "diverged",
            "body rate 10.02 rad/s beyond 10 rad/s at t = 3.2 s"
        ),
        reason_class(
            "diverged",
            "body rate 11.5 rad/s beyond 10 rad/s at t = 1.0 s"
        )
    );
    assert_eq!(
        reason_class(
            "diverged",
            "attitude beyond 1.2 rad at t = 3.388 s (phi = -0.8)"
        ),
        "diverged: attitude beyond # rad"
    );
}
