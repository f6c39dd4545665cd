//! The PX4 organisation's `px4-ulog` crate (an independent reader) reads
//! the log of a real flight computer: the thesis chain (navigation, Kalman
//! predictor, LQI) of `helicon-core` stepped at 400 Hz on sensor frames for
//! 10 s, every step's `Telemetry` and every frame logged through
//! `FlightLog`. Every control step is present, in order, at 400 Hz ± 0.1 %,
//! with monotonic timestamps and the telemetry's values bit for bit.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame, SensorNoise};
use helicon_core::{
    FlightComputer, GainSet, KalmanPredictor, Lqi, LqiOptions, NavigationConfig, NavigationFilter,
    Reference, ServoLimits, ThesisEstimator,
};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo};
use nalgebra::{SMatrix, SVector, Vector3};
use px4_ulog::full_parser::{Completeness, MultiId, SomeVec, read_file};

const TS: f64 = 0.0025;
const RATE_HZ: f64 = 400.0;
const G: f64 = 9.81;
const FIELD: [f64; 3] = [0.153, 0.008, -0.438];

/// A stable synthetic design (the numbers do not matter, the code path does).
fn computer() -> FlightComputer<ThesisEstimator, Lqi> {
    let g = GainSet {
        sample_time_s: TS,
        alpha: 1.002,
        x_trim: SVector::zeros(),
        u_trim: SVector::from([0.1, 0.0, 0.0, 0.05]),
        phi: SMatrix::identity() * 0.99,
        gamma: SMatrix::from_fn(|i, j| if i % 4 == j { 1e-3 } else { 0.0 }),
        ls: SMatrix::from_fn(|i, j| if j % 4 == i { 0.01 } else { 0.0 }),
        li: SMatrix::identity() * 1e-4,
        k: SMatrix::from_fn(|i, j| if i == j { 0.5 } else { 0.0 }),
        options: LqiOptions {
            integral_action: true,
            reference_in_proportional: false,
            anti_windup: true,
        },
    };
    let noise = SensorNoise {
        gps_sigma_m: Vector3::new(1.5, 1.5, 3.0),
        gps_vel_sigma_m_s: Vector3::new(0.05, 0.05, 0.1),
        mag_field_ned: Vector3::from(FIELD),
        gravity_m_s2: G,
    };
    let nav = NavigationFilter::new(
        &NavigationConfig::default(),
        &noise,
        TS,
        &SVector::zeros(),
        &Vector3::zeros(),
    )
    .unwrap();
    let limits = ServoLimits {
        min: SVector::from([-0.1, -1.0, -1.0, -0.5]),
        max: SVector::from([0.3, 1.0, 1.0, 0.5]),
    };
    let est = ThesisEstimator {
        navigation: nav,
        predictor: KalmanPredictor::new(&g, &g.x_trim).unwrap(),
    };
    FlightComputer::new(est, Lqi::new(&g, limits, true).unwrap())
}

fn frame(k: u64) -> SensorFrame {
    let t = k as f64 * TS;
    let wobble = 1e-3 * (t * 7.0).sin();
    SensorFrame {
        t_s: t,
        imu: ImuSample {
            specific_force_body_m_s2: Vector3::new(wobble, -wobble, -G),
            gyro_body_rad_s: Vector3::new(wobble, 0.0, -wobble),
        },
        mag_body: (k % 4 == 0).then(|| Vector3::from(FIELD)),
        gps: (k % 80 == 0).then(|| GpsFix {
            epoch_s: t - 0.1,
            fix: GpsFixType::Fix3d,
            position_ned_m: Vector3::new(wobble, 0.0, 0.0),
            velocity_ned_m_s: Some(Vector3::zeros()),
        }),
    }
}

fn u64s(v: &SomeVec) -> &[u64] {
    match v {
        SomeVec::UInt64(x) => x,
        other => panic!("not uint64: {other:?}"),
    }
}

fn f64s(v: &SomeVec) -> &[f64] {
    match v {
        SomeVec::Double(x) => x,
        other => panic!("not double: {other:?}"),
    }
}

#[test]
fn px4_ulog_reads_every_control_step_at_400_hz() {
    let dir = std::env::temp_dir().join(format!("helicon_ulog_px4_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("flight.ulg");
    let n = 4000u64; // 10 s at 400 Hz
    let mut fc = computer();
    let r = Reference {
        velocity_ned_m_s: Vector3::new(1.0, 0.0, 0.0),
        yaw_rad: 0.3,
    };
    let mut log = FlightLog::create(&path, &LogInfo::default(), FlushPolicy::default()).unwrap();
    let mut commands = Vec::new();
    let mut estimates = Vec::new();
    for k in 0..n {
        let f = frame(k);
        let t = fc.step(&f, &r).unwrap();
        log.log_frame(&f).unwrap();
        log.log_telemetry(&t).unwrap();
        commands.push(t.command[0]);
        estimates.push(t.estimate[5]);
    }
    log.finish().unwrap();

    let parsed = read_file(path.to_str().unwrap()).unwrap();
    assert_eq!(parsed.completeness, Completeness::Complete);
    let control = &parsed.messages["control"][&MultiId::new(0)];
    let ts = u64s(&control["timestamp"]);
    let samples = u64s(&control["sample"]);
    // every control step present, in order
    assert_eq!(samples.len() as u64, n);
    assert!(samples.iter().enumerate().all(|(i, s)| *s == i as u64));
    // strictly monotonic timestamps
    assert!(ts.windows(2).all(|w| w[1] > w[0]));
    // 400 Hz ± 0.1 %, overall and step by step
    let rate = (ts.len() - 1) as f64 / ((ts[ts.len() - 1] - ts[0]) as f64 * 1e-6);
    assert!((rate / RATE_HZ - 1.0).abs() < 1e-3, "rate {rate} Hz");
    assert!(ts.windows(2).all(|w| (w[1] - w[0]).abs_diff(2500) <= 2));
    // the telemetry's values, bit for bit
    let cmd0 = f64s(&control["command[0]"]);
    assert!(
        cmd0.iter()
            .zip(&commands)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    let psi = f64s(&control["estimate[5]"]);
    assert!(
        psi.iter()
            .zip(&estimates)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    // trailing padding is not a field
    assert!(!control.keys().any(|k| k.starts_with("_padding")));
    // the sensors: an IMU record per step, magnetometer every 4th, GPS every 80th
    let count = |topic: &str| u64s(&parsed.messages[topic][&MultiId::new(0)]["timestamp"]).len();
    assert_eq!(count("sensor_imu") as u64, n);
    assert_eq!(count("helicon_mag") as u64, n / 4);
    assert_eq!(count("helicon_gps") as u64, n / 80);
    assert_eq!(count("navigation") as u64, n);
    std::fs::remove_dir_all(&dir).unwrap();
}
