//! The flight computer: one estimator and one state-feedback law, stepped
//! once per control sample. The very same type flies in the simulator and on
//! board; [`FlightComputer::step`] allocates nothing and returns one
//! [`Telemetry`] record from which the simulator's log, the on-board log and
//! the ground-station messages are all filled.

use crate::error::CoreError;
use crate::eskf::EskfEstimator;
use crate::estimator::{Estimator, ThesisEstimator, Timestamped};
use crate::lqi::{Reference, StateFeedback};
use crate::navigation::NavigationSolution;
use crate::schedule::{AnyPredictor, Law};
use crate::sensor::SensorFrame;
use crate::state::{Input, MeasuredStates, NU, NY, ReducedState};
use nalgebra::SVector;

/// Everything the flight software decided and knew in one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Telemetry {
    /// Sample counter since the computer was built (0, 1, 2, …).
    pub sample: u64,
    /// Time of the measurement the sample was computed from (s).
    pub t_s: f64,
    /// The reference tracked.
    pub reference: Reference,
    /// Servo commands sent (after saturation).
    pub command: Input,
    /// Which commands were saturated.
    pub saturated: [bool; NU],
    /// Output errors [ψ (rad), vn, ve, vd (m/s)], reference − estimate.
    pub tracking_error: SVector<f64, NY>,
    /// Integral states after this sample.
    pub integral: SVector<f64, NY>,
    /// The absolute reduced-state estimate used by the law.
    pub estimate: ReducedState,
    /// The nine measured states the estimator was given.
    pub measured: MeasuredStates,
    /// The navigation solution, when the estimator runs one.
    pub navigation: Option<NavigationSolution>,
}

/// Estimator + state feedback.
#[derive(Debug, Clone)]
pub struct FlightComputer<E, F> {
    /// The state estimator.
    pub estimator: E,
    /// The control law.
    pub feedback: F,
    sample: u64,
}

impl<E: Estimator, F: StateFeedback> FlightComputer<E, F> {
    /// A flight computer from its two parts.
    pub fn new(estimator: E, feedback: F) -> Self {
        FlightComputer {
            estimator,
            feedback,
            sample: 0,
        }
    }

    /// One control sample: measurement and reference in, servo commands and
    /// telemetry out. An error (a navigation failure, a non-finite
    /// measurement or estimate) leaves the commands of the previous sample to
    /// the caller's failsafe.
    #[inline]
    pub fn step(
        &mut self,
        measurement: &E::Measurement,
        reference: &Reference,
    ) -> Result<Telemetry, CoreError> {
        self.step_with_excitation(measurement, reference, &Input::zeros())
    }

    /// [`FlightComputer::step`] with a flight-test excitation: `offset`
    /// (servo units, rad) is added to the law's command before saturation,
    /// so the estimator predicts with, and the telemetry's `command` holds,
    /// what was applied. Allocates nothing.
    pub fn step_with_excitation(
        &mut self,
        measurement: &E::Measurement,
        reference: &Reference,
        offset: &Input,
    ) -> Result<Telemetry, CoreError> {
        self.step_applied(measurement, reference, offset, None)
    }

    /// [`FlightComputer::step_with_excitation`] for a sample whose servos
    /// get `applied` instead of the law's command (the pilot's sticks in
    /// manual flight, the trim on the ground), when given: the estimator
    /// predicts with what the servos got and the telemetry's `command`
    /// holds it (its `saturated` all false); the law still runs on the
    /// estimate (its tracking error and integral are reported). Allocates
    /// nothing.
    pub fn step_applied(
        &mut self,
        measurement: &E::Measurement,
        reference: &Reference,
        offset: &Input,
        applied: Option<&Input>,
    ) -> Result<Telemetry, CoreError> {
        self.step_servo(measurement, reference, offset, |_| applied.copied())
    }

    /// [`FlightComputer::step_applied`] with the servos' command decided
    /// from this sample's law command: `servo` is given the law's command
    /// and returns what the servos get instead (`None`: the law's). For a
    /// ground logic that blends the law's fresh command from ground idle
    /// (`helicon_flight::landing`): the estimator predicts with the
    /// blended command, the law's own is what `servo` saw. Allocates
    /// nothing.
    pub fn step_servo(
        &mut self,
        measurement: &E::Measurement,
        reference: &Reference,
        offset: &Input,
        servo: impl FnOnce(&Input) -> Option<Input>,
    ) -> Result<Telemetry, CoreError> {
        let estimate = self.estimator.update(measurement)?;
        let cmd = self
            .feedback
            .command_with_offset(&estimate.state, reference, offset);
        let (u, saturated) = match servo(&cmd.u) {
            Some(a) => (a, [false; NU]),
            None => (cmd.u, cmd.saturated),
        };
        self.estimator.predict(&u)?;
        let t = Telemetry {
            sample: self.sample,
            t_s: measurement.t_s(),
            reference: *reference,
            command: u,
            saturated,
            tracking_error: cmd.tracking_error,
            integral: cmd.integral,
            estimate: estimate.state,
            measured: estimate.measured,
            navigation: estimate.navigation,
        };
        self.sample += 1;
        Ok(t)
    }
}

/// The flight computer fed by the sensors, with the navigation the
/// configuration chose (the thesis's chain or the ESKF) and the law and
/// predictor of one design or of a gain schedule. The simulator, SITL and
/// the on-board program fly this one type; stepping it allocates nothing.
#[derive(Debug, Clone)]
#[allow(
    clippy::large_enum_variant,
    reason = "built once and owned in place (boxed by its owner); no indirection in the control step"
)]
pub enum SensorComputer {
    /// q-method + fusion filter + Kalman predictor + LQI (thesis ch. 13–15).
    Thesis(FlightComputer<ThesisEstimator<AnyPredictor>, Law>),
    /// ESKF with IMU biases + Kalman predictor + LQI.
    Eskf(FlightComputer<EskfEstimator<AnyPredictor>, Law>),
}

impl SensorComputer {
    /// One control sample from a sensor frame (see [`FlightComputer::step`]).
    #[inline]
    pub fn step(
        &mut self,
        frame: &SensorFrame,
        reference: &Reference,
    ) -> Result<Telemetry, CoreError> {
        self.step_with_excitation(frame, reference, &Input::zeros())
    }

    /// One control sample with a servo excitation added before saturation
    /// (see [`FlightComputer::step_with_excitation`]).
    #[inline]
    pub fn step_with_excitation(
        &mut self,
        frame: &SensorFrame,
        reference: &Reference,
        offset: &Input,
    ) -> Result<Telemetry, CoreError> {
        match self {
            SensorComputer::Thesis(c) => c.step_with_excitation(frame, reference, offset),
            SensorComputer::Eskf(c) => c.step_with_excitation(frame, reference, offset),
        }
    }

    /// One control sample whose servos get `applied` instead of the law's
    /// command, when given (see [`FlightComputer::step_applied`]).
    #[inline]
    pub fn step_applied(
        &mut self,
        frame: &SensorFrame,
        reference: &Reference,
        offset: &Input,
        applied: Option<&Input>,
    ) -> Result<Telemetry, CoreError> {
        match self {
            SensorComputer::Thesis(c) => c.step_applied(frame, reference, offset, applied),
            SensorComputer::Eskf(c) => c.step_applied(frame, reference, offset, applied),
        }
    }

    /// One control sample whose servos get what `servo` makes of the
    /// law's command (see [`FlightComputer::step_servo`]).
    #[inline]
    pub fn step_servo(
        &mut self,
        frame: &SensorFrame,
        reference: &Reference,
        offset: &Input,
        servo: impl FnOnce(&Input) -> Option<Input>,
    ) -> Result<Telemetry, CoreError> {
        match self {
            SensorComputer::Thesis(c) => c.step_servo(frame, reference, offset, servo),
            SensorComputer::Eskf(c) => c.step_servo(frame, reference, offset, servo),
        }
    }

    /// Clears the law's integrators (entering automatic flight).
    pub fn reset_feedback(&mut self) {
        match self {
            SensorComputer::Thesis(c) => c.feedback.reset(),
            SensorComputer::Eskf(c) => c.feedback.reset(),
        }
    }

    /// The estimator's short name, as configurations spell it.
    pub fn estimator_kind(&self) -> &'static str {
        match self {
            SensorComputer::Thesis(_) => "thesis",
            SensorComputer::Eskf(_) => "eskf",
        }
    }
}
