//! IMU health: vibration level and likely hidden accelerometer saturation,
//! estimated from what the accelerometer's output still shows (thesis
//! §3.3.2, Appendix A).
//!
//! A sensing element clipped by vibration above its internal filter's
//! cut-off is invisible at the output: the high-band energy is filtered
//! away. Two things remain observable, and this monitor tracks them on the
//! flight computer's IMU samples (allocation-free, a few multiplications per
//! sample):
//!
//! - **the mean specific force against gravity.** Clipping moves the mean of
//!   each axis toward zero, so the running mean of the specific force
//!   (time constant `mean_time_constant_s`) falls short of local gravity. In
//!   hover and steady flight `|mean f| = g`; a manoeuvre's own mean
//!   acceleration over the window also moves it (a horizontal 2 m/s² by
//!   0.2 m/s², a vertical one by its full size), hence the tolerance;
//! - **the in-band residue**: the part of the output above
//!   `residue_corner_hz` (vibration at rotor frequencies inside the filter's
//!   pass band, plus noise), as an RMS over `residue_time_constant_s`.
//!
//! [`ImuHealth::flags`] combine them: [`ImuHealth::VIBRATION`] (residue above
//! its threshold), [`ImuHealth::NEAR_RANGE`] (the output peaks within 10 %
//! of the range: clipping visible at the output), [`ImuHealth::GRAVITY_DEFICIT`]
//! (the mean is short of gravity by more than the tolerance: likely hidden
//! mechanical saturation, the thesis's first-flight failure).

use crate::sensor::ImuSample;
use nalgebra::Vector3;

/// Settings of the [`ImuHealthMonitor`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ImuHealthConfig {
    /// Local gravity (m/s²): the helicopter's parameter.
    pub gravity_m_s2: f64,
    /// IMU sample period (s).
    pub sample_time_s: f64,
    /// Accelerometer output range (m/s²).
    pub accel_range_m_s2: f64,
    /// Time constant of the running mean of the specific force (s).
    pub mean_time_constant_s: f64,
    /// Corner above which the output counts as vibration residue (Hz).
    pub residue_corner_hz: f64,
    /// Time constant of the residue's mean square (s).
    pub residue_time_constant_s: f64,
    /// Gravity deficit beyond which hidden saturation is suspected (m/s²).
    pub gravity_tolerance_m_s2: f64,
    /// Residue RMS above which vibration is flagged (m/s²).
    pub vibration_threshold_m_s2: f64,
}

impl ImuHealthConfig {
    /// Defaults for a helicopter IMU: 2 s mean, residue above 5 Hz over 1 s,
    /// tolerance 0.5 m/s² (0.05 g), vibration threshold 1 m/s² (0.1 g).
    pub fn new(gravity_m_s2: f64, sample_time_s: f64, accel_range_m_s2: f64) -> Self {
        ImuHealthConfig {
            gravity_m_s2,
            sample_time_s,
            accel_range_m_s2,
            mean_time_constant_s: 2.0,
            residue_corner_hz: 5.0,
            residue_time_constant_s: 1.0,
            gravity_tolerance_m_s2: 0.5,
            vibration_threshold_m_s2: 1.0,
        }
    }

    /// The first setting that is not finite and positive, by name.
    pub fn first_invalid(&self) -> Option<&'static str> {
        [
            ("gravity_m_s2", self.gravity_m_s2),
            ("sample_time_s", self.sample_time_s),
            ("accel_range_m_s2", self.accel_range_m_s2),
            ("mean_time_constant_s", self.mean_time_constant_s),
            ("residue_corner_hz", self.residue_corner_hz),
            ("residue_time_constant_s", self.residue_time_constant_s),
            ("gravity_tolerance_m_s2", self.gravity_tolerance_m_s2),
            ("vibration_threshold_m_s2", self.vibration_threshold_m_s2),
        ]
        .into_iter()
        .find(|(_, v)| !(v.is_finite() && *v > 0.0))
        .map(|(name, _)| name)
    }
}

/// The monitor's estimate after a sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImuHealth {
    /// |running mean of the specific force| (m/s²).
    pub mean_specific_force_m_s2: f64,
    /// |mean f| − g (m/s²): negative when short of gravity.
    pub gravity_residual_m_s2: f64,
    /// RMS of the in-band residue, all three axes (m/s²).
    pub vibration_rms_m_s2: f64,
    /// Decaying peak of the largest axis over the output range (0..1).
    pub peak_fraction: f64,
    /// The flags ([`ImuHealth::VIBRATION`], …); 0 is healthy.
    pub flags: u8,
}

impl ImuHealth {
    /// In-band vibration above the threshold.
    pub const VIBRATION: u8 = 1;
    /// The output peaks within 10 % of its range (visible clipping).
    pub const NEAR_RANGE: u8 = 2;
    /// The mean specific force is short of gravity beyond the tolerance:
    /// likely hidden mechanical saturation.
    pub const GRAVITY_DEFICIT: u8 = 4;
    /// The monitor has not yet seen one mean time constant of samples (the
    /// other flags are held off).
    pub const SETTLING: u8 = 8;

    /// True when `flag` is set.
    pub fn has(&self, flag: u8) -> bool {
        self.flags & flag != 0
    }
}

/// The running estimator of [`ImuHealth`]; see the module documentation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuHealthMonitor {
    cfg: ImuHealthConfig,
    alpha_mean: f64,
    alpha_corner: f64,
    alpha_residue: f64,
    peak_decay: f64,
    mean: Vector3<f64>,
    low: Vector3<f64>,
    residue_ms: f64,
    peak: f64,
    samples: u64,
    settle_samples: u64,
    last: ImuHealth,
}

impl ImuHealthMonitor {
    /// A monitor; `None` when a setting is not finite and positive
    /// ([`ImuHealthConfig::first_invalid`] names it).
    pub fn new(cfg: ImuHealthConfig) -> Option<Self> {
        if cfg.first_invalid().is_some() {
            return None;
        }
        let ts = cfg.sample_time_s;
        let alpha = |tau: f64| 1.0 - (-ts / tau).exp();
        Some(ImuHealthMonitor {
            cfg,
            alpha_mean: alpha(cfg.mean_time_constant_s),
            alpha_corner: alpha(1.0 / (2.0 * std::f64::consts::PI * cfg.residue_corner_hz)),
            alpha_residue: alpha(cfg.residue_time_constant_s),
            // the peak halves in one residue time constant
            peak_decay: 0.5f64.powf(ts / cfg.residue_time_constant_s),
            mean: Vector3::zeros(),
            low: Vector3::zeros(),
            residue_ms: 0.0,
            peak: 0.0,
            samples: 0,
            settle_samples: (cfg.mean_time_constant_s / ts).ceil() as u64,
            last: ImuHealth::default(),
        })
    }

    /// The settings.
    pub fn config(&self) -> &ImuHealthConfig {
        &self.cfg
    }

    /// Take one IMU sample; returns the updated estimate. A non-finite sample
    /// is skipped (the flight computer reports it) and the last estimate kept.
    pub fn update(&mut self, imu: &ImuSample) -> ImuHealth {
        let f = &imu.specific_force_body_m_s2;
        if !f.iter().all(|v| v.is_finite()) {
            return self.last;
        }
        if self.samples == 0 {
            self.mean = *f;
            self.low = *f;
        }
        self.samples += 1;
        // the plain average of the samples so far until it is as long as
        // the time constant: the first sample's vibration is not kept
        let alpha = self.alpha_mean.max(1.0 / self.samples as f64);
        self.mean += (f - self.mean) * alpha;
        self.low += (f - self.low) * self.alpha_corner;
        let residue = f - self.low;
        self.residue_ms += (residue.norm_squared() - self.residue_ms) * self.alpha_residue;
        let biggest = f.amax() / self.cfg.accel_range_m_s2;
        self.peak = biggest.max(self.peak * self.peak_decay);
        let mean_norm = self.mean.norm();
        let residual = mean_norm - self.cfg.gravity_m_s2;
        let rms = self.residue_ms.sqrt();
        let mut flags = 0;
        if self.samples < self.settle_samples {
            flags |= ImuHealth::SETTLING;
        } else {
            if rms > self.cfg.vibration_threshold_m_s2 {
                flags |= ImuHealth::VIBRATION;
            }
            if self.peak >= 0.9 {
                flags |= ImuHealth::NEAR_RANGE;
            }
            if residual < -self.cfg.gravity_tolerance_m_s2 {
                flags |= ImuHealth::GRAVITY_DEFICIT;
            }
        }
        self.last = ImuHealth {
            mean_specific_force_m_s2: mean_norm,
            gravity_residual_m_s2: residual,
            vibration_rms_m_s2: rms,
            peak_fraction: self.peak,
            flags,
        };
        self.last
    }

    /// The last estimate.
    pub fn health(&self) -> ImuHealth {
        self.last
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(f: Vector3<f64>) -> ImuSample {
        ImuSample {
            specific_force_body_m_s2: f,
            gyro_body_rad_s: Vector3::zeros(),
        }
    }

    fn run(f: impl Fn(f64) -> Vector3<f64>) -> ImuHealth {
        let mut m = ImuHealthMonitor::new(ImuHealthConfig::new(9.82, 0.0025, 10.0 * 9.82)).unwrap();
        let mut h = ImuHealth::default();
        for k in 0..4000 {
            h = m.update(&sample(f(k as f64 * 0.0025)));
        }
        h
    }

    #[test]
    fn at_rest_healthy() {
        let h = run(|_| Vector3::new(0.0, 0.0, -9.82));
        assert_eq!(h.flags, 0);
        assert!(h.gravity_residual_m_s2.abs() < 1e-9);
        assert!(h.vibration_rms_m_s2 < 1e-9);
    }

    #[test]
    fn in_band_vibration_is_measured() {
        // 2 m/s² at 16 Hz on z: RMS 2/√2 (the 5 Hz first-order high-pass
        // passes 95 % of it)
        let h = run(|t| {
            Vector3::new(
                0.0,
                0.0,
                -9.82 + 2.0 * (2.0 * std::f64::consts::PI * 16.0 * t).sin(),
            )
        });
        assert!(h.has(ImuHealth::VIBRATION), "{h:?}");
        assert!(
            (h.vibration_rms_m_s2 - 2.0 / 2f64.sqrt()).abs() < 0.15,
            "{h:?}"
        );
        assert!(!h.has(ImuHealth::GRAVITY_DEFICIT));
    }

    #[test]
    fn a_shifted_mean_is_a_gravity_deficit() {
        // the thesis's ±2 g part at 2 g of hidden vibration: mean −0.78 g
        let h = run(|_| Vector3::new(0.0, 0.0, -0.78 * 9.82));
        assert!(h.has(ImuHealth::GRAVITY_DEFICIT), "{h:?}");
        assert!(!h.has(ImuHealth::VIBRATION));
        assert!((h.gravity_residual_m_s2 + 0.22 * 9.82).abs() < 1e-6);
    }

    #[test]
    fn settling_and_bad_input() {
        let mut m = ImuHealthMonitor::new(ImuHealthConfig::new(9.82, 0.0025, 98.2)).unwrap();
        let h = m.update(&sample(Vector3::new(0.0, 0.0, -5.0)));
        assert_eq!(h.flags, ImuHealth::SETTLING);
        let k = m.update(&sample(Vector3::new(f64::NAN, 0.0, 0.0)));
        assert_eq!(k, h);
        let mut c = ImuHealthConfig::new(9.82, 0.0025, 98.2);
        c.residue_corner_hz = f64::INFINITY;
        assert_eq!(c.first_invalid(), Some("residue_corner_hz"));
        assert!(ImuHealthMonitor::new(c).is_none());
    }
}
