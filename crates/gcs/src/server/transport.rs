//! The server's transport: the address list (`udpin:`, `udpout:`,
//! `tcpin:`), its sockets, the table of ground stations heard (each its own
//! address, liveness, MAVLink version and stream rates), and one turn of
//! input from the sockets.

use super::tcp::Tcp;
use super::{GcsError, MAX_PEERS, PEER_SILENCE_S, STREAMS, Server, Upload, interval_of};
use crate::link::Downlink;
use mavlink::MavlinkReader;
use mavlink::dialects::common::MavMessage;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::time::Duration;

/// One endpoint of the `--gcs` / `[gcs] address` list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endpoint {
    /// `udpin:HOST:PORT`: listen; every ground station that speaks is a peer.
    UdpIn(SocketAddr),
    /// `udpout:HOST:PORT`: send to this ground station from the start.
    UdpOut(SocketAddr),
    /// `tcpin:HOST:PORT`: accept TCP clients (at most
    /// [`tcp::MAX_TCP_CLIENTS`]); each is a peer from its connection on.
    TcpIn(SocketAddr),
}

/// The most endpoints one address list may name.
pub const MAX_ENDPOINTS: usize = 4;

/// Parse and check an address: `udpin:`, `udpout:` or `tcpin:` HOST:PORT,
/// or a comma-separated list of them (at most [`MAX_ENDPOINTS`]), each
/// resolved to its first address.
pub fn parse_address(address: &str) -> Result<Vec<Endpoint>, GcsError> {
    let bad = |message: String| GcsError::Address {
        address: address.to_string(),
        message,
    };
    const EXPECTED: &str =
        "expected udpin:HOST:PORT, udpout:HOST:PORT or tcpin:HOST:PORT (or a comma-separated list)";
    let mut out = Vec::new();
    for part in address.split(',') {
        let part = part.trim();
        let Some((kind, host)) = part.split_once(':') else {
            return Err(bad(EXPECTED.into()));
        };
        let make: fn(SocketAddr) -> Endpoint = match kind {
            "udpin" => Endpoint::UdpIn,
            "udpout" => Endpoint::UdpOut,
            "tcpin" => Endpoint::TcpIn,
            _ => return Err(bad(EXPECTED.into())),
        };
        let addr = host
            .to_socket_addrs()
            .map_err(|e| bad(format!("`{part}`: {e}")))?
            .next()
            .ok_or_else(|| bad(format!("`{part}` resolves to no address")))?;
        let e = make(addr);
        if out.contains(&e) {
            return Err(bad(format!("`{part}` given twice")));
        }
        out.push(e);
    }
    if out.len() > MAX_ENDPOINTS {
        return Err(bad(format!("at most {MAX_ENDPOINTS} endpoints")));
    }
    Ok(out)
}

/// Where a peer is reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Dest {
    /// A datagram address on the UDP socket of that index.
    Udp(usize, SocketAddr),
    /// The TCP client of that serial.
    Tcp(u32),
}

/// A UDP socket and its `udpout:` destination.
pub(super) type UdpEnd = (UdpSocket, Option<SocketAddr>);

/// The sockets of an address list: the UDP sockets with their `udpout:`
/// destinations, and the TCP listeners.
pub(super) fn bind(address: &str) -> Result<(Vec<UdpEnd>, Tcp), GcsError> {
    let bad = |message: String| GcsError::Address {
        address: address.to_string(),
        message,
    };
    let mut udp = Vec::new();
    let mut tcp = Tcp::new();
    for e in parse_address(address)? {
        match e {
            Endpoint::UdpIn(addr) => {
                udp.push((UdpSocket::bind(addr).map_err(|e| bad(e.to_string()))?, None))
            }
            Endpoint::UdpOut(addr) => {
                let any: SocketAddr = if addr.is_ipv4() {
                    ([0, 0, 0, 0], 0).into()
                } else {
                    ([0u16; 8], 0).into()
                };
                udp.push((
                    UdpSocket::bind(any).map_err(|e| bad(e.to_string()))?,
                    Some(addr),
                ))
            }
            Endpoint::TcpIn(addr) => tcp.listen(addr).map_err(|e| bad(e.to_string()))?,
        }
    }
    // the first UDP socket paces the loop (its read waits up to 2 ms); the
    // others, and the TCP sockets, never wait
    for (i, (socket, _)) in udp.iter().enumerate() {
        if i == 0 {
            socket.set_read_timeout(Some(Duration::from_millis(2)))
        } else {
            socket.set_nonblocking(true)
        }
        .map_err(|e| bad(e.to_string()))?;
    }
    Ok((udp, tcp))
}

/// One ground station.
pub(super) struct Peer {
    pub(super) addr: Dest,
    /// The `udpout:` destination: sent to before it speaks, never evicted.
    pub(super) configured: bool,
    /// Has sent a frame that passed signing (every peer when signing is off).
    pub(super) trusted: bool,
    /// On-board time of its last valid frame (s; `None`: never).
    pub(super) heard_s: Option<f64>,
    /// Its last frame was MAVLink 1: it is answered in MAVLink 1 (messages
    /// with ids above 255, which MAVLink 1 cannot carry, are not sent to it).
    pub(super) v1: bool,
    pub(super) intervals_s: [Option<f64>; STREAMS.len()],
    pub(super) next_due_s: [f64; STREAMS.len()],
}

impl Server {
    pub(super) fn new_peer(&self, addr: Dest) -> Peer {
        Peer {
            addr,
            configured: false,
            trusted: self.signing.is_none(),
            heard_s: None,
            v1: false,
            intervals_s: self.config.rates_hz.map(|r| interval_of(r.min(100.0))),
            next_due_s: [0.0; STREAMS.len()],
        }
    }

    /// The peer of an address that has just sent a valid frame: found, or
    /// added (replacing the one heard longest ago when the table is full).
    pub(super) fn peer_of(&mut self, addr: Dest) -> usize {
        let now = self.now_s();
        let i = if let Some(i) = self.peers.iter().position(|p| p.addr == addr) {
            i
        } else {
            let mut p = self.new_peer(addr);
            p.next_due_s = [now; STREAMS.len()];
            if self.peers.len() < MAX_PEERS {
                self.peers.push(p);
                self.report.peers_max = self.report.peers_max.max(self.peers.len());
                self.peers.len() - 1
            } else {
                let i = self.oldest_heard().unwrap_or(MAX_PEERS - 1);
                self.peers[i] = p;
                self.report.peers_evicted += 1;
                i
            }
        };
        let p = &mut self.peers[i];
        p.heard_s = Some(now);
        p.trusted = true;
        i
    }

    /// The peer heard longest ago (never heard first) that may be evicted
    /// for a new one: not a configured destination nor a TCP client.
    fn oldest_heard(&self) -> Option<usize> {
        (0..self.peers.len())
            .filter(|&i| !self.peers[i].configured)
            .min_by(|&a, &b| {
                let t = |p: &Peer| p.heard_s.unwrap_or(f64::NEG_INFINITY);
                t(&self.peers[a]).total_cmp(&t(&self.peers[b]))
            })
    }

    /// A peer is sent status texts and streams: trusted, and heard within
    /// [`PEER_SILENCE_S`] (the configured destination always).
    pub(super) fn live(&self, p: &Peer) -> bool {
        p.trusted
            && (p.configured
                || p.heard_s
                    .is_some_and(|h| self.now_s() - h <= PEER_SILENCE_S))
    }

    pub(super) fn send_bytes(&mut self, bytes: &[u8], to: Dest) {
        let ok = match to {
            Dest::Udp(i, addr) => self.udp[i].send_to(bytes, addr).is_ok(),
            Dest::Tcp(serial) => self.tcp.send(serial, bytes),
        };
        if ok {
            self.report.sent += 1;
        } else {
            self.report.send_errors += 1;
        }
    }

    /// One turn: datagrams in (up to the read timeout), then the vehicle's
    /// statuses and events out.
    /// Returns the statuses and events handled.
    pub(super) fn poll(&mut self) -> u64 {
        let mut input = false;
        for u in 0..self.udp.len() {
            for _ in 0..32 {
                match self.udp[u].recv_from(&mut self.buffer) {
                    Ok((n, from)) => {
                        input = true;
                        self.datagram(n, Dest::Udp(u, from));
                    }
                    Err(_) => break,
                }
            }
        }
        if !self.tcp.is_empty() {
            input |= self.poll_tcp();
            if !input && self.udp.is_empty() {
                // nothing waits on a read: pace the loop
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        let mut n = 0;
        while let Ok(d) = self.end.downlink.pop() {
            match d {
                Downlink::Status(s) => self.on_status(&s),
                Downlink::Event(t, e) => self.on_event(t, e),
            }
            n += 1;
        }
        n
    }

    /// The frames of one datagram (the first `n` bytes of the buffer), all
    /// of them its sender's.
    pub(super) fn datagram(&mut self, n: usize, from: Dest) {
        self.report.datagrams += 1;
        let bytes = std::mem::take(&mut self.buffer);
        let mut reader = MavlinkReader::with_capacity(n.min(bytes.len()), &bytes[..n]);
        let mut frames = 0;
        // a frame is at least 8 bytes: a datagram holds at most n/8 of them
        for _ in 0..=n / 8 {
            match reader.read_any_raw_message::<MavMessage>() {
                Ok(raw) => {
                    frames += 1;
                    self.receive(&raw, from);
                }
                Err(_) => break,
            }
        }
        if frames == 0 {
            self.report.garbage_datagrams += 1;
        }
        self.buffer = bytes;
    }

    /// The TCP turn: new clients become peers (sent the heartbeat from the
    /// start, like a `udpout:` destination), each client's frames are
    /// received, and the pending bytes written; the peers of closed or
    /// dropped clients are removed. Returns whether a frame came in.
    pub(super) fn poll_tcp(&mut self) -> bool {
        for serial in self.tcp.accept().into_iter().flatten() {
            let now = self.now_s();
            let mut p = self.new_peer(Dest::Tcp(serial));
            p.configured = true;
            p.next_due_s = [now; STREAMS.len()];
            if self.peers.len() >= MAX_PEERS {
                // the table's oldest station heard (never a connected one)
                if let Some(i) = self.oldest_heard() {
                    self.peers[i] = p;
                    self.report.peers_evicted += 1;
                }
            } else {
                self.peers.push(p);
                self.report.peers_max = self.report.peers_max.max(self.peers.len());
            }
        }
        let mut input = false;
        for serial in self.tcp.serials().into_iter().flatten() {
            // a bounded number of frames per client and turn
            for _ in 0..64 {
                let Some(raw) = self.tcp.next_frame(serial) else {
                    break;
                };
                input = true;
                self.report.received_tcp_frames += 1;
                self.receive(&raw, Dest::Tcp(serial));
            }
        }
        self.tcp.flush();
        let tcp = &self.tcp;
        let before = self.peers.len();
        self.peers.retain(|p| match p.addr {
            Dest::Tcp(serial) => tcp.alive(serial),
            Dest::Udp(..) => true,
        });
        if self.peers.len() != before
            && let Upload::Receiving {
                from: Dest::Tcp(serial),
                ..
            } = self.upload
            && !self.tcp.alive(serial)
        {
            self.upload = Upload::Idle;
        }
        input
    }
}
