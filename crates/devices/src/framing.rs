//! The one streaming framer every decoder of this crate is built on.
//!
//! A [`StreamDecoder`] keeps a fixed buffer of at most [`MAX_FRAME_BYTES`]
//! bytes holding the candidate frame that starts at the last start byte seen.
//! After every byte it asks the protocol whether the candidate is still
//! incomplete, complete, malformed or too long. A complete frame whose
//! checksum holds is decoded into a message; anything else drops the first
//! byte of the candidate and searches the rest of the buffer for the next
//! start byte, so a real frame hidden behind a false start (garbage that
//! happened to contain a sync byte, or a frame cut short) is still found.
//! While a candidate is incomplete, a frame starting at a later sync byte
//! that completes with a valid checksum is taken at once, so a false start
//! declaring a long frame does not delay the real frames behind it.
//! Nothing here allocates and no input can make it panic or loop: every
//! step either consumes an input byte or shortens the buffer.

/// Largest frame any protocol of this crate accepts (bytes). Also the size of
/// an [`EncodedFrame`].
pub const MAX_FRAME_BYTES: usize = 256;

/// Counters of a streaming decoder (monotonic since construction or
/// [`StreamDecoder::reset`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Bytes pushed into the decoder.
    pub bytes: u64,
    /// Frames with a valid checksum that decoded into a message.
    pub messages: u64,
    /// Frames whose checksum did not match.
    pub checksum_failures: u64,
    /// Candidate frames rejected before their checksum (bad header, bad
    /// characters, impossible length).
    pub malformed: u64,
    /// Candidate frames longer than the protocol allows.
    pub oversize: u64,
    /// Frames with a valid checksum that this crate does not decode (another
    /// message type, another sentence) or whose fields are out of range.
    pub unsupported: u64,
    /// Times the decoder had to search for a new start byte after a rejected
    /// candidate.
    pub resyncs: u64,
    /// Bytes thrown away outside any accepted frame (garbage, rejected frames).
    pub discarded_bytes: u64,
    /// Messages decoded but never read because a [`Messages`] iterator was
    /// dropped before its end.
    pub unread: u64,
}

/// What a protocol says about a candidate frame (a buffer starting with a
/// start byte).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameStatus {
    /// More bytes are needed.
    Incomplete,
    /// The first `n` bytes are a complete frame (checksum not yet checked).
    Complete(usize),
    /// The candidate cannot be a frame of this protocol.
    Malformed,
    /// The candidate declares or reaches a length beyond the protocol's limit.
    Oversize,
}

/// Why a complete frame with a valid checksum gave no message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reject {
    /// The checksum does not match.
    Checksum,
    /// A frame of this protocol that this crate does not decode, or whose
    /// fields are out of range.
    Unsupported,
}

/// A byte protocol: how frames start, end, are checked and decoded.
pub trait Protocol {
    /// The decoded message.
    type Message;
    /// Largest frame of this protocol (bytes, at most [`MAX_FRAME_BYTES`]).
    const MAX_FRAME: usize;
    /// Whether `byte` may start a frame.
    fn is_start(byte: u8) -> bool;
    /// Status of a candidate (`candidate[0]` is a start byte).
    fn status(candidate: &[u8]) -> FrameStatus;
    /// Checks and decodes a complete frame.
    fn decode(frame: &[u8]) -> Result<Self::Message, Reject>;
}

/// A streaming decoder of protocol `P`: push byte chunks of any size, get
/// messages out. Fixed-size; never allocates, never panics.
#[derive(Debug, Clone)]
pub struct StreamDecoder<P: Protocol> {
    buf: [u8; MAX_FRAME_BYTES],
    len: usize,
    stats: DecoderStats,
    _protocol: core::marker::PhantomData<P>,
}

impl<P: Protocol> Default for StreamDecoder<P> {
    fn default() -> Self {
        Self::new()
    }
}

impl<P: Protocol> StreamDecoder<P> {
    /// An empty decoder.
    pub fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME_BYTES],
            len: 0,
            stats: DecoderStats::default(),
            _protocol: core::marker::PhantomData,
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Forgets any partial frame and zeroes the counters.
    pub fn reset(&mut self) {
        self.len = 0;
        self.stats = DecoderStats::default();
    }

    /// Bytes held as a partial frame.
    pub fn pending_bytes(&self) -> usize {
        self.len
    }

    /// Feeds `bytes`; the returned iterator yields the messages they complete.
    /// Iterate it to the end: bytes left when it is dropped are still
    /// decoded, but their messages are only counted in
    /// [`DecoderStats::unread`].
    pub fn push<'a>(&'a mut self, bytes: &'a [u8]) -> Messages<'a, P> {
        Messages {
            decoder: self,
            input: bytes,
        }
    }

    /// Feeds `bytes` and calls `on_message` for every message completed.
    pub fn push_with(&mut self, bytes: &[u8], mut on_message: impl FnMut(P::Message)) {
        let mut input = bytes;
        while let Some(m) = self.next_message(&mut input) {
            on_message(m);
        }
    }

    /// Drops the first byte of the candidate and moves the buffer to the next
    /// start byte (or empties it).
    fn resync(&mut self) {
        self.stats.resyncs += 1;
        let next = self.buf[1..self.len]
            .iter()
            .position(|&b| P::is_start(b))
            .map_or(self.len, |i| i + 1);
        self.stats.discarded_bytes += next as u64;
        self.buf.copy_within(next..self.len, 0);
        self.len -= next;
    }

    /// Removes the first `n` bytes (a consumed frame).
    fn consume(&mut self, n: usize) {
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    /// Look-ahead past a false start: while the candidate at the buffer's
    /// start is still incomplete, a frame that starts at a later sync byte and
    /// has just been completed by the last byte, with a valid checksum, is
    /// taken at once (the bytes before it are discarded as a false start).
    /// Without it a false start that declares a long frame would hold back
    /// the real frames behind it until its declared length had arrived.
    fn nested_frame(&mut self) -> Option<P::Message> {
        let len = self.len;
        for k in 1..len {
            if !P::is_start(self.buf[k]) {
                continue;
            }
            if P::status(&self.buf[k..len]) != FrameStatus::Complete(len - k) {
                continue;
            }
            if let Ok(m) = P::decode(&self.buf[k..len]) {
                self.stats.resyncs += 1;
                self.stats.discarded_bytes += k as u64;
                self.stats.messages += 1;
                self.len = 0;
                return Some(m);
            }
        }
        None
    }

    /// The next message from the buffer and `input` (advanced past what was
    /// consumed), or `None` once `input` is exhausted.
    fn next_message(&mut self, input: &mut &[u8]) -> Option<P::Message> {
        loop {
            if self.len > 0 {
                match P::status(&self.buf[..self.len]) {
                    FrameStatus::Complete(n) if n <= self.len && n > 0 => {
                        let decoded = P::decode(&self.buf[..n]);
                        match decoded {
                            Ok(m) => {
                                self.stats.messages += 1;
                                self.consume(n);
                                return Some(m);
                            }
                            Err(Reject::Unsupported) => {
                                self.stats.unsupported += 1;
                                self.stats.discarded_bytes += n as u64;
                                self.consume(n);
                            }
                            Err(Reject::Checksum) => {
                                self.stats.checksum_failures += 1;
                                self.resync();
                            }
                        }
                        continue;
                    }
                    FrameStatus::Complete(_) | FrameStatus::Malformed => {
                        self.stats.malformed += 1;
                        self.resync();
                        continue;
                    }
                    FrameStatus::Oversize => {
                        self.stats.oversize += 1;
                        self.resync();
                        continue;
                    }
                    FrameStatus::Incomplete if self.len >= P::MAX_FRAME.min(MAX_FRAME_BYTES) => {
                        self.stats.oversize += 1;
                        self.resync();
                        continue;
                    }
                    FrameStatus::Incomplete => {
                        if let Some(m) = self.nested_frame() {
                            return Some(m);
                        }
                    }
                }
            }
            let (&byte, rest) = input.split_first()?;
            *input = rest;
            self.stats.bytes += 1;
            if self.len == 0 && !P::is_start(byte) {
                self.stats.discarded_bytes += 1;
                continue;
            }
            self.buf[self.len] = byte;
            self.len += 1;
        }
    }
}

/// The messages completed by one [`StreamDecoder::push`].
#[derive(Debug)]
pub struct Messages<'a, P: Protocol> {
    decoder: &'a mut StreamDecoder<P>,
    input: &'a [u8],
}

impl<P: Protocol> Iterator for Messages<'_, P> {
    type Item = P::Message;

    fn next(&mut self) -> Option<P::Message> {
        self.decoder.next_message(&mut self.input)
    }
}

impl<P: Protocol> Drop for Messages<'_, P> {
    fn drop(&mut self) {
        while self.decoder.next_message(&mut self.input).is_some() {
            self.decoder.stats.unread += 1;
        }
    }
}

/// One encoded frame, ready to write (fixed-size, no allocation).
#[derive(Clone, Copy)]
pub struct EncodedFrame {
    buf: [u8; MAX_FRAME_BYTES],
    len: usize,
}

impl core::fmt::Debug for EncodedFrame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EncodedFrame")
            .field("bytes", &self.as_bytes())
            .finish()
    }
}

impl Default for EncodedFrame {
    fn default() -> Self {
        Self::new()
    }
}

impl EncodedFrame {
    /// An empty frame.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME_BYTES],
            len: 0,
        }
    }

    /// The bytes of the frame.
    pub fn as_bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    /// Length in bytes.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when nothing was written.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends bytes; false (and nothing written) when they do not fit.
    pub(crate) fn extend(&mut self, bytes: &[u8]) -> bool {
        let Some(end) = self.len.checked_add(bytes.len()) else {
            return false;
        };
        if end > MAX_FRAME_BYTES {
            return false;
        }
        self.buf[self.len..end].copy_from_slice(bytes);
        self.len = end;
        true
    }
}

impl core::fmt::Write for EncodedFrame {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        if self.extend(s.as_bytes()) {
            Ok(())
        } else {
            Err(core::fmt::Error)
        }
    }
}

impl AsRef<[u8]> for EncodedFrame {
    fn as_ref(&self) -> &[u8] {
        self.as_bytes()
    }
}
