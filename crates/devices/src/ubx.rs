//! GPS in u-blox UBX: the NAV-PVT solution (class 0x01, id 0x07, 92-byte
//! payload), as the *u-blox 8 / u-blox M8 Receiver Description including
//! Protocol Specification* defines it.
//!
//! ```text
//! 0xB5 0x62 | class | id | length (u16 LE) | payload | CK_A CK_B
//! ```
//! The checksum is the 8-bit Fletcher sum over class, id, length and payload
//! ([`crate::checksum::ubx_fletcher`]). This crate frames UBX itself (uniform
//! statistics and resynchronisation) and hands each frame whose checksum
//! holds to the `ublox` crate, which decodes the NAV-PVT fields; the `ublox`
//! crate does not write NAV-PVT, so encoding is by hand.
//!
//! Quantisation as the receiver sends it: latitude and longitude 1e-7°
//! (1.1 cm of latitude), heights and accuracies 1 mm, velocities 1 mm/s,
//! headings 1e-5°, time of week 1 ms.

use crate::checksum::ubx_fletcher;
use crate::error::{EncodeError, check_range};
use crate::framing::{EncodedFrame, FrameStatus, Protocol, Reject, StreamDecoder};
use crate::geodetic::{Geodetic, LocalNed};
use helicon_core::sensor::{GpsFix, GpsFixType};
use nalgebra::Vector3;

/// First UBX sync character.
pub const UBX_SYNC_1: u8 = 0xB5;
/// Second UBX sync character.
pub const UBX_SYNC_2: u8 = 0x62;
/// NAV class.
pub const UBX_CLASS_NAV: u8 = 0x01;
/// NAV-PVT message id.
pub const UBX_ID_NAV_PVT: u8 = 0x07;
/// NAV-PVT payload length (bytes).
pub const NAV_PVT_LEN: usize = 92;
/// Largest UBX frame this decoder accepts (bytes; longer frames, which no
/// message used here has, are skipped as oversize).
pub const UBX_MAX_FRAME: usize = 256;

/// `fixType` of NAV-PVT.
pub mod fix_type {
    /// No fix.
    pub const NO_FIX: u8 = 0;
    /// Dead reckoning only.
    pub const DEAD_RECKONING: u8 = 1;
    /// 2-D fix.
    pub const FIX_2D: u8 = 2;
    /// 3-D fix.
    pub const FIX_3D: u8 = 3;
    /// GNSS + dead reckoning.
    pub const GNSS_DEAD_RECKONING: u8 = 4;
    /// Time only.
    pub const TIME_ONLY: u8 = 5;
}

/// `flags` bit 0 of NAV-PVT: valid fix within the DOP and accuracy masks.
pub const FLAG_GNSS_FIX_OK: u8 = 0x01;

/// One NAV-PVT solution, in the receiver's integer units (so that it
/// round-trips bit for bit). Fields not listed are written as zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NavPvt {
    /// GPS time of week of the navigation epoch (ms).
    pub itow_ms: u32,
    /// UTC year.
    pub year: u16,
    /// UTC month (1–12).
    pub month: u8,
    /// UTC day (1–31).
    pub day: u8,
    /// UTC hour.
    pub hour: u8,
    /// UTC minute.
    pub min: u8,
    /// UTC second.
    pub sec: u8,
    /// Validity flags (bit 0 date, bit 1 time, bit 2 fully resolved).
    pub valid: u8,
    /// Fix type, see [`fix_type`].
    pub fix_type: u8,
    /// Fix status flags (bit 0: gnssFixOK).
    pub flags: u8,
    /// Satellites used.
    pub num_sv: u8,
    /// Longitude (1e-7 °).
    pub lon_e7: i32,
    /// Latitude (1e-7 °).
    pub lat_e7: i32,
    /// Height above the ellipsoid (mm).
    pub height_mm: i32,
    /// Height above mean sea level (mm).
    pub height_msl_mm: i32,
    /// Horizontal accuracy estimate (mm).
    pub h_acc_mm: u32,
    /// Vertical accuracy estimate (mm).
    pub v_acc_mm: u32,
    /// Velocity north, east, down (mm/s).
    pub vel_ned_mm_s: [i32; 3],
    /// Ground speed (mm/s).
    pub g_speed_mm_s: i32,
    /// Heading of motion (1e-5 °).
    pub head_mot_e5: i32,
    /// Speed accuracy estimate (mm/s).
    pub s_acc_mm_s: u32,
    /// Heading accuracy estimate (1e-5 °).
    pub head_acc_e5: u32,
    /// Position DOP (0.01).
    pub pdop_e2: u16,
}

/// The UBX protocol (NAV-PVT) for [`StreamDecoder`]; other UBX messages with
/// a valid checksum count as unsupported.
#[derive(Debug, Clone, Copy)]
pub struct Ubx;

impl Protocol for Ubx {
    type Message = NavPvt;
    const MAX_FRAME: usize = UBX_MAX_FRAME;

    fn is_start(byte: u8) -> bool {
        byte == UBX_SYNC_1
    }

    fn status(c: &[u8]) -> FrameStatus {
        if c.len() >= 2 && c[1] != UBX_SYNC_2 {
            return FrameStatus::Malformed;
        }
        if c.len() < 6 {
            return FrameStatus::Incomplete;
        }
        let n = 8 + usize::from(u16::from_le_bytes([c[4], c[5]]));
        if n > UBX_MAX_FRAME {
            FrameStatus::Oversize
        } else if c.len() < n {
            FrameStatus::Incomplete
        } else {
            FrameStatus::Complete(n)
        }
    }

    fn decode(frame: &[u8]) -> Result<NavPvt, Reject> {
        let n = frame.len();
        let (a, b) = ubx_fletcher(&frame[2..n - 2]);
        if (a, b) != (frame[n - 2], frame[n - 1]) {
            return Err(Reject::Checksum);
        }
        if frame[2] != UBX_CLASS_NAV || frame[3] != UBX_ID_NAV_PVT || n != NAV_PVT_LEN + 8 {
            return Err(Reject::Unsupported);
        }
        let mut parser = ublox::Parser::<ublox::FixedBuffer<128>>::new_fixed();
        let mut packets = parser.consume_ubx(frame);
        let Some(Ok(ublox::UbxPacket::Proto23(ublox::proto23::PacketRef::NavPvt(p)))) =
            packets.next()
        else {
            return Err(Reject::Unsupported);
        };
        Ok(NavPvt {
            itow_ms: p.itow(),
            year: p.year(),
            month: p.month(),
            day: p.day(),
            hour: p.hour(),
            min: p.min(),
            sec: p.sec(),
            valid: p.valid_raw(),
            fix_type: p.fix_type_raw(),
            flags: p.flags_raw(),
            num_sv: p.num_satellites(),
            lon_e7: p.longitude_raw(),
            lat_e7: p.latitude_raw(),
            height_mm: p.height_above_ellipsoid_raw(),
            height_msl_mm: p.height_msl_raw(),
            h_acc_mm: p.horizontal_accuracy_raw(),
            v_acc_mm: p.vertical_accuracy_raw(),
            vel_ned_mm_s: [p.vel_north_raw(), p.vel_east_raw(), p.vel_down_raw()],
            g_speed_mm_s: p.ground_speed_2d_raw(),
            head_mot_e5: p.heading_motion_raw(),
            s_acc_mm_s: p.speed_accuracy_raw(),
            head_acc_e5: p.heading_accuracy_raw(),
            pdop_e2: p.pdop_raw(),
        })
    }
}

/// Streaming decoder of UBX NAV-PVT.
pub type UbxDecoder = StreamDecoder<Ubx>;

/// Rounds `value / quantum` to an `i32`, or an error naming `field`.
fn quantise_i32(field: &'static str, value: f64, quantum: f64) -> Result<i32, EncodeError> {
    let q = check_range(
        field,
        value,
        f64::from(i32::MIN) * quantum,
        f64::from(i32::MAX) * quantum,
    )?;
    Ok((q / quantum).round() as i32)
}

impl NavPvt {
    /// Encodes the frame (sync, class, id, length, 92-byte payload, checksum).
    pub fn encode(&self) -> EncodedFrame {
        let mut p = [0u8; NAV_PVT_LEN];
        let mut put = |offset: usize, bytes: &[u8]| {
            p[offset..offset + bytes.len()].copy_from_slice(bytes);
        };
        put(0, &self.itow_ms.to_le_bytes());
        put(4, &self.year.to_le_bytes());
        put(
            6,
            &[
                self.month, self.day, self.hour, self.min, self.sec, self.valid,
            ],
        );
        put(20, &[self.fix_type, self.flags, 0, self.num_sv]);
        put(24, &self.lon_e7.to_le_bytes());
        put(28, &self.lat_e7.to_le_bytes());
        put(32, &self.height_mm.to_le_bytes());
        put(36, &self.height_msl_mm.to_le_bytes());
        put(40, &self.h_acc_mm.to_le_bytes());
        put(44, &self.v_acc_mm.to_le_bytes());
        for (i, v) in self.vel_ned_mm_s.iter().enumerate() {
            put(48 + 4 * i, &v.to_le_bytes());
        }
        put(60, &self.g_speed_mm_s.to_le_bytes());
        put(64, &self.head_mot_e5.to_le_bytes());
        put(68, &self.s_acc_mm_s.to_le_bytes());
        put(72, &self.head_acc_e5.to_le_bytes());
        put(76, &self.pdop_e2.to_le_bytes());
        let mut out = EncodedFrame::new();
        out.extend(&[UBX_SYNC_1, UBX_SYNC_2, UBX_CLASS_NAV, UBX_ID_NAV_PVT]);
        out.extend(&(NAV_PVT_LEN as u16).to_le_bytes());
        out.extend(&p);
        let (a, b) = ubx_fletcher(&out.as_bytes()[2..]);
        out.extend(&[a, b]);
        out
    }

    /// Latitude, longitude (degrees) and ellipsoid height (m).
    pub fn geodetic(&self) -> Option<Geodetic> {
        Geodetic::new(
            f64::from(self.lat_e7) * 1e-7,
            f64::from(self.lon_e7) * 1e-7,
            f64::from(self.height_mm) * 1e-3,
        )
        .ok()
    }

    /// NED velocity (m/s).
    pub fn velocity_ned_m_s(&self) -> Vector3<f64> {
        Vector3::from(self.vel_ned_mm_s.map(|v| f64::from(v) * 1e-3))
    }

    /// The kind of fix: 3-D (or GNSS + dead reckoning) with gnssFixOK is
    /// [`GpsFixType::Fix3d`], 2-D with gnssFixOK is
    /// [`GpsFixType::Fix2d`], anything else no fix.
    pub fn gps_fix_type(&self) -> GpsFixType {
        let ok = self.flags & FLAG_GNSS_FIX_OK != 0;
        match self.fix_type {
            fix_type::FIX_3D | fix_type::GNSS_DEAD_RECKONING if ok => GpsFixType::Fix3d,
            fix_type::FIX_2D if ok => GpsFixType::Fix2d,
            _ => GpsFixType::NoFix,
        }
    }

    /// The fix in the local NED frame, stamped `epoch_s` on the on-board
    /// clock, with the Doppler velocity. A position out of range is no fix.
    pub fn to_gps_fix(&self, frame: &LocalNed, epoch_s: f64) -> GpsFix {
        let fix = self.gps_fix_type();
        match (fix, self.geodetic()) {
            (GpsFixType::Fix2d | GpsFixType::Fix3d, Some(p)) => GpsFix {
                epoch_s,
                fix,
                position_ned_m: frame.to_ned_m(&p),
                velocity_ned_m_s: Some(self.velocity_ned_m_s()),
            },
            _ => GpsFix {
                epoch_s,
                fix: GpsFixType::NoFix,
                position_ned_m: Vector3::zeros(),
                velocity_ned_m_s: None,
            },
        }
    }

    /// The solution a simulated receiver reports for `fix`: position and
    /// velocity quantised as the receiver does, `itow_ms` its time of week,
    /// geoid separation `geoid_separation_m` (height above MSL = ellipsoid
    /// height − separation), 12 satellites, PDOP 1.2, accuracies 1.5 m
    /// horizontal, 2.5 m vertical, 0.1 m/s speed. Without a velocity the
    /// velocity fields are zero.
    pub fn from_gps_fix(
        fix: &GpsFix,
        frame: &LocalNed,
        itow_ms: u32,
        geoid_separation_m: f64,
    ) -> Result<NavPvt, EncodeError> {
        for (field, v) in [
            ("GPS position", Some(fix.position_ned_m)),
            ("GPS velocity", fix.velocity_ned_m_s),
        ] {
            if let Some(bad) = v.and_then(|v| v.iter().copied().find(|x| !x.is_finite())) {
                return Err(EncodeError::NonFinite { field, value: bad });
            }
        }
        let p = frame.to_geodetic(&fix.position_ned_m);
        let p = Geodetic::new(p.latitude_deg, p.longitude_deg, p.height_m)?;
        let v = fix.velocity_ned_m_s.unwrap_or_else(Vector3::zeros);
        let (fix_type, flags, num_sv) = match fix.fix {
            GpsFixType::Fix3d => (fix_type::FIX_3D, FLAG_GNSS_FIX_OK, 12),
            GpsFixType::Fix2d => (fix_type::FIX_2D, FLAG_GNSS_FIX_OK, 4),
            GpsFixType::NoFix => (fix_type::NO_FIX, 0, 0),
        };
        let course = v.y.atan2(v.x).to_degrees().rem_euclid(360.0);
        Ok(NavPvt {
            itow_ms,
            fix_type,
            flags,
            num_sv,
            lon_e7: quantise_i32("longitude", p.longitude_deg, 1e-7)?,
            lat_e7: quantise_i32("latitude", p.latitude_deg, 1e-7)?,
            height_mm: quantise_i32("height", p.height_m, 1e-3)?,
            height_msl_mm: quantise_i32("height MSL", p.height_m - geoid_separation_m, 1e-3)?,
            h_acc_mm: 1500,
            v_acc_mm: 2500,
            vel_ned_mm_s: [
                quantise_i32("velocity north", v.x, 1e-3)?,
                quantise_i32("velocity east", v.y, 1e-3)?,
                quantise_i32("velocity down", v.z, 1e-3)?,
            ],
            g_speed_mm_s: quantise_i32("ground speed", v.x.hypot(v.y), 1e-3)?,
            head_mot_e5: quantise_i32("heading of motion", course, 1e-5)?,
            s_acc_mm_s: 100,
            head_acc_e5: 1_000_000,
            pdop_e2: 120,
            ..NavPvt::default()
        })
    }
}
