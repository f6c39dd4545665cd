//! The avionics interface (the thesis's servo board with the pilot switch,
//! §3.1.2): this project's own framed protocol, both directions on one
//! serial line. Byte layout (all multi-byte fields little-endian):
//!
//! ```text
//! offset  size  field
//! 0       2     sync 0xA5 0x5A
//! 2       1     payload length L
//! 3       1     message type (0x01 servo command, 0x02 RC input)
//! 4       1     sequence number (wraps at 255)
//! 5       L     payload
//! 5+L     2     CRC-16/CCITT-FALSE over bytes 2 … 4+L (length, type,
//!               sequence, payload), little-endian
//! ```
//!
//! Servo command (computer → avionics, type 0x01, L = 9): `flags` (u8, bit 0
//! armed, bit 1 throttle hold: the engine cut), then the four servo commands `[S_col, S_lat, S_lon, S_tr]` in the
//! model's units as i16 in steps of 1e-4 (range ±3.2767; the model's servo
//! ranges are within ±0.75).
//!
//! RC input (avionics → computer, type 0x02, L = 26): `flags` (u8, bit 0 the
//! pilot's switch in autonomous, bit 1 receiver failsafe), eight receiver
//! channels as u16 pulse widths in µs, the four servo positions actually
//! applied (i16, 1e-4, whichever source drove them) and the sequence number
//! of the last servo command applied (u8).

use crate::checksum::AVIONICS_CRC;
use crate::error::{EncodeError, check_range};
use crate::framing::{EncodedFrame, FrameStatus, Protocol, Reject, StreamDecoder};
use helicon_core::state::Input;

/// First sync byte.
pub const AVIONICS_SYNC_1: u8 = 0xA5;
/// Second sync byte.
pub const AVIONICS_SYNC_2: u8 = 0x5A;
/// Message type of a servo command.
pub const TYPE_SERVO_COMMAND: u8 = 0x01;
/// Message type of an RC input report.
pub const TYPE_RC_INPUT: u8 = 0x02;
/// Servo quantum (model units per count).
pub const SERVO_QUANTUM: f64 = 1e-4;
/// Receiver channels carried.
pub const RC_CHANNELS: usize = 8;
/// Servo-command payload length.
const SERVO_LEN: usize = 9;
/// RC-input payload length.
const RC_LEN: usize = 1 + 2 * RC_CHANNELS + 8 + 1;
/// Largest frame: header 5, payload, CRC 2.
const AVIONICS_MAX_FRAME: usize = 5 + RC_LEN + 2;

/// Servo commands, computer → avionics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ServoCommand {
    /// Sequence number (the avionics echoes the last one applied).
    pub seq: u8,
    /// The computer's permission to drive the servos; the avionics holds
    /// the servos at the pilot's commands when false.
    pub armed: bool,
    /// Throttle hold: the engine cut (at idle with the rotor free), as a
    /// helicopter's throttle-hold switch; clear, the governor runs the
    /// rotor up to its speed and holds it.
    pub throttle_hold: bool,
    /// `[S_col, S_lat, S_lon, S_tr]` in counts of [`SERVO_QUANTUM`].
    pub servo_counts: [i16; 4],
}

/// Receiver state and applied servo positions, avionics → computer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RcInput {
    /// Sequence number of this report.
    pub seq: u8,
    /// The pilot's switch is in autonomous (the computer's commands drive
    /// the servos); false is manual.
    pub autonomous: bool,
    /// The receiver lost the transmitter and outputs its failsafe values.
    pub failsafe: bool,
    /// Receiver channel pulse widths (µs, nominally 1000–2000).
    pub channels_us: [u16; RC_CHANNELS],
    /// Servo positions actually applied, in counts of [`SERVO_QUANTUM`].
    pub applied_counts: [i16; 4],
    /// Sequence number of the last servo command applied.
    pub last_command_seq: u8,
}

/// A decoded avionics message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AvionicsMessage {
    /// Servo command.
    Servo(ServoCommand),
    /// RC input report.
    Rc(RcInput),
}

/// Model units → counts, or an error naming the servo.
fn to_counts(u: &Input) -> Result<[i16; 4], EncodeError> {
    const NAMES: [&str; 4] = ["S_col", "S_lat", "S_lon", "S_tr"];
    let max = f64::from(i16::MAX) * SERVO_QUANTUM;
    let mut out = [0i16; 4];
    for i in 0..4 {
        out[i] = (check_range(NAMES[i], u[i], -max, max)? / SERVO_QUANTUM).round() as i16;
    }
    Ok(out)
}

fn to_units(c: &[i16; 4]) -> Input {
    Input::from_fn(|i, _| f64::from(c[i]) * SERVO_QUANTUM)
}

impl ServoCommand {
    /// A command from servo inputs in model units (rounded to 1e-4).
    pub fn from_inputs(seq: u8, armed: bool, u: &Input) -> Result<Self, EncodeError> {
        Ok(Self {
            seq,
            armed,
            throttle_hold: false,
            servo_counts: to_counts(u)?,
        })
    }

    /// The servo inputs in model units.
    pub fn inputs(&self) -> Input {
        to_units(&self.servo_counts)
    }

    /// Encodes the frame.
    pub fn encode(&self) -> EncodedFrame {
        let mut p = [0u8; SERVO_LEN];
        p[0] = u8::from(self.armed) | (u8::from(self.throttle_hold) << 1);
        for (i, c) in self.servo_counts.iter().enumerate() {
            p[1 + 2 * i..3 + 2 * i].copy_from_slice(&c.to_le_bytes());
        }
        frame(TYPE_SERVO_COMMAND, self.seq, &p)
    }
}

impl RcInput {
    /// Sets the applied servo positions from model units.
    pub fn with_applied(mut self, u: &Input) -> Result<Self, EncodeError> {
        self.applied_counts = to_counts(u)?;
        Ok(self)
    }

    /// The applied servo positions in model units.
    pub fn applied(&self) -> Input {
        to_units(&self.applied_counts)
    }

    /// Encodes the frame.
    pub fn encode(&self) -> EncodedFrame {
        let mut p = [0u8; RC_LEN];
        p[0] = u8::from(self.autonomous) | (u8::from(self.failsafe) << 1);
        for (i, c) in self.channels_us.iter().enumerate() {
            p[1 + 2 * i..3 + 2 * i].copy_from_slice(&c.to_le_bytes());
        }
        let base = 1 + 2 * RC_CHANNELS;
        for (i, c) in self.applied_counts.iter().enumerate() {
            p[base + 2 * i..base + 2 + 2 * i].copy_from_slice(&c.to_le_bytes());
        }
        p[RC_LEN - 1] = self.last_command_seq;
        frame(TYPE_RC_INPUT, self.seq, &p)
    }
}

impl AvionicsMessage {
    /// Encodes the frame.
    pub fn encode(&self) -> EncodedFrame {
        match self {
            AvionicsMessage::Servo(s) => s.encode(),
            AvionicsMessage::Rc(r) => r.encode(),
        }
    }
}

fn frame(kind: u8, seq: u8, payload: &[u8]) -> EncodedFrame {
    let mut out = EncodedFrame::new();
    out.extend(&[
        AVIONICS_SYNC_1,
        AVIONICS_SYNC_2,
        payload.len() as u8,
        kind,
        seq,
    ]);
    out.extend(payload);
    let crc = AVIONICS_CRC.checksum(&out.as_bytes()[2..]);
    out.extend(&crc.to_le_bytes());
    out
}

fn i16_at(p: &[u8], i: usize) -> i16 {
    i16::from_le_bytes([p[i], p[i + 1]])
}

/// The avionics protocol for [`StreamDecoder`].
#[derive(Debug, Clone, Copy)]
pub struct Avionics;

impl Protocol for Avionics {
    type Message = AvionicsMessage;
    const MAX_FRAME: usize = AVIONICS_MAX_FRAME;

    fn is_start(byte: u8) -> bool {
        byte == AVIONICS_SYNC_1
    }

    fn status(c: &[u8]) -> FrameStatus {
        if c.len() >= 2 && c[1] != AVIONICS_SYNC_2 {
            return FrameStatus::Malformed;
        }
        if c.len() < 3 {
            return FrameStatus::Incomplete;
        }
        let n = 5 + usize::from(c[2]) + 2;
        if n > AVIONICS_MAX_FRAME {
            FrameStatus::Oversize
        } else if c.len() < n {
            FrameStatus::Incomplete
        } else {
            FrameStatus::Complete(n)
        }
    }

    fn decode(f: &[u8]) -> Result<AvionicsMessage, Reject> {
        let n = f.len();
        if AVIONICS_CRC.checksum(&f[2..n - 2]) != u16::from_le_bytes([f[n - 2], f[n - 1]]) {
            return Err(Reject::Checksum);
        }
        let (kind, seq, p) = (f[3], f[4], &f[5..n - 2]);
        match (kind, p.len()) {
            (TYPE_SERVO_COMMAND, SERVO_LEN) if p[0] & !3 == 0 => {
                Ok(AvionicsMessage::Servo(ServoCommand {
                    seq,
                    armed: p[0] & 1 != 0,
                    throttle_hold: p[0] & 2 != 0,
                    servo_counts: core::array::from_fn(|i| i16_at(p, 1 + 2 * i)),
                }))
            }
            (TYPE_RC_INPUT, RC_LEN) if p[0] & !3 == 0 => {
                let base = 1 + 2 * RC_CHANNELS;
                Ok(AvionicsMessage::Rc(RcInput {
                    seq,
                    autonomous: p[0] & 1 != 0,
                    failsafe: p[0] & 2 != 0,
                    channels_us: core::array::from_fn(|i| {
                        u16::from_le_bytes([p[1 + 2 * i], p[2 + 2 * i]])
                    }),
                    applied_counts: core::array::from_fn(|i| i16_at(p, base + 2 * i)),
                    last_command_seq: p[RC_LEN - 1],
                }))
            }
            _ => Err(Reject::Unsupported),
        }
    }
}

/// Streaming decoder of avionics frames (either direction).
pub type AvionicsDecoder = StreamDecoder<Avionics>;
