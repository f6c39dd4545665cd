//! Sensor models: noise levels, bias walk, saturation, quantisation, GPS
//! timing, TOML errors, reproducibility; and the plot module.
#![allow(clippy::unwrap_used)] // test/bench helpers: a failed unwrap is a failed test

use helicon_sim::plot::{LinePlot, PlotError, Series};
use helicon_sim::sensors::{G0_M_S2, SensorConfig, SensorConfigError, SensorSuite};
use helicon_sim::trajectory::{ScriptedTrajectory, TruthSample};
use nalgebra::Vector3;

fn at_rest(t: f64) -> TruthSample {
    TruthSample {
        t_s: t,
        pos_ned_m: Vector3::new(1.0, 2.0, -3.0),
        vel_ned_m_s: Vector3::zeros(),
        acc_ned_m_s2: Vector3::zeros(),
        euler_rad: Vector3::zeros(),
        omega_body_rad_s: Vector3::zeros(),
    }
}

#[test]
fn white_noise_matches_density_times_sqrt_rate() {
    let mut cfg = SensorConfig::default();
    // Isolate white noise: no bias, walk, scale or quantisation.
    for c in [&mut cfg.imu.accel, &mut cfg.imu.gyro] {
        c.bias_random_walk = 0.0;
        c.initial_bias_sigma = 0.0;
        c.scale_factor_sigma = 0.0;
        c.resolution = 0.0;
    }
    let mut s = SensorSuite::new(cfg, 9.82).unwrap();
    let n = 100_000;
    let (mut sa, mut sg) = (0.0, 0.0);
    for k in 0..n {
        let y = s.sample(&at_rest(k as f64 / cfg.imu.rate_hz));
        sa += (y.imu.specific_force_body_m_s2.x).powi(2);
        sg += (y.imu.gyro_body_rad_s.y).powi(2);
    }
    let sig_a = (sa / n as f64).sqrt();
    let sig_g = (sg / n as f64).sqrt();
    let want_a = cfg.imu.accel.noise_density * cfg.imu.rate_hz.sqrt();
    let want_g = cfg.imu.gyro.noise_density * cfg.imu.rate_hz.sqrt();
    println!("accel σ {sig_a:.5} (want {want_a:.5}), gyro σ {sig_g:.6} (want {want_g:.6})");
    // 2%: sampling scatter of σ from 1e5 samples is 0.22%.
    assert!((sig_a / want_a - 1.0).abs() < 0.02);
    assert!((sig_g / want_g - 1.0).abs() < 0.02);
}

#[test]
fn bias_random_walk_variance_grows_linearly() {
    let mut cfg = SensorConfig::default();
    cfg.imu.accel.initial_bias_sigma = 0.0;
    let t_end = 100.0;
    let runs = 400;
    let mut var = 0.0;
    for seed in 0..runs {
        cfg.seed = seed;
        let mut s = SensorSuite::new(cfg, 9.82).unwrap();
        let n = (t_end * cfg.imu.rate_hz) as usize;
        for k in 0..n {
            s.sample(&at_rest(k as f64 / cfg.imu.rate_hz));
        }
        var += s.biases().0.x.powi(2);
    }
    var /= runs as f64;
    let want = cfg.imu.accel.bias_random_walk.powi(2) * t_end;
    println!("bias walk variance after {t_end} s: {var:.3e} (want {want:.3e})");
    // 20%: 400 runs give a variance scatter of sqrt(2/400) = 7%.
    assert!((var / want - 1.0).abs() < 0.2);
}

#[test]
fn saturation_and_quantisation() {
    let cfg = SensorConfig::default();
    let mut s = SensorSuite::new(cfg, 9.82).unwrap();
    // 30 g upwards acceleration: must clip at +/-10 g.
    let mut truth = at_rest(0.0);
    truth.acc_ned_m_s2 = Vector3::new(0.0, 0.0, -30.0 * G0_M_S2);
    let y = s.sample(&truth);
    let range = 10.0 * G0_M_S2;
    assert!((y.imu.specific_force_body_m_s2.z.abs() - range).abs() < 1e-12);
    // Quantised to the resolution (16 bit over +/-10 g).
    let res = cfg.imu.accel.resolution;
    let y = s.sample(&at_rest(0.0025));
    for v in y.imu.specific_force_body_m_s2.iter() {
        let k = v / res;
        assert!((k - k.round()).abs() < 1e-6, "{v} not a multiple of {res}");
    }
}

#[test]
fn gps_rate_latency_and_dropouts() {
    let mut cfg = SensorConfig::default();
    cfg.gps.rate_hz = 10.0;
    cfg.gps.latency_s = 0.2;
    cfg.gps.dropout_probability = 0.1;
    let mut s = SensorSuite::new(cfg, 9.82).unwrap();
    let traj = ScriptedTrajectory::default();
    let n = (600.0 * cfg.imu.rate_hz) as usize;
    let mut fixes = 0;
    let mut mags = 0;
    for k in 0..n {
        let t = k as f64 / cfg.imu.rate_hz;
        let y = s.sample(&traj.truth(t));
        if let Some(epoch) = y.gps.map(|g| g.epoch_s) {
            assert!((t - epoch - 0.2).abs() < 0.5 / cfg.imu.rate_hz + 1e-9);
            fixes += 1;
        }
        mags += usize::from(y.mag_body.is_some());
    }
    let expected = 6000.0 * 0.9;
    println!("GPS fixes {fixes} of 6000 epochs (10% dropouts), magnetometer samples {mags}");
    // Binomial scatter sqrt(6000·0.09) = 23 fixes; allow 5σ.
    assert!((fixes as f64 - expected).abs() < 120.0);
    assert_eq!(mags, 60_000);
}

#[test]
fn same_seed_same_data_other_seed_differs() {
    let traj = ScriptedTrajectory::default();
    let run = |seed| {
        let cfg = SensorConfig {
            seed,
            ..Default::default()
        };
        let mut s = SensorSuite::new(cfg, 9.82).unwrap();
        (0..100)
            .map(|k| {
                s.sample(&traj.truth(k as f64 * 0.0025))
                    .imu
                    .specific_force_body_m_s2
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(run(1), run(1));
    assert_ne!(run(1), run(2));
}

#[test]
fn default_config_toml_round_trips() {
    let cfg = SensorConfig::default();
    let text = cfg.to_toml().unwrap();
    let back = SensorConfig::from_toml_str(&text, "default.toml").unwrap();
    assert_eq!(back, cfg);
}

#[test]
fn toml_config_errors_name_file_and_field() {
    let ok = SensorConfig::from_toml_str("seed = 3\n[gps]\nrate_hz = 2.0\n", "a.toml").unwrap();
    assert_eq!(ok.seed, 3);
    assert_eq!(ok.gps.rate_hz, 2.0);
    let e = SensorConfig::from_toml_str("[gps]\nrate_hz = 20.0\n", "b.toml").unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, SensorConfigError::Invalid { .. }));
    assert!(
        msg.contains("b.toml") && msg.contains("gps.rate_hz"),
        "{msg}"
    );
    let e = SensorConfig::from_toml_str("[gps]\nrate_hzz = 2.0\n", "c.toml").unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("c.toml") && msg.contains("rate_hzz"), "{msg}");
    let e =
        SensorConfig::from_toml_str("[imu.accel]\nnoise_density = 0.1\n", "d.toml").unwrap_err();
    assert!(e.to_string().contains("d.toml"), "{e}");
}

#[test]
fn plot_writes_png_and_svg() {
    let dir = std::env::temp_dir().join(format!("helicon_plot_test_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let a: Vec<(f64, f64)> = (0..200)
        .map(|i| (i as f64 * 0.05, (i as f64 * 0.05).sin()))
        .collect();
    let b: Vec<(f64, f64)> = (0..200)
        .map(|i| (i as f64 * 0.05, f64::NAN))
        .chain([(1.0, 0.5)])
        .collect();
    for ext in ["png", "svg"] {
        let path = dir.join(format!("p.{ext}"));
        LinePlot::new("Test", "time [s]", "y [-]")
            .series(Series::new("sin", &a))
            .series(Series::new("with NaN", &b))
            .write(&path)
            .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.len() > 1000);
        if ext == "png" {
            assert_eq!(&bytes[1..4], b"PNG");
        } else {
            assert!(String::from_utf8_lossy(&bytes).contains("<svg"));
        }
    }
    let empty: Vec<(f64, f64)> = vec![];
    let e = LinePlot::new("E", "x", "y")
        .series(Series::new("e", &empty))
        .write(&dir.join("e.png"));
    assert!(matches!(e, Err(PlotError::Empty { .. })));
    assert!(matches!(
        LinePlot::new("E", "x", "y")
            .series(Series::new("a", &a))
            .write(&dir.join("e.jpg")),
        Err(PlotError::Format { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn gps_outage_withholds_every_fix_in_its_window() {
    let mut cfg = SensorConfig::default();
    cfg.gps.dropout_probability = 0.0;
    cfg.gps.outage = Some(helicon_sim::sensors::GpsOutage {
        start_s: 2.1,
        duration_s: 10.0,
    });
    let mut s = SensorSuite::new(cfg, 9.82).unwrap();
    let mut epochs = Vec::new();
    for k in 0..(20.0 * cfg.imu.rate_hz) as usize {
        let t = k as f64 / cfg.imu.rate_hz;
        if let Some(g) = s.sample(&at_rest(t)).gps {
            epochs.push(g.epoch_s);
        }
    }
    assert!(epochs.iter().all(|e| !(2.1..12.1).contains(e)));
    // 5 Hz: the 11 fixes of 0–2 s before the outage, the rest after it
    assert_eq!(epochs.iter().filter(|e| **e < 2.1).count(), 11);
    assert!(epochs.iter().filter(|e| **e >= 12.1).count() >= 38);
    let bad = "[gps.outage]\nstart_s = -1.0\nduration_s = 2.0\n";
    let e = SensorConfig::from_toml_str(bad, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("x.toml") && e.contains("gps.outage.start_s"),
        "{e}"
    );
}

#[test]
fn imu_presets_are_valid_and_ordered_by_class() {
    use helicon_sim::sensors::{ImuConfig, ImuPreset};
    let [hobby, better, industrial] = [
        ImuPreset::Mpu6000,
        ImuPreset::Icm20602,
        ImuPreset::Adis16470,
    ]
    .map(|p| ImuConfig::preset(p, 400.0));
    for imu in [hobby, better, industrial] {
        let cfg = SensorConfig {
            imu,
            ..SensorConfig::default()
        };
        cfg.validate("preset").unwrap();
    }
    // datasheet figures in SI: MPU-6000 400 µg/√Hz, ICM-20602 100 µg/√Hz
    assert!((hobby.accel.noise_density - 400e-6 * G0_M_S2).abs() < 1e-12);
    assert!((better.accel.noise_density - 100e-6 * G0_M_S2).abs() < 1e-12);
    // the industrial IMU is better on every bias figure
    assert!(industrial.gyro.initial_bias_sigma < better.gyro.initial_bias_sigma);
    assert!(industrial.accel.initial_bias_sigma < better.accel.initial_bias_sigma);
    assert!(industrial.gyro.bias_random_walk < hobby.gyro.bias_random_walk);
}
