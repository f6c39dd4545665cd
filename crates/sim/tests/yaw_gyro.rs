//! The thesis scenarios flown with the yaw-rate gyro on (thesis §3.1.1): the
//! tail input is the gyro's yaw-rate command, the controller is designed on
//! the gyro-augmented model, and the thesis bounds still hold.
//!
//! Both modes are flown with the shipped parameter files: heading hold
//! (`params/yaw-gyro.toml`) and rate mode (`params/yaw-gyro-rate.toml`,
//! Ki = 0, where the 27-state design model is exactly the helicopter as
//! flown). The checks are the gyro-less tests' (`thesis_checks`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod thesis_checks;

use helicon_model::Params;
use helicon_sim::closed_loop::{Flight, Outcome, Termination, fly, prepare, prepare_with_params};
use helicon_sim::scenario::Scenario;
use std::path::Path;

fn scenario(name: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    Scenario::from_file(&path).unwrap()
}

/// The shipped parameter files of the two gyro modes (`helicon sim
/// --params`): heading hold (Ki = 0.8) and rate mode (Ki = 0).
fn gyro_params(file: &str) -> Params {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../params")
        .join(file);
    let p = Params::from_file(&path).unwrap();
    assert!(p.yaw_gyro.is_enabled());
    p
}

const MODES: [&str; 2] = ["yaw-gyro.toml", "yaw-gyro-rate.toml"];

fn rate_mode_gyro() -> Params {
    let p = gyro_params("yaw-gyro-rate.toml");
    assert_eq!(p.yaw_gyro.ki, 0.0);
    p
}

/// Fly every case of a shipped scenario with the gyro parameters `file`;
/// each flight is named `case/file`.
fn fly_with_gyro(scenario_file: &str, file: &str) -> Vec<(String, Flight)> {
    scenario(scenario_file)
        .cases()
        .into_iter()
        .map(|c| {
            let p = prepare_with_params(&c, gyro_params(file)).unwrap();
            // the design is the gyro's: tail trim input at mid-range (0 rad/s)
            assert!((p.gains.set.u_trim[3] - 0.125).abs() < 1e-12);
            let name = format!("{}/{file}", c.name);
            (name, fly(&c, &p, None).unwrap())
        })
        .collect()
}

/// The case name of a `case/file` flight name.
fn case_of(name: &str) -> &str {
    name.split('/').next().unwrap_or(name)
}

#[test]
fn fig_14_5_with_the_gyro_meets_the_thesis_bounds_in_both_modes() {
    // All four steps, ψ = π included, in heading-hold and rate mode: the
    // stepped output settles within 3.5 s of its step with < 5 % overshoot.
    for file in MODES {
        for (name, f) in fly_with_gyro("thesis-fig14-5.toml", file) {
            let (t, os) = thesis_checks::check_fig_14_5(case_of(&name), &f);
            eprintln!("{name}: {t:.3} s, {os:.2} %");
        }
    }
}

/// The peak |S_lat − trim| of a flight (servo units).
fn peak_lateral_cyclic(f: &Flight, trim: f64) -> f64 {
    f.log
        .iter()
        .map(|r| (r.u[1] - trim).abs())
        .fold(0.0, f64::max)
}

#[test]
fn psi_step_diverged_because_the_tail_weight_was_a_servo_deflection() {
    // The cause of the ψ = π divergence with the gyro on: the design weighed
    // the tail input with the thesis's tail-pitch maximum 0.04 (14.27), which
    // as a rate command is 0.24 rad/s. So dear a yaw-rate command made the
    // LQR meet the pincer's heading decay with the cyclic: its ψ gain on
    // S_lat was six times the gyro-less design's, the π step drove the
    // lateral cyclic to its range and rolled the helicopter past 1.2 rad
    // within 0.4 s of the step. Weighing the rate command on its own range
    // gives a ψ → S_lat gain well below the gyro-less one and the step flies.
    let a = scenario("thesis-fig14-5.toml").cases().remove(0);
    assert_eq!(a.reference[0].output, "psi");
    let plain = prepare(&a).unwrap();
    let gyro = rate_mode_gyro();
    let c = gyro.yaw_gyro.max_rate_rad_s / (0.5 * (gyro.servos[3].s_max - gyro.servos[3].s_min));
    let mut old = a.clone();
    old.controller.design.yaw_rate_command_max_rad_s = Some(0.04 * c);
    let (p_old, p_new) = (
        prepare_with_params(&old, gyro).unwrap(),
        prepare_with_params(&a, gyro).unwrap(),
    );
    let k = |p: &helicon_sim::closed_loop::Prepared| p.gains.set.ls[(1, 2)].abs();
    eprintln!(
        "|Ls[S_lat, psi]|: gyro-less {:.4}, gyro with the servo weight {:.4}, with the rate weight {:.4}",
        k(&plain),
        k(&p_old),
        k(&p_new)
    );
    assert!(k(&p_old) > 5.0 * k(&plain));
    assert!(k(&p_new) < 0.5 * k(&plain));
    let f_old = fly(&old, &p_old, None).unwrap();
    assert_eq!(f_old.summary.outcome, Outcome::Diverged);
    assert_eq!(f_old.summary.termination, Termination::AttitudeLimit);
    assert!(f_old.summary.t_end_s < 1.5, "{}", f_old.summary.t_end_s);
    let trim_lat = p_old.trim.u[1];
    let room = (gyro.servos[1].s_max - trim_lat).min(trim_lat - gyro.servos[1].s_min);
    let peak_old = peak_lateral_cyclic(&f_old, trim_lat);
    let f_new = fly(&a, &p_new, None).unwrap();
    let peak_new = peak_lateral_cyclic(&f_new, p_new.trim.u[1]);
    eprintln!(
        "peak |S_lat - trim|: servo weight {peak_old:.3} (room {room:.3}), rate weight {peak_new:.3}"
    );
    assert!(peak_old > 0.85 * room);
    assert!(peak_new < 0.05);
    thesis_checks::check_fig_14_5(&a.name, &f_new);
}

#[test]
fn fig_14_3_with_the_gyro_settles_in_both_modes() {
    for file in MODES {
        for (name, f) in fly_with_gyro("thesis-fig14-3.toml", file) {
            thesis_checks::check_fig_14_3(&name, &f);
        }
    }
}

#[test]
fn fig_14_8_with_the_gyro_tracks_in_the_thesis_wind() {
    for (name, f) in fly_with_gyro("thesis-fig14-8.toml", "yaw-gyro.toml") {
        thesis_checks::check_fig_14_8(case_of(&name), &f);
    }
}

#[test]
fn appendix_f_with_the_gyro() {
    // With the gyro the tail input is a rate command weighed on its own
    // range, so the appendix's two tail weights (14.24) and 1/1.0² give the
    // same design; what carries over is the inflow: the thesis's iteration
    // still breaks down (the gyro drives the tail servo as hard as the
    // thesis's law did), the converged solver flies. Appendix F states no
    // settling time; the gyro-less test holds ψ to 3 s (it settles in
    // 2.34 s with 31 % overshoot). With the gyro ψ settles in 3.21 s (heading
    // hold) and 3.24 s (rate mode) with 17–21 % overshoot: the bound here is
    // the thesis's heading bound of Figure 14.5, 3.5 s, and the overshoot
    // below the gyro-less flight's.
    let plain = scenario("thesis-appendix-f.toml").cases().remove(1);
    let f_plain = fly(&plain, &prepare(&plain).unwrap(), None).unwrap();
    let os_plain = f_plain.summary.metrics["psi"].overshoot_pct;
    for file in MODES {
        let flights = fly_with_gyro("thesis-appendix-f.toml", file);
        assert_eq!(flights.len(), 4);
        for (name, f) in flights {
            if case_of(&name).ends_with("thesis-inflow") {
                thesis_checks::check_appendix_f_thesis_inflow(&name, &f);
            } else {
                let (t, os) = thesis_checks::check_appendix_f_converged(&name, &f, 3.5);
                eprintln!(
                    "{name}: psi settles in {t:.3} s, overshoot {os:.1} % (gyro-less {os_plain:.1} %)"
                );
                assert!(os < os_plain, "{name}: {os} against {os_plain}");
            }
        }
    }
}

#[test]
fn gyro_off_leaves_the_flight_bit_identical() {
    // `enabled = false` with other gyro gains: the same flight to the bit
    let c = scenario("thesis-fig14-5.toml").cases().remove(1);
    let mut p = Params::bergen_twin();
    p.yaw_gyro.kp_s = 3.0;
    p.yaw_gyro.ki = 7.0;
    let a = fly(&c, &prepare(&c).unwrap(), None).unwrap();
    let b = fly(&c, &prepare_with_params(&c, p).unwrap(), None).unwrap();
    assert_eq!(a.log.len(), b.log.len());
    for (ra, rb) in a.log.iter().zip(&b.log) {
        assert_eq!(format!("{ra:?}"), format!("{rb:?}"));
    }
}

#[test]
fn gains_designed_without_the_gyro_are_refused_with_it_on() {
    let mut c = scenario("thesis-fig14-5.toml").cases().remove(1);
    let plain = prepare(&c).unwrap();
    let dir = std::env::temp_dir().join(format!("helicon-gyro-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("plain-gains.json");
    plain.gains.save(&file).unwrap();
    c.controller.gains_file = Some(file.clone());
    let Err(e) = prepare_with_params(&c, rate_mode_gyro()) else {
        panic!("gyro-less gains flown with the gyro on");
    };
    let msg = e.to_string();
    assert!(
        msg.contains("plain-gains.json") && msg.contains("yaw_gyro.enabled"),
        "{msg}"
    );
    // the gyro's own design, saved and loaded, is accepted
    let gyro = prepare_with_params(&c_without_file(&c), rate_mode_gyro()).unwrap();
    gyro.gains.save(&file).unwrap();
    assert!(prepare_with_params(&c, rate_mode_gyro()).is_ok());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn c_without_file(c: &Scenario) -> Scenario {
    let mut c = c.clone();
    c.controller.gains_file = None;
    c
}
