//! The server's TCP transport on 127.0.0.1, with real sockets: TCP
//! clients and a UDP client at once, answers to the requester over its own
//! connection, MAVLink 1 answered in MAVLink 1, and the limits (a fifth
//! client refused, garbage dropped, a client that does not read dropped,
//! memory not grown).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::client::Client;
use common::vehicle::*;
use helicon_gcs::link::Uplink;
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{MAVLinkMessageRaw, MavHeader, MavlinkReader, Message, MessageData};
use helicon_gcs::server::tcp::{MAX_TCP_CLIENTS, TCP_GARBAGE_BYTES};
use std::io::{ErrorKind, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// A TCP ground station (system `sys`, component 190).
struct TcpClient {
    reader: MavlinkReader<TcpStream>,
    sys: u8,
    /// Every frame received: (version 1, header, message).
    log: Vec<(bool, MavHeader, MavMessage)>,
    /// The server closed the connection.
    closed: bool,
}

impl TcpClient {
    fn connect(port: u16, sys: u8) -> TcpClient {
        let s = TcpStream::connect(("127.0.0.1", port)).unwrap();
        s.set_read_timeout(Some(Duration::from_millis(2))).unwrap();
        TcpClient {
            reader: MavlinkReader::new(s),
            sys,
            log: Vec::new(),
            closed: false,
        }
    }

    fn stream(&self) -> &TcpStream {
        self.reader.get_ref()
    }

    fn send_version(&self, msg: &MavMessage, v1: bool) {
        let h = MavHeader {
            system_id: self.sys,
            component_id: 190,
            sequence: 0,
        };
        let mut buf = Vec::new();
        if v1 {
            helicon_gcs::mavlink::write_v1_msg(&mut buf, h, msg).unwrap();
        } else {
            helicon_gcs::mavlink::write_v2_msg(&mut buf, h, msg).unwrap();
        }
        self.stream().write_all(&buf).unwrap();
    }

    fn send(&self, msg: &MavMessage) {
        self.send_version(msg, false);
    }

    /// Read what is waiting.
    fn drain(&mut self) {
        while !self.closed {
            match self.reader.read_any_raw_message::<MavMessage>() {
                Ok(raw) => {
                    let v1 = matches!(raw, MAVLinkMessageRaw::V1(_));
                    let h = MavHeader {
                        system_id: raw.system_id(),
                        component_id: raw.component_id(),
                        sequence: raw.sequence(),
                    };
                    if let Ok(m) = MavMessage::parse(raw.version(), raw.message_id(), raw.payload())
                    {
                        self.log.push((v1, h, m));
                    }
                }
                Err(helicon_gcs::mavlink::error::MessageReadError::Io(e))
                    if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) =>
                {
                    return;
                }
                Err(_) => self.closed = true,
            }
        }
    }

    /// Wait (wall clock) for a message after `from` that `pred` accepts.
    fn wait(
        &mut self,
        from: usize,
        pred: impl Fn(&MavMessage) -> bool,
    ) -> Option<(bool, MavMessage)> {
        let start = Instant::now();
        loop {
            self.drain();
            if let Some((v1, _, m)) = self.log[from.min(self.log.len())..]
                .iter()
                .find(|(_, _, m)| pred(m))
            {
                return Some((*v1, m.clone()));
            }
            if self.closed || start.elapsed() > T {
                return None;
            }
        }
    }

    /// Wait (wall clock) for the server to close the connection.
    fn wait_closed(&mut self) -> bool {
        self.wait_closed_within(T)
    }

    fn wait_closed_within(&mut self, within: Duration) -> bool {
        let start = Instant::now();
        while !self.closed && start.elapsed() < within {
            self.drain();
        }
        self.closed
    }
}

fn is_heartbeat(m: &MavMessage) -> bool {
    matches!(m, MavMessage::HEARTBEAT(_))
}

fn ack_to(c: &mut TcpClient, from: usize, command: MavCmd) -> Option<COMMAND_ACK_DATA> {
    match c.wait(
        from,
        |m| matches!(m, MavMessage::COMMAND_ACK(a) if a.command == command),
    ) {
        Some((_, MavMessage::COMMAND_ACK(a))) => Some(a),
        _ => None,
    }
}

#[test]
fn tcp_and_udp_clients_at_once_each_answered_on_its_own_connection() {
    let mut veh = Vehicle::start_on(None, true);
    let mut a = TcpClient::connect(veh.tcp_port, 255);
    let mut b = TcpClient::connect(veh.tcp_port, 254);
    let mut u = Client::to_port(veh.port, None);
    u.heartbeat();
    veh.status(2.0);
    // every client is sent the heartbeat, the TCP ones from their
    // connection on (before they have said anything)
    assert!(a.wait(0, is_heartbeat).is_some());
    assert!(b.wait(0, is_heartbeat).is_some());
    assert!(u.wait(0, T, is_heartbeat).is_some());
    // a's command is answered to a alone, addressed to its system and
    // component
    let (fa, fb, fu) = (a.log.len(), b.log.len(), u.log.len());
    a.send(&long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1, 1, ARM));
    veh.status(0.2);
    let ack = ack_to(&mut a, fa, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM).expect("a's ack");
    assert_eq!(ack.result, MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!((ack.target_system, ack.target_component), (255, 190));
    veh.status(0.5);
    b.drain();
    u.drain();
    let acks_b = b.log[fb..]
        .iter()
        .filter(|(_, _, m)| matches!(m, MavMessage::COMMAND_ACK(_)))
        .count();
    assert_eq!(acks_b, 0, "b was sent a's answer");
    assert_eq!(
        count(&mut u, fu, COMMAND_ACK_DATA::ID),
        0,
        "u was sent a's answer"
    );
    // b asks in MAVLink 1 and is answered in MAVLink 1, addressed to it
    let (fa, fb) = (a.log.len(), b.log.len());
    b.send_version(
        &long(MavCmd::MAV_CMD_REQUEST_MESSAGE, 1, 1, {
            let mut p = [0.0; 7];
            p[0] = AUTOPILOT_VERSION_DATA::ID as f32;
            p
        }),
        true,
    );
    veh.status(0.2);
    let (v1, _) = b
        .wait(fb, |m| matches!(m, MavMessage::COMMAND_ACK(_)))
        .expect("b's ack");
    // (MAVLink 1 carries no extension fields: its ack names no target)
    assert!(v1, "a MAVLink 1 request answered in MAVLink 2");
    // and the version asked for, to b alone (a speaks MAVLink 2)
    assert!(
        b.wait(fb, |m| matches!(m, MavMessage::AUTOPILOT_VERSION(_)))
            .is_none_or(|(v1, _)| v1)
    );
    // the UDP client's parameter read is answered to it, not over TCP
    a.drain();
    assert!(
        !a.log[fa..]
            .iter()
            .any(|(_, _, m)| matches!(m, MavMessage::COMMAND_ACK(_))),
        "a was sent b's answer"
    );
    let fa = a.log.len();
    assert!(param(&mut u, "GF_MAX_HOR_DIST") > 0.0);
    veh.status(0.3);
    a.drain();
    assert!(
        !a.log[fa..]
            .iter()
            .any(|(_, _, m)| matches!(m, MavMessage::PARAM_VALUE(_))),
        "a was sent u's parameter"
    );
    // streams keep reaching the TCP clients after they spoke
    let (fa, fb) = (a.log.len(), b.log.len());
    veh.status(1.5);
    assert!(
        a.wait(fa, |m| matches!(m, MavMessage::ATTITUDE(_)))
            .is_some()
    );
    assert!(b.wait(fb, is_heartbeat).is_some());
    // a client that closes is forgotten; the others keep being served
    drop(a);
    veh.status(1.0);
    let fb = b.log.len();
    veh.status(1.2);
    assert!(b.wait(fb, is_heartbeat).is_some());
    let r = veh.stop();
    println!("{r:?}");
    assert_eq!(r.tcp_accepted, 2, "{r:?}");
    assert_eq!(
        (r.tcp_refused, r.tcp_dropped_slow, r.tcp_dropped_garbage),
        (0, 0, 0),
        "{r:?}"
    );
    assert!(r.tcp_bytes_in > 0 && r.tcp_bytes_out > 0, "{r:?}");
}

#[test]
fn a_fifth_client_is_closed_at_once() {
    let mut veh = Vehicle::start_on(None, true);
    let mut cs: Vec<TcpClient> = (0..MAX_TCP_CLIENTS)
        .map(|i| TcpClient::connect(veh.tcp_port, 250 + i as u8))
        .collect();
    veh.status(0.5);
    for c in &mut cs {
        assert!(c.wait(0, is_heartbeat).is_some());
    }
    let mut fifth = TcpClient::connect(veh.tcp_port, 249);
    veh.status(0.5);
    assert!(fifth.wait_closed(), "a fifth client was served");
    assert!(fifth.log.is_empty());
    // once one leaves, a new client is served
    drop(cs.pop());
    veh.status(0.5);
    let mut again = TcpClient::connect(veh.tcp_port, 249);
    veh.status(1.5);
    assert!(again.wait(0, is_heartbeat).is_some());
    let r = veh.stop();
    assert_eq!((r.tcp_accepted, r.tcp_refused), (5, 1), "{r:?}");
}

#[test]
fn garbage_drops_the_client_and_creates_nothing() {
    let mut veh = Vehicle::start_on(None, true);
    let mut g = TcpClient::connect(veh.tcp_port, 255);
    let mut good = TcpClient::connect(veh.tcp_port, 254);
    veh.status(0.2);
    // bytes that start no frame (no 0xFD, no 0xFE), just under the limit:
    // the client is kept
    let junk: Vec<u8> = (0..TCP_GARBAGE_BYTES as usize)
        .map(|i| (i % 200) as u8 + 1)
        .collect();
    g.stream().write_all(&junk).unwrap();
    veh.status(0.2);
    let f = g.log.len();
    veh.status(1.2);
    assert!(g.wait(f, is_heartbeat).is_some(), "dropped under the limit");
    // another 1 KiB and it is over
    g.stream().write_all(&junk[..1024]).unwrap();
    veh.status(0.3);
    assert!(g.wait_closed(), "a garbage client was kept");
    assert_eq!(veh.commands(), vec![], "garbage commanded the vehicle");
    // the other client is still served
    let f = good.log.len();
    veh.status(1.2);
    assert!(good.wait(f, is_heartbeat).is_some());
    let r = veh.stop();
    assert_eq!(r.tcp_dropped_garbage, 1, "{r:?}");
    assert_eq!(r.received_tcp_frames, 0, "{r:?}");
}

#[test]
fn a_client_that_does_not_read_is_dropped() {
    let mut veh = Vehicle::start_on(None, true);
    let mut good = TcpClient::connect(veh.tcp_port, 254);
    // the slow client asks for every stream at 100 Hz and never reads
    let slow = TcpClient::connect(veh.tcp_port, 253);
    for (id, _, _) in helicon_gcs::server::STREAMS {
        slow.send(&long(
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            1,
            1,
            [id as f32, 10_000.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ));
    }
    // some 40 kB a simulated second to it: 300 s fill the loopback's
    // buffers (a few MB at most) and the server's 64 KiB many times over
    for _ in 0..300 {
        veh.status(1.0);
        good.drain();
    }
    let f = good.log.len();
    veh.status(1.2);
    assert!(
        good.wait(f, is_heartbeat).is_some(),
        "the reading client was dropped"
    );
    let r = veh.stop();
    println!("{r:?}");
    assert_eq!(r.tcp_dropped_slow, 1, "{r:?}");
    // the slow client's connection was closed: reading it ends
    let mut slow = slow;
    assert!(slow.wait_closed_within(Duration::from_secs(10)));
}

/// Upload `items` of `mission_type` from `c` (answering its item requests);
/// the MISSION_ACK's result, and the requests' (target_system,
/// target_component).
fn upload_over(
    c: &mut TcpClient,
    veh: &mut Vehicle,
    mission_type: MavMissionType,
    items: &[MISSION_ITEM_INT_DATA],
) -> (Option<MavMissionResult>, Vec<(u8, u8)>) {
    let mut from = c.log.len();
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: items.len() as u16,
        target_system: 1,
        target_component: 1,
        mission_type,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    let mut targets = Vec::new();
    loop {
        veh.status(0.02);
        match c.wait(from, |m| {
            matches!(
                m,
                MavMessage::MISSION_REQUEST_INT(_) | MavMessage::MISSION_ACK(_)
            )
        }) {
            Some((_, MavMessage::MISSION_REQUEST_INT(r))) => {
                from = c.log.len();
                targets.push((r.target_system, r.target_component));
                assert_eq!(r.mission_type, mission_type);
                c.send(&MavMessage::MISSION_ITEM_INT(
                    items[usize::from(r.seq)].clone(),
                ));
            }
            Some((_, MavMessage::MISSION_ACK(a))) => {
                assert_eq!(a.mission_type, mission_type);
                return (Some(a.mavtype), targets);
            }
            _ => return (None, targets),
        }
    }
}

/// Download the items of `mission_type`.
fn download_over(
    c: &mut TcpClient,
    veh: &mut Vehicle,
    mission_type: MavMissionType,
) -> Vec<MISSION_ITEM_INT_DATA> {
    let from = c.log.len();
    c.send(&MavMessage::MISSION_REQUEST_LIST(
        MISSION_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
            mission_type,
        },
    ));
    veh.status(0.02);
    let Some((_, MavMessage::MISSION_COUNT(n))) =
        c.wait(from, |m| matches!(m, MavMessage::MISSION_COUNT(_)))
    else {
        panic!("no MISSION_COUNT");
    };
    assert_eq!(n.mission_type, mission_type);
    let mut out = Vec::new();
    for seq in 0..n.count {
        let from = c.log.len();
        c.send(&MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            seq,
            target_system: 1,
            target_component: 1,
            mission_type,
        }));
        veh.status(0.02);
        let Some((_, MavMessage::MISSION_ITEM_INT(it))) =
            c.wait(from, |m| matches!(m, MavMessage::MISSION_ITEM_INT(_)))
        else {
            panic!("no item {seq}");
        };
        out.push(it);
    }
    out
}

fn fence_item(
    seq: u16,
    command: MavCmd,
    param1: f32,
    lat_e7: i32,
    lon_e7: i32,
) -> MISSION_ITEM_INT_DATA {
    MISSION_ITEM_INT_DATA {
        param1,
        x: lat_e7,
        y: lon_e7,
        seq,
        command,
        target_system: 1,
        target_component: 1,
        frame: MavFrame::MAV_FRAME_GLOBAL,
        mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
        ..MISSION_ITEM_INT_DATA::DEFAULT
    }
}

#[test]
fn a_fence_uploaded_over_tcp_checks_targets_and_clears_alone() {
    let mut veh = Vehicle::start_on(None, true);
    let mut a = TcpClient::connect(veh.tcp_port, 255);
    veh.status(0.2);
    let fence = MavMissionType::MAV_MISSION_TYPE_FENCE;
    // home is 57.0146 N 9.9869 E: a 40 m inclusion circle about it
    let circle = vec![fence_item(
        0,
        MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
        40.0,
        570_146_000,
        99_869_000,
    )];
    let (r, targets) = upload_over(&mut a, &mut veh, fence, &circle);
    assert_eq!(r, Some(MavMissionResult::MAV_MISSION_ACCEPTED));
    assert_eq!(targets, vec![(255, 190)]);
    assert_eq!(
        veh.uplinks()
            .iter()
            .filter(|u| matches!(u, Uplink::Zones(_)))
            .count(),
        1
    );
    let back = download_over(&mut a, &mut veh, fence);
    assert_eq!(back.len(), 1);
    assert_eq!(
        (back[0].command, back[0].param1, back[0].x, back[0].y),
        (circle[0].command, 40.0, circle[0].x, circle[0].y)
    );
    assert_eq!(
        (back[0].target_system, back[0].target_component),
        (255, 190)
    );
    // a mission: a waypoint 20 m north is inside, 60 m north outside
    let wp = |seq, dlat| {
        let mut it = common::client::item(
            seq,
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            570_146_000 + dlat,
            99_869_000,
            10.0,
        );
        it.target_component = 1;
        it
    };
    let mission = MavMissionType::MAV_MISSION_TYPE_MISSION;
    let takeoff = common::client::item(0, MavCmd::MAV_CMD_NAV_TAKEOFF, 0, 0, 10.0);
    let (r, _) = upload_over(&mut a, &mut veh, mission, &[takeoff.clone(), wp(1, 1_798)]);
    assert_eq!(r, Some(MavMissionResult::MAV_MISSION_ACCEPTED));
    let (r, _) = upload_over(&mut a, &mut veh, mission, &[takeoff.clone(), wp(1, 5_395)]);
    assert_eq!(r, Some(MavMissionResult::MAV_MISSION_DENIED));
    // the mission kept is the first
    assert_eq!(download_over(&mut a, &mut veh, mission).len(), 2);
    // a bad fence is refused and the old one kept
    let (r, _) = upload_over(
        &mut a,
        &mut veh,
        fence,
        &[fence_item(
            0,
            MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
            -1.0,
            570_146_000,
            99_869_000,
        )],
    );
    assert_eq!(r, Some(MavMissionResult::MAV_MISSION_INVALID_PARAM1));
    assert_eq!(download_over(&mut a, &mut veh, fence).len(), 1);
    // clearing the fence leaves the mission
    let from = a.log.len();
    a.send(&MavMessage::MISSION_CLEAR_ALL(MISSION_CLEAR_ALL_DATA {
        target_system: 1,
        target_component: 1,
        mission_type: fence,
    }));
    veh.status(0.05);
    assert!(a.wait(from, |m| matches!(m, MavMessage::MISSION_ACK(k) if k.mission_type == fence && k.mavtype == MavMissionResult::MAV_MISSION_ACCEPTED)).is_some());
    assert!(download_over(&mut a, &mut veh, fence).is_empty());
    assert_eq!(download_over(&mut a, &mut veh, mission).len(), 2);
    // and the far waypoint is now accepted
    let (r, _) = upload_over(&mut a, &mut veh, mission, &[takeoff, wp(1, 5_395)]);
    assert_eq!(r, Some(MavMissionResult::MAV_MISSION_ACCEPTED));
    veh.stop();
}
