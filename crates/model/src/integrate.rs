//! Fourth-order Runge–Kutta integration, thesis (10.1)–(10.5).
//!
//! The input and wind are held constant over a step (zero-order hold, as a
//! 400 Hz controller drives the servos). The default step is 1/400 s
//! ([`DEFAULT_STEP_S`]), the thesis's sampling time.

use crate::drivetrain::{DriveCommand, RotorState};
use crate::model::{Aux, Model, ModelError, PlantState, PlantVector};
use crate::options::InflowMode;
use crate::state::NX;
use crate::state::{Input, State};
use nalgebra::Vector3;

/// Default integration step (s): 1/400 s.
pub const DEFAULT_STEP_S: f64 = 1.0 / 400.0;

/// One classical RK4 step of ẋ = f(x), (10.1)–(10.5), for any fallible `f`
/// on a fixed-size vector (the model's [`State`], or the plant's
/// [`crate::PlantVector`]).
pub fn rk4<const N: usize, E>(
    x: &nalgebra::SVector<f64, N>,
    dt: f64,
    mut f: impl FnMut(&nalgebra::SVector<f64, N>) -> Result<nalgebra::SVector<f64, N>, E>,
) -> Result<nalgebra::SVector<f64, N>, E> {
    let k1 = f(x)?;
    let k2 = f(&(x + k1 * (0.5 * dt)))?;
    let k3 = f(&(x + k2 * (0.5 * dt)))?;
    let k4 = f(&(x + k3 * dt))?;
    Ok(x + (k1 + (k2 + k3) * 2.0 + k4) * (dt / 6.0))
}

impl Model {
    /// One RK4 step of the plant ([`Model::plant_derivative`]): the 30
    /// states and the drivetrain's integrated together, the inputs, the
    /// wind, the drive command and the friction anchors held; the anchors
    /// then follow ([`Model::update_anchors`]). The inflow of each stage is
    /// warm-started from the previous stage's. Returns the auxiliary outputs
    /// at the start of the step; on error the plant is left unchanged.
    pub fn plant_step(
        &self,
        plant: &mut PlantState,
        u: &Input,
        wind_ned: &Vector3<f64>,
        drive: &DriveCommand,
        dt: f64,
    ) -> Result<Aux, ModelError> {
        let mut first: Option<Aux> = None;
        let mut lam: Option<(f64, f64)> = None;
        let anchors = plant.anchors;
        let next = rk4(&plant.vector(), dt, |v| {
            let mut s = PlantState {
                x: State::zeros(),
                rotor: RotorState {
                    omega_rad_s: 0.0,
                    governor_integral: 0.0,
                },
                anchors,
            };
            s.set_vector(v);
            let mode = match lam {
                Some((l, lt)) => InflowMode::ConvergedFrom {
                    lambda_mr_hint: l,
                    lambda_tr_hint: lt,
                },
                None => InflowMode::Converged,
            };
            let (xd, rd, a) = self.plant_derivative(&s, u, wind_ned, mode, drive)?;
            lam = Some((a.lambda_mr, a.lambda_tr));
            first.get_or_insert(a);
            let mut d = PlantVector::zeros();
            d.fixed_rows_mut::<NX>(0).copy_from(&xd);
            d[NX] = rd.omega_rad_s;
            d[NX + 1] = rd.governor_integral;
            Ok(d)
        })?;
        plant.set_vector(&next);
        self.update_anchors(plant);
        Ok(first.unwrap_or_default())
    }

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
