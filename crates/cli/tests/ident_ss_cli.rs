//! `helicon ident frf` with many conditioning inputs on the flown
//! identification log (`scenarios/ident-hover-sweep.toml`), and
//! `helicon ident ss` on exact and flown responses, run as a user would.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};
use helicon_ident::Complex64;
use helicon_ident::frf::{WindowSpec, composite, conditioned, cross_spectra_grid, log_grid};
use helicon_model::linearize::linearize;
use helicon_model::{InflowMode, REDUCED_STATE_NAMES};
use nalgebra::{DMatrix, DVector, Vector3};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn scenario_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ident-hover-sweep.toml")
}

/// The named columns of a CSV with a header row.
fn columns(path: &Path, names: &[&str]) -> Vec<Vec<f64>> {
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .unwrap();
    let header = rdr.headers().unwrap().clone();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| header.iter().position(|h| h == *n).unwrap())
        .collect();
    let mut out = vec![Vec::new(); names.len()];
    for rec in rdr.records() {
        let rec = rec.unwrap();
        for (c, &i) in idx.iter().enumerate() {
            out[c].push(rec[i].parse::<f64>().unwrap());
        }
    }
    out
}

/// Rows of one output of a frf.csv: (ω, H, γ², ε).
fn frf_rows(path: &Path, output: &str) -> Vec<(f64, Complex64, f64, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .filter(|l| l.split(',').next() == Some(output))
        .map(|l| {
            let v: Vec<f64> = l.split(',').skip(1).map(|x| x.parse().unwrap()).collect();
            let h = Complex64::from_polar(10f64.powf(v[1] / 20.0), v[2].to_radians());
            (v[0], h, v[3], v[4])
        })
        .collect()
}

fn percentile(v: &[f64], p: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = ((p * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

/// The flown identification log through `ident frf` conditioned on the four
/// servos: the 57 s window (2.9 averages for 4 inputs) is left out with a
/// note, the response equals the library's conditioned composite on the
/// windows used, and matches the linearised hover model within its random
/// error as `crates/sim/tests/excitation.rs` requires of the library.
#[test]
#[allow(
    clippy::too_many_lines,
    reason = "one flight, its checks in sequence (flying it once per check would triple the time)"
)]
fn ident_frf_conditioned_on_four_servos_on_the_flown_sweep_log() {
    let dir = tmpdir("flown");
    let run = dir.join("run");
    let (ok, _, err) = helicon(&[
        "sim",
        scenario_path().to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let log = run.join("log.csv");
    let frf_dir = dir.join("frf");
    let (ok, out, err) = helicon(&[
        "ident",
        "frf",
        log.to_str().unwrap(),
        "--input",
        "S_lon",
        "--output",
        "q,u",
        "--conditioned-on",
        "S_col,S_lat,S_tr",
        "--omega-min",
        "1.5",
        "--omega-max",
        "25",
        "--points",
        "60",
        "--out",
        frf_dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    println!("{out}{err}");
    assert!(
        err.contains(
            "57.000 s window holds 2.89 effective averages, fewer than the 4 inputs need: left out"
        ),
        "{err}"
    );
    assert!(out.contains("windows 28.500/14.250/7.125/3.562 s"), "{out}");
    let q = frf_rows(&frf_dir.join("frf.csv"), "q");

    // The library on the same columns and windows.
    let names = ["S_lon", "S_col", "S_lat", "S_tr", "q", "t_s"];
    let cols = columns(&log, &names);
    let n = cols[0].len();
    // the CLI's sample time: the median step of the time column
    let mut steps: Vec<f64> = cols[5].windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let dt = steps[steps.len() / 2];
    let chans: Vec<&[f64]> = cols[..5].iter().map(Vec::as_slice).collect();
    let grid = log_grid(1.5, 25.0, 60).unwrap();
    let lens: Vec<usize> = (2..=5).map(|k| n >> k).collect();
    let parts: Vec<_> = lens
        .iter()
        .map(|&l| {
            let cs = cross_spectra_grid(&chans, dt, WindowSpec::half_overlap(l), &grid).unwrap();
            conditioned(&cs, &[0, 1, 2, 3], 4).unwrap().0.swap_remove(0)
        })
        .collect();
    let secs: Vec<f64> = lens.iter().map(|l| *l as f64 * dt).collect();
    let lib = composite(&parts, &secs).unwrap();
    assert_eq!(lib.len(), q.len());
    let mut worst = 0.0_f64;
    for (k, row) in q.iter().enumerate() {
        assert!((row.0 - lib.omega_rad_s[k]).abs() < 1e-12 * row.0);
        worst = worst.max((row.1 - lib.h[k]).norm() / lib.h[k].norm());
        assert!(
            (row.2 - lib.coherence[k]).abs() < 1e-12,
            "{} {}",
            row.2,
            lib.coherence[k]
        );
    }
    println!("CLI against the library: worst relative difference {worst:.2e}");
    // the CSV holds dB and degrees printed to round trip: only the
    // conversions' round-off remains
    assert!(worst < 1e-12, "{worst}");

    // Against the linearised hover model at the flown trim (ZOH at the
    // control rate), as crates/sim/tests/excitation.rs does.
    let s = helicon_sim::scenario::Scenario::from_file(&scenario_path()).unwrap();
    let p = helicon_sim::closed_loop::prepare(&s).unwrap();
    let ts = p.gains.set.sample_time_s;
    let lm = linearize(
        &p.model,
        &p.trim.x,
        &p.trim.u,
        &Vector3::zeros(),
        InflowMode::Converged,
    )
    .unwrap();
    let (phi, gamma) = lm.discretize(ts).unwrap();
    let ns = phi.nrows();
    let row = REDUCED_STATE_NAMES.iter().position(|s| *s == "q").unwrap();
    let e: Vec<f64> = q
        .iter()
        .filter(|r| r.2 > 0.6)
        .map(|&(w, h_est, _, eps)| {
            let z = Complex64::from_polar(1.0, w * ts);
            let m = DMatrix::from_fn(ns, ns, |i, j| {
                (if i == j { z } else { Complex64::new(0.0, 0.0) })
                    - Complex64::new(phi[(i, j)], 0.0)
            });
            let g = DVector::from_fn(ns, |i, _| Complex64::new(gamma[(i, 2)], 0.0));
            let h = m.lu().solve(&g).unwrap()[row];
            (h_est - h).norm() / (h.norm() * eps)
        })
        .collect();
    let (p50, p95) = (percentile(&e, 0.5), percentile(&e, 0.95));
    println!(
        "q/S_lon via the CLI: {} of {} points with γ² > 0.6, normalised error median {p50:.3} p95 {p95:.3}",
        e.len(),
        q.len()
    );
    assert!(e.len() * 10 >= q.len() * 9, "{}", e.len());
    assert!(p50 > 0.5 && p50 < 1.8, "{p50}");
    assert!(p95 < 3.5, "{p95}");

    // --max-window-s leaves the long windows out; nothing left is refused
    // naming the options to change.
    let (ok, out, err) = helicon(&[
        "ident",
        "frf",
        log.to_str().unwrap(),
        "--input",
        "S_lon",
        "--output",
        "q",
        "--conditioned-on",
        "S_col,S_lat,S_tr",
        "--max-window-s",
        "10",
        "--out",
        dir.join("frf10").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(err.contains("longer than --max-window-s 10"), "{err}");
    assert!(out.contains("windows 7.125/3.562 s"), "{out}");
    let (ok, _, err) = helicon(&[
        "ident",
        "frf",
        log.to_str().unwrap(),
        "--input",
        "S_lon",
        "--output",
        "q",
        "--conditioned-on",
        "S_col,S_lat,S_tr",
        "--windows",
        "1",
        "--out",
        dir.join("frf1").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("no window qualifies") && err.contains("--windows"),
        "{err}"
    );
    for bad in ["0", "-3", "nan"] {
        let (ok, _, err) = helicon(&[
            "ident",
            "frf",
            log.to_str().unwrap(),
            "--input",
            "S_lon",
            "--output",
            "q",
            "--max-window-s",
            bad,
            "--out",
            dir.join("frfbad").to_str().unwrap(),
        ]);
        assert!(!ok && err.contains("--max-window-s"), "{bad}: {err}");
    }

    // A quasi-steady u–q–θ model fitted to the flown q and u responses.
    let model = dir.join("model.toml");
    std::fs::write(&model, flown_model()).unwrap();
    let (ok, out, err) = helicon(&[
        "ident",
        "ss",
        model.to_str().unwrap(),
        "--out",
        dir.join("ss").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    println!("{out}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ss/ss_fit.json")).unwrap())
            .unwrap();
    let cost = doc["cost"].as_f64().unwrap();
    assert!(cost < 20.0, "{cost}");
    let par = |name: &str| {
        doc["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap()
            .clone()
    };
    // the pitch damping and control derivative meet the guidelines
    for name in ["M_q", "M_lon", "tau"] {
        assert_eq!(par(name)["meets_guidelines"], true, "{name}");
    }
    assert!(par("M_q")["value"].as_f64().unwrap() < 0.0);
    assert!(dir.join("ss/ss_S_lon_q.png").exists() && dir.join("ss/ss_S_lon_u.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The shipped hover longitudinal model (examples/ident), its response files
/// pointed at the test's `frf/frf.csv`.
fn flown_model() -> String {
    include_str!("../../../examples/ident/hover-longitudinal.toml")
        .replace("../../out/ident/frf/frf.csv", "frf/frf.csv")
}

/// A two-input, two-output model with a shared parameter: exact responses
/// written to two frf.csv files, fitted by `ident ss` from perturbed starts.
const EXACT_MODEL: &str = r#"
states = ["p", "q"]
inputs = ["lat", "lon"]
outputs = ["p", "q"]
min_coherence = 0.5
[A]
p = ["L_p", "K"]
q = ["K", "M_q"]
[B]
p = ["L_lat", 0.5]
q = [0.0, "M_lon"]
[C]
p = [1, 0]
q = [0, 1]
[delay_s]
lon = "tau"
[[parameter]]
name = "L_p"
start = -4.0
[[parameter]]
name = "M_q"
start = -1.0
[[parameter]]
name = "K"
start = 0.3
[[parameter]]
name = "L_lat"
start = 30.0
[[parameter]]
name = "M_lon"
start = 10.0
[[parameter]]
name = "tau"
start = 0.05
min = 0.0
max = 0.5
[[response]]
input = "lat"
output = "p"
frf = "lat/frf.csv"
[[response]]
input = "lon"
output = "q"
frf = "lon/frf.csv"
[[response]]
input = "lon"
output = "p"
frf = "lon/frf.csv"
frf_output = "p_meas"
"#;

#[test]
fn ident_ss_fits_exact_responses_and_writes_the_report() {
    let dir = tmpdir("exact");
    // truth: L_p −6, M_q −2, K 1.5, L_lat 45, M_lon 18, τ 0.03
    let (lp, mq, k, llat, mlon, tau) = (-6.0, -2.0, 1.5, 45.0, 18.0, 0.03);
    let grid = log_grid(0.5, 50.0, 60).unwrap();
    let resp = |w: f64, input: usize, out: usize| {
        let s = Complex64::new(0.0, w);
        let a = DMatrix::from_row_slice(2, 2, &[lp, k, k, mq]).map(|v| Complex64::new(v, 0.0));
        let b =
            DMatrix::from_row_slice(2, 2, &[llat, 0.5, 0.0, mlon]).map(|v| Complex64::new(v, 0.0));
        let m = DMatrix::<Complex64>::identity(2, 2) * s - a;
        let x = m.lu().solve(&b).unwrap();
        let delay = if input == 1 {
            (-s * tau).exp()
        } else {
            Complex64::new(1.0, 0.0)
        };
        x[(out, input)] * delay
    };
    for (sub, input, outs) in [
        ("lat", 0, vec![("p", 0)]),
        ("lon", 1, vec![("q", 1), ("p_meas", 0)]),
    ] {
        let mut text = String::from("output,omega_rad_s,mag_db,phase_deg,coherence,random_error\n");
        for (name, o) in outs {
            let h: Vec<Complex64> = grid.iter().map(|w| resp(*w, input, o)).collect();
            let ph = helicon_ident::frf::unwrap_deg(
                &h.iter().map(|v| v.arg().to_degrees()).collect::<Vec<_>>(),
            );
            for (i, w) in grid.iter().enumerate() {
                writeln!(
                    text,
                    "{name},{w},{},{},0.99,0.01",
                    20.0 * h[i].norm().log10(),
                    ph[i]
                )
                .unwrap();
            }
        }
        std::fs::create_dir_all(dir.join(sub)).unwrap();
        std::fs::write(dir.join(sub).join("frf.csv"), text).unwrap();
    }
    let model = dir.join("model.toml");
    std::fs::write(&model, EXACT_MODEL).unwrap();
    let out_dir = dir.join("out");
    let (ok, out, err) = helicon(&[
        "ident",
        "ss",
        model.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    println!("{out}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("ss_fit.json")).unwrap())
            .unwrap();
    let truth = [lp, mq, k, llat, mlon, tau];
    let params = doc["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 6);
    for (p, t) in params.iter().zip(truth) {
        let v = p["value"].as_f64().unwrap();
        assert!((v - t).abs() < 1e-6 * t.abs(), "{}: {v} vs {t}", p["name"]);
        assert!(p["cramer_rao_pct"].as_f64().unwrap() < 1e-3);
        assert_eq!(p["meets_guidelines"], true);
    }
    assert_eq!(doc["min_coherence"], 0.5);
    assert_eq!(doc["responses"].as_array().unwrap().len(), 3);
    assert_eq!(doc["responses"][2]["frf_output"], "p_meas");
    assert_eq!(doc["correlation"]["matrix"].as_array().unwrap().len(), 6);
    assert_eq!(doc["A"][0][1], doc["A"][1][0]);
    assert_eq!(doc["B"][0][1], 0.5);
    assert!(doc["cost"].as_f64().unwrap() < 1e-10);
    for png in ["ss_lat_p.png", "ss_lon_q.png", "ss_lon_p.png"] {
        assert!(out_dir.join(png).exists(), "{png}");
    }

    // Bad model files: the file and the field named.
    for (from, to, field) in [
        ("q = [\"K\", \"M_q\"]", "q = [\"K\", \"M_qq\"]", "A.q[1]"),
        ("q = [\"K\", \"M_q\"]", "q = [\"K\"]", "A.q"),
        (
            "frf = \"lat/frf.csv\"",
            "frf = \"nowhere/frf.csv\"",
            "response[0].frf",
        ),
        ("start = -4.0", "start = inf", "parameter[0].start"),
    ] {
        let bad = dir.join("bad.toml");
        std::fs::write(&bad, EXACT_MODEL.replacen(from, to, 1)).unwrap();
        let (ok, _, err) = helicon(&[
            "ident",
            "ss",
            bad.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        assert!(!ok);
        assert!(
            err.contains("bad.toml") && err.contains(field),
            "{field}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
