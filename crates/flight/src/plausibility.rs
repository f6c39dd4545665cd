//! Plausibility before fusion: every sensor sample is checked against what
//! its device can report and what the airframe can do before the navigation
//! sees it. A refused sample counts as missing (the supervisor's stale
//! limits then act on it); a sensor whose samples keep being refused until
//! its stale limit passes is a sensor fault with its own failsafe reason
//! (`imu_rejected`, `gps_rejected`, `mag_rejected`).
//!
//! | sensor | refused when | why |
//! |---|---|---|
//! | accelerometer | a component beyond the configured range `sensors.imu.accel.range` × (1 + `range_margin`) | the sensor saturates at its range: a larger output is not a measurement |
//! | gyro | a component beyond `sensors.imu.gyro.range` × (1 + `range_margin`) | the same |
//! | magnetometer | the field's magnitude outside `mag_ratio_min`…`mag_ratio_max` × the configured local field `sensors.mag.field_ned` | the Earth's field does not change in flight; a factor 2 is a broken sensor or a motor's field, not a heading |
//! | GPS | fix type below 3-D, `gnssFixOK` clear, fewer than `gps_min_satellites`, accuracy estimates above `gps_max_h_acc_m`/`gps_max_v_acc_m`/`gps_max_s_acc_m_s`, speed above `gps_max_speed_m_s`, a position beyond `gps_max_range_m` from home | a fix the receiver itself does not vouch for, or one the helicopter cannot have reached |
//!
//! A GPS fix that passes is still gated by the navigation filter's
//! innovation test (`navigation.gps_gate_nis`, the ESKF's `gate_nis`): a
//! jump from where the helicopter can be is refused there, and counts as
//! missing too. Non-finite values never reach this gate (the frame is
//! refused whole by the navigation, a navigation failure).
//!
//! The GPS accuracy defaults are PX4's requirements for the GPS to be used
//! (`EKF2_REQ_EPH` 3 m, `EKF2_REQ_EPV` 5 m, `EKF2_REQ_SACC` 0.5 m/s,
//! `EKF2_REQ_NSATS` 6); the speed limit is twice what an RC helicopter of
//! the thesis's class flies (≈ 20 m/s).

use helicon_config::ConfigError;
use helicon_core::SensorFrame;
use helicon_setup::sensors::SensorConfig;
use serde::{Deserialize, Serialize};

/// `v` is not at most `max` (NaN included).
fn beyond(v: f64, max: f64) -> bool {
    v.is_nan() || v > max
}

/// The limits (TOML `[plausibility]` of the on-board configuration).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlausibilityConfig {
    /// Margin over the configured accelerometer and gyro ranges (fraction).
    pub range_margin: f64,
    /// Least accepted field magnitude, as a fraction of the configured field's.
    pub mag_ratio_min: f64,
    /// Largest accepted field magnitude, as a multiple of the configured field's.
    pub mag_ratio_max: f64,
    /// Least number of satellites in a fix.
    pub gps_min_satellites: u8,
    /// Largest horizontal accuracy estimate of a fix (m).
    pub gps_max_h_acc_m: f64,
    /// Largest vertical accuracy estimate of a fix (m).
    pub gps_max_v_acc_m: f64,
    /// Largest speed accuracy estimate of a fix (m/s).
    pub gps_max_s_acc_m_s: f64,
    /// Largest speed over ground and vertical (m/s).
    pub gps_max_speed_m_s: f64,
    /// Largest distance of a fix from home (m).
    pub gps_max_range_m: f64,
}

impl Default for PlausibilityConfig {
    fn default() -> Self {
        PlausibilityConfig {
            range_margin: 0.02,
            mag_ratio_min: 0.5,
            mag_ratio_max: 1.5,
            gps_min_satellites: 6,
            gps_max_h_acc_m: 3.0,
            gps_max_v_acc_m: 5.0,
            gps_max_s_acc_m_s: 0.5,
            gps_max_speed_m_s: 40.0,
            gps_max_range_m: 20_000.0,
        }
    }
}

impl PlausibilityConfig {
    /// Check every limit (`file` names the configuration in errors).
    pub fn validate(&self, file: &str) -> Result<(), ConfigError> {
        let check = |field: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(ConfigError::invalid(
                    file,
                    format!("plausibility.{field}"),
                    v,
                    format!("must be finite, in [{lo}, {hi}]"),
                ))
            }
        };
        check("range_margin", self.range_margin, 0.0, 1.0)?;
        check("mag_ratio_min", self.mag_ratio_min, 0.0, 1.0)?;
        check("mag_ratio_max", self.mag_ratio_max, 1.0, 10.0)?;
        check(
            "gps_min_satellites",
            f64::from(self.gps_min_satellites),
            4.0,
            64.0,
        )?;
        check("gps_max_h_acc_m", self.gps_max_h_acc_m, 0.01, 100.0)?;
        check("gps_max_v_acc_m", self.gps_max_v_acc_m, 0.01, 100.0)?;
        check("gps_max_s_acc_m_s", self.gps_max_s_acc_m_s, 0.01, 10.0)?;
        check("gps_max_speed_m_s", self.gps_max_speed_m_s, 1.0, 200.0)?;
        check("gps_max_range_m", self.gps_max_range_m, 10.0, 1e6)?;
        Ok(())
    }
}

/// What a GPS receiver says of its own fix (u-blox NAV-PVT's fields).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsQuality {
    /// The receiver's fix type (u-blox: 0 none, 1 dead reckoning, 2 2-D,
    /// 3 3-D, 4 GNSS + dead reckoning, 5 time only).
    pub fix_type: u8,
    /// The receiver's `gnssFixOK` flag (the fix is within its masks).
    pub fix_ok: bool,
    /// Satellites used.
    pub satellites: u8,
    /// Horizontal accuracy estimate (m).
    pub h_acc_m: f64,
    /// Vertical accuracy estimate (m).
    pub v_acc_m: f64,
    /// Speed accuracy estimate (m/s).
    pub s_acc_m_s: f64,
}

impl GpsQuality {
    /// The quality a NAV-PVT message reports.
    pub fn from_nav_pvt(p: &helicon_devices::NavPvt) -> Self {
        GpsQuality {
            fix_type: p.fix_type,
            fix_ok: p.flags & helicon_devices::ubx::FLAG_GNSS_FIX_OK != 0,
            satellites: p.num_sv,
            h_acc_m: f64::from(p.h_acc_mm) * 1e-3,
            v_acc_m: f64::from(p.v_acc_mm) * 1e-3,
            s_acc_m_s: f64::from(p.s_acc_mm_s) * 1e-3,
        }
    }
}

/// Why a sample was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Rejection {
    /// An acceleration beyond the accelerometer's range.
    AccelRange,
    /// A rate beyond the gyro's range.
    GyroRange,
    /// A field magnitude far from the local field's.
    MagField,
    /// The receiver reports no 3-D fix (or not `gnssFixOK`).
    GpsNoFix,
    /// Too few satellites, or accuracy estimates above the limits.
    GpsQuality,
    /// A speed the helicopter cannot fly.
    GpsSpeed,
    /// A position beyond the range from home.
    GpsRange,
    /// The navigation's innovation gate refused the fix (a jump).
    GpsJump,
}

impl Rejection {
    /// Every kind, in code order.
    pub const ALL: [Rejection; 8] = [
        Rejection::AccelRange,
        Rejection::GyroRange,
        Rejection::MagField,
        Rejection::GpsNoFix,
        Rejection::GpsQuality,
        Rejection::GpsSpeed,
        Rejection::GpsRange,
        Rejection::GpsJump,
    ];

    /// The sensor refused.
    pub fn sensor(self) -> Sensor {
        match self {
            Rejection::AccelRange | Rejection::GyroRange => Sensor::Imu,
            Rejection::MagField => Sensor::Mag,
            _ => Sensor::Gps,
        }
    }

    /// The operator's text (at most 50 bytes: one MAVLink STATUSTEXT).
    pub fn text(self) -> &'static str {
        match self {
            Rejection::AccelRange => "IMU: acceleration beyond range, refused",
            Rejection::GyroRange => "IMU: rate beyond range, refused",
            Rejection::MagField => "mag: field magnitude implausible, refused",
            Rejection::GpsNoFix => "GPS: no 3-D fix, refused",
            Rejection::GpsQuality => "GPS: satellites/accuracy poor, refused",
            Rejection::GpsSpeed => "GPS: impossible speed, refused",
            Rejection::GpsRange => "GPS: position beyond range, refused",
            Rejection::GpsJump => "GPS: jump refused by the innovation gate",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// The three sensors the gate checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sensor {
    /// The IMU (accelerometer and gyro).
    Imu,
    /// The magnetometer.
    Mag,
    /// The GPS receiver.
    Gps,
}

/// What the gate let through of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gated {
    /// The frame with its refused parts removed; `None` when the IMU sample
    /// itself was refused (its magnetometer and GPS samples are kept for the
    /// next frame).
    pub frame: Option<SensorFrame>,
    /// The IMU sample's refusal.
    pub imu: Option<Rejection>,
    /// The magnetometer sample's refusal.
    pub mag: Option<Rejection>,
    /// The GPS fix's refusal.
    pub gps: Option<Rejection>,
}

/// The gate: limits and the counts of what it refused (no allocation).
#[derive(Debug, Clone)]
pub struct SensorGate {
    accel_max_m_s2: f64,
    gyro_max_rad_s: f64,
    mag_min: f64,
    mag_max: f64,
    config: PlausibilityConfig,
    counts: [u64; 8],
    pending_mag: Option<nalgebra::Vector3<f64>>,
    pending_gps: Option<helicon_core::sensor::GpsFix>,
}

impl SensorGate {
    /// The gate of `config` for the sensors of `sensors` (their ranges and
    /// the local field); `file` names the configuration in errors.
    pub fn new(
        config: &PlausibilityConfig,
        sensors: &SensorConfig,
        file: &str,
    ) -> Result<Self, ConfigError> {
        config.validate(file)?;
        let field = nalgebra::Vector3::from(sensors.mag.field_ned).norm();
        if !(field.is_finite() && field > 0.0) {
            return Err(ConfigError::invalid(
                file,
                "sensors.mag.field_ned",
                field,
                "must have a finite, non-zero magnitude",
            ));
        }
        let margin = 1.0 + config.range_margin;
        Ok(SensorGate {
            accel_max_m_s2: sensors.imu.accel.range * margin,
            gyro_max_rad_s: sensors.imu.gyro.range * margin,
            mag_min: config.mag_ratio_min * field,
            mag_max: config.mag_ratio_max * field,
            config: *config,
            counts: [0; 8],
            pending_mag: None,
            pending_gps: None,
        })
    }

    /// The gate of the default limits for the default sensors.
    pub fn default_for(sensors: &SensorConfig) -> Result<Self, ConfigError> {
        Self::new(&PlausibilityConfig::default(), sensors, "defaults")
    }

    /// Samples refused so far, by kind (in [`Rejection::ALL`]'s order).
    pub fn counts(&self) -> &[u64; 8] {
        &self.counts
    }

    /// How many samples of `kind` were refused so far.
    pub fn count(&self, kind: Rejection) -> u64 {
        self.counts[kind.index()]
    }

    /// Count a refusal made elsewhere (the navigation's innovation gate);
    /// returns the count so far.
    pub fn count_rejection(&mut self, kind: Rejection) -> u64 {
        let c = &mut self.counts[kind.index()];
        *c += 1;
        *c
    }

    /// Check one frame; `quality` is the receiver's report of the frame's
    /// fix, when it gives one (positions are in the NED frame of home).
    pub fn check(&mut self, frame: &SensorFrame, quality: Option<&GpsQuality>) -> Gated {
        let bad_axis =
            |v: &nalgebra::Vector3<f64>, max: f64| v.iter().any(|x| beyond(x.abs(), max));
        let imu = if bad_axis(&frame.imu.specific_force_body_m_s2, self.accel_max_m_s2) {
            Some(Rejection::AccelRange)
        } else if bad_axis(&frame.imu.gyro_body_rad_s, self.gyro_max_rad_s) {
            Some(Rejection::GyroRange)
        } else {
            None
        };
        let mut out = *frame;
        let mag = frame.mag_body.and_then(|m| {
            let n = m.norm();
            (beyond(n, self.mag_max) || beyond(self.mag_min, n)).then_some(Rejection::MagField)
        });
        if mag.is_some() {
            out.mag_body = None;
        }
        let gps = frame.gps.and_then(|g| self.gps_rejection(&g, quality));
        if gps.is_some() {
            out.gps = None;
        }
        for r in [imu, mag, gps].into_iter().flatten() {
            self.count_rejection(r);
        }
        if imu.is_some() {
            // the IMU sample refused: the frame is not a fresh sample; its
            // accepted magnetometer and GPS samples wait for the next one
            self.pending_mag = out.mag_body.or(self.pending_mag);
            self.pending_gps = out.gps.or(self.pending_gps);
            return Gated {
                frame: None,
                imu,
                mag,
                gps,
            };
        }
        if out.mag_body.is_none() {
            out.mag_body = self.pending_mag;
        }
        if out.gps.is_none() {
            out.gps = self.pending_gps;
        }
        self.pending_mag = None;
        self.pending_gps = None;
        Gated {
            frame: Some(out),
            imu,
            mag,
            gps,
        }
    }

    fn gps_rejection(
        &self,
        g: &helicon_core::sensor::GpsFix,
        quality: Option<&GpsQuality>,
    ) -> Option<Rejection> {
        let c = &self.config;
        if !g.is_valid() {
            return Some(Rejection::GpsNoFix);
        }
        if let Some(q) = quality {
            if !(q.fix_ok && (q.fix_type == 3 || q.fix_type == 4)) {
                return Some(Rejection::GpsNoFix);
            }
            if q.satellites < c.gps_min_satellites
                || beyond(q.h_acc_m, c.gps_max_h_acc_m)
                || beyond(q.v_acc_m, c.gps_max_v_acc_m)
                || beyond(q.s_acc_m_s, c.gps_max_s_acc_m_s)
            {
                return Some(Rejection::GpsQuality);
            }
        }
        if beyond(g.position_ned_m.norm(), c.gps_max_range_m) {
            return Some(Rejection::GpsRange);
        }
        if let Some(v) = g.velocity_ned_m_s
            && beyond(v.norm(), c.gps_max_speed_m_s)
        {
            return Some(Rejection::GpsSpeed);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
    use nalgebra::Vector3;

    fn frame() -> SensorFrame {
        SensorFrame {
            t_s: 1.0,
            imu: ImuSample {
                specific_force_body_m_s2: Vector3::new(0.0, 0.0, -9.81),
                gyro_body_rad_s: Vector3::new(0.01, 0.0, 0.0),
            },
            mag_body: Some(Vector3::from(SensorConfig::default().mag.field_ned)),
            gps: Some(GpsFix {
                epoch_s: 0.9,
                fix: GpsFixType::Fix3d,
                position_ned_m: Vector3::new(10.0, 5.0, -20.0),
                velocity_ned_m_s: Some(Vector3::new(3.0, 0.0, 0.0)),
            }),
        }
    }

    fn good() -> GpsQuality {
        GpsQuality {
            fix_type: 3,
            fix_ok: true,
            satellites: 12,
            h_acc_m: 1.5,
            v_acc_m: 2.5,
            s_acc_m_s: 0.1,
        }
    }

    fn gate() -> SensorGate {
        SensorGate::default_for(&SensorConfig::default()).unwrap()
    }

    #[test]
    fn a_plausible_frame_passes_whole() {
        let mut g = gate();
        let out = g.check(&frame(), Some(&good()));
        assert_eq!(out.frame, Some(frame()));
        assert_eq!((out.imu, out.mag, out.gps), (None, None, None));
        assert_eq!(g.counts().iter().sum::<u64>(), 0);
    }

    /// The reliability pass's finite but impossible samples: 3e38 m/s²,
    /// 1e30 rad/s, a 3e38-gauss field; and a receiver's no-fix and glitch.
    #[test]
    fn impossible_samples_are_refused_by_kind() {
        let mut g = gate();
        let mut f = frame();
        f.imu.specific_force_body_m_s2.x = 3e38;
        let out = g.check(&f, Some(&good()));
        assert_eq!(out.imu, Some(Rejection::AccelRange));
        assert!(out.frame.is_none());
        // its magnetometer and fix reach the next frame
        let mut next = frame();
        next.mag_body = None;
        next.gps = None;
        let out = g.check(&next, None);
        assert_eq!(out.frame.unwrap().gps, frame().gps);
        assert_eq!(out.frame.unwrap().mag_body, frame().mag_body);
        let mut f = frame();
        f.imu.gyro_body_rad_s.z = -1e30;
        assert_eq!(g.check(&f, None).imu, Some(Rejection::GyroRange));
        // (a frame whose IMU passes takes what the refused one held)
        assert!(g.check(&frame(), None).frame.is_some());
        let mut f = frame();
        f.mag_body = Some(Vector3::new(3e38, 0.0, 0.0));
        let out = g.check(&f, Some(&good()));
        assert_eq!(out.mag, Some(Rejection::MagField));
        assert!(out.frame.unwrap().mag_body.is_none() && out.frame.unwrap().gps.is_some());
        f.mag_body = Some(Vector3::new(0.01, 0.0, 0.0));
        assert_eq!(g.check(&f, None).mag, Some(Rejection::MagField));
        let no_fix = GpsQuality {
            fix_type: 0,
            fix_ok: false,
            ..good()
        };
        let out = g.check(&frame(), Some(&no_fix));
        assert_eq!(out.gps, Some(Rejection::GpsNoFix));
        assert!(out.frame.unwrap().gps.is_none());
        let few = GpsQuality {
            satellites: 4,
            ..good()
        };
        assert_eq!(
            g.check(&frame(), Some(&few)).gps,
            Some(Rejection::GpsQuality)
        );
        let vague = GpsQuality {
            h_acc_m: 25.0,
            ..good()
        };
        assert_eq!(
            g.check(&frame(), Some(&vague)).gps,
            Some(Rejection::GpsQuality)
        );
        let mut glitch = frame();
        glitch.gps = Some(GpsFix {
            position_ned_m: Vector3::new(10_000.0, 0.0, -5_000.0),
            velocity_ned_m_s: Some(Vector3::new(300.0, 0.0, 0.0)),
            ..frame().gps.unwrap()
        });
        assert_eq!(
            g.check(&glitch, Some(&good())).gps,
            Some(Rejection::GpsSpeed)
        );
        let mut far = frame();
        far.gps = Some(GpsFix {
            position_ned_m: Vector3::new(300_000.0, 0.0, 0.0),
            ..frame().gps.unwrap()
        });
        assert_eq!(g.check(&far, None).gps, Some(Rejection::GpsRange));
        assert_eq!(g.count(Rejection::GpsQuality), 2);
        assert_eq!(g.count(Rejection::AccelRange), 1);
        // a sample at the range itself is the sensor saturated: accepted
        let mut sat = frame();
        sat.imu.specific_force_body_m_s2.z = -SensorConfig::default().imu.accel.range;
        assert_eq!(g.check(&sat, None).imu, None);
    }

    #[test]
    fn texts_fit_a_status_text_and_bad_limits_are_named() {
        for r in Rejection::ALL {
            assert!(r.text().len() <= 50, "{}", r.text());
        }
        let bad = PlausibilityConfig {
            mag_ratio_max: f64::NAN,
            ..PlausibilityConfig::default()
        };
        let e = SensorGate::new(&bad, &SensorConfig::default(), "o.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("o.toml") && e.contains("plausibility.mag_ratio_max"),
            "{e}"
        );
    }
}
