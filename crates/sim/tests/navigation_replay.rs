//! One navigation: the sensor frames a closed-loop flight gave its flight
//! software, written to a sensor log, read back and replayed through
//! `replay_navigation` (what `helicon fuse` runs) give the very measured
//! states the flight computer produced in flight, sample for sample.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_sim::closed_loop::{Outcome, fly, prepare};
use helicon_sim::navigation::{
    ReplayInit, ReplayNavigation, imu_noise, replay_navigation, sensor_noise,
};
use helicon_sim::scenario::{EstimatorKind, Scenario};
use helicon_sim::sensor_log::{SensorLogWriter, read_sensor_log};
use std::path::Path;

#[test]
fn fuse_replay_equals_closed_loop_navigation() {
    replay_equals_flight(EstimatorKind::Thesis);
}

#[test]
fn fuse_replay_equals_closed_loop_eskf() {
    replay_equals_flight(EstimatorKind::Eskf);
}

fn replay_equals_flight(kind: EstimatorKind) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml");
    let mut s = Scenario::from_file(&path).unwrap();
    s.estimator.kind = kind;
    s.duration_s = 8.0; // through the 1 s velocity step and the 6 s heading step
    s.log.decimation = 1;
    s.log.sensors = true;
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(f.summary.outcome, Outcome::Completed);
    assert_eq!(f.sensors.len(), f.log.len());

    let dir = std::env::temp_dir().join(format!("helicon-replay-{kind:?}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("sensors.csv");
    let mut w = SensorLogWriter::new(
        std::io::BufWriter::new(std::fs::File::create(&file).unwrap()),
        "sensors.csv",
        "closed-loop replay test",
    )
    .unwrap();
    for row in &f.sensors {
        w.write(row).unwrap();
    }
    w.finish().unwrap();
    let log = read_sensor_log(&file).unwrap();
    // the log reads back bit for bit
    assert_eq!(log.rows, f.sensors);

    let g = p.model.params().environment.g_m_s2;
    let noise = sensor_noise(&s.sensors, g);
    let mut k = 0;
    let mut worst = 0.0f64;
    replay_navigation(
        &log,
        match kind {
            EstimatorKind::Thesis => ReplayNavigation::Thesis(&s.navigation),
            EstimatorKind::Eskf => ReplayNavigation::Eskf(&s.estimator.eskf, imu_noise(&s.sensors)),
        },
        &noise,
        ReplayInit::Truth,
        |row, y, _| {
            let flown = &f.log[k];
            assert_eq!(flown.t_s, row.frame.t_s);
            for i in 0..9 {
                worst = worst.max((y[i] - flown.measured9[i]).abs());
            }
            k += 1;
            Ok::<(), ()>(())
        },
    )
    .unwrap()
    .unwrap();
    assert_eq!(k, f.log.len());
    // The replay's step is the log's mean step, (t_end − t_0)/(n − 1), which
    // may differ from the flown 0.0025 s in the last bit; 1e-12 bounds that.
    assert!(
        worst <= 1e-12,
        "replay differs from the flight by {worst:e}"
    );
    println!("{kind:?} replay vs flight: max |Δy| = {worst:e} over {k} samples");
}
