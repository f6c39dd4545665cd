//! The ground-station server: MAVLink 2 (common dialect) over UDP and TCP
//! on its own thread. It reads the vehicle's status and events from the downlink ring
//! and writes commands to the uplink ring; the control task never waits for
//! it.
//!
//! **Peers.** Several ground stations may speak at once. Each is a peer with
//! its own address, liveness and stream rates; a peer exists only after a
//! CRC-valid MAVLink frame from its address (signed with the vehicle's key
//! when signing is configured): a datagram of garbage creates nothing. The
//! table holds at most [`MAX_PEERS`]; a new peer then replaces the one
//! heard longest ago, so a flood of addresses cannot grow memory. Answers
//! (COMMAND_ACK, PARAM_VALUE, the mission protocol) go to the peer that
//! asked; streams to each live peer at its own rates; status texts to every
//! live peer. A peer is live (is sent telemetry) while it was heard within
//! [`PEER_SILENCE_S`], so that a station whose uplink failed still sees the
//! failsafe; the link-loss failsafe acts when no trusted peer's
//! ground-station heartbeat arrived within `FS_LINK_TO`.
//!
//! **Transports.** The address is one endpoint or a comma-separated list
//! (`udpin:127.0.0.1:14550,tcpin:127.0.0.1:5760`): every socket is polled
//! in the one loop. A TCP client ([`tcp`]) is a peer from its connection
//! on (sent the heartbeat like a `udpout:` destination, never evicted) and
//! is forgotten when it closes or is dropped; replies go over the
//! connection the request came on, streams and texts to every live peer of
//! every transport.
//!
//! **Addressing.** Every message with a target (COMMAND_LONG/INT, SET_MODE,
//! PARAM_*, MISSION_*, SET_POSITION_TARGET_*, REQUEST_DATA_STREAM, …) is
//! handled only when its `target_system` is this vehicle's id or 0
//! (broadcast) and its `target_component` is the autopilot's (1), 0, or
//! for the mission protocol the mission planner's (190), as PX4 does;
//! anything else is ignored without an answer (MAVLink's routing rules).
//!
//! **Signing.** With a key configured, a frame that is unsigned, signed
//! with another key, or replayed (its timestamp not newer than the last of
//! its link id, system and component, the MAVLink 2 signing rules) changes
//! nothing — no peer, no liveness, no stream rate, parameter, mode or
//! mission; a command among them is answered `MAV_RESULT_DENIED` to its
//! sender only. Telemetry goes only to peers that have signed (the
//! configured `udpout:` destination gets the heartbeat alone until then,
//! so that it can find the vehicle).
//!
//! **Fence.** Position targets, guided gotos (`MAV_CMD_DO_REPOSITION`),
//! mission waypoints and takeoff heights outside the geofence
//! ([`crate::fence`]) are refused with the protocol's error result; the
//! navigator acts on a breach of the estimate.
//!
//! Streams are scheduled in on-board time (the status's `t_s`), so a
//! lock-step SITL flight that runs faster than the wall clock still sends
//! every stream at its rate per simulated second, and the rates are exact
//! multiples of the status period.

// ground stations still send the superseded REQUEST_DATA_STREAM, SET_MODE
// and the *_INT mission frames: they are understood
#![allow(deprecated)]

use crate::fence::{Fence, Zones};
use crate::geo::global_position_ned_m;
use crate::link::{LandedState, ServerEnd, Uplink, VehicleEvent, VehicleStatus};
use crate::mission_item::item_int;
use crate::modes;
use crate::navigator::{GuidedTarget, NavEvent, NavMode, NavigatorConfig};
use crate::params::{PARAMS, ParamError, ParamTable};
use helicon_devices::{Geodetic, LocalNed};
use mavlink::dialects::common::*;
use mavlink::{
    MAVLinkMessageRaw, MavHeader, MavlinkVersion, Message, MessageData, SigningConfig, SigningData,
};
use nalgebra::Vector3;
use std::net::UdpSocket;
use tcp::Tcp;

mod commands;
mod mission;
mod streams;
pub mod tcp;
mod transport;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use transport::{Dest, Peer, UdpEnd, bind};
pub use transport::{Endpoint, MAX_ENDPOINTS, parse_address};

/// The default address: where ground stations listen.
pub const DEFAULT_ADDRESS: &str = "udpout:127.0.0.1:14550";

/// The largest number of ground stations (peers) the server keeps.
pub const MAX_PEERS: usize = 8;

/// A ground station silent this long (on-board s) is sent nothing more.
/// Longer than the longest link-loss timeout and hold (`FS_LINK_TO` and
/// `FS_LINK_HOLD`, 120 s each at most): a station whose uplink fails keeps
/// its telemetry and sees the failsafe act.
pub const PEER_SILENCE_S: f64 = 300.0;

/// Largest guided velocity accepted (m/s): anything faster is not a
/// helicopter's target but a corrupted one (the navigator limits the
/// speeds it flies to its own `NAV_MAX_SPD`, `NAV_CLIMB_SPD`, `NAV_DESC_SPD`).
pub const MAX_GUIDED_SPEED_M_S: f64 = 50.0;

/// The messages the server streams, with their default rates (Hz; 0: off
/// until asked for).
pub const STREAMS: [(u32, &str, f64); 12] = [
    (HEARTBEAT_DATA::ID, "HEARTBEAT", 1.0),
    (SYS_STATUS_DATA::ID, "SYS_STATUS", 1.0),
    (ATTITUDE_DATA::ID, "ATTITUDE", 10.0),
    (GLOBAL_POSITION_INT_DATA::ID, "GLOBAL_POSITION_INT", 5.0),
    (LOCAL_POSITION_NED_DATA::ID, "LOCAL_POSITION_NED", 5.0),
    (GPS_RAW_INT_DATA::ID, "GPS_RAW_INT", 1.0),
    (VFR_HUD_DATA::ID, "VFR_HUD", 4.0),
    (SERVO_OUTPUT_RAW_DATA::ID, "SERVO_OUTPUT_RAW", 2.0),
    (RC_CHANNELS_DATA::ID, "RC_CHANNELS", 0.0),
    (EXTENDED_SYS_STATE_DATA::ID, "EXTENDED_SYS_STATE", 1.0),
    (MISSION_CURRENT_DATA::ID, "MISSION_CURRENT", 1.0),
    (HOME_POSITION_DATA::ID, "HOME_POSITION", 0.5),
];

/// `EXTENDED_SYS_STATE`'s place in [`STREAMS`]: besides its rate, it is sent
/// at once on each change of the landed state.
const EXTENDED_SYS_STATE_STREAM: usize = 9;
const _: () = assert!(STREAMS[EXTENDED_SYS_STATE_STREAM].0 == EXTENDED_SYS_STATE_DATA::ID);

/// The server's settings.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// `udpout:HOST:PORT` (send to this ground station from the start; others
    /// may join by speaking) or `udpin:HOST:PORT` (listen; every ground
    /// station that speaks is a peer).
    pub address: String,
    /// The vehicle's MAVLink system id.
    pub system_id: u8,
    /// The origin of the local NED frame (the GPS receiver's home).
    pub home: Geodetic,
    /// The navigator's tuning and the fence at start (the parameter table's
    /// values).
    pub navigator: NavigatorConfig,
    /// MAVLink 2 signing key: when set, only frames signed with it (and not
    /// replayed) are heard.
    pub signing_key: Option<[u8; 32]>,
    /// Start-up rate of each of [`STREAMS`] (Hz, 0: off, at most 100) of
    /// every peer; each ground station changes its own.
    pub rates_hz: [f64; STREAMS.len()],
}

/// The default rates of [`STREAMS`].
pub fn default_rates_hz() -> [f64; STREAMS.len()] {
    STREAMS.map(|(_, _, r)| r)
}

/// Errors starting the server.
#[derive(Debug, thiserror::Error)]
pub enum GcsError {
    /// The address is not `udpin:`/`udpout:` HOST:PORT, or cannot be bound.
    #[error("ground-station address `{address}`: {message}")]
    Address {
        /// The address given.
        address: String,
        /// What failed.
        message: String,
    },
    /// The thread could not be started.
    #[error("ground-station thread: {0}")]
    Thread(String),
}

/// What the server counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ServerReport {
    /// Messages sent (one per destination).
    pub sent: u64,
    /// Messages received (CRC-valid, parsed, and signed when signing is on).
    pub received: u64,
    /// Frames refused for a missing, wrong or replayed signature.
    pub refused_unsigned: u64,
    /// Messages for another system or component, ignored.
    pub other_target: u64,
    /// Datagrams read.
    pub datagrams: u64,
    /// Datagrams without a single CRC-valid frame of the dialect.
    pub garbage_datagrams: u64,
    /// Peers replaced because the table was full.
    pub peers_evicted: u64,
    /// The most peers held at once (at most [`MAX_PEERS`]).
    pub peers_max: usize,
    /// Send errors (a ground station not listening is one per message; a
    /// frame not queued to a TCP client is one).
    pub send_errors: u64,
    /// CRC-valid frames read from TCP clients.
    pub received_tcp_frames: u64,
    /// TCP clients accepted and served.
    pub tcp_accepted: u64,
    /// TCP clients closed at once ([`tcp::MAX_TCP_CLIENTS`] were served).
    pub tcp_refused: u64,
    /// TCP clients dropped because their send buffer filled or stalled.
    pub tcp_dropped_slow: u64,
    /// TCP clients dropped for sending garbage.
    pub tcp_dropped_garbage: u64,
    /// Bytes read from TCP clients.
    pub tcp_bytes_in: u64,
    /// Bytes written to TCP clients.
    pub tcp_bytes_out: u64,
    /// The server's own status texts sent to the flight log.
    pub texts_logged: u64,
    /// The server's own status texts not logged: beyond the log's rate
    /// ([`TEXT_LOG_RATE_HZ`], bursts of [`TEXT_LOG_BURST`]) or a full ring.
    pub texts_not_logged: u64,
}

/// The server's own status texts (replies, refusals) reach the flight log
/// at most this often on average…
pub const TEXT_LOG_RATE_HZ: f64 = 10.0;

/// …with bursts of up to this many: a ground station that repeats a
/// refused command cannot fill the log.
pub const TEXT_LOG_BURST: f64 = 20.0;

/// The running server.
pub struct ServerHandle {
    stop: Arc<AtomicBool>,
    processed: Arc<AtomicU64>,
    thread: JoinHandle<ServerReport>,
}

impl ServerHandle {
    /// Statuses and events the server has handled (sent on) so far.
    pub fn processed(&self) -> u64 {
        self.processed.load(Ordering::Acquire)
    }

    /// Stop the server and wait for its thread.
    pub fn stop(self) -> ServerReport {
        self.stop.store(true, Ordering::SeqCst);
        self.thread.join().unwrap_or_default()
    }
}

/// Start the server on its own thread.
pub fn spawn(config: ServerConfig, end: ServerEnd) -> Result<ServerHandle, GcsError> {
    let (udp, tcp) = bind(&config.address)?;
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = stop.clone();
    let processed = Arc::new(AtomicU64::new(0));
    let processed2 = processed.clone();
    let thread = std::thread::Builder::new()
        .name("gcs".into())
        .spawn(move || {
            let mut s = Server::new(config, end, udp, tcp);
            while !stop2.load(Ordering::Relaxed) {
                let n = s.poll();
                processed2.fetch_add(n, Ordering::Release);
            }
            s.tcp.flush();
            s.report()
        })
        .map_err(|e| GcsError::Thread(e.to_string()))?;
    Ok(ServerHandle {
        stop,
        processed,
        thread,
    })
}

enum Upload {
    Idle,
    Receiving {
        /// The peer uploading (its address).
        from: Dest,
        /// Its system and component (the requests are addressed to them).
        requester: (u8, u8),
        /// On-board time of its last message (s).
        last_s: f64,
        /// On-board time the last request went out (s).
        requested_s: f64,
        /// Requests repeated for the item expected.
        retries: u8,
        /// The flight mission or the fence.
        mission_type: MavMissionType,
        count: u16,
        items: Vec<MISSION_ITEM_INT_DATA>,
    },
}

/// The mission protocol's item timeout (on-board s): an item not received
/// this long after its request is requested again (the MAVLink mission
/// microservice's default, 1500 ms).
pub const MISSION_ITEM_TIMEOUT_S: f64 = 1.5;

/// Requests repeated for one item before the upload is cancelled
/// (`MAV_MISSION_OPERATION_CANCELLED`).
pub const MISSION_ITEM_RETRIES: u8 = 5;

/// What a ground station asked for before arming: PX4 (and so QGC's
/// takeoff and start-mission actions) takes the mode first and flies it at
/// the arming.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Pending {
    /// Take off to this height above home at the arming.
    Takeoff(f64),
    /// Start the mission at the arming.
    Mission,
}

/// An upload idle this long (on-board s) may be taken over by another peer.
const UPLOAD_IDLE_S: f64 = 5.0;

struct Server {
    config: ServerConfig,
    end: ServerEnd,
    /// The UDP sockets (`udpin:`/`udpout:`), in the order given.
    udp: Vec<UdpSocket>,
    /// The TCP listeners and clients (`tcpin:`).
    tcp: Tcp,
    /// The datagram buffer (allocated once).
    buffer: Vec<u8>,
    home: LocalNed,
    params: ParamTable,
    signing: Option<SigningData>,
    peers: Vec<Peer>,
    /// The peer whose message is being handled: answers go to it alone.
    current: Option<usize>,
    /// The system and component of the message being handled: answers are
    /// addressed to them.
    src: (u8, u8),
    /// A takeoff or mission asked for while disarmed on the ground.
    pending: Option<Pending>,
    /// The id of the last chunked status text.
    text_id: u16,
    /// The log's token bucket for the server's own texts (tokens, and the
    /// time they were counted).
    text_tokens: (f64, f64),
    /// The mission's last item was reached (MISSION_CURRENT's state
    /// COMPLETE until the mission is flown again or replaced).
    mission_complete: bool,
    sequence: u8,
    status: Option<VehicleStatus>,
    mission: Vec<MISSION_ITEM_INT_DATA>,
    /// The fence items as uploaded (downloads return them).
    fence_items: Vec<MISSION_ITEM_INT_DATA>,
    /// The rally points as uploaded (downloads return them; the navigator
    /// has their positions).
    rally_items: Vec<MISSION_ITEM_INT_DATA>,
    /// The zones of the fence upload (the server's target checks; the
    /// navigator holds a copy for its own and the breach monitor).
    zones: Zones,
    upload: Upload,
    last_flight_mode: &'static str,
    /// The landed state of the last status (`None` before the first): a
    /// change sends `EXTENDED_SYS_STATE` at once.
    last_landed: Option<LandedState>,
    /// An arm/disarm sent on and not yet seen in a status: the commands
    /// that follow it in the ring find the vehicle in that state.
    arm_requested: Option<bool>,
    /// The last refusal text to an unsigned sender (address, on-board s):
    /// at most one a second to the same address.
    last_refusal: Option<(Dest, f64)>,
    report: ServerReport,
}

fn interval_of(rate_hz: f64) -> Option<f64> {
    (rate_hz.is_finite() && rate_hz > 0.0).then(|| 1.0 / rate_hz)
}

/// The target of a message is this vehicle: its system or broadcast (0),
/// the autopilot component, broadcast, or (mission protocol) the mission
/// planner. Messages without a target are for everyone.
fn addressed_to(msg: &MavMessage, system_id: u8) -> bool {
    let system_ok = msg
        .target_system_id()
        .is_none_or(|t| t == 0 || t == system_id);
    let mission = matches!(
        msg.message_id(),
        MISSION_COUNT_DATA::ID
            | MISSION_ITEM_INT_DATA::ID
            | MISSION_ITEM_DATA::ID
            | MISSION_REQUEST_LIST_DATA::ID
            | MISSION_REQUEST_INT_DATA::ID
            | MISSION_REQUEST_DATA::ID
            | MISSION_CLEAR_ALL_DATA::ID
            | MISSION_ACK_DATA::ID
    );
    let component_ok = msg.target_component_id().is_none_or(|c| {
        c == 0
            || c == MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8
            || (mission && c == MavComponent::MAV_COMP_ID_MISSIONPLANNER as u8)
    });
    system_ok && component_ok
}

impl Server {
    fn new(config: ServerConfig, end: ServerEnd, udp: Vec<UdpEnd>, tcp: Tcp) -> Self {
        let signing = config
            .signing_key
            .map(|k| SigningData::from_config(SigningConfig::new(k, 0, false, false)));
        let mut s = Server {
            home: LocalNed::new(config.home),
            params: ParamTable::new(config.navigator),
            peers: Vec::with_capacity(MAX_PEERS),
            current: None,
            src: (0, 0),
            pending: None,
            text_id: 0,
            text_tokens: (TEXT_LOG_BURST, 0.0),
            mission_complete: false,
            sequence: 0,
            status: None,
            mission: Vec::new(),
            fence_items: Vec::new(),
            rally_items: Vec::new(),
            zones: Zones::default(),
            upload: Upload::Idle,
            last_flight_mode: "",
            last_landed: None,
            arm_requested: None,
            last_refusal: None,
            report: ServerReport::default(),
            buffer: vec![0; 65_536],
            signing,
            config,
            end,
            udp: Vec::with_capacity(udp.len()),
            tcp,
        };
        for (i, (socket, dest)) in udp.into_iter().enumerate() {
            if let Some(addr) = dest {
                let mut p = s.new_peer(Dest::Udp(i, addr));
                p.configured = true;
                s.peers.push(p);
                s.report.peers_max = s.peers.len();
            }
            s.udp.push(socket);
        }
        s
    }

    fn now_s(&self) -> f64 {
        self.status.map_or(0.0, |s| s.t_s)
    }

    fn fence(&self) -> &Fence {
        &self.params.config().fence
    }

    fn header(&mut self) -> MavHeader {
        let h = MavHeader {
            system_id: self.config.system_id,
            component_id: MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        h
    }

    /// The report with the TCP transport's counters.
    fn report(&self) -> ServerReport {
        ServerReport {
            tcp_accepted: self.tcp.accepted,
            tcp_refused: self.tcp.refused,
            tcp_dropped_slow: self.tcp.dropped_slow,
            tcp_dropped_garbage: self.tcp.dropped_garbage,
            tcp_bytes_in: self.tcp.bytes_in,
            tcp_bytes_out: self.tcp.bytes_out,
            ..self.report.clone()
        }
    }

    /// Send to the peer being answered, or else to every live peer.
    fn send(&mut self, msg: &MavMessage) {
        let to = self.current.map(|i| self.peers[i].addr);
        self.send_to(msg, to);
    }

    /// Send to `to`, or (`None`) to every live peer, each in the MAVLink
    /// version it speaks.
    fn send_to(&mut self, msg: &MavMessage, to: Option<Dest>) {
        let header = self.header();
        self.send_frames(to, msg.message_id(), |version, w| match version {
            MavlinkVersion::V2 => mavlink::write_v2_msg(w, header, msg).ok(),
            MavlinkVersion::V1 => mavlink::write_v1_msg(w, header, msg).ok(),
        });
    }

    /// Send a frame written by `write` (for a version, into a buffer; `None`:
    /// it failed) to `to` (a peer or the sender of a refused frame) or to
    /// every live peer. A MAVLink 1 peer is sent MAVLink 1, and nothing with
    /// an id MAVLink 1 cannot carry.
    fn send_frames(
        &mut self,
        to: Option<Dest>,
        id: u32,
        mut write: impl FnMut(MavlinkVersion, &mut &mut [u8]) -> Option<usize>,
    ) {
        let mut targets = [None; MAX_PEERS + 1];
        match to {
            Some(addr) => {
                let v1 = self.peers.iter().any(|p| p.addr == addr && p.v1);
                targets[0] = Some((addr, v1));
            }
            None => {
                for (t, p) in targets.iter_mut().zip(&self.peers) {
                    if self.live(p) {
                        *t = Some((p.addr, p.v1));
                    }
                }
            }
        }
        let mut frames = [None; 2];
        for (addr, v1) in targets.into_iter().flatten() {
            if v1 && id > 255 {
                continue;
            }
            let (version, slot) = if v1 {
                (MavlinkVersion::V1, 1)
            } else {
                (MavlinkVersion::V2, 0)
            };
            if frames[slot].is_none() {
                let mut buf = [0u8; mavlink::consts::MAX_FRAME_SIZE];
                let mut w: &mut [u8] = &mut buf;
                match write(version, &mut w) {
                    Some(n) => frames[slot] = Some((buf, n)),
                    None => {
                        self.report.send_errors += 1;
                        continue;
                    }
                }
            }
            if let Some((buf, n)) = frames[slot] {
                self.send_bytes(&buf[..n], addr);
            }
        }
    }

    /// A status text of the server's own (a reply, a refusal) to the
    /// requester, also sent to the flight log, rate-limited. Texts that
    /// tell the vehicle's own events use [`Self::text`]: the vehicle logs
    /// those itself.
    fn say(&mut self, severity: MavSeverity, text: &str) {
        let to = self.current.map(|i| self.peers[i].addr);
        self.say_to(severity, text, to);
    }

    /// [`Self::say`] to `to`.
    fn say_to(&mut self, severity: MavSeverity, text: &str, to: Option<Dest>) {
        self.text_to(severity, text, to);
        let now = self.now_s();
        let (tokens, at) = self.text_tokens;
        let tokens = (tokens + (now - at).max(0.0) * TEXT_LOG_RATE_HZ).min(TEXT_LOG_BURST);
        if tokens >= 1.0
            && self.uplink(Uplink::Text(crate::link::OperatorText::new(
                severity as u8,
                text,
            )))
        {
            self.text_tokens = (tokens - 1.0, now);
            self.report.texts_logged += 1;
        } else {
            self.text_tokens = (tokens, now);
            self.report.texts_not_logged += 1;
        }
    }

    fn text(&mut self, severity: MavSeverity, text: &str) {
        let to = self.current.map(|i| self.peers[i].addr);
        self.text_to(severity, text, to);
    }

    /// A status text; one longer than a STATUSTEXT's 50 bytes goes out in
    /// chunks of 50 with one `id` and `chunk_seq` 0, 1, … (common.xml: the
    /// last chunk shorter than 50 bytes, or followed by an empty one).
    fn text_to(&mut self, severity: MavSeverity, text: &str, to: Option<Dest>) {
        let bytes = text.as_bytes();
        let chunks = bytes.len() / 50 + 1;
        let id = if bytes.len() < 50 {
            0
        } else {
            self.text_id = self.text_id.wrapping_add(1).max(1);
            self.text_id
        };
        for c in 0..chunks.min(256) {
            let part = &bytes[(c * 50).min(bytes.len())..((c + 1) * 50).min(bytes.len())];
            let mut chunk = [0u8; 50];
            chunk[..part.len()].copy_from_slice(part);
            self.send_to(
                &MavMessage::STATUSTEXT(STATUSTEXT_DATA {
                    severity,
                    text: chunk.into(),
                    id,
                    chunk_seq: c as u8,
                }),
                to,
            );
        }
    }

    fn uplink(&mut self, u: Uplink) -> bool {
        self.end.uplink.push(u).is_ok()
    }

    /// Whether a message is a command (a refusal of it is answered).
    fn is_command(id: u32) -> bool {
        matches!(
            id,
            COMMAND_LONG_DATA::ID
                | COMMAND_INT_DATA::ID
                | SET_MODE_DATA::ID
                | PARAM_SET_DATA::ID
                | MISSION_COUNT_DATA::ID
                | MISSION_ITEM_INT_DATA::ID
                | MISSION_CLEAR_ALL_DATA::ID
                | SET_POSITION_TARGET_LOCAL_NED_DATA::ID
                | SET_POSITION_TARGET_GLOBAL_INT_DATA::ID
                | REQUEST_DATA_STREAM_DATA::ID
        )
    }

    /// One CRC-valid frame from `from`.
    fn receive(&mut self, raw: &MAVLinkMessageRaw, from: Dest) {
        if raw.system_id() == self.config.system_id {
            return; // our own echo
        }
        let id = raw.message_id();
        let parsed = MavMessage::parse(raw.version(), id, raw.payload());
        if let Some(sig) = &self.signing {
            // unsigned, another key, or a replay (the crate keeps the last
            // timestamp of each link id, system and component)
            let ok = match raw {
                MAVLinkMessageRaw::V2(v2) => sig.verify_signature(v2),
                MAVLinkMessageRaw::V1(_) => false,
            };
            if !ok {
                self.report.refused_unsigned += 1;
                if let Ok(msg) = &parsed
                    && Self::is_command(id)
                    && addressed_to(msg, self.config.system_id)
                {
                    self.refuse_unsigned(msg, from);
                }
                return;
            }
        }
        // a command the dialect does not define still gets its answer
        let unknown = match &parsed {
            Err(_) => UnknownCommand::of(raw),
            Ok(_) => None,
        };
        if parsed.is_err() && unknown.is_none() {
            return;
        }
        self.report.received += 1;
        let p = self.peer_of(from);
        self.peers[p].v1 = matches!(raw, MAVLinkMessageRaw::V1(_));
        if let Some(u) = unknown {
            if u.addressed_to(self.config.system_id) {
                self.current = Some(p);
                self.ack_unknown(u.command, raw.system_id(), raw.component_id());
                self.current = None;
            } else {
                self.report.other_target += 1;
            }
            return;
        }
        let Ok(msg) = parsed else {
            return;
        };
        if let MavMessage::HEARTBEAT(h) = &msg
            && h.mavtype == MavType::MAV_TYPE_GCS
        {
            self.uplink(Uplink::GcsHeartbeat);
        }
        if !addressed_to(&msg, self.config.system_id) {
            self.report.other_target += 1;
            return;
        }
        self.current = Some(p);
        self.src = (raw.system_id(), raw.component_id());
        self.dispatch(&msg, from, raw.system_id(), raw.component_id());
        self.current = None;
    }

    /// `COMMAND_ACK` `MAV_RESULT_UNSUPPORTED` for a command id the dialect
    /// does not define, to the peer being answered.
    fn ack_unknown(&mut self, command: u16, sys: u8, comp: u8) {
        let header = self.header();
        let to = self.current.map(|i| self.peers[i].addr);
        let ack = UnknownCommandAck {
            command,
            target: (sys, comp),
        };
        self.send_frames(to, COMMAND_ACK_DATA::ID, |version, w| {
            use std::io::Write;
            match version {
                MavlinkVersion::V2 => {
                    let mut f = mavlink::MAVLinkV2MessageRaw::new();
                    f.serialize_message_data(header, &ack);
                    w.write_all(f.raw_bytes()).ok()?;
                    Some(f.raw_bytes().len())
                }
                MavlinkVersion::V1 => {
                    let mut f = mavlink::MAVLinkV1MessageRaw::new();
                    f.serialize_message_data(header, &ack);
                    w.write_all(f.raw_bytes()).ok()?;
                    Some(f.raw_bytes().len())
                }
            }
        });
    }

    /// Answer a command that failed signing (to its sender only; the text at
    /// most once a second per address).
    fn refuse_unsigned(&mut self, msg: &MavMessage, from: Dest) {
        let now = self.now_s();
        if self
            .last_refusal
            .is_none_or(|(a, t)| a != from || now - t >= 1.0)
        {
            self.last_refusal = Some((from, now));
            self.say_to(
                MavSeverity::MAV_SEVERITY_WARNING,
                "refused: command not signed with the vehicle's key",
                Some(from),
            );
        }
        let command = match msg {
            MavMessage::COMMAND_LONG(c) => Some(c.command),
            MavMessage::COMMAND_INT(c) => Some(c.command),
            _ => None,
        };
        if let Some(command) = command {
            self.send_to(
                &MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                    command,
                    result: MavResult::MAV_RESULT_DENIED,
                    ..COMMAND_ACK_DATA::DEFAULT
                }),
                Some(from),
            );
        }
    }

    fn dispatch(&mut self, msg: &MavMessage, from: Dest, sys: u8, comp: u8) {
        match msg {
            MavMessage::COMMAND_LONG(c) => {
                let p = [
                    c.param1, c.param2, c.param3, c.param4, c.param5, c.param6, c.param7,
                ];
                let r = if c.command == MavCmd::MAV_CMD_DO_REPOSITION {
                    // PX4's COMMAND_LONG form: degrees as floats, AMSL
                    let deg = |v: f32| {
                        if v.is_finite() {
                            (f64::from(v) * 1e7).round() as i32
                        } else {
                            i32::MAX
                        }
                    };
                    self.reposition(MavFrame::MAV_FRAME_GLOBAL, p, deg(p[4]), deg(p[5]), p[6])
                } else {
                    self.command(c.command, p)
                };
                self.ack(c.command, r, sys, comp);
            }
            MavMessage::COMMAND_INT(c) => {
                let p = [c.param1, c.param2, c.param3, c.param4, 0.0, 0.0, c.z];
                let r = if c.command == MavCmd::MAV_CMD_DO_REPOSITION {
                    self.reposition(c.frame, p, c.x, c.y, c.z)
                } else {
                    self.command(c.command, p)
                };
                self.ack(c.command, r, sys, comp);
            }
            MavMessage::SET_MODE(m) => {
                // PX4 (and so pymavlink scripts) acknowledge it as DO_SET_MODE
                let (main, sub) = modes::main_sub(m.custom_mode);
                let r = self.set_mode(main, sub);
                self.ack(MavCmd::MAV_CMD_DO_SET_MODE, r, sys, comp);
            }
            MavMessage::REQUEST_DATA_STREAM(r) => self.request_stream(r),
            MavMessage::PARAM_REQUEST_LIST(_) => {
                for i in 0..self.params.len() {
                    self.param_value(i);
                }
            }
            MavMessage::PARAM_REQUEST_READ(r) => {
                let name = r.param_id.to_str().unwrap_or("").trim_end_matches('\0');
                let i = if r.param_index >= 0 {
                    Some(r.param_index as usize)
                } else {
                    self.params.index_of(name)
                };
                if let Some(i) = i.filter(|i| *i < self.params.len()) {
                    self.param_value(i);
                }
            }
            MavMessage::PARAM_SET(p) => self.param_set(p),
            MavMessage::MISSION_COUNT(c) => self.mission_count(c, from),
            MavMessage::MISSION_ITEM_INT(it) => self.mission_item(it, from),
            MavMessage::MISSION_ITEM(it) => self.mission_item(&item_int(it), from),
            MavMessage::MISSION_REQUEST_LIST(r) if self.mission_type_ok(r.mission_type) => {
                let count = self.items_of(r.mission_type).len() as u16;
                self.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                    count,
                    target_system: sys,
                    target_component: comp,
                    mission_type: r.mission_type,
                    ..MISSION_COUNT_DATA::DEFAULT
                }));
            }
            MavMessage::MISSION_REQUEST_INT(r) => self.send_item(r.seq, r.mission_type, true),
            MavMessage::MISSION_REQUEST(r) => self.send_item(r.seq, r.mission_type, false),
            MavMessage::MISSION_CLEAR_ALL(c) => self.clear_all(c.mission_type),
            MavMessage::SET_POSITION_TARGET_LOCAL_NED(t) => self.guided(t),
            MavMessage::SET_POSITION_TARGET_GLOBAL_INT(t) => self.guided_global(t),
            _ => {}
        }
    }
}

/// The guided target of a SET_POSITION_TARGET_* (its type mask: a velocity
/// when only the velocity is given, else the position; `None`: neither).
fn target_of(
    m: PositionTargetTypemask,
    yaw: f32,
    position_ned_m: Vector3<f64>,
    velocity: [f32; 3],
) -> Option<GuidedTarget> {
    let pos_ignored = m.contains(
        PositionTargetTypemask::POSITION_TARGET_TYPEMASK_X_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Y_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Z_IGNORE,
    );
    let vel_ignored = m.contains(
        PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VX_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VY_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VZ_IGNORE,
    );
    let yaw = (!m.contains(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE))
        .then_some(f64::from(yaw));
    if !vel_ignored && pos_ignored {
        Some(GuidedTarget::Velocity(
            Vector3::from(velocity.map(f64::from)),
            yaw,
        ))
    } else if !pos_ignored {
        Some(GuidedTarget::Position(position_ned_m, yaw))
    } else {
        None
    }
}

/// AUTOPILOT_VERSION: what the server offers (QGroundControl and MAVSDK
/// choose their protocols by these bits) and helicon's version
/// (`flight_sw_version` major, minor, patch, 0xFF release type, PX4's layout).
fn autopilot_version() -> AUTOPILOT_VERSION_DATA {
    let v = |s: &str| s.parse::<u32>().unwrap_or(0) & 0xFF;
    let flight_sw_version = (v(env!("CARGO_PKG_VERSION_MAJOR")) << 24)
        | (v(env!("CARGO_PKG_VERSION_MINOR")) << 16)
        | (v(env!("CARGO_PKG_VERSION_PATCH")) << 8)
        | 0xFF;
    AUTOPILOT_VERSION_DATA {
        capabilities: MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_INT
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_RALLY
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_COMMAND_INT
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MAVLINK2,
        flight_sw_version,
        ..AUTOPILOT_VERSION_DATA::DEFAULT
    }
}

/// A `COMMAND_LONG` or `COMMAND_INT` whose command id the common dialect
/// does not define (the crate's `MavCmd` has no value for it, so the message
/// does not parse): its id and target, read from the CRC-checked payload.
#[derive(Debug, Clone, Copy, PartialEq)]
struct UnknownCommand {
    command: u16,
    target_system: u8,
    target_component: u8,
}

impl UnknownCommand {
    /// The command of a frame that did not parse, when it is a command.
    /// Both messages put the command (u16) at byte 28 and the target system
    /// and component at 30 and 31 (MAVLink's size-sorted field order); a
    /// MAVLink 2 payload may be cut after its last non-zero byte.
    fn of(raw: &MAVLinkMessageRaw) -> Option<Self> {
        if !matches!(
            raw.message_id(),
            COMMAND_LONG_DATA::ID | COMMAND_INT_DATA::ID
        ) {
            return None;
        }
        let mut p = [0u8; 32];
        let payload = raw.payload();
        let n = payload.len().min(32);
        p[..n].copy_from_slice(&payload[..n]);
        Some(UnknownCommand {
            command: u16::from_le_bytes([p[28], p[29]]),
            target_system: p[30],
            target_component: p[31],
        })
    }

    /// Addressed to this vehicle's autopilot (or broadcast).
    fn addressed_to(&self, system_id: u8) -> bool {
        (self.target_system == 0 || self.target_system == system_id)
            && (self.target_component == 0
                || self.target_component == MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8)
    }
}

/// The `COMMAND_ACK` (`MAV_RESULT_UNSUPPORTED`) of an [`UnknownCommand`]:
/// the crate's `COMMAND_ACK_DATA` serialised, with its first field (the
/// command, u16, first on the wire) set to the id `MavCmd` cannot hold.
struct UnknownCommandAck {
    command: u16,
    target: (u8, u8),
}

impl MessageData for UnknownCommandAck {
    type Message = MavMessage;
    const ID: u32 = COMMAND_ACK_DATA::ID;
    const NAME: &'static str = COMMAND_ACK_DATA::NAME;
    const EXTRA_CRC: u8 = COMMAND_ACK_DATA::EXTRA_CRC;
    const ENCODED_LEN: usize = COMMAND_ACK_DATA::ENCODED_LEN;

    fn ser(&self, version: MavlinkVersion, payload: &mut [u8]) -> usize {
        let ack = COMMAND_ACK_DATA {
            result: MavResult::MAV_RESULT_UNSUPPORTED,
            target_system: self.target.0,
            target_component: self.target.1,
            ..COMMAND_ACK_DATA::DEFAULT
        };
        // at least 3 bytes: the result (non-zero) follows the command
        let n = ack.ser(version, payload);
        payload[..2].copy_from_slice(&self.command.to_le_bytes());
        n
    }

    fn deser(_: MavlinkVersion, _: &[u8]) -> Result<Self, mavlink::error::ParserError> {
        // only ever sent
        Err(mavlink::error::ParserError::UnknownMessage { id: Self::ID })
    }
}

/// The MAVLink 2 version the server speaks.
pub const VERSION: MavlinkVersion = MavlinkVersion::V2;
