//! Discrete-time algebraic Riccati equation (DARE) by the structured doubling algorithm.
//!
//! Solves, for the stabilizing symmetric X ⪰ 0,
//!
//! ```text
//! X = AᵀXA − (AᵀXB + N)(R + BᵀXB)⁻¹(BᵀXA + Nᵀ) + Q
//! ```
//!
//! (the steady state of thesis (14.11)–(14.12) with S = X).
//!
//! Method: the structure-preserving doubling algorithm (SDA) of E. K.-W. Chu, H.-Y. Fan,
//! W.-W. Lin, C.-S. Wang, "Structure-preserving algorithms for periodic discrete-time
//! algebraic Riccati equations", Int. J. Control 77(8):767–788, 2004, in the form analysed by
//! W.-W. Lin and S.-F. Xu, "Convergence analysis of structure-preserving doubling algorithms
//! for Riccati-type matrix equations", SIAM J. Matrix Anal. Appl. 28(1):26–39, 2006:
//!
//! ```text
//! A₀ = A, G₀ = B R⁻¹ Bᵀ, H₀ = Q
//! W_k = I + G_k H_k
//! A_{k+1} = A_k W_k⁻¹ A_k
//! G_{k+1} = G_k + A_k W_k⁻¹ G_k A_kᵀ
//! H_{k+1} = H_k + A_kᵀ H_k W_k⁻¹ A_k        → X (quadratically)
//! ```
//!
//! Only I + G_k H_k is ever factored (nonsingular since G_k, H_k ⪰ 0), never A: a singular A
//! (e.g. a pure delay, or Φ of a system with a dead-beat mode) needs no special treatment.
//! The cross term N is removed first by the substitution Ã = A − B R⁻¹ Nᵀ,
//! Q̃ = Q − N R⁻¹ Nᵀ. An optional Newton refinement (G. A. Hewer, "An iterative technique for
//! the computation of the steady state gains for the discrete optimal regulator", IEEE TAC
//! 16(4):382–384, 1971) solves Δ − A_cᵀ Δ A_c = Res(X) by Smith's doubling for the Stein
//! equation and keeps the step only if it lowers the residual.

use nalgebra::DMatrix;

use crate::analysis;
use crate::check;
use crate::error::{LtiError, Result};

/// Options of [`dare_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DareOptions {
    /// Stop when ‖H_{k+1} − H_k‖_F ≤ `tol`·‖H_{k+1}‖_F (default 1e-14).
    pub tol: f64,
    /// Maximum doubling steps (default 100: quadratic convergence needs ~log₂ of the
    /// closed-loop time constant in samples, e.g. ≈ 20 for a 400 Hz helicopter model).
    pub max_iter: usize,
    /// Newton (Hewer) refinement steps always attempted after the SDA (default 0).
    pub newton_steps: usize,
    /// If the relative residual after the SDA exceeds this, up to 3 Newton steps are
    /// attempted (default 1e-12).
    pub refine_above: f64,
    /// Strict mode: run the PBH checks of stabilizability of (A, B) and detectability of
    /// (Q, A) (at the eigenvalues with |λ| ≥ 1 − 1e-8) *before* solving (default false).
    /// Without it the same diagnosis runs only when the iteration fails (no convergence, no
    /// stabilizing solution, singular step), so successful solves do not pay for it. SDA
    /// from H₀ = Q converges to the minimal PSD solution, which is not stabilizing when an
    /// unstable mode is unobservable in Q, so such problems end in the same typed
    /// [`LtiError::NotStabilizable`] / [`LtiError::NotDetectable`] either way.
    pub check_structure: bool,
}

impl Default for DareOptions {
    fn default() -> Self {
        Self {
            tol: 1e-14,
            max_iter: 100,
            newton_steps: 0,
            refine_above: 1e-12,
            check_structure: false,
        }
    }
}

/// Solution of a DARE.
#[derive(Debug, Clone, PartialEq)]
pub struct DareSolution {
    /// The stabilizing solution X = Xᵀ ⪰ 0.
    pub x: DMatrix<f64>,
    /// The optimal gain K = (R + BᵀXB)⁻¹(BᵀXA + Nᵀ), so that u = −Kx.
    pub k: DMatrix<f64>,
    /// Relative residual ‖Res(X)‖_F / (‖Q‖_F + ‖AᵀXA‖_F + ‖X‖_F + ‖(AᵀXB+N)K‖_F).
    pub residual: f64,
    /// SDA doubling steps used.
    pub iterations: usize,
    /// Newton refinement steps accepted.
    pub newton_steps: usize,
    /// Spectral radius of A − BK (< 1 for the stabilizing solution).
    pub closed_loop_spectral_radius: f64,
}

/// Solves the DARE with default [`DareOptions`]. `n` is the optional cross weight N (n×m).
///
/// On success X, K, the residual and the spectral radius are all finite.
///
/// # Errors
/// Dimension/finite/symmetry/definiteness violations of the inputs (Q ⪰ 0, R ≻ 0, and the
/// joint weight [[Q, N], [Nᵀ, R]] ⪰ 0 when N is given); entries above
/// [`MAX_ENTRY`](crate::MAX_ENTRY) ([`LtiError::TooLarge`]); [`LtiError::NotStabilizable`];
/// [`LtiError::NotDetectable`]; [`LtiError::NoConvergence`];
/// [`LtiError::NoStabilizingSolution`]; [`LtiError::Overflow`] when an iterate or the
/// result leaves the f64 range (badly scaled or nearly singular data, e.g. R ≈ 0).
pub fn dare(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
) -> Result<DareSolution> {
    dare_with(a, b, q, r, n, &DareOptions::default())
}

/// Validates the DARE data; returns (n, m).
fn validate(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
) -> Result<(usize, usize)> {
    let nx = check::square("A", a)?;
    let m = b.ncols();
    check::shape("B", b, nx, m)?;
    check::shape("Q", q, nx, nx)?;
    check::shape("R", r, m, m)?;
    if let Some(nn) = n {
        check::shape("N", nn, nx, m)?;
        check::bounded("N", nn)?;
    }
    check::bounded("A", a)?;
    check::bounded("B", b)?;
    check::bounded("Q", q)?;
    check::bounded("R", r)?;
    check::psd("Q", q)?;
    check::pd("R", r)?;
    Ok((nx, m))
}

/// Frobenius norm that does not overflow for large finite entries ([`check::fro`]).
fn fro(m: &DMatrix<f64>) -> f64 {
    check::fro(m)
}

/// Relative residual of X for the (cross-term-free) data, and the gain K.
pub(crate) fn residual_and_gain(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
    x: &DMatrix<f64>,
) -> Result<(f64, DMatrix<f64>, DMatrix<f64>)> {
    let xa = x * a;
    let xb = x * b;
    let mut btxa_nt = b.transpose() * &xa;
    if let Some(nn) = n {
        btxa_nt += nn.transpose();
    }
    let mut s = r + b.transpose() * &xb;
    check::symmetrize(&mut s);
    let k = solve_spd_or_lu(&s, &btxa_nt, "R + BᵀXB")?;
    let atxa = a.transpose() * &xa;
    let corr = btxa_nt.transpose() * &k;
    let mut res = q + &atxa - x - &corr;
    check::symmetrize(&mut res);
    let denom = fro(q) + fro(&atxa) + fro(x) + fro(&corr);
    let rel = if denom > 0.0 {
        fro(&res) / denom
    } else {
        fro(&res)
    };
    Ok((rel, k, res))
}

/// Solves S Y = B for symmetric positive definite S (Cholesky), falling back to LU.
fn solve_spd_or_lu(
    s: &DMatrix<f64>,
    rhs: &DMatrix<f64>,
    what: &'static str,
) -> Result<DMatrix<f64>> {
    if let Some(ch) = s.clone().cholesky() {
        return Ok(ch.solve(rhs));
    }
    s.clone().lu().solve(rhs).ok_or(LtiError::Singular { what })
}

/// Scales a matrix to Frobenius norm `target` (unless it is zero).
fn scaled(m: &DMatrix<f64>, target: f64) -> DMatrix<f64> {
    let nm = fro(m);
    if nm > 0.0 {
        m * (target / nm)
    } else {
        m.clone()
    }
}

/// Options must be usable numbers (a NaN tolerance would silently never stop).
fn validate_options(opts: &DareOptions) -> Result<()> {
    if opts.tol.is_nan() || opts.tol < 0.0 {
        return Err(LtiError::Parameter {
            what: "DareOptions::tol",
            value: opts.tol,
            allowed: ">= 0 (relative change of the iterate)".to_string(),
        });
    }
    if opts.refine_above.is_nan() {
        return Err(LtiError::Parameter {
            what: "DareOptions::refine_above",
            value: opts.refine_above,
            allowed: "not NaN (relative residual)".to_string(),
        });
    }
    Ok(())
}

/// Stabilizability of (A, B) and detectability of (Q, A) by PBH at |λ| ≥ 1 − 1e-8.
/// B and Q are first scaled to the Frobenius norm of A (at least 1) so the σ ratio measures
/// geometry, not units. Tolerance [`analysis::PBH_TOL`].
fn check_structure(a: &DMatrix<f64>, b: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<()> {
    let target = fro(a).max(1.0);
    let margin = 1e-8;
    // One eigen-decomposition serves both tests: eig(Aᵀ) = eig(A).
    let eig = analysis::eigenvalues(a)?;
    let outside = |z: nalgebra::Complex<f64>| z.norm() >= 1.0 - margin;
    if !eig.iter().any(|&z| outside(z)) {
        return Ok(());
    }
    let rep = analysis::pbh_at(a, &scaled(b, target), &eig, analysis::PBH_TOL, outside)?;
    if let Some(l) = rep.failing.first() {
        return Err(LtiError::NotStabilizable {
            pair: "(A, B)",
            re: l.re,
            im: l.im,
            ratio: rep.min_ratio,
        });
    }
    let rep = analysis::pbh_at(
        &a.transpose(),
        &scaled(q, target),
        &eig,
        analysis::PBH_TOL,
        outside,
    )?;
    if let Some(l) = rep.failing.first() {
        return Err(LtiError::NotDetectable {
            pair: "(Q, A)",
            re: l.re,
            im: l.im,
            ratio: rep.min_ratio,
        });
    }
    Ok(())
}

/// Removes the cross term: returns (Ã, Q̃) = (A − B R⁻¹ Nᵀ, Q − N R⁻¹ Nᵀ).
fn remove_cross(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    nn: &DMatrix<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let rinv_nt = solve_spd_or_lu(r, &nn.transpose(), "R")?;
    let at = a - b * &rinv_nt;
    let mut qt = q - nn * &rinv_nt;
    check::symmetrize(&mut qt);
    check::output(
        "A - B R^-1 N^T (cross-term removal; R nearly singular?)",
        &at,
    )?;
    check::output(
        "Q - N R^-1 N^T (cross-term removal; R nearly singular?)",
        &qt,
    )?;
    // The joint weight [[Q, N], [Nᵀ, R]] ⪰ 0 iff Q̃ ⪰ 0 (Schur complement, R ≻ 0).
    check::psd("Q - N R^-1 N^T (joint weight [[Q, N], [N^T, R]])", &qt)?;
    Ok((at, qt))
}

/// The SDA iteration on cross-term-free data; returns (X, iterations).
fn sda(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    opts: &DareOptions,
) -> Result<(DMatrix<f64>, usize)> {
    let nx = a.nrows();
    // G₀ = B R⁻¹ Bᵀ via the Cholesky factor R = LLᵀ: G₀ = (B L⁻ᵀ)(B L⁻ᵀ)ᵀ.
    let ch = r.clone().cholesky().ok_or(LtiError::NotPositiveDefinite {
        what: "R",
        min_eigenvalue: f64::NAN,
    })?;
    let l = ch.l();
    let bs_t = l
        .solve_lower_triangular(&b.transpose())
        .ok_or(LtiError::Singular {
            what: "Cholesky factor of R",
        })?;
    let mut g = bs_t.transpose() * &bs_t;
    check::output("B R^-1 B^T (SDA start; R nearly singular?)", &g)?;
    let mut h = q.clone();
    let mut ak = a.clone();
    let ident = DMatrix::<f64>::identity(nx, nx);
    let mut prev_change = f64::INFINITY;
    let mut change = f64::INFINITY;
    for it in 1..=opts.max_iter {
        let w = &ident + &g * &h;
        // One LU and an explicit inverse (n right-hand sides instead of 2n), then products.
        let winv = w.try_inverse().ok_or(LtiError::Singular {
            what: "I + G_k H_k (SDA)",
        })?;
        let y1 = &winv * &ak; // W⁻¹ A_k
        let y2 = &winv * &g; // W⁻¹ G_k
        let h_next = {
            let mut t = &h + ak.transpose() * (&h * &y1);
            check::symmetrize(&mut t);
            t
        };
        let g_next = {
            let mut t = &g + &ak * (&y2 * ak.transpose());
            check::symmetrize(&mut t);
            t
        };
        let a_next = &ak * &y1;
        let hn = fro(&h_next);
        let diff = fro(&(&h_next - &h));
        change = if hn > 0.0 { diff / hn } else { diff };
        h = h_next;
        g = g_next;
        ak = a_next;
        // Overflow of an iterate (an unstable mode that cannot be stabilized grows like
        // λ^(2^k), or data too badly scaled) is reported, never iterated on as NaN. Checking
        // H suffices: a non-finite A_k or G_k reaches H_{k+1} through W_k and the products.
        if !(change.is_finite() && h.as_slice().iter().all(|v| v.is_finite())) {
            return Err(LtiError::Overflow {
                what: "SDA iterate (DARE)",
                detail: format!(
                    "left the f64 range at doubling step {it}; {}",
                    check::OVERFLOW_HINT
                ),
            });
        }
        if change <= opts.tol {
            return Ok((h, it));
        }
        // Rounding floor: once the change is tiny and stops shrinking quadratically, stop.
        if change < 1e-10 && change > 0.5 * prev_change {
            return Ok((h, it));
        }
        prev_change = change;
    }
    Err(LtiError::NoConvergence {
        what: "SDA (DARE)",
        iterations: opts.max_iter,
        last_change: change,
    })
}

/// Solves the Stein equation X = Mᵀ X M + S by Smith's doubling (R. A. Smith, "Matrix
/// equation XA + BX = C", SIAM J. Appl. Math. 16(1):198–201, 1968), for ρ(M) < 1.
pub(crate) fn stein_doubling(m: &DMatrix<f64>, s: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let mut x = s.clone();
    let mut mk = m.clone();
    for it in 1..=64 {
        let inc = mk.transpose() * &x * &mk;
        let xn = fro(&x);
        let incn = fro(&inc);
        x += inc;
        mk = &mk * &mk;
        if incn <= f64::EPSILON * xn || fro(&mk) == 0.0 {
            check::symmetrize(&mut x);
            return Ok(x);
        }
        if !incn.is_finite() {
            return Err(LtiError::NoConvergence {
                what: "Stein doubling",
                iterations: it,
                last_change: incn,
            });
        }
    }
    Err(LtiError::NoConvergence {
        what: "Stein doubling",
        iterations: 64,
        last_change: f64::NAN,
    })
}

/// Solves the DARE with explicit options; see the module documentation for the method.
///
/// # Errors
/// As [`dare`].
pub fn dare_with(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
    opts: &DareOptions,
) -> Result<DareSolution> {
    validate(a, b, q, r, n)?;
    validate_options(opts)?;
    let (at, qt) = match n {
        Some(nn) => remove_cross(a, b, q, r, nn)?,
        None => (a.clone(), q.clone()),
    };
    if opts.check_structure {
        check_structure(&at, b, &qt)?;
    }
    match solve_checked(a, b, q, r, n, &at, &qt, opts) {
        Err(
            e @ (LtiError::NoConvergence { .. }
            | LtiError::NoStabilizingSolution { .. }
            | LtiError::Singular { .. }
            | LtiError::Overflow { .. }),
        ) => {
            // Diagnose: a structural cause is the more useful error.
            check_structure(&at, b, &qt)?;
            Err(e)
        }
        other => other,
    }
}

/// SDA, optional Newton refinement, residual and stability of the result.
fn solve_checked(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
    at: &DMatrix<f64>,
    qt: &DMatrix<f64>,
    opts: &DareOptions,
) -> Result<DareSolution> {
    let (mut x, iterations) = sda(at, b, qt, r, opts)?;
    check::symmetrize(&mut x);
    let (mut rel, mut k, mut res) = residual_and_gain(at, b, qt, r, None, &x)?;
    check::output("gain K (DARE)", &k)?;
    check::output_scalar("DARE residual", rel)?;
    let mut accepted = 0;
    let max_newton = if rel > opts.refine_above {
        opts.newton_steps.max(3)
    } else {
        opts.newton_steps
    };
    for _ in 0..max_newton {
        let ac = at - b * &k;
        let Ok(delta) = stein_doubling(&ac, &res) else {
            break;
        };
        let mut xn = &x + delta;
        check::symmetrize(&mut xn);
        let (rn, kn, resn) = residual_and_gain(at, b, qt, r, None, &xn)?;
        // A non-finite candidate fails `rn < rel` (NaN) or is caught here.
        if rn < rel && kn.iter().all(|v| v.is_finite()) {
            x = xn;
            rel = rn;
            k = kn;
            res = resn;
            accepted += 1;
        } else {
            break;
        }
    }
    // Report in terms of the original data (with N).
    let (rel_orig, k_orig, _) = residual_and_gain(a, b, q, r, n, &x)?;
    check::output("Riccati solution X", &x)?;
    check::output("gain K (DARE)", &k_orig)?;
    check::output_scalar("DARE residual", rel_orig)?;
    let acl = a - b * &k_orig;
    check::output("closed loop A - BK", &acl)?;
    let rho = analysis::spectral_radius(&acl)?;
    if rho.partial_cmp(&1.0) != Some(std::cmp::Ordering::Less) {
        return Err(LtiError::NoStabilizingSolution {
            spectral_radius: rho,
        });
    }
    Ok(DareSolution {
        x,
        k: k_orig,
        residual: rel_orig,
        iterations,
        newton_steps: accepted,
        closed_loop_spectral_radius: rho,
    })
}
