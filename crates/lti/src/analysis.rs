//! Structural analysis: poles, natural frequency and damping, controllability and
//! observability.
//!
//! Controllability is never judged from the power matrix [B AB … Aⁿ⁻¹B]: its columns span
//! dozens of orders of magnitude (for the thesis hover model, singular values from 6e62 to
//! 5e33, so a numerical rank of 11 instead of 27). Instead:
//! * [`pbh_controllability`]: the Popov–Belevitch–Hautus test, σ_min([A − λI, B]) relative
//!   to σ_max at every eigenvalue λ (Hautus 1969), with SVD;
//! * [`reachable_dimension`]: the dimension of the reachable subspace by an orthogonal block
//!   Krylov (block Arnoldi / staircase) iteration with rank decisions by SVD (Varga 1981,
//!   "Numerically stable algorithm for standard controllability form determination",
//!   Electronics Letters 17(2); Van Dooren 1981 staircase form).

use nalgebra::{Complex, DMatrix};

use crate::check;
use crate::error::{LtiError, Result};

/// Maximum QR iterations per eigenvalue before a decomposition is declared failed.
const MAX_ITER: usize = 10_000;

/// Eigenvalues of a general real square matrix (real Schur form, nalgebra), ordered by
/// ascending real part, then imaginary part.
///
/// nalgebra's Francis QR has no exceptional shifts and can stagnate on matrices that are
/// exactly reducible (e.g. the integral-augmented [[Φ, 0], [−H, I]] of thesis (14.31)). We
/// therefore try, in order: A; Aᵀ; the orthogonal similarity P A P with a fixed Householder
/// reflector P = I − 2vvᵀ (v ∝ (1, 2, …, n)); each first with tolerance ε, then 1e-14.
/// All have the same eigenvalues; the first converging decomposition is used.
///
/// Any finite matrix is accepted: it is first scaled by a power of two to max |a_ij| < 1
/// (exact, so the digits are those of the unscaled computation), and the eigenvalues are
/// scaled back.
///
/// # Errors
/// Non-square or non-finite input; Schur iteration not converging in any variant;
/// [`LtiError::Overflow`] if an eigenvalue (or its modulus) exceeds the f64 range (entries
/// near f64::MAX).
pub fn eigenvalues(a: &DMatrix<f64>) -> Result<Vec<Complex<f64>>> {
    check::square("A", a)?;
    check::finite("A", a)?;
    let n = a.nrows();
    if n == 0 {
        return Ok(Vec::new());
    }
    let f = check::pow2_scale(a.amax());
    let a = &(a * f);
    let reflected = || {
        let v = DMatrix::from_fn(n, 1, |i, _| (i + 1) as f64);
        let v = &v / v.norm();
        let p = DMatrix::<f64>::identity(n, n) - &v * v.transpose() * 2.0;
        &p * a * &p
    };
    let mut schur = None;
    'outer: for eps in [f64::EPSILON, 1e-14] {
        for variant in 0..3 {
            let m = match variant {
                0 => a.clone(),
                1 => a.transpose(),
                _ => reflected(),
            };
            // Typical convergence needs 2–4 QR sweeps per eigenvalue; the first round allows
            // 10 per eigenvalue so a stagnating variant fails fast, the second LAPACK's 30.
            let limit = if eps == f64::EPSILON {
                10 * n + 20
            } else {
                30 * n + 100
            };
            if let Some(s) = nalgebra::Schur::try_new(m, eps, limit) {
                schur = Some(s);
                break 'outer;
            }
        }
    }
    let schur = schur.ok_or(LtiError::Decomposition { what: "Schur" })?;
    let ev = schur.complex_eigenvalues();
    let mut v: Vec<Complex<f64>> = ev.iter().map(|z| z / f).collect();
    if let Some(z) = v
        .iter()
        .find(|z| !(z.re.is_finite() && z.im.is_finite() && z.norm().is_finite()))
    {
        return Err(LtiError::Overflow {
            what: "eigenvalues",
            detail: format!(
                "eigenvalue {z} exceeds the f64 range (max |a_ij| = {:.3e})",
                a.amax() / f
            ),
        });
    }
    v.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
    Ok(v)
}

/// Spectral radius max |λ_i(A)|.
///
/// # Errors
/// As [`eigenvalues`].
pub fn spectral_radius(a: &DMatrix<f64>) -> Result<f64> {
    Ok(eigenvalues(a)?.iter().map(|z| z.norm()).fold(0.0, f64::max))
}

/// One pole with its natural frequency and damping ratio, in MATLAB `damp` conventions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pole {
    /// The pole (continuous: s in rad/s; discrete: z, dimensionless).
    pub value: Complex<f64>,
    /// Natural frequency ω_n = |s| in rad/s (for a discrete pole, of s = ln(z)/Ts).
    pub natural_frequency_rad_s: f64,
    /// Damping ratio ζ = −Re(s)/|s|; −1 for s = 0 (MATLAB `damp` convention, as Table 14.1).
    pub damping: f64,
}

fn damp_of(s: Complex<f64>) -> (f64, f64) {
    let wn = s.norm();
    if wn == 0.0 {
        (0.0, -1.0)
    } else {
        (wn, -s.re / wn)
    }
}

/// Poles of a continuous-time system ẋ = A x with natural frequency and damping
/// (MATLAB `damp`; the quantities of thesis Table 14.1).
///
/// # Errors
/// As [`eigenvalues`] (which also guarantees finite |s|, so ω_n and ζ are finite).
pub fn damp(a: &DMatrix<f64>) -> Result<Vec<Pole>> {
    Ok(eigenvalues(a)?
        .into_iter()
        .map(|s| {
            let (wn, z) = damp_of(s);
            Pole {
                value: s,
                natural_frequency_rad_s: wn,
                damping: z,
            }
        })
        .collect())
}

/// Poles of a discrete-time system x⁺ = Φ x with sample time `ts_s`; frequency and damping
/// are those of the equivalent continuous pole s = ln(z)/Ts (MATLAB `damp(sys)` for a
/// discrete `sys`). A pole at z = 0 gets ω_n = ∞ and ζ = 1 (as MATLAB).
/// Apart from that documented ∞, all returned numbers are finite.
///
/// # Errors
/// As [`eigenvalues`]; `ts_s` not finite and positive, or so small that ln(z)/Ts overflows
/// ([`LtiError::Parameter`] naming Ts with the smallest usable value).
pub fn damp_discrete(phi: &DMatrix<f64>, ts_s: f64) -> Result<Vec<Pole>> {
    check::positive("Ts", ts_s)?;
    let mut out = Vec::with_capacity(phi.nrows());
    for z in eigenvalues(phi)? {
        if z.norm() == 0.0 {
            out.push(Pole {
                value: z,
                natural_frequency_rad_s: f64::INFINITY,
                damping: 1.0,
            });
            continue;
        }
        let ln_z = z.ln();
        let s = ln_z / ts_s;
        let (wn, d) = damp_of(s);
        if !(wn.is_finite() && d.is_finite()) {
            return Err(LtiError::Parameter {
                what: "Ts",
                value: ts_s,
                allowed: format!(
                    "at least {:.3e} s: ln(z)/Ts overflows f64 for the pole z = {z}",
                    ln_z.norm() / f64::MAX
                ),
            });
        }
        out.push(Pole {
            value: z,
            natural_frequency_rad_s: wn,
            damping: d,
        });
    }
    Ok(out)
}

/// Result of a PBH (Popov–Belevitch–Hautus) test.
#[derive(Debug, Clone, PartialEq)]
pub struct PbhReport {
    /// True if every tested eigenvalue passes (ratio above the tolerance).
    pub full_rank: bool,
    /// Smallest σ_min/σ_max over the tested eigenvalues.
    pub min_ratio: f64,
    /// The eigenvalue at which `min_ratio` occurs (None if nothing was tested).
    pub worst_eigenvalue: Option<Complex<f64>>,
    /// Eigenvalues that failed the test.
    pub failing: Vec<Complex<f64>>,
}

/// Default relative tolerance of the PBH test: σ_min/σ_max below 1e-10 means rank loss.
/// Rounding in the SVD of an (n)×(n+m) matrix is ≈ n·ε ≈ 1e-14 relative; genuine
/// uncontrollable modes computed from perturbed data typically land at 1e-14..1e-12, while
/// the thesis model's weakest genuine direction is 1.3e-5 (control.) and 3.5e-7 (obs.).
pub const PBH_TOL: f64 = 1e-10;

fn to_complex(m: &DMatrix<f64>) -> DMatrix<Complex<f64>> {
    m.map(|v| Complex::new(v, 0.0))
}

/// Singular values of a real matrix, guarded: nalgebra's SVD panics ("Singular value was
/// NaN") on non-finite input and asserts on an empty matrix, so both are turned into
/// [`LtiError::Decomposition`] here, as is a non-finite result.
fn singular_values(m: DMatrix<f64>, what: &'static str) -> Result<nalgebra::DVector<f64>> {
    if m.is_empty() || !m.iter().all(|v| v.is_finite()) {
        return Err(LtiError::Decomposition { what });
    }
    let sv = nalgebra::SVD::try_new(m, false, false, f64::EPSILON, MAX_ITER)
        .ok_or(LtiError::Decomposition { what })?
        .singular_values;
    if !sv.iter().all(|v| v.is_finite()) {
        return Err(LtiError::Decomposition { what });
    }
    Ok(sv)
}

/// As [`singular_values`] for a complex matrix.
fn singular_values_complex(
    m: DMatrix<Complex<f64>>,
    what: &'static str,
) -> Result<nalgebra::DVector<f64>> {
    if m.is_empty() || !m.iter().all(|v| v.re.is_finite() && v.im.is_finite()) {
        return Err(LtiError::Decomposition { what });
    }
    let sv = nalgebra::SVD::try_new(m, false, false, f64::EPSILON, MAX_ITER)
        .ok_or(LtiError::Decomposition { what })?
        .singular_values;
    if !sv.iter().all(|v| v.is_finite()) {
        return Err(LtiError::Decomposition { what });
    }
    Ok(sv)
}

/// σ_min/σ_max of [A − λI, B] (or its transpose arrangement for observability). Real λ
/// uses a real SVD (a quarter of the work of the complex one). The caller scales A, B and λ
/// to magnitudes ≲ 1 (see [`pbh_at`]), so forming A − λI cannot overflow.
fn pbh_ratio(a: &DMatrix<f64>, b: &DMatrix<f64>, lambda: Complex<f64>) -> Result<f64> {
    let n = a.nrows();
    let m = b.ncols();
    let sv = if lambda.im == 0.0 {
        let mut mat = DMatrix::<f64>::zeros(n, n + m);
        mat.view_mut((0, 0), (n, n)).copy_from(a);
        for i in 0..n {
            mat[(i, i)] -= lambda.re;
        }
        mat.view_mut((0, n), (n, m)).copy_from(b);
        singular_values(mat, "SVD (PBH)")?
    } else {
        let mut mat = DMatrix::<Complex<f64>>::zeros(n, n + m);
        mat.view_mut((0, 0), (n, n)).copy_from(&to_complex(a));
        for i in 0..n {
            mat[(i, i)] -= lambda;
        }
        mat.view_mut((0, n), (n, m)).copy_from(&to_complex(b));
        singular_values_complex(mat, "SVD (PBH)")?
    };
    let smax = sv.iter().copied().fold(0.0, f64::max);
    // n singular values for an n×(n+m) matrix: the smallest is σ_min.
    let smin = sv.iter().copied().fold(f64::INFINITY, f64::min);
    Ok(if smax == 0.0 { 0.0 } else { smin / smax })
}

/// Fails with [`LtiError::Parameter`] unless a rank tolerance is finite and ≥ 0.
fn tolerance(what: &'static str, tol: f64) -> Result<()> {
    if tol.is_finite() && tol >= 0.0 {
        Ok(())
    } else {
        Err(LtiError::Parameter {
            what,
            value: tol,
            allowed: "finite and >= 0 (relative singular-value threshold)".to_string(),
        })
    }
}

fn pbh_generic(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    tol: f64,
    only: impl Fn(Complex<f64>) -> bool,
) -> Result<PbhReport> {
    let eig = eigenvalues(a)?;
    pbh_at(a, b, &eig, tol, only)
}

/// PBH test of (A, B) at the given eigenvalues of A. Conjugates give the same σ's, so only
/// the upper member of a pair is tested; eigenvalues equal to within 1e-10·max(1, |λ|)
/// (a repeated eigenvalue split by rounding) are tested once.
///
/// The ratio is invariant under a common scaling of A, B and λ, so all three are scaled by
/// one power of two to magnitudes below 1 first: any finite data then gives a finite
/// [A − λI, B] (no overflow into the SVD).
pub(crate) fn pbh_at(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    eig: &[Complex<f64>],
    tol: f64,
    only: impl Fn(Complex<f64>) -> bool,
) -> Result<PbhReport> {
    tolerance("PBH tolerance", tol)?;
    check::finite("A", a)?;
    check::finite("B", b)?;
    let lam_max = eig.iter().map(|z| z.norm()).fold(0.0, f64::max);
    if !lam_max.is_finite() {
        return Err(LtiError::Overflow {
            what: "eigenvalues",
            detail: "an eigenvalue is not finite".to_string(),
        });
    }
    let f = check::pow2_scale(a.amax().max(b.amax()).max(lam_max));
    let (a, b) = (&(a * f), &(b * f));
    let mut rep = PbhReport {
        full_rank: true,
        min_ratio: f64::INFINITY,
        worst_eigenvalue: None,
        failing: Vec::new(),
    };
    let mut tested: Vec<Complex<f64>> = Vec::new();
    for &lam in eig {
        if !only(lam) || lam.im < 0.0 {
            continue;
        }
        if tested
            .iter()
            .any(|t| (t - lam).norm() <= 1e-10 * lam.norm().max(1.0))
        {
            continue;
        }
        tested.push(lam);
        let r = pbh_ratio(a, b, lam * f)?;
        if r < rep.min_ratio {
            rep.min_ratio = r;
            rep.worst_eigenvalue = Some(lam);
        }
        if r <= tol {
            rep.full_rank = false;
            rep.failing.push(lam);
        }
    }
    Ok(rep)
}

/// PBH controllability test: rank [A − λI, B] = n at every eigenvalue λ of A, judged by
/// σ_min/σ_max > `tol` (use [`PBH_TOL`] by default).
///
/// # Errors
/// Dimension mismatch, non-finite input, `tol` not finite and ≥ 0, decomposition failure.
/// Any finite A, B (C) is accepted (rescaled internally).
pub fn pbh_controllability(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64) -> Result<PbhReport> {
    let n = check::square("A", a)?;
    check::shape("B", b, n, b.ncols())?;
    check::finite("B", b)?;
    tolerance("PBH tolerance", tol)?;
    pbh_generic(a, b, tol, |_| true)
}

/// PBH observability test: rank [A − λI; C] = n at every eigenvalue (by duality, the
/// controllability test of (Aᵀ, Cᵀ)).
///
/// # Errors
/// Dimension mismatch, non-finite input, `tol` not finite and ≥ 0, decomposition failure.
/// Any finite A, B (C) is accepted (rescaled internally).
pub fn pbh_observability(a: &DMatrix<f64>, c: &DMatrix<f64>, tol: f64) -> Result<PbhReport> {
    let n = check::square("A", a)?;
    check::shape("C", c, c.nrows(), n)?;
    check::finite("C", c)?;
    tolerance("PBH tolerance", tol)?;
    pbh_generic(&a.transpose(), &c.transpose(), tol, |_| true)
}

/// Reachable subspace of (A, B) by an orthogonal block-Krylov (staircase) iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct Reachable {
    /// Dimension of the reachable (controllable) subspace.
    pub dimension: usize,
    /// Orthonormal basis, n × dimension.
    pub basis: DMatrix<f64>,
    /// Smallest singular value kept in a rank decision, relative to the scale ‖[A B]‖_F.
    pub smallest_kept: f64,
    /// Largest singular value dropped in a rank decision, relative to the same scale.
    pub largest_dropped: f64,
}

/// Default relative tolerance of the staircase rank decisions (times ‖[A, B]‖_F): well
/// above the rounding level (≈ n·ε) and well below genuine weak directions.
pub const STAIRCASE_TOL: f64 = 1e-10;

/// Dimension of the reachable subspace of (A, B): an orthonormal basis V is grown block by
/// block, V_{k+1} = orth((I − V Vᵀ) A V_k) with two passes of block Gram–Schmidt and an SVD
/// rank decision relative to `tol`·‖[A, B]‖_F (block Arnoldi; the orthogonal staircase of
/// Varga 1981 / Van Dooren 1981). (A, B) is controllable iff the dimension is n.
///
/// # Errors
/// Dimension mismatch, non-finite input, `tol` not finite and ≥ 0, SVD failure.
/// Any finite A, B is accepted (rescaled internally).
pub fn reachable_dimension(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64) -> Result<Reachable> {
    let n = check::square("A", a)?;
    check::shape("B", b, n, b.ncols())?;
    check::finite("A", a)?;
    check::finite("B", b)?;
    tolerance("staircase tolerance", tol)?;
    // The reachable subspace is invariant under a common scaling of A and B, and so are the
    // relative rank decisions: scale both by one power of two (exact) to entries below 1,
    // so that the norms and the SVD below cannot overflow for any finite input.
    let f = check::pow2_scale(a.amax().max(b.amax()));
    let (a, b) = (&(a * f), &(b * f));
    let scale = (a.norm_squared() + b.norm_squared())
        .sqrt()
        .max(f64::MIN_POSITIVE);
    let thresh = tol * scale;
    let mut basis = DMatrix::<f64>::zeros(n, 0);
    let mut kept_min = f64::INFINITY;
    let mut dropped_max: f64 = 0.0;
    let mut block = b.clone();
    while basis.ncols() < n && block.ncols() > 0 {
        // Two passes of block Gram–Schmidt against the current basis.
        for _ in 0..2 {
            if basis.ncols() > 0 {
                let proj = basis.transpose() * &block;
                block -= &basis * proj;
            }
        }
        // nalgebra's SVD panics on non-finite input (see `singular_values`).
        if !block.iter().all(|v| v.is_finite()) {
            return Err(LtiError::Decomposition {
                what: "SVD (staircase)",
            });
        }
        let svd = nalgebra::SVD::try_new(block.clone(), true, false, f64::EPSILON, MAX_ITER)
            .ok_or(LtiError::Decomposition {
                what: "SVD (staircase)",
            })?;
        let u = svd.u.ok_or(LtiError::Decomposition {
            what: "SVD (staircase)",
        })?;
        let mut keep: Vec<usize> = Vec::new();
        for (i, &s) in svd.singular_values.iter().enumerate() {
            if s > thresh {
                keep.push(i);
                kept_min = kept_min.min(s / scale);
            } else {
                dropped_max = dropped_max.max(s / scale);
            }
        }
        let room = n - basis.ncols();
        keep.truncate(room);
        if keep.is_empty() {
            break;
        }
        let newcols = u.select_columns(keep.iter());
        let old = basis.ncols();
        let mut grown = DMatrix::<f64>::zeros(n, old + newcols.ncols());
        grown.view_mut((0, 0), (n, old)).copy_from(&basis);
        grown
            .view_mut((0, old), (n, newcols.ncols()))
            .copy_from(&newcols);
        basis = grown;
        block = a * newcols;
    }
    Ok(Reachable {
        dimension: basis.ncols(),
        basis,
        smallest_kept: if kept_min.is_finite() { kept_min } else { 0.0 },
        largest_dropped: dropped_max,
    })
}

/// Dimension of the observable subspace of (A, C) (duality: reachable subspace of
/// (Aᵀ, Cᵀ)).
///
/// # Errors
/// As [`reachable_dimension`].
pub fn observable_dimension(a: &DMatrix<f64>, c: &DMatrix<f64>, tol: f64) -> Result<Reachable> {
    let n = check::square("A", a)?;
    check::shape("C", c, c.nrows(), n)?;
    check::finite("C", c)?;
    reachable_dimension(&a.transpose(), &c.transpose(), tol)
}

/// True iff (A, B) is controllable by both the staircase ([`reachable_dimension`]) and the
/// PBH test, with the default tolerances.
///
/// # Errors
/// As [`reachable_dimension`] and [`pbh_controllability`].
pub fn is_controllable(a: &DMatrix<f64>, b: &DMatrix<f64>) -> Result<bool> {
    let r = reachable_dimension(a, b, STAIRCASE_TOL)?;
    let p = pbh_controllability(a, b, PBH_TOL)?;
    Ok(r.dimension == a.nrows() && p.full_rank)
}
