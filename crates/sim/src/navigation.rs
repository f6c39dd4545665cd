//! Sensors in the loop: the sensor models ([`SensorSuite`]) sample the true
//! motion and the on-board [`NavigationFilter`] of `helicon_gnc` (q-method +
//! fusion) turns the samples into the nine measured states of (15.2).
//! [`Navigator`] pairs the two for analyses that want navigation without the
//! controller; the closed loop flies `helicon_gnc::navigation::FlightComputer`.

use crate::sensors::{SensorConfig, SensorSample, SensorSuite};
use crate::trajectory::TruthSample;
use helicon_gnc::fusion::FusionError;
pub use helicon_gnc::navigation::NavigationConfig;
use helicon_gnc::navigation::{NavigationFilter, SensorFrame, SensorNoise};
use helicon_model::State;
use helicon_model::frames::EulerTrig;
use helicon_model::state::ix;
use nalgebra::{SVector, Vector3};

/// The sensor suite of `config` sampled every `dt_s` (its IMU rate is set to
/// 1/dt_s, the controller rate).
pub fn sensor_suite_at(config: &SensorConfig, dt_s: f64) -> Result<SensorSuite, FusionError> {
    let mut cfg = *config;
    cfg.imu.rate_hz = 1.0 / dt_s;
    SensorSuite::new(cfg).map_err(|_| FusionError::InvalidConfig {
        field: "imu.rate_hz",
        value: cfg.imu.rate_hz,
        allowed: "a valid sensor configuration at the controller rate",
    })
}

/// The noise figures of a sensor configuration, as the fusion filter needs them.
pub fn sensor_noise(config: &SensorConfig) -> SensorNoise {
    let g = &config.gps;
    SensorNoise {
        gps_sigma_m: Vector3::new(
            g.horizontal_sigma_m,
            g.horizontal_sigma_m,
            g.vertical_sigma_m,
        ),
        gps_vel_sigma_m_s: Vector3::new(
            g.velocity_sigma_m_s,
            g.velocity_sigma_m_s,
            2.0 * g.velocity_sigma_m_s,
        ),
        mag_field_ned: Vector3::from(config.mag.field_ned),
        gravity_m_s2: config.gravity_m_s2,
    }
}

/// A navigation filter initialised at the true full state `x0` (as after
/// alignment on the ground).
pub fn navigation_filter_at(
    config: &SensorConfig,
    nav: &NavigationConfig,
    dt_s: f64,
    x0: &State,
) -> Result<NavigationFilter, FusionError> {
    let trig = EulerTrig::new(x0[ix::PHI], x0[ix::THETA], x0[ix::PSI]);
    let v_ned = trig.ned_from_body() * Vector3::new(x0[ix::U], x0[ix::V], x0[ix::W]);
    let mut s0 = SVector::<f64, 9>::zeros();
    for i in 0..3 {
        s0[i] = x0[ix::X + i];
        s0[3 + i] = v_ned[i];
        s0[6 + i] = x0[ix::PHI + i];
    }
    NavigationFilter::new(
        nav,
        &sensor_noise(config),
        dt_s,
        &s0,
        &Vector3::new(x0[ix::P], x0[ix::Q], x0[ix::R]),
    )
}

/// The sensor frame the on-board software sees from one sensor sample.
pub fn frame(sample: &SensorSample) -> SensorFrame {
    SensorFrame {
        specific_force_body_m_s2: sample.specific_force_body_m_s2,
        gyro_body_rad_s: sample.gyro_body_rad_s,
        mag_body: sample.mag_body,
        gps_ned_m: sample.gps_ned_m,
        gps_vel_ned_m_s: sample.gps_vel_ned_m_s,
    }
}

/// Sensor models + on-board navigation.
#[derive(Debug, Clone)]
pub struct Navigator {
    suite: SensorSuite,
    filter: NavigationFilter,
}

impl Navigator {
    /// A navigator sampling at `dt_s`, initialised at the true state `x0`.
    pub fn new(
        config: SensorConfig,
        nav: &NavigationConfig,
        dt_s: f64,
        x0: &State,
    ) -> Result<Self, FusionError> {
        Ok(Navigator {
            suite: sensor_suite_at(&config, dt_s)?,
            filter: navigation_filter_at(&config, nav, dt_s, x0)?,
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
        self.filter.step(&frame(&sample), own_accel_body)
    }

    /// The navigation filter.
    pub fn filter(&self) -> &NavigationFilter {
        &self.filter
    }
}
