//! Design the controller, build the flight computer from the gains, and fly
//! a closed-loop scenario (thesis chapters 14–15).
#![allow(missing_docs)]

use helicon_core::sensor::{ImuSample, SensorFrame, SensorNoise};
use helicon_core::{
    FlightComputer, KalmanPredictor, Lqi, NavigationConfig, NavigationFilter, Reference,
    ServoLimits, ThesisEstimator,
};
use helicon_gnc::design::{ControllerConfig, Gains, design};
use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Input, Model, Params, Preset};
use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
use nalgebra::{SVector, Vector3};

fn main() -> anyhow::Result<()> {
    // 1. Design at hover, at the helicopter's own sample time.
    let model = Model::new(Params::bergen_twin(), Preset::Physical.options());
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default())?;
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged)?;
    let ts = model.params().control.sample_time_s;
    let (phi, gamma) = lm.discretize(ts)?;
    let gains = design(&phi, &gamma, &t.x, &t.u, ts, &ControllerConfig::default())?;
    let path = std::env::temp_dir().join("helicon-example-gains.json");
    gains.save(&path)?;
    println!(
        "designed at {:.0} Hz, pincer alpha {:.5}, closed-loop |z|max {:.5}; wrote {}",
        1.0 / ts,
        gains.set.alpha,
        gains.spectral_radius(),
        path.display()
    );

    // 2. The flight computer from the gains file, as the on-board program builds it.
    let gains = Gains::load(&path)?;
    let p = model.params();
    let g = p.environment.g_m_s2;
    let limits = ServoLimits {
        min: Input::from_fn(|i, _| p.servos[i].s_min),
        max: Input::from_fn(|i, _| p.servos[i].s_max),
    };
    let noise = SensorNoise {
        gps_sigma_m: Vector3::new(1.5, 1.5, 3.0),
        gps_vel_sigma_m_s: Vector3::new(0.05, 0.05, 0.1),
        mag_field_ned: Vector3::new(0.153, 0.008, -0.438),
        gravity_m_s2: g,
    };
    let mut nav0 = SVector::<f64, 9>::zeros();
    for i in 0..3 {
        nav0[6 + i] = t.x[i]; // attitude at trim
    }
    let estimator = ThesisEstimator {
        navigation: NavigationFilter::new(
            &NavigationConfig::default(),
            &noise,
            ts,
            &nav0,
            &Vector3::zeros(),
        )?,
        predictor: KalmanPredictor::new(&gains.set, &gains.set.x_trim)?,
    };
    let mut computer = FlightComputer::new(estimator, Lqi::new(&gains.set, limits, true)?);
    let specific_force = helicon_model::frames::EulerTrig::new(t.x[0], t.x[1], 0.0)
        .ned_from_body()
        .transpose()
        * Vector3::new(0.0, 0.0, -g);
    for k in 0..4u32 {
        let frame = SensorFrame::imu_only(
            f64::from(k) * ts,
            ImuSample {
                specific_force_body_m_s2: specific_force,
                gyro_body_rad_s: Vector3::zeros(),
            },
        );
        let tel = computer.step(&frame, &Reference::default())?;
        println!(
            "  sample {}: servos {:.5?}",
            tel.sample,
            tel.command.as_slice()
        );
    }

    // 3. A whole closed-loop scenario (the format of scenarios/*.toml).
    let scenario = Scenario::from_toml_str(
        r#"
name = "north step"
duration_s = 10.0
[[reference]]
t_s = 1.0
output = "vn"
value = 1.0
[controller]
fusion = true
"#,
        "<example>",
    )?;
    let prepared = prepare(&scenario)?;
    let flight = fly(&scenario, &prepared, None)?;
    let s = &flight.summary;
    println!(
        "flew '{}': {} at {:.2} s; vn RMS error {:.4} m/s, settling to 1 %: {}",
        s.scenario,
        s.outcome.as_str(),
        s.t_end_s,
        s.metrics["vn"].rms_error,
        s.metrics["vn"].settling_time_s.map_or_else(
            || "not within the band at the end (sensor noise)".into(),
            |t| format!("{t:.2} s")
        )
    );
    Ok(())
}
