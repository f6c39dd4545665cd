//! The flight computer as the runtime will run it: the thesis chain
//! (navigation + Kalman predictor + LQI) stepped on sensor frames, counted by
//! a wrapping global allocator (this test binary only), and the layering
//! rule that the core depends on nalgebra only.
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame, SensorNoise};
use helicon_core::{
    FlightComputer, GainSet, KalmanPredictor, Lqi, LqiOptions, NavigationConfig, NavigationFilter,
    Reference, ServoLimits, ThesisEstimator,
};
use nalgebra::{SMatrix, SVector, Vector3};

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

const TS: f64 = 0.0025;
const G: f64 = 9.81;
const FIELD: [f64; 3] = [0.153, 0.008, -0.438];

/// A stable synthetic design: Φ = 0.99 I, small gains. The numbers do not
/// matter here; the shapes and the code path do.
fn gains() -> GainSet {
    GainSet {
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
    }
}

fn computer() -> FlightComputer<ThesisEstimator, Lqi> {
    let g = gains();
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

/// The frame of sample k for a level helicopter at rest: magnetometer every
/// 4th sample, a GPS fix with Doppler velocity every 80th.
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

#[test]
fn flight_computer_step_does_not_allocate() {
    let mut c = computer();
    let r = Reference {
        velocity_ned_m_s: Vector3::new(1.0, 0.0, 0.0),
        yaw_rad: 0.3,
    };
    let _ = c.step(&frame(0), &r).unwrap();
    let before = allocations();
    let mut acc = 0.0;
    let mut fixes = 0;
    for k in 1..4000 {
        let t = c.step(&frame(k), &r).unwrap();
        acc += t.command.sum();
        fixes += usize::from(t.navigation.is_some_and(|n| n.gps_fused));
    }
    let allocs = allocations() - before;
    assert!(acc.is_finite());
    assert_eq!(fixes, 49, "GPS fixes fused");
    assert_eq!(allocs, 0, "FlightComputer::step allocated {allocs} times");
}

#[test]
fn telemetry_is_stamped_and_counted() {
    let mut c = computer();
    let r = Reference::default();
    for k in 0..10 {
        let t = c.step(&frame(k), &r).unwrap();
        assert_eq!(t.sample, k);
        assert_eq!(t.t_s, k as f64 * TS);
        let n = t.navigation.unwrap();
        assert_eq!(n.attitude_fix, k % 4 == 0);
        assert_eq!(t.reference, r);
    }
}

#[test]
fn bad_frames_are_errors_not_nan() {
    let mut c = computer();
    let r = Reference::default();
    let mut f = frame(0);
    f.imu.gyro_body_rad_s.z = f64::NAN;
    let e = c.step(&f, &r).unwrap_err().to_string();
    assert!(e.contains("gyro"), "{e}");
    // the computer keeps working after a rejected frame
    assert!(c.step(&frame(1), &r).is_ok());
}

#[test]
fn core_depends_on_nalgebra_only() {
    // The layering rule: nothing but nalgebra (and serde behind an opt-in
    // feature) among the core's normal dependencies.
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml")).unwrap();
    let deps = text
        .split("[dependencies]")
        .nth(1)
        .unwrap()
        .split("\n[")
        .next()
        .unwrap();
    let names: Vec<&str> = deps
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| l.split(['=', '.', ' ']).next().unwrap())
        .collect();
    assert_eq!(names, ["nalgebra", "serde"], "{deps}");
    assert!(deps.contains("optional = true"), "serde must stay optional");
}

/// `step_with_excitation`: the offset is added to the law's command before
/// saturation (the telemetry holds what was applied), the estimator
/// predicts with the applied command, a zero offset is `step` bit for bit,
/// and it allocates nothing.
#[test]
fn excitation_is_added_before_saturation_and_predicted_with() {
    let r = Reference::default();
    let (mut plain, mut zero) = (computer(), computer());
    let offset = SVector::from([0.0, 0.02, -0.03, 2.0]); // the tail offset saturates
    let before = allocations();
    for k in 0..200 {
        let a = plain.step(&frame(k), &r).unwrap();
        let b = zero
            .step_with_excitation(&frame(k), &r, &SVector::zeros())
            .unwrap();
        assert_eq!(a, b, "sample {k}");
    }
    assert_eq!(allocations() - before, 0, "step_with_excitation allocated");
    // one excited sample from identical computers: the law's command plus the
    // offset, clipped to the limits; the saturation flagged
    let (mut c1, mut c2) = (computer(), computer());
    let law = c1.step(&frame(0), &r).unwrap();
    let exc = c2.step_with_excitation(&frame(0), &r, &offset).unwrap();
    let max = [0.3, 1.0, 1.0, 0.5];
    for i in 0..4 {
        let want = (law.command[i] + offset[i]).min(max[i]);
        assert_eq!(exc.command[i], want, "servo {i}");
    }
    assert_eq!(exc.saturated, [false, false, false, true]);
    // the predictor advanced with the applied (excited) command: the next
    // estimate differs by Γ (u_exc − u_law) in the predicted states
    let (n1, n2) = (
        c1.step(&frame(1), &r).unwrap(),
        c2.step(&frame(1), &r).unwrap(),
    );
    let g = gains();
    let du = exc.command - law.command;
    let want = g.gamma * du;
    // the measured states (first nine) are corrected by the navigation; the
    // rest of the predicted states carry Γ Δu (×(1 − K) = 1 on them: K is 0
    // off the measured block in this design)
    for i in 9..27 {
        let d = n2.estimate[i] - n1.estimate[i];
        assert!((d - want[i]).abs() < 1e-15, "state {i}: {d} vs {}", want[i]);
    }
    assert!(want.iter().skip(9).any(|v| v.abs() > 1e-6));
}

/// `step_applied`: with the servos given something else than the law's
/// command (the pilot's sticks), the estimator predicts with that and the
/// telemetry holds it; the law's errors are still reported; `None` is
/// `step_with_excitation` bit for bit.
#[test]
fn the_predictor_is_told_what_was_applied() {
    let r = Reference::default();
    let zero = SVector::zeros();
    let (mut a, mut b) = (computer(), computer());
    for k in 0..50 {
        assert_eq!(
            a.step_applied(&frame(k), &r, &zero, None).unwrap(),
            b.step_with_excitation(&frame(k), &r, &zero).unwrap()
        );
    }
    // the pilot's sticks against the law's command, from identical computers
    let (mut law_c, mut pilot_c) = (computer(), computer());
    let sticks = SVector::from([0.2, -0.1, 0.15, 0.05]);
    let law = law_c.step(&frame(0), &r).unwrap();
    let piloted = pilot_c
        .step_applied(&frame(0), &r, &zero, Some(&sticks))
        .unwrap();
    assert_eq!(piloted.command, sticks);
    assert_eq!(piloted.saturated, [false; 4]);
    assert_eq!(piloted.tracking_error, law.tracking_error);
    // the next estimate differs by Γ (u_pilot − u_law) off the measured block
    let (n1, n2) = (
        law_c.step(&frame(1), &r).unwrap(),
        pilot_c.step(&frame(1), &r).unwrap(),
    );
    let want = gains().gamma * (sticks - law.command);
    for i in 9..27 {
        let d = n2.estimate[i] - n1.estimate[i];
        assert!((d - want[i]).abs() < 1e-15, "state {i}: {d} vs {}", want[i]);
    }
    assert!(want.iter().skip(9).any(|v| v.abs() > 1e-6));
}

/// `step_servo`: the function sees this sample's law command (the one
/// `step` sends), and what it returns is what the servos get and the
/// estimator predicts with — a ground logic's blend of the fresh command.
#[test]
fn step_servo_blends_this_samples_law_command() {
    let r = Reference::default();
    let zero = SVector::zeros();
    let (mut law_c, mut blend_c) = (computer(), computer());
    for k in 0..20 {
        let law = law_c.step(&frame(k), &r).unwrap();
        let mut seen = None;
        let blended = blend_c
            .step_servo(&frame(k), &r, &zero, |u| {
                seen = Some(*u);
                None
            })
            .unwrap();
        assert_eq!(blended, law, "None is the law's command, bit for bit");
        assert_eq!(seen, Some(law.command));
    }
    let law = law_c.step(&frame(20), &r).unwrap();
    let half = blend_c
        .step_servo(&frame(20), &r, &zero, |u| Some(u * 0.5))
        .unwrap();
    assert_eq!(half.command, law.command * 0.5);
    assert_eq!(half.saturated, [false; 4]);
    // the next estimate differs by Γ (u_blend − u_law) off the measured block
    let (n1, n2) = (
        law_c.step(&frame(21), &r).unwrap(),
        blend_c.step(&frame(21), &r).unwrap(),
    );
    let want = gains().gamma * (half.command - law.command);
    for i in 9..27 {
        let d = n2.estimate[i] - n1.estimate[i];
        assert!((d - want[i]).abs() < 1e-15, "state {i}: {d} vs {}", want[i]);
    }
}
