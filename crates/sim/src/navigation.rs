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
//! The fusion filter has no bias states (nor has the thesis's); its process
//! noise ([`NavigationConfig`]) absorbs the IMU biases. Beyond the thesis, the
//! GPS receiver's Doppler velocity is fused too (hobby receivers give it at
//! ~0.05 m/s): with position-only fixes of 1.5 m white noise the velocity
//! estimate is too noisy to close the loop on (the helicopter diverges within
//! seconds in the `beyond-physical-turbulence` scenario); with it, the
//! default tuning 0.5 m/s², 0.02 rad/s, 0.03 rad flies the scenario.

use crate::sensors::{SensorConfig, SensorSuite};
use crate::trajectory::TruthSample;
use helicon_gnc::attitude::{VectorObservation, gravity_observation, q_method};
use helicon_gnc::fusion::{FusionConfig, FusionError, FusionFilter, FusionInput};
use helicon_model::State;
use helicon_model::frames::EulerTrig;
use helicon_model::state::ix;
use nalgebra::{SMatrix, SVector, Vector3};

/// Tuning of the navigation filter (TOML `[navigation]`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NavigationConfig {
    /// Process noise of the NED acceleration input per sample (m/s²).
    pub accel_sigma_m_s2: f64,
    /// Process noise of the Euler-rate input per sample (rad/s).
    pub euler_rate_sigma_rad_s: f64,
    /// Standard deviation of the q-method attitude measurement (rad).
    pub attitude_sigma_rad: f64,
    /// Weight of the gravity observation in the q-method (the magnetometer's is 1).
    pub gravity_weight: f64,
}

impl Default for NavigationConfig {
    fn default() -> Self {
        NavigationConfig {
            accel_sigma_m_s2: 0.5,
            euler_rate_sigma_rad_s: 0.02,
            attitude_sigma_rad: 0.03,
            gravity_weight: 1.0,
        }
    }
}

impl NavigationConfig {
    /// Check every field is finite and positive.
    pub fn validate(&self) -> Result<(), FusionError> {
        for (field, value) in [
            ("navigation.accel_sigma_m_s2", self.accel_sigma_m_s2),
            (
                "navigation.euler_rate_sigma_rad_s",
                self.euler_rate_sigma_rad_s,
            ),
            ("navigation.attitude_sigma_rad", self.attitude_sigma_rad),
            ("navigation.gravity_weight", self.gravity_weight),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(FusionError::InvalidConfig {
                    field,
                    value,
                    allowed: "finite and > 0",
                });
            }
        }
        Ok(())
    }
}

/// Sensor models + attitude determination + fusion filter.
#[derive(Debug, Clone)]
pub struct Navigator {
    suite: SensorSuite,
    filter: FusionFilter,
    field_ned: Vector3<f64>,
    gravity_weight: f64,
    last_f: Vector3<f64>,
    last_w: Vector3<f64>,
}

impl Navigator {
    /// A navigator sampling at the controller period `dt_s` (the IMU rate is
    /// set to 1/dt_s), initialised at the true state `x0` (as after alignment
    /// on the ground) with a modest uncertainty.
    pub fn new(
        config: SensorConfig,
        nav: &NavigationConfig,
        dt_s: f64,
        x0: &State,
    ) -> Result<Self, FusionError> {
        nav.validate()?;
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
            accel_sigma_m_s2: nav.accel_sigma_m_s2,
            euler_rate_sigma_rad_s: nav.euler_rate_sigma_rad_s,
            gps_sigma_m: Vector3::new(
                cfg.gps.horizontal_sigma_m,
                cfg.gps.horizontal_sigma_m,
                cfg.gps.vertical_sigma_m,
            ),
            gps_vel_sigma_m_s: Vector3::new(
                cfg.gps.velocity_sigma_m_s,
                cfg.gps.velocity_sigma_m_s,
                2.0 * cfg.gps.velocity_sigma_m_s,
            )
            .map(|v| v.max(1e-3)),
            attitude_sigma_rad: Vector3::repeat(nav.attitude_sigma_rad),
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
            gravity_weight: nav.gravity_weight,
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
                gravity_observation(
                    self.gravity_weight,
                    &sample.specific_force_body_m_s2,
                    own_accel_body,
                ),
                VectorObservation::new(1.0, m, self.field_ned),
            ];
            q_method(&obs).ok().map(|sol| sol.euler())
        });
        self.filter.step(&FusionInput {
            specific_force_body_m_s2: self.last_f,
            gyro_body_rad_s: self.last_w,
            gps_ned_m: sample.gps_ned_m,
            gps_vel_ned_m_s: sample.gps_vel_ned_m_s,
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
