//! A server listening on a free loopback port with the vehicle's ring ends
//! in the test's hands, and the messages the hostile tests send.
#![allow(dead_code)]
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test
#![allow(deprecated)]

use super::client::Client;
use helicon_core::Reference;
use helicon_core::state::Input;
use helicon_devices::Geodetic;
use helicon_gcs::link::{Downlink, FlightMode, Uplink, VehicleEnd, VehicleStatus, channel};
use helicon_gcs::mavlink::Message;
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{MavHeader, SigningConfig, SigningData, write_v2_msg_signed};
use helicon_gcs::navigator::{NavMode, NavigatorConfig};
use helicon_gcs::server::{self, ServerConfig, ServerHandle, ServerReport, default_rates_hz};
use nalgebra::Vector3;
use std::net::UdpSocket;
use std::time::{Duration, Instant};

pub const SHORT: Duration = Duration::from_millis(300);
pub const T: Duration = Duration::from_secs(3);

pub fn status(t_s: f64, armed: bool, nav_mode: NavMode) -> VehicleStatus {
    VehicleStatus {
        t_s,
        armed,
        nav_mode,
        flight_mode: FlightMode {
            name: "auto",
            law_flies: true,
        },
        attitude_rad: Vector3::zeros(),
        rates_rad_s: Vector3::zeros(),
        position_ned_m: Vector3::new(0.0, 0.0, -10.0),
        velocity_ned_m_s: Vector3::zeros(),
        position_sigma_m: Vector3::repeat(0.5),
        navigation_ok: true,
        gps_ok: true,
        servo: Input::zeros(),
        reference: Reference {
            velocity_ned_m_s: Vector3::zeros(),
            yaw_rad: 0.0,
        },
        mission_current: (0, 0),
        link_lost: false,
        load: 0.1,
        ground: helicon_gcs::link::GroundState::default(),
    }
}

/// A server listening on a free port (`udpin:`), with or without a key.
pub struct Vehicle {
    /// The port the server listens on.
    pub port: u16,
    /// The TCP port it also listens on (`tcpin:`; 0: none).
    pub tcp_port: u16,
    v: VehicleEnd,
    h: Option<ServerHandle>,
    pushed: u64,
    t_s: f64,
    /// The statuses say armed (holding).
    pub armed: bool,
    /// The server's own texts sent to the flight log (`Uplink::Text`),
    /// taken out of the uplinks as they are read.
    pub logged_texts: Vec<String>,
}

impl Vehicle {
    pub fn start(key: Option<[u8; 32]>) -> Vehicle {
        Self::start_on(key, false)
    }

    /// As [`Vehicle::start`], also listening on TCP (`tcpin:`, a free port)
    /// when `tcp`.
    pub fn start_on(key: Option<[u8; 32]>, tcp: bool) -> Vehicle {
        let port = UdpSocket::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let tcp_port = if tcp {
            std::net::TcpListener::bind("127.0.0.1:0")
                .unwrap()
                .local_addr()
                .unwrap()
                .port()
        } else {
            0
        };
        let mut address = format!("udpin:127.0.0.1:{port}");
        if tcp {
            address += &format!(",tcpin:127.0.0.1:{tcp_port}");
        }
        let (v, s) = channel(4096);
        let h = server::spawn(
            ServerConfig {
                address,
                system_id: 1,
                home: Geodetic::new(57.0146, 9.9869, 20.0).unwrap(),
                navigator: NavigatorConfig::default(),
                signing_key: key,
                rates_hz: default_rates_hz(),
            },
            s,
        )
        .unwrap();
        let mut me = Vehicle {
            port,
            tcp_port,
            v,
            h: Some(h),
            pushed: 0,
            t_s: 0.0,
            armed: false,
            logged_texts: Vec::new(),
        };
        me.status(0.0);
        me
    }

    /// Push `seconds` of statuses at 100 Hz and wait for the server to
    /// have sent them on (lock-step).
    pub fn status(&mut self, seconds: f64) {
        // the datagrams just sent are read before these statuses
        std::thread::sleep(Duration::from_millis(5));
        let n = (seconds * 100.0).round().max(1.0) as u64;
        let mode = if self.armed {
            NavMode::Hold
        } else {
            NavMode::Idle
        };
        for _ in 0..n {
            self.v
                .downlink
                .push(Downlink::Status(status(self.t_s, self.armed, mode)))
                .unwrap();
            self.t_s += 0.01;
            self.pushed += 1;
        }
        let h = self.h.as_ref().unwrap();
        let t = Instant::now();
        while h.processed() < self.pushed {
            assert!(t.elapsed() < T, "the server does not keep up");
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// What the server put on the uplink (after a pause for the datagrams
    /// in flight).
    pub fn uplinks(&mut self) -> Vec<Uplink> {
        std::thread::sleep(Duration::from_millis(50));
        let mut out = Vec::new();
        while let Ok(u) = self.v.uplink.pop() {
            match u {
                Uplink::Text(t) => self.logged_texts.push(t.as_str().to_string()),
                u => out.push(u),
            }
        }
        out
    }

    pub fn commands(&mut self) -> Vec<Uplink> {
        self.uplinks()
            .into_iter()
            .filter(|u| *u != Uplink::GcsHeartbeat)
            .collect()
    }

    pub fn stop(mut self) -> ServerReport {
        self.h.take().unwrap().stop()
    }
}

/// The messages `id` received after `from` (the client's log read up first).
pub fn count(c: &mut Client, from: usize, id: u32) -> usize {
    std::thread::sleep(Duration::from_millis(20));
    c.drain();
    c.collect(from, |m| (m.message_id() == id).then_some(()))
        .len()
}

pub fn long(command: MavCmd, target_system: u8, target_component: u8, p: [f32; 7]) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: p[0],
        param2: p[1],
        param3: p[2],
        param4: p[3],
        param5: p[4],
        param6: p[5],
        param7: p[6],
        command,
        target_system,
        target_component,
        confirmation: 0,
    })
}

pub const ARM: [f32; 7] = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];

pub fn param_set(name: &str, value: f32, target_system: u8) -> MavMessage {
    MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: value,
        target_system,
        target_component: 1,
        param_id: name.into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    })
}

/// The value of a parameter as the server answers a read.
pub fn param(c: &mut Client, name: &str) -> f32 {
    // answers still in flight (a set's value) are not this read's
    std::thread::sleep(Duration::from_millis(20));
    c.drain();
    let from = c.log.len();
    c.send(&MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
        param_index: -1,
        target_system: 1,
        target_component: 1,
        param_id: name.into(),
    }));
    match c.wait(from, T, |m| {
        matches!(m, MavMessage::PARAM_VALUE(p) if p.param_id.to_str().unwrap_or("").trim_end_matches('\0') == name)
    }) {
        Some(MavMessage::PARAM_VALUE(p)) => p.param_value,
        other => panic!("no PARAM_VALUE {name}: {other:?}"),
    }
}

pub fn ack_within(
    c: &mut Client,
    from: usize,
    command: MavCmd,
    within: Duration,
) -> Option<MavResult> {
    match c.wait(
        from,
        within,
        |m| matches!(m, MavMessage::COMMAND_ACK(a) if a.command == command),
    ) {
        Some(MavMessage::COMMAND_ACK(a)) => Some(a.result),
        _ => None,
    }
}

pub fn position_target(x: f32, y: f32, z: f32, target_system: u8) -> MavMessage {
    MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
        x,
        y,
        z,
        type_mask: PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VX_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VY_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VZ_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AX_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AY_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AZ_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE,
        target_system,
        target_component: 1,
        coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
        ..SET_POSITION_TARGET_LOCAL_NED_DATA::DEFAULT
    })
}

/// Upload a mission; the MISSION_ACK's result.
pub fn upload(c: &mut Client, items: &[MISSION_ITEM_INT_DATA]) -> Option<MavMissionResult> {
    let mut cursor = c.log.len();
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: items.len() as u16,
        target_system: 1,
        target_component: 1,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    loop {
        let (i, m) = c.wait_index(cursor, T, |m| {
            matches!(
                m,
                MavMessage::MISSION_REQUEST_INT(_) | MavMessage::MISSION_ACK(_)
            )
        })?;
        cursor = i + 1;
        match m {
            MavMessage::MISSION_REQUEST_INT(r) => {
                c.send(&MavMessage::MISSION_ITEM_INT(items[r.seq as usize].clone()));
            }
            MavMessage::MISSION_ACK(a) => return Some(a.mavtype),
            _ => unreachable!(),
        }
    }
}

/// The messages a raw socket receives within `within` (one frame a datagram).
pub fn received(s: &UdpSocket, within: Duration) -> Vec<MavMessage> {
    s.set_read_timeout(Some(within)).unwrap();
    let mut out = Vec::new();
    let mut b = [0u8; 512];
    while let Ok((n, _)) = s.recv_from(&mut b) {
        let mut r = helicon_gcs::mavlink::MavlinkReader::new(&b[..n]);
        if let Ok((_, m)) = r.read_any_message::<MavMessage>() {
            out.push(m);
        }
    }
    out
}

/// A raw socket that receives nothing within `within`.
pub fn silent(s: &UdpSocket, within: Duration) -> bool {
    s.set_read_timeout(Some(within)).unwrap();
    let mut b = [0u8; 512];
    s.recv_from(&mut b).is_err()
}

/// Signed frames as a ground station with `key` on `link_id` sends them.
pub struct Signer {
    /// The signing state.
    pub data: SigningData,
    seq: u8,
}

impl Signer {
    pub fn new(key: [u8; 32], link_id: u8) -> Signer {
        Signer {
            data: SigningData::from_config(SigningConfig::new(key, link_id, true, false)),
            seq: 0,
        }
    }

    pub fn frame(&mut self, msg: &MavMessage) -> Vec<u8> {
        let mut out = Vec::new();
        let h = MavHeader {
            system_id: 255,
            component_id: 190,
            sequence: self.seq,
        };
        self.seq = self.seq.wrapping_add(1);
        write_v2_msg_signed(&mut out, h, msg, Some(&self.data)).unwrap();
        out
    }
}
