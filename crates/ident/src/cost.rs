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
    /// the cost does not depend on, for one in a direction the information
    /// matrix does not resolve ([`CONDITION_LIMIT`]), and for every
    /// parameter when the information matrix is singular (`separable` false).
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
        .clone()
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
    let cov = &inv * &gs * &inv;
    // Parameters in a direction the information matrix does not determine
    // to double precision (an eigenvalue of the unit-diagonal M below
    // CONDITION_LIMIT times the largest): their inverse is round-off, and a
    // negative variance clipped to 0 would read as a perfect bound.
    let eig = ms.symmetric_eigen();
    let lmax = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut undetermined = vec![false; ns];
    for (k, l) in eig.eigenvalues.iter().enumerate() {
        if *l <= CONDITION_LIMIT * lmax {
            for (i, u) in undetermined.iter_mut().enumerate() {
                if eig.eigenvectors[(i, k)].abs() > 0.1 {
                    *u = true;
                }
            }
        }
    }
    for (i, &a) in seen.iter().enumerate() {
        let var = s2 * cov[(i, i)];
        // without a residual correlation CR ≥ I holds exactly (M⁻¹_ii ≥ 1/M_ii)
        let below_insensitivity = jrj.is_none() && var.sqrt() / d[a] < ins[a] * (1.0 - 1e-6);
        if undetermined[i] || !(var.is_finite() && var > 0.0) || below_insensitivity {
            continue; // infinite bound, NaN correlations
        }
        cr[a] = var.sqrt() / d[a];
    }
    for (i, &a) in seen.iter().enumerate() {
        for (j, &b) in seen.iter().enumerate() {
            if cr[a].is_finite() && cr[b].is_finite() {
                corr[(a, b)] = cov[(i, j)] / (cov[(i, i)] * cov[(j, j)]).sqrt();
            }
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

/// The smallest eigenvalue, relative to the largest, of the unit-diagonal
/// information matrix whose directions [`accuracy`] still resolves; the
/// parameters of a smaller one get infinite Cramér–Rao bounds.
pub const CONDITION_LIMIT: f64 = 1e-12;

/// A parameter whose Cramér–Rao bound (or insensitivity) is at least this
/// % of its value is not identifiable from the data: one standard
/// deviation spans zero, so not even its sign is determined.
pub const NOT_IDENTIFIABLE_PCT: f64 = 100.0;

/// Whether a parameter with this Cramér–Rao bound and insensitivity (% of
/// its value) is determined by the data: both finite and below
/// [`NOT_IDENTIFIABLE_PCT`].
pub fn identifiable(cramer_rao_pct: f64, insensitivity_pct: f64) -> bool {
    cramer_rao_pct < NOT_IDENTIFIABLE_PCT && insensitivity_pct < NOT_IDENTIFIABLE_PCT
}

/// `100 · v / |p|` for each pair: a bound in % of its parameter.
pub(crate) fn percent(v: &[f64], p: &[f64]) -> Vec<f64> {
    v.iter().zip(p).map(|(c, p)| 100.0 * c / p.abs()).collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// Two parameters whose Jacobian columns agree to round-off (a zero and
    /// a delay trading against each other): their bounds are infinite, not
    /// the 0 a negative round-off variance would clip to; a third, separate
    /// parameter keeps a finite bound.
    #[test]
    fn an_undetermined_combination_has_infinite_bounds() {
        let n = 50;
        let jac = DMatrix::from_fn(n, 3, |i, j| {
            let x = i as f64 / n as f64;
            match j {
                0 => x,
                1 => -x * (1.0 + 1e-15 * (i % 3) as f64),
                _ => (7.0 * x).cos(),
            }
        });
        let acc = accuracy(&jac, 1.0, 1e-12).unwrap();
        assert!(acc.cramer_rao[0].is_infinite() && acc.cramer_rao[1].is_infinite());
        assert!(acc.cramer_rao[2].is_finite() && acc.cramer_rao[2] > 0.0);
        assert!(acc.insensitivity.iter().all(|v| v.is_finite() && *v > 0.0));
        assert!(acc.correlation[(0, 1)].is_nan());
        // well separated columns: finite bounds, CR ≥ I
        let jac = DMatrix::from_fn(n, 2, |i, j| {
            let x = i as f64 / n as f64;
            if j == 0 { x } else { x * x }
        });
        let acc = accuracy(&jac, 1.0, 1e-12).unwrap();
        for k in 0..2 {
            assert!(acc.cramer_rao[k].is_finite());
            assert!(acc.cramer_rao[k] >= acc.insensitivity[k]);
        }
    }

    #[test]
    fn identifiable_needs_both_bounds_below_the_limit() {
        assert!(identifiable(5.0, 1.0));
        assert!(!identifiable(f64::INFINITY, 1.0));
        assert!(!identifiable(150.0, 1.0));
        assert!(!identifiable(5.0, 6e7));
        assert!(!identifiable(f64::NAN, 1.0));
    }
}
