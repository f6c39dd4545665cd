//! Regenerates the figures of docs/sensors.md:
//! `cargo run -p helicon-sim --release --example sensors_figures -- docs/sensors`
//!
//! - thesis Figures 13.5/13.6 (GPS vs integrated accelerometer vs fused),
//! - thesis Figures 14.6/14.7 (wind speed and wind vector),
//! - Dryden turbulence time series and its sample PSD against MIL-F-8785C.
#![allow(clippy::unwrap_used)] // example: a failure aborts with a message

use helicon_core::fusion::{FusionConfig, FusionFilter, FusionInput, Matrix9, Vector9};
use helicon_sim::plot::{LinePlot, Series};
use helicon_sim::wind::{DrydenConfig, DrydenTurbulence, ThesisWind, ThesisWindConfig, WindModel};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;
use std::path::PathBuf;

fn main() {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "docs/sensors".into()),
    );
    std::fs::create_dir_all(&dir).unwrap();
    fig13(&dir);
    fig14(&dir);
    dryden(&dir);
    println!("figures written to {}", dir.display());
}

/// Same experiment as crates/gnc/tests/xval_fusion.rs (seed 1356).
fn fig13(dir: &std::path::Path) {
    let (t_end, dt, g) = (60.0, 0.01, 9.82);
    let pos = |t: f64| {
        Vector3::new(
            15.0 * (1.0 - (PI * t / t_end).cos()),
            30.0 * t / t_end + 5.0 * (2.0 * PI * t / t_end).sin(),
            0.0,
        )
    };
    let vel = |t: f64| {
        Vector3::new(
            15.0 * PI / t_end * (PI * t / t_end).sin(),
            30.0 / t_end + 5.0 * 2.0 * PI / t_end * (2.0 * PI * t / t_end).cos(),
            0.0,
        )
    };
    let acc = |t: f64| {
        Vector3::new(
            15.0 * (PI / t_end).powi(2) * (PI * t / t_end).cos(),
            -5.0 * (2.0 * PI / t_end).powi(2) * (2.0 * PI * t / t_end).sin(),
            0.0,
        )
    };
    let (sigma_acc, sigma_gps) = (0.1, 1.0);
    let bias = Vector3::new(0.02, -0.015, 0.0);
    let mut rng = ChaCha8Rng::seed_from_u64(1356);
    let na = Normal::new(0.0, sigma_acc).unwrap();
    let ng = Normal::new(0.0, sigma_gps).unwrap();
    let cfg = FusionConfig {
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
    let mut f = FusionFilter::new(cfg, x0, p0).unwrap();
    let (mut dp, mut dv) = (pos(0.0), vel(0.0));
    let (mut truth, mut gps, mut dr, mut fused) = (vec![], vec![], vec![], vec![]);
    for k in 1..=6000 {
        let (tp, t) = ((k - 1) as f64 * dt, k as f64 * dt);
        let a = acc(tp) + bias + Vector3::new(na.sample(&mut rng), na.sample(&mut rng), 0.0);
        let z = if k % 10 == 0 {
            Some(pos(t) + Vector3::new(ng.sample(&mut rng), ng.sample(&mut rng), 0.0))
        } else {
            None
        };
        f.step(&FusionInput {
            specific_force_body_m_s2: a - Vector3::new(0.0, 0.0, g),
            gyro_body_rad_s: Vector3::zeros(),
            gps_ned_m: z,
            gps_vel_ned_m_s: None,
            attitude_rad: Some(Vector3::zeros()),
        })
        .unwrap();
        dp += dv * dt + 0.5 * a * dt * dt;
        dv += a * dt;
        let p = pos(t);
        truth.push((p.y, p.x));
        if let Some(z) = z {
            gps.push((z.y, z.x));
        }
        dr.push((dp.y, dp.x));
        fused.push((f.state()[1], f.state()[0]));
    }
    LinePlot::new(
        "Thesis Fig. 13.5(a): GPS measurements",
        "east [m]",
        "north [m]",
    )
    .series(Series::new("actual trajectory", &truth))
    .series(Series::new("GPS (1 m, 10 Hz)", &gps))
    .write(&dir.join("fig13_5a_gps.png"))
    .unwrap();
    LinePlot::new(
        "Thesis Fig. 13.5(b): double-integrated accelerometer",
        "east [m]",
        "north [m]",
    )
    .series(Series::new("actual trajectory", &truth))
    .series(Series::new("integrated acc.", &dr))
    .write(&dir.join("fig13_5b_integrated_acc.png"))
    .unwrap();
    LinePlot::new("Thesis Fig. 13.6: fused estimate", "east [m]", "north [m]")
        .series(Series::new("actual trajectory", &truth))
        .series(Series::new("fused", &fused))
        .write(&dir.join("fig13_6_fused.png"))
        .unwrap();
}

fn fig14(dir: &std::path::Path) {
    let cfg = ThesisWindConfig::default();
    let mut m = ThesisWind::new(cfg, 14, 1).unwrap();
    let dt = 1.0 / 400.0;
    let (mut speed, mut wx, mut wy, mut wz) = (vec![], vec![], vec![], vec![]);
    for k in 0..2000 {
        let t = k as f64 * dt;
        let w = m.step(t, dt);
        if t <= 1.0 {
            speed.push((t, w.dot(&cfg.direction(t))));
        }
        wx.push((t, w.x));
        wy.push((t, w.y));
        wz.push((t, w.z));
    }
    LinePlot::new(
        "Thesis Fig. 14.6: wind speed |w(t)| (14.38), σ_t² = 0.1",
        "time [s]",
        "speed [m/s]",
    )
    .series(Series::new("|w(t)|", &speed))
    .write(&dir.join("fig14_6_wind_speed.png"))
    .unwrap();
    LinePlot::new(
        "Thesis Fig. 14.7: wind velocity (14.40)-(14.42), NED",
        "time [s]",
        "velocity [m/s]",
    )
    .series(Series::new("w_x (north)", &wx))
    .series(Series::new("w_y (east)", &wy))
    .series(Series::new("w_z (down)", &wz))
    .write(&dir.join("fig14_7_wind_vector.png"))
    .unwrap();
}

fn dryden(dir: &std::path::Path) {
    let cfg = DrydenConfig {
        w20_m_s: 15.4,
        altitude_m: 20.0,
        airspeed_m_s: 10.0,
        heading_rad: 0.0,
    };
    let dt = 1.0 / 100.0;
    let mut d = DrydenTurbulence::new(cfg, 5, 2).unwrap();
    let scales = *d.scales();
    let mut ts = [vec![], vec![], vec![]];
    let seg = 1 << 14;
    let n = seg * 60;
    let mut x = [vec![], vec![], vec![]];
    for k in 0..n {
        let v = d.step_uvw(dt);
        for a in 0..3 {
            x[a].push(v[a]);
            if k < 6000 {
                ts[a].push((k as f64 * dt, v[a]));
            }
        }
    }
    LinePlot::new(
        "Dryden turbulence, moderate (W20 = 15.4 m/s), h = 20 m, V = 10 m/s",
        "time [s]",
        "velocity [m/s]",
    )
    .series(Series::new("u (along mean wind)", &ts[0]))
    .series(Series::new("v (lateral)", &ts[1]))
    .series(Series::new("w (down)", &ts[2]))
    .write(&dir.join("dryden_time.png"))
    .unwrap();
    // Log-log PSD (plotted as log10 values on linear axes).
    let mut pl = LinePlot::new(
        "Dryden PSD: sample (Welch, dt = 0.01 s) vs MIL-F-8785C",
        "log10 frequency [Hz]",
        "log10 PSD [(m/s)²/Hz]",
    );
    let mut store = Vec::new();
    for a in 0..3 {
        let psd = helicon_sim::spectral::welch_psd(&x[a], dt, seg);
        let df = 1.0 / (dt * seg as f64);
        // Log-spaced averaging for a readable curve.
        let mut pts = vec![];
        let mut anal = vec![];
        let mut lo = 0.01;
        while lo < 50.0 {
            let hi = lo * 1.25;
            let (mut s, mut c) = (0.0, 0);
            for (k, p) in psd.iter().enumerate() {
                let f = k as f64 * df;
                if f >= lo && f < hi {
                    s += p;
                    c += 1;
                }
            }
            if c > 0 {
                let fm = (lo * hi).sqrt();
                pts.push((fm.log10(), (s / c as f64).log10()));
                anal.push((fm.log10(), scales.psd_one_sided(a, fm).log10()));
            }
            lo = hi;
        }
        store.push((pts, anal));
    }
    let names = [
        ("u sample", "u analytic"),
        ("v sample", "v analytic"),
        ("w sample", "w analytic"),
    ];
    for (a, (p, an)) in store.iter().enumerate() {
        pl = pl
            .series(Series::new(names[a].0, p))
            .series(Series::new(names[a].1, an));
    }
    pl.write(&dir.join("dryden_psd.png")).unwrap();
}
