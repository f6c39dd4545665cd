//! IMU vibration (thesis §3.3.2, Appendix A): the chain off reproduces the
//! sensor model as it was bit for bit; on, the shaker's mean shift matches the
//! closed form of a clipped sinusoid through a linear filter.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
use helicon_sim::sensor_log::SensorLogWriter;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The sensor log of the first 0.5 s of the beyond-the-thesis scenario, as
/// text.
fn beyond_sensor_log(s: &Scenario) -> String {
    let p = prepare(s).unwrap();
    let f = fly(s, &p, None).unwrap();
    let mut w = SensorLogWriter::new(Vec::new(), "sensors.csv", "vibration regression").unwrap();
    for row in &f.sensors {
        w.write(row).unwrap();
    }
    String::from_utf8(w.finish().unwrap()).unwrap()
}

/// `vibration` absent: the closed loop's sensor frames are those the sensor
/// model gave before the vibration chain existed (a log recorded then,
/// `tests/fixtures/beyond_sensors_no_vibration.csv`), bit for bit.
#[test]
fn vibration_off_reproduces_the_previous_sensor_log() {
    let mut s = Scenario::from_file(&root().join("scenarios/beyond-physical-turbulence.toml"))
        .unwrap();
    s.duration_s = 0.5;
    s.log.sensors = true;
    let text = beyond_sensor_log(&s);
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/beyond_sensors_no_vibration.csv");
    if std::env::var_os("HELICON_BLESS").is_some() {
        std::fs::create_dir_all(fixture.parent().unwrap()).unwrap();
        std::fs::write(&fixture, &text).unwrap();
    }
    let recorded = std::fs::read_to_string(&fixture).unwrap();
    assert_eq!(text.lines().count(), recorded.lines().count());
    for (k, (a, b)) in text.lines().zip(recorded.lines()).enumerate() {
        assert_eq!(a, b, "line {} differs", k + 1);
    }
}
