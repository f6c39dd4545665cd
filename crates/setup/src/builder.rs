//! The one builder of the sensor-fed flight computer: gains (or a gain
//! schedule), the sensors' figures, the navigation's tuning and the
//! estimator choice turned into the core's [`SensorComputer`] (navigation +
//! Kalman predictor + LQI), started from an aligned state. `helicon sim`
//! (with `fusion = true`), SITL and `helicon onboard` all build what flies
//! here, so the three fly the same software.

use crate::estimator::{EstimatorKind, EstimatorSection};
use crate::sensors::{SensorConfig, imu_noise, sensor_noise};
use helicon_config::ConfigError;
use helicon_core::eskf::{Eskf, EskfConfig};
use helicon_core::frames::EulerTrig;
use helicon_core::fusion::FusionError;
use helicon_core::imu_health::{ImuHealthConfig, ImuHealthMonitor};
use helicon_core::navigation::{NavigationConfig, NavigationFilter};
use helicon_core::schedule::{AnyPredictor, Law, ScheduledLqi, ScheduledPredictor};
use helicon_core::state::{REDUCED_OFFSET, ReducedState, State, ix};
use helicon_core::{
    CoreError, EskfEstimator, FlightComputer, GainSchedule, GainSet, KalmanPredictor, Lqi,
    SensorComputer, ServoLimits, ThesisEstimator,
};
use nalgebra::{SVector, Vector3};
use std::sync::Arc;

/// Errors building the flight computer.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The gains or the schedule could not make a law or a predictor.
    #[error("flight software: {0}")]
    Core(#[from] CoreError),
    /// The navigation could not be set up from the sensors' figures.
    #[error(transparent)]
    Fusion(#[from] FusionError),
    /// A configuration value the flight software cannot use.
    #[error(transparent)]
    Config(#[from] ConfigError),
}

/// The predictor's initial reduced state: the nine measured states of `x0`
/// and the trim for the rest.
fn estimator_start(trim_x: &ReducedState, x0: &State) -> ReducedState {
    let mut x0_est: ReducedState = *trim_x;
    for i in 0..9 {
        x0_est[i] = x0[i + REDUCED_OFFSET];
    }
    x0_est
}

/// What the on-board chain is built from, wherever it flies.
#[derive(Debug, Clone, Copy)]
pub struct OnBoardSetup<'a> {
    /// The servo range the law saturates to (the parameters').
    pub servo_limits: ServoLimits,
    /// Local gravity (m/s², the parameters' `environment.g_m_s2`).
    pub gravity_m_s2: f64,
    /// The gains flown (their sample time is the control period); with a
    /// schedule, its design point nearest the trim.
    pub gains: &'a GainSet,
    /// The gain schedule flown instead of `gains`, when one is configured.
    pub schedule: Option<&'a Arc<GainSchedule>>,
    /// The trim the predictor starts from for the states not measured.
    pub trim_x: &'a ReducedState,
    /// The sensors' noise figures and local magnetic field (the navigation's
    /// measurement model).
    pub sensors: &'a SensorConfig,
    /// The thesis navigation's tuning.
    pub navigation: &'a NavigationConfig,
    /// Which navigation flies (thesis chain or ESKF) and the ESKF's tuning.
    pub estimator: &'a EstimatorSection,
    /// Feedback on (off: trim inputs held).
    pub feedback: bool,
    /// The full state the navigation and the predictor start from (after
    /// alignment on the ground).
    pub x0: &'a State,
}

impl OnBoardSetup<'_> {
    /// The control law: one design's LQI or the schedule's.
    pub fn law(&self) -> Result<Law, BuildError> {
        let limits = self.servo_limits;
        Ok(match self.schedule {
            Some(s) => Law::Scheduled(ScheduledLqi::new(Arc::clone(s), limits, self.feedback)?),
            None => Law::Fixed(Lqi::new(self.gains, limits, self.feedback)?),
        })
    }

    /// The Kalman predictor, started from the measured states of `x0` and
    /// the trim for the rest: one design's or the schedule's.
    pub fn predictor(&self) -> Result<AnyPredictor, BuildError> {
        let x0_est = estimator_start(self.trim_x, self.x0);
        Ok(match self.schedule {
            Some(s) => AnyPredictor::Scheduled(ScheduledPredictor::new(Arc::clone(s), &x0_est)?),
            None => AnyPredictor::Fixed(KalmanPredictor::new(self.gains, &x0_est)?),
        })
    }
}

/// The sensor-fed on-board chain (navigation + Kalman predictor + LQI, the
/// navigation being the thesis's or the ESKF as configured) exactly as the
/// simulator flies it with `fusion = true`: `helicon sim`, `helicon sitl`
/// and `helicon onboard` all build their flight computer here.
pub fn flight_computer(setup: &OnBoardSetup<'_>) -> Result<SensorComputer, BuildError> {
    let ts = setup.gains.sample_time_s;
    let g = setup.gravity_m_s2;
    let law = setup.law()?;
    let predictor = setup.predictor()?;
    Ok(match setup.estimator.kind {
        EstimatorKind::Thesis => {
            let navigation =
                navigation_filter_at(setup.sensors, setup.navigation, ts, g, setup.x0)?;
            SensorComputer::Thesis(FlightComputer::new(
                ThesisEstimator {
                    navigation,
                    predictor,
                },
                law,
            ))
        }
        EstimatorKind::Eskf => {
            let navigation = eskf_at(setup.sensors, &setup.estimator.eskf, ts, g, setup.x0)?;
            SensorComputer::Eskf(FlightComputer::new(
                EskfEstimator {
                    navigation,
                    predictor,
                },
                law,
            ))
        }
    })
}

/// The navigation's initial state `[x y z vn ve vd φ θ ψ]` and body rates
/// from a full state (as after alignment on the ground).
pub fn navigation_initial(x0: &State) -> (SVector<f64, 9>, Vector3<f64>) {
    let trig = EulerTrig::new(x0[ix::PHI], x0[ix::THETA], x0[ix::PSI]);
    let v_ned = trig.ned_from_body() * Vector3::new(x0[ix::U], x0[ix::V], x0[ix::W]);
    let mut s0 = SVector::<f64, 9>::zeros();
    for i in 0..3 {
        s0[i] = x0[ix::X + i];
        s0[3 + i] = v_ned[i];
        s0[6 + i] = x0[ix::PHI + i];
    }
    (s0, Vector3::new(x0[ix::P], x0[ix::Q], x0[ix::R]))
}

/// A navigation filter initialised at the full state `x0`.
pub fn navigation_filter_at(
    config: &SensorConfig,
    nav: &NavigationConfig,
    dt_s: f64,
    gravity_m_s2: f64,
    x0: &State,
) -> Result<NavigationFilter, FusionError> {
    let (s0, omega0) = navigation_initial(x0);
    NavigationFilter::new(nav, &sensor_noise(config, gravity_m_s2), dt_s, &s0, &omega0)
}

/// An ESKF navigation initialised at the full state `x0`.
pub fn eskf_at(
    config: &SensorConfig,
    eskf: &EskfConfig,
    dt_s: f64,
    gravity_m_s2: f64,
    x0: &State,
) -> Result<Eskf, FusionError> {
    let (s0, _) = navigation_initial(x0);
    Eskf::new(
        eskf,
        &imu_noise(config),
        &sensor_noise(config, gravity_m_s2),
        dt_s,
        &s0,
    )
}

/// The IMU health monitor the flight software runs (`helicon sim`, SITL
/// and the on-board program alike): local gravity `gravity_m_s2`, one
/// sample per control period, the accelerometer range of `sensors` (`file`
/// names the configuration in the error).
pub fn imu_health_at(
    gravity_m_s2: f64,
    sample_time_s: f64,
    sensors: &SensorConfig,
    file: &str,
) -> Result<ImuHealthMonitor, ConfigError> {
    let cfg = ImuHealthConfig::new(gravity_m_s2, sample_time_s, sensors.imu.accel.range);
    ImuHealthMonitor::new(cfg).ok_or_else(|| {
        ConfigError::invalid(
            file,
            "sensors.imu.accel.range",
            cfg.accel_range_m_s2,
            format!(
                "the IMU health monitor's `{}` must be finite and > 0",
                cfg.first_invalid().unwrap_or("setting")
            ),
        )
    })
}
