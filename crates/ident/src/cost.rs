//! The coherence-weighted cost of rotorcraft frequency-domain fits
//! (CIFER/NAVFIT) and the accuracy of the fitted parameters, shared by the
//! transfer-function fit ([`crate::fit`]) and the state-space fit
//! ([`crate::ssfit`]):
//!
//! J = (20/n_ω) Σ W_γ [W_g (|T̂| − |T|)²_dB + W_p (∠T̂ − ∠T)²_deg],
//! W_g = 1, W_p = 0.01745, W_γ = [1.58 (1 − e^{−γ²})]²,
//!
//! over the points with γ² above a threshold. The cost is written as a sum
//! of squared residuals, two per point: √(20/n_ω · W_γ W_g) · 20 log10 |T/H|
//! and √(20/n_ω · W_γ W_p) · ∠(T/H) in degrees (wrapped into (−180, 180]).

use crate::error::{IdentError, Result};
use crate::frf::Frf;
use nalgebra::DMatrix;
use rustfft::num_complex::Complex64;

/// Weights and point selection of the cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostOptions {
    /// Points with γ² at or below this are left out (0.6).
    pub min_coherence: f64,
    /// Magnitude weight W_g, per dB² (1).
    pub w_gain: f64,
    /// Phase weight W_p, per deg² (0.01745: 1 dB ≈ 7.57° of phase).
    pub w_phase: f64,
}

impl Default for CostOptions {
    fn default() -> Self {
        Self {
            min_coherence: 0.6,
            w_gain: 1.0,
            w_phase: 0.01745,
        }
    }
}

/// The coherence weight W_γ = [1.58 (1 − e^{−γ²})]² (γ² given).
pub fn coherence_weight(gamma2: f64) -> f64 {
    let w = 1.58 * (1.0 - (-gamma2).exp());
    w * w
}

/// 20 / ln 10: dB per neper.
pub(crate) const DB: f64 = 8.685_889_638_065_037;

/// The selected points of one response: ω, the measured response and the
/// residual scales √(20/n_ω · W_γ · W_g) and √(20/n_ω · W_γ · W_p).
pub(crate) struct Points {
    pub omega: Vec<f64>,
    pub h: Vec<Complex64>,
    pub scale_mag: Vec<f64>,
    pub scale_ph: Vec<f64>,
}

impl Points {
    /// The two residuals of point `k` for the model response `t`.
    pub fn residuals(&self, k: usize, t: Complex64) -> (f64, f64) {
        let ratio = t / self.h[k];
        (
            self.scale_mag[k] * DB * ratio.norm().ln(),
            self.scale_ph[k] * wrap_deg(ratio.arg().to_degrees()),
        )
    }

    /// The two Jacobian entries of point `k` for d(log T)/dθ = `dlog`.
    pub fn jacobian(&self, k: usize, dlog: Complex64) -> (f64, f64) {
        (
            self.scale_mag[k] * DB * dlog.re,
            self.scale_ph[k] * dlog.im.to_degrees(),
        )
    }
}

/// Phase difference in degrees brought into (−180, 180].
pub(crate) fn wrap_deg(d: f64) -> f64 {
    d - 360.0 * ((d - 180.0) / 360.0).ceil()
}

/// Select the points of `frf` with γ² above the threshold (and ω inside
/// `[omega_lo, omega_hi]`), with their residual scales.
pub(crate) fn select(frf: &Frf, opts: &CostOptions, omega_lo: f64, omega_hi: f64) -> Points {
    let idx: Vec<usize> = (0..frf.len())
        .filter(|&k| {
            let w = frf.omega_rad_s[k];
            frf.coherence[k] > opts.min_coherence
                && w > 0.0
                && w >= omega_lo
                && w <= omega_hi
                && frf.h[k].norm() > 0.0
                && frf.h[k].norm().is_finite()
        })
        .collect();
    let nw = idx.len() as f64;
    let scale = |k: usize, w: f64| (20.0 / nw * coherence_weight(frf.coherence[k]) * w).sqrt();
    Points {
        omega: idx.iter().map(|&k| frf.omega_rad_s[k]).collect(),
        h: idx.iter().map(|&k| frf.h[k]).collect(),
        scale_mag: idx.iter().map(|&k| scale(k, opts.w_gain)).collect(),
        scale_ph: idx.iter().map(|&k| scale(k, opts.w_phase)).collect(),
    }
}

/// The accuracy of fitted parameters from the Jacobian of the weighted
/// residuals at the optimum.
#[derive(Debug, Clone)]
pub struct Accuracy {
    /// Cramér–Rao bounds (one standard deviation); infinite for a parameter
    /// the cost does not depend on, and for every parameter when the
    /// information matrix is singular (`separable` false).
    pub cramer_rao: Vec<f64>,
    /// Insensitivities; infinite for a parameter the cost does not depend on.
    pub insensitivity: Vec<f64>,
    /// Parameter correlations (M⁻¹ normalised to a unit diagonal); NaN in
    /// the rows and columns of parameters the cost does not depend on, and
    /// everywhere when the information matrix is singular.
    pub correlation: DMatrix<f64>,
    /// False when the information matrix of the parameters the cost depends
    /// on is singular: some combination of them is not determined.
    pub separable: bool,
}

/// Cramér–Rao bounds, insensitivities and correlations: with the
/// information matrix M = JᵀJ and the residual variance s² = J_min/(n_r − n_p)
/// (the cost's residuals treated as independent with equal variance),
/// CR_i = s √(M⁻¹)_ii and I_i = s / √M_ii (I_i ≤ CR_i; they differ when
/// parameters are correlated). A parameter whose Jacobian column norm is at
/// most `no_information` times the largest one is reported with infinite
/// bounds and left out of M⁻¹: 1e-12 for analytic Jacobians, larger for
/// finite differences whose round-off shows up as a small column. Errors only
/// on a non-finite Jacobian.
pub fn accuracy(jac: &DMatrix<f64>, cost: f64, no_information: f64) -> Result<Accuracy> {
    accuracy_correlated(jac, cost, no_information, None)
}

/// [`accuracy`] for residuals that are correlated with each other, as the
/// points of a frequency response estimated on a grid finer than its
/// windows' resolution are: with the residuals' correlation matrix R
/// (variance s² R) and `jrj` = JᵀRJ, the least-squares estimate's covariance
/// is the sandwich s² M⁻¹ (JᵀRJ) M⁻¹ (the estimator is still the one of
/// independent residuals; only its scatter is stated truly), so
/// CR_i = s √(M⁻¹JᵀRJM⁻¹)_ii, I_i = s √(JᵀRJ)_ii / M_ii and the correlations
/// are those of the sandwich. `None` is R = I, [`accuracy`].
pub fn accuracy_correlated(
    jac: &DMatrix<f64>,
    cost: f64,
    no_information: f64,
    jrj: Option<&DMatrix<f64>>,
) -> Result<Accuracy> {
    if !(cost.is_finite() && cost >= 0.0) {
        return Err(IdentError::Fit(format!(
            "accuracy: the cost {cost} must be finite and >= 0 (a sum of squares)"
        )));
    }
    if !(no_information.is_finite() && (0.0..1.0).contains(&no_information)) {
        return Err(IdentError::Fit(format!(
            "accuracy: the no-information threshold {no_information} must be in [0, 1)"
        )));
    }
    let (nr, np) = jac.shape();
    let s2 = cost / nr.saturating_sub(np).max(1) as f64;
    let m = jac.transpose() * jac;
    let g = match jrj {
        Some(g) if g.shape() == (np, np) && g.iter().all(|v| v.is_finite()) => g.clone(),
        Some(_) => {
            return Err(IdentError::Fit(
                "residual correlation: JᵀRJ is not a finite square of the parameters".into(),
            ));
        }
        None => m.clone(),
    };
    // Scale to unit diagonal before inverting (the parameters span decades).
    let d: Vec<f64> = (0..np).map(|i| m[(i, i)].sqrt()).collect();
    if d.iter().any(|v| !v.is_finite()) || !s2.is_finite() {
        return Err(IdentError::Fit("non-finite information matrix".into()));
    }
    let dmax = d.iter().copied().fold(0.0, f64::max);
    let seen: Vec<usize> = (0..np).filter(|&i| d[i] > no_information * dmax).collect();
    let ns = seen.len();
    let scaled = |x: &DMatrix<f64>| {
        DMatrix::from_fn(ns, ns, |i, j| {
            let (a, b) = (seen[i], seen[j]);
            x[(a, b)] / (d[a] * d[b])
        })
    };
    let (ms, gs) = (scaled(&m), scaled(&g));
    let mut cr = vec![f64::INFINITY; np];
    let mut ins = vec![f64::INFINITY; np];
    let mut corr = DMatrix::from_element(np, np, f64::NAN);
    for (i, &a) in seen.iter().enumerate() {
        ins[a] = (s2 * gs[(i, i)]).max(0.0).sqrt() / d[a];
    }
    let inv = ms
        .try_inverse()
        .filter(|inv| inv.iter().all(|v| v.is_finite()));
    let Some(inv) = inv else {
        return Ok(Accuracy {
            cramer_rao: cr,
            insensitivity: ins,
            correlation: corr,
            separable: false,
        });
    };
    let cov = &inv * gs * &inv;
    for (i, &a) in seen.iter().enumerate() {
        cr[a] = (s2 * cov[(i, i)]).max(0.0).sqrt() / d[a];
        for (j, &b) in seen.iter().enumerate() {
            corr[(a, b)] = cov[(i, j)] / (cov[(i, i)] * cov[(j, j)]).sqrt();
        }
    }
    Ok(Accuracy {
        cramer_rao: cr,
        insensitivity: ins,
        correlation: corr,
        separable: true,
    })
}

/// [`accuracy`] for an analytic Jacobian, refusing a singular information
/// matrix (the fit's parameters are not separable).
pub(crate) fn separable_accuracy(jac: &DMatrix<f64>, cost: f64) -> Result<Accuracy> {
    let acc = accuracy(jac, cost, 1e-12)?;
    if !acc.separable {
        return Err(IdentError::Fit(
            "singular information matrix: parameters not separable".into(),
        ));
    }
    Ok(acc)
}

/// `100 · v / |p|` for each pair: a bound in % of its parameter.
pub(crate) fn percent(v: &[f64], p: &[f64]) -> Vec<f64> {
    v.iter().zip(p).map(|(c, p)| 100.0 * c / p.abs()).collect()
}
