//! Discrete LQR design after thesis chapter 14: `dlqr`, Bryson's rule, the pincer procedure
//! and integral action.

use nalgebra::{Complex, DMatrix};

use crate::analysis;
use crate::check;
use crate::error::{LtiError, Result};
use crate::riccati::{self, DareOptions};

/// A discrete LQR design: u(k) = −K x(k).
#[derive(Debug, Clone, PartialEq)]
pub struct Lqr {
    /// Feedback gain K (m×n): the steady-state L(0) of thesis (14.11)/(14.13) with the sign of
    /// the control law (14.10), u = −K x.
    pub k: DMatrix<f64>,
    /// Riccati solution S (the steady state of (14.12)).
    pub s: DMatrix<f64>,
    /// Closed-loop eigenvalues of the physical system, eig(Φ − ΓK), sorted by real part.
    pub poles: Vec<Complex<f64>>,
    /// Relative residual of the Riccati equation that was solved.
    pub residual: f64,
}

/// eig(Φ − ΓK), with the closed-loop matrix checked for finiteness first.
fn closed_loop_poles(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    k: &DMatrix<f64>,
) -> Result<Vec<Complex<f64>>> {
    let acl = phi - gamma * k;
    check::output("closed loop Phi - Gamma K", &acl)?;
    analysis::eigenvalues(&acl)
}

/// Discrete-time LQR, MATLAB/python-control `dlqr(Φ, Γ, Q, R[, N])`: minimizes
/// Σ xᵀQx + uᵀRu + 2xᵀNu for x(k+1) = Φx(k) + Γu(k) (thesis (14.9)–(14.13)).
///
/// # Errors
/// As [`riccati::dare`].
pub fn dlqr(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
) -> Result<Lqr> {
    let sol = riccati::dare_with(phi, gamma, q, r, n, &DareOptions::default())?;
    let poles = closed_loop_poles(phi, gamma, &sol.k)?;
    Ok(Lqr {
        k: sol.k,
        s: sol.x,
        poles,
        residual: sol.residual,
    })
}

/// Pincer procedure with prescribed degree of stability α ≥ 1 (thesis (14.18)–(14.21)):
/// the cost weighted by α^{2k} equals the standard cost of z(k) = αᵏx(k), v(k) = αᵏu(k)
/// (14.19), whose dynamics are z(k+1) = αΦ z(k) + αΓ v(k) (14.20); the gain L_α(0) of that
/// problem is used unchanged on the original system, u = −L_α(0) x (14.21). All closed-loop
/// poles of Φ − ΓK then lie inside the circle |z| < 1/α.
///
/// The returned `poles` are those of the physical closed loop Φ − ΓK (not of αΦ − αΓK as
/// printed in (14.26), which are α times larger).
///
/// # Errors
/// α not finite, < 1, or so large that α·max(|Φ|, |Γ|) exceeds
/// [`MAX_ENTRY`](crate::MAX_ENTRY) ([`LtiError::Parameter`] naming alpha with the allowed
/// range for this Φ, Γ); otherwise as [`dlqr`] on (αΦ, αΓ) (stabilizability is then judged
/// at |λ| ≥ 1/α for the original Φ).
pub fn dlqr_pincer(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
    alpha: f64,
) -> Result<Lqr> {
    if !(alpha.is_finite() && alpha >= 1.0) {
        return Err(LtiError::Parameter {
            what: "alpha",
            value: alpha,
            allowed: "finite and >= 1".to_string(),
        });
    }
    // Judge Φ, Γ themselves first (so an error names them, not the scaled copies), then
    // the scaled data against the same bound.
    check::bounded("A", phi)?;
    check::bounded("B", gamma)?;
    let amax = phi.amax().max(gamma.amax());
    if alpha * amax > check::MAX_ENTRY {
        return Err(LtiError::Parameter {
            what: "alpha",
            value: alpha,
            allowed: format!(
                "finite, >= 1 and at most {:.3e} here (alpha·max(|Phi|, |Gamma|) must stay \
                 below {:.0e})",
                check::MAX_ENTRY / amax,
                check::MAX_ENTRY
            ),
        });
    }
    let sol = riccati::dare(&(phi * alpha), &(gamma * alpha), q, r, n)?;
    let poles = closed_loop_poles(phi, gamma, &sol.k)?;
    Ok(Lqr {
        k: sol.k,
        s: sol.x,
        poles,
        residual: sol.residual,
    })
}

/// α from a maximum settling time, thesis (14.22): α = 100^{Ts/ts}, so that every
/// transient decays to 1 % within `settling_time_s` (α^{-k} = 0.01 at k = ts/Ts).
/// Thesis values Ts = 1/400 s, ts = 5 s give α = 1.0023 (14.25).
///
/// # Errors
/// Non-finite or non-positive times; a settling time so much shorter than Ts that α
/// overflows (Ts/ts > log₁₀(f64::MAX)/2 ≈ 154).
pub fn alpha_from_settling_time(sample_time_s: f64, settling_time_s: f64) -> Result<f64> {
    check::positive("Ts", sample_time_s)?;
    check::positive("settling time", settling_time_s)?;
    let alpha = 100f64.powf(sample_time_s / settling_time_s);
    if !alpha.is_finite() {
        return Err(LtiError::Parameter {
            what: "settling time",
            value: settling_time_s,
            allowed: format!(
                "finite, > 0 and at least Ts/154 = {:.3e} s (alpha = 100^(Ts/ts) must be finite)",
                sample_time_s / 154.0
            ),
        });
    }
    Ok(alpha)
}

/// Bryson's rule, thesis (14.15)/(14.16): diag(1/y₁,max², …, 1/y_p,max²) from the maximum
/// allowable deviations.
///
/// # Errors
/// A maximum that is not finite and positive, or so small/large that 1/max² is not a finite
/// normal number (max outside about [1.5e-154, 6.7e153]).
pub fn bryson(max_deviation: &[f64]) -> Result<DMatrix<f64>> {
    for &v in max_deviation {
        let w = 1.0 / (v * v);
        if !(v.is_finite() && v > 0.0 && w.is_finite() && w >= f64::MIN_POSITIVE) {
            return Err(LtiError::Parameter {
                what: "Bryson maximum deviation",
                value: v,
                allowed: "finite, > 0 and within [1.5e-154, 6.7e153] (1/max^2 must be a \
                          finite normal number)"
                    .to_string(),
            });
        }
    }
    let d: Vec<f64> = max_deviation.iter().map(|v| 1.0 / (v * v)).collect();
    Ok(DMatrix::from_diagonal(&nalgebra::DVector::from_vec(d)))
}

/// Weights of the Bryson–Ho cost (14.17): Q₁ = Hsᵀ Q_y Hs (14.14) with Q_y = bryson(y_max)
/// (14.15), and R = ρ Q₂ with Q₂ = bryson(u_max) (14.16). Returns (Q₁, R).
///
/// # Errors
/// Bad maxima, ρ not finite and positive, `hs` not having `y_max.len()` rows or with
/// entries above [`MAX_ENTRY`](crate::MAX_ENTRY), or a weight that overflows
/// ([`LtiError::Overflow`] for Q₁, [`LtiError::Parameter`] naming ρ for R).
pub fn bryson_weights(
    hs: &DMatrix<f64>,
    y_max: &[f64],
    u_max: &[f64],
    rho: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    check::positive("rho", rho)?;
    check::shape("Hs", hs, y_max.len(), hs.ncols())?;
    check::bounded("Hs", hs)?;
    let qy = bryson(y_max)?;
    let mut q1 = hs.transpose() * qy * hs;
    check::symmetrize(&mut q1);
    check::output("Q1 = Hs^T Qy Hs (Bryson)", &q1)?;
    let r = bryson(u_max)? * rho;
    rho_times_finite(&r, rho)?;
    Ok((q1, r))
}

/// Fails with [`LtiError::Parameter`] naming ρ if R = ρ·Q₂ has an entry above
/// [`MAX_ENTRY`](crate::MAX_ENTRY) (or overflowed), i.e. would be rejected as input R.
fn rho_times_finite(r: &DMatrix<f64>, rho: f64) -> Result<()> {
    if r.iter().all(|v| v.abs() <= check::MAX_ENTRY) {
        return Ok(());
    }
    Err(LtiError::Parameter {
        what: "rho",
        value: rho,
        allowed: format!(
            "finite, > 0 and small enough that rho·max|Q2| <= {:.0e}",
            check::MAX_ENTRY
        ),
    })
}

/// The integral-action augmented system of thesis (14.28)–(14.31), before the pincer
/// scaling: with x = [x_s; x_i] and x_i(k+1) = x_i(k) + r(k) − y(k) (14.29),
///
/// ```text
/// Φ = [[Φs, 0], [−Hs, I]],  Γ = [[Γs], [0]],  He = [−Hs, 0],  Hi = [0, I]   (14.31)
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct IntegralAugmented {
    /// Augmented Φ ((n+p)×(n+p)).
    pub phi: DMatrix<f64>,
    /// Augmented Γ ((n+p)×m).
    pub gamma: DMatrix<f64>,
    /// Output-error map He = [−Hs, 0], e = He x for r = 0 (14.31).
    pub he: DMatrix<f64>,
    /// Integral-state map Hi = [0, I] (14.31).
    pub hi: DMatrix<f64>,
    /// Number of plant states n.
    pub n_states: usize,
    /// Number of integrators p (rows of Hs).
    pub n_integrators: usize,
}

/// Builds the augmented system (14.31) from (Φs, Γs, Hs).
///
/// # Errors
/// Dimension mismatch, non-finite entries or entries above
/// [`MAX_ENTRY`](crate::MAX_ENTRY).
pub fn augment_integral(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    hs: &DMatrix<f64>,
) -> Result<IntegralAugmented> {
    let n = check::square("Phi", phi)?;
    let m = gamma.ncols();
    check::shape("Gamma", gamma, n, m)?;
    let p = hs.nrows();
    check::shape("Hs", hs, p, n)?;
    check::bounded("Phi", phi)?;
    check::bounded("Gamma", gamma)?;
    check::bounded("Hs", hs)?;
    let mut pa = DMatrix::<f64>::zeros(n + p, n + p);
    pa.view_mut((0, 0), (n, n)).copy_from(phi);
    pa.view_mut((n, 0), (p, n)).copy_from(&(-hs));
    pa.view_mut((n, n), (p, p)).fill_with_identity();
    let mut ga = DMatrix::<f64>::zeros(n + p, m);
    ga.view_mut((0, 0), (n, m)).copy_from(gamma);
    let mut he = DMatrix::<f64>::zeros(p, n + p);
    he.view_mut((0, 0), (p, n)).copy_from(&(-hs));
    let mut hi = DMatrix::<f64>::zeros(p, n + p);
    hi.view_mut((0, n), (p, p)).fill_with_identity();
    Ok(IntegralAugmented {
        phi: pa,
        gamma: ga,
        he,
        hi,
        n_states: n,
        n_integrators: p,
    })
}

/// LQR with integral action, thesis (14.31)–(14.34).
#[derive(Debug, Clone, PartialEq)]
pub struct IntegralLqr {
    /// The augmented system (14.31).
    pub system: IntegralAugmented,
    /// Full gain L_α(0) = [Ls, Li] (m×(n+p)), u = −L_α(0) x (14.34).
    pub k: DMatrix<f64>,
    /// State-feedback part Ls,α(0) (m×n) (14.34).
    pub ls: DMatrix<f64>,
    /// Integral part Li,α(0) (m×p) (14.34).
    pub li: DMatrix<f64>,
    /// Riccati solution of the augmented problem.
    pub s: DMatrix<f64>,
    /// Closed-loop eigenvalues of Φ − ΓL_α(0) (augmented, unscaled), all with |z| < 1/α.
    pub poles: Vec<Complex<f64>>,
    /// Relative Riccati residual.
    pub residual: f64,
}

/// Designs the LQR with integral action of thesis (14.28)–(14.34): augments (Φs, Γs) with
/// integrators of the outputs Hs xs, weights Q₁ = Heᵀ Qe He + Hiᵀ Qi Hi (14.33) and ρ Q₂
/// (14.32), solves the DARE for the pincer-scaled augmented system (αΦ, αΓ) (14.31)–(14.32)
/// and partitions the gain into Ls, Li (14.34). With α = 1 this is the plain design.
///
/// Note: (14.31) prints αΦs in the upper-left block only but then writes the whole
/// augmented system as αΦx + αΓu; we scale the whole augmented system, which is what the
/// pincer guarantee |z| < 1/α requires (the integrators' unit poles are scaled too).
///
/// # Errors
/// Bad dimensions/weights (Qe, Qi p×p PSD, Q₂ m×m PD, entries within
/// [`MAX_ENTRY`](crate::MAX_ENTRY)), α < 1, ρ ≤ 0 or ρ·Q₂ overflowing, or a DARE failure
/// (e.g. an output whose integrator cannot be stabilized because the plant has a
/// transmission zero at z = 1).
pub fn dlqr_integral(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    hs: &DMatrix<f64>,
    qe: &DMatrix<f64>,
    qi: &DMatrix<f64>,
    q2: &DMatrix<f64>,
    rho: f64,
    alpha: f64,
) -> Result<IntegralLqr> {
    check::positive("rho", rho)?;
    let sys = augment_integral(phi, gamma, hs)?;
    let p = sys.n_integrators;
    let n = sys.n_states;
    let m = sys.gamma.ncols();
    check::shape("Qe", qe, p, p)?;
    check::shape("Qi", qi, p, p)?;
    check::shape("Q2", q2, m, m)?;
    check::bounded("Qe", qe)?;
    check::bounded("Qi", qi)?;
    check::bounded("Q2", q2)?;
    check::psd("Qe", qe)?;
    check::psd("Qi", qi)?;
    check::pd("Q2", q2)?;
    let mut q1 = sys.he.transpose() * qe * &sys.he + sys.hi.transpose() * qi * &sys.hi;
    check::symmetrize(&mut q1);
    check::output("Q1 = He^T Qe He + Hi^T Qi Hi", &q1)?;
    let r = q2 * rho;
    rho_times_finite(&r, rho)?;
    let lqr = dlqr_pincer(&sys.phi, &sys.gamma, &q1, &r, None, alpha)?;
    let ls = lqr.k.view((0, 0), (m, n)).into_owned();
    let li = lqr.k.view((0, n), (m, p)).into_owned();
    Ok(IntegralLqr {
        system: sys,
        k: lqr.k,
        ls,
        li,
        s: lqr.s,
        poles: lqr.poles,
        residual: lqr.residual,
    })
}
