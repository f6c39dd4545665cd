//! Steady-state Kalman gains by duality with the DARE (thesis chapter 15).

use nalgebra::{Complex, DMatrix};

use crate::analysis;
use crate::check;
use crate::error::{LtiError, Result};
use crate::riccati;

/// Steady-state Kalman estimator for x(k+1) = Φx + Γu + G w, y = Cx + v,
/// E[wwᵀ] = Qn, E[vvᵀ] = Rn (w, v uncorrelated).
#[derive(Debug, Clone, PartialEq)]
pub struct Kalman {
    /// Predictor gain L (n×p): x̂(k+1) = Φx̂(k) + Γu(k) + L(y(k) − Cx̂(k)), thesis (15.8)
    /// with K(0) = L. Equals python-control's `dlqe` L: L = Φ P Cᵀ (C P Cᵀ + Rn)⁻¹.
    pub l: DMatrix<f64>,
    /// Filter ("current estimator") gain M = P Cᵀ (C P Cᵀ + Rn)⁻¹:
    /// x̂(k|k) = x̄(k) + M (y(k) − C x̄(k)), x̄(k+1) = Φ x̂(k|k) + Γu(k). L = Φ M.
    pub m: DMatrix<f64>,
    /// Prior (one-step predicted) error covariance P, the DARE solution (python-control
    /// `dlqe`'s P).
    pub p: DMatrix<f64>,
    /// Posterior (filtered) error covariance Z = P − M C P.
    pub z: DMatrix<f64>,
    /// Estimator-error poles eig(Φ − LC).
    pub poles: Vec<Complex<f64>>,
    /// Relative residual of the dual DARE.
    pub residual: f64,
}

/// Steady-state Kalman gain from (Φ, C, Qn, Rn[, G]) by duality: P solves the DARE for
/// (Φᵀ, Cᵀ, G Qn Gᵀ, Rn) (the dual of thesis (14.11)–(14.12), see §15.2). `g` defaults
/// to the identity (then Qn is n×n).
///
/// # Errors
/// Dimension/finite/definiteness violations; non-detectable (Φ, C) appears as
/// [`LtiError::NotStabilizable`] of the dual pair, non-stabilizable (Φ, G Qn^{1/2}) as
/// [`LtiError::NotDetectable`]; as [`riccati::dare`] otherwise.
pub fn dlqe(
    phi: &DMatrix<f64>,
    g: Option<&DMatrix<f64>>,
    c: &DMatrix<f64>,
    qn: &DMatrix<f64>,
    rn: &DMatrix<f64>,
) -> Result<Kalman> {
    let n = check::square("Phi", phi)?;
    let p_out = c.nrows();
    check::shape("C", c, p_out, n)?;
    check::finite("C", c)?;
    let w = match g {
        Some(gm) => {
            check::shape("G", gm, n, gm.ncols())?;
            check::finite("G", gm)?;
            check::shape("Qn", qn, gm.ncols(), gm.ncols())?;
            check::finite("Qn", qn)?;
            check::psd("Qn", qn)?;
            let mut w = gm * qn * gm.transpose();
            check::symmetrize(&mut w);
            w
        }
        None => {
            check::shape("Qn", qn, n, n)?;
            qn.clone()
        }
    };
    let sol = riccati::dare(&phi.transpose(), &c.transpose(), &w, rn, None)?;
    let p = sol.x;
    let pct = &p * c.transpose();
    let mut s = c * &pct + rn;
    check::symmetrize(&mut s);
    // M = P Cᵀ S⁻¹ → Mᵀ = S⁻¹ C P.
    let mt = match s.clone().cholesky() {
        Some(ch) => ch.solve(&pct.transpose()),
        None => s.lu().solve(&pct.transpose()).ok_or(LtiError::Singular {
            what: "C P Cᵀ + Rn",
        })?,
    };
    let m = mt.transpose();
    let l = phi * &m;
    let mut z = &p - &m * c * &p;
    check::symmetrize(&mut z);
    let poles = analysis::eigenvalues(&(phi - &l * c))?;
    Ok(Kalman {
        l,
        m,
        p,
        z,
        poles,
        residual: sol.residual,
    })
}
