//! ArduPilot's JSON physics interface (`libraries/SITL/SIM_JSON.cpp`, its
//! `examples/JSON/readme.md`): the servo packet ArduPilot sends, and the
//! state line the physics answers.
//!
//! ```text
//! servo packet (little-endian, as SITL's struct on its host):
//!   u16 magic = 18458 (16 channels) | 29569 (32 channels, SERVO_32_ENABLE = 1)
//!   u16 frame_rate   (Hz: the time step the physics should take)
//!   u32 frame_count  (one more per frame; back to 0 when SITL restarts)
//!   u16 pwm[16 | 32] (µs)
//! reply: "\n" + one JSON object + "\n", e.g.
//!   {"timestamp":0.0025,"imu":{"gyro":[p,q,r],"accel_body":[fx,fy,fz]},
//!    "position":[n,e,d],"velocity":[vn,ve,vd],"attitude":[roll,pitch,yaw]}
//! ```
//!
//! ArduPilot's parser looks a key up by name and reads the number right
//! after `"key":`, so the line has no spaces; the numbers are Rust's
//! shortest round-trip form (never an exponent, which `atof`/`sscanf`
//! would read anyway).

use std::fmt::Write as _;

/// The magic number of a 16-channel packet.
pub const MAGIC_16: u16 = 18458;
/// The magic number of a 32-channel packet.
pub const MAGIC_32: u16 = 29569;
/// The size of a 16-channel packet (bytes).
pub const SIZE_16: usize = 8 + 2 * 16;
/// The size of a 32-channel packet (bytes).
pub const SIZE_32: usize = 8 + 2 * 32;
/// The frame rates accepted (Hz): ArduPilot's `SIM_RATE_HZ` is kept above
/// the vehicle's loop rate (400 Hz on copters and helicopters).
pub const FRAME_RATE_HZ: std::ops::RangeInclusive<u16> = 20..=8000;
/// The PWM values accepted (µs; 0 is a channel with no output yet).
pub const PWM_US: std::ops::RangeInclusive<u16> = 0..=3000;

/// One servo packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ServoPacket {
    /// The physics step asked for (Hz).
    pub frame_rate_hz: u16,
    /// The frame's number.
    pub frame_count: u32,
    /// The PWM of `SERVO1 …` (µs); `channels` of them are valid.
    pub pwm: [u16; 32],
    /// 16 or 32.
    pub channels: usize,
}

impl ServoPacket {
    /// The valid PWM values.
    pub fn pwm(&self) -> &[u16] {
        &self.pwm[..self.channels]
    }

    /// The packet's bytes (what ArduPilot sends), for stand-ins and tests.
    pub fn encode(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(SIZE_32);
        let magic = if self.channels == 32 {
            MAGIC_32
        } else {
            MAGIC_16
        };
        b.extend_from_slice(&magic.to_le_bytes());
        b.extend_from_slice(&self.frame_rate_hz.to_le_bytes());
        b.extend_from_slice(&self.frame_count.to_le_bytes());
        for v in self.pwm() {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b
    }
}

/// Why a packet was ignored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PacketError {
    /// Neither 40 nor 72 bytes.
    #[error("{0} bytes: a servo packet has 40 (16 channels) or 72 (32 channels)")]
    Size(usize),
    /// An unknown magic number, or one that does not match the size.
    #[error("magic {magic} in a packet of {size} bytes (18458: 40 bytes, 29569: 72 bytes)")]
    Magic {
        /// The magic read.
        magic: u16,
        /// The packet's size.
        size: usize,
    },
    /// A frame rate outside [`FRAME_RATE_HZ`].
    #[error("frame rate {0} Hz outside 20 ..= 8000 Hz")]
    FrameRate(u16),
    /// A PWM value outside [`PWM_US`].
    #[error("SERVO{channel} = {value} µs outside 0 ..= 3000 µs")]
    Pwm {
        /// The output (1-based).
        channel: usize,
        /// Its value.
        value: u16,
    },
}

/// Read a servo packet.
pub fn parse_servo_packet(b: &[u8]) -> Result<ServoPacket, PacketError> {
    let channels = match b.len() {
        SIZE_16 => 16,
        SIZE_32 => 32,
        n => return Err(PacketError::Size(n)),
    };
    let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
    let magic = u16_at(0);
    if !((magic == MAGIC_16 && channels == 16) || (magic == MAGIC_32 && channels == 32)) {
        return Err(PacketError::Magic {
            magic,
            size: b.len(),
        });
    }
    let frame_rate_hz = u16_at(2);
    if !FRAME_RATE_HZ.contains(&frame_rate_hz) {
        return Err(PacketError::FrameRate(frame_rate_hz));
    }
    let frame_count = u32::from_le_bytes([b[4], b[5], b[6], b[7]]);
    let mut pwm = [0u16; 32];
    for (i, v) in pwm.iter_mut().take(channels).enumerate() {
        *v = u16_at(8 + 2 * i);
        if !PWM_US.contains(v) {
            return Err(PacketError::Pwm {
                channel: i + 1,
                value: *v,
            });
        }
    }
    Ok(ServoPacket {
        frame_rate_hz,
        frame_count,
        pwm,
        channels,
    })
}

/// The state ArduPilot reads, in its frames and units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PhysicsState {
    /// Physics time (s).
    pub timestamp_s: f64,
    /// Body rates, body FRD (rad/s).
    pub gyro_rad_s: [f64; 3],
    /// Specific force, body FRD (m/s²): (0, 0, −g) at rest, level.
    pub accel_body_m_s2: [f64; 3],
    /// Position from the home on the ground, NED (m).
    pub position_ned_m: [f64; 3],
    /// Velocity, NED (m/s).
    pub velocity_ned_m_s: [f64; 3],
    /// 3-2-1 Euler angles roll, pitch, yaw (rad).
    pub attitude_rad: [f64; 3],
}

impl PhysicsState {
    /// All its numbers are finite (a reply can be written).
    pub fn is_finite(&self) -> bool {
        self.timestamp_s.is_finite()
            && [
                self.gyro_rad_s,
                self.accel_body_m_s2,
                self.position_ned_m,
                self.velocity_ned_m_s,
                self.attitude_rad,
            ]
            .iter()
            .flatten()
            .all(|v| v.is_finite())
    }

    /// Write the reply line into `out` (cleared first; no allocation once
    /// `out` has grown to a line's size): `"\n{…}\n"`.
    pub fn write_json(&self, out: &mut String) {
        out.clear();
        let v = |out: &mut String, key: &str, a: &[f64; 3]| {
            let _ = write!(out, "\"{key}\":[{},{},{}]", a[0], a[1], a[2]);
        };
        let _ = write!(out, "\n{{\"timestamp\":{},\"imu\":{{", self.timestamp_s);
        v(out, "gyro", &self.gyro_rad_s);
        out.push(',');
        v(out, "accel_body", &self.accel_body_m_s2);
        out.push_str("},");
        v(out, "position", &self.position_ned_m);
        out.push(',');
        v(out, "velocity", &self.velocity_ned_m_s);
        out.push(',');
        v(out, "attitude", &self.attitude_rad);
        out.push_str("}\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_packet_reads_back() {
        let mut pwm = [0u16; 32];
        for (i, v) in pwm.iter_mut().enumerate() {
            *v = 1000 + i as u16;
        }
        for channels in [16, 32] {
            let p = ServoPacket {
                frame_rate_hz: 400,
                frame_count: 7,
                pwm,
                channels,
            };
            let b = p.encode();
            assert_eq!(b.len(), if channels == 16 { SIZE_16 } else { SIZE_32 });
            let mut q = parse_servo_packet(&b).unwrap();
            if channels == 16 {
                q.pwm[16..].copy_from_slice(&pwm[16..]);
            }
            assert_eq!(q, p);
        }
    }

    #[test]
    fn bad_packets_are_named() {
        let p = ServoPacket {
            frame_rate_hz: 400,
            frame_count: 1,
            pwm: [1500; 32],
            channels: 16,
        };
        let good = p.encode();
        assert_eq!(parse_servo_packet(&good[..39]), Err(PacketError::Size(39)));
        let mut b = good.clone();
        b[0] = 0;
        assert!(matches!(
            parse_servo_packet(&b),
            Err(PacketError::Magic { .. })
        ));
        let mut b = good.clone();
        b[2..4].copy_from_slice(&0u16.to_le_bytes());
        assert_eq!(parse_servo_packet(&b), Err(PacketError::FrameRate(0)));
        let mut b = good;
        b[8 + 2 * 5..8 + 2 * 6].copy_from_slice(&3001u16.to_le_bytes());
        assert_eq!(
            parse_servo_packet(&b),
            Err(PacketError::Pwm {
                channel: 6,
                value: 3001
            })
        );
    }

    #[test]
    fn the_reply_is_a_json_line_without_spaces() {
        let s = PhysicsState {
            timestamp_s: 0.0025,
            accel_body_m_s2: [0.0, 0.0, -9.82],
            attitude_rad: [0.1, -0.2, 3.0],
            ..PhysicsState::default()
        };
        let mut out = String::new();
        s.write_json(&mut out);
        assert!(out.starts_with('\n') && out.ends_with('\n'));
        assert!(!out.contains(' '));
        let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
        assert_eq!(v["timestamp"], 0.0025);
        assert_eq!(v["imu"]["accel_body"][2], -9.82);
        assert_eq!(v["attitude"][1], -0.2);
    }
}
