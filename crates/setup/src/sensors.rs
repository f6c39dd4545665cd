//! The sensors' configuration (`[sensors]` of a scenario and of
//! `onboard.toml`): the IMU, magnetometer and GPS figures the simulator's
//! sensor models draw from and the navigation's measurement model assumes
//! (noise densities, bias walks, ranges, the local magnetic field, the GPS
//! rate, accuracy and latency), checked field by field.
//!
//! The models that sample these figures live in the simulator; the flight
//! software reads the same figures through [`sensor_noise`] and
//! [`imu_noise`].

use crate::vibration::{StageConfig, VibrationConfig};
use helicon_core::eskf::ImuNoise;
use helicon_core::sensor::SensorNoise;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Standard gravity for unit conversions of datasheet values (m/s²).
pub const G0_M_S2: f64 = 9.80665;

/// Error loading or validating a sensor configuration: the toolkit's one
/// configuration error shape.
pub type SensorConfigError = helicon_config::ConfigError;

/// One inertial sensor axis triad (accelerometer or gyro). Units: the
/// sensor's unit `u` (m/s² or rad/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InertialConfig {
    /// White-noise density (u/√Hz).
    pub noise_density: f64,
    /// Bias random walk (u/√s).
    pub bias_random_walk: f64,
    /// Standard deviation of the initial (turn-on) bias (u).
    pub initial_bias_sigma: f64,
    /// Standard deviation of the per-axis scale-factor error (dimensionless).
    pub scale_factor_sigma: f64,
    /// Saturation: output limited to ±range (u).
    pub range: f64,
    /// Quantisation step (u); 0 disables.
    pub resolution: f64,
}

/// IMU (accelerometer + gyro) configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImuConfig {
    /// Sample rate (Hz); the sensor suite is stepped at this rate.
    pub rate_hz: f64,
    /// Accelerometer (m/s²).
    pub accel: InertialConfig,
    /// Gyro (rad/s).
    pub gyro: InertialConfig,
    /// Vibration at the sensor (`[imu.vibration]`, off by default: the
    /// model above exactly).
    pub vibration: VibrationConfig,
    /// The accelerometer's internal stages (used with vibration on).
    pub accel_stage: StageConfig,
    /// The gyro's internal stages (used with vibration on).
    pub gyro_stage: StageConfig,
}

impl Default for ImuConfig {
    /// A typical hobby MEMS IMU (MPU-6000 class) at 400 Hz (the thesis's
    /// control rate): accelerometer 400 µg/√Hz, ±10 g (Appendix A), 16 bit;
    /// gyro 0.005 °/s/√Hz, ±500 °/s, 16 bit.
    fn default() -> Self {
        let acc_range = 10.0 * G0_M_S2;
        let gyro_range = 500f64.to_radians();
        Self {
            rate_hz: 400.0,
            accel: InertialConfig {
                noise_density: 400e-6 * G0_M_S2,
                bias_random_walk: 3e-4,
                initial_bias_sigma: 0.05,
                scale_factor_sigma: 0.005,
                range: acc_range,
                resolution: 2.0 * acc_range / 65536.0,
            },
            gyro: InertialConfig {
                noise_density: 0.005f64.to_radians(),
                bias_random_walk: 2e-5,
                initial_bias_sigma: 0.5f64.to_radians(),
                scale_factor_sigma: 0.005,
                range: gyro_range,
                resolution: 2.0 * gyro_range / 65536.0,
            },
            vibration: VibrationConfig::default(),
            accel_stage: StageConfig::default(),
            gyro_stage: StageConfig::default(),
        }
    }
}

/// IMU presets with figures from the manufacturers' datasheets
/// (the project's navigation-eskf documentation reads each figure).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ImuPreset {
    /// Hobby class, InvenSense MPU-6000/MPU-6050 Product Specification:
    /// gyro 0.005 °/s/√Hz, accelerometer 400 µg/√Hz, zero-g offset ±50 mg
    /// (σ 25 mg), sensitivity tolerance ±3 % (σ 1 %); the gyro's ±20 °/s
    /// raw zero-rate offset is taken out by the usual calibration at rest,
    /// leaving the few tenths of a degree per second of temperature drift
    /// (σ 0.3 °/s). No bias random walk is specified: the class's typical
    /// Allan figures (2e-5 rad/s/√s, 3e-4 m/s²/√s).
    Mpu6000,
    /// Better hobby class, TDK InvenSense ICM-20602 datasheet: gyro
    /// 0.004 °/s/√Hz, accelerometer 100 µg/√Hz, zero-rate offset ±1 °/s
    /// (σ 0.5 °/s), zero-g offset ±25 mg (σ 12.5 mg), sensitivity ±1 %
    /// (σ 0.5 %).
    Icm20602,
    /// Industrial class, Analog Devices ADIS16470 data sheet: gyro angle
    /// random walk 0.34 °/√h (the white noise used; the broadband rate noise
    /// density is 0.008 °/s/√Hz),
    /// 8 °/h in-run bias stability, velocity random walk 0.037 m/s/√h,
    /// 13 µg in-run bias stability, factory calibrated (bias σ 0.05 °/s and
    /// 2 mg, sensitivity σ 0.1 %); the random walks reach the in-run bias
    /// stability in ~100 s.
    Adis16470,
}

impl ImuConfig {
    /// The IMU of a datasheet preset at `rate_hz`, ±10 g / ±500 °/s, 16 bit.
    pub fn preset(preset: ImuPreset, rate_hz: f64) -> Self {
        let base = ImuConfig {
            rate_hz,
            ..ImuConfig::default()
        };
        let deg = |v: f64| v.to_radians();
        let mg = |v: f64| v * 1e-3 * G0_M_S2;
        let (acc, gyro) = match preset {
            ImuPreset::Mpu6000 => (
                (mg(0.4), 3e-4, mg(25.0), 0.01),
                (deg(0.005), 2e-5, deg(0.3), 0.01),
            ),
            ImuPreset::Icm20602 => (
                (mg(0.1), 3e-4, mg(12.5), 0.005),
                (deg(0.004), 2e-5, deg(0.5), 0.005),
            ),
            ImuPreset::Adis16470 => (
                (0.037 / 60.0, mg(0.013) / 10.0, mg(2.0), 0.001),
                (deg(0.34 / 60.0), deg(8.0 / 3600.0) / 10.0, deg(0.05), 0.001),
            ),
        };
        let set = |c: InertialConfig, (n, rw, b, sf): (f64, f64, f64, f64)| InertialConfig {
            noise_density: n,
            bias_random_walk: rw,
            initial_bias_sigma: b,
            scale_factor_sigma: sf,
            ..c
        };
        ImuConfig {
            accel: set(base.accel, acc),
            gyro: set(base.gyro, gyro),
            ..base
        }
    }
}

/// Magnetometer configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MagConfig {
    /// Sample rate (Hz); must divide the IMU rate.
    pub rate_hz: f64,
    /// White-noise standard deviation per axis (field units).
    pub noise_sigma: f64,
    /// Local field in NED (field units), default thesis (13.14).
    pub field_ned: [f64; 3],
}

impl Default for MagConfig {
    /// 100 Hz, 2 mG noise (HMC5883-class), thesis field (13.14) in gauss.
    fn default() -> Self {
        Self {
            rate_hz: 100.0,
            noise_sigma: 0.002,
            field_ned: [0.153, 0.008, -0.438],
        }
    }
}

/// GPS configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GpsConfig {
    /// Fix rate (Hz), 1–10.
    pub rate_hz: f64,
    /// Horizontal noise σ per axis (m).
    pub horizontal_sigma_m: f64,
    /// Vertical noise σ (m).
    pub vertical_sigma_m: f64,
    /// Delay between a fix's epoch and its delivery (s), ≥ 0.
    pub latency_s: f64,
    /// Probability that a fix is lost, 0–1.
    pub dropout_probability: f64,
    /// Deliver the receiver's (Doppler) velocity with each fix.
    pub velocity_output: bool,
    /// Velocity noise σ per horizontal axis (m/s); twice that vertically.
    pub velocity_sigma_m_s: f64,
    /// A GPS outage: no fix whose epoch falls in it (off by default).
    pub outage: Option<GpsOutage>,
}

/// A window without GPS fixes (`[sensors.gps.outage]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GpsOutage {
    /// Start of the outage (s).
    pub start_s: f64,
    /// Length of the outage (s).
    pub duration_s: f64,
}

impl Default for GpsConfig {
    /// u-blox M8-class hobby GPS: 5 Hz, 1.5 m / 3 m, 100 ms latency, 2% dropouts.
    fn default() -> Self {
        Self {
            rate_hz: 5.0,
            horizontal_sigma_m: 1.5,
            vertical_sigma_m: 3.0,
            latency_s: 0.1,
            dropout_probability: 0.02,
            velocity_output: true,
            velocity_sigma_m_s: 0.05,
            outage: None,
        }
    }
}

/// Full sensor configuration (TOML).
///
/// ```toml
/// seed = 42
/// [imu]
/// rate_hz = 400.0
/// [imu.accel]
/// noise_density = 0.0039
/// # ... all six fields of an InertialConfig
/// [gps]
/// rate_hz = 5.0
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// Seed of the sensor RNG streams.
    pub seed: u64,
    /// IMU.
    pub imu: ImuConfig,
    /// Magnetometer.
    pub mag: MagConfig,
    /// GPS.
    pub gps: GpsConfig,
}

impl SensorConfig {
    /// Parse TOML text; `file` names the source in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, SensorConfigError> {
        let cfg: Self = toml::from_str(text).map_err(|e| SensorConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        cfg.validate(file)?;
        Ok(cfg)
    }

    /// This configuration as TOML (e.g. the defaults, as a starting point for
    /// a user's own sensors).
    pub fn to_toml(&self) -> Result<String, SensorConfigError> {
        toml::to_string(self).map_err(|e| SensorConfigError::Parse {
            file: "<serialise>".to_string(),
            message: e.to_string(),
        })
    }

    /// Load and validate a TOML file.
    pub fn from_file(path: &Path) -> Result<Self, SensorConfigError> {
        let (file, text) = helicon_config::ConfigError::read_file(path)?;
        Self::from_toml_str(&text, &file)
    }

    /// Check every field's range; `file` names the source in errors.
    pub fn validate(&self, file: &str) -> Result<(), SensorConfigError> {
        let bad = |field: String, value: f64, allowed: &'static str| {
            SensorConfigError::invalid(file, field, value, format!("allowed: {allowed}"))
        };
        let nonneg = |field: String, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(bad(field, v, "finite, >= 0"))
            }
        };
        if !(self.imu.rate_hz.is_finite()
            && self.imu.rate_hz >= 1.0
            && self.imu.rate_hz <= 10_000.0)
        {
            return Err(bad("imu.rate_hz".into(), self.imu.rate_hz, "1..=10000"));
        }
        for (name, c) in [("imu.accel", &self.imu.accel), ("imu.gyro", &self.imu.gyro)] {
            nonneg(format!("{name}.noise_density"), c.noise_density)?;
            nonneg(format!("{name}.bias_random_walk"), c.bias_random_walk)?;
            nonneg(format!("{name}.initial_bias_sigma"), c.initial_bias_sigma)?;
            nonneg(format!("{name}.scale_factor_sigma"), c.scale_factor_sigma)?;
            nonneg(format!("{name}.resolution"), c.resolution)?;
            if !(c.range.is_finite() && c.range > 0.0) {
                return Err(bad(format!("{name}.range"), c.range, "> 0"));
            }
        }
        let ratio = self.imu.rate_hz / self.mag.rate_hz;
        if !(self.mag.rate_hz.is_finite()
            && self.mag.rate_hz > 0.0
            && ratio >= 1.0
            && (ratio - ratio.round()).abs() < 1e-9)
        {
            return Err(bad(
                "mag.rate_hz".into(),
                self.mag.rate_hz,
                "> 0 and dividing imu.rate_hz",
            ));
        }
        nonneg("mag.noise_sigma".into(), self.mag.noise_sigma)?;
        let f = self.mag.field_ned;
        if !f.iter().all(|v| v.is_finite()) || f.iter().all(|v| *v == 0.0) {
            return Err(bad("mag.field_ned".into(), f[0], "finite, non-zero vector"));
        }
        if !(self.gps.rate_hz.is_finite() && (1.0..=10.0).contains(&self.gps.rate_hz)) {
            return Err(bad("gps.rate_hz".into(), self.gps.rate_hz, "1..=10"));
        }
        nonneg("gps.horizontal_sigma_m".into(), self.gps.horizontal_sigma_m)?;
        nonneg("gps.vertical_sigma_m".into(), self.gps.vertical_sigma_m)?;
        nonneg("gps.velocity_sigma_m_s".into(), self.gps.velocity_sigma_m_s)?;
        if !(self.gps.latency_s.is_finite() && (0.0..=2.0).contains(&self.gps.latency_s)) {
            return Err(bad("gps.latency_s".into(), self.gps.latency_s, "0..=2"));
        }
        if let Some(o) = &self.gps.outage {
            nonneg("gps.outage.start_s".into(), o.start_s)?;
            nonneg("gps.outage.duration_s".into(), o.duration_s)?;
        }
        let p = self.gps.dropout_probability;
        if !(p.is_finite() && (0.0..=1.0).contains(&p)) {
            return Err(bad("gps.dropout_probability".into(), p, "0..=1"));
        }
        let imu = &self.imu;
        imu.vibration
            .validate([&imu.accel_stage, &imu.gyro_stage], imu.rate_hz, file)
    }
}

/// The noise figures of a sensor configuration, as the navigation needs
/// them, in local gravity `gravity_m_s2`.
pub fn sensor_noise(config: &SensorConfig, gravity_m_s2: f64) -> SensorNoise {
    let g = &config.gps;
    SensorNoise {
        gps_sigma_m: Vector3::new(
            g.horizontal_sigma_m,
            g.horizontal_sigma_m,
            g.vertical_sigma_m,
        ),
        gps_vel_sigma_m_s: Vector3::new(
            g.velocity_sigma_m_s,
            g.velocity_sigma_m_s,
            2.0 * g.velocity_sigma_m_s,
        ),
        mag_field_ned: Vector3::from(config.mag.field_ned),
        gravity_m_s2,
    }
}

/// The IMU and magnetometer figures of a sensor configuration, as the ESKF
/// assumes them (the filter is tuned from the sensors' datasheet figures).
pub fn imu_noise(config: &SensorConfig) -> ImuNoise {
    let (a, g) = (&config.imu.accel, &config.imu.gyro);
    ImuNoise {
        accel_noise_density: a.noise_density,
        accel_bias_walk: a.bias_random_walk,
        // the scale-factor error on the 1 g the accelerometer carries in hover
        // acts as a bias: the filter's initial bias σ covers both
        accel_bias_sigma: a.initial_bias_sigma.hypot(a.scale_factor_sigma * G0_M_S2),
        gyro_noise_density: g.noise_density,
        gyro_bias_walk: g.bias_random_walk,
        gyro_bias_sigma: g.initial_bias_sigma,
        mag_sigma: config.mag.noise_sigma,
    }
}
