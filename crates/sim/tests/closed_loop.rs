//! The closed loop against the thesis's experiments (chapters 14–15, Appendix
//! F) and beyond them (issue 6). Each test flies the shipped scenario files,
//! so what is tested is what users run with `helicon sim`.
//!
//! Where the thesis's own claim is not reproduced with its printed weights
//! (Figure 14.3's "all settle within 2 s"), the test asserts what the model
//! actually does and docs/closed-loop.md gives the numbers and the reason.
#![allow(clippy::too_many_lines, clippy::panic, clippy::cast_possible_wrap)] // tests: long scenarios, panics are failures
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod thesis_checks;

use helicon_sim::closed_loop::{Flight, Outcome, fly, prepare};
use helicon_sim::scenario::{OUTPUTS, Scenario};
use std::path::Path;

fn scenario(name: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    Scenario::from_file(&path).unwrap()
}

fn fly_all(s: &Scenario) -> Vec<(String, Flight)> {
    s.cases()
        .into_iter()
        .map(|c| {
            let p = prepare(&c).unwrap();
            let f = fly(&c, &p, None).unwrap();
            (c.name.clone(), f)
        })
        .collect()
}

#[test]
fn fig_14_3_unit_initial_conditions_settle() {
    // Thesis: every output settles within 1 % before 2 s. With the printed
    // weights (14.23), (14.27), ρ = 10, our design settles every output within
    // 1.55–3.25 s (docs: ρ ≈ 0.3 would be needed for 2 s; the literal reading
    // of the thesis's dlqr call, without ρ, gives ≤ 2.3 s). Bound: 3.5 s, well
    // inside the thesis's 5 s specification (§14.2) that α guarantees.
    for (name, f) in fly_all(&scenario("thesis-fig14-3.toml")) {
        thesis_checks::check_fig_14_3(&name, &f);
    }
}

#[test]
fn fig_14_5_steps_settle_within_3_5_s() {
    // The stepped output settles within 3.5 s of its step with < 5 %
    // overshoot (thesis_checks::check_fig_14_5); the coupled outputs stay
    // within 0.3 m/s of their references (ψ case: vd dips 1.07 m/s while the
    // main rotor yaws the helicopter).
    for (name, f) in fly_all(&scenario("thesis-fig14-5.toml")) {
        thesis_checks::check_fig_14_5(&name, &f);
    }
}

#[test]
fn fig_14_8_tracking_in_the_thesis_wind() {
    // With the thesis wind (2 Hz gust up to 2 m/s, turbulence) 1 % settling is
    // not defined; the thesis judged tracking from its plots and could fly only
    // 1.5 m/s on the vertical axis. We fly 2 m/s on every axis
    // (thesis_checks::check_fig_14_8).
    for (name, f) in fly_all(&scenario("thesis-fig14-8.toml")) {
        thesis_checks::check_fig_14_8(&name, &f);
    }
}

#[test]
fn appendix_f_reproduced_and_solved() {
    // Thesis Appendix F: a 1 rad yaw initial condition with the original tail
    // weight (14.24) made the closed loop unstable. With the thesis's inflow
    // computation (7 plain Newton–Raphson steps per evaluation, warm-started),
    // the tail-rotor iteration breaks down as the tail thrust drops, the force
    // reverses and the helicopter spins away within a second; the converged
    // solver flies the same controller, and the more aggressive 1/1.0² too.
    let flights = fly_all(&scenario("thesis-appendix-f.toml"));
    for (name, f) in &flights {
        println!(
            "{name}: {:?} {:?} at {:.3} s",
            f.summary.outcome, f.summary.reason, f.summary.t_end_s
        );
        if name.ends_with("thesis-inflow") {
            thesis_checks::check_appendix_f_thesis_inflow(name, f);
        } else {
            thesis_checks::check_appendix_f_converged(name, f, 3.0);
        }
    }
    assert_eq!(flights.len(), 4);
}

#[test]
fn beyond_physical_turbulence_sensors_fusion_estimator_20_seeds() {
    // Physical preset, Dryden (light) + 2 m/s mean wind, sensor noise, fusion
    // and the estimator in the loop, no truth feedback: 60 s of 2 m/s steps on
    // each axis and a half turn, for 20 wind/sensor seeds: all complete.
    let base = scenario("beyond-physical-turbulence.toml");
    let mut worst = [0.0f64; 4];
    for seed in 0..20u64 {
        let mut s = base.clone();
        s.wind.seed = 1000 + seed;
        s.sensors.seed = 2000 + seed;
        let p = prepare(&s).unwrap();
        let f = fly(&s, &p, None).unwrap();
        assert_eq!(
            f.summary.outcome,
            Outcome::Completed,
            "seed {seed}: {:?}",
            f.summary.reason
        );
        for (j, out) in OUTPUTS.iter().enumerate() {
            worst[j] = worst[j].max(f.summary.metrics[*out].rms_error);
        }
    }
    println!("worst tracking RMS over 20 seeds [vn, ve, vd, psi]: {worst:?}");
    // The 2 m/s / π rad steps dominate the RMS (a step with a ~1.5 s time
    // constant alone contributes ~0.35 m/s over 60 s); turbulence and the
    // navigation errors add the rest. Measured worst: 0.62 m/s, 0.31 rad.
    for (j, w) in worst.iter().enumerate() {
        assert!(*w < if j == 3 { 0.5 } else { 0.8 }, "{}: {w}", OUTPUTS[j]);
    }
}

#[test]
fn divergence_stops_cleanly_and_keeps_the_log() {
    // Open loop (feedback off) on the physical model: the hover is unstable
    // (three unstable poles), so the attitude limit is reached and the run
    // stops with a reason; the log so far is kept, one row per sample.
    let mut s = scenario("thesis-fig14-3.toml").cases()[1].clone(); // vn(0) = 1 m/s
    s.preset = helicon_model::Preset::Physical;
    s.controller.feedback = false;
    s.duration_s = 60.0;
    s.plant.max_attitude_rad = 0.3;
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(f.summary.outcome, Outcome::Diverged);
    let reason = f.summary.reason.clone().unwrap();
    assert!(reason.contains("t = "), "{reason}");
    assert!(f.summary.t_end_s < 60.0);
    let expected_rows = (f.summary.t_end_s / 0.0025).round() as usize + 1;
    assert!(
        (f.log.len() as i64 - expected_rows as i64).abs() <= 1,
        "{} vs {expected_rows}",
        f.log.len()
    );
    assert!(
        f.summary
            .metrics
            .values()
            .all(|m| m.settling_time_s.is_none())
    );
}

#[test]
fn bad_scenarios_name_the_file_and_field() {
    let e = Scenario::from_toml_str("duration_s = -1.0\n", "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("x.toml") && e.contains("duration_s"), "{e}");
    let e = Scenario::from_toml_str("duration_s = 1.0\n[initial]\nbogus = 1.0\n", "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("initial.bogus"), "{e}");
    let e = Scenario::from_toml_str(
        "duration_s = 1.0\n[[reference]]\nt_s = 1\noutput = \"up\"\nvalue = 1\n",
        "x.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("reference[0].output"), "{e}");
    let e = Scenario::from_toml_str("duration_s = 1.0\nspeed = 3\n", "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("speed"), "{e}");
    let e = Scenario::from_toml_str(
        "duration_s = 1.0\n[[case]]\nname = \"a\"\n[[case]]\nname = \"a\"\n",
        "x.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("not unique"), "{e}");
    let e = Scenario::from_toml_str(
        "duration_s = 1.0\n[[case]]\nname = \"a\"\nplant = { substeps = 0 }\n",
        "x.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("case `a`") && e.contains("plant.substeps"),
        "{e}"
    );
}
