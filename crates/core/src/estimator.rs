//! State estimation: the [`Estimator`] extension point and its
//! implementations.
//!
//! An estimator consumes one measurement per sample and offers the absolute
//! reduced-state estimate the control law uses this sample
//! ([`Estimator::update`]); once the law has chosen the servo commands it is
//! told what was applied and advances to the next sample
//! ([`Estimator::predict`]). This is the order of the thesis's predictor
//! form (15.8): the law at sample k uses x̂(k|k−1), and the measurement of
//! sample k enters x̂(k+1|k).
//!
//! - [`ThesisEstimator`]: the thesis's chain — navigation (q-method + GPS/IMU
//!   fusion, chapter 13) to the nine measured states, then the steady-state
//!   Kalman predictor (chapter 15) to all 27 states.
//! - [`KalmanPredictor`]: the predictor alone, fed the nine measured states
//!   directly (ideal navigation, for analyses).
//! - [`TruthFeed`]: the full true state passed through (the thesis's
//!   "estimator off" switch; simulation only).

use crate::error::CoreError;
use crate::frames::wrap_pi;
use crate::fusion::FusionError;
use crate::gains::GainSet;
use crate::navigation::{NavigationFilter, NavigationSolution};
use crate::sensor::SensorFrame;
use crate::state::{Input, MeasuredStates, NM, NU, NX_REDUCED, ReducedState};
use nalgebra::{SMatrix, SVector};

/// A measurement stamped with its sample time.
pub trait Timestamped {
    /// Time of the sample (s, on-board clock).
    fn t_s(&self) -> f64;
}

impl Timestamped for SensorFrame {
    fn t_s(&self) -> f64 {
        self.t_s
    }
}

/// The nine measured states (15.2) as an ideal navigation would give them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateMeasurement {
    /// Time of the sample (s).
    pub t_s: f64,
    /// `[φ θ ψ u v w p q r]`, absolute.
    pub measured: MeasuredStates,
}

impl Timestamped for StateMeasurement {
    fn t_s(&self) -> f64 {
        self.t_s
    }
}

/// The full true reduced state (simulation analyses only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthMeasurement {
    /// Time of the sample (s).
    pub t_s: f64,
    /// The true 27-state, absolute.
    pub state: ReducedState,
}

impl Timestamped for TruthMeasurement {
    fn t_s(&self) -> f64 {
        self.t_s
    }
}

/// What an estimator offers the control law and the logs each sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The absolute reduced-state estimate used by the law this sample.
    pub state: ReducedState,
    /// The nine measured states the estimator was given this sample.
    pub measured: MeasuredStates,
    /// The navigation solution, when the estimator runs a navigation.
    pub navigation: Option<NavigationSolution>,
}

/// The extension point for state estimators. Implementations must not
/// allocate in `update` or `predict`.
pub trait Estimator {
    /// The measurement consumed each sample.
    type Measurement: Timestamped;
    /// Absorb this sample's measurement; returns the estimate the law uses now.
    fn update(&mut self, measurement: &Self::Measurement) -> Result<Estimate, CoreError>;
    /// The commands actually applied this sample (after saturation): advance
    /// to the next sample.
    fn predict(&mut self, applied: &Input) -> Result<(), CoreError>;
}

/// A state predictor fed the nine measured states: the second stage of the
/// thesis's chain ([`ThesisEstimator`]). No allocation in either method.
pub trait Predictor {
    /// Absorb the nine measured states; returns the absolute estimate x̂(k|k−1).
    fn absorb(&mut self, measured: &MeasuredStates) -> Result<ReducedState, CoreError>;
    /// Advance with the applied commands and the last absorbed measurement.
    fn advance(&mut self, applied: &Input) -> Result<(), CoreError>;
}

impl Predictor for KalmanPredictor {
    fn absorb(&mut self, measured: &MeasuredStates) -> Result<ReducedState, CoreError> {
        KalmanPredictor::absorb(self, measured)
    }
    fn advance(&mut self, applied: &Input) -> Result<(), CoreError> {
        KalmanPredictor::advance(self, applied)
    }
}

/// The steady-state Kalman predictor (15.8) on the nine measured states:
/// x̂(k+1) = Φ x̂(k) + Γ (u(k) − u_trim) + K (y_m(k) − Hm x̂(k)), deviations
/// from trim, yaw innovation wrapped.
#[derive(Debug, Clone, PartialEq)]
pub struct KalmanPredictor {
    pub(crate) phi: SMatrix<f64, NX_REDUCED, NX_REDUCED>,
    pub(crate) gamma: SMatrix<f64, NX_REDUCED, NU>,
    pub(crate) k: SMatrix<f64, NX_REDUCED, NM>,
    pub(crate) x_trim: ReducedState,
    pub(crate) u_trim: Input,
    /// x̂(k): predicted deviation from trim.
    pub(crate) x_hat: ReducedState,
    /// y_m(k), kept between `update` and `predict`.
    y_m: MeasuredStates,
}

impl KalmanPredictor {
    /// The predictor of a gain set, starting at the absolute state `x0`.
    pub fn new(gains: &GainSet, x0: &ReducedState) -> Result<Self, CoreError> {
        gains.check()?;
        if !x0.iter().all(|v| v.is_finite()) {
            return Err(CoreError::NonFiniteMeasurement {
                what: "initial state",
            });
        }
        Ok(KalmanPredictor {
            phi: gains.phi,
            gamma: gains.gamma,
            k: gains.k,
            x_trim: gains.x_trim,
            u_trim: gains.u_trim,
            x_hat: x0 - gains.x_trim,
            y_m: MeasuredStates::from_fn(|i, _| x0[i]),
        })
    }

    /// Absorb the nine measured states; returns the absolute estimate x̂(k|k−1).
    #[inline]
    pub fn absorb(&mut self, measured: &MeasuredStates) -> Result<ReducedState, CoreError> {
        if !measured.as_slice().iter().all(|v| v.is_finite()) {
            return Err(CoreError::NonFiniteMeasurement {
                what: "measured states",
            });
        }
        self.y_m = *measured;
        Ok(self.x_hat + self.x_trim)
    }

    /// Advance with the applied commands and the last absorbed measurement.
    pub fn advance(&mut self, applied: &Input) -> Result<(), CoreError> {
        let mut innov =
            MeasuredStates::from_fn(|i, _| self.y_m[i] - self.x_trim[i] - self.x_hat[i]);
        innov[2] = wrap_pi(innov[2]);
        let next = mul_vec(&self.phi, &self.x_hat)
            + mul_vec(&self.gamma, &(applied - self.u_trim))
            + mul_vec(&self.k, &innov);
        // a slice walk: nalgebra's matrix iterator costs ~15 instructions an entry here
        if !next.as_slice().iter().all(|v| v.is_finite()) {
            return Err(CoreError::NonFiniteEstimate);
        }
        self.x_hat = next;
        Ok(())
    }
}

/// `m · x` for the predictor's fixed-size matrices, bit for bit nalgebra's
/// product (each row summed over the columns in order, `y = m[:, 0]·x0`,
/// then `y += m[:, j]·xj`) as a plain walk down the column-major storage the
/// compiler vectorizes: nalgebra's strided `gemv` is scalar here (~1 700 of
/// the 27×27 predictor's ~2 300 instructions a step).
#[inline]
fn mul_vec<const R: usize, const C: usize>(
    m: &SMatrix<f64, R, C>,
    x: &SVector<f64, C>,
) -> SVector<f64, R> {
    let mut y = [0.0; R];
    let a = m.as_slice();
    if C > 0 {
        for (yi, &mi) in y.iter_mut().zip(&a[..R]) {
            *yi = mi * x[0];
        }
    }
    for j in 1..C {
        let xj = x[j];
        for (yi, &mi) in y.iter_mut().zip(&a[j * R..(j + 1) * R]) {
            *yi += mi * xj;
        }
    }
    SVector::from(y)
}

/// Every predictor is an estimator fed the nine measured states (ideal
/// navigation): the fixed design, the scheduled one and either of them.
impl<P: Predictor> Estimator for P {
    type Measurement = StateMeasurement;

    fn update(&mut self, m: &StateMeasurement) -> Result<Estimate, CoreError> {
        Ok(Estimate {
            state: self.absorb(&m.measured)?,
            measured: m.measured,
            navigation: None,
        })
    }

    fn predict(&mut self, applied: &Input) -> Result<(), CoreError> {
        Predictor::advance(self, applied)
    }
}

/// A navigation: sensor frames in, the nine measured states
/// `[φ θ ψ u v w p q r]` out, and its solution for the logs. Implemented by
/// the thesis's [`NavigationFilter`] and the ESKF ([`crate::eskf::Eskf`]).
pub trait Navigation {
    /// Absorb one sensor frame; returns the nine measured states.
    fn step(&mut self, frame: &SensorFrame) -> Result<MeasuredStates, FusionError>;
    /// The navigation solution after the last frame.
    fn solution(&self) -> NavigationSolution;
}

impl Navigation for NavigationFilter {
    #[inline]
    fn step(&mut self, frame: &SensorFrame) -> Result<MeasuredStates, FusionError> {
        NavigationFilter::step(self, frame)
    }
    fn solution(&self) -> NavigationSolution {
        NavigationFilter::solution(self)
    }
}

/// An estimation chain: a navigation, then the Kalman predictor (or any
/// [`Predictor`], e.g. the gain-scheduled one) for the states it does not
/// measure.
#[derive(Debug, Clone)]
pub struct NavigatedEstimator<N, P = KalmanPredictor> {
    /// The navigation (nine measured states from sensor frames).
    pub navigation: N,
    /// The predictor.
    pub predictor: P,
}

/// The thesis's chain: q-method attitude + GPS/IMU fusion, then the predictor.
pub type ThesisEstimator<P = KalmanPredictor> = NavigatedEstimator<NavigationFilter, P>;

impl<N: Navigation, P: Predictor> Estimator for NavigatedEstimator<N, P> {
    type Measurement = SensorFrame;

    #[inline]
    fn update(&mut self, frame: &SensorFrame) -> Result<Estimate, CoreError> {
        let y = self.navigation.step(frame)?;
        Ok(Estimate {
            state: self.predictor.absorb(&y)?,
            measured: y,
            navigation: Some(self.navigation.solution()),
        })
    }

    fn predict(&mut self, applied: &Input) -> Result<(), CoreError> {
        self.predictor.advance(applied)
    }
}

/// Passes the true state through (the "estimator off" analysis switch).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TruthFeed;

impl Estimator for TruthFeed {
    type Measurement = TruthMeasurement;

    fn update(&mut self, m: &TruthMeasurement) -> Result<Estimate, CoreError> {
        if !m.state.iter().all(|v| v.is_finite()) {
            return Err(CoreError::NonFiniteMeasurement { what: "true state" });
        }
        Ok(Estimate {
            state: m.state,
            measured: MeasuredStates::from_fn(|i, _| m.state[i]),
            navigation: None,
        })
    }

    fn predict(&mut self, _applied: &Input) -> Result<(), CoreError> {
        Ok(())
    }
}
