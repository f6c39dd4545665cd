//! `[[excitation]]` in scenarios: the servo offsets reach the plant through
//! the flight computer (before saturation, logged), open loop and closed
//! loop, bad entries are refused naming file and field, and the shipped
//! identification flight (`scenarios/ident-hover-sweep.toml`: sweeps on S_lon
//! then S_lat in hover, the whole on-board chain with sensor noise, light
//! Dryden turbulence) gives frequency responses that match the linearised
//! hover model within their random error where γ² > 0.6.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::Complex64;
use helicon_ident::frf::{WindowSpec, composite, conditioned, cross_spectra_grid, log_grid};
use helicon_ident::inputs::Sweep;
use helicon_model::linearize::linearize;
use helicon_model::{InflowMode, REDUCED_STATE_NAMES};
use helicon_sim::closed_loop::{Flight, Outcome, fly, prepare};
use helicon_sim::log_csv::log_column;
use helicon_sim::scenario::Scenario;
use nalgebra::{DMatrix, DVector, Vector3};
use std::path::Path;

fn shipped() -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ident-hover-sweep.toml");
    Scenario::from_file(&path).unwrap()
}

fn column(f: &Flight, name: &str) -> Vec<f64> {
    let c = log_column(name).unwrap();
    f.log.iter().map(|r| c.value(r)).collect()
}

fn percentile(v: &[f64], p: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = ((p * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

const HOVER_OPEN_LOOP: &str = r#"
duration_s = 3.0
[controller]
feedback = false
estimator = false
[[excitation]]
servo = "S_lon"
t_s = 0.5
input = { kind = "doublet", amplitude = 0.01, pulse_s = 0.5 }
[[excitation]]
servo = "S_tr"
t_s = 1.0
input = { kind = "3211", amplitude = 0.5, pulse_s = 0.25 }
"#;

#[test]
fn open_loop_holds_trim_plus_excitation_and_saturates_before_sending() {
    let s = Scenario::from_toml_str(HOVER_OPEN_LOOP, "open.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    let u_trim = p.trim.u;
    let lim = p.model.params().servo_limits();
    let (mut lon_seen, mut tr_clipped) = (0.0_f64, 0);
    for r in &f.log {
        // the logged excitation is the ident input at the time since its start
        let lon = helicon_ident::inputs::Doublet {
            amplitude: 0.01,
            pulse_s: 0.5,
        }
        .value(r.t_s - 0.5);
        assert_eq!(r.excitation[2], lon, "t = {}", r.t_s);
        assert_eq!(r.excitation[0], 0.0);
        // open loop: the command is trim + excitation, exactly, unless clipped
        assert_eq!(r.u[2], u_trim[2] + lon, "t = {}", r.t_s);
        let tr = u_trim[3] + r.excitation[3];
        if !(lim.min[3]..=lim.max[3]).contains(&tr) {
            tr_clipped += 1;
            assert_eq!(r.u[3], tr.clamp(lim.min[3], lim.max[3]));
        } else {
            assert_eq!(r.u[3], tr);
        }
        lon_seen = lon_seen.max(r.excitation[2].abs());
    }
    assert_eq!(lon_seen, 0.01);
    assert!(
        tr_clipped > 0,
        "the 0.5 rad 3211 must reach the tail servo limit"
    );
}

#[test]
fn bad_excitation_entries_name_the_file_and_field() {
    let cases = [
        (
            "servo = \"S_yaw\"\nt_s = 0.0\ninput = { kind = \"doublet\", amplitude = 0.01, pulse_s = 0.5 }",
            "excitation[0].servo",
        ),
        (
            "servo = \"S_lon\"\nt_s = -1.0\ninput = { kind = \"doublet\", amplitude = 0.01, pulse_s = 0.5 }",
            "excitation[0].t_s",
        ),
        (
            "servo = \"S_lon\"\ninput = { kind = \"sweep\", amplitude = 0.01, omega_min_rad_s = 1.0, omega_max_rad_s = 30.0, duration_s = 10.0 }",
            "excitation[0].input.duration_s",
        ),
        (
            "servo = \"S_lon\"\ninput = { kind = \"doublet\", amplitude = nan, pulse_s = 0.5 }",
            "excitation[0].input.amplitude",
        ),
    ];
    for (entry, field) in cases {
        let text = format!("duration_s = 1.0\n[[excitation]]\n{entry}\n");
        let e = Scenario::from_toml_str(&text, "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.toml") && e.contains(field), "{field}: {e}");
    }
    let e = Scenario::from_toml_str(
        "duration_s = 1.0\n[[excitation]]\nservo = \"S_lon\"\ngain = 2\ninput = { kind = \"doublet\", amplitude = 0.01, pulse_s = 0.5 }\n",
        "bad.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("bad.toml") && e.contains("gain"), "{e}");
}

/// The pairs compared: (servo index, log channel index, output name).
const PAIRS: [(usize, usize, &str); 2] = [(2, 5, "q"), (1, 4, "p")];

/// Fly the shipped identification scenario with the wind and sensor seed
/// `seed` and return, for each of [`PAIRS`], the normalised errors
/// |Ĥ − H| / (|H| ε) where γ² > 0.6 (and the number of grid points).
fn normalised_errors(seed: u64) -> Vec<(Vec<f64>, usize)> {
    let mut s = shipped();
    s.wind.seed = seed;
    s.sensors.seed = seed;
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(
        f.summary.outcome,
        Outcome::Completed,
        "{:?}",
        f.summary.reason
    );
    let ts = p.gains.set.sample_time_s;
    // the logged excitation is the scenario's sweeps (S_lon first, S_lat second)
    let sweep = Sweep::new(0.02, 1.2, 30.0, 27.0).unwrap();
    for r in &f.log {
        assert_eq!(r.excitation[2], sweep.value(r.t_s - 1.0));
        assert_eq!(r.excitation[1], sweep.value(r.t_s - 29.0));
    }
    // the reference: the linearised hover model at the flown trim, ZOH at
    // the control rate, C (zI − Φ)⁻¹ Γ
    let lm = linearize(
        &p.model,
        &p.trim.x,
        &p.trim.u,
        &Vector3::zeros(),
        InflowMode::Converged,
    )
    .unwrap();
    let (phi, gamma) = lm.discretize(ts).unwrap();
    let n = phi.nrows();
    let names = ["S_col", "S_lat", "S_lon", "S_tr", "p", "q"];
    let chans: Vec<Vec<f64>> = names.iter().map(|c| column(&f, c)).collect();
    let refs: Vec<&[f64]> = chans.iter().map(Vec::as_slice).collect();
    let grid = log_grid(1.5, 25.0, 60).unwrap();
    // CIFER practice: the composite of several window lengths (the long
    // ones for the low frequencies), Hann, half overlap.
    let windows_s = [24.0, 12.0, 6.0];
    let spectra: Vec<_> = windows_s
        .iter()
        .map(|w| {
            let spec = WindowSpec::half_overlap((w / ts).round() as usize);
            cross_spectra_grid(&refs, ts, spec, &grid).unwrap()
        })
        .collect();
    PAIRS
        .iter()
        .map(|&(servo, out, out_name)| {
            let row = REDUCED_STATE_NAMES
                .iter()
                .position(|s| *s == out_name)
                .unwrap();
            // conditioned on all four servos: the law moves them all
            let parts: Vec<_> = spectra
                .iter()
                .map(|cs| {
                    conditioned(cs, &[0, 1, 2, 3], out)
                        .unwrap()
                        .0
                        .swap_remove(servo)
                })
                .collect();
            let fr = composite(&parts, &windows_s).unwrap();
            let e: Vec<f64> = (0..fr.len())
                .filter(|&k| fr.coherence[k] > 0.6)
                .map(|k| {
                    let z = Complex64::from_polar(1.0, fr.omega_rad_s[k] * ts);
                    let m = DMatrix::from_fn(n, n, |i, j| {
                        (if i == j { z } else { Complex64::new(0.0, 0.0) })
                            - Complex64::new(phi[(i, j)], 0.0)
                    });
                    let g = DVector::from_fn(n, |i, _| Complex64::new(gamma[(i, servo)], 0.0));
                    let h = m.lu().solve(&g).unwrap()[row];
                    (fr.h[k] - h).norm() / (h.norm() * fr.random_error[k])
                })
                .collect();
            println!(
                "seed {seed} {out_name}/{}: {} of {} points with γ² > 0.6, normalised error median {:.3} p95 {:.3}",
                names[servo],
                e.len(),
                fr.len(),
                percentile(&e, 0.5),
                percentile(&e, 0.95)
            );
            (e, fr.len())
        })
        .collect()
}

/// The shipped identification flight (seed 3) and two other turbulence and
/// sensor-noise realisations: S_lon → q and S_lat → p, conditioned on the
/// four servos, against the linearised hover model where γ² > 0.6. The
/// normalised error is Rayleigh with σ = 1 if the estimate is unbiased and
/// ε right (median 1.18, p95 2.45); the percentiles are of the three flights
/// pooled (one flight's 60 correlated grid points give a noisy p95: 4.2 for
/// p at seed 3 alone, from a 10–14 % low magnitude below 2.3 rad/s).
#[test]
fn ident_hover_sweep_matches_the_linearised_model_within_its_random_error() {
    let mut pooled = vec![Vec::new(); PAIRS.len()];
    for seed in [1, 2, 3] {
        for (i, (e, points)) in normalised_errors(seed).into_iter().enumerate() {
            // γ² > 0.6 over most of the band 1.5–25 rad/s
            assert!(
                e.len() * 10 >= points * 9,
                "{}: {} of {points}",
                PAIRS[i].2,
                e.len()
            );
            pooled[i].extend(e);
        }
    }
    for (i, e) in pooled.iter().enumerate() {
        let (p50, p95) = (percentile(e, 0.5), percentile(e, 0.95));
        println!("pooled {}: median {p50:.3} p95 {p95:.3}", PAIRS[i].2);
        // within the random error as a distribution: the ident crate's bounds
        assert!(p50 > 0.5 && p50 < 1.8, "{}: median {p50}", PAIRS[i].2);
        assert!(p95 < 3.5, "{}: p95 {p95}", PAIRS[i].2);
    }
}
