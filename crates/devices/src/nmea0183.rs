//! GPS in NMEA 0183: GGA, RMC and VTG sentences.
//!
//! Framing (`$`, at most 82 characters up to the line feed, `*hh` XOR
//! checksum) is this crate's streaming framer, so partial reads, garbage and
//! checksum failures are handled and counted uniformly; the fields of a
//! sentence whose checksum holds are parsed by the `nmea` crate (which does
//! not stream and does not write). Encoding is by hand, with the field widths
//! of a u-blox M8 receiver: latitude/longitude in degrees and minutes with 5
//! decimals of a minute (1e-5′ ≈ 1.9 cm), altitude and geoid separation in
//! 0.1 m, speed in 0.001 kn, course in 0.01°, UTC time in 0.01 s.
//!
//! NMEA carries no vertical velocity, so a [`GpsFix`] assembled from it has
//! no velocity; fly NAV-PVT (see [`crate::ubx`]) for Doppler velocity. GGA
//! does not distinguish 2-D from 3-D fixes: a valid quality with an altitude
//! is taken as 3-D.

use crate::error::{EncodeError, check_range};
use crate::framing::{EncodedFrame, FrameStatus, Protocol, Reject, StreamDecoder};
use crate::geodetic::{Geodetic, LocalNed};
use crate::vectornav::{finish_sentence, sentence_body, sentence_status};
use chrono::{Datelike, Timelike};
use core::fmt::Write;
use helicon_core::sensor::{GpsFix, GpsFixType};

/// Longest NMEA 0183 sentence (`$` to line feed inclusive), as the standard
/// limits it.
pub const NMEA_MAX_SENTENCE: usize = 82;

/// Knots per m/s.
const KNOTS_PER_M_S: f64 = 3600.0 / 1852.0;

/// GGA: fix data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gga {
    /// UTC time of the fix (seconds of the day).
    pub utc_time_s: Option<f64>,
    /// Latitude (degrees).
    pub latitude_deg: Option<f64>,
    /// Longitude (degrees).
    pub longitude_deg: Option<f64>,
    /// Fix quality: 0 invalid, 1 GPS, 2 DGPS, 3 PPS, 4 RTK, 5 float RTK,
    /// 6 estimated, 7 manual, 8 simulation.
    pub quality: u8,
    /// Satellites used.
    pub satellites: Option<u8>,
    /// Horizontal dilution of precision.
    pub hdop: Option<f64>,
    /// Altitude above mean sea level (m).
    pub altitude_msl_m: Option<f64>,
    /// Geoid separation: ellipsoid height minus MSL altitude (m).
    pub geoid_separation_m: Option<f64>,
}

/// RMC: recommended minimum data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rmc {
    /// UTC time (seconds of the day).
    pub utc_time_s: Option<f64>,
    /// UTC date (year, month, day). RMC carries a two-digit year, read as
    /// 1983–2082; the encoder refuses years outside that window.
    pub date: Option<(i32, u8, u8)>,
    /// Status `A` (valid).
    pub valid: bool,
    /// Latitude (degrees).
    pub latitude_deg: Option<f64>,
    /// Longitude (degrees).
    pub longitude_deg: Option<f64>,
    /// Speed over ground (knots).
    pub speed_knots: Option<f64>,
    /// Course over ground, true (degrees).
    pub course_true_deg: Option<f64>,
}

/// VTG: course and speed over ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vtg {
    /// Course over ground, true (degrees).
    pub course_true_deg: Option<f64>,
    /// Speed over ground (knots).
    pub speed_knots: Option<f64>,
}

/// A decoded NMEA sentence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NmeaMessage {
    /// GGA.
    Gga(Gga),
    /// RMC.
    Rmc(Rmc),
    /// VTG.
    Vtg(Vtg),
}

fn seconds_of_day(t: &chrono::NaiveTime) -> f64 {
    f64::from(t.num_seconds_from_midnight()) + f64::from(t.nanosecond()) * 1e-9
}

fn finite(x: Option<f64>) -> Result<Option<f64>, Reject> {
    match x {
        Some(v) if !v.is_finite() => Err(Reject::Unsupported),
        v => Ok(v),
    }
}

/// The NMEA 0183 protocol (GGA, RMC, VTG) for [`StreamDecoder`].
#[derive(Debug, Clone, Copy)]
pub struct Nmea;

impl Protocol for Nmea {
    type Message = NmeaMessage;
    const MAX_FRAME: usize = NMEA_MAX_SENTENCE;

    fn is_start(byte: u8) -> bool {
        byte == b'$'
    }

    fn status(c: &[u8]) -> FrameStatus {
        sentence_status(c, NMEA_MAX_SENTENCE)
    }

    fn decode(frame: &[u8]) -> Result<NmeaMessage, Reject> {
        sentence_body(frame)?;
        let line = frame.trim_ascii_end();
        let parsed = nmea::parse_bytes(line).map_err(|_| Reject::Unsupported)?;
        let msg = match parsed {
            nmea::ParseResult::GGA(g) => NmeaMessage::Gga(Gga {
                utc_time_s: g.fix_time.as_ref().map(seconds_of_day),
                latitude_deg: finite(g.latitude)?,
                longitude_deg: finite(g.longitude)?,
                quality: g.fix_type.map_or(0, fix_quality),
                satellites: g.fix_satellites.and_then(|n| u8::try_from(n).ok()),
                hdop: finite(g.hdop.map(f64::from))?,
                altitude_msl_m: finite(g.altitude.map(f64::from))?,
                geoid_separation_m: finite(g.geoid_separation.map(f64::from))?,
            }),
            nmea::ParseResult::RMC(r) => NmeaMessage::Rmc(Rmc {
                utc_time_s: r.fix_time.as_ref().map(seconds_of_day),
                date: r
                    .fix_date
                    .map(|d| (d.year(), d.month() as u8, d.day() as u8)),
                valid: matches!(
                    r.status_of_fix,
                    nmea::sentences::rmc::RmcStatusOfFix::Autonomous
                        | nmea::sentences::rmc::RmcStatusOfFix::Differential
                ),
                latitude_deg: finite(r.lat)?,
                longitude_deg: finite(r.lon)?,
                speed_knots: finite(r.speed_over_ground.map(f64::from))?,
                course_true_deg: finite(r.true_course.map(f64::from))?,
            }),
            nmea::ParseResult::VTG(v) => NmeaMessage::Vtg(Vtg {
                course_true_deg: finite(v.true_course.map(f64::from))?,
                speed_knots: finite(v.speed_over_ground.map(f64::from))?,
            }),
            _ => return Err(Reject::Unsupported),
        };
        Ok(msg)
    }
}

fn fix_quality(f: nmea::sentences::FixType) -> u8 {
    use nmea::sentences::FixType as F;
    match f {
        F::Invalid => 0,
        F::Gps => 1,
        F::DGps => 2,
        F::Pps => 3,
        F::Rtk => 4,
        F::FloatRtk => 5,
        F::Estimated => 6,
        F::Manual => 7,
        F::Simulation => 8,
    }
}

/// Streaming decoder of NMEA 0183 GGA/RMC/VTG sentences.
pub type NmeaDecoder = StreamDecoder<Nmea>;

// ------------------------------------------------------------- encoding ---

fn too_long(_: core::fmt::Error) -> EncodeError {
    EncodeError::TooLong {
        limit: NMEA_MAX_SENTENCE,
    }
}

fn write_time(out: &mut EncodedFrame, t: Option<f64>) -> Result<(), EncodeError> {
    if let Some(t) = t {
        let cs = (check_range("utc_time_s", t, 0.0, 86_399.994)? * 100.0).round() as u64;
        let (h, m, s, c) = (cs / 360_000, cs / 6000 % 60, cs / 100 % 60, cs % 100);
        write!(out, "{h:02}{m:02}{s:02}.{c:02}").map_err(too_long)?;
    }
    Ok(())
}

/// Writes `ddmm.mmmmm,N` (or `dddmm.mmmmm,E` for longitude); empty fields
/// when absent.
fn write_angle(out: &mut EncodedFrame, v: Option<f64>, lat: bool) -> Result<(), EncodeError> {
    let Some(v) = v else {
        return write!(out, ",").map_err(too_long);
    };
    let (field, max, width) = if lat {
        ("latitude_deg", 90.0, 2)
    } else {
        ("longitude_deg", 180.0, 3)
    };
    let v = check_range(field, v, -max, max)?;
    let hemi = match (lat, v < 0.0) {
        (true, false) => 'N',
        (true, true) => 'S',
        (false, false) => 'E',
        (false, true) => 'W',
    };
    // integer 1e-5 arc-minutes, so a carry never prints 60.00000′
    let total = (v.abs() * 60.0 * 1e5).round() as u64;
    let (deg, min_e5) = (total / 6_000_000, total % 6_000_000);
    write!(
        out,
        "{deg:0width$}{:02}.{:05},{hemi}",
        min_e5 / 100_000,
        min_e5 % 100_000
    )
    .map_err(too_long)
}

fn write_opt(out: &mut EncodedFrame, v: Option<f64>, decimals: usize) -> Result<(), EncodeError> {
    if let Some(v) = v {
        check_range("NMEA field", v, -1e6, 1e6)?;
        write!(out, "{v:.decimals$}").map_err(too_long)?;
    }
    Ok(())
}

impl Gga {
    /// Encodes a `$GPGGA` sentence.
    pub fn encode(&self) -> Result<EncodedFrame, EncodeError> {
        let mut out = EncodedFrame::new();
        write!(out, "$GPGGA,").map_err(too_long)?;
        write_time(&mut out, self.utc_time_s)?;
        write!(out, ",").map_err(too_long)?;
        write_angle(&mut out, self.latitude_deg, true)?;
        write!(out, ",").map_err(too_long)?;
        write_angle(&mut out, self.longitude_deg, false)?;
        check_range("quality", f64::from(self.quality), 0.0, 8.0)?;
        write!(out, ",{},", self.quality).map_err(too_long)?;
        if let Some(n) = self.satellites {
            write!(out, "{n:02}").map_err(too_long)?;
        }
        write!(out, ",").map_err(too_long)?;
        write_opt(&mut out, self.hdop, 2)?;
        write!(out, ",").map_err(too_long)?;
        write_opt(&mut out, self.altitude_msl_m, 1)?;
        write!(out, ",M,").map_err(too_long)?;
        write_opt(&mut out, self.geoid_separation_m, 1)?;
        write!(out, ",M,,").map_err(too_long)?;
        finish(out)
    }
}

fn finish(mut out: EncodedFrame) -> Result<EncodedFrame, EncodeError> {
    finish_sentence(&mut out)?;
    if out.len() > NMEA_MAX_SENTENCE {
        return Err(EncodeError::TooLong {
            limit: NMEA_MAX_SENTENCE,
        });
    }
    Ok(out)
}

impl Rmc {
    /// Encodes a `$GPRMC` sentence (NMEA 2.3 form with the mode indicator).
    pub fn encode(&self) -> Result<EncodedFrame, EncodeError> {
        let mut out = EncodedFrame::new();
        write!(out, "$GPRMC,").map_err(too_long)?;
        write_time(&mut out, self.utc_time_s)?;
        let status = if self.valid { 'A' } else { 'V' };
        write!(out, ",{status},").map_err(too_long)?;
        write_angle(&mut out, self.latitude_deg, true)?;
        write!(out, ",").map_err(too_long)?;
        write_angle(&mut out, self.longitude_deg, false)?;
        write!(out, ",").map_err(too_long)?;
        write_opt(&mut out, self.speed_knots, 3)?;
        write!(out, ",").map_err(too_long)?;
        write_opt(&mut out, self.course_true_deg, 2)?;
        write!(out, ",").map_err(too_long)?;
        if let Some((y, m, d)) = self.date {
            // the two-digit year reads back as 1983–2082 (the `nmea` crate's window)
            check_range("year", f64::from(y), 1983.0, 2082.0)?;
            check_range("month", f64::from(m), 1.0, 12.0)?;
            check_range("day", f64::from(d), 1.0, 31.0)?;
            write!(out, "{d:02}{m:02}{:02}", y.rem_euclid(100)).map_err(too_long)?;
        }
        let mode = if self.valid { 'A' } else { 'N' };
        write!(out, ",,,{mode}").map_err(too_long)?;
        finish(out)
    }
}

impl Vtg {
    /// Encodes a `$GPVTG` sentence (NMEA 2.3 form, speed also in km/h).
    pub fn encode(&self) -> Result<EncodedFrame, EncodeError> {
        let mut out = EncodedFrame::new();
        write!(out, "$GPVTG,").map_err(too_long)?;
        write_opt(&mut out, self.course_true_deg, 2)?;
        write!(out, ",T,,M,").map_err(too_long)?;
        write_opt(&mut out, self.speed_knots, 3)?;
        write!(out, ",N,").map_err(too_long)?;
        write_opt(&mut out, self.speed_knots.map(|k| k * 1.852), 3)?;
        let mode = if self.speed_knots.is_some() { 'A' } else { 'N' };
        write!(out, ",K,{mode}").map_err(too_long)?;
        finish(out)
    }
}

// ---------------------------------------------------------- conversions ---

/// The sentences a simulated receiver sends for one solution: GGA (position,
/// quality 1 for a fix, 0 otherwise), RMC and VTG (ground speed and course
/// from the NED velocity). `utc_time_s` is the UTC time of the epoch
/// (seconds of the day), `geoid_separation_m` the local geoid height.
pub fn sentences_from_fix(
    fix: &GpsFix,
    frame: &LocalNed,
    utc_time_s: f64,
    geoid_separation_m: f64,
) -> Result<[NmeaMessage; 3], EncodeError> {
    let p = frame.to_geodetic(&fix.position_ned_m);
    let has_fix = fix.fix != GpsFixType::NoFix;
    let (speed_knots, course) = match fix.velocity_ned_m_s {
        Some(v) => {
            let course = v.y.atan2(v.x).to_degrees().rem_euclid(360.0);
            (Some(v.x.hypot(v.y) * KNOTS_PER_M_S), Some(course))
        }
        None => (None, None),
    };
    let pos = |x: f64| has_fix.then_some(x);
    Ok([
        NmeaMessage::Gga(Gga {
            utc_time_s: Some(utc_time_s),
            latitude_deg: pos(p.latitude_deg),
            longitude_deg: pos(p.longitude_deg),
            quality: u8::from(has_fix),
            satellites: Some(if has_fix { 10 } else { 0 }),
            hdop: Some(if has_fix { 0.9 } else { 99.99 }),
            altitude_msl_m: pos(p.height_m - geoid_separation_m),
            geoid_separation_m: Some(geoid_separation_m),
        }),
        NmeaMessage::Rmc(Rmc {
            utc_time_s: Some(utc_time_s),
            date: None,
            valid: has_fix,
            latitude_deg: pos(p.latitude_deg),
            longitude_deg: pos(p.longitude_deg),
            speed_knots,
            course_true_deg: course,
        }),
        NmeaMessage::Vtg(Vtg {
            course_true_deg: course,
            speed_knots,
        }),
    ])
}

impl NmeaMessage {
    /// Encodes the sentence.
    pub fn encode(&self) -> Result<EncodedFrame, EncodeError> {
        match self {
            NmeaMessage::Gga(g) => g.encode(),
            NmeaMessage::Rmc(r) => r.encode(),
            NmeaMessage::Vtg(v) => v.encode(),
        }
    }
}

impl Gga {
    /// The fix in the local NED frame, stamped `epoch_s` on the on-board
    /// clock. Quality 0 or a missing latitude, longitude or altitude is no
    /// fix; otherwise 3-D. No velocity (NMEA has no vertical velocity).
    pub fn to_gps_fix(&self, frame: &LocalNed, epoch_s: f64) -> GpsFix {
        let position = match (
            self.quality,
            self.latitude_deg,
            self.longitude_deg,
            self.altitude_msl_m,
        ) {
            (1.., Some(lat), Some(lon), Some(alt)) => {
                let h = alt + self.geoid_separation_m.unwrap_or(0.0);
                Geodetic::new(lat, lon, h).ok()
            }
            _ => None,
        };
        match position {
            Some(p) => GpsFix {
                epoch_s,
                fix: GpsFixType::Fix3d,
                position_ned_m: frame.to_ned_m(&p),
                velocity_ned_m_s: None,
            },
            None => GpsFix {
                epoch_s,
                fix: GpsFixType::NoFix,
                position_ned_m: nalgebra::Vector3::zeros(),
                velocity_ned_m_s: None,
            },
        }
    }
}
