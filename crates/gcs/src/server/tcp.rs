//! The server's TCP transport (`tcpin:HOST:PORT`, MAVLink's convention of
//! port 5760): listeners and their clients, non-blocking, polled from the
//! server's one loop (no thread per client).
//!
//! Limits, each counted in the [`ServerReport`](super::ServerReport):
//! - at most [`MAX_TCP_CLIENTS`] clients at once; one more is closed as it
//!   is accepted;
//! - a send buffer of [`TCP_SEND_BUFFER_BYTES`] per client, allocated at
//!   the accept and never grown: a frame that does not fit means the
//!   client reads too slowly, and it is dropped;
//! - a client whose pending bytes could not be written for
//!   [`TCP_STALL_S`] (wall-clock) is dropped;
//! - a client that has sent more than [`TCP_GARBAGE_BYTES`] bytes that
//!   are part of no CRC-valid frame is dropped.

use mavlink::dialects::common::MavMessage;
use mavlink::error::MessageReadError;
use mavlink::{MAVLinkMessageRaw, MavlinkReader};
use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::time::{Duration, Instant};

/// The most TCP clients served at once (over every `tcpin:` listener).
pub const MAX_TCP_CLIENTS: usize = 4;

/// Each TCP client's send buffer (bytes): a client that lets it fill is
/// too slow and is dropped.
pub const TCP_SEND_BUFFER_BYTES: usize = 64 * 1024;

/// A TCP client whose pending bytes could not be written for this long
/// (wall-clock s) is dropped.
pub const TCP_STALL_S: f64 = 30.0;

/// A TCP client that sends more than this many bytes that parse as no
/// MAVLink frame is dropped.
pub const TCP_GARBAGE_BYTES: u64 = 8 * 1024;

/// Bytes read from one client per frame asked for, at most: a client that
/// sends faster than the loop parses cannot hold it, and the garbage rule
/// is judged at least this often.
const READ_BUDGET_BYTES: usize = 4096;

/// The bytes read from a stream, counted (for the garbage rule), at most
/// `budget` before it reports `WouldBlock`.
struct Counted {
    stream: TcpStream,
    read: u64,
    budget: usize,
}

impl Read for Counted {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.budget == 0 {
            return Err(ErrorKind::WouldBlock.into());
        }
        let room = buf.len().min(self.budget);
        let n = self.stream.read(&mut buf[..room])?;
        self.read += n as u64;
        self.budget -= n;
        Ok(n)
    }
}

/// One connected client.
struct Client {
    /// Unique over the server's life (a peer names its client by it).
    serial: u32,
    reader: MavlinkReader<Counted>,
    /// Bytes of CRC-valid frames read.
    frame_bytes: u64,
    /// Bytes waiting to be written (capacity fixed at the accept).
    out: Vec<u8>,
    /// Last time the send buffer was empty or a write made progress.
    progress: Instant,
    /// To be closed at the next turn (too slow, garbage, closed, failed).
    dead: bool,
}

/// The TCP listeners and their clients.
pub(super) struct Tcp {
    listeners: Vec<TcpListener>,
    clients: Vec<Client>,
    next_serial: u32,
    /// Accepted clients (served).
    pub accepted: u64,
    /// Clients closed at once because [`MAX_TCP_CLIENTS`] were served.
    pub refused: u64,
    /// Clients dropped for a full or stalled send buffer.
    pub dropped_slow: u64,
    /// Clients dropped for garbage.
    pub dropped_garbage: u64,
    /// Bytes read from clients.
    pub bytes_in: u64,
    /// Bytes written to clients.
    pub bytes_out: u64,
}

impl Tcp {
    /// No listener yet.
    pub fn new() -> Self {
        Tcp {
            listeners: Vec::new(),
            clients: Vec::with_capacity(MAX_TCP_CLIENTS),
            next_serial: 0,
            accepted: 0,
            refused: 0,
            dropped_slow: 0,
            dropped_garbage: 0,
            bytes_in: 0,
            bytes_out: 0,
        }
    }

    /// Listen on `addr` (non-blocking).
    pub fn listen(&mut self, addr: SocketAddr) -> std::io::Result<()> {
        let l = TcpListener::bind(addr)?;
        l.set_nonblocking(true)?;
        self.listeners.push(l);
        Ok(())
    }

    /// Whether anything listens.
    pub fn is_empty(&self) -> bool {
        self.listeners.is_empty()
    }

    /// Accept waiting connections; returns the serial of each new client
    /// (at most [`MAX_TCP_CLIENTS`] at a time, so a fixed array).
    pub fn accept(&mut self) -> [Option<u32>; MAX_TCP_CLIENTS] {
        let mut new = [None; MAX_TCP_CLIENTS];
        let mut k = 0;
        for l in &self.listeners {
            // a bounded number per turn: a connect flood cannot hold the loop
            for _ in 0..8 {
                let Ok((stream, _)) = l.accept() else {
                    break;
                };
                if self.clients.len() >= MAX_TCP_CLIENTS || k >= MAX_TCP_CLIENTS {
                    self.refused += 1;
                    drop(stream);
                    continue;
                }
                if stream.set_nonblocking(true).is_err() {
                    continue;
                }
                let _ = stream.set_nodelay(true);
                self.next_serial = self.next_serial.wrapping_add(1);
                let serial = self.next_serial;
                self.clients.push(Client {
                    serial,
                    reader: MavlinkReader::with_capacity(
                        mavlink::consts::MAX_FRAME_SIZE,
                        Counted {
                            stream,
                            read: 0,
                            budget: 0,
                        },
                    ),
                    frame_bytes: 0,
                    out: Vec::with_capacity(TCP_SEND_BUFFER_BYTES),
                    progress: Instant::now(),
                    dead: false,
                });
                self.accepted += 1;
                new[k] = Some(serial);
                k += 1;
            }
        }
        new
    }

    /// The serials of the clients served (the dead ones not yet removed
    /// included).
    pub fn serials(&self) -> [Option<u32>; MAX_TCP_CLIENTS] {
        let mut s = [None; MAX_TCP_CLIENTS];
        for (s, c) in s.iter_mut().zip(&self.clients) {
            *s = Some(c.serial);
        }
        s
    }

    /// Whether a client is served and alive.
    pub fn alive(&self, serial: u32) -> bool {
        self.clients.iter().any(|c| c.serial == serial && !c.dead)
    }

    /// The next CRC-valid frame a client has sent (`None`: none now; a
    /// closed connection or too much garbage marks it dead).
    pub fn next_frame(&mut self, serial: u32) -> Option<MAVLinkMessageRaw> {
        let c = self
            .clients
            .iter_mut()
            .find(|c| c.serial == serial && !c.dead)?;
        let before = c.reader.get_ref().read;
        c.reader.get_mut().budget = READ_BUDGET_BYTES;
        let r = c.reader.read_any_raw_message::<MavMessage>();
        self.bytes_in += c.reader.get_ref().read - before;
        match r {
            Ok(raw) => {
                c.frame_bytes += match &raw {
                    MAVLinkMessageRaw::V1(r) => r.raw_bytes().len(),
                    MAVLinkMessageRaw::V2(r) => r.raw_bytes().len(),
                } as u64;
                Some(raw)
            }
            Err(MessageReadError::Io(e)) if e.kind() == ErrorKind::WouldBlock => {
                // the read-ahead holds at most one frame's bytes not yet
                // judged: they are not counted against the client
                let unjudged = mavlink::consts::MAX_FRAME_SIZE as u64;
                let garbage = c.reader.get_ref().read.saturating_sub(c.frame_bytes);
                if garbage > TCP_GARBAGE_BYTES + unjudged {
                    c.dead = true;
                    self.dropped_garbage += 1;
                }
                None
            }
            Err(_) => {
                c.dead = true;
                None
            }
        }
    }

    /// Queue a frame to a client; a full buffer drops it (too slow).
    /// Returns whether the frame was queued.
    pub fn send(&mut self, serial: u32, bytes: &[u8]) -> bool {
        let Some(c) = self
            .clients
            .iter_mut()
            .find(|c| c.serial == serial && !c.dead)
        else {
            return false;
        };
        if c.out.len() + bytes.len() > TCP_SEND_BUFFER_BYTES {
            Self::flush_one(c, &mut self.bytes_out);
        }
        if c.dead {
            return false;
        }
        if c.out.len() + bytes.len() > TCP_SEND_BUFFER_BYTES {
            c.dead = true;
            self.dropped_slow += 1;
            return false;
        }
        c.out.extend_from_slice(bytes);
        true
    }

    fn flush_one(c: &mut Client, bytes_out: &mut u64) {
        let now = Instant::now();
        while !c.out.is_empty() {
            match (&c.reader.get_ref().stream).write(&c.out) {
                Ok(0) => {
                    c.dead = true;
                    return;
                }
                Ok(n) => {
                    *bytes_out += n as u64;
                    c.out.drain(..n);
                    c.progress = now;
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(_) => {
                    c.dead = true;
                    return;
                }
            }
        }
        if c.out.is_empty() {
            c.progress = now;
        }
    }

    /// Write what is pending, drop stalled clients, and remove the dead.
    pub fn flush(&mut self) {
        let stall = Duration::from_secs_f64(TCP_STALL_S);
        for c in &mut self.clients {
            if c.dead {
                continue;
            }
            Self::flush_one(c, &mut self.bytes_out);
            if !c.dead && !c.out.is_empty() && c.progress.elapsed() >= stall {
                c.dead = true;
                self.dropped_slow += 1;
            }
        }
        self.clients.retain(|c| !c.dead);
    }
}
