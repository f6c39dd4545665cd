//! The byte protocols the on-board computer speaks to its hardware, both
//! directions — decoding for the on-board software, encoding for the
//! software-in-the-loop side that plays the hardware — and the serial
//! transport they travel on.
//!
//! | device | protocol | module | decoder | message |
//! |---|---|---|---|---|
//! | IMU + magnetometer | VectorNav VN-100 binary output, Common group (*VN-100 User Manual*) | [`vectornav`] | [`VnBinaryDecoder`] | [`VnCommon`] |
//! | IMU + magnetometer | VectorNav ASCII `$VNYMR` | [`vectornav`] | [`VnAsciiDecoder`] | [`VnYmr`] |
//! | GPS | NMEA 0183 GGA, RMC, VTG | [`nmea0183`] | [`NmeaDecoder`] | [`NmeaMessage`] |
//! | GPS | u-blox UBX NAV-PVT (*u-blox M8 Receiver Description*) | [`ubx`] | [`UbxDecoder`] | [`NavPvt`] |
//! | servo board + RC receiver | this project's framed protocol with CRC-16 | [`avionics`] | [`AvionicsDecoder`] | [`AvionicsMessage`] |
//!
//! # Decoding
//!
//! Every decoder is a [`StreamDecoder`]: push byte chunks of any size as
//! they arrive, iterate the messages they complete. It keeps one fixed
//! buffer of [`MAX_FRAME_BYTES`] bytes, never allocates, never panics,
//! verifies every checksum, resynchronises after garbage, a bad checksum or
//! a frame cut short (a real frame hidden behind a false start is found),
//! and counts what it rejected ([`DecoderStats`]).
//!
//! ```
//! use helicon_devices::{AvionicsDecoder, AvionicsMessage, ServoCommand};
//! let frame = ServoCommand { seq: 7, armed: true, throttle_hold: false, servo_counts: [1850, 0, -12, 300] }.encode();
//! let mut bytes = b"line noise".to_vec();
//! bytes.extend_from_slice(frame.as_bytes());
//! let mut decoder = AvionicsDecoder::new();
//! // the first 14 bytes: the noise and half a frame, no message yet
//! assert_eq!(decoder.push(&bytes[..14]).count(), 0);
//! let later: Vec<_> = decoder.push(&bytes[14..]).collect();
//! assert!(matches!(later[..], [AvionicsMessage::Servo(ServoCommand { seq: 7, .. })]));
//! assert_eq!(decoder.stats().discarded_bytes, 10);
//! ```
//!
//! # Encoding
//!
//! Messages encode into an [`EncodedFrame`] (fixed-size, no allocation);
//! encoders refuse non-finite values and values the protocol cannot carry
//! with an [`EncodeError`] naming the field.
//!
//! # Conversions to the flight software
//!
//! - [`VnCommon::imu_sample`] / [`VnCommon::mag_body_gauss`] →
//!   [`helicon_core::sensor::ImuSample`] and the magnetometer vector (body
//!   FRD, gauss, the unit of the navigation's local field);
//!   [`VnCommon::from_samples`] the other way.
//! - [`NavPvt::to_gps_fix`] / [`Gga::to_gps_fix`] →
//!   [`helicon_core::sensor::GpsFix`] in the local NED frame of a home
//!   position ([`LocalNed`], WGS-84); [`NavPvt::from_gps_fix`] and
//!   [`nmea0183::sentences_from_fix`] the other way.
//! - [`ServoCommand::from_inputs`] / [`RcInput::applied`] ↔ the model's
//!   inputs `[S_col, S_lat, S_lon, S_tr]`.
//!
//! # Transport
//!
//! [`SerialLink`] (the `serialport` crate, no libudev), [`PtyPair`] (a raw
//! pseudo-terminal pair whose slave path the on-board side opens as its
//! serial port), [`StaleDetector`] (last-seen time and threshold per
//! sensor).

pub mod avionics;
pub mod checksum;
pub mod error;
pub mod framing;
pub mod geodetic;
pub mod nmea0183;
pub mod transport;
pub mod ubx;
pub mod vectornav;

pub use avionics::{AvionicsDecoder, AvionicsMessage, RcInput, ServoCommand};
pub use error::{EncodeError, TransportError};
pub use framing::{DecoderStats, EncodedFrame, MAX_FRAME_BYTES, Messages, StreamDecoder};
pub use geodetic::{Geodetic, LocalNed};
pub use nmea0183::{Gga, NmeaDecoder, NmeaMessage, Rmc, Vtg};
pub use transport::{PARTIAL_WRITE_WAIT, PtyPair, SerialLink, StaleDetector, Written};
pub use ubx::{NavPvt, UbxDecoder};
pub use vectornav::{VnAsciiDecoder, VnBinaryDecoder, VnCommon, VnMagPres, VnYmr};
