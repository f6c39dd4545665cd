//! The thesis scenarios flown with the yaw-rate gyro on (thesis §3.1.1): the
//! tail input is the gyro's yaw-rate command, the controller is designed on
//! the gyro-augmented model, and the thesis bounds still hold.
//!
//! Rate mode (Ki = 0): the 27-state design model is then exactly the
//! helicopter as flown with the gyro. Known gap (docs/envelope.md): the
//! ψ = π step of Figure 14.5 (case a) diverges with the gyro on, and in
//! heading-hold mode (Ki > 0, integrator not in the design model) the
//! east-velocity step overshoots 7.7 % (> 5 %).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use helicon_model::Params;
use helicon_sim::closed_loop::{Outcome, fly, prepare, prepare_with_params};
use helicon_sim::scenario::Scenario;
use std::path::Path;

fn scenario(name: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    Scenario::from_file(&path).unwrap()
}

fn rate_mode_gyro() -> Params {
    let mut p = Params::bergen_twin();
    p.yaw_gyro.enabled = 1.0;
    p.yaw_gyro.ki = 0.0;
    p
}

#[test]
fn fig_14_5_velocity_steps_with_the_rate_gyro_settle_within_3_5_s() {
    for c in scenario("thesis-fig14-5.toml").cases() {
        let name = &c.name;
        let stepped = if name.ends_with("-b") {
            "vn"
        } else if name.ends_with("-c") {
            "ve"
        } else if name.ends_with("-d") {
            "vd"
        } else {
            continue; // case a (ψ = π): the known gap
        };
        let p = prepare_with_params(&c, rate_mode_gyro()).unwrap();
        // the design is the gyro's: tail trim input at mid-range (0 rad/s)
        assert!((p.gains.set.u_trim[3] - 0.125).abs() < 1e-12);
        let f = fly(&c, &p, None).unwrap();
        assert_eq!(f.summary.outcome, Outcome::Completed, "{name}");
        let m = &f.summary.metrics[stepped];
        eprintln!(
            "{name} (rate gyro): {stepped} settles in {:?} s, overshoot {:.2} %",
            m.settling_time_s, m.overshoot_pct
        );
        // the thesis bounds of Figure 14.5 (as tests/closed_loop.rs)
        assert!(m.settling_time_s.unwrap() <= 3.5, "{name}: {m:?}");
        assert!(m.overshoot_pct < 5.0, "{name}: {m:?}");
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
