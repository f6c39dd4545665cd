//! Sensors in the loop: the simulator's sensor models ([`SensorSuite`])
//! sampled at the controller rate and the core's [`NavigationFilter`] set up
//! from the same configuration. The navigation itself lives in
//! `helicon_core`: the closed loop and `helicon fuse` run that one type.

use crate::sensors::{SensorConfig, SensorConfigError, SensorSuite};
use helicon_core::eskf::{Eskf, EskfConfig, ImuNoise};
use helicon_core::fusion::FusionError;
pub use helicon_core::navigation::NavigationConfig;
use helicon_core::navigation::NavigationFilter;
use helicon_core::sensor::SensorNoise;
pub use helicon_setup::builder::{eskf_at, navigation_filter_at, navigation_initial};
pub use helicon_setup::sensors::{imu_noise, sensor_noise};
use nalgebra::{SVector, Vector3};

/// The sensor suite of `config` sampled every `dt_s` (its IMU rate is set to
/// 1/dt_s, the controller rate) in local gravity `gravity_m_s2`.
pub fn sensor_suite_at(
    config: &SensorConfig,
    dt_s: f64,
    gravity_m_s2: f64,
) -> Result<SensorSuite, SensorConfigError> {
    let mut cfg = *config;
    cfg.imu.rate_hz = 1.0 / dt_s;
    SensorSuite::new(cfg, gravity_m_s2)
}

/// How a navigation replaying a sensor log is initialised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReplayInit {
    /// From the log's truth columns of the first row (position, velocity,
    /// attitude, rates), as the closed loop initialises its navigation
    /// (alignment on the ground). Needs a simulated log.
    Truth,
    /// From the sensors: the first GPS fix (position, and velocity when
    /// logged; else at rest), the first q-method attitude, the first gyro sample.
    Sensors,
}

/// Errors replaying a sensor log.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The log cannot serve the requested initialisation.
    #[error("{file}: {message}")]
    Init {
        /// The log.
        file: String,
        /// What is missing.
        message: String,
    },
    /// The navigation failed at a row.
    #[error("{file}: at t = {t_s} s: {source}")]
    Navigation {
        /// The log.
        file: String,
        /// Time of the row.
        t_s: f64,
        /// Cause.
        #[source]
        source: FusionError,
    },
    /// The log's sampling.
    #[error(transparent)]
    Log(#[from] crate::sensor_log::SensorLogError),
}

/// The navigation's initial state `[x y z vn ve vd φ θ ψ]` and body rates for
/// replaying `log`.
pub fn replay_initial(
    log: &crate::sensor_log::SensorLog,
    init: ReplayInit,
    noise: &SensorNoise,
) -> Result<(SVector<f64, 9>, Vector3<f64>), ReplayError> {
    let file = log.file.display().to_string();
    let first = log.rows.first().ok_or_else(|| ReplayError::Init {
        file: file.clone(),
        message: "empty log".into(),
    })?;
    let mut s0 = SVector::<f64, 9>::zeros();
    match init {
        ReplayInit::Truth => {
            let t = &first.truth;
            let (Some(p), Some(v), Some(e), Some(w)) = (
                t.position_ned_m,
                t.velocity_ned_m_s,
                t.euler_rad,
                t.rates_body_rad_s,
            ) else {
                return Err(ReplayError::Init {
                    file,
                    message: "initialising from the truth needs the true position, velocity, \
                              attitude and rate columns in the first row (a simulated log); \
                              use the sensors instead"
                        .into(),
                });
            };
            for i in 0..3 {
                s0[i] = p[i];
                s0[3 + i] = v[i];
                s0[6 + i] = e[i];
            }
            Ok((s0, w))
        }
        ReplayInit::Sensors => {
            let fix = log.rows.iter().find_map(|r| r.frame.gps);
            let attitude = log.rows.iter().find_map(|r| {
                let m = r.frame.mag_body?;
                let obs = [
                    helicon_core::attitude::gravity_observation(
                        1.0,
                        &r.frame.imu.specific_force_body_m_s2,
                        None,
                    ),
                    helicon_core::attitude::VectorObservation::new(1.0, m, noise.mag_field_ned),
                ];
                helicon_core::attitude::q_method(&obs)
                    .ok()
                    .map(|s| s.euler())
            });
            let Some(attitude) = attitude else {
                return Err(ReplayError::Init {
                    file,
                    message: "no row gives a q-method attitude (magnetometer and accelerometer \
                              needed) to initialise the navigation"
                        .into(),
                });
            };
            if let Some(g) = fix {
                for i in 0..3 {
                    s0[i] = g.position_ned_m[i];
                    s0[3 + i] = g.velocity_ned_m_s.map_or(0.0, |v| v[i]);
                }
            }
            for i in 0..3 {
                s0[6 + i] = attitude[i];
            }
            Ok((s0, first.frame.imu.gyro_body_rad_s))
        }
    }
}

/// Which navigation a replay runs, with its tuning.
#[derive(Debug, Clone, Copy)]
pub enum ReplayNavigation<'a> {
    /// The thesis's navigation (q-method + fusion filter).
    Thesis(&'a NavigationConfig),
    /// The ESKF, with the IMU figures it assumes ([`imu_noise`]).
    Eskf(&'a EskfConfig, ImuNoise),
}

/// A navigation being replayed.
#[derive(Debug, Clone)]
pub enum ReplayFilter {
    /// The thesis's navigation.
    Thesis(Box<NavigationFilter>),
    /// The ESKF.
    Eskf(Box<Eskf>),
}

impl ReplayFilter {
    fn step(&mut self, frame: &helicon_core::SensorFrame) -> Result<SVector<f64, 9>, FusionError> {
        match self {
            ReplayFilter::Thesis(f) => f.step(frame),
            ReplayFilter::Eskf(f) => f.step(frame),
        }
    }

    /// The navigation solution after the last step.
    pub fn solution(&self) -> helicon_core::NavigationSolution {
        match self {
            ReplayFilter::Thesis(f) => f.solution(),
            ReplayFilter::Eskf(f) => f.solution(),
        }
    }

    /// 1σ of the attitude (rad): of the Euler angles for the thesis's
    /// filter, of the body-axis attitude error for the ESKF (the same to
    /// first order near level flight).
    pub fn attitude_sigma_rad(&self) -> Vector3<f64> {
        let (p, i) = match self {
            ReplayFilter::Thesis(f) => {
                let c = f.filter().covariance();
                return Vector3::new(c[(6, 6)], c[(7, 7)], c[(8, 8)]).map(f64::sqrt);
            }
            ReplayFilter::Eskf(f) => (f.covariance(), 0),
        };
        Vector3::new(p[(i, i)], p[(i + 1, i + 1)], p[(i + 2, i + 2)]).map(f64::sqrt)
    }
}

/// Replay a sensor log through a navigation that flies: one step per row,
/// calling `each(row, y, filter)` with the nine measured states it produced.
pub fn replay_navigation<E>(
    log: &crate::sensor_log::SensorLog,
    nav: ReplayNavigation<'_>,
    noise: &SensorNoise,
    init: ReplayInit,
    mut each: impl FnMut(
        &crate::sensor_log::SensorLogRow,
        &SVector<f64, 9>,
        &ReplayFilter,
    ) -> Result<(), E>,
) -> Result<Result<(), E>, ReplayError> {
    let dt = crate::sensor_log::uniform_step_s(log)?;
    let (s0, omega0) = replay_initial(log, init, noise)?;
    let file = log.file.display().to_string();
    let built = match nav {
        ReplayNavigation::Thesis(cfg) => NavigationFilter::new(cfg, noise, dt, &s0, &omega0)
            .map(|f| ReplayFilter::Thesis(Box::new(f))),
        ReplayNavigation::Eskf(cfg, imu) => {
            Eskf::new(cfg, &imu, noise, dt, &s0).map(|f| ReplayFilter::Eskf(Box::new(f)))
        }
    };
    let mut filter = built.map_err(|source| ReplayError::Navigation {
        file: file.clone(),
        t_s: log.rows[0].frame.t_s,
        source,
    })?;
    for row in &log.rows {
        let y = filter
            .step(&row.frame)
            .map_err(|source| ReplayError::Navigation {
                file: file.clone(),
                t_s: row.frame.t_s,
                source,
            })?;
        if let Err(e) = each(row, &y, &filter) {
            return Ok(Err(e));
        }
    }
    Ok(Ok(()))
}
