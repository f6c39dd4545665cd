//! Input validation helpers shared by the algorithms.

use nalgebra::DMatrix;

use crate::error::{LtiError, Result};

/// Fails with [`LtiError::NonFinite`] on the first NaN or infinite entry.
pub fn finite(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if !m[(i, j)].is_finite() {
                return Err(LtiError::NonFinite {
                    what,
                    row: i,
                    col: j,
                });
            }
        }
    }
    Ok(())
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

/// Fails unless `m` is symmetric to [`SYMMETRY_TOL`] relative (Frobenius norm).
pub fn symmetric(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    let norm = m.norm();
    if norm == 0.0 {
        return Ok(());
    }
    let asym = (m - m.transpose()).norm() / norm;
    if asym > SYMMETRY_TOL {
        return Err(LtiError::NotSymmetric {
            what,
            asymmetry: asym,
        });
    }
    Ok(())
}

/// Smallest eigenvalue of the symmetric part of `m`.
pub fn min_sym_eigenvalue(what: &'static str, m: &DMatrix<f64>) -> Result<f64> {
    if m.nrows() == 0 {
        return Ok(0.0);
    }
    let s = (m + m.transpose()) * 0.5;
    let eig = nalgebra::SymmetricEigen::try_new(s, f64::EPSILON, 10_000)
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
    let lmin = min_sym_eigenvalue(what, m)?;
    let scale = m.norm().max(f64::MIN_POSITIVE);
    let tol = (m.nrows().max(1) as f64) * 1e3 * f64::EPSILON * scale;
    if lmin < -tol {
        return Err(LtiError::NotPositiveSemidefinite {
            what,
            min_eigenvalue: lmin,
        });
    }
    Ok(())
}

/// Fails unless `m` is symmetric positive definite (Cholesky succeeds and the smallest
/// eigenvalue exceeds n·ε·‖m‖, so the factorization is meaningful).
pub fn pd(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    symmetric(what, m)?;
    let lmin = min_sym_eigenvalue(what, m)?;
    let scale = m.norm();
    let floor = (m.nrows().max(1) as f64) * f64::EPSILON * scale;
    // NaN-safe: a NaN eigenvalue also fails.
    if lmin.partial_cmp(&floor) != Some(std::cmp::Ordering::Greater) {
        return Err(LtiError::NotPositiveDefinite {
            what,
            min_eigenvalue: lmin,
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
