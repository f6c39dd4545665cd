//! Benchmarks of the hot paths: q-method, one fusion step, one ESKF step.
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

/// One ESKF step at 400 Hz: IMU only (3 of 4 samples at a 100 Hz
/// magnetometer), with the magnetometer, and with a delayed GPS fix
/// (position + velocity) and the magnetometer (the worst sample).
fn bench_eskf_step(c: &mut Criterion) {
    use helicon_core::eskf::{Eskf, EskfConfig, ImuNoise};
    use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame, SensorNoise};
    let imu = ImuNoise {
        accel_noise_density: 0.004,
        accel_bias_walk: 3e-4,
        accel_bias_sigma: 0.2,
        gyro_noise_density: 1e-4,
        gyro_bias_walk: 2e-5,
        gyro_bias_sigma: 0.01,
        mag_sigma: 0.002,
    };
    let noise = SensorNoise {
        gps_sigma_m: Vector3::new(1.5, 1.5, 3.0),
        gps_vel_sigma_m_s: Vector3::new(0.05, 0.05, 0.1),
        mag_field_ned: Vector3::new(0.153, 0.008, -0.438),
        gravity_m_s2: 9.81,
    };
    let dt = 0.0025;
    let mut f = Eskf::new(
        &EskfConfig::default(),
        &imu,
        &noise,
        dt,
        &nalgebra::SVector::<f64, 9>::zeros(),
    )
    .unwrap();
    let frame = |t: f64| {
        SensorFrame::imu_only(
            t,
            ImuSample {
                specific_force_body_m_s2: Vector3::new(0.01, -0.02, -9.81),
                gyro_body_rad_s: Vector3::new(0.001, -0.002, 0.003),
            },
        )
    };
    // warm up to a filled history and a settled covariance
    for k in 0..400 {
        f.step(&frame(f64::from(k) * dt)).unwrap();
    }
    // one filter stepped on (no clone per iteration: the clone's latency
    // ring would dominate); the time advances one sample per iteration
    let mut k = 400.0;
    let mut step = |f: &mut Eskf, mag: bool, gps: bool| {
        k += 1.0;
        let t = k * dt;
        let frame = SensorFrame {
            mag_body: mag.then_some(noise.mag_field_ned),
            gps: gps.then_some(GpsFix {
                epoch_s: t - 0.1,
                fix: GpsFixType::Fix3d,
                position_ned_m: Vector3::zeros(),
                velocity_ned_m_s: Some(Vector3::zeros()),
            }),
            ..frame(t)
        };
        f.step(black_box(&frame)).unwrap()
    };
    c.bench_function("eskf_step_imu", |b| b.iter(|| step(&mut f, false, false)));
    c.bench_function("eskf_step_imu_mag", |b| {
        b.iter(|| step(&mut f, true, false))
    });
    c.bench_function("eskf_step_imu_mag_gps", |b| {
        b.iter(|| step(&mut f, true, true))
    });
}

criterion_group!(benches, bench_q_method, bench_fusion_step, bench_eskf_step);
criterion_main!(benches);
