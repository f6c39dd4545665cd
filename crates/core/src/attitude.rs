//! Attitude determination by Davenport's q-method, thesis §13.2 (13.1)–(13.14).
//!
//! # Quaternion convention
//!
//! Every quaternion in this module is a **Hamilton** quaternion, **scalar first**
//! `(w, x, y, z)`, representing the rotation **`body_from_ned`**: the active
//! rotation matrix of `q` is `R_be`, so `v_body = R(q) · v_ned`. It is stored as
//! an `nalgebra::UnitQuaternion`, whose `Quaternion::new(w, x, y, z)` constructor
//! is scalar-first and Hamilton. The sign of `q` is fixed by `w ≥ 0`.
//!
//! The thesis (following Hall 2003 / Shuster) writes the K matrix (13.8) for the
//! vector-first quaternion of the *passive* attitude matrix `A(q̄) = R_be`.
//! That quaternion has the same components as the Hamilton quaternion of
//! `R_eb = ned_from_body`, so the Hamilton `body_from_ned` quaternion returned
//! here is its conjugate: `q = (q̄₄, −q̄₁, −q̄₂, −q̄₃)`.
//!
//! # Observations
//!
//! Vector observations are pairs (body-frame measurement `b_k`, NED reference
//! `r_k`) with a non-negative weight `w_k`; both vectors are normalised to unit
//! length before use, as Wahba's problem (13.4) is stated for unit vectors.
//! The two observations of the thesis (13.2) are gravity (accelerometer minus the
//! helicopter's own acceleration, see [`gravity_observation`]) and the
//! magnetometer against the local field (13.14), see [`THESIS_MAG_FIELD_NED`].
//!
//! # Degenerate geometry
//!
//! The attitude is unique only if the largest eigenvalue of K is simple. A zero
//! or non-finite vector, a negative or non-finite weight, all weights zero, or
//! observations that are all parallel (gap between the two largest eigenvalues
//! below [`MIN_RELATIVE_EIGEN_GAP`] of the weight sum) give an
//! [`AttitudeError`], never NaN.

use nalgebra::{Matrix3, Matrix4, Quaternion, UnitQuaternion, Vector3, Vector4};

/// Local gravity in NED used by the thesis, (13.13): `[0, 0, 9.82]` m/s².
pub const THESIS_GRAVITY_NED_M_S2: [f64; 3] = [0.0, 0.0, 9.82];

/// Local magnetic field in NED measured by the thesis when headed north,
/// (13.14): `[0.153, 0.008, −0.438]` (sensor units, gauss). Only its direction
/// matters to the q-method. The negative down component is as printed (the
/// true field at Aalborg points down; the sign is the sensor's convention).
pub const THESIS_MAG_FIELD_NED: [f64; 3] = [0.153, 0.008, -0.438];

/// Smallest accepted gap between the two largest eigenvalues of K, relative to
/// the sum of the weights. Below it the attitude is not unique (parallel
/// observations) or is so ill-conditioned that noise of 1e-9 rad would move it.
pub const MIN_RELATIVE_EIGEN_GAP: f64 = 1e-9;

/// Error of the attitude determination.
#[derive(Debug, Clone, PartialEq)]
pub enum AttitudeError {
    /// Fewer than one observation was given.
    NoObservations,
    /// A vector or weight is NaN or infinite.
    NonFinite {
        /// Index of the offending observation (0-based).
        index: usize,
    },
    /// A body or reference vector has zero length.
    ZeroVector {
        /// Index of the offending observation (0-based).
        index: usize,
    },
    /// A weight is negative.
    NegativeWeight {
        /// Index of the offending observation (0-based).
        index: usize,
        /// The weight given.
        weight: f64,
    },
    /// All weights are zero.
    ZeroWeights,
    /// The observations do not determine the attitude (parallel vectors).
    Degenerate {
        /// `(λ₁ − λ₂) / Σ w_k`.
        relative_gap: f64,
    },
    /// The symmetric eigen-solver did not converge.
    EigenFailure,
}

impl std::fmt::Display for AttitudeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AttitudeError::NoObservations => write!(f, "no vector observations given"),
            AttitudeError::NonFinite { index } => {
                write!(f, "observation {index}: non-finite value")
            }
            AttitudeError::ZeroVector { index } => {
                write!(f, "observation {index}: zero-length vector")
            }
            AttitudeError::NegativeWeight { index, weight } => {
                write!(f, "observation {index}: negative weight {weight}")
            }
            AttitudeError::ZeroWeights => write!(f, "all observation weights are zero"),
            AttitudeError::Degenerate { relative_gap } => write!(
                f,
                "degenerate geometry: eigenvalue gap {relative_gap:e} (relative) below \
                 {MIN_RELATIVE_EIGEN_GAP:e}; observations are (nearly) parallel"
            ),
            AttitudeError::EigenFailure => write!(f, "eigen-solver did not converge"),
        }
    }
}

impl std::error::Error for AttitudeError {}

/// One weighted vector observation for Wahba's problem (13.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VectorObservation {
    /// Weight `w_k ≥ 0` (for the optimal estimate, `1/σ_k²`).
    pub weight: f64,
    /// Measured direction in body axes, `ᵇv_k` (any non-zero length).
    pub body: Vector3<f64>,
    /// Reference direction in NED, `ᵉv_k` (any non-zero length).
    pub reference_ned: Vector3<f64>,
}

impl VectorObservation {
    /// A new observation.
    pub fn new(weight: f64, body: Vector3<f64>, reference_ned: Vector3<f64>) -> Self {
        Self {
            weight,
            body,
            reference_ned,
        }
    }
}

/// Result of the q-method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudeSolution {
    /// Optimal attitude, Hamilton scalar-first `body_from_ned` with `w ≥ 0`.
    pub body_from_ned: UnitQuaternion<f64>,
    /// Wahba loss (13.4) at the optimum, `J = Σ w_k − λ_max` (unit vectors).
    pub loss: f64,
    /// Largest eigenvalue of K (13.7), the optimal gain (13.6).
    pub lambda_max: f64,
    /// Second largest eigenvalue of K (its gap to `lambda_max` measures how
    /// well the attitude is determined).
    pub lambda_second: f64,
}

impl AttitudeSolution {
    /// 3-2-1 Euler angles `(φ, θ, ψ)` in rad of the solution, thesis (9.5).
    pub fn euler(&self) -> Vector3<f64> {
        euler_from_quaternion(&self.body_from_ned)
    }
}

/// Solve Wahba's problem (13.4) by Davenport's q-method, (13.7)–(13.12).
///
/// `B = Σ w_k ᵇv̂_k ᵉv̂_kᵀ` (13.9), `S = B + Bᵀ` (13.10),
/// `Z = [B₂₃−B₃₂, B₃₁−B₁₃, B₁₂−B₂₁]ᵀ` (13.11), `σ = tr B` (13.12),
/// `K = [[S − σI, Z], [Zᵀ, σ]]` (13.8); the optimal quaternion is the
/// eigenvector of the largest eigenvalue (13.7). Fixed-size, no allocation.
pub fn q_method(observations: &[VectorObservation]) -> Result<AttitudeSolution, AttitudeError> {
    if observations.is_empty() {
        return Err(AttitudeError::NoObservations);
    }
    let mut b = Matrix3::<f64>::zeros();
    let mut weight_sum = 0.0;
    for (index, obs) in observations.iter().enumerate() {
        if !obs.weight.is_finite()
            || !obs.body.iter().all(|v| v.is_finite())
            || !obs.reference_ned.iter().all(|v| v.is_finite())
        {
            return Err(AttitudeError::NonFinite { index });
        }
        if obs.weight < 0.0 {
            return Err(AttitudeError::NegativeWeight {
                index,
                weight: obs.weight,
            });
        }
        let nb = obs.body.norm();
        let nr = obs.reference_ned.norm();
        if !(nb > 0.0 && nr > 0.0 && nb.is_finite() && nr.is_finite()) {
            return Err(AttitudeError::ZeroVector { index });
        }
        // (13.9)
        b += (obs.body / nb) * (obs.reference_ned / nr).transpose() * obs.weight;
        weight_sum += obs.weight;
    }
    if weight_sum <= 0.0 {
        return Err(AttitudeError::ZeroWeights);
    }
    let k = davenport_k(&b);
    let (lambda_max, lambda_second) = k_eigenvalues(&b, weight_sum, &k);
    let relative_gap = (lambda_max - lambda_second) / weight_sum;
    if !relative_gap.is_finite() || relative_gap < MIN_RELATIVE_EIGEN_GAP {
        return Err(AttitudeError::Degenerate { relative_gap });
    }
    // Eigenvector from the adjugate, then one Rayleigh-quotient refinement of
    // λ_max (error O(|δv|²)) and a second adjugate: removes the round-off of
    // the polynomial root from the attitude (worst noise-free error ~2e-13 rad).
    let v0 = dominant_adjugate_column(&(k - Matrix4::identity() * lambda_max));
    let lambda_ref = v0.dot(&(k * v0)) / v0.dot(&v0);
    let lambda_use = if lambda_ref.is_finite() {
        lambda_ref
    } else {
        lambda_max
    };
    let v = dominant_adjugate_column(&(k - Matrix4::identity() * lambda_use));
    // Shuster vector-first q̄ = (v0, v1, v2, v3) of A = R_be; Hamilton
    // body_from_ned is its conjugate (see module docs).
    let mut q = Quaternion::new(v[3], -v[0], -v[1], -v[2]);
    if q.w < 0.0 {
        q = -q;
    }
    let norm = q.norm();
    if norm.is_nan() || norm <= 0.0 || norm.is_infinite() {
        return Err(AttitudeError::EigenFailure);
    }
    let body_from_ned = UnitQuaternion::new_unchecked(q / norm);
    Ok(AttitudeSolution {
        body_from_ned,
        loss: (weight_sum - lambda_use).max(0.0),
        lambda_max: lambda_use,
        lambda_second,
    })
}

/// Largest and second largest eigenvalue of K (13.8).
///
/// Primary path: Newton's method on the characteristic polynomial of K in
/// Shuster's closed form (QUEST, Shuster & Oh 1981),
/// `f(λ) = λ⁴ − (a+b)λ² − cλ + (ab + cσ − d)` with `a = σ² − tr adj S`,
/// `b = σ² + ZᵀZ`, `c = det S + ZᵀSZ`, `d = ZᵀS²Z`, started at `Σ w_k ≥ λ_max`
/// (monotone convergence from above), then the deflated cubic
/// `f(λ)/(λ − λ_max)` solved in closed (trigonometric) form for `λ₂`. This
/// solves the same eigenproblem (13.7) exactly, ~5× faster than a general
/// symmetric QR. If Newton does not converge in 50 iterations (near-degenerate
/// spectra), nalgebra's fixed-size symmetric eigenvalue solver is used.
fn k_eigenvalues(b: &Matrix3<f64>, weight_sum: f64, k: &Matrix4<f64>) -> (f64, f64) {
    let s = b + b.transpose();
    let sigma = b.trace();
    let z = Vector3::new(
        b[(1, 2)] - b[(2, 1)],
        b[(2, 0)] - b[(0, 2)],
        b[(0, 1)] - b[(1, 0)],
    );
    // tr adj S = sum of principal 2×2 minors.
    let kappa = s[(1, 1)] * s[(2, 2)] - s[(1, 2)] * s[(2, 1)] + s[(0, 0)] * s[(2, 2)]
        - s[(0, 2)] * s[(2, 0)]
        + s[(0, 0)] * s[(1, 1)]
        - s[(0, 1)] * s[(1, 0)];
    let sz = s * z;
    let a = sigma * sigma - kappa;
    let bb = sigma * sigma + z.dot(&z);
    let c = s.determinant() + z.dot(&sz);
    let d = sz.dot(&sz);
    let e = a * bb + c * sigma - d;
    let p2 = a + bb;
    let mut lam = weight_sum;
    let mut converged = false;
    for _ in 0..50 {
        let f = ((lam * lam - p2) * lam - c) * lam + e;
        let df = (4.0 * lam * lam - 2.0 * p2) * lam - c;
        if df == 0.0 || !df.is_finite() {
            break;
        }
        let step = f / df;
        lam -= step;
        if step.abs() <= 4.0 * f64::EPSILON * weight_sum {
            converged = true;
            break;
        }
    }
    if converged {
        // Deflate: f(λ) = (λ − λ₁)(λ³ + λ₁λ² + (λ₁² − p2)λ + (λ₁³ − p2 λ₁ − c)).
        let (c2, c1, c0) = (lam, lam * lam - p2, lam * lam * lam - p2 * lam - c);
        // Depressed cubic t³ + pt + q with λ = t − c2/3; three real roots.
        let shift = c2 / 3.0;
        let p = c1 - c2 * c2 / 3.0;
        let q = 2.0 * c2 * c2 * c2 / 27.0 - c2 * c1 / 3.0 + c0;
        let lam2 = if p < 0.0 {
            let m = 2.0 * (-p / 3.0).sqrt();
            let arg = (3.0 * q / (p * m)).clamp(-1.0, 1.0);
            m * (arg.acos() / 3.0).cos() - shift
        } else {
            // p ≥ 0 with three real roots means a triple root at t = 0.
            -shift
        };
        if lam2.is_finite() && lam2 <= lam + 1e-12 * weight_sum {
            return (lam, lam2);
        }
    }
    let vals = k.symmetric_eigenvalues();
    let mut i_max = 0;
    for i in 1..4 {
        if vals[i] > vals[i_max] {
            i_max = i;
        }
    }
    let mut second = f64::NEG_INFINITY;
    for i in 0..4 {
        if i != i_max && vals[i] > second {
            second = vals[i];
        }
    }
    (vals[i_max], second)
}

/// The column of `adj(M)` with the largest diagonal entry, for a symmetric
/// 4×4 `M` of rank 3 (then `adj(M) = c·v vᵀ` with `M v = 0`).
fn dominant_adjugate_column(m: &Matrix4<f64>) -> Vector4<f64> {
    // 2×2 minors of rows 2,3 and rows 0,1 (Laplace expansion helpers).
    let det3 = |r: [usize; 3], c: [usize; 3]| -> f64 {
        m[(r[0], c[0])] * (m[(r[1], c[1])] * m[(r[2], c[2])] - m[(r[1], c[2])] * m[(r[2], c[1])])
            - m[(r[0], c[1])]
                * (m[(r[1], c[0])] * m[(r[2], c[2])] - m[(r[1], c[2])] * m[(r[2], c[0])])
            + m[(r[0], c[2])]
                * (m[(r[1], c[0])] * m[(r[2], c[1])] - m[(r[1], c[1])] * m[(r[2], c[0])])
    };
    const OTHERS: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];
    // Diagonal cofactors adj_jj = det(minor_jj) = c·v_j²: pick the largest.
    let mut j = 0;
    let mut best = f64::NEG_INFINITY;
    for d in 0..4 {
        let c = det3(OTHERS[d], OTHERS[d]).abs();
        if c > best {
            best = c;
            j = d;
        }
    }
    // Column j of adj(M): adj_ij = (−1)^{i+j} det(M without row j, column i).
    let mut v = Vector4::zeros();
    for i in 0..4 {
        let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
        v[i] = sign * det3(OTHERS[j], OTHERS[i]);
    }
    v
}

/// Davenport's K matrix (13.8) from the attitude profile matrix B (13.9),
/// with (13.10)–(13.12).
pub fn davenport_k(b: &Matrix3<f64>) -> Matrix4<f64> {
    let s = b + b.transpose(); // (13.10)
    let z = Vector3::new(
        b[(1, 2)] - b[(2, 1)],
        b[(2, 0)] - b[(0, 2)],
        b[(0, 1)] - b[(1, 0)],
    ); // (13.11)
    let sigma = b.trace(); // (13.12)
    let mut k = Matrix4::zeros();
    k.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(s - Matrix3::identity() * sigma));
    k.fixed_view_mut::<3, 1>(0, 3).copy_from(&z);
    k.fixed_view_mut::<1, 3>(3, 0).copy_from(&z.transpose());
    k[(3, 3)] = sigma;
    k
}

/// Wahba loss (13.4) of an attitude for the given observations (vectors
/// normalised as in [`q_method`]); useful to check an attitude from elsewhere.
pub fn wahba_loss(body_from_ned: &UnitQuaternion<f64>, observations: &[VectorObservation]) -> f64 {
    let r = body_from_ned.to_rotation_matrix();
    observations
        .iter()
        .map(|o| {
            let d = o.body.normalize() - r * o.reference_ned.normalize();
            0.5 * o.weight * d.norm_squared()
        })
        .sum()
}

/// 3-2-1 Euler angles `(φ, θ, ψ)` (rad) of a Hamilton `body_from_ned`
/// quaternion, thesis (9.5): `R_eb = R(q)ᵀ`, `θ = −asin R_eb[3,1]`,
/// `φ = atan2(R_eb[3,2], R_eb[3,3])`, `ψ = atan2(R_eb[2,1], R_eb[1,1])`
/// (1-based indices); `ψ, φ ∈ (−π, π]`, `θ ∈ [−π/2, π/2]`.
pub fn euler_from_quaternion(body_from_ned: &UnitQuaternion<f64>) -> Vector3<f64> {
    let r_eb = body_from_ned.to_rotation_matrix().into_inner().transpose();
    let theta = (-r_eb[(2, 0)]).clamp(-1.0, 1.0).asin();
    let phi = r_eb[(2, 1)].atan2(r_eb[(2, 2)]);
    let psi = r_eb[(1, 0)].atan2(r_eb[(0, 0)]);
    Vector3::new(phi, theta, psi)
}

/// Hamilton `body_from_ned` quaternion (w ≥ 0) of 3-2-1 Euler angles (rad),
/// thesis (9.5): the inverse of [`euler_from_quaternion`] away from θ = ±π/2.
pub fn quaternion_from_euler(phi: f64, theta: f64, psi: f64) -> UnitQuaternion<f64> {
    // R_eb = Rz(ψ) Ry(θ) Rx(φ) (9.5); R_be is its inverse.
    let q_eb = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), psi)
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), theta)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), phi);
    let q = q_eb.inverse();
    if q.w < 0.0 {
        UnitQuaternion::new_unchecked(-q.into_inner())
    } else {
        q
    }
}

/// The gravity observation of (13.2): the accelerometer measures the specific
/// force `f = a − g` (body axes); the gravity direction in body axes is
/// `g_body = a_body − f`, i.e. the accelerometer reading minus the helicopter's
/// own acceleration (sign as the thesis: "subtracted"). Pass the helicopter's
/// acceleration in body axes (m/s²) if known (from the model or estimator), or
/// `None` to assume it zero (the thesis implementation, valid only when not
/// accelerating). The reference is `[0, 0, g]` NED.
///
/// With `f` the accelerometer reading (which reads `−g` = `[0,0,−9.82]` at
/// rest in FRD), gravity in body axes is `−(f − a)`; the returned observation
/// pairs `−(f − a)` with `+ĝ_ned`.
pub fn gravity_observation(
    weight: f64,
    specific_force_body_m_s2: &Vector3<f64>,
    own_acceleration_body_m_s2: Option<&Vector3<f64>>,
) -> VectorObservation {
    let a = own_acceleration_body_m_s2
        .copied()
        .unwrap_or_else(Vector3::zeros);
    VectorObservation::new(
        weight,
        a - specific_force_body_m_s2,
        Vector3::new(0.0, 0.0, 1.0),
    )
}

/// The magnetometer observation of (13.2): measured field in body axes against
/// the local field in NED (e.g. [`THESIS_MAG_FIELD_NED`], (13.14)).
pub fn magnetometer_observation(
    weight: f64,
    field_body: &Vector3<f64>,
    field_ned: &Vector3<f64>,
) -> VectorObservation {
    VectorObservation::new(weight, *field_body, *field_ned)
}

/// Predicted covariance (rad²) of the small-angle attitude error of the
/// optimal q-method estimate, in body axes, for observations with isotropic
/// direction noise of standard deviation `sigma_k` (rad) per axis
/// (Shuster & Oh 1981, QUEST measurement model):
/// `P = [Σ σ_k⁻² (I − b̂_k b̂_kᵀ)]⁻¹`. The error is defined by
/// `R_est = exp(−[δθ×]) R_true` with `R = body_from_ned`, i.e. `δθ` is the
/// rotation vector of `R_true R_estᵀ`. Returns `None` if singular (parallel
/// observations).
pub fn predicted_attitude_covariance(
    body_unit: &[Vector3<f64>],
    sigma_rad: &[f64],
) -> Option<Matrix3<f64>> {
    let mut info = Matrix3::zeros();
    for (b, s) in body_unit.iter().zip(sigma_rad) {
        let bn = b.normalize();
        info += (Matrix3::identity() - bn * bn.transpose()) / (s * s);
    }
    info.try_inverse()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn euler_roundtrip_and_matches_model_rotation() {
        let (phi, theta, psi) = (0.3, -0.4, 2.1);
        let q = quaternion_from_euler(phi, theta, psi);
        let r_be = crate::frames::body_from_ned(phi, theta, psi);
        assert_relative_eq!(q.to_rotation_matrix().into_inner(), r_be, epsilon = 1e-15);
        let e = euler_from_quaternion(&q);
        assert_relative_eq!(e, Vector3::new(phi, theta, psi), epsilon = 1e-14);
    }

    #[test]
    fn degenerate_inputs_are_typed_errors() {
        let x = Vector3::x();
        let y = Vector3::y();
        assert_eq!(q_method(&[]), Err(AttitudeError::NoObservations));
        assert!(matches!(
            q_method(&[VectorObservation::new(1.0, x, x)]),
            Err(AttitudeError::Degenerate { .. })
        ));
        assert!(matches!(
            q_method(&[
                VectorObservation::new(1.0, x, y),
                VectorObservation::new(2.0, -x, -y)
            ]),
            Err(AttitudeError::Degenerate { .. })
        ));
        assert_eq!(
            q_method(&[
                VectorObservation::new(1.0, Vector3::zeros(), y),
                VectorObservation::new(1.0, x, y)
            ]),
            Err(AttitudeError::ZeroVector { index: 0 })
        );
        assert_eq!(
            q_method(&[
                VectorObservation::new(1.0, x, y),
                VectorObservation::new(1.0, Vector3::new(f64::NAN, 0.0, 0.0), y)
            ]),
            Err(AttitudeError::NonFinite { index: 1 })
        );
        assert!(matches!(
            q_method(&[
                VectorObservation::new(-1.0, x, y),
                VectorObservation::new(1.0, y, x)
            ]),
            Err(AttitudeError::NegativeWeight { index: 0, .. })
        ));
        assert_eq!(
            q_method(&[
                VectorObservation::new(0.0, x, y),
                VectorObservation::new(0.0, y, x)
            ]),
            Err(AttitudeError::ZeroWeights)
        );
        // Huge but finite vectors whose squared norm overflows.
        assert!(
            q_method(&[
                VectorObservation::new(1.0, Vector3::new(1e300, 1e300, 0.0), y),
                VectorObservation::new(1.0, x, x)
            ])
            .is_err()
        );
    }

    #[test]
    fn closed_form_eigenvalues_match_nalgebra_symmetric_eigen() {
        // Deterministic pseudo-random B matrices (LCG), including noisy ones.
        let mut state = 12345u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..500 {
            let b = Matrix3::from_fn(|_, _| rnd());
            let k = davenport_k(&b);
            // Weight sum bound: ‖B‖ nuclear norm ≤ Σ w; use a generous bound.
            let wsum = b.norm() * 3.0;
            let (l1, l2) = k_eigenvalues(&b, wsum, &k);
            let mut v: Vec<f64> = nalgebra::SymmetricEigen::new(k)
                .eigenvalues
                .iter()
                .copied()
                .collect();
            v.sort_by(|x, y| y.total_cmp(x));
            // 1e-12 relative to the scale: both are backward stable.
            assert!((l1 - v[0]).abs() < 1e-12 * wsum, "{l1} vs {}", v[0]);
            assert!((l2 - v[1]).abs() < 1e-9 * wsum, "{l2} vs {}", v[1]);
        }
    }

    #[test]
    fn gravity_observation_at_rest_points_down() {
        // Level, at rest: accelerometer reads −g along body z.
        let f = Vector3::new(0.0, 0.0, -9.82);
        let o = gravity_observation(1.0, &f, None);
        assert_relative_eq!(o.body.normalize(), Vector3::z(), epsilon = 1e-15);
        // Accelerating forward at 2 m/s² level: f = a − g = (2, 0, −9.82).
        let f = Vector3::new(2.0, 0.0, -9.82);
        let a = Vector3::new(2.0, 0.0, 0.0);
        let o = gravity_observation(1.0, &f, Some(&a));
        assert_relative_eq!(o.body.normalize(), Vector3::z(), epsilon = 1e-15);
    }
}
