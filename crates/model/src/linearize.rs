//! Linearization about an operating point, thesis (12.12)–(12.18).
//!
//! A = ∂f27/∂x27 and B = ∂f27/∂u by central differences with Richardson
//! extrapolation: D(h) = (f(x+h) − f(x−h))/(2h), J = (4D(h) − D(2h))/3, which
//! cancels the h² truncation term (error O(h⁴)). The step is per variable,
//! h_i = 1e-5·max(1, |x_i|), balancing truncation (~h⁴·f⁽⁵⁾) against
//! round-off (~ε|f|/h ≈ 1e-11 relative).
//!
//! The affine residual ẋ(trim) is reported: a linear model is only exact at an
//! equilibrium, and this makes any residual visible instead of hiding it.

use crate::model::{Model, ModelError};
use crate::options::InflowMode;
use crate::state::{
    INPUT_NAMES, Input, NU, NX_REDUCED, REDUCED_OFFSET, REDUCED_STATE_NAMES, ReducedState, expand,
};
use nalgebra::{SMatrix, Vector3};

/// A 27-state linear model ẋ ≈ ẋ0 + A(x − x0) + B(u − u0).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearModel {
    /// State matrix (27×27), rows/columns in [`crate::REDUCED_STATE_NAMES`] order.
    pub a: SMatrix<f64, NX_REDUCED, NX_REDUCED>,
    /// Input matrix (27×4), columns in [`crate::INPUT_NAMES`] order.
    pub b: SMatrix<f64, NX_REDUCED, NU>,
    /// The reduced derivative at the operating point (zero at an exact trim).
    pub xdot0: ReducedState,
    /// The operating point.
    pub x0: ReducedState,
    /// The operating input.
    pub u0: Input,
}

/// The largest ‖ẋ(x0, u0)‖∞ (SI units) at which an operating point counts as
/// an equilibrium: 1e4 × the trim tolerance (1e-10), leaving room for the
/// round-off of the thesis inflow iteration at its fixed point, and far below
/// any physical acceleration. A point beyond it (e.g. a trim whose input the
/// servo saturation clips) makes the affine term ẋ0 part of the model.
pub const EQUILIBRIUM_TOL: f64 = 1e-6;

/// The reduced derivative f27(x27, u) (position does not enter the dynamics).
pub fn reduced_derivative(
    model: &Model,
    xr: &ReducedState,
    u: &Input,
    wind_ned: &Vector3<f64>,
    inflow: InflowMode,
) -> Result<ReducedState, ModelError> {
    let x = expand(xr, [0.0; 3]);
    let (xd, _) = model.derivative_with(&x, u, wind_ned, inflow)?;
    Ok(ReducedState::from_fn(|i, _| xd[i + REDUCED_OFFSET]))
}

/// Linearize at (x0, u0) with the given wind and inflow mode. For the thesis
/// Appendix E emulation pass `InflowMode::ThesisIteration` with the trim's
/// inflow ratios and 7 iterations (MODEL.md §11).
pub fn linearize(
    model: &Model,
    x0: &ReducedState,
    u0: &Input,
    wind_ned: &Vector3<f64>,
    inflow: InflowMode,
) -> Result<LinearModel, ModelError> {
    let f = |x: &ReducedState, u: &Input| reduced_derivative(model, x, u, wind_ned, inflow);
    let xdot0 = f(x0, u0)?;
    let mut a = SMatrix::<f64, NX_REDUCED, NX_REDUCED>::zeros();
    let mut b = SMatrix::<f64, NX_REDUCED, NU>::zeros();
    for j in 0..NX_REDUCED {
        let h = 1e-5 * x0[j].abs().max(1.0);
        let col = richardson(h, |d| {
            let mut x = *x0;
            x[j] += d;
            f(&x, u0)
        })?;
        a.set_column(j, &col);
    }
    for j in 0..NU {
        let h = 1e-5 * u0[j].abs().max(1.0);
        let col = richardson(h, |d| {
            let mut u = *u0;
            u[j] += d;
            f(x0, &u)
        })?;
        b.set_column(j, &col);
    }
    for (m, what, cols) in [
        (
            a.as_slice(),
            "entry of A in column",
            &REDUCED_STATE_NAMES[..],
        ),
        (b.as_slice(), "entry of B in column", &INPUT_NAMES[..]),
    ] {
        if let Some(k) = m.iter().position(|v| !v.is_finite()) {
            return Err(ModelError::NonFiniteOutput {
                what,
                name: cols[k / NX_REDUCED],
                value: m[k],
            });
        }
    }
    if let Some(i) = xdot0.iter().position(|v| !v.is_finite()) {
        return Err(ModelError::NonFiniteOutput {
            what: "derivative of",
            name: REDUCED_STATE_NAMES[i],
            value: xdot0[i],
        });
    }
    Ok(LinearModel {
        a,
        b,
        xdot0,
        x0: *x0,
        u0: *u0,
    })
}

impl LinearModel {
    /// The largest |ẋ0| component and its state name (the affine residual).
    pub fn worst_residual(&self) -> (&'static str, f64) {
        let i = self.xdot0.iamax();
        (REDUCED_STATE_NAMES[i], self.xdot0[i])
    }

    /// Whether the operating point is an equilibrium: ‖ẋ0‖∞ ≤ [`EQUILIBRIUM_TOL`].
    pub fn is_equilibrium(&self) -> bool {
        self.xdot0.amax() <= EQUILIBRIUM_TOL
    }

    /// A as a dynamic matrix (for the generic analysis of `helicon-lti`).
    pub fn a_dyn(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::from_column_slice(NX_REDUCED, NX_REDUCED, self.a.as_slice())
    }

    /// B as a dynamic matrix.
    pub fn b_dyn(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::from_column_slice(NX_REDUCED, NU, self.b.as_slice())
    }

    /// Poles with natural frequency and damping (MATLAB `damp` conventions),
    /// sorted by natural frequency.
    pub fn poles(&self) -> Result<Vec<helicon_lti::analysis::Pole>, helicon_lti::LtiError> {
        let mut p = helicon_lti::analysis::damp(&self.a_dyn())?;
        p.sort_by(|a, b| {
            a.natural_frequency_rad_s
                .total_cmp(&b.natural_frequency_rad_s)
                .then(a.value.im.total_cmp(&b.value.im))
        });
        Ok(p)
    }

    /// Zero-order-hold discretization (Φ, Γ) at sample time `ts_s`.
    pub fn discretize(
        &self,
        ts_s: f64,
    ) -> Result<(nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>), helicon_lti::LtiError> {
        helicon_lti::expm::c2d(&self.a_dyn(), &self.b_dyn(), ts_s)
    }
}

fn richardson(
    h: f64,
    mut f: impl FnMut(f64) -> Result<ReducedState, ModelError>,
) -> Result<ReducedState, ModelError> {
    let d1 = (f(h)? - f(-h)?) / (2.0 * h);
    let d2 = (f(2.0 * h)? - f(-2.0 * h)?) / (4.0 * h);
    Ok((d1 * 4.0 - d2) / 3.0)
}
