//! `[[excitation]]` in scenarios: the servo offsets reach the plant through
//! the flight computer (before saturation, logged), open loop and closed
//! loop, bad entries are refused naming file and field, and the shipped
//! identification flight (`scenarios/ident-hover-sweep.toml`: sweeps on S_lon
//! then S_lat in hover, the whole on-board chain with sensor noise, light
//! Dryden turbulence) gives frequency responses that match the linearised
//! hover model within their random error where γ² > 0.6.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::Complex64;
use helicon_ident::frf::{WindowSpec, conditioned, cross_spectra_grid, log_grid};
use helicon_ident::inputs::Sweep;
use helicon_model::linearize::linearize;
use helicon_model::{InflowMode, REDUCED_STATE_NAMES};
use helicon_sim::closed_loop::{Flight, Outcome, fly, prepare, servo_limits};
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
    let lim = servo_limits(p.model.params());
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
    assert!(tr_clipped > 0, "the 0.5 rad 3211 must reach the tail servo limit");
}

#[test]
fn bad_excitation_entries_name_the_file_and_field() {
    let cases = [
        ("servo = \"S_yaw\"\nt_s = 0.0\ninput = { kind = \"doublet\", amplitude = 0.01, pulse_s = 0.5 }", "excitation[0].servo"),
        ("servo = \"S_lon\"\nt_s = -1.0\ninput = { kind = \"doublet\", amplitude = 0.01, pulse_s = 0.5 }", "excitation[0].t_s"),
        ("servo = \"S_lon\"\ninput = { kind = \"sweep\", amplitude = 0.01, omega_min_rad_s = 1.0, omega_max_rad_s = 30.0, duration_s = 10.0 }", "excitation[0].input.duration_s"),
        ("servo = \"S_lon\"\ninput = { kind = \"doublet\", amplitude = nan, pulse_s = 0.5 }", "excitation[0].input.amplitude"),
    ];
    for (entry, field) in cases {
        let text = format!("duration_s = 1.0\n[[excitation]]\n{entry}\n");
        let e = Scenario::from_toml_str(&text, "bad.toml").unwrap_err().to_string();
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

/// The shipped identification flight: S_lon → q and S_lat → p, conditioned
/// on the four servos, against the linearised hover model's
/// C(zI − Φ)⁻¹Γ (ZOH at the control rate) where γ² > 0.6.
#[test]
fn ident_hover_sweep_matches_the_linearised_model_within_its_random_error() {
    let s = shipped();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(f.summary.outcome, Outcome::Completed, "{:?}", f.summary.reason);
    let ts = p.gains.set.sample_time_s;
    // the logged excitation is the scenario's sweep
    let sweep = Sweep::new(0.02, 1.0, 30.0, 40.0).unwrap();
    for r in &f.log {
        assert_eq!(r.excitation[2], sweep.value(r.t_s - 2.0));
        assert_eq!(r.excitation[1], sweep.value(r.t_s - 48.0));
    }
    let lm = linearize(&p.model, &p.trim.x, &p.trim.u, &Vector3::zeros(), InflowMode::Converged).unwrap();
    let (phi, gamma) = lm.discretize(ts).unwrap();
    let n = phi.nrows();
    let names = ["S_col", "S_lat", "S_lon", "S_tr", "p", "q"];
    let chans: Vec<Vec<f64>> = names.iter().map(|c| column(&f, c)).collect();
    let refs: Vec<&[f64]> = chans.iter().map(Vec::as_slice).collect();
    let grid = log_grid(1.5, 25.0, 60).unwrap();
    // 10 s Hann windows, half overlap: ~17 windows over the 92 s flight
    let spec = WindowSpec::half_overlap((10.0 / ts).round() as usize);
    let cs = cross_spectra_grid(&refs, ts, spec, &grid).unwrap();
    let mut all = Vec::new();
    for (servo, out, out_name) in [(2usize, 5usize, "q"), (1, 4, "p")] {
        let row = REDUCED_STATE_NAMES.iter().position(|s| *s == out_name).unwrap();
        let (frfs, _) = conditioned(&cs, &[0, 1, 2, 3], out).unwrap();
        let fr = &frfs[servo];
        let mut e = Vec::new();
        for k in 0..fr.len() {
            if fr.coherence[k] <= 0.6 {
                continue;
            }
            let z = Complex64::from_polar(1.0, fr.omega_rad_s[k] * ts);
            let m = DMatrix::from_fn(n, n, |i, j| {
                (if i == j { z } else { Complex64::new(0.0, 0.0) }) - Complex64::new(phi[(i, j)], 0.0)
            });
            let g = DVector::from_fn(n, |i, _| Complex64::new(gamma[(i, servo)], 0.0));
            let h = m.lu().solve(&g).unwrap()[row];
            e.push((fr.h[k] - h).norm() / (h.norm() * fr.random_error[k]));
        }
        let (p50, p95) = (percentile(&e, 0.5), percentile(&e, 0.95));
        println!(
            "{out_name}/{}: {} of {} points with γ² > 0.6, normalised error median {p50:.3} p95 {p95:.3}",
            names[servo],
            e.len(),
            fr.len()
        );
        assert!(e.len() > 30, "{out_name}: {} points with γ² > 0.6", e.len());
        all.push((p50, p95));
    }
    for (p50, p95) in all {
        // Rayleigh with σ = 1 if ε is right: median 1.18, p95 2.45
        assert!(p50 < 1.8, "median {p50}");
        assert!(p95 < 3.5, "p95 {p95}");
    }
}
