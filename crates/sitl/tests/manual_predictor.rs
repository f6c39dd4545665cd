//! In manual flight the Kalman predictor is told what the servos got (the
//! pilot's sticks), not the idle law's command: its one-step prediction
//! keeps matching the navigation's measurement while the pilot flies off
//! the trim, and handing back to auto finds an estimate without a jump
//! (lock-step SITL, `log.csv`'s `est_*` and `meas_*` columns).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::{Ulog, options, scenario};
use helicon_core::state::Input;
use helicon_sim::closed_loop::{Termination, prepare};
use helicon_sim::log_csv::read_log_csv;
use helicon_sitl as sitl;

const STATES: [&str; 9] = ["phi", "theta", "psi", "u", "v", "w", "p", "q", "r"];

/// RMS of the innovation (measurement − prediction) of each measured state
/// over samples `a..b`.
fn innovation_rms(meas: &[Vec<f64>], est: &[Vec<f64>], a: usize, b: usize) -> [f64; 9] {
    std::array::from_fn(|i| {
        let s: f64 = (a..b).map(|k| (meas[i][k] - est[i][k]).powi(2)).sum();
        (s / (b - a) as f64).sqrt()
    })
}

#[test]
fn the_predictor_is_told_the_pilots_commands_in_manual() {
    let s = scenario("demo.toml", 3.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("manual_predictor");
    // the pilot flies 1 s off the trim (collective up, cyclic and pedal
    // off), then hands back
    o.pilot.manual_from_s = Some(1.0);
    o.pilot.manual_until_s = Some(2.0);
    o.pilot.stick_offset = Input::new(0.01, 0.02, -0.02, 0.02);
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let log = read_log_csv(&r.log_csv).unwrap();
    let meas: Vec<Vec<f64>> = STATES
        .iter()
        .map(|n| log.column(&format!("meas_{n}")).unwrap().to_vec())
        .collect();
    let est: Vec<Vec<f64>> = STATES
        .iter()
        .map(|n| log.column(&format!("est_{n}")).unwrap().to_vec())
        .collect();
    let auto = innovation_rms(&meas, &est, 100, 400);
    let manual = innovation_rms(&meas, &est, 400, 800);
    let handback = innovation_rms(&meas, &est, 800, 900);
    for i in 0..9 {
        eprintln!(
            "{}: auto {:.3e} manual {:.3e} handback {:.3e}",
            STATES[i], auto[i], manual[i], handback[i]
        );
    }
    // the body rates, which the servo input moves within a sample: their
    // innovation in the manual second and the quarter second after the
    // hand-back stays within 1.5× of auto's before. Measured: manual
    // p, q, r 1.00, 0.92, 1.07×, after p, q 0.95, 0.90×; told the law's
    // command instead (the previous behaviour) they were 2.3, 4.8, 4.3×
    // and 2.7, 3.0×.
    for i in 6..9 {
        assert!(manual[i] <= 1.5 * auto[i], "{} in manual", STATES[i]);
    }
    for i in 6..8 {
        assert!(
            handback[i] <= 1.5 * auto[i],
            "{} after the hand-back",
            STATES[i]
        );
    }
    // the predictor was told the pilot's sticks: the on-board control
    // record's command is what the plant got (up to the avionics
    // protocol's 1e-4 counts), not the law's
    let ulog = Ulog::read(&r.ulog);
    for i in 0..4 {
        let c = ulog.f64s("control", &format!("command[{i}]"));
        for k in 400..800 {
            assert!((c[k] - r.received[k][i]).abs() <= 0.5e-4 + 1e-12, "k {k}");
        }
    }
}
