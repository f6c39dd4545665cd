//! Sensor models: accelerometer, gyro, magnetometer and GPS, configured in TOML
//! with defaults for a typical hobby IMU/GPS, one seeded RNG stream each.
//!
//! Inertial axis model (per axis, body FRD, sampled at `imu.rate_hz`):
//! `y = Q_res(sat_range((1 + s) x + b + n))` with `s` a scale-factor error
//! drawn once per run, `b` a bias that starts at a random value and random-walks
//! (`b += σ_rw √dt ν`), `n` white noise of density `N` (σ = N √rate),
//! saturation at ±range (accelerometer ±10 g, the IMU fitted after the
//! vibration problem of Appendix A / §3) and quantisation to the resolution.
//! The accelerometer measures specific force `f = R_be (a − g)`; the gyro the
//! body rates. Magnetometer: `R_be m_ned + n` at `mag.rate_hz` (a divisor of
//! the IMU rate). GPS: NED position + white noise at 1–10 Hz, delivered
//! `latency_s` after its epoch, each fix dropped with probability
//! `dropout_probability`. GPS noise is white per fix here (real receivers show
//! slowly correlated errors; not modelled).

use crate::trajectory::TruthSample;
use crate::vibration::{ChainSetup, RotorSpeeds, StageDiagnostics, VibrationChain};
use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame};
use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::VecDeque;

pub use helicon_setup::sensors::{
    G0_M_S2, GpsConfig, GpsOutage, ImuConfig, ImuPreset, InertialConfig, MagConfig, SensorConfig,
    SensorConfigError,
};

/// One inertial triad's output stage: scale factor, bias (turn-on + random
/// walk), white noise, quantisation and output range.
#[derive(Debug, Clone)]
pub(crate) struct InertialState {
    cfg: InertialConfig,
    scale: Vector3<f64>,
    bias: Vector3<f64>,
}

impl InertialState {
    pub(crate) fn new(cfg: InertialConfig, rng: &mut ChaCha8Rng) -> Self {
        let mut n = || -> f64 { StandardNormal.sample(rng) };
        let scale = Vector3::new(n(), n(), n()) * cfg.scale_factor_sigma;
        let bias = Vector3::new(n(), n(), n()) * cfg.initial_bias_sigma;
        Self { cfg, scale, bias }
    }

    pub(crate) fn measure(
        &mut self,
        x: &Vector3<f64>,
        rate_hz: f64,
        rng: &mut ChaCha8Rng,
    ) -> Vector3<f64> {
        let dt = 1.0 / rate_hz;
        let sigma_white = self.cfg.noise_density * rate_hz.sqrt();
        let mut y = Vector3::zeros();
        for i in 0..3 {
            let white: f64 = StandardNormal.sample(rng);
            let v = (1.0 + self.scale[i]) * x[i] + self.bias[i] + sigma_white * white;
            let q = if self.cfg.resolution > 0.0 {
                (v / self.cfg.resolution).round() * self.cfg.resolution
            } else {
                v
            };
            y[i] = q.clamp(-self.cfg.range, self.cfg.range);
            let walk: f64 = StandardNormal.sample(rng);
            self.bias[i] += self.cfg.bias_random_walk * dt.sqrt() * walk;
        }
        y
    }
}

/// The sensor suite: step it once per IMU sample with the truth.
#[derive(Debug, Clone)]
pub struct SensorSuite {
    config: SensorConfig,
    gravity_m_s2: f64,
    accel: InertialState,
    gyro: InertialState,
    rng_imu: ChaCha8Rng,
    rng_mag: ChaCha8Rng,
    rng_gps: ChaCha8Rng,
    step_index: u64,
    mag_every: u64,
    next_gps_epoch_s: f64,
    pending_gps: VecDeque<(f64, Vector3<f64>, Vector3<f64>)>,
    rng_gps_vel: ChaCha8Rng,
    /// The vibration and the sensors' internal stages (vibration on).
    vibration: Option<VibrationChain>,
}

/// The vibration chain of `config` at `rotor`, its random phases from the
/// sensor seed's own stream (the other streams are untouched).
fn vibration_chain(
    config: &SensorConfig,
    rotor: RotorSpeeds,
) -> Result<Option<VibrationChain>, SensorConfigError> {
    let imu = &config.imu;
    if !imu.vibration.enabled {
        return Ok(None);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    rng.set_stream(14);
    let setup = ChainSetup {
        imu_rate_hz: imu.rate_hz,
        output_range: (imu.accel.range, imu.gyro.range),
        rotor,
    };
    let speeds = [
        rotor.main_rad_s,
        rotor.tail_rad_s,
        rotor.main_blades,
        rotor.tail_blades,
    ];
    if !speeds.iter().all(|v| v.is_finite() && *v >= 0.0) {
        return Err(SensorConfigError::invalid(
            "<parameters>",
            "main_rotor.omega_rad_s",
            rotor.main_rad_s,
            "rotor speeds and blade counts must be finite and >= 0",
        ));
    }
    VibrationChain::new(
        &imu.vibration,
        &imu.accel_stage,
        &imu.gyro_stage,
        &setup,
        || rng.random::<f64>(),
    )
    .map(Some)
    .ok_or_else(|| {
        SensorConfigError::invalid(
            "<sensor config>",
            "imu.vibration",
            imu.rate_hz,
            "a stage frequency is out of range at this IMU rate",
        )
    })
}

impl SensorSuite {
    /// A new suite in local gravity `gravity_m_s2` (the helicopter's
    /// `environment.g_m_s2`; config validated, errors name the field).
    pub fn new(config: SensorConfig, gravity_m_s2: f64) -> Result<Self, SensorConfigError> {
        config.validate("<sensor config>")?;
        if !(gravity_m_s2.is_finite() && gravity_m_s2 > 0.0) {
            return Err(SensorConfigError::invalid(
                "<parameters>",
                "environment.g_m_s2",
                gravity_m_s2,
                "must be finite and > 0",
            ));
        }
        let stream = |s: u64| {
            let mut r = ChaCha8Rng::seed_from_u64(config.seed);
            r.set_stream(s);
            r
        };
        let mut rng_imu = stream(10);
        let accel = InertialState::new(config.imu.accel, &mut rng_imu);
        let gyro = InertialState::new(config.imu.gyro, &mut rng_imu);
        Ok(Self {
            config,
            gravity_m_s2,
            accel,
            gyro,
            rng_imu,
            rng_mag: stream(11),
            rng_gps: stream(12),
            step_index: 0,
            mag_every: (config.imu.rate_hz / config.mag.rate_hz).round() as u64,
            next_gps_epoch_s: 0.0,
            // room for the fixes in flight during the latency, so sampling
            // does not allocate
            pending_gps: VecDeque::with_capacity(
                (config.gps.latency_s * config.gps.rate_hz).ceil() as usize + 4,
            ),
            rng_gps_vel: stream(13),
            vibration: vibration_chain(&config, RotorSpeeds::default())?,
        })
    }

    /// The suite with the vibration frequencies of these rotors (the
    /// helicopter's; default the Bergen Twin's). No effect with vibration off.
    pub fn with_rotor(mut self, rotor: RotorSpeeds) -> Result<Self, SensorConfigError> {
        self.vibration = vibration_chain(&self.config, rotor)?;
        Ok(self)
    }

    /// What the sensors' mechanical stages saw over the last sample (truth,
    /// for analysis); `None` with vibration off.
    pub fn stage_diagnostics(&self) -> Option<StageDiagnostics> {
        self.vibration.as_ref().map(VibrationChain::diagnostics)
    }

    /// The configuration.
    pub fn config(&self) -> &SensorConfig {
        &self.config
    }

    /// Local gravity the accelerometer senses (m/s²).
    pub fn gravity_m_s2(&self) -> f64 {
        self.gravity_m_s2
    }

    /// IMU sample period (s).
    pub fn dt_s(&self) -> f64 {
        1.0 / self.config.imu.rate_hz
    }

    /// Current accelerometer and gyro biases (body; truth for analysis).
    pub fn biases(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.accel.bias, self.gyro.bias)
    }

    /// Produce the sensor readings for the truth at `truth.t_s` (call at the
    /// IMU rate with increasing times).
    pub fn sample(&mut self, truth: &TruthSample) -> SensorFrame {
        let rate = self.config.imu.rate_hz;
        // one rotation per sample for the accelerometer and the magnetometer
        let body_from_ned = truth.body_from_ned();
        let f_true =
            body_from_ned * (truth.acc_ned_m_s2 - Vector3::new(0.0, 0.0, self.gravity_m_s2));
        let (f_sensed, omega_sensed) = match self.vibration.as_mut() {
            Some(chain) => chain.step(&f_true, &truth.omega_body_rad_s),
            None => (f_true, truth.omega_body_rad_s),
        };
        let specific_force = self.accel.measure(&f_sensed, rate, &mut self.rng_imu);
        let gyro = self.gyro.measure(&omega_sensed, rate, &mut self.rng_imu);
        let mag_body = if self.step_index % self.mag_every == 0 {
            let m = body_from_ned * Vector3::from(self.config.mag.field_ned);
            let s = self.config.mag.noise_sigma;
            let mut n = || -> f64 { StandardNormal.sample(&mut self.rng_mag) };
            Some(m + Vector3::new(n(), n(), n()) * s)
        } else {
            None
        };
        // GPS epochs: take the fix when the epoch is reached (to within half an
        // IMU sample), deliver it `latency` later.
        let half = 0.5 / rate;
        let gps_dt = 1.0 / self.config.gps.rate_hz;
        while truth.t_s + half >= self.next_gps_epoch_s {
            let epoch = self.next_gps_epoch_s;
            self.next_gps_epoch_s += gps_dt;
            let dropped = self.rng_gps.random::<f64>() < self.config.gps.dropout_probability;
            let g = &self.config.gps;
            let mut n = || -> f64 { StandardNormal.sample(&mut self.rng_gps) };
            let noise = Vector3::new(
                n() * g.horizontal_sigma_m,
                n() * g.horizontal_sigma_m,
                n() * g.vertical_sigma_m,
            );
            // velocity noise from its own stream: position draws are unchanged
            let sv = g.velocity_sigma_m_s;
            let mut nv = || -> f64 { StandardNormal.sample(&mut self.rng_gps_vel) };
            let vel_noise = Vector3::new(nv() * sv, nv() * sv, 2.0 * nv() * sv);
            let in_outage = g
                .outage
                .is_some_and(|o| epoch >= o.start_s && epoch < o.start_s + o.duration_s);
            if !dropped && !in_outage {
                self.pending_gps.push_back((
                    epoch,
                    truth.pos_ned_m + noise,
                    truth.vel_ned_m_s + vel_noise,
                ));
            }
        }
        let mut gps = None;
        while let Some((epoch, _, _)) = self.pending_gps.front() {
            if truth.t_s + half >= epoch + self.config.gps.latency_s {
                gps = self.pending_gps.pop_front();
            } else {
                break;
            }
        }
        self.step_index += 1;
        let velocity_output = self.config.gps.velocity_output;
        SensorFrame {
            t_s: truth.t_s,
            imu: ImuSample {
                specific_force_body_m_s2: specific_force,
                gyro_body_rad_s: gyro,
            },
            mag_body,
            gps: gps.map(|(epoch_s, position_ned_m, velocity)| GpsFix {
                epoch_s,
                fix: GpsFixType::Fix3d,
                position_ned_m,
                velocity_ned_m_s: velocity_output.then_some(velocity),
            }),
        }
    }
}
