//! The one sensor frame the on-board software consumes: what the sensor
//! server hands to the control task each sample, whatever produced it (the
//! simulator's sensor models, a replayed log, or device drivers on board).
//!
//! Frames: body FRD for the IMU and magnetometer, NED for GPS. Times are
//! seconds on the on-board clock (since boot or since the start of a run).

use nalgebra::Vector3;

/// One IMU sample (accelerometer and gyro, sampled together).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    /// Accelerometer specific force `f = a − g` in body axes (m/s²); reads
    /// `[0, 0, −g]` at rest and level.
    pub specific_force_body_m_s2: Vector3<f64>,
    /// Gyro rates in body axes (rad/s).
    pub gyro_body_rad_s: Vector3<f64>,
}

/// The kind of GPS fix a receiver reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GpsFixType {
    /// No position (the position fields are stale or meaningless).
    NoFix,
    /// Horizontal position only.
    Fix2d,
    /// Full 3-D position.
    Fix3d,
}

/// One GPS solution as delivered by the receiver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsFix {
    /// Time of validity of the solution (s, on-board clock). It precedes the
    /// frame's time by the receiver's latency.
    pub epoch_s: f64,
    /// Kind of fix; only [`GpsFixType::Fix3d`] is fused.
    pub fix: GpsFixType,
    /// Position in the local NED frame (m).
    pub position_ned_m: Vector3<f64>,
    /// Velocity in NED (m/s), when the receiver gives one (Doppler).
    pub velocity_ned_m_s: Option<Vector3<f64>>,
}

impl GpsFix {
    /// True when the fix may be fused (a 3-D fix).
    pub fn is_valid(&self) -> bool {
        self.fix == GpsFixType::Fix3d
    }
}

/// Everything the sensors delivered for one control sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorFrame {
    /// Time of the sample (s, on-board clock).
    pub t_s: f64,
    /// The IMU sample (every frame has one: the IMU paces the control task).
    pub imu: ImuSample,
    /// Magnetometer field in body axes, in the units of the local field the
    /// navigation is configured with, when sampled this frame.
    pub mag_body: Option<Vector3<f64>>,
    /// A GPS solution delivered this frame.
    pub gps: Option<GpsFix>,
}

impl SensorFrame {
    /// A frame with an IMU sample only.
    pub fn imu_only(t_s: f64, imu: ImuSample) -> Self {
        SensorFrame {
            t_s,
            imu,
            mag_body: None,
            gps: None,
        }
    }

    /// The first non-finite quantity in the frame, if any (by name).
    pub fn first_non_finite(&self) -> Option<&'static str> {
        let bad = |v: &Vector3<f64>| !v.iter().all(|x| x.is_finite());
        if !self.t_s.is_finite() {
            return Some("time");
        }
        if bad(&self.imu.specific_force_body_m_s2) {
            return Some("accelerometer sample");
        }
        if bad(&self.imu.gyro_body_rad_s) {
            return Some("gyro sample");
        }
        if self.mag_body.as_ref().is_some_and(bad) {
            return Some("magnetometer sample");
        }
        if let Some(g) = &self.gps {
            if !g.epoch_s.is_finite() || bad(&g.position_ned_m) {
                return Some("GPS fix");
            }
            if g.velocity_ned_m_s.as_ref().is_some_and(bad) {
                return Some("GPS velocity");
            }
        }
        None
    }
}

/// Sensor noise figures and the local environment the navigation needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorNoise {
    /// GPS position σ per NED axis (m).
    pub gps_sigma_m: Vector3<f64>,
    /// GPS velocity σ per NED axis (m/s).
    pub gps_vel_sigma_m_s: Vector3<f64>,
    /// The local magnetic field in NED (13.14), in the magnetometer's units.
    pub mag_field_ned: Vector3<f64>,
    /// Local gravity (m/s²): the helicopter's parameter, one value everywhere.
    pub gravity_m_s2: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_fields_are_named() {
        let imu = ImuSample {
            specific_force_body_m_s2: Vector3::new(0.0, 0.0, -9.81),
            gyro_body_rad_s: Vector3::zeros(),
        };
        let mut f = SensorFrame::imu_only(0.0, imu);
        assert_eq!(f.first_non_finite(), None);
        f.gps = Some(GpsFix {
            epoch_s: 0.0,
            fix: GpsFixType::Fix3d,
            position_ned_m: Vector3::zeros(),
            velocity_ned_m_s: Some(Vector3::new(f64::NAN, 0.0, 0.0)),
        });
        assert_eq!(f.first_non_finite(), Some("GPS velocity"));
        f.gps = None;
        f.imu.gyro_body_rad_s.y = f64::INFINITY;
        assert_eq!(f.first_non_finite(), Some("gyro sample"));
    }
}
