//! Cost of the IMU vibration chain (thesis Appendix A): one IMU sample of the
//! sensor suite with vibration off and on (20 internal sub-steps, six lines,
//! mechanical stage and fifth-order filter on six axes), and 10 s of the
//! beyond-vibration-2g flight.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
use helicon_sim::sensors::{SensorConfig, SensorSuite};
use helicon_sim::trajectory::ScriptedTrajectory;
use std::hint::black_box;
use std::path::Path;

fn bench(c: &mut Criterion) {
    let traj = ScriptedTrajectory::default();
    let truths: Vec<_> = (0..400).map(|k| traj.truth(f64::from(k) / 400.0)).collect();
    let mut g = c.benchmark_group("vibration");
    g.sample_size(30);
    for on in [false, true] {
        let mut cfg = SensorConfig::default();
        cfg.imu.vibration.enabled = on;
        let mut suite = SensorSuite::new(cfg, 9.82).unwrap();
        let mut k = 0;
        let name = if on {
            "sample_vibration_on"
        } else {
            "sample_vibration_off"
        };
        g.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) % truths.len();
                black_box(suite.sample(black_box(&truths[k])))
            })
        });
    }
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/beyond-vibration-2g.toml");
    let mut s = Scenario::from_file(&path).unwrap();
    s.duration_s = 10.0;
    let p = prepare(&s).unwrap();
    g.sample_size(10);
    g.bench_function("fly_10s_beyond_vibration_2g", |b| {
        b.iter(|| fly(black_box(&s), &p, None).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
