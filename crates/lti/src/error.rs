//! Typed errors of the `helicon-lti` crate.

use thiserror::Error;

/// Everything that can go wrong in `helicon-lti`.
///
/// Bad input is always reported through this type; the library never panics on it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LtiError {
    /// A matrix has the wrong shape.
    #[error("dimension mismatch: {what} is {rows}x{cols}, expected {expected}")]
    Dimension {
        /// Which argument.
        what: &'static str,
        /// Its number of rows.
        rows: usize,
        /// Its number of columns.
        cols: usize,
        /// A description of the expected shape.
        expected: String,
    },
    /// A matrix contains NaN or an infinity.
    #[error("{what} contains a non-finite entry at 0-based ({row}, {col})")]
    NonFinite {
        /// Which argument.
        what: &'static str,
        /// Row of the first bad entry (0-based).
        row: usize,
        /// Column of the first bad entry (0-based).
        col: usize,
    },
    /// A matrix entry is finite but larger in magnitude than the algorithm can handle
    /// without overflowing f64 (see [`MAX_ENTRY`](crate::MAX_ENTRY) for the bound and why).
    #[error(
        "{what} has an entry of magnitude {value:e} at 0-based ({row}, {col}); entries must be at \
         most {max:.0e} in magnitude (larger ones overflow f64 in the matrix products of the \
         algorithm: rescale states/inputs)"
    )]
    TooLarge {
        /// Which argument.
        what: &'static str,
        /// Row of the first bad entry (0-based).
        row: usize,
        /// Column of the first bad entry (0-based).
        col: usize,
        /// Its magnitude.
        value: f64,
        /// The allowed maximum magnitude.
        max: f64,
    },
    /// A quantity computed from finite, in-range inputs overflowed (or became NaN): the
    /// problem is too badly scaled or too ill-conditioned for f64.
    #[error("{what} is not finite: {detail}")]
    Overflow {
        /// Which computed quantity.
        what: &'static str,
        /// Why, and what to change.
        detail: String,
    },
    /// A matrix that must be symmetric is not (relative tolerance stated in the message).
    #[error("{what} is not symmetric (relative asymmetry {asymmetry:.3e})")]
    NotSymmetric {
        /// Which argument.
        what: &'static str,
        /// ‖M − Mᵀ‖_F / ‖M‖_F.
        asymmetry: f64,
    },
    /// A weight that must be positive semidefinite has a negative eigenvalue.
    #[error("{what} is not positive semidefinite (smallest eigenvalue {min_eigenvalue:.3e})")]
    NotPositiveSemidefinite {
        /// Which argument.
        what: &'static str,
        /// Its smallest eigenvalue.
        min_eigenvalue: f64,
    },
    /// A weight that must be positive definite is not.
    #[error("{what} is not positive definite (smallest eigenvalue {min_eigenvalue:.3e})")]
    NotPositiveDefinite {
        /// Which argument.
        what: &'static str,
        /// Its smallest eigenvalue.
        min_eigenvalue: f64,
    },
    /// A pair is not stabilizable: a mode with |λ| ≥ 1 cannot be reached from the input.
    /// For the DARE the pair is (A, B); for a Kalman filter it is (Φ, G Qn^½), the process
    /// noise not exciting the mode.
    #[error(
        "{pair} is not stabilizable: mode {re:+.6e}{im:+.6e}i (|λ| ≥ 1) is uncontrollable \
         (PBH sigma_min/sigma_max = {ratio:.3e})"
    )]
    NotStabilizable {
        /// Which pair, e.g. "(A, B)".
        pair: &'static str,
        /// Real part of the offending eigenvalue.
        re: f64,
        /// Imaginary part of the offending eigenvalue.
        im: f64,
        /// σ_min/σ_max of [A − λI, B].
        ratio: f64,
    },
    /// A pair is not detectable: a mode with |λ| ≥ 1 is invisible. For the DARE the pair is
    /// (Q, A) (the mode does not appear in the cost); for a Kalman filter it is (A, C) (the
    /// measurements C do not see the mode).
    #[error(
        "{pair} is not detectable: mode {re:+.6e}{im:+.6e}i (|λ| ≥ 1) is unobservable \
         (PBH sigma_min/sigma_max = {ratio:.3e})"
    )]
    NotDetectable {
        /// Which pair, e.g. "(Q, A)" or "(A, C)".
        pair: &'static str,
        /// Real part of the offending eigenvalue.
        re: f64,
        /// Imaginary part of the offending eigenvalue.
        im: f64,
        /// σ_min/σ_max of [A − λI; Q].
        ratio: f64,
    },
    /// An iteration did not converge.
    #[error(
        "{what} did not converge in {iterations} iterations (last relative change {last_change:.3e})"
    )]
    NoConvergence {
        /// Which algorithm.
        what: &'static str,
        /// Iterations used.
        iterations: usize,
        /// Last relative change of the iterate.
        last_change: f64,
    },
    /// The computed Riccati solution does not stabilize the closed loop
    /// (typically an eigenvalue of the symplectic pencil on the unit circle).
    #[error("no stabilizing solution: closed-loop spectral radius {spectral_radius:.12} ≥ 1")]
    NoStabilizingSolution {
        /// Spectral radius of A − BK.
        spectral_radius: f64,
    },
    /// A linear system that had to be solved was singular.
    #[error("singular matrix in {what}")]
    Singular {
        /// Where.
        what: &'static str,
    },
    /// An eigenvalue or singular value decomposition did not converge.
    #[error("{what} decomposition did not converge")]
    Decomposition {
        /// Which decomposition.
        what: &'static str,
    },
    /// A scalar parameter is out of its allowed range.
    #[error("parameter {what} = {} is out of range: {allowed}", short(.value))]
    Parameter {
        /// Which parameter.
        what: &'static str,
        /// The given value.
        value: f64,
        /// The allowed range (may depend on the other arguments, e.g. α·max|Φ| ≤ 1e100).
        allowed: String,
    },
}

impl LtiError {
    /// The argument (matrix or scalar parameter) an input error is about, as named in the
    /// message (e.g. "A", "Qn", "alpha", "sample time Ts"); `None` for errors about the
    /// problem as a whole (structure, convergence, overflow of computed quantities).
    /// Front ends use it to point at the file or option the value came from.
    pub fn argument(&self) -> Option<&'static str> {
        match self {
            Self::Dimension { what, .. }
            | Self::NonFinite { what, .. }
            | Self::TooLarge { what, .. }
            | Self::NotSymmetric { what, .. }
            | Self::NotPositiveSemidefinite { what, .. }
            | Self::NotPositiveDefinite { what, .. }
            | Self::Parameter { what, .. } => Some(what),
            _ => None,
        }
    }
}

/// A number as written by a person: plain for moderate magnitudes, else exponent notation
/// (so 1e300 is not printed as 301 digits).
fn short(v: &f64) -> String {
    if *v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Result alias for this crate.
pub type Result<T> = std::result::Result<T, LtiError>;
