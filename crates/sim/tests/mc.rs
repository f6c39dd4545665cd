//! Monte Carlo campaigns: determinism across threads and shards, resume,
//! file errors, and the sampling of dispersions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use helicon_sim::closed_loop::Termination;
use helicon_sim::mc::{
    Campaign, CampaignOverrides, ErrorStage, FORMAT_VERSION, McError, RunOptions, RunOutcome,
    RunTermination, Shard, Stats, merge, percentile, run,
};
use helicon_sim::scenario::ScenarioError;
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
    assert!(a.join("runs.bin").exists());
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
fn traces_only_for_the_runs_asked_for() {
    let c = small();
    let few = c
        .clone()
        .with_overrides(&CampaignOverrides {
            trace_runs: Some(3),
            ..Default::default()
        })
        .unwrap();
    assert_ne!(few.hash, c.hash);
    assert_eq!(few.overrides, ["--trace-runs 3"]);
    assert!(few.traced(2) && !few.traced(3) && c.traced(7));
    let (all, part, s0, s1, merged) = (
        tmp("tr-all"),
        tmp("tr-3"),
        tmp("tr-s0"),
        tmp("tr-s1"),
        tmp("tr-m"),
    );
    let ra = run(&c, &RunOptions::default(), &all, None).unwrap();
    let rp = run(&few, &RunOptions::default(), &part, None).unwrap();
    // the same runs and statistics (another hash); traces of runs 0..3 only,
    // those of the full campaign
    assert_eq!(read(&all.join("runs.csv")), read(&part.join("runs.csv")));
    assert_eq!(ra.stats.metrics, rp.stats.metrics);
    let t_all = read(&all.join("traces.csv"));
    let t_part = read(&part.join("traces.csv"));
    let first3: Vec<&str> = t_all
        .lines()
        .filter(|l| l.starts_with("index") || ["0,", "1,", "2,"].iter().any(|p| l.starts_with(p)))
        .collect();
    assert_eq!(t_part.lines().collect::<Vec<_>>(), first3);
    assert!(t_part.lines().count() > 3);
    // sharded and merged: the same folder
    for (k, d) in [(0, &s0), (1, &s1)] {
        let o = RunOptions {
            shard: Some(Shard { k, m: 2 }),
            ..Default::default()
        };
        run(&few, &o, d, None).unwrap();
    }
    merge(&[s1.to_path_buf(), s0.to_path_buf()], &merged).unwrap();
    for f in ["runs.csv", "traces.csv", "stats.json", "stats.md"] {
        assert_eq!(read(&part.join(f)), read(&merged.join(f)), "{f}");
    }
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
    // an interrupted campaign leaves the slots of the runs that finished,
    // in any order, maybe a torn one: copy run 5's slot (and its trace) from
    // the full campaign, and half of run 6's
    run(&c, &RunOptions::default(), &full, None).unwrap();
    let runs_bin = std::fs::read(full.join("runs.bin")).unwrap();
    let traces_bin = std::fs::read(full.join("traces.bin")).unwrap();
    let (rs, ts) = (runs_bin.len() / 8, 40 * c.footprint().trace_points as usize);
    assert_eq!(rs * 8, runs_bin.len());
    let patch = |file: &str, at: usize, bytes: &[u8]| {
        use std::os::unix::fs::FileExt;
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(d.join(file))
            .unwrap();
        f.write_all_at(bytes, at as u64).unwrap();
    };
    patch("traces.bin", 5 * ts, &traces_bin[5 * ts..6 * ts]);
    patch("runs.bin", 5 * rs, &runs_bin[5 * rs..6 * rs]);
    patch("runs.bin", 6 * rs, &runs_bin[6 * rs..6 * rs + rs / 2]);
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
    // typed: outcome `invalid`, termination the parameter key
    let invalid = csv
        .lines()
        .filter(|l| l.contains(",invalid,body.mass_kg,"))
        .count();
    let negative = (0..8).filter(|&i| c.draw(i).values[0] <= 0.0).count();
    assert!(negative > 0, "the seed should give some negative masses");
    assert_eq!(invalid, negative);
    assert!(csv.contains("invalid draw: body.mass_kg"), "{csv}");
    assert!(r.stats.failed >= invalid);
    let f = r
        .stats
        .failures
        .iter()
        .find(|f| f.termination == RunTermination::InvalidDraw("body.mass_kg".into()))
        .unwrap();
    assert_eq!(f.outcome, RunOutcome::Invalid);
    assert_eq!(f.runs, negative);
    assert!(
        f.example.starts_with("invalid draw: body.mass_kg = -"),
        "{f:?}"
    );
    // stats.json carries the typed class as words, and its format version
    let json: serde_json::Value = serde_json::from_str(&read(&d.join("stats.json"))).unwrap();
    assert_eq!(json["format_version"], FORMAT_VERSION);
    assert!(
        json["failures"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["outcome"] == "invalid" && f["termination"] == "body.mass_kg"),
        "{json}"
    );
}

/// A campaign where every run exceeds a tiny body-rate limit.
fn diverging() -> Campaign {
    let text = SMALL.replace(
        "[scenario.controller]",
        "[scenario.plant]\nmax_rate_rad_s = 0.02\n[scenario.controller]",
    );
    Campaign::from_toml_str(&text, "div.toml", None).unwrap()
}

#[test]
fn failures_are_grouped_by_typed_termination_and_read_back_on_resume() {
    let c = diverging();
    let d = tmp("typed");
    let r = run(&c, &RunOptions::default(), &d, None).unwrap();
    let csv = read(&d.join("runs.csv"));
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let o = header.iter().position(|h| *h == "outcome").unwrap();
    assert_eq!(header[o + 1..o + 4], ["termination", "reason", "t_end_s"]);
    // every flown run diverges on the rate limit: one class, no `#` placeholders
    let flown: usize = r
        .stats
        .failures
        .iter()
        .filter(|f| f.outcome == RunOutcome::Diverged)
        .map(|f| f.runs)
        .sum();
    assert!(flown > 0, "{:?}", r.stats.failures);
    for f in &r.stats.failures {
        assert!(!f.termination.as_str().contains('#'), "{f:?}");
        if f.outcome == RunOutcome::Diverged {
            assert_eq!(
                f.termination,
                RunTermination::Flight(Termination::RateLimit)
            );
            assert!(f.example.starts_with("body rate"), "{f:?}");
        }
    }
    let md = read(&d.join("stats.md"));
    assert!(md.contains("| diverged | rate_limit |"), "{md}");
    // resume reads the typed columns back: nothing flown, same statistics
    let again = run(&c, &RunOptions::default(), &d, None).unwrap();
    assert_eq!((again.flown, again.skipped), (0, 8));
    assert_eq!(again.stats, r.stats);
    assert_eq!(read(&d.join("runs.csv")), csv);
}

#[test]
fn typed_outcomes_parse_and_refuse_inconsistent_words() {
    for o in RunOutcome::ALL {
        assert_eq!(o.as_str().parse::<RunOutcome>().unwrap(), o);
    }
    for t in Termination::ALL {
        let rt = RunTermination::parse(t.outcome().into(), t.as_str()).unwrap();
        assert_eq!(rt, RunTermination::Flight(t));
    }
    for s in ErrorStage::ALL {
        let rt = RunTermination::parse(RunOutcome::Error, s.as_str()).unwrap();
        assert_eq!(rt, RunTermination::Error(s));
        assert_eq!(rt.to_string(), format!("error: {}", s.as_str()));
    }
    assert!(RunTermination::parse(RunOutcome::Invalid, "body.mass_kg").is_ok());
    // a diverged run cannot have completed, nor name a parameter
    assert!(RunTermination::parse(RunOutcome::Diverged, "completed").is_err());
    assert!(RunTermination::parse(RunOutcome::Diverged, "body.mass_kg").is_err());
    assert!(RunTermination::parse(RunOutcome::Completed, "rate_limit").is_err());
    assert!(RunTermination::parse(RunOutcome::Invalid, "body.mas_kg").is_err());
    assert!(RunTermination::parse(RunOutcome::Error, "nowhere").is_err());
    assert!("crashed".parse::<RunOutcome>().is_err());
}

#[test]
fn a_torn_or_corrupted_slot_is_flown_again_and_a_misplaced_one_is_refused() {
    let c = small();
    let d = tmp("badslot");
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
    assert_eq!(first.flown, 3);
    let csv = read(&d.join("runs.csv"));
    let bin = std::fs::read(d.join("runs.bin")).unwrap();
    let rs = bin.len() / 3;
    use std::os::unix::fs::FileExt;
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(d.join("runs.bin"))
        .unwrap();
    // one bit of run 1's metrics flipped: its checksum fails, it is flown again
    f.write_all_at(&[bin[rs + rs - 3] ^ 4], (2 * rs - 3) as u64)
        .unwrap();
    let again = run(
        &c,
        &RunOptions {
            runs: Some(3),
            ..Default::default()
        },
        &d,
        None,
    )
    .unwrap();
    assert_eq!((again.flown, again.skipped), (1, 2));
    assert_eq!(read(&d.join("runs.csv")), csv);
    // one bit of run 2's trace flipped: the same
    let t = std::fs::read(d.join("traces.bin")).unwrap();
    let tf = std::fs::OpenOptions::new()
        .write(true)
        .open(d.join("traces.bin"))
        .unwrap();
    let ts = 40 * c.footprint().trace_points as usize;
    tf.write_all_at(&[t[2 * ts + 9] ^ 1], (2 * ts + 9) as u64)
        .unwrap();
    let again = run(
        &c,
        &RunOptions {
            runs: Some(3),
            ..Default::default()
        },
        &d,
        None,
    )
    .unwrap();
    assert_eq!((again.flown, again.skipped), (1, 2));
    assert_eq!(read(&d.join("runs.csv")), csv);
    // a valid slot in the place of another run (untraced runs: a slot's
    // checksum covers its own trace slot): an error naming file and slot
    let c = Campaign::from_toml_str(
        &SMALL.replace("trace_rate_hz = 20.0", "trace_rate_hz = 0.0"),
        "n.toml",
        None,
    )
    .unwrap();
    let d = tmp("badslot-untraced");
    run(
        &c,
        &RunOptions {
            runs: Some(3),
            ..Default::default()
        },
        &d,
        None,
    )
    .unwrap();
    let bin = std::fs::read(d.join("runs.bin")).unwrap();
    let rs = bin.len() / 3;
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(d.join("runs.bin"))
        .unwrap();
    f.write_all_at(&bin[..rs], rs as u64).unwrap();
    let e = run(
        &c,
        &RunOptions {
            runs: Some(3),
            ..Default::default()
        },
        &d,
        None,
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, McError::Store { slot: 1, .. }), "{msg}");
    assert!(
        msg.contains("runs.bin") && msg.contains("holds run 0"),
        "{msg}"
    );
}

#[test]
fn a_key_dispersed_twice_is_an_error_naming_the_file_key_and_both_entries() {
    let text = format!(
        "{SMALL}\n[[dispersion]]\nparam = \"servo.tail.omega_n_rad_s\"\ndistribution = \"normal\"\nkind = \"relative\"\nsigma = 0.05\n"
    );
    let e = Campaign::from_toml_str(&text, "twice.toml", None).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, McError::Config(ScenarioError::Invalid { .. })),
        "{msg}"
    );
    for part in [
        "twice.toml",
        "servo.tail.omega_n_rad_s",
        "dispersion[3]",
        "dispersion[1]",
    ] {
        assert!(msg.contains(part), "{part}: {msg}");
    }
}

#[test]
fn runs_beyond_the_disk_budget_are_refused_before_anything_is_written() {
    let c = small();
    let d = tmp("toomany");
    // a billion runs: refused at once, from the file system's own figure
    let e = run(
        &c,
        &RunOptions {
            runs: Some(1_000_000_000),
            ..Default::default()
        },
        &d,
        None,
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            McError::TooManyRuns {
                runs: 1_000_000_000,
                ..
            }
        ),
        "{msg}"
    );
    assert!(msg.contains("at most") && msg.contains("--shard"), "{msg}");
    assert!(!d.exists(), "nothing written");
    // a budget for exactly three runs: 3 fly, 4 do not
    let f = c.footprint();
    assert!(f.trace_points >= 20, "1 s at 20 Hz: {f:?}");
    assert!(f.disk_bytes_per_traced_run > f.disk_bytes_per_run);
    let budget = 3 * f.disk_bytes_per_traced_run;
    let opts = |runs| RunOptions {
        runs: Some(runs),
        disk_budget_bytes: Some(budget),
        ..Default::default()
    };
    let e = run(&c, &opts(4), &d, None).unwrap_err();
    assert!(
        matches!(
            e,
            McError::TooManyRuns {
                runs: 4,
                max_runs: 3,
                ..
            }
        ),
        "{e}"
    );
    assert!(!d.exists());
    assert_eq!(run(&c, &opts(3), &d, None).unwrap().flown, 3);
    // the estimate bounds what is written
    let written: u64 = std::fs::read_dir(&*d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            [
                "runs.bin",
                "traces.bin",
                "reasons.bin",
                "runs.csv",
                "traces.csv",
            ]
            .iter()
            .any(|n| p.ends_with(n))
        })
        .map(|p| std::fs::metadata(p).unwrap().len())
        .sum();
    assert!(written <= budget, "{written} > {budget}");
    // a shard counts only its own runs: 7 runs in shards of 2 → 4 and 3
    let s1 = tmp("toomany-s1");
    let o = RunOptions {
        shard: Some(Shard { k: 1, m: 2 }),
        ..opts(7)
    };
    assert_eq!(run(&c, &o, &s1, None).unwrap().flown, 3);
    // untraced runs cost less: with trace_runs = 1, four fit
    let few = c
        .clone()
        .with_overrides(&CampaignOverrides {
            trace_runs: Some(1),
            ..Default::default()
        })
        .unwrap();
    let s2 = tmp("toomany-untraced");
    assert_eq!(run(&few, &opts(4), &s2, None).unwrap().flown, 4);
}

#[test]
fn an_unwritable_output_folder_is_an_error_before_any_run_is_flown() {
    let c = small();
    let d = tmp("unwritable");
    std::fs::create_dir_all(&*d).unwrap();
    let file = d.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    let flown = std::sync::atomic::AtomicUsize::new(0);
    let progress = |_: usize, _: usize| {
        flown.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    };
    let e = run(
        &c,
        &RunOptions::default(),
        &file.join("out"),
        Some(&progress),
    )
    .unwrap_err();
    assert!(
        matches!(e, McError::Config(ScenarioError::Io { .. })),
        "{e}"
    );
    assert!(e.to_string().contains("a-file/out"), "{e}");
    // a file in the folder that cannot be written (a directory in its place)
    let d2 = d.join("out2");
    std::fs::create_dir_all(d2.join("runs.bin")).unwrap();
    let e = run(&c, &RunOptions::default(), &d2, Some(&progress)).unwrap_err();
    assert!(e.to_string().contains("runs.bin"), "{e}");
    assert_eq!(flown.load(std::sync::atomic::Ordering::Relaxed), 0);
}

#[test]
fn a_folder_of_another_format_version_is_refused() {
    let c = small();
    let d = tmp("format1");
    run(
        &c,
        &RunOptions {
            runs: Some(1),
            ..Default::default()
        },
        &d,
        None,
    )
    .unwrap();
    // a version-1 manifest has no `format_version`
    let m = read(&d.join("manifest.json"));
    let v1 = m.replace(&format!("\"format_version\": {FORMAT_VERSION},"), "");
    assert_ne!(m, v1);
    std::fs::write(d.join("manifest.json"), v1).unwrap();
    let e = run(&c, &RunOptions::default(), &d, None).unwrap_err();
    assert!(matches!(e, McError::Format { found: 1, .. }), "{e}");
    let e = merge(&[d.to_path_buf()], &tmp("format1-merged")).unwrap_err();
    assert!(matches!(e, McError::Format { found: 1, .. }), "{e}");
    assert!(matches!(merge(&[], &d).unwrap_err(), McError::NoFolders));
}

#[test]
fn overrides_are_validated_and_make_another_campaign() {
    let c = small();
    let o = |seed, duration_s, params| CampaignOverrides {
        seed,
        duration_s,
        params,
        trace_runs: None,
    };
    let s = c.clone().with_overrides(&o(Some(12), None, None)).unwrap();
    assert_eq!(s.seed, 12);
    assert_ne!(s.hash, c.hash);
    assert_ne!(s.draw(0).values, c.draw(0).values);
    assert_eq!(s.overrides, ["--seed 12"]);
    // the same seed as the file's: same runs, and the hash of the file with that seed
    let same = c.clone().with_overrides(&o(Some(11), None, None)).unwrap();
    assert_eq!(same.hash, c.hash);
    let twelve =
        Campaign::from_toml_str(&SMALL.replace("seed = 11", "seed = 12"), "s.toml", None).unwrap();
    assert_eq!(s.hash, twelve.hash);
    let d = c.clone().with_overrides(&o(None, Some(0.5), None)).unwrap();
    assert_eq!(d.scenario.duration_s, 0.5);
    assert_ne!(d.hash, c.hash);
    for bad in [-1.0, 0.0, f64::NAN, 1e6] {
        let msg = c
            .clone()
            .with_overrides(&o(None, Some(bad), None))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("--duration") && msg.contains("duration_s"),
            "{msg}"
        );
    }
    let dir = tmp("params");
    std::fs::create_dir_all(&*dir).unwrap();
    let p = dir.join("heavy.toml");
    std::fs::write(&p, "[body]\nmass_kg = 15.0\n").unwrap();
    let h = c
        .clone()
        .with_overrides(&o(None, None, Some(p.clone())))
        .unwrap();
    assert_eq!(h.nominal.body.mass_kg, 15.0);
    assert_ne!(h.hash, c.hash);
    // the dispersion is around the new nominal: relative draws scale with it
    assert!((h.draw(3).values[0] / c.draw(3).values[0] - 15.0 / 14.0).abs() < 1e-12);
    let missing = dir.join("missing.toml");
    let msg = format!(
        "{:#}",
        anyhow_like(
            c.clone()
                .with_overrides(&o(None, None, Some(missing)))
                .unwrap_err()
        )
    );
    assert!(msg.contains("missing.toml"), "{msg}");
    std::fs::write(&p, "[body]\nmass_kg = -1.0\n").unwrap();
    let msg = c
        .with_overrides(&o(None, None, Some(p)))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("heavy.toml") && msg.contains("body.mass_kg"),
        "{msg}"
    );
}

/// The error and its sources, as `helicon` prints them.
fn anyhow_like(e: McError) -> String {
    let mut s = e.to_string();
    let mut src = std::error::Error::source(&e);
    while let Some(c) = src {
        s.push_str(": ");
        s.push_str(&c.to_string());
        src = c.source();
    }
    s
}

#[test]
fn statistics_are_finite_or_refused_never_null() {
    // percentiles and means of finite data near the largest floats stay finite
    let big = [-f64::MAX, f64::MAX];
    assert_eq!(percentile(&big, 0.5), Some(0.0));
    let v = [f64::MAX, f64::MAX];
    assert_eq!(percentile(&v, 0.3), Some(f64::MAX));
    let r = |i: usize, m: f64| helicon_sim::mc::RunRecord {
        index: i,
        wind_seed: 0,
        sensor_seed: 0,
        values: vec![],
        termination: RunTermination::Flight(Termination::Completed),
        reason: String::new(),
        t_end_s: 1.0,
        metrics: vec![Some(m); 20],
    };
    let recs = [r(0, f64::MAX), r(1, f64::MAX), r(2, f64::MAX)];
    let refs: Vec<_> = recs.iter().collect();
    let s = Stats::from_records("big", "h", &refs);
    assert_eq!(s.metrics["vn_rms"].mean, Some(f64::MAX));
    s.check_finite("stats.json").unwrap();
    // a non-finite statistic is an error naming the file and the field
    let mut bad = s.clone();
    bad.metrics.get_mut("vd_rms").unwrap().p95 = Some(f64::NAN);
    let e = bad.check_finite("out/stats.json").unwrap_err();
    assert!(
        matches!(e, McError::NonFinite { .. }) && e.to_string().contains("metrics.vd_rms.p95"),
        "{e}"
    );
}

#[test]
fn percentiles() {
    let v = [1.0, 2.0, 3.0, 4.0, 5.0];
    assert_eq!(percentile(&v, 0.5), Some(3.0));
    assert_eq!(percentile(&v, 0.05), Some(1.2));
    assert_eq!(percentile(&v, 0.95), Some(4.8));
    assert_eq!(percentile(&[], 0.5), None);
}
