//! End-to-end tests of `helicon mc`: the options (`--params`, `--seed`,
//! `--duration`, `--runs`) in `--help`, applied and validated, and a
//! billion runs refused at once (never a panic, the file or option named).
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

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

/// Two short runs of the thesis controller in calm air, mass dispersed.
const CAMPAIGN: &str = r#"
name = "cli-mc"
runs = 2
seed = 5
trace_rate_hz = 10.0

[scenario]
name = "cli-mc-scenario"
duration_s = 0.3
[[scenario.reference]]
t_s = 0.1
output = "vn"
value = 0.2

[[dispersion]]
param = "body.mass_kg"
distribution = "normal"
kind = "relative"
sigma = 0.02
"#;

fn setup(name: &str) -> helicon_test_support::Scratch {
    let d = tmpdir(name);
    std::fs::write(d.join("c.toml"), CAMPAIGN).unwrap();
    std::fs::write(d.join("heavy.toml"), "[body]\nmass_kg = 15.0\n").unwrap();
    d
}

#[test]
fn mc_help_lists_the_options() {
    let o = helicon_in(&std::env::temp_dir(), &["mc", "--help"]);
    assert!(o.status.success());
    let help = text(&o.stdout);
    for opt in [
        "--params <FILE>",
        "--seed <SEED>",
        "--duration <S>",
        "--runs <RUNS>",
        "--threads",
        "--shard",
        "--out",
    ] {
        assert!(help.contains(opt), "{opt}: {help}");
    }
}

#[test]
fn mc_seed_duration_and_params_are_applied_and_recorded() {
    let d = setup("overrides");
    let o = helicon_in(
        &d,
        &[
            "mc",
            "c.toml",
            "--seed",
            "9",
            "--duration",
            "0.4",
            "--params",
            "heavy.toml",
            "--out",
            "r",
        ],
    );
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let r = d.join("r");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(r.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["seed"], 9);
    assert_eq!(
        manifest["overrides"],
        serde_json::json!(["--seed 9", "--duration 0.4", "--params heavy.toml"])
    );
    let scenario = std::fs::read_to_string(r.join("scenario.toml")).unwrap();
    assert!(scenario.contains("duration_s = 0.4"), "{scenario}");
    let params = std::fs::read_to_string(r.join("params.toml")).unwrap();
    assert!(params.contains("mass_kg = 15.0"), "{params}");
    // the runs flew 0.4 s around 15 kg (σ 2 %, truncated at 3σ)
    let csv = std::fs::read_to_string(r.join("runs.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let mass: f64 = f[col("body.mass_kg")].parse().unwrap();
        assert!((mass - 15.0).abs() <= 15.0 * 0.06 + 1e-12, "{mass}");
        assert_eq!(f[col("outcome")], "completed", "{row}");
        let t: f64 = f[col("t_end_s")].parse().unwrap();
        assert!((t - 0.4).abs() < 0.01, "{t}");
    }
    // the default folder carries the overridden seed
    let o = helicon_in(&d, &["mc", "c.toml", "--seed", "9", "--runs", "1"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(d.join("out/mc/cli-mc-seed9/runs.csv").exists());
}

#[test]
fn mc_bad_options_name_the_option_or_file() {
    let d = setup("bad");
    let cases: [(&[&str], &str); 7] = [
        (&["--duration", "-1"], "--duration"),
        (&["--duration", "nan"], "--duration"),
        (&["--duration", "fast"], "--duration"),
        (&["--params", "missing.toml"], "missing.toml"),
        (&["--seed", "-3"], "--seed"),
        (&["--runs", "0"], "--runs"),
        (&["--threads", "0"], "--threads"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["mc", "c.toml", "--out", "never"];
        args.extend_from_slice(extra);
        let o = helicon_in(&d, &args);
        no_panic(&o);
        assert!(!o.status.success(), "{extra:?}");
        let err = text(&o.stderr);
        assert!(err.contains(needle), "{extra:?}: {err}");
        assert!(!d.join("never").exists(), "{extra:?}: nothing written");
    }
    // a parameter file breaking a rule names the file and the key
    std::fs::write(d.join("neg.toml"), "[body]\nmass_kg = -2.0\n").unwrap();
    let o = helicon_in(&d, &["mc", "c.toml", "--params", "neg.toml"]);
    no_panic(&o);
    let err = text(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("neg.toml") && err.contains("body.mass_kg"),
        "{err}"
    );
}

#[test]
fn mc_a_billion_runs_is_refused_at_once() {
    let d = setup("billion");
    let t0 = Instant::now();
    let o = helicon_in(
        &d,
        &["mc", "c.toml", "--runs", "1000000000", "--out", "big"],
    );
    let dt = t0.elapsed();
    no_panic(&o);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("1000000000 runs: at most"), "{err}");
    assert!(err.contains("MiB") && err.contains("--shard"), "{err}");
    assert!(!d.join("big").exists());
    // refused before anything grows: well under the seconds a run would take
    assert!(dt < Duration::from_secs(10), "{dt:?}");
}

#[test]
fn mc_slurm_dry_run_writes_the_array_and_merge_scripts_and_status_follows_the_shards() {
    let d = setup("slurm");
    let o = helicon_in(
        &d,
        &[
            "mc",
            "c.toml",
            "--runs",
            "6",
            "--slurm",
            "--array",
            "3",
            "--partition",
            "short",
            "--time",
            "0:30:00",
            "--out",
            "sl",
            "--dry-run",
        ],
    );
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("would run: sbatch --parsable --array=0-2"),
        "{out}"
    );
    assert!(out.contains("--dependency=afterok:"), "{out}");
    let array = std::fs::read_to_string(d.join("sl/slurm/array.sbatch")).unwrap();
    for part in [
        "#SBATCH --array=0-2",
        "#SBATCH --partition=short",
        "#SBATCH --time=0:30:00",
        "--runs 6 --shard \"$K/3\"",
        "SLURM_ARRAY_TASK_ID",
    ] {
        assert!(array.contains(part), "{part}: {array}");
    }
    let merge = std::fs::read_to_string(d.join("sl/slurm/merge.sbatch")).unwrap();
    assert!(
        merge.contains(" mc merge ") && merge.contains("shard-2-of-3"),
        "{merge}"
    );
    // nothing run yet
    let st = helicon_in(&d, &["mc", "status", "sl"]);
    assert!(st.status.success(), "{}", text(&st.stderr));
    let s = text(&st.stdout);
    assert!(
        s.contains("shards: 0 done") && s.contains("3 missing"),
        "{s}"
    );
    assert!(s.contains("merged: not yet"), "{s}");
    // the tasks' command run by hand: shard 1 done, the others missing
    let o = helicon_in(
        &d,
        &[
            "mc",
            "c.toml",
            "--runs",
            "6",
            "--shard",
            "1/3",
            "--out",
            "sl/shards/shard-1-of-3",
        ],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let s = text(&helicon_in(&d, &["mc", "status", "sl"]).stdout);
    assert!(
        s.contains("shards: 1 done") && s.contains("2 missing"),
        "{s}"
    );
    assert!(s.contains("runs: 2/6 done"), "{s}");
    // a plan of another size in the same folder is refused
    let o = helicon_in(
        &d,
        &[
            "mc",
            "c.toml",
            "--runs",
            "6",
            "--slurm",
            "--array",
            "2",
            "--out",
            "sl",
            "--dry-run",
        ],
    );
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("use another --out"),
        "{}",
        text(&o.stderr)
    );
    // bad values name the option
    for (args, want) in [
        (vec!["--array", "7"], "--array 7"),
        (vec!["--time", "soon"], "--time `soon`"),
        (vec!["--partition", "a b"], "--partition `a b`"),
    ] {
        let mut a = vec![
            "mc",
            "c.toml",
            "--runs",
            "6",
            "--slurm",
            "--out",
            "sl2",
            "--dry-run",
        ];
        a.extend(args);
        let o = helicon_in(&d, &a);
        no_panic(&o);
        assert!(!o.status.success());
        assert!(
            text(&o.stderr).contains(want),
            "{want}: {}",
            text(&o.stderr)
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn mc_of_the_ground_campaign_prints_the_take_off_and_landing_failure_rate() {
    let d = tmpdir("ground");
    let campaign = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../campaigns/ground.toml");
    let o = helicon_in(
        &d,
        &[
            "mc",
            campaign.to_str().unwrap(),
            "--runs",
            "2",
            "--out",
            "g",
        ],
    );
    no_panic(&o);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = format!("{}{}", text(&o.stdout), text(&o.stderr));
    // the first two runs take off and land (docs/monte-carlo.md, "Take-offs
    // and landings"); the Wilson interval of 0 in 2 is 0 – 65.8 %
    assert!(
        out.contains("take-offs and landings: 0 of 2 runs failed (failure rate 0.0 %, 95 % Wilson interval 0.0 % – 65.8 %)"),
        "{out}"
    );
    let md = std::fs::read_to_string(d.join("g/stats.md")).unwrap();
    assert!(
        md.contains("## Take-offs and landings") && md.contains("| hard_landing | 2 m/s | 0 |"),
        "{md}"
    );
    assert!(d.join("g/hist_touchdown_vertical_speed_m_s.png").exists());
    let _ = std::fs::remove_dir_all(&d);
}
