//! An error-state extended Kalman filter (ESKF) navigation with IMU bias
//! states, and the estimator that flies it ahead of the thesis's Kalman
//! predictor.
//!
//! The thesis estimates the state in three linear stages (q-method attitude,
//! a GPS/IMU fusion filter without bias states, the steady-state predictor,
//! chapters 13 and 15) and names a nonlinear estimator as further work
//! (Appendix F). [`Eskf`] is the navigation a rotorcraft GNC engineer flies
//! today:
//!
//! - **Nominal state:** attitude as a unit quaternion `q` (`ned_from_body`,
//!   no Euler singularity), NED velocity `v` and position `p`, gyro bias
//!   `b_g` and accelerometer bias `b_a` (body axes).
//! - **Error state (15):** `[δθ δv δp δb_g δb_a]`, `δθ` a small rotation in
//!   body axes (`R = R̂ Exp(δθ)`).
//! - **Process model:** the strapdown mechanisation driven by the
//!   bias-corrected IMU, `ω = ω_m − b_g`, `f = f_m − b_a`,
//!   `q ← q ⊗ Exp(ω T)`, `a = R f + [0 0 g]`, `p ← p + v T + a T²/2`,
//!   `v ← v + a T`; biases random walks. The error transition is the
//!   first-order `F = I + A T` of the standard error-state dynamics
//!   (`δθ̇ = −[ω]× δθ − δb_g`, `δv̇ = −R [f]× δθ − R δb_a`, `δṗ = δv`), the
//!   attitude block exact (`Exp(−ω T)`); the process noise is the sensors'
//!   white-noise densities and bias random walks times the sample time.
//! - **Updates:** magnetometer vector (`Rᵀ m_ned`), GPS position and GPS
//!   (Doppler) velocity, each a 3-vector update in Joseph form
//!   `P = (I − KH) P (I − KH)ᵀ + K R Kᵀ`, symmetrised, followed by the
//!   error reset of the attitude block (`G = I − [δθ/2]×`).
//! - **GPS latency:** a fix is compared with the filter's estimate *at the
//!   fix's epoch*, kept in a fixed ring of past positions and velocities
//!   (corrected since by every later update); the correction is applied to
//!   the current state with the current covariance (the delayed-innovation
//!   approximation; the error's change over the latency, ~0.1 s, is neglected).
//! - **Gating:** every update's normalised innovation squared (NIS) is
//!   tested against a χ² bound (3 degrees of freedom); rejected updates
//!   are counted per sensor ([`EskfDiagnostics`]) for the logs.
//!
//! The filter allocates once, at construction (the latency ring); a step
//! allocates nothing (fixed-size nalgebra).

use crate::error::CoreError;
use crate::estimator::{KalmanPredictor, NavigatedEstimator, Navigation};
use crate::frames::wrap_pi;
use crate::fusion::FusionError;
use crate::gains::GainSet;
use crate::navigation::{ImuBiasEstimate, NavigationSolution};
use crate::sensor::{SensorFrame, SensorNoise};
use crate::state::{MeasuredStates, NM, ReducedState};
use nalgebra::{Matrix3, SMatrix, SVector, UnitQuaternion, Vector3};

/// Number of error states.
pub const N_ERR: usize = 15;
/// The 15×15 error covariance.
pub type Matrix15 = SMatrix<f64, N_ERR, N_ERR>;
/// A 15-vector of the error state.
pub type Vector15 = SVector<f64, N_ERR>;

/// Offsets of the error-state blocks.
const ATT: usize = 0;
const VEL: usize = 3;
const POS: usize = 6;
const BG: usize = 9;
const BA: usize = 12;

/// Samples of position/velocity history kept for delayed GPS fixes: 2.56 s
/// at 400 Hz, beyond the sensor models' largest latency (2 s).
pub const HISTORY_SAMPLES: usize = 1024;

/// χ² bound for 3 degrees of freedom at 99.9 %: the default innovation gate.
pub const CHI2_3DOF_999: f64 = 16.266;

/// The IMU and magnetometer figures the filter assumes (from the sensors'
/// datasheets or the simulator's sensor configuration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuNoise {
    /// Accelerometer white-noise density (m/s²/√Hz).
    pub accel_noise_density: f64,
    /// Accelerometer bias random walk (m/s²/√s).
    pub accel_bias_walk: f64,
    /// Accelerometer turn-on bias σ (m/s²).
    pub accel_bias_sigma: f64,
    /// Gyro white-noise density (rad/s/√Hz).
    pub gyro_noise_density: f64,
    /// Gyro bias random walk (rad/s/√s).
    pub gyro_bias_walk: f64,
    /// Gyro turn-on bias σ (rad/s).
    pub gyro_bias_sigma: f64,
    /// Magnetometer white-noise σ per axis (field units).
    pub mag_sigma: f64,
}

/// Tuning of the ESKF (TOML `[estimator.eskf]`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
pub struct EskfConfig {
    /// Multiplies the IMU white-noise densities (covers unmodelled vibration,
    /// scale factors, quantisation); 1 trusts the datasheet.
    pub imu_noise_scale: f64,
    /// Multiplies the bias random walks.
    pub bias_walk_scale: f64,
    /// Floor of the magnetometer σ relative to the field's magnitude (covers
    /// unmodelled soft-iron and declination errors).
    pub mag_sigma_floor: f64,
    /// Innovation gate: largest accepted NIS of a 3-vector update (χ², 3 dof).
    pub gate_nis: f64,
    /// After this many consecutive rejections of one sensor's updates the
    /// next is fused ungated (the filter, not the sensor, is then presumed
    /// wrong: a bad initialisation or a long outage); 0 never forces.
    pub gate_reset_after: u32,
    /// Initial attitude σ per axis (rad), after alignment.
    pub attitude_sigma0_rad: f64,
    /// Initial velocity σ per axis (m/s).
    pub velocity_sigma0_m_s: f64,
    /// Initial position σ per axis (m).
    pub position_sigma0_m: f64,
}

impl Default for EskfConfig {
    fn default() -> Self {
        EskfConfig {
            imu_noise_scale: 1.0,
            bias_walk_scale: 1.0,
            mag_sigma_floor: 0.0,
            gate_nis: CHI2_3DOF_999,
            gate_reset_after: 25,
            attitude_sigma0_rad: 0.02,
            velocity_sigma0_m_s: 0.1,
            position_sigma0_m: 1.0,
        }
    }
}

impl EskfConfig {
    /// Check every field (finite, positive; the floor may be zero).
    pub fn validate(&self) -> Result<(), FusionError> {
        for (field, value, zero_ok) in [
            (
                "estimator.eskf.imu_noise_scale",
                self.imu_noise_scale,
                false,
            ),
            ("estimator.eskf.bias_walk_scale", self.bias_walk_scale, true),
            ("estimator.eskf.mag_sigma_floor", self.mag_sigma_floor, true),
            ("estimator.eskf.gate_nis", self.gate_nis, false),
            (
                "estimator.eskf.attitude_sigma0_rad",
                self.attitude_sigma0_rad,
                false,
            ),
            (
                "estimator.eskf.velocity_sigma0_m_s",
                self.velocity_sigma0_m_s,
                false,
            ),
            (
                "estimator.eskf.position_sigma0_m",
                self.position_sigma0_m,
                false,
            ),
        ] {
            let ok = value.is_finite() && (value > 0.0 || (zero_ok && value == 0.0));
            if !ok {
                return Err(FusionError::InvalidConfig {
                    field,
                    value,
                    allowed: if zero_ok {
                        "finite and >= 0"
                    } else {
                        "finite and > 0"
                    },
                });
            }
        }
        Ok(())
    }
}

impl ImuNoise {
    fn validate(&self) -> Result<(), FusionError> {
        for (field, value) in [
            ("imu.accel.noise_density", self.accel_noise_density),
            ("imu.accel.bias_random_walk", self.accel_bias_walk),
            ("imu.accel.initial_bias_sigma", self.accel_bias_sigma),
            ("imu.gyro.noise_density", self.gyro_noise_density),
            ("imu.gyro.bias_random_walk", self.gyro_bias_walk),
            ("imu.gyro.initial_bias_sigma", self.gyro_bias_sigma),
            ("mag.noise_sigma", self.mag_sigma),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(FusionError::InvalidConfig {
                    field,
                    value,
                    allowed: "finite and >= 0",
                });
            }
        }
        Ok(())
    }
}

/// Counters and the last normalised innovations (for logs and consistency
/// checks).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EskfDiagnostics {
    /// Magnetometer updates fused.
    pub mag_fused: u64,
    /// Magnetometer updates rejected by the gate.
    pub mag_rejected: u64,
    /// GPS position updates fused.
    pub gps_position_fused: u64,
    /// GPS position updates rejected by the gate.
    pub gps_position_rejected: u64,
    /// GPS velocity updates fused.
    pub gps_velocity_fused: u64,
    /// GPS velocity updates rejected by the gate.
    pub gps_velocity_rejected: u64,
    /// GPS fixes older than the history (or from the future), not fused.
    pub gps_stale: u64,
    /// Updates fused beyond the gate after `gate_reset_after` rejections.
    pub forced: u64,
    /// Sums of the NIS of every magnetometer, GPS position and GPS velocity
    /// update (gated or not): divided by the counts, the mean NIS (3 for a
    /// consistent filter).
    pub nis_sum: [f64; 3],
    /// NIS of the last magnetometer update (χ², 3 dof), gated or not.
    pub last_mag_nis: f64,
    /// NIS of the last GPS position update.
    pub last_gps_position_nis: f64,
    /// NIS of the last GPS velocity update.
    pub last_gps_velocity_nis: f64,
}

impl EskfDiagnostics {
    /// All updates rejected by the gate or as stale.
    pub fn rejected(&self) -> u64 {
        self.mag_rejected + self.gps_position_rejected + self.gps_velocity_rejected + self.gps_stale
    }
}

/// The error-state Kalman filter navigation (see the module documentation).
#[derive(Debug, Clone)]
pub struct Eskf {
    dt_s: f64,
    gravity_m_s2: f64,
    field_ned: Vector3<f64>,
    gate_nis: f64,
    gate_reset_after: u32,
    /// Consecutive rejections per [`Update`].
    streak: [u32; 3],
    /// Measurement variances: magnetometer, GPS position, GPS velocity.
    r_mag: Vector3<f64>,
    r_gps_pos: Vector3<f64>,
    r_gps_vel: Vector3<f64>,
    /// Process-noise variances per sample: δθ, δv, δb_g, δb_a.
    q_att: f64,
    q_vel: f64,
    q_bg: f64,
    q_ba: f64,
    /// Nominal state.
    q: UnitQuaternion<f64>,
    v_ned: Vector3<f64>,
    p_ned: Vector3<f64>,
    b_g: Vector3<f64>,
    b_a: Vector3<f64>,
    /// Error covariance.
    p: Matrix15,
    /// Ring of `[p − Σδp, v − Σδv]` per sample (a past estimate corrected by
    /// every later update is the entry plus today's sums).
    history: Vec<[f64; 6]>,
    /// Index of the newest history entry and the number filled.
    head: usize,
    filled: usize,
    /// Sums of all position and velocity corrections applied.
    corr_p: Vector3<f64>,
    corr_v: Vector3<f64>,
    /// Time of the newest history entry (s).
    t_s: Option<f64>,
    /// The unwrapped yaw of the last output (rad).
    psi_unwrapped: f64,
    /// Bias-corrected body rates of the last sample (rad/s).
    omega_body: Vector3<f64>,
    mag_fused: bool,
    gps_fused: bool,
    diag: EskfDiagnostics,
}

/// The non-zero blocks of the error transition F beyond the identity.
struct FBlocks {
    /// Exp(−ω T), the attitude block.
    att_att: Matrix3<f64>,
    /// −R [f]× T.
    vel_att: Matrix3<f64>,
    /// −R T.
    vel_ba: Matrix3<f64>,
    /// T.
    dt: f64,
}

impl FBlocks {
    /// F P Fᵀ for a symmetric P, by 3×3 blocks: M = F P changes only the
    /// attitude, velocity and position block rows, and of M Fᵀ only the
    /// blocks on and above the diagonal are formed (the others are their
    /// transposes): 20 block products instead of the dense form's 2 × 15³
    /// multiply-adds. The result is exactly symmetric off the diagonal
    /// blocks; those are symmetrised by the caller.
    #[inline]
    fn sandwich(&self, p: &Matrix15) -> Matrix15 {
        const A: usize = 0;
        const V: usize = 1;
        const PP: usize = 2;
        const G: usize = 3;
        const B: usize = 4;
        let blk = |k: usize, l: usize| -> Matrix3<f64> {
            p.fixed_view::<3, 3>(3 * k, 3 * l).into_owned()
        };
        let (phi, vm, bm, dt) = (&self.att_att, &self.vel_att, &self.vel_ba, self.dt);
        // M = F P, block by block (rows g and b are P's)
        let mut m = [[Matrix3::zeros(); 5]; 5];
        for l in 0..5 {
            let (pa, pv, pg, pb) = (blk(A, l), blk(V, l), blk(G, l), blk(B, l));
            m[A][l] = phi * pa - pg * dt;
            m[V][l] = pv + vm * pa + bm * pb;
            m[PP][l] = blk(PP, l) + pv * dt;
            m[G][l] = pg;
            m[B][l] = pb;
        }
        let (phi_t, vm_t, bm_t) = (phi.transpose(), vm.transpose(), bm.transpose());
        let mut out = Matrix15::zeros();
        for i in 0..5 {
            let mi = &m[i];
            for j in i..5 {
                // (M Fᵀ)_ij = M_i· (F_j·)ᵀ
                let c = match j {
                    A => mi[A] * phi_t - mi[G] * dt,
                    V => mi[V] + mi[A] * vm_t + mi[B] * bm_t,
                    PP => mi[PP] + mi[V] * dt,
                    G => mi[G],
                    _ => mi[B],
                };
                out.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&c);
                if j > i {
                    out.fixed_view_mut::<3, 3>(3 * j, 3 * i)
                        .copy_from(&c.transpose());
                }
            }
        }
        out
    }
}

/// The three updates (index into the rejection streaks).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Update {
    Mag = 0,
    GpsPosition = 1,
    GpsVelocity = 2,
}

/// The skew-symmetric matrix `[a]×` (`[a]× b = a × b`).
#[inline]
fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    a.cross_matrix()
}

impl Eskf {
    /// A filter sampled every `dt_s`, initialised at `[x y z vn ve vd φ θ ψ]`
    /// (as after alignment on the ground) with zero biases, and the covariance
    /// of `config` and the sensors' turn-on bias σ.
    pub fn new(
        config: &EskfConfig,
        imu: &ImuNoise,
        noise: &SensorNoise,
        dt_s: f64,
        initial: &SVector<f64, NM>,
    ) -> Result<Self, FusionError> {
        config.validate()?;
        imu.validate()?;
        for (field, value) in [("dt_s", dt_s), ("gravity_m_s2", noise.gravity_m_s2)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(FusionError::InvalidConfig {
                    field,
                    value,
                    allowed: "finite and > 0",
                });
            }
        }
        let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
        if !(initial.iter().all(|x| x.is_finite())
            && finite(&noise.gps_sigma_m)
            && finite(&noise.gps_vel_sigma_m_s)
            && finite(&noise.mag_field_ned))
        {
            return Err(FusionError::NonFiniteInput {
                what: "initial state or sensor noise",
            });
        }
        let field_norm = noise.mag_field_ned.norm();
        if field_norm <= 0.0 {
            return Err(FusionError::InvalidConfig {
                field: "mag.field_ned",
                value: field_norm,
                allowed: "a non-zero vector",
            });
        }
        let mag_sigma = imu
            .mag_sigma
            .max(config.mag_sigma_floor * field_norm)
            .max(1e-9);
        let s = config.imu_noise_scale;
        let w = config.bias_walk_scale;
        let mut p = Matrix15::zeros();
        for i in 0..3 {
            p[(ATT + i, ATT + i)] = config.attitude_sigma0_rad.powi(2);
            p[(VEL + i, VEL + i)] = config.velocity_sigma0_m_s.powi(2);
            p[(POS + i, POS + i)] = config.position_sigma0_m.powi(2);
            p[(BG + i, BG + i)] = imu.gyro_bias_sigma.max(1e-6).powi(2);
            p[(BA + i, BA + i)] = imu.accel_bias_sigma.max(1e-5).powi(2);
        }
        let q =
            crate::attitude::quaternion_from_euler(initial[6], initial[7], initial[8]).inverse();
        let v_ned = Vector3::new(initial[3], initial[4], initial[5]);
        let p_ned = Vector3::new(initial[0], initial[1], initial[2]);
        Ok(Eskf {
            dt_s,
            gravity_m_s2: noise.gravity_m_s2,
            field_ned: noise.mag_field_ned,
            gate_nis: config.gate_nis,
            gate_reset_after: config.gate_reset_after,
            streak: [0; 3],
            r_mag: Vector3::repeat(mag_sigma * mag_sigma),
            r_gps_pos: noise.gps_sigma_m.map(|v| v.max(1e-3).powi(2)),
            r_gps_vel: noise.gps_vel_sigma_m_s.map(|v| v.max(1e-3).powi(2)),
            q_att: (s * imu.gyro_noise_density).powi(2) * dt_s,
            q_vel: (s * imu.accel_noise_density).powi(2) * dt_s,
            q_bg: (w * imu.gyro_bias_walk).powi(2) * dt_s,
            q_ba: (w * imu.accel_bias_walk).powi(2) * dt_s,
            q,
            v_ned,
            p_ned,
            b_g: Vector3::zeros(),
            b_a: Vector3::zeros(),
            p,
            history: vec![[0.0; 6]; HISTORY_SAMPLES],
            head: 0,
            filled: 0,
            corr_p: Vector3::zeros(),
            corr_v: Vector3::zeros(),
            t_s: None,
            psi_unwrapped: initial[8],
            omega_body: Vector3::zeros(),
            mag_fused: false,
            gps_fused: false,
            diag: EskfDiagnostics::default(),
        })
    }

    /// One sample: propagate over the interval ending at the frame's time with
    /// its IMU sample (the mean over the interval, as delta-angle and
    /// delta-velocity IMUs deliver it; the periods of samples that did not
    /// come propagated too, at most
    /// [`MAX_MISSED_PERIODS`](crate::navigation::MAX_MISSED_PERIODS)), then
    /// fuse the magnetometer and a valid GPS fix. Returns the nine measured
    /// states (15.2) `[φ θ ψ u v w p q r]`.
    pub fn step(&mut self, frame: &SensorFrame) -> Result<MeasuredStates, FusionError> {
        if let Some(what) = frame.first_non_finite() {
            return Err(FusionError::NonFiniteInput { what });
        }
        let omega = frame.imu.gyro_body_rad_s - self.b_g;
        let f = frame.imu.specific_force_body_m_s2 - self.b_a;
        if let Some(last) = self.t_s {
            // periods without a sample (never came, or a real-time reader
            // superseded them) propagated with this sample, the mean over
            // the interval, each with its history entry
            let missed = crate::navigation::missed_periods(Some(last), frame.t_s, self.dt_s);
            for k in 1..=missed {
                self.propagate(&omega, &f);
                self.push_history(last + f64::from(k) * self.dt_s);
            }
            self.propagate(&omega, &f);
        }
        self.push_history(frame.t_s);
        self.mag_fused = false;
        self.gps_fused = false;
        if let Some(m) = frame.mag_body {
            self.update_mag(&m)?;
        }
        if let Some(g) = frame.gps.filter(|g| g.is_valid()) {
            self.update_gps(frame.t_s, g.epoch_s, &g.position_ned_m, g.velocity_ned_m_s)?;
        }
        let mut nominal = self
            .v_ned
            .iter()
            .chain(self.p_ned.iter())
            .chain(self.b_g.iter())
            .chain(self.b_a.iter())
            .chain(self.q.coords.iter());
        if !(self.p.as_slice().iter().all(|v| v.is_finite()) && nominal.all(|v| v.is_finite())) {
            return Err(FusionError::NonFiniteInput {
                what: "navigation state (the filter diverged)",
            });
        }
        self.omega_body = frame.imu.gyro_body_rad_s - self.b_g;
        let e = self.euler_rad();
        let v_body = self.q.inverse_transform_vector(&self.v_ned);
        Ok(MeasuredStates::from_column_slice(&[
            e.x,
            e.y,
            e.z,
            v_body.x,
            v_body.y,
            v_body.z,
            self.omega_body.x,
            self.omega_body.y,
            self.omega_body.z,
        ]))
    }

    /// The strapdown mechanisation and the covariance prediction over one sample.
    fn propagate(&mut self, omega: &Vector3<f64>, f: &Vector3<f64>) {
        let dt = self.dt_s;
        let r = self.q.to_rotation_matrix().into_inner();
        let a = r * f + Vector3::new(0.0, 0.0, self.gravity_m_s2);
        self.p_ned += self.v_ned * dt + a * (0.5 * dt * dt);
        self.v_ned += a * dt;
        let dq = UnitQuaternion::from_scaled_axis(omega * dt);
        self.q *= dq;
        self.q.renormalize_fast();
        // F = I + A T, the attitude block exact: Exp(−ω T) = dqᵀ; P ← F P Fᵀ
        // by blocks, the upper half formed and mirrored
        let f_blocks = FBlocks {
            att_att: dq.to_rotation_matrix().into_inner().transpose(),
            vel_att: -(r * skew(f)) * dt,
            vel_ba: -r * dt,
            dt,
        };
        self.p = f_blocks.sandwich(&self.p);
        for i in 0..3 {
            self.p[(ATT + i, ATT + i)] += self.q_att;
            self.p[(VEL + i, VEL + i)] += self.q_vel;
            self.p[(BG + i, BG + i)] += self.q_bg;
            self.p[(BA + i, BA + i)] += self.q_ba;
        }
        // only the diagonal blocks can be asymmetric (round-off)
        for k in (0..N_ERR).step_by(3) {
            for i in k..k + 3 {
                for j in (i + 1)..k + 3 {
                    let m = 0.5 * (self.p[(i, j)] + self.p[(j, i)]);
                    self.p[(i, j)] = m;
                    self.p[(j, i)] = m;
                }
            }
        }
    }

    fn symmetrise(&mut self) {
        for i in 0..N_ERR {
            for j in (i + 1)..N_ERR {
                let m = 0.5 * (self.p[(i, j)] + self.p[(j, i)]);
                self.p[(i, j)] = m;
                self.p[(j, i)] = m;
            }
        }
    }

    fn push_history(&mut self, t_s: f64) {
        if self.filled > 0 {
            self.head = (self.head + 1) % HISTORY_SAMPLES;
        }
        self.filled = (self.filled + 1).min(HISTORY_SAMPLES);
        let p = self.p_ned - self.corr_p;
        let v = self.v_ned - self.corr_v;
        self.history[self.head] = [p.x, p.y, p.z, v.x, v.y, v.z];
        self.t_s = Some(t_s);
    }

    /// The estimate of position and velocity at `epoch_s`, as corrected by
    /// every update since: `None` when older than the history.
    fn past(&self, t_now_s: f64, epoch_s: f64) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let back = ((t_now_s - epoch_s) / self.dt_s).round();
        if !(back >= 0.0 && back < self.filled as f64) {
            return None;
        }
        let back = back as usize;
        let e = &self.history[(self.head + HISTORY_SAMPLES - back) % HISTORY_SAMPLES];
        Some((
            Vector3::new(e[0], e[1], e[2]) + self.corr_p,
            Vector3::new(e[3], e[4], e[5]) + self.corr_v,
        ))
    }

    fn update_mag(&mut self, m_body: &Vector3<f64>) -> Result<(), FusionError> {
        let predicted = self.q.inverse_transform_vector(&self.field_ned);
        let mut h = SMatrix::<f64, 3, N_ERR>::zeros();
        h.fixed_view_mut::<3, 3>(0, ATT)
            .copy_from(&skew(&predicted));
        self.mag_fused = self.correct(Update::Mag, &(m_body - predicted), &h)?;
        Ok(())
    }

    fn update_gps(
        &mut self,
        t_now_s: f64,
        epoch_s: f64,
        position_ned_m: &Vector3<f64>,
        velocity_ned_m_s: Option<Vector3<f64>>,
    ) -> Result<(), FusionError> {
        let Some((p_then, _)) = self.past(t_now_s, epoch_s) else {
            self.diag.gps_stale += 1;
            return Ok(());
        };
        let mut h = SMatrix::<f64, 3, N_ERR>::zeros();
        h.fixed_view_mut::<3, 3>(0, POS)
            .copy_from(&Matrix3::identity());
        self.gps_fused = self.correct(Update::GpsPosition, &(position_ned_m - p_then), &h)?;
        if let Some(vel) = velocity_ned_m_s {
            // the position update moved the history: read it again
            let Some((_, v_then)) = self.past(t_now_s, epoch_s) else {
                return Ok(());
            };
            let mut h = SMatrix::<f64, 3, N_ERR>::zeros();
            h.fixed_view_mut::<3, 3>(0, VEL)
                .copy_from(&Matrix3::identity());
            self.gps_fused |= self.correct(Update::GpsVelocity, &(vel - v_then), &h)?;
        }
        Ok(())
    }

    /// A 3-vector update with innovation `y`, Jacobian `h` and diagonal
    /// variances `r`: gate on the NIS, Joseph-form covariance, inject the
    /// error into the nominal state and reset. Returns whether it was fused.
    fn correct(
        &mut self,
        which: Update,
        y: &Vector3<f64>,
        h: &SMatrix<f64, 3, N_ERR>,
    ) -> Result<bool, FusionError> {
        let r = match which {
            Update::Mag => self.r_mag,
            Update::GpsPosition => self.r_gps_pos,
            Update::GpsVelocity => self.r_gps_vel,
        };
        let ph_t = self.p * h.transpose();
        let s = h * ph_t + Matrix3::from_diagonal(&r);
        let chol = nalgebra::Cholesky::new(s).ok_or(FusionError::SingularInnovation)?;
        let s_inv_y = chol.solve(y);
        let nis = y.dot(&s_inv_y);
        if !nis.is_finite() {
            return Err(FusionError::SingularInnovation);
        }
        let i = which as usize;
        let d = &mut self.diag;
        let (last, fused, rejected) = match which {
            Update::Mag => (&mut d.last_mag_nis, &mut d.mag_fused, &mut d.mag_rejected),
            Update::GpsPosition => (
                &mut d.last_gps_position_nis,
                &mut d.gps_position_fused,
                &mut d.gps_position_rejected,
            ),
            Update::GpsVelocity => (
                &mut d.last_gps_velocity_nis,
                &mut d.gps_velocity_fused,
                &mut d.gps_velocity_rejected,
            ),
        };
        *last = nis;
        d.nis_sum[i] += nis;
        let forced = self.gate_reset_after > 0 && self.streak[i] >= self.gate_reset_after;
        if nis > self.gate_nis && !forced {
            *rejected += 1;
            self.streak[i] += 1;
            return Ok(false);
        }
        *fused += 1;
        self.streak[i] = 0;
        if nis > self.gate_nis {
            d.forced += 1;
            return self.reset_to(which, y, &r);
        }
        // K = P Hᵀ S⁻¹ = (S⁻¹ H P)ᵀ (S symmetric)
        let k: SMatrix<f64, N_ERR, 3> = chol.solve(&ph_t.transpose()).transpose();
        let dx: Vector15 = ph_t * s_inv_y;
        // Joseph form (I − KH) P (I − KH)ᵀ + K R Kᵀ, expanded (exact for any
        // K, without the 15×15 products): P − K(HP) − (K(HP))ᵀ + K S Kᵀ
        let khp = k * ph_t.transpose();
        let ks = k * s;
        self.p += ks * k.transpose() - khp - khp.transpose();
        self.inject(&dx);
        Ok(true)
    }

    /// The forced update after a streak of rejections: a GPS position or
    /// velocity is taken as the state (its block's covariance set to the
    /// measurement's, correlations dropped); the magnetometer's attitude
    /// uncertainty is widened by 0.3 rad before it is fused.
    fn reset_to(
        &mut self,
        which: Update,
        y: &Vector3<f64>,
        r: &Vector3<f64>,
    ) -> Result<bool, FusionError> {
        let block = match which {
            Update::GpsPosition => POS,
            Update::GpsVelocity => VEL,
            Update::Mag => {
                for i in 0..3 {
                    self.p[(ATT + i, ATT + i)] += 0.09;
                }
                let predicted = self.q.inverse_transform_vector(&self.field_ned);
                let mut h = SMatrix::<f64, 3, N_ERR>::zeros();
                h.fixed_view_mut::<3, 3>(0, ATT)
                    .copy_from(&skew(&predicted));
                let gate = self.gate_nis;
                self.gate_nis = f64::INFINITY;
                let res = self.correct(Update::Mag, y, &h);
                self.gate_nis = gate;
                return res;
            }
        };
        let mut dx = Vector15::zeros();
        for i in 0..3 {
            dx[block + i] = y[i];
        }
        self.p.fixed_rows_mut::<3>(block).fill(0.0);
        self.p.fixed_columns_mut::<3>(block).fill(0.0);
        for i in 0..3 {
            self.p[(block + i, block + i)] = r[i];
        }
        self.inject(&dx);
        Ok(true)
    }

    /// Add the error estimate to the nominal state and reset the covariance.
    fn inject(&mut self, dx: &Vector15) {
        let dtheta = Vector3::new(dx[ATT], dx[ATT + 1], dx[ATT + 2]);
        let dv = Vector3::new(dx[VEL], dx[VEL + 1], dx[VEL + 2]);
        let dp = Vector3::new(dx[POS], dx[POS + 1], dx[POS + 2]);
        self.q *= UnitQuaternion::from_scaled_axis(dtheta);
        self.q.renormalize_fast();
        self.v_ned += dv;
        self.p_ned += dp;
        self.corr_v += dv;
        self.corr_p += dp;
        for i in 0..3 {
            self.b_g[i] += dx[BG + i];
            self.b_a[i] += dx[BA + i];
        }
        // reset: δθ⁺ = G δθ with G = I − [δθ/2]×, rows and columns of the
        // attitude block only
        let g = Matrix3::identity() - skew(&(dtheta * 0.5));
        let rows: SMatrix<f64, 3, N_ERR> = g * self.p.fixed_rows::<3>(ATT);
        self.p.fixed_rows_mut::<3>(ATT).copy_from(&rows);
        let cols: SMatrix<f64, N_ERR, 3> = self.p.fixed_columns::<3>(ATT) * g.transpose();
        self.p.fixed_columns_mut::<3>(ATT).copy_from(&cols);
        self.symmetrise();
    }

    /// 3-2-1 Euler angles (rad) of the estimate, yaw unwrapped continuously
    /// from the initial heading (the references may turn many times).
    fn euler_rad(&mut self) -> Vector3<f64> {
        let (phi, theta, psi) = self.q.euler_angles();
        self.psi_unwrapped += wrap_pi(psi - self.psi_unwrapped);
        Vector3::new(phi, theta, self.psi_unwrapped)
    }

    /// Attitude `ned_from_body`.
    pub fn attitude(&self) -> &UnitQuaternion<f64> {
        &self.q
    }

    /// Velocity NED (m/s).
    pub fn velocity_ned_m_s(&self) -> &Vector3<f64> {
        &self.v_ned
    }

    /// Position NED (m).
    pub fn position_ned_m(&self) -> &Vector3<f64> {
        &self.p_ned
    }

    /// Estimated gyro bias (body, rad/s).
    pub fn gyro_bias_rad_s(&self) -> &Vector3<f64> {
        &self.b_g
    }

    /// Estimated accelerometer bias (body, m/s²).
    pub fn accel_bias_m_s2(&self) -> &Vector3<f64> {
        &self.b_a
    }

    /// The error-state covariance `[δθ δv δp δb_g δb_a]`.
    pub fn covariance(&self) -> &Matrix15 {
        &self.p
    }

    /// Update counters and the last NIS values.
    pub fn diagnostics(&self) -> &EskfDiagnostics {
        &self.diag
    }

    /// The navigation solution after the last [`Eskf::step`].
    pub fn solution(&self) -> NavigationSolution {
        let sd = |i: usize| {
            Vector3::new(
                self.p[(i, i)],
                self.p[(i + 1, i + 1)],
                self.p[(i + 2, i + 2)],
            )
            .map(f64::sqrt)
        };
        let (phi, theta, _) = self.q.euler_angles();
        NavigationSolution {
            position_ned_m: self.p_ned,
            velocity_ned_m_s: self.v_ned,
            attitude_rad: Vector3::new(phi, theta, self.psi_unwrapped),
            position_sigma_m: sd(POS),
            attitude_fix: self.mag_fused,
            gps_fused: self.gps_fused,
            imu_bias: Some(ImuBiasEstimate {
                gyro_rad_s: self.b_g,
                accel_m_s2: self.b_a,
                gyro_sigma_rad_s: sd(BG),
                accel_sigma_m_s2: sd(BA),
            }),
            rejected_updates: self.diag.rejected(),
        }
    }
}

/// The ESKF navigation ahead of the thesis's Kalman predictor: the ESKF
/// gives the nine measured states (attitude, body velocity, bias-corrected
/// rates), the predictor the flapping, servo and the other reduced states.
pub type EskfEstimator<P = KalmanPredictor> = NavigatedEstimator<Eskf, P>;

impl EskfEstimator {
    /// The estimator of a gain set: the navigation as built, the predictor
    /// starting at the absolute reduced state `x0`.
    pub fn new(navigation: Eskf, gains: &GainSet, x0: &ReducedState) -> Result<Self, CoreError> {
        Ok(NavigatedEstimator {
            navigation,
            predictor: KalmanPredictor::new(gains, x0)?,
        })
    }
}

impl Navigation for Eskf {
    #[inline]
    fn step(&mut self, frame: &SensorFrame) -> Result<MeasuredStates, FusionError> {
        Eskf::step(self, frame)
    }
    fn solution(&self) -> NavigationSolution {
        Eskf::solution(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::{GpsFix, GpsFixType, ImuSample};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    const DT: f64 = 0.0025;
    const G: f64 = 9.81;

    fn imu() -> ImuNoise {
        ImuNoise {
            accel_noise_density: 0.004,
            accel_bias_walk: 3e-4,
            accel_bias_sigma: 0.3,
            gyro_noise_density: 1e-4,
            gyro_bias_walk: 2e-5,
            gyro_bias_sigma: 0.01,
            mag_sigma: 0.002,
        }
    }

    fn noise() -> SensorNoise {
        SensorNoise {
            gps_sigma_m: Vector3::new(1.5, 1.5, 3.0),
            gps_vel_sigma_m_s: Vector3::new(0.05, 0.05, 0.1),
            mag_field_ned: Vector3::new(0.153, 0.008, -0.438),
            gravity_m_s2: G,
        }
    }

    /// Synthetic flight: constant NED velocity `vel`, level, yawing at
    /// `yaw_rate`; the IMU with constant biases and white noise, the
    /// magnetometer at 100 Hz, GPS at 5 Hz delivered `latency` s late.
    /// Returns the filter after `seconds`.
    fn fly(
        vel: Vector3<f64>,
        yaw_rate: f64,
        bg: Vector3<f64>,
        ba: Vector3<f64>,
        latency: f64,
        seconds: f64,
        mut each: impl FnMut(&Eskf, f64, &Vector3<f64>, f64),
    ) -> Eskf {
        fly_told(vel, yaw_rate, bg, ba, latency, latency, seconds, &mut each)
    }

    /// As [`fly`], the fixes stamped `told` s before delivery while they
    /// are `latency` s old.
    fn fly_told(
        vel: Vector3<f64>,
        yaw_rate: f64,
        bg: Vector3<f64>,
        ba: Vector3<f64>,
        latency: f64,
        told: f64,
        seconds: f64,
        each: &mut impl FnMut(&Eskf, f64, &Vector3<f64>, f64),
    ) -> Eskf {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut n = move || -> f64 { StandardNormal.sample(&mut rng) };
        let init = SVector::<f64, 9>::from_column_slice(&[
            0.0, 0.0, 0.0, vel.x, vel.y, vel.z, 0.0, 0.0, 0.0,
        ]);
        let mut f = Eskf::new(&EskfConfig::default(), &imu(), &noise(), DT, &init).unwrap();
        let steps = (seconds / DT).round() as usize;
        let sa = imu().accel_noise_density / DT.sqrt();
        let sg = imu().gyro_noise_density / DT.sqrt();
        for k in 0..=steps {
            let t = k as f64 * DT;
            let psi = yaw_rate * t;
            let r_bn = crate::frames::body_from_ned(0.0, 0.0, psi);
            let nv = Vector3::new(n(), n(), n());
            let ng = Vector3::new(n(), n(), n());
            let frame = SensorFrame {
                t_s: t,
                imu: ImuSample {
                    specific_force_body_m_s2: r_bn * Vector3::new(0.0, 0.0, -G) + ba + nv * sa,
                    gyro_body_rad_s: Vector3::new(0.0, 0.0, yaw_rate) + bg + ng * sg,
                },
                mag_body: (k % 4 == 0)
                    .then(|| r_bn * noise().mag_field_ned + Vector3::new(n(), n(), n()) * 0.002),
                gps: (k % 80 == 0 && t >= latency).then(|| {
                    let epoch = t - latency;
                    GpsFix {
                        epoch_s: t - told,
                        fix: GpsFixType::Fix3d,
                        position_ned_m: vel * epoch + Vector3::new(1.5 * n(), 1.5 * n(), 3.0 * n()),
                        velocity_ned_m_s: Some(vel + Vector3::new(n(), n(), 2.0 * n()) * 0.05),
                    }
                }),
            };
            f.step(&frame).unwrap();
            each(&f, t, &(vel * t), psi);
        }
        f
    }

    #[test]
    fn biases_are_estimated_while_turning() {
        // a slow turn makes the horizontal accelerometer biases observable
        let bg = Vector3::new(0.008, -0.006, 0.005);
        let ba = Vector3::new(0.25, -0.2, 0.15);
        let f = fly(
            Vector3::new(2.0, 0.0, 0.0),
            0.1,
            bg,
            ba,
            0.1,
            120.0,
            |_, _, _, _| {},
        );
        let eg = (f.gyro_bias_rad_s() - bg).abs().max();
        let ea = (f.accel_bias_m_s2() - ba).abs().max();
        // bounds: 3σ of the filter's own covariance, and absolute figures
        // well below the biases (5 % of the gyro's, 10 % of the accelerometer's)
        assert!(eg < 4e-4, "gyro bias error {eg} rad/s");
        assert!(ea < 0.03, "accel bias error {ea} m/s²");
        let p = f.covariance();
        for i in 0..3 {
            assert!((f.gyro_bias_rad_s()[i] - bg[i]).abs() < 3.0 * p[(BG + i, BG + i)].sqrt());
        }
        // covariance symmetric positive definite
        assert_eq!(p, &p.transpose());
        assert!(nalgebra::Cholesky::new(*p).is_some());
    }

    #[test]
    fn latency_is_compensated() {
        // 10 m/s with 0.1 s latency: fusing the fix as current would bias the
        // position 1 m behind; the delayed innovation leaves < 0.3 m mean error
        let vel = Vector3::new(10.0, 0.0, 0.0);
        let mut sum = 0.0;
        let mut count = 0.0;
        fly(
            vel,
            0.0,
            Vector3::zeros(),
            Vector3::zeros(),
            0.1,
            60.0,
            |f, t, p, _| {
                if t > 20.0 {
                    sum += f.position_ned_m().x - p.x;
                    count += 1.0;
                }
            },
        );
        let mean = sum / count;
        assert!(mean.abs() < 0.3, "mean along-track position error {mean} m");
        // the control: the same fixes stamped as current lag ~1 m
        let (mut sum, mut count) = (0.0, 0.0);
        let mut each = |f: &Eskf, t: f64, p: &Vector3<f64>, _: f64| {
            if t > 20.0 {
                sum += f.position_ned_m().x - p.x;
                count += 1.0;
            }
        };
        fly_told(
            vel,
            0.0,
            Vector3::zeros(),
            Vector3::zeros(),
            0.1,
            0.0,
            60.0,
            &mut each,
        );
        let lag = sum / count;
        assert!(lag < -0.7, "fixes fused as current: mean error {lag} m");
    }

    #[test]
    fn outliers_are_gated_and_counted() {
        let init = SVector::<f64, 9>::zeros();
        let mut f = Eskf::new(&EskfConfig::default(), &imu(), &noise(), DT, &init).unwrap();
        let frame = |t: f64, pos: Vector3<f64>| SensorFrame {
            t_s: t,
            imu: ImuSample {
                specific_force_body_m_s2: Vector3::new(0.0, 0.0, -G),
                gyro_body_rad_s: Vector3::zeros(),
            },
            mag_body: Some(noise().mag_field_ned),
            gps: Some(GpsFix {
                epoch_s: t,
                fix: GpsFixType::Fix3d,
                position_ned_m: pos,
                velocity_ned_m_s: None,
            }),
        };
        f.step(&frame(0.0, Vector3::zeros())).unwrap();
        f.step(&frame(DT, Vector3::new(100.0, 0.0, 0.0))).unwrap();
        assert_eq!(f.diagnostics().gps_position_rejected, 1);
        assert!(f.diagnostics().last_gps_position_nis > 1000.0);
        assert!(f.position_ned_m().norm() < 0.1);
        assert_eq!(f.solution().rejected_updates, 1);
        // a fix older than the history is not fused
        let mut old = frame(2.0 * DT, Vector3::zeros());
        if let Some(g) = old.gps.as_mut() {
            g.epoch_s = -10.0;
        }
        f.step(&old).unwrap();
        assert_eq!(f.diagnostics().gps_stale, 1);
    }

    #[test]
    fn a_wrong_start_is_recovered_by_the_gate_reset() {
        // the filter starts 10 m/s off: every GPS velocity is rejected until
        // the reset forces one, then the filter converges
        let vel = Vector3::new(10.0, 0.0, 0.0);
        // the same run from a 10 m/s wrong start
        let init = SVector::<f64, 9>::zeros();
        let mut g = Eskf::new(&EskfConfig::default(), &imu(), &noise(), DT, &init).unwrap();
        for k in 0..4000 {
            let t = k as f64 * DT;
            let frame = SensorFrame {
                t_s: t,
                imu: ImuSample {
                    specific_force_body_m_s2: Vector3::new(0.0, 0.0, -G),
                    gyro_body_rad_s: Vector3::zeros(),
                },
                mag_body: Some(noise().mag_field_ned),
                gps: (k % 80 == 0).then_some(GpsFix {
                    epoch_s: t,
                    fix: GpsFixType::Fix3d,
                    position_ned_m: vel * t,
                    velocity_ned_m_s: Some(vel),
                }),
            };
            g.step(&frame).unwrap();
        }
        assert!(g.diagnostics().forced >= 1);
        assert!(
            (g.velocity_ned_m_s() - vel).norm() < 0.1,
            "{}",
            g.velocity_ned_m_s()
        );
        assert!(
            (g.position_ned_m() - vel * 3999.0 * DT).norm() < 0.5,
            "{}",
            g.position_ned_m()
        );
    }

    #[test]
    fn block_products_equal_the_dense_forms() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut n = move || -> f64 { StandardNormal.sample(&mut rng) };
        let l = Matrix15::from_fn(|_, _| n());
        let p = l * l.transpose();
        let r = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.2, 1.0))
            .to_rotation_matrix()
            .into_inner();
        let f = Vector3::new(0.5, -0.3, -9.7);
        let dq = UnitQuaternion::from_scaled_axis(Vector3::new(0.01, 0.02, -0.03));
        let dt = 0.0025;
        let blocks = FBlocks {
            att_att: dq.to_rotation_matrix().into_inner().transpose(),
            vel_att: -(r * skew(&f)) * dt,
            vel_ba: -r * dt,
            dt,
        };
        let mut fm = Matrix15::identity();
        fm.fixed_view_mut::<3, 3>(ATT, ATT)
            .copy_from(&blocks.att_att);
        fm.fixed_view_mut::<3, 3>(ATT, BG)
            .copy_from(&(-Matrix3::identity() * dt));
        fm.fixed_view_mut::<3, 3>(VEL, ATT)
            .copy_from(&blocks.vel_att);
        fm.fixed_view_mut::<3, 3>(VEL, BA).copy_from(&blocks.vel_ba);
        fm.fixed_view_mut::<3, 3>(POS, VEL)
            .copy_from(&(Matrix3::identity() * dt));
        let dense = fm * p * fm.transpose();
        let by_blocks = blocks.sandwich(&p);
        assert!((dense - by_blocks).abs().max() < 1e-12 * p.abs().max());
        // exactly symmetric off the diagonal blocks
        for i in 0..N_ERR {
            for j in 0..N_ERR {
                if i / 3 != j / 3 {
                    assert_eq!(by_blocks[(i, j)].to_bits(), by_blocks[(j, i)].to_bits());
                }
            }
        }
        // the expanded Joseph form equals the literal one for any gain K
        let h = SMatrix::<f64, 3, N_ERR>::from_fn(|_, _| n());
        let k = SMatrix::<f64, N_ERR, 3>::from_fn(|_, _| n());
        let rm = Matrix3::from_diagonal(&Vector3::new(0.1, 0.2, 0.3));
        let a = Matrix15::identity() - k * h;
        let literal = a * p * a.transpose() + k * rm * k.transpose();
        let khp = k * (h * p);
        let expanded = p + k * (h * p * h.transpose() + rm) * k.transpose() - khp - khp.transpose();
        assert!((literal - expanded).abs().max() < 1e-10 * literal.abs().max());
    }

    #[test]
    fn bad_inputs_are_errors_naming_them() {
        let init = SVector::<f64, 9>::zeros();
        let cfg = EskfConfig {
            gate_nis: f64::NAN,
            ..EskfConfig::default()
        };
        let e = Eskf::new(&cfg, &imu(), &noise(), DT, &init).unwrap_err();
        assert!(e.to_string().contains("estimator.eskf.gate_nis"), "{e}");
        let mut f = Eskf::new(&EskfConfig::default(), &imu(), &noise(), DT, &init).unwrap();
        let mut frame = SensorFrame::imu_only(
            0.0,
            ImuSample {
                specific_force_body_m_s2: Vector3::new(0.0, f64::NAN, -G),
                gyro_body_rad_s: Vector3::zeros(),
            },
        );
        let e = f.step(&frame).unwrap_err();
        assert!(e.to_string().contains("accelerometer"), "{e}");
        frame.imu.specific_force_body_m_s2.y = 0.0;
        assert!(f.step(&frame).is_ok());
    }
}
