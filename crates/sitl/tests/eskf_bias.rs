//! The ESKF's IMU bias estimates in the on-board log (lock-step SITL,
//! `[estimator] kind = "eskf"`), read back by `px4-ulog`, an independent
//! reader: one `estimator_bias` record per control step, against the
//! biases the simulated IMU was given.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::{Ulog, options, scenario};
use helicon_sim::closed_loop::{Termination, prepare};
use helicon_sim::navigation::sensor_suite_at;
use helicon_sitl as sitl;

#[test]
fn the_ulog_carries_the_eskf_bias_estimates() {
    let s = scenario("beyond-eskf.toml", 6.0);
    let prepared = prepare(&s).unwrap();
    let r = sitl::run(&s, &prepared, &options("eskf_bias")).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let log = Ulog::read(&r.ulog);
    let ts = log.u64s("estimator_bias", "timestamp");
    assert_eq!(ts.len() as u64, r.onboard.steps);
    assert_eq!(ts, log.u64s("control", "timestamp"));
    // the IMU's turn-on biases, drawn from the scenario's seed (the same
    // suite the hardware samples; its random walk over 6 s is 1e-4 of them)
    let suite = sensor_suite_at(
        &s.sensors,
        prepared.gains.set.sample_time_s,
        prepared.model.params().environment.g_m_s2,
    )
    .unwrap();
    let (_, gyro_true) = suite.biases();
    let n = ts.len() - 1;
    for i in 0..3 {
        let b = log.f64s("estimator_bias", &format!("gyro_rad_s[{i}]"));
        let sigma = log.f64s("estimator_bias", &format!("gyro_sigma_rad_s[{i}]"));
        let a = log.f64s("estimator_bias", &format!("accel_m_s2[{i}]"));
        let sa = log.f64s("estimator_bias", &format!("accel_sigma_m_s2[{i}]"));
        assert!(b.iter().chain(&a).all(|v| v.is_finite()));
        // started at zero with the turn-on σ, the σ shrinks
        assert!(b[0].abs().max(a[0].abs()) < 1e-3, "axis {i}");
        assert!(sigma[n] < sigma[0] && sa[n] <= sa[0], "axis {i}");
        // the gyro bias found within 3σ of the truth
        let err = (b[n] - gyro_true[i]).abs();
        eprintln!(
            "gyro bias axis {i}: true {:.5} est {:.5} sigma {:.5} rad/s",
            gyro_true[i], b[n], sigma[n]
        );
        assert!(
            err <= 3.0 * sigma[n],
            "axis {i}: |{err}| > 3σ = {}",
            3.0 * sigma[n]
        );
    }
    // the thesis's navigation estimates no bias: no record
    let d = scenario("demo.toml", 0.5);
    let pd = prepare(&d).unwrap();
    let rd = sitl::run(&d, &pd, &options("no_bias")).unwrap();
    assert!(
        Ulog::read(&rd.ulog)
            .u64s("estimator_bias", "timestamp")
            .is_empty()
    );
}
