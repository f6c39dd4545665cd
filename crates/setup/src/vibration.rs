//! The vibration environment at the IMU and the sensors' internal stages
//! (`[imu.vibration]`, `[imu.accel_stage]`, `[imu.gyro_stage]` of the
//! sensors' configuration; thesis §3.3.2 and Appendix A), checked field by
//! field. The simulator's vibration chain samples them.

use helicon_config::ConfigError;
use serde::{Deserialize, Serialize};

/// Highest internal low-pass order (four second-order sections).
pub const MAX_FILTER_ORDER: u32 = 8;

/// One vibration line: per-axis amplitudes (body FRD) at the reference
/// rotor speed.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VibrationLine {
    /// Acceleration amplitude per axis (m/s², zero to peak).
    pub accel_m_s2: [f64; 3],
    /// Angular-rate amplitude per axis (rad/s, zero to peak).
    pub gyro_rad_s: [f64; 3],
}

impl VibrationLine {
    /// `accel_g` vertically and half in x and y; `gyro_rad_s` in roll and
    /// pitch, half in yaw.
    fn hard_mounted(accel_g: f64, gyro_rad_s: f64) -> Self {
        let a = accel_g * crate::sensors::G0_M_S2;
        VibrationLine {
            accel_m_s2: [0.5 * a, 0.5 * a, a],
            gyro_rad_s: [gyro_rad_s, gyro_rad_s, 0.5 * gyro_rad_s],
        }
    }
}

/// The vibration environment at the IMU (`[imu.vibration]`): off by default,
/// and then the sensor model is exactly the one without it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VibrationConfig {
    /// Simulate the vibration and the sensors' internal stages.
    pub enabled: bool,
    /// Internal sub-steps per IMU sample (the internal rate is
    /// `oversample · imu.rate_hz`, at most 200 kHz), 1..=200.
    pub oversample: u32,
    /// Rotor speed at which the amplitudes are given (rad/s); at rotor speed
    /// Ω each amplitude is scaled by (Ω / this)².
    pub reference_rotor_speed_rad_s: f64,
    /// Engine revolutions per main-rotor revolution.
    pub engine_gear_ratio: f64,
    /// Engine firings per engine revolution (two-stroke twin: 2).
    pub engine_firings_per_rev: f64,
    /// Natural frequency of a vibration isolator between the airframe and
    /// the IMU (Hz): each line is scaled by the mount's transmissibility
    /// `|T| = √((1 + (2ζr)²) / ((1 − r²)² + (2ζr)²))`, `r = f / f_n`.
    /// Absent: hard mounted. Rigid-body motion passes unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub isolator_natural_frequency_hz: Option<f64>,
    /// Damping ratio ζ of the isolator, (0, 10].
    pub isolator_damping_ratio: f64,
    /// Main rotor, once per revolution (imbalance), Ω.
    pub main_1p: VibrationLine,
    /// Main rotor, blade passage, b·Ω.
    pub main_bp: VibrationLine,
    /// Tail rotor, once per revolution, Ωtr.
    pub tail_1p: VibrationLine,
    /// Tail rotor, blade passage, btr·Ωtr.
    pub tail_bp: VibrationLine,
    /// Engine firing frequency.
    pub engine_1f: VibrationLine,
    /// Engine firing frequency, second harmonic.
    pub engine_2f: VibrationLine,
}

impl Default for VibrationConfig {
    /// Off; when switched on, an illustrative hard-mounted IMU on a gasoline
    /// helicopter (docs/vibration.md): engine firing 1.5 g and its second
    /// harmonic 0.8 g vertically, rotor and tail-rotor lines 0.1–0.3 g, half that in x and
    /// y; angular lines 0.01–0.05 rad/s. Not a measurement: the thesis gives
    /// no spectrum ("lack of knowledge about the exact frequency").
    fn default() -> Self {
        VibrationConfig {
            enabled: false,
            oversample: 20,
            reference_rotor_speed_rad_s: 100.0,
            engine_gear_ratio: 8.0,
            engine_firings_per_rev: 2.0,
            isolator_natural_frequency_hz: None,
            isolator_damping_ratio: 0.1,
            main_1p: VibrationLine::hard_mounted(0.1, 0.05),
            main_bp: VibrationLine::hard_mounted(0.2, 0.03),
            tail_1p: VibrationLine::hard_mounted(0.2, 0.01),
            tail_bp: VibrationLine::hard_mounted(0.3, 0.01),
            engine_1f: VibrationLine::hard_mounted(1.5, 0.02),
            engine_2f: VibrationLine::hard_mounted(0.8, 0.01),
        }
    }
}

impl VibrationConfig {
    /// The six lines with their names.
    pub fn lines(&self) -> [(&'static str, &VibrationLine); 6] {
        [
            ("main_1p", &self.main_1p),
            ("main_bp", &self.main_bp),
            ("tail_1p", &self.tail_1p),
            ("tail_bp", &self.tail_bp),
            ("engine_1f", &self.engine_1f),
            ("engine_2f", &self.engine_2f),
        ]
    }

    /// The isolator's transmissibility at `f_hz` (1 when hard mounted).
    pub fn transmissibility(&self, f_hz: f64) -> f64 {
        match self.isolator_natural_frequency_hz {
            None => 1.0,
            Some(fn_hz) => {
                let r = f_hz / fn_hz;
                let d = 2.0 * self.isolator_damping_ratio * r;
                ((1.0 + d * d) / ((1.0 - r * r).powi(2) + d * d)).sqrt()
            }
        }
    }
}

impl VibrationConfig {
    /// Check the vibration and stage settings for an IMU at `imu_rate_hz`
    /// with output ranges `output_range` (accelerometer, gyro); only when
    /// `enabled`. Fields are named from `imu.`.
    pub fn validate(
        &self,
        stages: [&StageConfig; 2],
        imu_rate_hz: f64,
        file: &str,
    ) -> Result<(), ConfigError> {
        if !self.enabled {
            return Ok(());
        }
        let bad = |field: String, value: f64, rule: &str| {
            Err(ConfigError::invalid(
                file,
                field,
                value,
                format!("allowed: {rule}"),
            ))
        };
        let fs = imu_rate_hz * f64::from(self.oversample);
        if !(1..=200).contains(&self.oversample) || fs > 200_000.0 {
            return bad(
                "imu.vibration.oversample".into(),
                f64::from(self.oversample),
                "1..=200 with oversample * imu.rate_hz <= 200000",
            );
        }
        let positive = |field: &str, v: f64| {
            if v.is_finite() && v > 0.0 && v <= 1e6 {
                Ok(())
            } else {
                bad(
                    format!("imu.vibration.{field}"),
                    v,
                    "finite, > 0 and <= 1e6",
                )
            }
        };
        positive(
            "reference_rotor_speed_rad_s",
            self.reference_rotor_speed_rad_s,
        )?;
        positive("engine_gear_ratio", self.engine_gear_ratio)?;
        positive("engine_firings_per_rev", self.engine_firings_per_rev)?;
        if let Some(f) = self.isolator_natural_frequency_hz {
            positive("isolator_natural_frequency_hz", f)?;
        }
        let z = self.isolator_damping_ratio;
        if !(z.is_finite() && z > 0.0 && z <= 10.0) {
            return bad("imu.vibration.isolator_damping_ratio".into(), z, "(0, 10]");
        }
        for (name, line) in self.lines() {
            for (what, v) in [
                ("accel_m_s2", line.accel_m_s2),
                ("gyro_rad_s", line.gyro_rad_s),
            ] {
                for x in v {
                    if !(x.is_finite() && (0.0..=1e4).contains(&x)) {
                        return bad(
                            format!("imu.vibration.{name}.{what}"),
                            x,
                            "0..=1e4 per axis",
                        );
                    }
                }
            }
        }
        for (name, st) in [
            ("imu.accel_stage", stages[0]),
            ("imu.gyro_stage", stages[1]),
        ] {
            if let Some(r) = st.mechanical_range
                && !(r.is_finite() && r > 0.0 && r <= 1e6)
            {
                return bad(
                    format!("{name}.mechanical_range"),
                    r,
                    "finite, > 0 and <= 1e6",
                );
            }
            let nyq = 0.45 * fs;
            for (field, f) in [
                ("mechanical_bandwidth_hz", st.mechanical_bandwidth_hz),
                ("filter_cutoff_hz", st.filter_cutoff_hz),
            ] {
                if !(f.is_finite() && f > 0.0 && f < nyq) {
                    return Err(ConfigError::invalid(
                        file,
                        format!("{name}.{field}"),
                        f,
                        format!(
                            "allowed: > 0 and < 0.45 x the internal rate \
                             (oversample * imu.rate_hz = {fs} Hz)"
                        ),
                    ));
                }
            }
            if !(1..=MAX_FILTER_ORDER).contains(&st.filter_order) {
                return bad(
                    format!("{name}.filter_order"),
                    f64::from(st.filter_order),
                    "1..=8",
                );
            }
        }
        Ok(())
    }
}

/// The internal stages of one inertial sensor (`[imu.accel_stage]`,
/// `[imu.gyro_stage]`), used when `[imu.vibration] enabled = true`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StageConfig {
    /// Range of the mechanical sensing element (sensor unit); absent: the
    /// output range (`imu.accel.range` / `imu.gyro.range`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mechanical_range: Option<f64>,
    /// Bandwidth of the mechanical stage (Hz): a second-order Butterworth
    /// response; below 0.45 × the internal rate.
    pub mechanical_bandwidth_hz: f64,
    /// Order of the internal low-pass filter, 1..=8 (the thesis's part: 5).
    pub filter_order: u32,
    /// Cut-off (−3 dB) of the internal low-pass filter (Hz); below 0.45 ×
    /// the internal rate.
    pub filter_cutoff_hz: f64,
}

impl Default for StageConfig {
    /// Fifth-order internal filter at 50 Hz (thesis Figure 3.6: a
    /// fifth-order analog low-pass; its cut-off is not given), mechanical
    /// bandwidth 1 kHz, mechanical range = output range.
    fn default() -> Self {
        StageConfig {
            mechanical_range: None,
            mechanical_bandwidth_hz: 1000.0,
            filter_order: 5,
            filter_cutoff_hz: 50.0,
        }
    }
}
