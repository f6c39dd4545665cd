//! Sensors in the loop: the sensor models sample the true motion, and the
//! on-board navigation (q-method attitude determination (13.4)–(13.12) + the
//! GPS/IMU fusion filter (13.15)–(13.29)) turns the samples into the nine
//! measured states of (15.2) that the state estimator expects:
//! [φ θ ψ] from the fusion filter, [u v w] = R_be(Θ̂)·v̂_ned, [p q r] from the gyro.
//!
//! The helicopter's own acceleration needed by the gravity observation (13.2)
//! comes from the caller: the flight controller's state estimator predicts it
//! (`FlightController::predicted_accel_body`). Differencing the fused
//! velocity instead is degenerate (the subtraction then returns the predicted
//! attitude itself; docs/sensors.md).
//!
//! The fusion filter has no bias states (nor has the thesis's), so its
//! process noise is inflated to absorb the IMU biases: 3 m/s² and 0.2 rad/s
//! per sample, the values `helicon fuse` uses by default.

use crate::sensors::{SensorConfig, SensorSuite};
use crate::trajectory::TruthSample;
use helicon_gnc::attitude::{VectorObservation, gravity_observation, q_method};
use helicon_gnc::fusion::{FusionConfig, FusionError, FusionFilter, FusionInput};
use helicon_model::State;
use helicon_model::frames::EulerTrig;
use helicon_model::state::ix;
use nalgebra::{SMatrix, SVector, Vector3};

/// Sensor models + attitude determination + fusion filter.
#[derive(Debug, Clone)]
pub struct Navigator {
    suite: SensorSuite,
    filter: FusionFilter,
    field_ned: Vector3<f64>,
    last_f: Vector3<f64>,
    last_w: Vector3<f64>,
}

impl Navigator {
    /// A navigator sampling at the controller period `dt_s` (the IMU rate is
    /// set to 1/dt_s), initialised at the true state `x0` (as after alignment
    /// on the ground) with a modest uncertainty.
    pub fn new(config: SensorConfig, dt_s: f64, x0: &State) -> Result<Self, FusionError> {
        let mut cfg = config;
        cfg.imu.rate_hz = 1.0 / dt_s;
        let suite = SensorSuite::new(cfg).map_err(|_| FusionError::InvalidConfig {
            field: "imu.rate_hz",
            value: cfg.imu.rate_hz,
            allowed: "a valid sensor configuration at the controller rate",
        })?;
        let fcfg = FusionConfig {
            dt_s,
            gravity_m_s2: cfg.gravity_m_s2,
            accel_sigma_m_s2: 3.0,
            euler_rate_sigma_rad_s: 0.2,
            gps_sigma_m: Vector3::new(
                cfg.gps.horizontal_sigma_m,
                cfg.gps.horizontal_sigma_m,
                cfg.gps.vertical_sigma_m,
            ),
            attitude_sigma_rad: Vector3::repeat(0.03),
        };
        let trig = EulerTrig::new(x0[ix::PHI], x0[ix::THETA], x0[ix::PSI]);
        let v_ned = trig.ned_from_body() * Vector3::new(x0[ix::U], x0[ix::V], x0[ix::W]);
        let mut s0 = SVector::<f64, 9>::zeros();
        for i in 0..3 {
            s0[i] = x0[ix::X + i];
            s0[3 + i] = v_ned[i];
            s0[6 + i] = x0[ix::PHI + i];
        }
        let p0 = SMatrix::<f64, 9, 9>::from_diagonal(&SVector::<f64, 9>::from_row_slice(&[
            1.0, 1.0, 1.0, 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4,
        ]));
        let filter = FusionFilter::new(fcfg, s0, p0)?;
        Ok(Navigator {
            suite,
            filter,
            field_ned: Vector3::from(cfg.mag.field_ned),
            last_f: trig.ned_from_body().transpose() * Vector3::new(0.0, 0.0, -cfg.gravity_m_s2),
            last_w: Vector3::new(x0[ix::P], x0[ix::Q], x0[ix::R]),
        })
    }

    /// One sample: sense the truth, determine attitude (subtracting
    /// `own_accel_body`, m/s², if given), fuse; returns the nine measured states.
    pub fn step(
        &mut self,
        truth: &TruthSample,
        own_accel_body: Option<&Vector3<f64>>,
    ) -> Result<SVector<f64, 9>, FusionError> {
        let sample = self.suite.sample(truth);
        let attitude = sample.mag_body.and_then(|m| {
            let obs = [
                gravity_observation(1.0, &sample.specific_force_body_m_s2, own_accel_body),
                VectorObservation::new(1.0, m, self.field_ned),
            ];
            q_method(&obs).ok().map(|sol| sol.euler())
        });
        self.filter.step(&FusionInput {
            specific_force_body_m_s2: self.last_f,
            gyro_body_rad_s: self.last_w,
            gps_ned_m: sample.gps_ned_m,
            attitude_rad: attitude,
        })?;
        self.last_f = sample.specific_force_body_m_s2;
        self.last_w = sample.gyro_body_rad_s;
        let s = *self.filter.state();
        let vel = Vector3::new(s[3], s[4], s[5]);
        let trig = EulerTrig::new(s[6], s[7], s[8]);
        let v_body = trig.ned_from_body().transpose() * vel;
        let mut y = SVector::<f64, 9>::zeros();
        for i in 0..3 {
            y[i] = s[6 + i];
            y[3 + i] = v_body[i];
            y[6 + i] = sample.gyro_body_rad_s[i];
        }
        Ok(y)
    }

    /// The fusion filter (for logging its covariance).
    pub fn filter(&self) -> &FusionFilter {
        &self.filter
    }
}
