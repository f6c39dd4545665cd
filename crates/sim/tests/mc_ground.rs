//! Monte Carlo of take-offs and landings: the ground metrics in the records
//! of a campaign with `[ground]`, the `[landing]` criteria and each run's
//! classification, the failure rate with its interval, and the figures of
//! `campaigns/ground.toml` that docs/monte-carlo.md quotes.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::mc::{
    Campaign, GROUND_METRIC_NAMES, LandingFailure, McError, RunOptions, Stats, WindKey, csv_header,
    run,
};
use helicon_sim::scenario::Scenario;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

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
    let d = std::env::temp_dir().join(format!("helicon-mcg-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    Tmp(d)
}

/// The hop of `campaigns/ground-scenario.toml` as an inline scenario,
/// descending at `descent_m_s`, with `extra` campaign lines (dispersions, a
/// `[landing]` table) before it.
fn hop(runs: usize, descent_m_s: f64, extra: &str) -> Campaign {
    let base = std::fs::read_to_string(root().join("campaigns/ground-scenario.toml")).unwrap();
    let params = root().join("scenarios/ground/twin-ground.toml");
    let mut scenario = String::new();
    for line in base.lines() {
        let l = line.trim();
        if l.starts_with('#') || l.is_empty() {
            continue;
        }
        let l = if l.starts_with("params") {
            format!("params = {:?}", params.display().to_string())
        } else if l == "value = 0.5" {
            format!("value = {descent_m_s}")
        } else {
            l.to_string()
        };
        // tables of the scenario become [scenario.…]
        let l = if let Some(t) = l.strip_prefix("[[") {
            format!("[[scenario.{t}")
        } else if let Some(t) = l.strip_prefix('[') {
            format!("[scenario.{t}")
        } else {
            l
        };
        scenario.push_str(&l);
        scenario.push('\n');
    }
    // the top-level keys of the scenario go under [scenario] itself
    let (top, tables) = scenario.split_at(scenario.find("[scenario.").unwrap());
    let text =
        format!("name = \"hop\"\nruns = {runs}\nseed = 5\n{extra}\n[scenario]\n{top}{tables}");
    Campaign::from_toml_str(&text, "hop.toml", None).unwrap()
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}

fn criterion(s: &Stats, c: LandingFailure) -> usize {
    let g = s.ground.as_ref().unwrap();
    g.criteria_failed
        .iter()
        .find(|x| x.criterion == c)
        .unwrap()
        .runs
}

#[test]
fn a_benign_campaign_has_no_failure_and_a_hard_landing_is_one() {
    // nominal parameters, the scenario's turbulence (W20 = 3.85 m/s) with a
    // wind seed per run, the default criteria: every take-off is detected
    // and every landing is soft
    let calm = hop(3, 0.5, "");
    assert!(calm.landing.is_some(), "a [ground] scenario has criteria");
    let out = tmp("benign");
    let r = run(&calm, &RunOptions::default(), &out, None).unwrap();
    let g = r.stats.ground.as_ref().unwrap();
    assert_eq!(
        (g.runs, g.failed),
        (3, 0),
        "{}",
        read(&out.join("stats.md"))
    );
    for c in &g.criteria_failed {
        assert_eq!(c.runs, 0, "{:?}", c.criterion);
    }
    let vz = g.metrics["touchdown_vertical_speed_m_s"].max.unwrap();
    assert!(vz > 0.05 && vz < 0.6, "{vz}");
    // a 3 m/s descent onto the skids: a hard landing (it bounces and rolls
    // over too; the hard landing is the cause, and it is named)
    let hard = hop(1, 3.0, "disperse_wind_seed = false");
    let out = tmp("hard");
    let r = run(&hard, &RunOptions::default(), &out, None).unwrap();
    let g = r.stats.ground.as_ref().unwrap();
    assert_eq!(g.failed, 1);
    assert_eq!(criterion(&r.stats, LandingFailure::HardLanding), 1);
    assert_eq!(criterion(&r.stats, LandingFailure::TouchdownOffset), 0);
    let vz = g.metrics["touchdown_vertical_speed_m_s"].max.unwrap();
    assert!(vz > 2.0, "{vz}");
    let rows = read(&out.join("runs.csv"));
    let last = rows.lines().nth(1).unwrap();
    assert!(
        last.ends_with("hard_landing;tip_over") || last.contains("hard_landing"),
        "{last}"
    );
    // the same flight judged with a looser limit is no hard landing
    let lenient = hop(
        1,
        3.0,
        "disperse_wind_seed = false\n[landing]\nmax_touchdown_vertical_speed_m_s = 3.0\n",
    );
    let out = tmp("lenient");
    let r = run(&lenient, &RunOptions::default(), &out, None).unwrap();
    assert_eq!(criterion(&r.stats, LandingFailure::HardLanding), 0);
}

#[test]
fn ground_columns_round_trip_through_the_store() {
    let c = hop(
        3,
        0.5,
        "[[dispersion]]\nparam = \"wind.steady.north_m_s\"\ndistribution = \"normal\"\nkind = \"absolute\"\nsigma = 1.0\n\
         [[dispersion]]\nparam = \"landing_gear.stiffness_n_m\"\ndistribution = \"uniform\"\nkind = \"relative\"\nhalf_width = 0.3\n",
    );
    let out = tmp("roundtrip");
    let first = run(&c, &RunOptions::default(), &out, None).unwrap();
    let csv1 = read(&out.join("runs.csv"));
    let stats1 = read(&out.join("stats.json"));
    // the header: the dispersed keys, the metrics, the ground metrics, the verdict
    let header = csv_header(
        &[
            "wind.steady.north_m_s".into(),
            "landing_gear.stiffness_n_m".into(),
        ],
        true,
    );
    assert_eq!(csv1.lines().next().unwrap(), header.join(","));
    assert_eq!(header.last().unwrap(), "landing");
    // each row's ground values are the flight's, bit for bit (shortest round-trip text)
    let nominal = c.prepare_nominal().unwrap();
    for (i, line) in csv1.lines().skip(1).enumerate() {
        let row: Vec<&str> = line.split(',').collect();
        assert_eq!(row.len(), header.len());
        let rec = c.run_one(&nominal, i).record;
        let n = GROUND_METRIC_NAMES.len();
        let ground = &rec.metrics[rec.metrics.len() - n..];
        for (k, v) in ground.iter().enumerate() {
            let col = header.len() - 1 - n + k;
            let text = v.map(|x| x.to_string()).unwrap_or_default();
            assert_eq!(row[col], text, "run {i} {}", header[col]);
            assert!(v.is_some(), "run {i}: {} missing", header[col]);
        }
        // the drawn wind is flown: a north wind makes the wind column differ per run
        assert_eq!(row[3].parse::<f64>().unwrap(), rec.values[0]);
    }
    // read back from the store on a rerun: nothing flown, the same files
    let again = run(&c, &RunOptions::default(), &out, None).unwrap();
    assert_eq!((again.flown, again.skipped), (0, 3));
    assert_eq!(read(&out.join("runs.csv")), csv1);
    assert_eq!(read(&out.join("stats.json")), stats1);
    assert_eq!(again.stats, first.stats);
    let manifest = read(&out.join("manifest.json"));
    assert!(manifest.contains("\"landing\""), "{manifest}");
    // two shards merged: the same files as the unsharded campaign
    let (s0, s1, merged) = (tmp("rt-s0"), tmp("rt-s1"), tmp("rt-merged"));
    for (k, d) in [(0, &s0), (1, &s1)] {
        let opts = RunOptions {
            shard: Some(helicon_sim::mc::Shard { k, m: 2 }),
            ..RunOptions::default()
        };
        run(&c, &opts, d, None).unwrap();
    }
    helicon_sim::mc::merge(&[s0.to_path_buf(), s1.to_path_buf()], &merged).unwrap();
    for f in ["runs.csv", "stats.json", "stats.md", "traces.csv"] {
        assert_eq!(read(&merged.join(f)), read(&out.join(f)), "{f}");
    }
    assert!(stats1.contains("\"failure_rate_high\""));
}

#[test]
fn landing_and_wind_dispersion_errors_name_the_file_and_field() {
    let base = "name = \"x\"\nruns = 1\nseed = 1\nscenario = \"robustness-scenario.toml\"\n";
    let dir = root().join("campaigns");
    // [landing] on a campaign without [ground]
    let e = Campaign::from_toml_str(
        &format!("{base}[landing]\nmax_liftoff_drift_m = 1.0\n"),
        "x.toml",
        Some(&dir),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("x.toml") && e.contains("`landing`") && e.contains("[ground]"),
        "{e}"
    );
    // a limit out of range
    let base_g = "name = \"x\"\nruns = 1\nseed = 1\nscenario = \"ground-scenario.toml\"\n";
    let e = Campaign::from_toml_str(
        &format!("{base_g}[landing]\nmax_touchdown_vertical_speed_m_s = -1.0\n"),
        "g.toml",
        Some(&dir),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("g.toml") && e.contains("landing.max_touchdown_vertical_speed_m_s"),
        "{e}"
    );
    // an unknown criterion
    let e = Campaign::from_toml_str(
        &format!("{base_g}[landing]\nmax_bounce_m = 1.0\n"),
        "g.toml",
        Some(&dir),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("max_bounce_m"), "{e}");
    // inf turns a criterion off
    let c = Campaign::from_toml_str(
        &format!("{base_g}[landing]\nmax_touchdown_offset_m = inf\n"),
        "g.toml",
        Some(&dir),
    )
    .unwrap();
    assert!(c.landing.unwrap().max_touchdown_offset_m.is_infinite());
    // a wind key whose section the scenario lacks (the robustness scenario has no Dryden)
    let e = Campaign::from_toml_str(
        &format!(
            "{base}[[dispersion]]\nparam = \"wind.dryden.w20_m_s\"\ndistribution = \"uniform\"\nkind = \"absolute\"\nhalf_width = 1.0\n"
        ),
        "x.toml",
        Some(&dir),
    )
    .unwrap_err();
    assert!(matches!(e, McError::Config(_)));
    let e = e.to_string();
    assert!(
        e.contains("x.toml")
            && e.contains("dispersion[0].param")
            && e.contains("wind.dryden.w20_m_s"),
        "{e}"
    );
    assert_eq!(
        WindKey::parse("wind.dryden.w20_m_s"),
        Some(WindKey::DrydenW20)
    );
}

#[test]
fn a_wind_draw_breaking_its_rule_is_an_invalid_run_named_by_its_key() {
    // W20 = 3.85 ± 10 m/s: some draws are negative
    let c = hop(
        6,
        0.5,
        "[[dispersion]]\nparam = \"wind.dryden.w20_m_s\"\ndistribution = \"uniform\"\nkind = \"absolute\"\nhalf_width = 10.0\n",
    );
    let nominal = c.prepare_nominal().unwrap();
    let mut invalid = 0;
    for i in 0..6 {
        let d = c.draw(i);
        let rec = c.run_one(&nominal, i).record;
        if d.values[0] < 0.0 {
            invalid += 1;
            assert_eq!(
                rec.termination.as_str(),
                "wind.dryden.w20_m_s",
                "{}",
                rec.reason
            );
            assert!(rec.reason.contains("w20_m_s"), "{}", rec.reason);
            let v = c.landing.unwrap().classify(&rec);
            assert!(v.has(LandingFailure::NotFlown) && v.failures().count() == 1);
        } else {
            assert_eq!(d.wind.dryden.unwrap().w20_m_s, d.values[0]);
        }
    }
    assert!(invalid > 0, "no negative draw in 6");
}

#[test]
fn a_campaign_without_ground_has_no_ground_output() {
    let c = Campaign::from_file(&root().join("tools/slurm/ci-campaign.toml")).unwrap();
    assert!(c.landing.is_none());
    let out = tmp("plain");
    let opts = RunOptions {
        runs: Some(2),
        ..RunOptions::default()
    };
    let r = run(&c, &opts, &out, None).unwrap();
    assert!(r.stats.ground.is_none());
    let header = read(&out.join("runs.csv"));
    let header = header.lines().next().unwrap();
    assert!(header.ends_with("effort_rms_S_tr"), "{header}");
    for name in GROUND_METRIC_NAMES {
        assert!(!header.contains(name), "{header}");
    }
    assert!(!read(&out.join("stats.json")).contains("\"ground\""));
    assert!(!read(&out.join("manifest.json")).contains("landing"));
    assert!(!read(&out.join("stats.md")).contains("Take-offs"));
    assert!(!out.join("hist_touchdown_vertical_speed_m_s.png").exists());
}

/// The figures docs/monte-carlo.md quotes for `campaigns/ground.toml` over
/// its first `runs` runs (the runs of an index are the same in every
/// campaign size).
fn shipped_campaign(runs: usize) -> Stats {
    let c = Campaign::from_file(&root().join("campaigns/ground.toml")).unwrap();
    let out = tmp(&format!("shipped-{runs}"));
    let opts = RunOptions {
        runs: Some(runs),
        ..RunOptions::default()
    };
    let r = run(&c, &opts, &out, None).unwrap();
    eprintln!("{}", read(&out.join("stats.md")));
    r.stats
}

fn near(x: Option<f64>, want: f64) -> bool {
    x.is_some_and(|x| (x - want).abs() <= 5e-4 * want.abs().max(1.0))
}

#[test]
fn the_first_24_runs_of_the_shipped_campaign_give_the_documented_figures() {
    let t0 = std::time::Instant::now();
    let s = shipped_campaign(24);
    let g = s.ground.as_ref().unwrap();
    // every take-off detected, every landing soft
    assert_eq!((g.runs, g.failed), (24, 0));
    assert_eq!(criterion(&s, LandingFailure::NoLiftoff), 0);
    assert!(
        g.failure_rate_low.abs() < 5e-4 && (g.failure_rate_high - 0.1380).abs() < 5e-4,
        "{} {}",
        g.failure_rate_low,
        g.failure_rate_high
    );
    let m = |k: &str| &g.metrics[k];
    let vz = m("touchdown_vertical_speed_m_s");
    assert!(
        near(vz.p50, 0.2913) && near(vz.p95, 0.4696) && near(vz.max, 0.5113),
        "{vz:?}"
    );
    let lo = m("liftoff_time_s");
    assert!(
        near(lo.p50, 9.8375) && near(lo.p95, 10.0120) && near(lo.max, 10.0250),
        "{lo:?}"
    );
    let arm = m("arm_to_liftoff_s");
    assert!(near(arm.p50, 9.8375) && near(arm.max, 10.0250), "{arm:?}");
    let det = m("liftoff_detected_s");
    assert_eq!(det.n, 24);
    assert!(near(det.p50, 10.1263) && near(det.max, 10.6800), "{det:?}");
    let off = m("touchdown_offset_m");
    assert!(
        near(off.p50, 0.1283) && near(off.p95, 0.3813) && near(off.max, 0.4259),
        "{off:?}"
    );
    let tilt = m("max_tilt_on_ground_rad");
    assert!(near(tilt.p50, 0.0486) && near(tilt.max, 0.0684), "{tilt:?}");
    assert!(t0.elapsed().as_secs() < 60, "{:?}", t0.elapsed());
}

/// The 200-run figures of the docs (`cargo test --release -p helicon-sim
/// --test mc_ground -- --ignored`; ~15 s on 2 shared cores).
#[test]
#[ignore = "the whole 200-run campaign: run with --ignored"]
fn the_shipped_campaign_gives_the_documented_figures() {
    let s = shipped_campaign(200);
    let g = s.ground.as_ref().unwrap();
    assert_eq!((g.runs, g.failed), (200, 4));
    assert_eq!(criterion(&s, LandingFailure::NoLiftoff), 0);
    assert_eq!(criterion(&s, LandingFailure::TipOver), 3);
    assert_eq!(criterion(&s, LandingFailure::Diverged), 3);
    assert!(
        (g.failure_rate_low - 0.0078).abs() < 1e-4,
        "{}",
        g.failure_rate_low
    );
    assert!(
        (g.failure_rate_high - 0.0502).abs() < 1e-4,
        "{}",
        g.failure_rate_high
    );
    let vz = &g.metrics["touchdown_vertical_speed_m_s"];
    assert!(
        near(vz.p50, 0.2899) && near(vz.p95, 0.4899) && near(vz.max, 0.6855),
        "{vz:?}"
    );
    let tilt = &g.metrics["max_tilt_on_ground_rad"];
    assert!(
        near(tilt.p50, 0.0497) && near(tilt.p95, 0.0729) && near(tilt.max, 1.2619),
        "{tilt:?}"
    );
    let det = &g.metrics["liftoff_detected_s"];
    assert_eq!(det.n, 200);
    assert!(
        near(det.p50, 10.0650) && near(det.p95, 10.4930) && near(det.max, 10.8800),
        "{det:?}"
    );
    let first = |c: LandingFailure| {
        g.criteria_failed
            .iter()
            .find(|x| x.criterion == c)
            .unwrap()
            .first_run
    };
    assert_eq!(first(LandingFailure::TipOver), Some(94));
    assert_eq!(first(LandingFailure::Diverged), Some(138));
    assert_eq!(criterion(&s, LandingFailure::TouchdownSideways), 1);
    assert_eq!(criterion(&s, LandingFailure::TouchdownDrift), 2);
    assert_eq!(criterion(&s, LandingFailure::HardLanding), 0);
    for (k, p50, p95, max) in [
        ("touchdown_horizontal_speed_m_s", 0.0515, 0.1397, 0.7729),
        ("liftoff_time_s", 9.8150, 10.0155, 10.0675),
        ("liftoff_drift_m", 0.0124, 0.0261, 0.0561),
        ("touchdown_offset_m", 0.1426, 0.4111, 0.8095),
        ("touchdown_drift_m", 0.0221, 0.0639, 0.6698),
    ] {
        let m = &g.metrics[k];
        assert!(
            near(m.p50, p50) && near(m.p95, p95) && near(m.max, max),
            "{k}: {m:?}"
        );
    }
}

#[test]
fn the_hop_scenario_flies_as_the_campaign_says() {
    let s = Scenario::from_file(&root().join("campaigns/ground-scenario.toml")).unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    let g = f.summary.ground.unwrap();
    // the tilt on the ground is the roll on the last loaded skid at lift-off:
    // about 2° with the on-board take-off (the law's integrators held until
    // lift-off), 0.02 ... 0.05 rad
    assert!(
        g.max_tilt_on_ground_rad > 0.02 && g.max_tilt_on_ground_rad < 0.05,
        "{g:?}"
    );
    assert!(g.liftoff_detected_s.is_some(), "{g:?}");
    // the nominal hop lifts off 1.7 s into the on-board take-off ramp
    // (docs/monte-carlo.md, to its printed digit)
    let into = g.liftoff_time_s.unwrap() - g.takeoff_start_s.unwrap();
    assert!((into - 1.7).abs() <= 0.05, "{into}");
    assert!(g.touchdown_offset_m.unwrap() < 0.5, "{g:?}");
}
