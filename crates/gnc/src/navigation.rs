//! On-board navigation and the flight computer.
//!
//! [`NavigationFilter`]: sensor samples → q-method attitude determination
//! (13.4)–(13.12) + the GPS/IMU fusion filter (13.15)–(13.29) → the nine
//! measured states of (15.2) the state estimator expects:
//! [φ θ ψ] from the fusion filter, [u v w] = R_be(Θ̂)·v̂_ned, [p q r] from the gyro.
//!
//! [`FlightComputer`]: the whole on-board chain of DESIGN.md — sensor samples
//! → navigation → estimator → LQR with integral action → saturated servo
//! commands — one allocation-free [`FlightComputer::step`] per sample. The
//! same type flies in simulation (`helicon_sim`) and, later, on board.
//!
//! The helicopter's own acceleration needed by the gravity observation (13.2)
//! is the flight controller's estimator prediction
//! ([`FlightController::predicted_accel_body`]). Differencing the fused
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

use crate::attitude::{VectorObservation, gravity_observation, q_method};
use crate::controller::{ControllerOutput, Feedback, FlightController, Reference};
use crate::fusion::{FusionConfig, FusionError, FusionFilter, FusionInput};
use helicon_model::frames::EulerTrig;
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

/// What the sensors deliver in one sample (body axes FRD, NED).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorFrame {
    /// Accelerometer specific force (m/s²).
    pub specific_force_body_m_s2: Vector3<f64>,
    /// Gyro rates (rad/s).
    pub gyro_body_rad_s: Vector3<f64>,
    /// Magnetometer reading, when sampled (field units of `field_ned`).
    pub mag_body: Option<Vector3<f64>>,
    /// GPS position fix NED (m), when delivered.
    pub gps_ned_m: Option<Vector3<f64>>,
    /// GPS velocity NED (m/s), when delivered.
    pub gps_vel_ned_m_s: Option<Vector3<f64>>,
}

/// Sensor noise figures the fusion filter needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorNoise {
    /// GPS position σ per NED axis (m).
    pub gps_sigma_m: Vector3<f64>,
    /// GPS velocity σ per NED axis (m/s).
    pub gps_vel_sigma_m_s: Vector3<f64>,
    /// The local magnetic field in NED (13.14), in the magnetometer's units.
    pub mag_field_ned: Vector3<f64>,
    /// Gravity (m/s²).
    pub gravity_m_s2: f64,
}

/// Attitude determination + fusion filter (fixed-size, `step` does not allocate).
#[derive(Debug, Clone)]
pub struct NavigationFilter {
    filter: FusionFilter,
    field_ned: Vector3<f64>,
    gravity_weight: f64,
    last_f: Vector3<f64>,
    last_w: Vector3<f64>,
}

impl NavigationFilter {
    /// A filter sampled every `dt_s`, initialised at position, NED velocity
    /// and attitude `[x y z vn ve vd φ θ ψ]` (as after alignment on the
    /// ground) with a modest uncertainty, the body rates `omega0` and the
    /// specific force of level rest.
    pub fn new(
        config: &NavigationConfig,
        noise: &SensorNoise,
        dt_s: f64,
        initial: &SVector<f64, 9>,
        omega0: &Vector3<f64>,
    ) -> Result<Self, FusionError> {
        config.validate()?;
        let fcfg = FusionConfig {
            dt_s,
            gravity_m_s2: noise.gravity_m_s2,
            accel_sigma_m_s2: config.accel_sigma_m_s2,
            euler_rate_sigma_rad_s: config.euler_rate_sigma_rad_s,
            gps_sigma_m: noise.gps_sigma_m,
            gps_vel_sigma_m_s: noise.gps_vel_sigma_m_s.map(|v| v.max(1e-3)),
            attitude_sigma_rad: Vector3::repeat(config.attitude_sigma_rad),
        };
        let p0 = SMatrix::<f64, 9, 9>::from_diagonal(&SVector::<f64, 9>::from_row_slice(&[
            1.0, 1.0, 1.0, 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4,
        ]));
        let filter = FusionFilter::new(fcfg, *initial, p0)?;
        let trig = EulerTrig::new(initial[6], initial[7], initial[8]);
        Ok(NavigationFilter {
            filter,
            field_ned: noise.mag_field_ned,
            gravity_weight: config.gravity_weight,
            last_f: trig.ned_from_body().transpose() * Vector3::new(0.0, 0.0, -noise.gravity_m_s2),
            last_w: *omega0,
        })
    }

    /// One sample: determine attitude (subtracting `own_accel_body`, m/s², if
    /// given) when the magnetometer was sampled, fuse; returns the nine
    /// measured states.
    pub fn step(
        &mut self,
        frame: &SensorFrame,
        own_accel_body: Option<&Vector3<f64>>,
    ) -> Result<SVector<f64, 9>, FusionError> {
        let attitude = frame.mag_body.and_then(|m| {
            let obs = [
                gravity_observation(
                    self.gravity_weight,
                    &frame.specific_force_body_m_s2,
                    own_accel_body,
                ),
                VectorObservation::new(1.0, m, self.field_ned),
            ];
            q_method(&obs).ok().map(|sol| sol.euler())
        });
        self.filter.step(&FusionInput {
            specific_force_body_m_s2: self.last_f,
            gyro_body_rad_s: self.last_w,
            gps_ned_m: frame.gps_ned_m,
            gps_vel_ned_m_s: frame.gps_vel_ned_m_s,
            attitude_rad: attitude,
        })?;
        self.last_f = frame.specific_force_body_m_s2;
        self.last_w = frame.gyro_body_rad_s;
        let s = *self.filter.state();
        let vel = Vector3::new(s[3], s[4], s[5]);
        let v_body = EulerTrig::new(s[6], s[7], s[8]).ned_from_body().transpose() * vel;
        let mut y = SVector::<f64, 9>::zeros();
        for i in 0..3 {
            y[i] = s[6 + i];
            y[3 + i] = v_body[i];
            y[6 + i] = frame.gyro_body_rad_s[i];
        }
        Ok(y)
    }

    /// The fusion filter (its state and covariance).
    pub fn filter(&self) -> &FusionFilter {
        &self.filter
    }
}

/// The on-board chain: navigation + estimator + controller.
#[derive(Debug, Clone)]
pub struct FlightComputer {
    /// Navigation (attitude determination + fusion).
    pub navigation: NavigationFilter,
    /// Estimator + LQR with integral action.
    pub controller: FlightController,
}

impl FlightComputer {
    /// One sample: sensor frame and reference in, saturated servo commands out.
    /// Also returns the nine measured states the navigation produced.
    pub fn step(
        &mut self,
        frame: &SensorFrame,
        reference: &Reference,
    ) -> Result<(ControllerOutput, SVector<f64, 9>), FusionError> {
        let own = self.controller.predicted_accel_body();
        let y = self.navigation.step(frame, Some(&own))?;
        let out = self.controller.step(Feedback::Measured(&y), reference);
        Ok((out, y))
    }
}
