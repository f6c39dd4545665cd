//! A MAVLink client for the tests (the `mavlink` crate's own UDP connection,
//! as a pymavlink script or a ground station would speak): it listens on a
//! free local port, the server sends to it (`udpout:`), it answers the
//! server.
#![allow(dead_code)]
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{
    Connectable, Connection, MavConnection, MavHeader, SigningConfig, UdpConfig, UdpMode,
};
use std::net::UdpSocket;
use std::time::{Duration, Instant};

/// What the client received, in order.
pub struct Client {
    conn: Connection<MavMessage>,
    /// Every message received: (header, message).
    pub log: Vec<(MavHeader, MavMessage)>,
    /// The port the client listens on.
    pub port: u16,
}

impl Client {
    /// A client listening on a free port (the server sends to it with
    /// `udpout:`); `key`: sign what it sends.
    pub fn new(key: Option<[u8; 32]>) -> Client {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        let port = socket.local_addr().unwrap().port();
        let config = UdpConfig::from_socket(socket, UdpMode::Udpin).unwrap();
        Self::with(config, port, key)
    }

    /// A client sending to a server listening (`udpin:`) on `port`.
    pub fn to_port(port: u16, key: Option<[u8; 32]>) -> Client {
        let config = UdpConfig::new(format!("127.0.0.1:{port}"), UdpMode::Udpout);
        Self::with(config, port, key)
    }

    fn with(config: UdpConfig, port: u16, key: Option<[u8; 32]>) -> Client {
        let mut conn = config.connect::<MavMessage>().unwrap();
        if let Some(k) = key {
            conn.setup_signing(Some(SigningConfig::new(k, 1, true, true)));
        }
        Client {
            conn,
            log: Vec::new(),
            port,
        }
    }

    /// The server address that sends to this client.
    pub fn server_address(&self) -> String {
        format!("udpout:127.0.0.1:{}", self.port)
    }

    /// Send as the ground station (system 255).
    pub fn send(&self, msg: &MavMessage) {
        let h = MavHeader {
            system_id: 255,
            component_id: 190,
            sequence: 0,
        };
        self.conn.send(&h, msg).unwrap();
    }

    /// A ground-station heartbeat.
    pub fn heartbeat(&self) {
        self.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_GCS,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }));
    }

    /// Read everything waiting; returns how many arrived.
    pub fn drain(&mut self) -> usize {
        let mut n = 0;
        while let Ok(m) = self.conn.try_recv() {
            self.log.push(m);
            n += 1;
        }
        n
    }

    /// Wait (wall clock, the simulation paused) for a message after
    /// `from` in the log that `pred` accepts.
    pub fn wait(
        &mut self,
        from: usize,
        timeout: Duration,
        pred: impl Fn(&MavMessage) -> bool,
    ) -> Option<MavMessage> {
        self.wait_index(from, timeout, pred).map(|(_, m)| m)
    }

    /// As [`Client::wait`], with the message's index in the log.
    pub fn wait_index(
        &mut self,
        from: usize,
        timeout: Duration,
        pred: impl Fn(&MavMessage) -> bool,
    ) -> Option<(usize, MavMessage)> {
        let start = Instant::now();
        loop {
            self.drain();
            let from = from.min(self.log.len());
            if let Some(i) = self.log[from..].iter().position(|(_, m)| pred(m)) {
                return Some((from + i, self.log[from + i].1.clone()));
            }
            if start.elapsed() > timeout {
                return None;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Send a COMMAND_LONG and wait for its COMMAND_ACK.
    pub fn command(&mut self, command: MavCmd, params: [f32; 7]) -> Option<MavResult> {
        let from = self.log.len();
        self.send(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: params[0],
            param2: params[1],
            param3: params[2],
            param4: params[3],
            param5: params[4],
            param6: params[5],
            param7: params[6],
            command,
            target_system: 1,
            target_component: 1,
            confirmation: 0,
        }));
        match self.wait(
            from,
            Duration::from_secs(3),
            |m| matches!(m, MavMessage::COMMAND_ACK(a) if a.command == command),
        ) {
            Some(MavMessage::COMMAND_ACK(a)) => Some(a.result),
            _ => None,
        }
    }

    /// The messages of the log after `from` that `f` maps.
    pub fn collect<T>(&self, from: usize, f: impl Fn(&MavMessage) -> Option<T>) -> Vec<T> {
        self.log[from.min(self.log.len())..]
            .iter()
            .filter_map(|(_, m)| f(m))
            .collect()
    }

    /// The STATUSTEXTs received.
    pub fn texts(&self) -> Vec<String> {
        self.collect(0, |m| match m {
            MavMessage::STATUSTEXT(s) => Some(
                s.text
                    .to_str()
                    .unwrap_or("")
                    .trim_end_matches('\0')
                    .to_string(),
            ),
            _ => None,
        })
    }
}

/// A mission item in the relative-altitude frame.
pub fn item(
    seq: u16,
    command: MavCmd,
    lat_e7: i32,
    lon_e7: i32,
    alt_m: f32,
) -> MISSION_ITEM_INT_DATA {
    MISSION_ITEM_INT_DATA {
        param1: 0.0,
        param2: 0.0,
        param3: 0.0,
        param4: f32::NAN,
        x: lat_e7,
        y: lon_e7,
        z: alt_m,
        seq,
        command,
        target_system: 1,
        target_component: 1,
        frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
        current: 0,
        autocontinue: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
    }
}
