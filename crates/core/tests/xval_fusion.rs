//! The fusion filter against an independent NumPy Kalman filter on the same
//! data (`tools/gen_fusion_fixtures.py`), and the thesis's Figures 13.5/13.6
//! experiment with numbers.
#![allow(clippy::unwrap_used)] // test/bench helpers: a failed unwrap is a failed test

use helicon_core::fusion::{FusionConfig, FusionFilter, FusionInput, Matrix9, Vector9};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn parse_opt3(f: &[&str], i: usize) -> Option<Vector3<f64>> {
    if f[i].is_empty() {
        None
    } else {
        Some(Vector3::new(
            f[i].parse().unwrap(),
            f[i + 1].parse().unwrap(),
            f[i + 2].parse().unwrap(),
        ))
    }
}

#[test]
fn xval_fusion_matches_numpy_reference_kf() {
    let text = include_str!("fixtures/fusion_reference.csv");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let cfg_line: Vec<f64> = lines
        .next()
        .unwrap()
        .split(',')
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let _header = lines.next().unwrap();
    let config = FusionConfig {
        dt_s: cfg_line[0],
        gravity_m_s2: cfg_line[1],
        accel_sigma_m_s2: cfg_line[2],
        euler_rate_sigma_rad_s: cfg_line[3],
        gps_sigma_m: Vector3::new(cfg_line[4], cfg_line[5], cfg_line[6]),
        gps_vel_sigma_m_s: Vector3::new(0.1, 0.1, 0.2),
        attitude_sigma_rad: Vector3::new(cfg_line[7], cfg_line[8], cfg_line[9]),
    };
    let x0 = Vector9::from_iterator(cfg_line[10..19].iter().copied());
    let p0 = Matrix9::from_diagonal(&Vector9::from_iterator(cfg_line[19..28].iter().copied()));
    let mut filter = FusionFilter::new(config, x0, p0).unwrap();
    let (mut worst_x, mut worst_p, mut steps, mut gps_steps) = (0.0f64, 0.0f64, 0, 0);
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let v = |i: usize| -> f64 { f[i].parse().unwrap() };
        let input = FusionInput {
            specific_force_body_m_s2: Vector3::new(v(0), v(1), v(2)),
            gyro_body_rad_s: Vector3::new(v(3), v(4), v(5)),
            gps_ned_m: parse_opt3(&f, 6),
            gps_vel_ned_m_s: None,
            attitude_rad: parse_opt3(&f, 9),
        };
        gps_steps += usize::from(input.gps_ned_m.is_some());
        filter.step(&input).unwrap();
        for i in 0..9 {
            worst_x = worst_x.max((filter.state()[i] - v(12 + i)).abs());
        }
        for i in 0..9 {
            for j in 0..9 {
                // Reference stores P row-major.
                worst_p = worst_p.max((filter.covariance()[(i, j)] - v(21 + 9 * i + j)).abs());
            }
        }
        steps += 1;
    }
    println!(
        "fusion vs NumPy KF: {steps} steps ({gps_steps} GPS fixes), max |dx| = {worst_x:e}, max |dP| = {worst_p:e}"
    );
    assert_eq!(steps, 400);
    // 1e-9: the requirement. Sequential vs joint update and
    // different summation order differ only by round-off (~1e-14 here).
    assert!(worst_x < 1e-9);
    assert!(worst_p < 1e-9);
}

/// Thesis Figures 13.5/13.6: an object travels ~30 m in the horizontal plane;
/// GPS alone is noisy, the twice-integrated accelerometer drifts, the fused
/// estimate beats both. Numbers printed for docs/sensors.md.
#[test]
fn thesis_fig_13_5_13_6_fused_beats_gps_and_dead_reckoning() {
    let t_end = 60.0;
    let dt = 0.01;
    let g = 9.82;
    let pi = std::f64::consts::PI;
    // p(t): smooth analytic trajectory, 30 m north and 30 m east.
    let pos = |t: f64| {
        Vector3::new(
            15.0 * (1.0 - (pi * t / t_end).cos()),
            30.0 * t / t_end + 5.0 * (2.0 * pi * t / t_end).sin(),
            0.0,
        )
    };
    let vel = |t: f64| {
        Vector3::new(
            15.0 * pi / t_end * (pi * t / t_end).sin(),
            30.0 / t_end + 5.0 * 2.0 * pi / t_end * (2.0 * pi * t / t_end).cos(),
            0.0,
        )
    };
    let acc = |t: f64| {
        Vector3::new(
            15.0 * (pi / t_end).powi(2) * (pi * t / t_end).cos(),
            -5.0 * (2.0 * pi / t_end).powi(2) * (2.0 * pi * t / t_end).sin(),
            0.0,
        )
    };
    let sigma_acc = 0.1; // m/s², hobby MEMS accelerometer at 100 Hz
    let bias_acc = Vector3::new(0.02, -0.015, 0.0); // residual calibration bias, m/s²
    let sigma_gps = 1.0; // m, per horizontal axis, 10 Hz
    let mut rng = ChaCha8Rng::seed_from_u64(1356);
    let na = Normal::new(0.0, sigma_acc).unwrap();
    let ng = Normal::new(0.0, sigma_gps).unwrap();
    let config = FusionConfig {
        dt_s: dt,
        gravity_m_s2: g,
        accel_sigma_m_s2: sigma_acc,
        euler_rate_sigma_rad_s: 0.01,
        gps_sigma_m: Vector3::new(sigma_gps, sigma_gps, 2.0),
        gps_vel_sigma_m_s: Vector3::new(0.1, 0.1, 0.2),
        attitude_sigma_rad: Vector3::repeat(0.01),
    };
    let mut x0 = Vector9::zeros();
    x0.fixed_rows_mut::<3>(0).copy_from(&pos(0.0));
    x0.fixed_rows_mut::<3>(3).copy_from(&vel(0.0));
    let p0 = Matrix9::from_diagonal(&Vector9::from_row_slice(&[
        1.0, 1.0, 1.0, 0.1, 0.1, 0.1, 1e-4, 1e-4, 1e-4,
    ]));
    let mut filter = FusionFilter::new(config, x0, p0).unwrap();
    let (mut dr_p, mut dr_v) = (pos(0.0), vel(0.0));
    let mut gps_hold = pos(0.0);
    let (mut se_fused, mut se_gps, mut se_dr) = (0.0, 0.0, 0.0);
    let n = (t_end / dt).round() as usize;
    for k in 1..=n {
        let t_prev = (k - 1) as f64 * dt;
        let t = k as f64 * dt;
        // Level attitude: specific force f = a − g in body = NED axes.
        let a_meas =
            acc(t_prev) + bias_acc + Vector3::new(na.sample(&mut rng), na.sample(&mut rng), 0.0);
        let f_body = a_meas - Vector3::new(0.0, 0.0, g);
        let gps = if k % 10 == 0 {
            let z = pos(t) + Vector3::new(ng.sample(&mut rng), ng.sample(&mut rng), 0.0);
            gps_hold = z;
            Some(z)
        } else {
            None
        };
        filter
            .step(&FusionInput {
                specific_force_body_m_s2: f_body,
                gyro_body_rad_s: Vector3::zeros(),
                gps_ned_m: gps,
                gps_vel_ned_m_s: None,
                attitude_rad: Some(Vector3::zeros()),
            })
            .unwrap();
        // Double integration of the accelerometer alone (Figure 13.5(b)).
        dr_p += dr_v * dt + 0.5 * a_meas * dt * dt;
        dr_v += a_meas * dt;
        let truth = pos(t);
        let horiz = |p: &Vector3<f64>| (p.x - truth.x).powi(2) + (p.y - truth.y).powi(2);
        se_fused += horiz(&filter.state().fixed_rows::<3>(0).into_owned());
        se_gps += horiz(&gps_hold);
        se_dr += horiz(&dr_p);
    }
    let rms = |s: f64| (s / n as f64).sqrt();
    let (fused, gps, dr) = (rms(se_fused), rms(se_gps), rms(se_dr));
    println!(
        "Fig 13.5/13.6 horizontal RMS error: fused {fused:.3} m, GPS only {gps:.3} m, integrated accelerometer {dr:.3} m"
    );
    assert!(fused < gps, "fused {fused} vs gps {gps}");
    assert!(fused < dr, "fused {fused} vs dead reckoning {dr}");
    // Regression pin (seeded run measured 0.80 m vs 1.41 m, ratio 0.57, with
    // the unmodelled 0.02 m/s² accelerometer bias): fused stays at least 30%
    // better than GPS alone.
    assert!(fused < 0.7 * gps);
}
