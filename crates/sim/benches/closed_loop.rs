//! Benchmark of the full closed loop (issue 6 target: ≥ 500× real time on one
//! core): sensors, navigation (q-method + fusion), estimator, controller, RK4
//! plant, wind and logging, flying 10 s of the `beyond-physical-turbulence`
//! scenario. Criterion reports the time per 10 s flight; the real-time
//! factor is 10 s divided by it.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
use std::hint::black_box;
use std::path::Path;

fn bench(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/beyond-physical-turbulence.toml");
    let mut s = Scenario::from_file(&path).unwrap();
    s.duration_s = 10.0;
    let p = prepare(&s).unwrap();
    let mut g = c.benchmark_group("closed_loop");
    g.sample_size(20);
    g.bench_function("fly_10s_sensors_fusion_estimator", |b| {
        b.iter(|| fly(black_box(&s), &p, None).unwrap())
    });
    let mut ideal = s.clone();
    ideal.controller.fusion = false;
    g.bench_function("fly_10s_ideal_measurements", |b| {
        b.iter(|| fly(black_box(&ideal), &p, None).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
