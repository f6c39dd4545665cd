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
    #[error("{what} contains a non-finite entry at ({row}, {col})")]
    NonFinite {
        /// Which argument.
        what: &'static str,
        /// Row of the first bad entry (0-based).
        row: usize,
        /// Column of the first bad entry (0-based).
        col: usize,
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
    /// (A, B) is not stabilizable: a mode with |λ| ≥ 1 cannot be reached from the input.
    #[error(
        "(A, B) is not stabilizable: mode {re:+.6e}{im:+.6e}i is uncontrollable \
         (PBH sigma_min/sigma_max = {ratio:.3e})"
    )]
    NotStabilizable {
        /// Real part of the offending eigenvalue.
        re: f64,
        /// Imaginary part of the offending eigenvalue.
        im: f64,
        /// σ_min/σ_max of [A − λI, B].
        ratio: f64,
    },
    /// (Q, A) is not detectable: a mode with |λ| ≥ 1 is invisible in the cost.
    #[error(
        "(Q, A) is not detectable: mode {re:+.6e}{im:+.6e}i is unobservable in the weight \
         (PBH sigma_min/sigma_max = {ratio:.3e})"
    )]
    NotDetectable {
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
    #[error("parameter {what} = {value} is out of range: {allowed}")]
    Parameter {
        /// Which parameter.
        what: &'static str,
        /// The given value.
        value: f64,
        /// The allowed range.
        allowed: &'static str,
    },
}

/// Result alias for this crate.
pub type Result<T> = std::result::Result<T, LtiError>;
