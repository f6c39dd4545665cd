//! The shaker experiment of thesis Appendix A: an accelerometer on a one-axis
//! exciter, `a(t) = A sin(2π f t)` along one axis, gravity along body z (the
//! part lies level: its z axis reads −1 g at rest), through the
//! accelerometer's mechanical stage, mechanical range, internal low-pass and
//! output stage ([`crate::vibration`], [`crate::sensors`]).
//!
//! Below ±1 g of vibration on z the mean stays at −1 g; above it the
//! mechanical stage clips at −2 g (a ±2 g part) on one side only and the mean
//! moves up, while at frequencies above the internal filter's cut-off the
//! output stays smooth and inside the range: the "hidden saturation". The
//! expected mean is the closed form [`clipped_sine_mean`] of the clipped
//! sinusoid (amplitude times the mechanical stage's gain at f) times the
//! internal filter's DC gain.

use crate::sensors::{InertialState, SensorConfig, SensorConfigError};
use crate::vibration::{SensorStage, clipped_sine_mean};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

/// One shaker run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShakerConfig {
    /// The sensor: `imu.rate_hz`, `imu.accel` (output stage),
    /// `imu.accel_stage` and `imu.vibration.oversample` are used, and `seed`.
    pub sensors: SensorConfig,
    /// Excited axis (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// Excitation frequency (Hz).
    pub freq_hz: f64,
    /// Excitation amplitude (m/s², zero to peak).
    pub amplitude_m_s2: f64,
    /// Gravity along body z (m/s²); the z axis reads −gravity at rest.
    pub gravity_m_s2: f64,
    /// Duration of the run (s).
    pub duration_s: f64,
    /// Start of the averaging window (s): the filters' transients have died.
    pub settle_s: f64,
}

/// One output sample of the excited axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShakerSample {
    /// Time (s).
    pub t_s: f64,
    /// The accelerometer's output on the excited axis (m/s²).
    pub output_m_s2: f64,
    /// Fraction of the internal sub-steps of this sample at which the
    /// mechanical stage was at its limit (hidden from the output).
    pub clipped_fraction: f64,
}

/// What a run showed, over the averaging window (a whole number of
/// excitation periods after `settle_s`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShakerSummary {
    /// Mean of the output (m/s²).
    pub mean_m_s2: f64,
    /// The closed form: the mean of the clipped sinusoid times the internal
    /// filter's DC gain (m/s²).
    pub expected_mean_m_s2: f64,
    /// The value at rest (m/s²): −g on z, 0 on x and y.
    pub rest_m_s2: f64,
    /// Amplitude at the mechanical stage's output, `A·|H_mech(f)|` (m/s²).
    pub mechanical_amplitude_m_s2: f64,
    /// The mechanical range (m/s²).
    pub mechanical_range_m_s2: f64,
    /// Smallest and largest output (m/s²).
    pub output_min_m_s2: f64,
    /// Largest output (m/s²).
    pub output_max_m_s2: f64,
    /// Fraction of the time the mechanical stage was at its limit.
    pub clipped_fraction: f64,
    /// Output samples averaged.
    pub samples: usize,
}

impl ShakerSummary {
    /// Mean shift from the value at rest (m/s²).
    pub fn shift_m_s2(&self) -> f64 {
        self.mean_m_s2 - self.rest_m_s2
    }

    /// True when the output shows the clipping: it reaches within 2 % of the
    /// mechanical range. Clipping that is not visible is hidden saturation.
    pub fn clipping_visible(&self) -> bool {
        let lim = 0.98 * self.mechanical_range_m_s2;
        self.output_min_m_s2 <= -lim || self.output_max_m_s2 >= lim
    }
}

fn check(cfg: &ShakerConfig) -> Result<(), SensorConfigError> {
    let bad = |field: &str, v: f64, rule: &str| {
        Err(SensorConfigError::invalid("<shaker>", field, v, rule))
    };
    if cfg.axis > 2 {
        return bad("axis", cfg.axis as f64, "x, y or z");
    }
    let rate = cfg.sensors.imu.rate_hz;
    let fs = rate * f64::from(cfg.sensors.imu.vibration.oversample);
    if !(cfg.freq_hz.is_finite() && cfg.freq_hz > 0.0 && cfg.freq_hz < 0.45 * fs) {
        return bad("freq_hz", cfg.freq_hz, "> 0 and < 0.45 x the internal rate");
    }
    if !(cfg.amplitude_m_s2.is_finite() && (0.0..=1e4).contains(&cfg.amplitude_m_s2)) {
        return bad(
            "amplitude",
            cfg.amplitude_m_s2,
            "0..=1e4 m/s^2 (about 1000 g)",
        );
    }
    if !(cfg.gravity_m_s2.is_finite() && cfg.gravity_m_s2 > 0.0 && cfg.gravity_m_s2 < 100.0) {
        return bad("gravity_m_s2", cfg.gravity_m_s2, "in (0, 100)");
    }
    if !(cfg.duration_s.is_finite() && cfg.duration_s > 0.0 && cfg.duration_s <= 3600.0) {
        return bad("duration_s", cfg.duration_s, "in (0, 3600]");
    }
    if !(cfg.settle_s.is_finite() && cfg.settle_s >= 0.0 && cfg.settle_s < cfg.duration_s) {
        return bad("settle_s", cfg.settle_s, ">= 0 and < duration_s");
    }
    // at least one whole period to average over
    if (cfg.duration_s - cfg.settle_s) * cfg.freq_hz < 1.0 {
        return bad(
            "duration_s",
            cfg.duration_s,
            "at least one excitation period after settle_s",
        );
    }
    Ok(())
}

/// Run the shaker; every output sample goes to `sink` (e.g. a CSV writer).
/// The sensor's settings are validated as a configuration (vibration
/// switched on for the stage checks).
pub fn shake(
    cfg: &ShakerConfig,
    mut sink: impl FnMut(&ShakerSample),
) -> Result<ShakerSummary, SensorConfigError> {
    let mut sensors = cfg.sensors;
    sensors.imu.vibration.enabled = true;
    sensors.validate("<shaker sensor>")?;
    check(cfg)?;
    let imu = &sensors.imu;
    let rate = imu.rate_hz;
    let over = imu.vibration.oversample;
    let fs = rate * f64::from(over);
    let stage = SensorStage::new(&imu.accel_stage, imu.accel.range, fs).ok_or_else(|| {
        SensorConfigError::invalid("<shaker>", "imu.accel_stage", fs, "stage out of range")
    })?;
    let mut stages = [stage; 3];
    let mut rng = ChaCha8Rng::seed_from_u64(sensors.seed);
    rng.set_stream(10);
    let mut out = InertialState::new(imu.accel, &mut rng);
    let rest = Vector3::new(0.0, 0.0, -cfg.gravity_m_s2);
    let n = (cfg.duration_s * rate).round() as usize;
    let periods = ((cfg.duration_s - cfg.settle_s) * cfg.freq_hz).floor();
    let t_avg_end = cfg.settle_s + periods / cfg.freq_hz;
    let (mut sum, mut count, mut clipped_sum) = (0.0, 0usize, 0.0);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let w = 2.0 * PI * cfg.freq_hz;
    for k in 1..=n {
        let mut last = Vector3::zeros();
        let mut clipped = 0u32;
        for j in 1..=over {
            let t = ((k - 1) as f64 + f64::from(j) / f64::from(over)) / rate;
            let mut x = rest;
            x[cfg.axis] += cfg.amplitude_m_s2 * (w * t).sin();
            for i in 0..3 {
                let (y, c) = stages[i].step(x[i]);
                last[i] = y;
                if i == cfg.axis {
                    clipped += u32::from(c);
                }
            }
        }
        let y = out.measure(&last, rate, &mut rng)[cfg.axis];
        let t_s = k as f64 / rate;
        let clipped_fraction = f64::from(clipped) / f64::from(over);
        // samples stand for the interval ending at t_s
        if t_s > cfg.settle_s && t_s <= t_avg_end + 0.5 / rate {
            sum += y;
            count += 1;
            clipped_sum += clipped_fraction;
            lo = lo.min(y);
            hi = hi.max(y);
        }
        sink(&ShakerSample {
            t_s,
            output_m_s2: y,
            clipped_fraction,
        });
    }
    let count_f = count.max(1) as f64;
    let mech_amp = cfg.amplitude_m_s2 * stage.mechanical_gain_at(cfg.freq_hz);
    let range = stage.range();
    let offset = rest[cfg.axis];
    Ok(ShakerSummary {
        mean_m_s2: sum / count_f,
        expected_mean_m_s2: stage.filter().dc_gain()
            * clipped_sine_mean(offset, mech_amp, -range, range),
        rest_m_s2: offset,
        mechanical_amplitude_m_s2: mech_amp,
        mechanical_range_m_s2: range,
        output_min_m_s2: lo,
        output_max_m_s2: hi,
        clipped_fraction: clipped_sum / count_f,
        samples: count,
    })
}

/// A sensor configuration for the shaker: the given one with noise, bias,
/// scale-factor error and quantisation of the accelerometer removed (an
/// ideal part apart from its stages and ranges), output and mechanical
/// range `range_m_s2`.
pub fn ideal_part(mut sensors: SensorConfig, range_m_s2: f64) -> SensorConfig {
    let a = &mut sensors.imu.accel;
    a.noise_density = 0.0;
    a.bias_random_walk = 0.0;
    a.initial_bias_sigma = 0.0;
    a.scale_factor_sigma = 0.0;
    a.resolution = 0.0;
    a.range = range_m_s2;
    sensors.imu.accel_stage.mechanical_range = Some(range_m_s2);
    sensors
}
