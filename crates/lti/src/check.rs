//! Input validation and output checks shared by the algorithms.

use nalgebra::DMatrix;

use crate::error::{LtiError, Result};

/// Largest entry magnitude accepted by the design algorithms ([`expm`](crate::expm()),
/// [`c2d`](crate::c2d), [`dare`](crate::dare), the LQR and Kalman designs).
///
/// Why 1e100: these algorithms multiply up to three data matrices before anything can be
/// judged (AᵀQA and B R⁻¹ BᵀQ in the first doubling step of the DARE, AᵀXB in its residual,
/// G Qn Gᵀ for the Kalman filter), and an entry of such a triple product of n×n matrices is
/// bounded by n²·max|entry|³. With 1e100 that is at most 1e308 < f64::MAX ≈ 1.8e308 for
/// n ≤ 10⁴. For the matrix exponential the bound keeps ‖A‖₁ ≤ n·1e100 finite, so the number
/// of squarings ⌈log₂(‖A‖₁/θ₁₃)⌉ stays below 350 (a non-finite norm would ask for 2³¹
/// squarings). Physical models in SI units are many orders of magnitude inside the bound;
/// data beyond it is reported as [`LtiError::TooLarge`] instead of overflowing into NaN.
/// The analysis functions (eigenvalues, PBH, staircase) work on any finite matrix: they
/// rescale by a power of two first.
pub const MAX_ENTRY: f64 = 1e100;

/// Position of the first entry of `m` (column-major) failing `ok`, if any.
fn first_bad(m: &DMatrix<f64>, ok: impl Fn(f64) -> bool) -> Option<(usize, usize)> {
    let rows = m.nrows().max(1);
    m.as_slice()
        .iter()
        .position(|&v| !ok(v))
        .map(|k| (k % rows, k / rows))
}

/// Fails with [`LtiError::NonFinite`] on the first NaN or infinite entry.
pub fn finite(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    match first_bad(m, f64::is_finite) {
        Some((row, col)) => Err(LtiError::NonFinite { what, row, col }),
        None => Ok(()),
    }
}

/// Fails with [`LtiError::NonFinite`] on NaN/∞ and with [`LtiError::TooLarge`] on an entry
/// larger in magnitude than [`MAX_ENTRY`].
pub fn bounded(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    finite(what, m)?;
    match first_bad(m, |v| v.abs() <= MAX_ENTRY) {
        Some((row, col)) => Err(LtiError::TooLarge {
            what,
            row,
            col,
            value: m[(row, col)].abs(),
            max: MAX_ENTRY,
        }),
        None => Ok(()),
    }
}

/// The detail text of [`LtiError::Overflow`] for a computed matrix.
pub const OVERFLOW_HINT: &str = "the problem is too badly scaled or too ill-conditioned for \
     f64; rescale states and inputs so the matrices have entries nearer 1";

/// Fails with [`LtiError::Overflow`] if a computed matrix has a NaN or infinite entry.
pub fn output(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    match first_bad(m, f64::is_finite) {
        Some((row, col)) => Err(LtiError::Overflow {
            what,
            detail: format!("entry ({row}, {col}) is {}; {OVERFLOW_HINT}", m[(row, col)]),
        }),
        None => Ok(()),
    }
}

/// Fails with [`LtiError::Overflow`] if a computed scalar is NaN or infinite.
pub fn output_scalar(what: &'static str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(LtiError::Overflow {
            what,
            detail: format!("value {v}; {OVERFLOW_HINT}"),
        })
    }
}

/// Fails with [`LtiError::Parameter`] unless `v` is finite and > 0.
pub fn positive(what: &'static str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(LtiError::Parameter {
            what,
            value: v,
            allowed: "finite and > 0".to_string(),
        })
    }
}

/// Power of two 2⁻ᵏ that brings a positive magnitude `x` into [0.5, 1), with k clamped to
/// [−1022, 1022] so the factor itself is a finite normal number (x·2⁻ᵏ then lies in
/// [0.5, 4) near f64::MAX and below 1 near the subnormal range). Multiplying by it is exact
/// (barring subnormal results), so scaled computations give the same digits as unscaled
/// ones wherever the latter do not overflow. Returns 1 for 0 or non-finite `x`.
pub fn pow2_scale(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let k = (x.log2().floor() as i32 + 1).clamp(-1022, 1022);
    // 2^(−k) built from its bit pattern: exponent field −k + 1023 ∈ [1, 2045], mantissa 0.
    f64::from_bits(((1023 - k) as u64) << 52)
}

/// Frobenius norm without overflow or underflow for any finite entries. Fast path: the
/// plain √(Σ m_ij²) (`m.norm()`, identical digits, one pass) whenever the sum of squares
/// is finite and ≥ 1e-200 (then squares that flush to zero are below n·1e-108 of it).
/// Otherwise it is recomputed relative to the largest magnitude. No allocation.
pub fn fro(m: &DMatrix<f64>) -> f64 {
    let s = m.norm_squared();
    if s.is_finite() && s >= 1e-200 {
        return s.sqrt();
    }
    let amax = m.amax();
    if amax == 0.0 || !amax.is_finite() {
        return if amax == 0.0 { 0.0 } else { f64::INFINITY };
    }
    let s: f64 = m.iter().map(|v| (v / amax) * (v / amax)).sum();
    s.sqrt() * amax
}

/// Fails with [`LtiError::Dimension`] unless `m` is `rows`×`cols`.
pub fn shape(what: &'static str, m: &DMatrix<f64>, rows: usize, cols: usize) -> Result<()> {
    if m.nrows() != rows || m.ncols() != cols {
        return Err(LtiError::Dimension {
            what,
            rows: m.nrows(),
            cols: m.ncols(),
            expected: format!("{rows}x{cols}"),
        });
    }
    Ok(())
}

/// Fails unless `m` is square.
pub fn square(what: &'static str, m: &DMatrix<f64>) -> Result<usize> {
    if m.nrows() != m.ncols() {
        return Err(LtiError::Dimension {
            what,
            rows: m.nrows(),
            cols: m.ncols(),
            expected: "square".to_string(),
        });
    }
    Ok(m.nrows())
}

/// Relative symmetry tolerance: weights typed in by hand or computed as HᵀQH are symmetric
/// to rounding (≈ 1e-16 relative); 1e-10 accepts those and rejects genuine asymmetry.
pub const SYMMETRY_TOL: f64 = 1e-10;

/// `m` scaled by [`pow2_scale`] of its largest magnitude, and the factor used.
fn normalized(m: &DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let f = pow2_scale(m.amax());
    (m * f, f)
}

/// Fails unless `m` is symmetric to [`SYMMETRY_TOL`] relative (Frobenius norm). Computed on
/// a power-of-two rescaled copy, so huge entries cannot overflow the norms into NaN.
pub fn symmetric(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    let (s, _) = normalized(m);
    let norm = s.norm();
    if norm == 0.0 {
        return Ok(());
    }
    let asym = (&s - s.transpose()).norm() / norm;
    // NaN-safe: anything but a small finite asymmetry fails.
    if asym.is_nan() || asym > SYMMETRY_TOL {
        return Err(LtiError::NotSymmetric {
            what,
            asymmetry: asym,
        });
    }
    Ok(())
}

/// Smallest eigenvalue of the symmetric part of the (already normalized) `s`.
fn min_sym_eigenvalue_of(what: &'static str, s: &DMatrix<f64>) -> Result<f64> {
    if s.nrows() == 0 {
        return Ok(0.0);
    }
    let sym = (s + s.transpose()) * 0.5;
    let eig = nalgebra::SymmetricEigen::try_new(sym, f64::EPSILON, 10_000)
        .ok_or(LtiError::Decomposition { what })?;
    Ok(eig
        .eigenvalues
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min))
}

/// Fails unless `m` is symmetric positive semidefinite. A smallest eigenvalue down to
/// −n·1e3·ε·‖m‖₂ is accepted as rounding of a semidefinite matrix (e.g. Q = CᵀC).
pub fn psd(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    symmetric(what, m)?;
    let (s, f) = normalized(m);
    let lmin = min_sym_eigenvalue_of(what, &s)?;
    let scale = s.norm().max(f64::MIN_POSITIVE);
    let tol = (s.nrows().max(1) as f64) * 1e3 * f64::EPSILON * scale;
    // NaN-safe: a NaN eigenvalue also fails.
    if lmin.is_nan() || lmin < -tol {
        return Err(LtiError::NotPositiveSemidefinite {
            what,
            min_eigenvalue: lmin / f,
        });
    }
    Ok(())
}

/// Fails unless `m` is symmetric positive definite (Cholesky succeeds and the smallest
/// eigenvalue exceeds n·ε·‖m‖, so the factorization is meaningful).
pub fn pd(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    symmetric(what, m)?;
    let (s, f) = normalized(m);
    let lmin = min_sym_eigenvalue_of(what, &s)?;
    let scale = s.norm();
    let floor = (s.nrows().max(1) as f64) * f64::EPSILON * scale;
    // NaN-safe: a NaN eigenvalue also fails.
    if lmin.partial_cmp(&floor) != Some(std::cmp::Ordering::Greater) {
        return Err(LtiError::NotPositiveDefinite {
            what,
            min_eigenvalue: lmin / f,
        });
    }
    Ok(())
}

/// Symmetrizes in place: M ← (M + Mᵀ)/2.
pub fn symmetrize(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for j in 0..n {
        for i in (j + 1)..n {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pow2_scale_is_a_power_of_two_into_half_one() {
        for &x in &[
            1e-310,
            5e-324,
            1e-300,
            0.3,
            1.0,
            2.0,
            1e100,
            1e308,
            f64::MAX,
        ] {
            let f = pow2_scale(x);
            assert!(f.is_finite() && f > 0.0, "{x}");
            assert_eq!(f.log2().fract(), 0.0, "{x}");
            let y = x * f;
            assert!(y < 4.0, "{x} -> {y}");
            if (1e-300..1e300).contains(&x) {
                assert!((0.5..1.0).contains(&y), "{x} -> {y}");
            }
        }
        assert_eq!(pow2_scale(0.0), 1.0);
        let m = DMatrix::from_row_slice(1, 2, &[3e300, 4e300]);
        assert!((fro(&m) / 5e300 - 1.0).abs() < 1e-15);
        let m = DMatrix::from_row_slice(1, 2, &[3e-300, 4e-300]);
        assert!((fro(&m) / 5e-300 - 1.0).abs() < 1e-15);
        assert_eq!(pow2_scale(f64::NAN), 1.0);
    }

    #[test]
    fn checks_survive_huge_entries() {
        // ‖m‖_F of 1e308 entries overflows a naive norm; the rescaled checks do not.
        let sym = DMatrix::from_row_slice(2, 2, &[1e308, 1e307, 1e307, 1e308]);
        assert!(symmetric("M", &sym).is_ok());
        assert!(psd("M", &sym).is_ok());
        assert!(pd("M", &sym).is_ok());
        let asym = DMatrix::from_row_slice(2, 2, &[1e308, -1e308, 1e308, 1e308]);
        assert!(matches!(
            symmetric("M", &asym),
            Err(LtiError::NotSymmetric { .. })
        ));
        let neg = DMatrix::from_row_slice(2, 2, &[-1e308, 0.0, 0.0, 1e308]);
        assert!(matches!(
            psd("M", &neg),
            Err(LtiError::NotPositiveSemidefinite { .. })
        ));
        assert!(matches!(
            bounded("M", &neg),
            Err(LtiError::TooLarge {
                what: "M",
                row: 0,
                col: 0,
                ..
            })
        ));
    }
}
