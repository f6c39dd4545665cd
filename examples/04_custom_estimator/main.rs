//! A new estimator through the core's `Estimator` extension point.
#![allow(missing_docs)]

use helicon_core::state::MeasuredStates;
use helicon_core::{
    CoreError, Estimate, Estimator, FlightComputer, KalmanPredictor, Lqi, Reference, ServoLimits,
    StateFeedback, StateMeasurement,
};
use helicon_gnc::design::{ControllerConfig, design};
use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Input, Model, Params, Preset};
use nalgebra::{DVector, Vector3};

/// The thesis's predictor behind a first-order low-pass on its measurements.
struct SmoothedPredictor {
    inner: KalmanPredictor,
    smoothed: Option<MeasuredStates>,
    /// Low-pass weight of the new sample, in (0, 1].
    weight: f64,
}

impl Estimator for SmoothedPredictor {
    type Measurement = StateMeasurement;

    fn update(&mut self, m: &StateMeasurement) -> Result<Estimate, CoreError> {
        let y = match self.smoothed {
            Some(s) => s + (m.measured - s) * self.weight,
            None => m.measured,
        };
        self.smoothed = Some(y);
        self.inner.update(&StateMeasurement {
            t_s: m.t_s,
            measured: y,
        })
    }

    fn predict(&mut self, applied: &Input) -> Result<(), CoreError> {
        self.inner.predict(applied)
    }
}

/// Fly `computer` for 20 s on the linear model it was designed on; returns
/// the north-velocity error at the end (m/s).
fn fly<E, F>(
    computer: &mut FlightComputer<E, F>,
    phi: &nalgebra::DMatrix<f64>,
    gamma: &nalgebra::DMatrix<f64>,
    x_trim: &DVector<f64>,
    u_trim: &DVector<f64>,
    measure: impl Fn(u32, &DVector<f64>) -> E::Measurement,
) -> anyhow::Result<f64>
where
    E: Estimator,
    F: StateFeedback,
{
    let reference = Reference {
        velocity_ned_m_s: Vector3::new(1.0, 0.0, 0.0),
        yaw_rad: 0.0,
    };
    let mut x = x_trim.clone();
    for k in 0..8000 {
        let tel = computer.step(&measure(k, &x), &reference)?;
        let du = DVector::from_column_slice(tel.command.as_slice()) - u_trim;
        x = x_trim + phi * (&x - x_trim) + gamma * du;
    }
    Ok(1.0 - x[3] * x[1].cos())
}

fn main() -> anyhow::Result<()> {
    let model = Model::new(Params::bergen_twin(), Preset::Thesis.options());
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default())?;
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged)?;
    let ts = model.params().control.sample_time_s;
    let (phi, gamma) = lm.discretize(ts)?;
    let gains = design(&phi, &gamma, &t.x, &t.u, ts, &ControllerConfig::default())?;
    let limits = ServoLimits {
        min: Input::repeat(-1.0),
        max: Input::repeat(1.0),
    };
    let x_trim = DVector::from_column_slice(t.x.as_slice());
    let u_trim = DVector::from_column_slice(t.u.as_slice());
    let measure = |k: u32, x: &DVector<f64>| StateMeasurement {
        t_s: f64::from(k) * ts,
        measured: MeasuredStates::from_fn(|i, _| x[i]),
    };

    let mut plain = FlightComputer::new(
        KalmanPredictor::new(&gains.set, &gains.set.x_trim)?,
        Lqi::new(&gains.set, limits, true)?,
    );
    let e_plain = fly(&mut plain, &phi, &gamma, &x_trim, &u_trim, measure)?;

    let mut smoothed = FlightComputer::new(
        SmoothedPredictor {
            inner: KalmanPredictor::new(&gains.set, &gains.set.x_trim)?,
            smoothed: None,
            weight: 0.2,
        },
        Lqi::new(&gains.set, limits, true)?,
    );
    let e_smooth = fly(&mut smoothed, &phi, &gamma, &x_trim, &u_trim, measure)?;
    println!(
        "1 m/s north step after 20 s: error {e_plain:.2e} m/s (predictor), {e_smooth:.2e} m/s (smoothed predictor)"
    );
    Ok(())
}
