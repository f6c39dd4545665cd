//! The IMU and magnetometer: a VectorNav VN-100, binary output protocol and
//! the ASCII `$VNYMR` asynchronous output, as the *VN-100 User Manual*
//! (VectorNav Technologies) defines them.
//!
//! # Binary output (section "Binary Output Protocol")
//!
//! ```text
//! 0xFA | groups (u8) | group-1 fields (u16 LE) | payload | CRC-16 (big-endian)
//! ```
//! The CRC is CRC-16-CCITT ([`crate::checksum::VECTORNAV_CRC`]) over every
//! byte after the sync byte up to the payload's end. Payload fields are
//! little-endian, in the order of their bits. This crate decodes the Common
//! group (group byte `0x01`) with any subset of its fields; the sizes of all
//! fifteen are known so unknown ones are skipped. Frames naming other groups
//! are rejected as malformed (the decoder resynchronises). Units as the device
//! sends them: time since startup in ns, angular rate in rad/s, acceleration
//! in m/s², magnetic field in gauss, temperature in °C, pressure in kPa, all
//! float32 (about 7 significant digits) in the sensor's body frame, which for
//! a sensor mounted with its connector aft is FRD, the helicopter's body frame.
//!
//! The accelerometer reads specific force: `[0, 0, −g]` at rest and level,
//! as [`helicon_core::sensor::ImuSample`] expects. The magnetometer reads
//! gauss; the navigation's local field (`mag.field_ned` of the sensor
//! configuration, the thesis's (13.14) in gauss by default) must be given in
//! gauss too — only the direction enters the q-method, so the conversion is
//! the identity.
//!
//! # ASCII `$VNYMR` (section "Yaw, Magnetic, Acceleration and Angular Rates")
//! `$VNYMR,yaw,pitch,roll,magX,magY,magZ,accX,accY,accZ,gyroX,gyroY,gyroZ*CS`
//! with degrees, gauss, m/s², rad/s and the 8-bit XOR checksum of NMEA.

use crate::checksum::{VECTORNAV_CRC, hex_value, xor8};
use crate::error::{EncodeError, check_range};
use crate::framing::{EncodedFrame, FrameStatus, Protocol, Reject, StreamDecoder};
use helicon_core::sensor::ImuSample;
use nalgebra::Vector3;

/// The binary sync byte.
pub const VN_SYNC: u8 = 0xFA;
/// Group byte of the Common group.
pub const VN_GROUP_COMMON: u8 = 0x01;

/// Sizes (bytes) of the fifteen Common-group fields, by bit (VN-100 User
/// Manual, binary output group 1 table; bit 15 is reserved).
pub const VN_COMMON_FIELD_BYTES: [usize; 15] =
    [8, 8, 8, 12, 16, 12, 24, 12, 12, 24, 20, 28, 2, 4, 8];

/// Common-group field bits used by this crate.
pub mod common_field {
    /// TimeStartup: u64 ns since power-on.
    pub const TIME_STARTUP: u16 = 1 << 0;
    /// YawPitchRoll: 3 × f32 degrees.
    pub const YAW_PITCH_ROLL: u16 = 1 << 3;
    /// Quaternion: 4 × f32 (vector part first, scalar last).
    pub const QUATERNION: u16 = 1 << 4;
    /// AngularRate: 3 × f32 rad/s, body.
    pub const ANGULAR_RATE: u16 = 1 << 5;
    /// Accel: 3 × f32 m/s², body.
    pub const ACCEL: u16 = 1 << 8;
    /// MagPres: 3 × f32 gauss, f32 °C, f32 kPa.
    pub const MAG_PRES: u16 = 1 << 10;
    /// SyncInCnt: u32.
    pub const SYNC_IN_CNT: u16 = 1 << 13;
}

/// Magnetometer, temperature and pressure (the Common group's MagPres field).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VnMagPres {
    /// Magnetic field in body axes (gauss).
    pub mag_gauss: [f32; 3],
    /// Temperature (°C).
    pub temperature_c: f32,
    /// Barometric pressure (kPa).
    pub pressure_kpa: f32,
}

/// One VN-100 binary output packet of the Common group. A field is `Some`
/// when the packet carries it; fields of the group not listed here are
/// skipped on decoding and never encoded.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VnCommon {
    /// Time since the sensor started (ns).
    pub time_startup_ns: Option<u64>,
    /// Yaw, pitch, roll (degrees).
    pub yaw_pitch_roll_deg: Option<[f32; 3]>,
    /// Attitude quaternion, vector part first, scalar last.
    pub quaternion: Option<[f32; 4]>,
    /// Angular rate in body axes (rad/s).
    pub angular_rate_rad_s: Option<[f32; 3]>,
    /// Acceleration (specific force) in body axes (m/s²).
    pub accel_m_s2: Option<[f32; 3]>,
    /// Magnetic field, temperature and pressure.
    pub mag_pres: Option<VnMagPres>,
    /// SYNC_IN pulse count.
    pub sync_in_count: Option<u32>,
}

/// Largest binary frame: sync, group, field mask, all fields, CRC.
const VN_MAX_FRAME: usize = 4 + 202 + 2;

/// Payload length of a Common-group field mask, or `None` if a reserved bit
/// is set.
fn common_payload_len(mask: u16) -> Option<usize> {
    if mask & 0x8000 != 0 {
        return None;
    }
    Some(
        VN_COMMON_FIELD_BYTES
            .iter()
            .enumerate()
            .filter(|(bit, _)| mask & (1 << bit) != 0)
            .map(|(_, n)| n)
            .sum(),
    )
}

/// Little-endian reader over a payload (bounds checked, never panics).
struct Reader<'a> {
    data: &'a [u8],
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (head, rest) = self.data.split_first_chunk::<N>()?;
        self.data = rest;
        Some(*head)
    }
    fn skip(&mut self, n: usize) -> Option<()> {
        self.data = self.data.get(n..)?;
        Some(())
    }
    fn f32s<const N: usize>(&mut self) -> Option<[f32; N]> {
        let mut out = [0.0f32; N];
        for v in &mut out {
            *v = f32::from_le_bytes(self.take::<4>()?);
            if !v.is_finite() {
                return None;
            }
        }
        Some(out)
    }
}

/// The VN-100 binary protocol (Common group) for [`StreamDecoder`].
#[derive(Debug, Clone, Copy)]
pub struct VnBinary;

impl Protocol for VnBinary {
    type Message = VnCommon;
    const MAX_FRAME: usize = VN_MAX_FRAME;

    fn is_start(byte: u8) -> bool {
        byte == VN_SYNC
    }

    fn status(c: &[u8]) -> FrameStatus {
        if c.len() < 2 {
            return FrameStatus::Incomplete;
        }
        if c[1] != VN_GROUP_COMMON {
            return FrameStatus::Malformed;
        }
        let Some(mask) = c.get(2..4) else {
            return FrameStatus::Incomplete;
        };
        let mask = u16::from_le_bytes([mask[0], mask[1]]);
        match common_payload_len(mask) {
            Some(n) if n > 0 => FrameStatus::Complete(4 + n + 2),
            _ => FrameStatus::Malformed,
        }
        .clamp_to(c.len())
    }

    fn decode(frame: &[u8]) -> Result<VnCommon, Reject> {
        if VECTORNAV_CRC.checksum(&frame[1..]) != 0 {
            return Err(Reject::Checksum);
        }
        let mask = u16::from_le_bytes([frame[2], frame[3]]);
        let mut r = Reader {
            data: &frame[4..frame.len() - 2],
        };
        decode_common(mask, &mut r).ok_or(Reject::Unsupported)
    }
}

impl FrameStatus {
    /// `Complete(n)` becomes `Incomplete` until `n` bytes are buffered.
    fn clamp_to(self, have: usize) -> FrameStatus {
        match self {
            FrameStatus::Complete(n) if n > have => FrameStatus::Incomplete,
            s => s,
        }
    }
}

fn decode_common(mask: u16, r: &mut Reader<'_>) -> Option<VnCommon> {
    use common_field as f;
    let mut m = VnCommon::default();
    for bit in 0..15u16 {
        let flag = 1u16 << bit;
        if mask & flag == 0 {
            continue;
        }
        match flag {
            f::TIME_STARTUP => m.time_startup_ns = Some(u64::from_le_bytes(r.take::<8>()?)),
            f::YAW_PITCH_ROLL => m.yaw_pitch_roll_deg = Some(r.f32s::<3>()?),
            f::QUATERNION => m.quaternion = Some(r.f32s::<4>()?),
            f::ANGULAR_RATE => m.angular_rate_rad_s = Some(r.f32s::<3>()?),
            f::ACCEL => m.accel_m_s2 = Some(r.f32s::<3>()?),
            f::MAG_PRES => {
                let [x, y, z, t, p] = r.f32s::<5>()?;
                m.mag_pres = Some(VnMagPres {
                    mag_gauss: [x, y, z],
                    temperature_c: t,
                    pressure_kpa: p,
                });
            }
            f::SYNC_IN_CNT => m.sync_in_count = Some(u32::from_le_bytes(r.take::<4>()?)),
            _ => r.skip(VN_COMMON_FIELD_BYTES[usize::from(bit)])?,
        }
    }
    Some(m)
}

/// Streaming decoder of VN-100 binary packets.
pub type VnBinaryDecoder = StreamDecoder<VnBinary>;

fn put_f32s(out: &mut EncodedFrame, field: &'static str, v: &[f32]) -> Result<(), EncodeError> {
    for &x in v {
        if !x.is_finite() {
            return Err(EncodeError::NonFinite {
                field,
                value: f64::from(x),
            });
        }
        out.extend(&x.to_le_bytes());
    }
    Ok(())
}

impl VnCommon {
    /// The Common-group field mask of the fields present.
    pub fn field_mask(&self) -> u16 {
        use common_field as f;
        let mut mask = 0;
        let mut set = |present: bool, flag: u16| {
            if present {
                mask |= flag;
            }
        };
        set(self.time_startup_ns.is_some(), f::TIME_STARTUP);
        set(self.yaw_pitch_roll_deg.is_some(), f::YAW_PITCH_ROLL);
        set(self.quaternion.is_some(), f::QUATERNION);
        set(self.angular_rate_rad_s.is_some(), f::ANGULAR_RATE);
        set(self.accel_m_s2.is_some(), f::ACCEL);
        set(self.mag_pres.is_some(), f::MAG_PRES);
        set(self.sync_in_count.is_some(), f::SYNC_IN_CNT);
        mask
    }

    /// Encodes the packet as the sensor sends it. Errors: no field present,
    /// or a non-finite value.
    pub fn encode(&self) -> Result<EncodedFrame, EncodeError> {
        let mask = self.field_mask();
        if mask == 0 {
            return Err(EncodeError::OutOfRange {
                field: "VN-100 field mask",
                value: 0.0,
                min: 1.0,
                max: f64::from(u16::MAX),
            });
        }
        let mut out = EncodedFrame::new();
        out.extend(&[VN_SYNC, VN_GROUP_COMMON]);
        out.extend(&mask.to_le_bytes());
        if let Some(t) = self.time_startup_ns {
            out.extend(&t.to_le_bytes());
        }
        if let Some(v) = &self.yaw_pitch_roll_deg {
            put_f32s(&mut out, "yaw/pitch/roll", v)?;
        }
        if let Some(v) = &self.quaternion {
            put_f32s(&mut out, "quaternion", v)?;
        }
        if let Some(v) = &self.angular_rate_rad_s {
            put_f32s(&mut out, "angular rate", v)?;
        }
        if let Some(v) = &self.accel_m_s2 {
            put_f32s(&mut out, "acceleration", v)?;
        }
        if let Some(m) = &self.mag_pres {
            put_f32s(&mut out, "magnetic field", &m.mag_gauss)?;
            put_f32s(&mut out, "temperature", &[m.temperature_c])?;
            put_f32s(&mut out, "pressure", &[m.pressure_kpa])?;
        }
        if let Some(c) = self.sync_in_count {
            out.extend(&c.to_le_bytes());
        }
        let crc = VECTORNAV_CRC.checksum(&out.as_bytes()[1..]);
        out.extend(&crc.to_be_bytes());
        Ok(out)
    }

    /// The packet the simulated sensor sends for one IMU sample (and a
    /// magnetometer sample in gauss, when there is one): time since startup,
    /// angular rate, acceleration and MagPres (temperature 20 °C, pressure
    /// 101.325 kPa: the simulator models neither). Values are rounded to
    /// float32 as the device does.
    pub fn from_samples(
        time_startup_s: f64,
        imu: &ImuSample,
        mag_body_gauss: Option<&Vector3<f64>>,
    ) -> Result<VnCommon, EncodeError> {
        let t = check_range("time since startup", time_startup_s, 0.0, 1.8e10)?;
        let to_f32 = |field: &'static str, v: &Vector3<f64>| -> Result<[f32; 3], EncodeError> {
            let mut out = [0.0f32; 3];
            for (o, &x) in out.iter_mut().zip(v.iter()) {
                *o = check_range(field, x, -f64::from(f32::MAX), f64::from(f32::MAX))? as f32;
            }
            Ok(out)
        };
        let mag_pres = match mag_body_gauss {
            Some(m) => Some(VnMagPres {
                mag_gauss: to_f32("magnetic field", m)?,
                temperature_c: 20.0,
                pressure_kpa: 101.325,
            }),
            None => None,
        };
        Ok(VnCommon {
            time_startup_ns: Some((t * 1e9).round() as u64),
            angular_rate_rad_s: Some(to_f32("angular rate", &imu.gyro_body_rad_s)?),
            accel_m_s2: Some(to_f32("acceleration", &imu.specific_force_body_m_s2)?),
            mag_pres,
            ..VnCommon::default()
        })
    }

    /// Time since startup (s), when carried.
    pub fn time_startup_s(&self) -> Option<f64> {
        self.time_startup_ns.map(|ns| ns as f64 * 1e-9)
    }

    /// The IMU sample (body FRD), when the packet carries both the angular
    /// rate and the acceleration.
    pub fn imu_sample(&self) -> Option<ImuSample> {
        let w = self.angular_rate_rad_s?;
        let a = self.accel_m_s2?;
        Some(ImuSample {
            specific_force_body_m_s2: vec3(a),
            gyro_body_rad_s: vec3(w),
        })
    }

    /// The magnetic field in body axes (gauss), when carried.
    pub fn mag_body_gauss(&self) -> Option<Vector3<f64>> {
        self.mag_pres.map(|m| vec3(m.mag_gauss))
    }
}

fn vec3(v: [f32; 3]) -> Vector3<f64> {
    Vector3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))
}

// ---------------------------------------------------------------- ASCII ---

/// One `$VNYMR` sentence: yaw/pitch/roll, magnetic field, acceleration and
/// angular rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VnYmr {
    /// Yaw, pitch, roll (degrees).
    pub yaw_pitch_roll_deg: [f64; 3],
    /// Magnetic field in body axes (gauss).
    pub mag_gauss: [f64; 3],
    /// Acceleration (specific force) in body axes (m/s²).
    pub accel_m_s2: [f64; 3],
    /// Angular rate in body axes (rad/s).
    pub angular_rate_rad_s: [f64; 3],
}

/// Longest ASCII sentence accepted (bytes, `$` to line feed).
const VN_ASCII_MAX: usize = 200;

/// Framing shared by the `$…*hh\r\n` sentences of NMEA 0183 and VectorNav
/// ASCII: returns the body between `$` and `*` when the checksum holds.
pub(crate) fn sentence_status(c: &[u8], max: usize) -> FrameStatus {
    for (i, &b) in c.iter().enumerate().skip(1) {
        match b {
            b'\n' => return FrameStatus::Complete(i + 1),
            b'$' => return FrameStatus::Malformed,
            b'\r' => {}
            0x20..=0x7e => {}
            _ => return FrameStatus::Malformed,
        }
    }
    if c.len() >= max {
        FrameStatus::Oversize
    } else {
        FrameStatus::Incomplete
    }
}

/// The body of a complete `$body*hh\r\n` sentence (or `\n`-terminated)
/// whose checksum holds.
pub(crate) fn sentence_body(frame: &[u8]) -> Result<&[u8], Reject> {
    let line = frame.strip_suffix(b"\n").ok_or(Reject::Unsupported)?;
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    let star = line.len().checked_sub(3).ok_or(Reject::Unsupported)?;
    if line.get(star) != Some(&b'*') || star < 1 {
        return Err(Reject::Unsupported);
    }
    let (hi, lo) = (hex_value(line[star + 1]), hex_value(line[star + 2]));
    let (Some(hi), Some(lo)) = (hi, lo) else {
        return Err(Reject::Checksum);
    };
    let body = &line[1..star];
    if xor8(body) != (hi << 4) | lo {
        return Err(Reject::Checksum);
    }
    Ok(body)
}

/// Appends `*hh\r\n` to a sentence that starts with `$`.
pub(crate) fn finish_sentence(out: &mut EncodedFrame) -> Result<(), EncodeError> {
    use core::fmt::Write;
    let cs = xor8(&out.as_bytes()[1..]);
    write!(out, "*{cs:02X}\r\n").map_err(|_| EncodeError::TooLong {
        limit: crate::framing::MAX_FRAME_BYTES,
    })
}

/// The VectorNav ASCII `$VNYMR` output for [`StreamDecoder`]; other `$VN…`
/// sentences count as unsupported.
#[derive(Debug, Clone, Copy)]
pub struct VnAscii;

impl Protocol for VnAscii {
    type Message = VnYmr;
    const MAX_FRAME: usize = VN_ASCII_MAX;

    fn is_start(byte: u8) -> bool {
        byte == b'$'
    }

    fn status(c: &[u8]) -> FrameStatus {
        sentence_status(c, VN_ASCII_MAX)
    }

    fn decode(frame: &[u8]) -> Result<VnYmr, Reject> {
        let body = sentence_body(frame)?;
        let text = core::str::from_utf8(body).map_err(|_| Reject::Unsupported)?;
        let mut fields = text.split(',');
        if fields.next() != Some("VNYMR") {
            return Err(Reject::Unsupported);
        }
        let mut v = [0.0f64; 12];
        for x in &mut v {
            *x = fields
                .next()
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|x| x.is_finite())
                .ok_or(Reject::Unsupported)?;
        }
        if fields.next().is_some() {
            return Err(Reject::Unsupported);
        }
        Ok(VnYmr {
            yaw_pitch_roll_deg: [v[0], v[1], v[2]],
            mag_gauss: [v[3], v[4], v[5]],
            accel_m_s2: [v[6], v[7], v[8]],
            angular_rate_rad_s: [v[9], v[10], v[11]],
        })
    }
}

/// Streaming decoder of VectorNav `$VNYMR` sentences.
pub type VnAsciiDecoder = StreamDecoder<VnAscii>;

impl VnYmr {
    /// Encodes the sentence with the device's field widths (`%+08.3f` angles,
    /// `%+08.4f` field, `%+07.3f` acceleration, `%+010.6f` rates): a decoded
    /// device sentence re-encodes to the same bytes.
    pub fn encode(&self) -> Result<EncodedFrame, EncodeError> {
        use core::fmt::Write;
        let all = self
            .yaw_pitch_roll_deg
            .iter()
            .chain(&self.mag_gauss)
            .chain(&self.accel_m_s2)
            .chain(&self.angular_rate_rad_s);
        for &x in all {
            check_range("VNYMR field", x, -9999.0, 9999.0)?;
        }
        let [y, p, r] = self.yaw_pitch_roll_deg;
        let [mx, my, mz] = self.mag_gauss;
        let [ax, ay, az] = self.accel_m_s2;
        let [gx, gy, gz] = self.angular_rate_rad_s;
        let mut out = EncodedFrame::new();
        let too_long = |_| EncodeError::TooLong {
            limit: VN_ASCII_MAX,
        };
        write!(
            out,
            "$VNYMR,{y:+08.3},{p:+08.3},{r:+08.3},{mx:+08.4},{my:+08.4},{mz:+08.4},\
             {ax:+07.3},{ay:+07.3},{az:+07.3},{gx:+010.6},{gy:+010.6},{gz:+010.6}"
        )
        .map_err(too_long)?;
        finish_sentence(&mut out)?;
        Ok(out)
    }

    /// The IMU sample (body FRD).
    pub fn imu_sample(&self) -> ImuSample {
        ImuSample {
            specific_force_body_m_s2: Vector3::from(self.accel_m_s2),
            gyro_body_rad_s: Vector3::from(self.angular_rate_rad_s),
        }
    }

    /// The magnetic field in body axes (gauss).
    pub fn mag_body_gauss(&self) -> Vector3<f64> {
        Vector3::from(self.mag_gauss)
    }
}
