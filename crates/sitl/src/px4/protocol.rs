//! MAVLink framing on PX4's simulator TCP stream, without allocating: a
//! fixed buffer the socket reads into, cut into frames (MAVLink 2 and 1),
//! each checked (CRC, known message id, payload) and parsed into the
//! common dialect's message; and the simulator's messages serialized into
//! a fixed buffer.

use helicon_gcs::mavlink::dialects::common::MavMessage;
use helicon_gcs::mavlink::{
    MAVLinkV1MessageRaw, MAVLinkV2MessageRaw, MavHeader, MavlinkVersion, Message,
};

const STX_V2: u8 = 0xFD;
const STX_V1: u8 = 0xFE;
/// The buffer: larger than any frame (280 bytes) many times over.
const BUFFER: usize = 4096;

/// Why bytes of the stream were not a message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// Bytes outside any frame (before a start marker), this many.
    Junk(usize),
    /// A frame whose checksum does not match (its start marker is skipped).
    Crc,
    /// A checked frame of a message id the common dialect does not have.
    UnknownId(u32),
    /// A frame whose payload does not parse (e.g. an enum value out of range).
    Payload(u32),
}

/// The receive side: bytes in, messages out.
pub struct Framer {
    buf: Box<[u8; BUFFER]>,
    len: usize,
    raw2: Box<MAVLinkV2MessageRaw>,
    raw1: Box<MAVLinkV1MessageRaw>,
}

impl std::fmt::Debug for Framer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Framer").field("len", &self.len).finish()
    }
}

impl Default for Framer {
    fn default() -> Self {
        Framer::new()
    }
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Self {
        Framer {
            buf: Box::new([0; BUFFER]),
            len: 0,
            raw2: Box::new(MAVLinkV2MessageRaw::new()),
            raw1: Box::new(MAVLinkV1MessageRaw::new()),
        }
    }

    /// Forget the buffered bytes (a new connection).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// The free space to read into; then [`Framer::commit`] the bytes read.
    pub fn spare(&mut self) -> &mut [u8] {
        &mut self.buf[self.len..]
    }

    /// `n` bytes were read into [`Framer::spare`].
    pub fn commit(&mut self, n: usize) {
        self.len = (self.len + n).min(BUFFER);
    }

    fn consume(&mut self, n: usize) {
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    /// The next message or error in the buffered bytes; `None`: more bytes
    /// are needed.
    pub fn next_message(&mut self) -> Option<Result<MavMessage, FrameError>> {
        if self.len == 0 {
            return None;
        }
        let start = self.buf[..self.len]
            .iter()
            .position(|&b| b == STX_V2 || b == STX_V1);
        match start {
            None => {
                let n = self.len;
                self.len = 0;
                return Some(Err(FrameError::Junk(n)));
            }
            Some(0) => {}
            Some(k) => {
                self.consume(k);
                return Some(Err(FrameError::Junk(k)));
            }
        }
        if self.len < 3 {
            return None;
        }
        let payload = usize::from(self.buf[1]);
        let v2 = self.buf[0] == STX_V2;
        let total = if v2 {
            let signed = self.buf[2] & 0x01 != 0;
            10 + payload + 2 + if signed { 13 } else { 0 }
        } else {
            6 + payload + 2
        };
        if self.len < total {
            return None;
        }
        let (crc_ok, id) = if v2 {
            self.raw2.as_mut_slice()[..total].copy_from_slice(&self.buf[..total]);
            (
                self.raw2.has_valid_crc::<MavMessage>(),
                self.raw2.message_id(),
            )
        } else {
            self.raw1.as_mut_slice()[..total].copy_from_slice(&self.buf[..total]);
            (
                self.raw1.has_valid_crc::<MavMessage>(),
                u32::from(self.raw1.message_id()),
            )
        };
        if !crc_ok {
            // a frame of an id we do not know cannot be checked: that is its kind
            let known = MavMessage::default_message_from_id(id).is_some();
            if known {
                // resynchronize on the next start marker
                self.consume(1);
                return Some(Err(FrameError::Crc));
            }
            self.consume(total);
            return Some(Err(FrameError::UnknownId(id)));
        }
        let parsed = if v2 {
            MavMessage::parse(MavlinkVersion::V2, id, self.raw2.payload())
        } else {
            MavMessage::parse(MavlinkVersion::V1, id, self.raw1.payload())
        };
        self.consume(total);
        Some(parsed.map_err(|_| FrameError::Payload(id)))
    }
}

/// The send side: messages serialized (MAVLink 2) one after the other into
/// a fixed buffer, written to the socket at once.
pub struct Outbox {
    buf: Box<[u8; BUFFER]>,
    len: usize,
    raw: Box<MAVLinkV2MessageRaw>,
    seq: u8,
    system_id: u8,
    component_id: u8,
}

impl std::fmt::Debug for Outbox {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Outbox").field("len", &self.len).finish()
    }
}

impl Outbox {
    /// An empty outbox sending as `system_id`/`component_id`.
    pub fn new(system_id: u8, component_id: u8) -> Self {
        Outbox {
            buf: Box::new([0; BUFFER]),
            len: 0,
            raw: Box::new(MAVLinkV2MessageRaw::new()),
            seq: 0,
            system_id,
            component_id,
        }
    }

    /// Append `msg` (dropped if the buffer were full: it never is, a step
    /// sends four messages of at most 280 bytes).
    pub fn push(&mut self, msg: &MavMessage) {
        let header = MavHeader {
            system_id: self.system_id,
            component_id: self.component_id,
            sequence: self.seq,
        };
        self.seq = self.seq.wrapping_add(1);
        self.raw.serialize_message(header, msg);
        let bytes = self.raw.raw_bytes();
        if self.len + bytes.len() <= BUFFER {
            self.buf[self.len..self.len + bytes.len()].copy_from_slice(bytes);
            self.len += bytes.len();
        }
    }

    /// The bytes to send.
    pub fn bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    /// Empty it (after sending).
    pub fn clear(&mut self) {
        self.len = 0;
    }
}
