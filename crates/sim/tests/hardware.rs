//! The hardware stepping API (`Hardware`: sense, actuate) driven by the
//! shared on-board constructor reproduces `fly` exactly: the same order of
//! wind, sensors, flight software and plant, so a software-in-the-loop run
//! differs from `helicon sim` only by what its transports do to the numbers.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_sim::closed_loop::{Hardware, LogRow, flight_computer, fly, prepare};
use helicon_sim::scenario::Scenario;
use std::path::Path;

fn demo(duration_s: f64) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml");
    let mut s = Scenario::from_file(&path).unwrap();
    s.duration_s = duration_s;
    s.log.decimation = 1;
    s
}

#[test]
fn hardware_steps_reproduce_fly_bit_for_bit() {
    let scenario = demo(3.0);
    let prepared = prepare(&scenario).unwrap();
    let flown = fly(&scenario, &prepared, None).unwrap();
    let mut hw = Hardware::new(&scenario, &prepared).unwrap();
    let x0 = *hw.state();
    let mut computer = flight_computer(&prepared.onboard_setup(&scenario, &x0)).unwrap();
    let mut rows = Vec::new();
    while let Some(sample) = hw.sense() {
        let tel = computer.step(&sample.frame, &sample.reference).unwrap();
        let step = hw.actuate(&tel.command, Some(&tel)).unwrap();
        rows.push(step.row);
        if step.end.is_some() {
            break;
        }
    }
    assert_eq!(rows.len(), flown.log.len());
    assert_eq!(rows.len(), 1201);
    for (a, b) in rows.iter().zip(&flown.log) {
        // The IMU health monitor is flight software that `fly` runs beside the
        // flight computer; the hardware does not see it (its columns stay 0).
        assert_eq!(a.imu_health, [0.0; 3]);
        let b = LogRow {
            imu_health: [0.0; 3],
            excitation: [0.0; 4],
            ..*b
        };
        assert_eq!(*a, b, "row at t = {}", a.t_s);
    }
    let s = hw.summary();
    assert_eq!(s.termination, flown.summary.termination);
    assert_eq!(
        serde_json::to_string(&s).unwrap(),
        serde_json::to_string(&flown.summary).unwrap()
    );
}
