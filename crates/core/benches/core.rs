//! Benchmarks of the hot paths: q-method and one fusion step.
#![allow(clippy::unwrap_used, missing_docs)] // bench: criterion macros generate undocumented items

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use helicon_core::attitude::{VectorObservation, q_method, quaternion_from_euler};
use helicon_core::fusion::{FusionConfig, FusionFilter, FusionInput, Matrix9, Vector9};
use nalgebra::Vector3;
use std::hint::black_box;

fn bench_q_method(c: &mut Criterion) {
    let q = quaternion_from_euler(0.1, -0.2, 0.7);
    let r = q.to_rotation_matrix();
    let g = Vector3::new(0.0, 0.0, 1.0);
    let m = Vector3::new(0.153, 0.008, -0.438);
    let obs = [
        VectorObservation::new(1.0, r * g, g),
        VectorObservation::new(0.5, r * m, m),
    ];
    c.bench_function("q_method_2obs", |b| b.iter(|| q_method(black_box(&obs))));
}

fn bench_fusion_step(c: &mut Criterion) {
    let cfg = FusionConfig::default();
    let f = FusionFilter::new(cfg, Vector9::zeros(), Matrix9::identity()).unwrap();
    let input = FusionInput {
        specific_force_body_m_s2: Vector3::new(0.1, -0.05, -9.8),
        gyro_body_rad_s: Vector3::new(0.01, 0.02, -0.01),
        gps_ned_m: Some(Vector3::new(0.1, 0.2, -0.1)),
        gps_vel_ned_m_s: None,
        attitude_rad: Some(Vector3::new(0.01, 0.0, 0.02)),
    };
    // Each iteration starts from the same filter (a long run of constant
    // gyro input would otherwise drift into gimbal lock and time the error path).
    c.bench_function("fusion_step_gps_att", |b| {
        b.iter_batched_ref(
            || f.clone(),
            |f| f.step(black_box(&input)).unwrap(),
            BatchSize::SmallInput,
        )
    });
    let input_pred = FusionInput {
        gps_ned_m: None,
        gps_vel_ned_m_s: None,
        attitude_rad: None,
        ..input
    };
    c.bench_function("fusion_step_predict_only", |b| {
        b.iter_batched_ref(
            || f.clone(),
            |f| f.step(black_box(&input_pred)).unwrap(),
            BatchSize::SmallInput,
        )
    });
}

criterion_group!(benches, bench_q_method, bench_fusion_step);
criterion_main!(benches);
