//! The hot paths (`q_method`, `FusionFilter::step`) do not allocate: counted
//! with a wrapping global allocator (this test binary only).
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::attitude::{VectorObservation, q_method, quaternion_from_euler};
use helicon_core::fusion::{FusionConfig, FusionFilter, FusionInput, Matrix9, Vector9};
use nalgebra::Vector3;

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

#[test]
fn q_method_and_fusion_step_do_not_allocate() {
    let q = quaternion_from_euler(0.1, -0.2, 0.7);
    let r = q.to_rotation_matrix();
    let g = Vector3::new(0.0, 0.0, 1.0);
    let m = Vector3::new(0.153, 0.008, -0.438);
    let obs = [
        VectorObservation::new(1.0, r * g, g),
        VectorObservation::new(0.5, r * m, m),
    ];
    let mut f = FusionFilter::new(
        FusionConfig::default(),
        Vector9::zeros(),
        Matrix9::identity(),
    )
    .unwrap();
    let input = FusionInput {
        specific_force_body_m_s2: Vector3::new(0.1, -0.05, -9.8),
        gyro_body_rad_s: Vector3::new(0.01, 0.02, -0.01),
        gps_ned_m: Some(Vector3::new(0.1, 0.2, -0.1)),
        gps_vel_ned_m_s: None,
        attitude_rad: Some(Vector3::new(0.01, 0.0, 0.02)),
    };
    let before = allocations();
    let mut acc = 0.0;
    for _ in 0..1000 {
        let s = q_method(&obs).unwrap();
        acc += s.loss;
        f.step(&input).unwrap();
    }
    let after = allocations();
    assert!(acc.is_finite());
    assert_eq!(
        after - before,
        0,
        "hot paths allocated {} times",
        after - before
    );
}

#[test]
fn eskf_step_does_not_allocate() {
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
    let init = nalgebra::SVector::<f64, 9>::zeros();
    // construction allocates the latency ring once; steps allocate nothing
    let mut f = Eskf::new(&EskfConfig::default(), &imu, &noise, dt, &init).unwrap();
    let before = allocations();
    for k in 0..4000u32 {
        let t = f64::from(k) * dt;
        let frame = SensorFrame {
            t_s: t,
            imu: ImuSample {
                specific_force_body_m_s2: Vector3::new(0.01, -0.02, -9.81),
                gyro_body_rad_s: Vector3::new(0.001, -0.002, 0.003),
            },
            mag_body: (k % 4 == 0).then_some(noise.mag_field_ned),
            gps: (k % 80 == 0 && k > 40).then_some(GpsFix {
                epoch_s: t - 0.1,
                fix: GpsFixType::Fix3d,
                position_ned_m: Vector3::zeros(),
                velocity_ned_m_s: Some(Vector3::zeros()),
            }),
        };
        f.step(&frame).unwrap();
        let _ = f.solution();
    }
    let after = allocations();
    assert!(f.diagnostics().gps_position_fused > 40);
    assert_eq!(
        after - before,
        0,
        "the ESKF allocated {} times",
        after - before
    );
}

#[test]
fn imu_health_update_does_not_allocate() {
    use helicon_core::imu_health::{ImuHealthConfig, ImuHealthMonitor};
    use helicon_core::sensor::ImuSample;
    let mut m = ImuHealthMonitor::new(ImuHealthConfig::new(9.82, 0.0025, 98.2)).unwrap();
    let before = allocations();
    let mut acc = 0.0;
    for k in 0..4000 {
        let t = f64::from(k) * 0.0025;
        let h = m.update(&ImuSample {
            specific_force_body_m_s2: Vector3::new(0.0, 0.0, -9.82 + (100.0 * t).sin()),
            gyro_body_rad_s: Vector3::zeros(),
        });
        acc += h.vibration_rms_m_s2;
    }
    let after = allocations();
    assert!(acc.is_finite());
    assert_eq!(after - before, 0, "ImuHealthMonitor::update allocated");
}
