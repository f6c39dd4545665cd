//! Steady-state Kalman gains by duality with the DARE (thesis chapter 15).

use nalgebra::{Complex, DMatrix};

use crate::analysis;
use crate::check;
use crate::error::{LtiError, Result};
use crate::riccati;

/// Steady-state Kalman estimator for x(k+1) = Φx + Γu + G w, y = Cx + v,
/// E(w wᵀ) = Qn, E(v vᵀ) = Rn (w, v uncorrelated).
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
/// to the identity (then Qn is n×n). All returned matrices are finite.
///
/// Errors name the arguments as "A" (= Φ), "C", "G", "Qn", "Rn".
///
/// # Errors
/// Dimension/finite/definiteness violations (Qn ⪰ 0, Rn ≻ 0), entries above
/// [`MAX_ENTRY`](crate::MAX_ENTRY); [`LtiError::NotDetectable`] with pair "(A, C)" when a
/// mode with |λ| ≥ 1 is invisible to the measurements; [`LtiError::NotStabilizable`] with
/// pair "(A, G Qn^1/2)" when such a mode is not excited by the process noise;
/// [`LtiError::Overflow`] when a result leaves the f64 range; as [`riccati::dare`]
/// otherwise.
pub fn dlqe(
    phi: &DMatrix<f64>,
    g: Option<&DMatrix<f64>>,
    c: &DMatrix<f64>,
    qn: &DMatrix<f64>,
    rn: &DMatrix<f64>,
) -> Result<Kalman> {
    let n = check::square("A", phi)?;
    let p_out = c.nrows();
    check::shape("C", c, p_out, n)?;
    check::bounded("A", phi)?;
    check::bounded("C", c)?;
    let w = match g {
        Some(gm) => {
            check::shape("G", gm, n, gm.ncols())?;
            check::bounded("G", gm)?;
            check::shape("Qn", qn, gm.ncols(), gm.ncols())?;
            check::bounded("Qn", qn)?;
            check::psd("Qn", qn)?;
            let mut w = gm * qn * gm.transpose();
            check::symmetrize(&mut w);
            check::output("G Qn G^T", &w)?;
            w
        }
        None => {
            check::shape("Qn", qn, n, n)?;
            check::bounded("Qn", qn)?;
            check::psd("Qn", qn)?;
            qn.clone()
        }
    };
    check::shape("Rn", rn, p_out, p_out)?;
    check::bounded("Rn", rn)?;
    check::pd("Rn", rn)?;
    // Structural failures of the dual DARE, restated for the filter: stabilizability of the
    // dual (Φᵀ, Cᵀ) is detectability of (Φ, C); detectability of the dual (W, Φᵀ) is
    // stabilizability of (Φ, G Qn^½).
    let sol = match riccati::dare(&phi.transpose(), &c.transpose(), &w, rn, None) {
        Ok(sol) => sol,
        Err(LtiError::NotStabilizable { re, im, ratio, .. }) => {
            return Err(LtiError::NotDetectable {
                pair: "(A, C)",
                re,
                im,
                ratio,
            });
        }
        Err(LtiError::NotDetectable { re, im, ratio, .. }) => {
            return Err(LtiError::NotStabilizable {
                pair: "(A, G Qn^1/2)",
                re,
                im,
                ratio,
            });
        }
        Err(e) => return Err(e),
    };
    let p = sol.x;
    let pct = &p * c.transpose();
    let mut s = c * &pct + rn;
    check::symmetrize(&mut s);
    check::output("C P C^T + Rn", &s)?;
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
    check::output("Kalman filter gain M", &m)?;
    check::output("Kalman predictor gain L", &l)?;
    check::output("posterior covariance Z", &z)?;
    let acl = phi - &l * c;
    check::output("estimator error dynamics A - L C", &acl)?;
    let poles = analysis::eigenvalues(&acl)?;
    Ok(Kalman {
        l,
        m,
        p,
        z,
        poles,
        residual: sol.residual,
    })
}
