//! Fourth-order Runge–Kutta integration, thesis (10.1)–(10.5).
//!
//! The input and wind are held constant over a step (zero-order hold, as a
//! 400 Hz controller drives the servos). The default step is 1/400 s
//! ([`DEFAULT_STEP_S`]), the thesis's sampling time.

use crate::model::{Aux, Model, ModelError};
use crate::options::InflowMode;
use crate::state::{Input, State};
use nalgebra::Vector3;

/// Default integration step (s): 1/400 s.
pub const DEFAULT_STEP_S: f64 = 1.0 / 400.0;

/// One classical RK4 step of ẋ = f(x), (10.1)–(10.5), for any fallible `f`.
pub fn rk4<E>(
    x: &State,
    dt: f64,
    mut f: impl FnMut(&State) -> Result<State, E>,
) -> Result<State, E> {
    let k1 = f(x)?;
    let k2 = f(&(x + k1 * (0.5 * dt)))?;
    let k3 = f(&(x + k2 * (0.5 * dt)))?;
    let k4 = f(&(x + k3 * dt))?;
    Ok(x + (k1 + (k2 + k3) * 2.0 + k4) * (dt / 6.0))
}

impl Model {
    /// One RK4 step with converged inflow; returns the new state and the
    /// auxiliary outputs at the start of the step.
    pub fn step(
        &self,
        x: &State,
        u: &Input,
        wind_ned: &Vector3<f64>,
        dt: f64,
    ) -> Result<(State, Aux), ModelError> {
        self.step_with(x, u, wind_ned, dt, InflowMode::Converged)
    }

    /// One RK4 step with a chosen inflow mode (the same mode at every stage).
    pub fn step_with(
        &self,
        x: &State,
        u: &Input,
        wind_ned: &Vector3<f64>,
        dt: f64,
        inflow: InflowMode,
    ) -> Result<(State, Aux), ModelError> {
        let mut first: Option<Aux> = None;
        let next = rk4(x, dt, |s| {
            let (d, a) = self.derivative_with(s, u, wind_ned, inflow)?;
            first.get_or_insert(a);
            Ok(d)
        })?;
        Ok((next, first.unwrap_or_default()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rk4_fourth_order_on_linear_oscillator() {
        // ẋ0 = x1, ẋ1 = −x0: exact solution cos/sin. Global error ∝ dt⁴:
        // halving the step divides it by ~16.
        let f = |x: &State| -> Result<State, ()> {
            let mut d = State::zeros();
            d[0] = x[1];
            d[1] = -x[0];
            Ok(d)
        };
        let err = |dt: f64| {
            let mut x = State::zeros();
            x[0] = 1.0;
            let n = (2.0 / dt).round() as usize;
            for _ in 0..n {
                x = rk4(&x, dt, f).unwrap();
            }
            (x[0] - 2.0f64.cos()).abs()
        };
        let ratio = err(0.1) / err(0.05);
        assert!((ratio - 16.0).abs() < 1.0, "ratio {ratio}");
    }
}
