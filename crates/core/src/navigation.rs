//! On-board navigation: sensor frames to the nine measured states.
//!
//! [`NavigationFilter`]: sensor samples → q-method attitude determination
//! (13.4)–(13.12) + the GPS/IMU fusion filter (13.15)–(13.29) → the nine
//! measured states of (15.2) the state estimator expects:
//! [φ θ ψ] from the fusion filter, [u v w] = R_be(Θ̂)·v̂_ned, [p q r] from the gyro.
//!
//! The gravity observation (13.2) assumes the helicopter is not accelerating,
//! as the thesis's implementation did: the accelerometer's specific force is
//! taken as gravity. (Differencing the fused velocity to subtract the own
//! acceleration is degenerate: the subtraction then returns the predicted
//! attitude itself.)
//!
//! The fusion filter has no bias states (nor has the thesis's); its process
//! noise ([`NavigationConfig`]) absorbs the IMU biases. Beyond the thesis, the
//! GPS receiver's Doppler velocity is fused too (hobby receivers give it at
//! ~0.05 m/s): with position-only fixes of 1.5 m white noise the velocity
//! estimate is too noisy to close the loop on (the helicopter diverges within
//! seconds in the `beyond-physical-turbulence` scenario); with it, the
//! default tuning 0.5 m/s², 0.02 rad/s, 0.03 rad flies the scenario.

use crate::attitude::{VectorObservation, gravity_observation, q_method};
use crate::frames::EulerTrig;
use crate::fusion::{FusionConfig, FusionError, FusionFilter, FusionInput, GpsGate};
use crate::sensor::{SensorFrame, SensorNoise};
use crate::state::{MeasuredStates, NM};
use nalgebra::{SMatrix, SVector, Vector3};

/// Tuning of the navigation filter (TOML `[navigation]`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
pub struct NavigationConfig {
    /// Process noise of the NED acceleration input per sample (m/s²).
    pub accel_sigma_m_s2: f64,
    /// Process noise of the Euler-rate input per sample (rad/s).
    pub euler_rate_sigma_rad_s: f64,
    /// Standard deviation of the q-method attitude measurement (rad).
    pub attitude_sigma_rad: f64,
    /// Weight of the gravity observation in the q-method (the magnetometer's is 1).
    pub gravity_weight: f64,
    /// Innovation gate of the GPS position and velocity updates: largest
    /// accepted normalised innovation squared (χ², 3 dof). Beyond the
    /// thesis, whose filter fused every fix: a receiver's glitch (a fix
    /// kilometres away, a velocity of hundreds of m/s) is not fused. `None`:
    /// no gate, the thesis's filter (the simulator's default, so its
    /// figures stay the thesis's); the on-board program flies
    /// [`GPS_GATE_NIS`] unless its configuration says otherwise.
    pub gps_gate_nis: Option<f64>,
    /// Refusals in a row after which the next GPS fix is fused ungated (the
    /// filter, not the receiver, is then presumed wrong; 0: never).
    pub gps_gate_reset_after: u32,
}

/// The default GPS innovation gate: NIS 50 for 3 degrees of freedom, whose
/// probability for a consistent filter is below 1e-10 — a bound no fix of
/// a working receiver reaches (well above the 99.9 % point 16.27, since the
/// thesis's filter has no bias states and its covariance is approximate).
pub const GPS_GATE_NIS: f64 = 50.0;

impl Default for NavigationConfig {
    fn default() -> Self {
        NavigationConfig {
            accel_sigma_m_s2: 0.5,
            euler_rate_sigma_rad_s: 0.02,
            attitude_sigma_rad: 0.03,
            gravity_weight: 1.0,
            gps_gate_nis: None,
            gps_gate_reset_after: 25,
        }
    }
}

impl NavigationConfig {
    /// Check every field is finite and positive.
    pub fn validate(&self) -> Result<(), FusionError> {
        for (field, value) in [
            ("navigation.accel_sigma_m_s2", self.accel_sigma_m_s2),
            (
                "navigation.euler_rate_sigma_rad_s",
                self.euler_rate_sigma_rad_s,
            ),
            ("navigation.attitude_sigma_rad", self.attitude_sigma_rad),
            ("navigation.gravity_weight", self.gravity_weight),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(FusionError::InvalidConfig {
                    field,
                    value,
                    allowed: "finite and > 0",
                });
            }
        }
        if let Some(g) = self.gps_gate_nis
            && (g.is_nan() || g <= 0.0)
        {
            return Err(FusionError::InvalidConfig {
                field: "navigation.gps_gate_nis",
                value: g,
                allowed: "> 0 (inf: no gate)",
            });
        }
        Ok(())
    }
}

/// Attitude determination + fusion filter (fixed-size, `step` does not allocate).
#[derive(Debug, Clone)]
pub struct NavigationFilter {
    filter: FusionFilter,
    field_ned: Vector3<f64>,
    gravity_weight: f64,
    last_f: Vector3<f64>,
    last_w: Vector3<f64>,
    /// The time of the last sample stepped (s): samples that never came
    /// between it and the next are propagated ([`NavigationFilter::step`]).
    last_t_s: Option<f64>,
    attitude_fix: bool,
    gps_fused: bool,
}

/// The most sample periods a missing stretch of samples is propagated over
/// (40 ms at 400 Hz: twice the IMU's default stale limit; a longer gap is
/// the IMU lost, and is propagated over this many periods only).
pub const MAX_MISSED_PERIODS: u32 = 16;

/// The sample periods of `dt_s` that passed without a sample between the
/// last sample stepped (`last_t_s`) and one at `t_s`: 0 for the next
/// sample in line (or a time that did not advance, or none before), at
/// most [`MAX_MISSED_PERIODS`] − 1. Both navigation filters predict these
/// periods first, so that their clock keeps up with the GPS's.
pub fn missed_periods(last_t_s: Option<f64>, t_s: f64, dt_s: f64) -> u32 {
    let Some(last) = last_t_s else { return 0 };
    let periods = ((t_s - last) / dt_s).round();
    if periods > 1.0 {
        (periods.min(f64::from(MAX_MISSED_PERIODS)) as u32) - 1
    } else {
        0
    }
}

/// What the navigation knows after one sample (for telemetry and logs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NavigationSolution {
    /// Fused position NED (m).
    pub position_ned_m: Vector3<f64>,
    /// Fused velocity NED (m/s).
    pub velocity_ned_m_s: Vector3<f64>,
    /// Fused attitude [φ θ ψ] (rad).
    pub attitude_rad: Vector3<f64>,
    /// 1σ of the fused position per NED axis (m).
    pub position_sigma_m: Vector3<f64>,
    /// A q-method attitude was determined and fused this sample.
    pub attitude_fix: bool,
    /// A GPS fix was fused this sample.
    pub gps_fused: bool,
    /// The IMU biases, when the navigation estimates them (the ESKF).
    pub imu_bias: Option<ImuBiasEstimate>,
    /// Updates rejected by the innovation gate (or stale) since the start.
    pub rejected_updates: u64,
}

/// The IMU biases a navigation estimates, with their 1σ (body axes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImuBiasEstimate {
    /// Gyro bias (rad/s).
    pub gyro_rad_s: Vector3<f64>,
    /// Accelerometer bias (m/s²).
    pub accel_m_s2: Vector3<f64>,
    /// 1σ of the gyro bias estimate (rad/s).
    pub gyro_sigma_rad_s: Vector3<f64>,
    /// 1σ of the accelerometer bias estimate (m/s²).
    pub accel_sigma_m_s2: Vector3<f64>,
}

impl NavigationFilter {
    /// A filter sampled every `dt_s`, initialised at position, NED velocity
    /// and attitude `[x y z vn ve vd φ θ ψ]` (as after alignment on the
    /// ground) with a modest uncertainty, the body rates `omega0` and the
    /// specific force of level rest.
    pub fn new(
        config: &NavigationConfig,
        noise: &SensorNoise,
        dt_s: f64,
        initial: &SVector<f64, NM>,
        omega0: &Vector3<f64>,
    ) -> Result<Self, FusionError> {
        config.validate()?;
        let fcfg = FusionConfig {
            dt_s,
            gravity_m_s2: noise.gravity_m_s2,
            accel_sigma_m_s2: config.accel_sigma_m_s2,
            euler_rate_sigma_rad_s: config.euler_rate_sigma_rad_s,
            gps_sigma_m: noise.gps_sigma_m,
            gps_vel_sigma_m_s: noise.gps_vel_sigma_m_s.map(|v| v.max(1e-3)),
            attitude_sigma_rad: Vector3::repeat(config.attitude_sigma_rad),
        };
        let p0 = SMatrix::<f64, 9, 9>::from_diagonal(&SVector::<f64, 9>::from_row_slice(&[
            1.0, 1.0, 1.0, 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4,
        ]));
        let filter = FusionFilter::new(fcfg, *initial, p0)?.with_gps_gate(GpsGate {
            nis: config.gps_gate_nis.unwrap_or(f64::INFINITY),
            reset_after: config.gps_gate_reset_after,
        })?;
        let trig = EulerTrig::new(initial[6], initial[7], initial[8]);
        Ok(NavigationFilter {
            filter,
            field_ned: noise.mag_field_ned,
            gravity_weight: config.gravity_weight,
            last_f: trig.ned_from_body().transpose() * Vector3::new(0.0, 0.0, -noise.gravity_m_s2),
            last_w: *omega0,
            last_t_s: None,
            attitude_fix: false,
            gps_fused: false,
        })
    }

    /// One sample: determine attitude by the q-method when the magnetometer
    /// was sampled, fuse it with the IMU and a valid GPS fix; returns the nine
    /// measured states (15.2) `[φ θ ψ u v w p q r]`.
    ///
    /// The filter is sampled every `dt_s`: when the sample's time is more
    /// than one period after the last one's (samples that never came, or
    /// that a real-time reader superseded), the missing periods are
    /// predicted first with the last sample held (at most
    /// [`MAX_MISSED_PERIODS`]), so that the filter's time keeps up with
    /// the GPS's and a missed sample costs resolution, not a bias.
    pub fn step(&mut self, frame: &SensorFrame) -> Result<MeasuredStates, FusionError> {
        if let Some(what) = frame.first_non_finite() {
            return Err(FusionError::NonFiniteInput { what });
        }
        let missed = missed_periods(self.last_t_s, frame.t_s, self.filter.config().dt_s);
        for _ in 0..missed {
            self.filter.step(&FusionInput {
                specific_force_body_m_s2: self.last_f,
                gyro_body_rad_s: self.last_w,
                gps_ned_m: None,
                gps_vel_ned_m_s: None,
                attitude_rad: None,
            })?;
        }
        self.last_t_s = Some(frame.t_s);
        let imu = &frame.imu;
        let attitude = frame.mag_body.and_then(|m| {
            let obs = [
                gravity_observation(self.gravity_weight, &imu.specific_force_body_m_s2, None),
                VectorObservation::new(1.0, m, self.field_ned),
            ];
            q_method(&obs).ok().map(|sol| sol.euler())
        });
        let gps = frame.gps.filter(|g| g.is_valid());
        self.filter.step(&FusionInput {
            specific_force_body_m_s2: self.last_f,
            gyro_body_rad_s: self.last_w,
            gps_ned_m: gps.map(|g| g.position_ned_m),
            gps_vel_ned_m_s: gps.and_then(|g| g.velocity_ned_m_s),
            attitude_rad: attitude,
        })?;
        self.last_f = imu.specific_force_body_m_s2;
        self.last_w = imu.gyro_body_rad_s;
        self.attitude_fix = attitude.is_some();
        let gate = self.filter.last_gate();
        // fused: the position passed the gate (a velocity alone does not
        // hold the position: a fix whose position jumped counts as refused)
        self.gps_fused = gps.is_some() && !gate.position_rejected;
        let s = *self.filter.state();
        let vel = Vector3::new(s[3], s[4], s[5]);
        let v_body = EulerTrig::new(s[6], s[7], s[8]).ned_from_body().transpose() * vel;
        let mut y = MeasuredStates::zeros();
        for i in 0..3 {
            y[i] = s[6 + i];
            y[3 + i] = v_body[i];
            y[6 + i] = imu.gyro_body_rad_s[i];
        }
        Ok(y)
    }

    /// The navigation solution after the last [`NavigationFilter::step`].
    #[inline]
    pub fn solution(&self) -> NavigationSolution {
        let s = self.filter.state();
        let p = self.filter.covariance();
        NavigationSolution {
            position_ned_m: Vector3::new(s[0], s[1], s[2]),
            velocity_ned_m_s: Vector3::new(s[3], s[4], s[5]),
            attitude_rad: Vector3::new(s[6], s[7], s[8]),
            position_sigma_m: Vector3::new(p[(0, 0)], p[(1, 1)], p[(2, 2)]).map(f64::sqrt),
            attitude_fix: self.attitude_fix,
            gps_fused: self.gps_fused,
            imu_bias: None,
            rejected_updates: self.filter.rejected_updates(),
        }
    }

    /// The fusion filter (its state and covariance).
    pub fn filter(&self) -> &FusionFilter {
        &self.filter
    }
}
