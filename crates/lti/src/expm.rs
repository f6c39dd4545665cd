//! Matrix exponential and zero-order-hold discretization.
//!
//! `expm` is the scaling-and-squaring algorithm with diagonal Padé approximants of degree
//! 3, 5, 7, 9 or 13 of N. J. Higham, "The scaling and squaring method for the matrix
//! exponential revisited", SIAM J. Matrix Anal. Appl. 26(4):1179–1193, 2005 (Algorithm 2.3,
//! with the θ_m of Table 2.3 and the coefficients b_j of the Padé approximants).

use nalgebra::{DMatrix, SMatrix};

use crate::check;
use crate::error::{LtiError, Result};

/// Padé coefficients b_0..b_m (Higham 2005, eq. (2.1) and Algorithm 2.3).
const B3: [f64; 4] = [120.0, 60.0, 12.0, 1.0];
const B5: [f64; 6] = [30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0];
const B7: [f64; 8] = [
    17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0,
];
const B9: [f64; 10] = [
    17643225600.0,
    8821612800.0,
    2075673600.0,
    302702400.0,
    30270240.0,
    2162160.0,
    110880.0,
    3960.0,
    90.0,
    1.0,
];
const B13: [f64; 14] = [
    64764752532480000.0,
    32382376266240000.0,
    7771770303897600.0,
    1187353796428800.0,
    129060195264000.0,
    10559470521600.0,
    670442572800.0,
    33522128640.0,
    1323241920.0,
    40840800.0,
    960960.0,
    16380.0,
    182.0,
    1.0,
];
/// θ_m for m = 3, 5, 7, 9, 13 (Higham 2005, Table 2.3, double precision).
const THETA: [f64; 5] = [
    1.495585217958292e-2,
    2.539398330063230e-1,
    9.504178996162932e-1,
    2.097847961257068e0,
    5.371920351148152e0,
];

fn norm1(a: &DMatrix<f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.column(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Solves (V − U) X = V + U for the Padé approximant r_m = (V−U)⁻¹(V+U).
fn pade_solve(u: DMatrix<f64>, v: DMatrix<f64>) -> Result<DMatrix<f64>> {
    let p = &v + &u;
    let q = v - u;
    q.lu().solve(&p).ok_or(LtiError::Singular {
        what: "expm Padé denominator",
    })
}

/// Low-degree Padé approximant r_m(A), m ∈ {3, 5, 7, 9}.
fn pade_low(a: &DMatrix<f64>, b: &[f64]) -> Result<DMatrix<f64>> {
    let n = a.nrows();
    let ident = DMatrix::<f64>::identity(n, n);
    let a2 = a * a;
    // Even powers A^0, A^2, A^4, ...
    let mut pow = ident.clone();
    let mut u_even = DMatrix::<f64>::zeros(n, n);
    let mut v = DMatrix::<f64>::zeros(n, n);
    let m = b.len() - 1;
    for k in 0..=(m / 2) {
        // U = A Σ b_{2k+1} A^{2k}, V = Σ b_{2k} A^{2k}
        u_even += &pow * b[2 * k + 1];
        v += &pow * b[2 * k];
        if k < m / 2 {
            pow = &pow * &a2;
        }
    }
    let u = a * u_even;
    pade_solve(u, v)
}

/// Degree-13 Padé approximant r_13(A) evaluated as in Higham 2005, eq. (2.3)-ish scheme.
fn pade13(a: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let n = a.nrows();
    let b = &B13;
    let ident = DMatrix::<f64>::identity(n, n);
    let a2 = a * a;
    let a4 = &a2 * &a2;
    let a6 = &a2 * &a4;
    let w1 = &a6 * b[13] + &a4 * b[11] + &a2 * b[9];
    let w2 = &a6 * b[7] + &a4 * b[5] + &a2 * b[3] + &ident * b[1];
    let z1 = &a6 * b[12] + &a4 * b[10] + &a2 * b[8];
    let z2 = &a6 * b[6] + &a4 * b[4] + &a2 * b[2] + &ident * b[0];
    let w = &a6 * w1 + w2;
    let u = a * w;
    let v = &a6 * z1 + z2;
    pade_solve(u, v)
}

/// ln(f64::MAX): e^x overflows f64 for x above this.
const LN_MAX: f64 = 709.782712893384;

/// Largest real part of the eigenvalues of `a` (spectral abscissa), if computable.
fn abscissa(a: &DMatrix<f64>) -> Option<f64> {
    crate::analysis::eigenvalues(a)
        .ok()?
        .iter()
        .map(|z| z.re)
        .reduce(f64::max)
}

/// e^A without the checks of [`expm`] (input already validated): scaling and squaring.
fn expm_unchecked(a: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let nrm = norm1(a);
    let low: [&[f64]; 4] = [&B3, &B5, &B7, &B9];
    for (i, b) in low.iter().enumerate() {
        if nrm <= THETA[i] {
            return pade_low(a, b);
        }
    }
    // ‖A‖₁ ≤ n·MAX_ENTRY is finite (checked by the callers), so s < 350 + log₂ n.
    let s = if nrm > THETA[4] {
        (nrm / THETA[4]).log2().ceil().max(0.0) as i32
    } else {
        0
    };
    let scaled = a * 2f64.powi(-s);
    let mut x = pade13(&scaled)?;
    for _ in 0..s {
        x = &x * &x;
    }
    Ok(x)
}

/// Matrix exponential e^A (Higham 2005, Algorithm 2.3: scaling and squaring with Padé
/// approximants of degree 3, 5, 7, 9 or 13, chosen from the 1-norm).
///
/// # Errors
/// [`LtiError::Dimension`] if `a` is not square, [`LtiError::NonFinite`] on NaN/∞ entries,
/// [`LtiError::TooLarge`] on entries above [`MAX_ENTRY`](crate::MAX_ENTRY) (which keeps
/// the number of squarings bounded), [`LtiError::Overflow`] if e^A itself exceeds the f64
/// range (a mode with Re λ > ln(f64::MAX) ≈ 709.78, or transient growth of a non-normal
/// A), [`LtiError::Singular`] if the Padé denominator is singular (cannot happen for
/// finite input within the θ_m bounds, but is reported rather than panicking).
pub fn expm(a: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    check::square("A", a)?;
    check::bounded("A", a)?;
    if a.nrows() == 0 {
        return Ok(DMatrix::zeros(0, 0));
    }
    let e = expm_unchecked(a)?;
    if e.iter().all(|v| v.is_finite()) {
        return Ok(e);
    }
    let detail = match abscissa(a) {
        Some(x) if x > LN_MAX => format!(
            "A has an eigenvalue with real part {x:.6e} > ln(f64::MAX) = {LN_MAX:.2}, so \
             e^A exceeds the f64 range"
        ),
        _ => format!(
            "e^A exceeds the f64 range through transient growth of the non-normal A \
             (‖A‖₁ = {:.3e})",
            norm1(a)
        ),
    };
    Err(LtiError::Overflow {
        what: "e^A",
        detail,
    })
}

/// Zero-order-hold discretization of ẋ = A x + B u with sample time `ts_s` (seconds):
/// Φ = e^{A Ts}, Γ = ∫₀^Ts e^{Aτ} dτ B, both read off the exponential of the augmented
/// matrix [[A, B], [0, 0]]·Ts (Van Loan 1978; exponential by [`expm`]). This is the
/// discretization of thesis §14.1, eq. (14.6).
///
/// Returns `(Phi, Gamma)`, both finite.
///
/// # Errors
/// Dimension mismatch; non-finite entries; entries above
/// [`MAX_ENTRY`](crate::MAX_ENTRY) in A, B, A·Ts or B·Ts; `ts_s` not finite and positive;
/// [`LtiError::Parameter`] naming Ts with its usable range when e^{A Ts} or Γ overflows
/// f64 (Ts·max Re λ(A) must stay below ln(f64::MAX) ≈ 709.78).
pub fn c2d(a: &DMatrix<f64>, b: &DMatrix<f64>, ts_s: f64) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let n = check::square("A", a)?;
    if b.nrows() != n {
        return Err(LtiError::Dimension {
            what: "B",
            rows: b.nrows(),
            cols: b.ncols(),
            expected: format!("{n}xm (rows of A)"),
        });
    }
    check::bounded("A", a)?;
    check::bounded("B", b)?;
    check::positive("sample time Ts", ts_s)?;
    let amax = a.amax().max(b.amax());
    if ts_s * amax > check::MAX_ENTRY {
        return Err(LtiError::Parameter {
            what: "sample time Ts",
            value: ts_s,
            allowed: format!(
                "finite, > 0 and at most {:.3e} s here (Ts·max(|A|, |B|) must stay below {:.0e})",
                check::MAX_ENTRY / amax,
                check::MAX_ENTRY
            ),
        });
    }
    let m = b.ncols();
    let mut aug = DMatrix::<f64>::zeros(n + m, n + m);
    aug.view_mut((0, 0), (n, n)).copy_from(&(a * ts_s));
    aug.view_mut((0, n), (n, m)).copy_from(&(b * ts_s));
    let e = if n + m == 0 {
        aug
    } else {
        expm_unchecked(&aug)?
    };
    if !e.iter().all(|v| v.is_finite()) {
        let allowed = match abscissa(a) {
            Some(x) if x > 0.0 => format!(
                "finite, > 0 and below about {:.3e} s here: A has a mode with real part \
                 {x:.3e} 1/s and e^(A·Ts) overflows f64 once Ts·Re λ > ln(f64::MAX) = {LN_MAX:.2}",
                LN_MAX / x
            ),
            _ => "finite, > 0 and smaller: e^(A·Ts) or its integral times B overflows f64 \
                  (transient growth of a non-normal A, or a large B)"
                .to_string(),
        };
        return Err(LtiError::Parameter {
            what: "sample time Ts",
            value: ts_s,
            allowed,
        });
    }
    let phi = e.view((0, 0), (n, n)).into_owned();
    let gamma = e.view((0, n), (n, m)).into_owned();
    Ok((phi, gamma))
}

/// Fixed-size convenience for [`c2d`]: the same ZOH discretization for `SMatrix` arguments
/// (converted through `DMatrix`; design-time code, not a hot path).
///
/// # Errors
/// As [`c2d`].
pub fn c2d_fixed<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    ts_s: f64,
) -> Result<(SMatrix<f64, N, N>, SMatrix<f64, N, M>)> {
    let ad = DMatrix::from_column_slice(N, N, a.as_slice());
    let bd = DMatrix::from_column_slice(N, M, b.as_slice());
    let (phi, gamma) = c2d(&ad, &bd, ts_s)?;
    Ok((
        SMatrix::from_column_slice(phi.as_slice()),
        SMatrix::from_column_slice(gamma.as_slice()),
    ))
}
