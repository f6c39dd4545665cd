//! # helicon-core
//!
//! The on-board flight software of the helicopter, as one core that the
//! simulator, software-in-the-loop runs and the on-board runtime all fly. It
//! depends on nalgebra only and allocates nothing per control sample.
//!
//! Data flow per sample (thesis Figure 3.5 and Figure 14.4):
//!
//! ```text
//! SensorFrame ─► Estimator ─► Estimate ─► StateFeedback ─► Command ─► servos
//!                   ▲                                         │
//!                   └──────────── applied commands ◄──────────┘
//! ```
//!
//! - [`state`], [`frames`]: the state layout and rotations shared with the model;
//! - [`sensor`]: the one timestamped [`SensorFrame`];
//! - [`attitude`] (q-method, §13.2), [`fusion`] (GPS/IMU filter, §13.3),
//!   [`navigation`] (both, frames to the nine measured states);
//! - [`eskf`]: the error-state Kalman filter navigation with IMU bias
//!   states, GPS latency and innovation gating (beyond the thesis);
//! - [`estimator`]: the [`Estimator`] extension point; the thesis's chain,
//!   the Kalman predictor alone, the truth feed;
//! - [`lqi`]: the [`StateFeedback`] extension point; the LQR with integral action;
//! - [`gains`]: the fixed-size [`GainSet`] a design produces;
//! - [`imu_health`]: vibration level and likely hidden accelerometer
//!   saturation from the IMU output (thesis Appendix A);
//! - [`schedule`]: gain scheduling over the envelope ([`GainSchedule`],
//!   [`ScheduledLqi`], [`ScheduledPredictor`]);
//! - [`trajectory`]: jerk-limited references (S-curves, a mission of speed,
//!   yaw rate and climb);
//! - [`computer`]: [`FlightComputer`] and its [`Telemetry`].
//!
//! To add a sensor: a field in [`SensorFrame`] and its use in an estimator.
//! To add an estimator: implement [`Estimator`]. To add a control law:
//! implement [`StateFeedback`]. [`FlightComputer`] composes any pair.

pub mod attitude;
pub mod computer;
pub mod error;
pub mod eskf;
pub mod estimator;
pub mod frames;
pub mod fusion;
pub mod gains;
pub mod imu_health;
pub mod lqi;
pub mod navigation;
pub mod schedule;
pub mod sensor;
pub mod state;
pub mod trajectory;

pub use computer::{FlightComputer, SensorComputer, Telemetry};
pub use error::CoreError;
pub use eskf::{Eskf, EskfConfig, EskfDiagnostics, EskfEstimator, ImuNoise};
pub use estimator::{
    Estimate, Estimator, KalmanPredictor, NavigatedEstimator, Navigation, Predictor,
    StateMeasurement, ThesisEstimator, Timestamped, TruthFeed, TruthMeasurement,
};
pub use gains::{GainSet, LqiOptions, ServoLimits};
pub use imu_health::{ImuHealth, ImuHealthConfig, ImuHealthMonitor};
pub use lqi::{Command, Lqi, Reference, StateFeedback};
pub use navigation::{ImuBiasEstimate, NavigationConfig, NavigationFilter, NavigationSolution};
pub use schedule::{
    AnyPredictor, GainSchedule, Law, ScheduleAxes, ScheduledLqi, ScheduledPredictor,
};
pub use sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame, SensorNoise};

/// The thesis's on-board chain: navigation + Kalman predictor + LQI.
pub type ThesisFlightComputer = FlightComputer<ThesisEstimator, Lqi>;

/// The ESKF navigation + Kalman predictor + LQI.
pub type EskfFlightComputer = FlightComputer<EskfEstimator, Lqi>;
