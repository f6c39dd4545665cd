//! The server under attack on real UDP sockets on 127.0.0.1: stray
//! datagrams, several ground stations at once, messages for another
//! vehicle, unsigned and replayed frames when signing is configured, and
//! targets outside the geofence. The vehicle's ring ends are the test's:
//! what reaches the uplink is what would fly.
#![allow(clippy::unwrap_used, clippy::expect_used)]
// test helpers: a failed unwrap is a failed test
// ground stations still send the superseded SET_MODE and REQUEST_DATA_STREAM
#![allow(deprecated)]

mod common;

use common::client::{Client, item};
use common::vehicle::*;
use helicon_gcs::link::Uplink;
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{Message, MessageData};
use helicon_gcs::navigator::{GuidedTarget, NavMode};
use helicon_gcs::server::{TEXT_LOG_BURST, TEXT_LOG_RATE_HZ};
use nalgebra::Vector3;
use std::net::UdpSocket;
use std::time::{Duration, Instant};

#[test]
fn a_stray_datagram_does_not_steal_the_telemetry() {
    let mut veh = Vehicle::start(None);
    let mut gcs = Client::to_port(veh.port, None);
    gcs.heartbeat();
    veh.status(1.0);
    assert!(
        count(&mut gcs, 0, HEARTBEAT_DATA::ID) >= 1,
        "the ground station hears nothing"
    );
    // a stray 1-byte datagram, and a datagram of noise with the MAVLink 2
    // start byte, from another address
    let stray = UdpSocket::bind("127.0.0.1:0").unwrap();
    stray.send_to(&[0x55], ("127.0.0.1", veh.port)).unwrap();
    stray
        .send_to(
            &[0xFD, 9, 0, 0, 1, 255, 190, 0, 0, 0, 1, 2, 3],
            ("127.0.0.1", veh.port),
        )
        .unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let from = gcs.log.len();
    veh.status(2.0);
    gcs.drain();
    // the ground station keeps every stream: 2 s of ATTITUDE at 10 Hz
    let n = count(&mut gcs, from, ATTITUDE_DATA::ID);
    assert!(n >= 19, "{n} ATTITUDE after the stray datagram");
    // the stray sender is sent nothing
    assert!(silent(&stray, SHORT), "the stray address was answered");
    let r = veh.stop();
    assert_eq!(r.garbage_datagrams, 2, "{r:?}");
    assert_eq!(r.peers_max, 1, "{r:?}");
}

#[test]
fn two_ground_stations_each_with_their_own_link_and_rates() {
    let mut veh = Vehicle::start(None);
    let mut a = Client::to_port(veh.port, None);
    let mut b = Client::to_port(veh.port, None);
    a.heartbeat();
    b.heartbeat();
    veh.status(0.5);
    // A stops ATTITUDE; B keeps it at 10 Hz and asks for RC_CHANNELS at 20 Hz
    let from = a.log.len();
    a.send(&long(
        MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        1,
        1,
        [ATTITUDE_DATA::ID as f32, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    ));
    assert_eq!(
        ack_within(&mut a, from, MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, T),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let from_b = b.log.len();
    b.send(&long(
        MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        1,
        1,
        [
            RC_CHANNELS_DATA::ID as f32,
            50_000.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
    ));
    assert_eq!(
        ack_within(&mut b, from_b, MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, T),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    // the acknowledgement went to the one who asked: B got one, not A's
    assert_eq!(count(&mut b, 0, COMMAND_ACK_DATA::ID), 1);
    let (fa, fb) = (a.log.len(), b.log.len());
    for _ in 0..4 {
        a.heartbeat();
        b.heartbeat();
        veh.status(0.5);
    }
    a.drain();
    b.drain();
    assert_eq!(count(&mut a, fa, ATTITUDE_DATA::ID), 0);
    assert_eq!(count(&mut a, fa, RC_CHANNELS_DATA::ID), 0);
    let att_b = count(&mut b, fb, ATTITUDE_DATA::ID);
    let rc_b = count(&mut b, fb, RC_CHANNELS_DATA::ID);
    assert!((19..=21).contains(&att_b), "B: {att_b} ATTITUDE in 2 s");
    assert!((39..=41).contains(&rc_b), "B: {rc_b} RC_CHANNELS in 2 s");
    for c in [&mut a, &mut b] {
        let hb = count(c, 0, HEARTBEAT_DATA::ID);
        assert!(hb >= 2, "{hb} heartbeats");
    }
    // both stations' heartbeats keep the link
    let hbs = veh
        .uplinks()
        .iter()
        .filter(|u| **u == Uplink::GcsHeartbeat)
        .count();
    assert!(hbs >= 10, "{hbs}");
    // A falls silent: it keeps its telemetry through a link loss (its
    // uplink may be what failed), and after 300 s it is sent nothing more
    for _ in 0..20 {
        b.heartbeat();
        veh.status(0.5);
    }
    let fa = a.log.len();
    veh.status(0.5);
    assert!(
        count(&mut a, fa, HEARTBEAT_DATA::ID) >= 1,
        "dropped after 10 s"
    );
    for _ in 0..580 {
        b.heartbeat();
        veh.status(0.5);
    }
    a.drain();
    let fa = a.log.len();
    let fb = b.log.len();
    b.heartbeat();
    veh.status(1.0);
    a.drain();
    b.drain();
    assert_eq!(a.log.len(), fa, "a silent station is still sent telemetry");
    assert!(b.log.len() > fb + 10);
    let r = veh.stop();
    assert_eq!(r.peers_max, 2);
}

#[test]
fn messages_for_another_vehicle_are_ignored_without_an_answer() {
    let mut veh = Vehicle::start(None);
    let mut c = Client::to_port(veh.port, None);
    c.heartbeat();
    veh.status(0.5);
    veh.uplinks();
    // COMMAND_LONG arm for system 99, and for component 50 of system 1
    for (sys, comp) in [(99, 1), (1, 50), (99, 0)] {
        let from = c.log.len();
        c.send(&long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, sys, comp, ARM));
        assert_eq!(
            ack_within(&mut c, from, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, SHORT),
            None,
            "({sys}, {comp}) answered"
        );
    }
    // COMMAND_INT, SET_MODE, PARAM_SET, MISSION_COUNT, MISSION_CLEAR_ALL,
    // REQUEST_DATA_STREAM, SET_POSITION_TARGET for system 99
    let from = c.log.len();
    c.send(&MavMessage::COMMAND_INT(COMMAND_INT_DATA {
        command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        param1: 1.0,
        target_system: 99,
        target_component: 1,
        ..COMMAND_INT_DATA::DEFAULT
    }));
    c.send(&MavMessage::SET_MODE(SET_MODE_DATA {
        custom_mode: NavMode::Hold.code(),
        target_system: 99,
        base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
    }));
    c.send(&param_set("NAV_CRUISE_SPD", 3.0, 99));
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: 1,
        target_system: 99,
        target_component: 1,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    c.send(&MavMessage::MISSION_CLEAR_ALL(MISSION_CLEAR_ALL_DATA {
        target_system: 99,
        target_component: 1,
        ..MISSION_CLEAR_ALL_DATA::DEFAULT
    }));
    c.send(&MavMessage::REQUEST_DATA_STREAM(REQUEST_DATA_STREAM_DATA {
        req_message_rate: 0,
        target_system: 99,
        target_component: 1,
        req_stream_id: MavDataStream::MAV_DATA_STREAM_ALL,
        start_stop: 0,
    }));
    c.send(&position_target(10.0, 0.0, -10.0, 99));
    veh.status(1.0);
    c.drain();
    let answers = c.collect(from, |m| match m {
        MavMessage::COMMAND_ACK(_)
        | MavMessage::PARAM_VALUE(_)
        | MavMessage::MISSION_REQUEST_INT(_)
        | MavMessage::MISSION_ACK(_)
        | MavMessage::STATUSTEXT(_) => Some(m.message_name()),
        _ => None,
    });
    assert!(answers.is_empty(), "answered: {answers:?}");
    // the streams go on (REQUEST_DATA_STREAM stop was not for us)
    assert!(count(&mut c, from, ATTITUDE_DATA::ID) >= 9);
    assert_eq!(
        veh.commands(),
        vec![],
        "a foreign message reached the vehicle"
    );
    assert_eq!(param(&mut c, "NAV_CRUISE_SPD"), 2.0);
    // broadcast (0) and this vehicle (1) are obeyed
    let from = c.log.len();
    c.send(&long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0, 0, ARM));
    assert_eq!(
        ack_within(&mut c, from, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, T),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    assert_eq!(veh.commands(), vec![Uplink::Arm(true)]);
    let r = veh.stop();
    assert_eq!(r.other_target, 10, "{r:?}");
}

#[test]
fn with_signing_nothing_unsigned_or_replayed_changes_anything() {
    let key = [7u8; 32];
    let mut veh = Vehicle::start(Some(key));
    let mut good = Client::to_port(veh.port, Some(key));
    good.heartbeat();
    veh.status(1.0);
    assert!(
        count(&mut good, 0, ATTITUDE_DATA::ID) >= 9,
        "the signed station hears nothing"
    );
    veh.uplinks();

    for (who, k) in [("unsigned", None), ("wrong key", Some([8u8; 32]))] {
        let mut bad = Client::to_port(veh.port, k);
        let from = good.log.len();
        // heartbeats, a stream stop for everyone, a parameter, a mode, a
        // mission clear, a guided target, an arm
        bad.heartbeat();
        bad.send(&MavMessage::REQUEST_DATA_STREAM(REQUEST_DATA_STREAM_DATA {
            req_message_rate: 0,
            target_system: 1,
            target_component: 1,
            req_stream_id: MavDataStream::MAV_DATA_STREAM_ALL,
            start_stop: 0,
        }));
        bad.send(&long(
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            1,
            1,
            [ATTITUDE_DATA::ID as f32, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ));
        bad.send(&param_set("FS_LINK_TO", 120.0, 1));
        bad.send(&MavMessage::SET_MODE(SET_MODE_DATA {
            custom_mode: NavMode::Land.code(),
            target_system: 1,
            base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
        }));
        bad.send(&MavMessage::MISSION_CLEAR_ALL(MISSION_CLEAR_ALL_DATA {
            target_system: 1,
            target_component: 1,
            ..MISSION_CLEAR_ALL_DATA::DEFAULT
        }));
        bad.send(&position_target(10.0, 0.0, -10.0, 1));
        let from_bad = bad.log.len();
        bad.send(&long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1, 1, ARM));
        // the command is refused to its sender
        assert_eq!(
            ack_within(&mut bad, from_bad, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, T),
            Some(MavResult::MAV_RESULT_DENIED),
            "{who}"
        );
        veh.status(1.0);
        good.drain();
        bad.drain();
        // nothing reached the vehicle, not even a heartbeat (the link-loss
        // failsafe is not held off)
        assert_eq!(veh.uplinks(), vec![], "{who}");
        // only the refusal, for the flight log
        assert!(
            veh.logged_texts
                .iter()
                .all(|t| t == "refused: command not signed with the vehicle's key"),
            "{who}: {:?}",
            veh.logged_texts
        );
        // the signed station's streams go on
        let n = count(&mut good, from, ATTITUDE_DATA::ID);
        assert!(n >= 9, "{who}: {n} ATTITUDE");
        // the unsigned sender is sent no telemetry
        let tele = bad.collect(0, |m| match m {
            MavMessage::COMMAND_ACK(_) | MavMessage::STATUSTEXT(_) => None,
            m => Some(m.message_name()),
        });
        assert!(tele.is_empty(), "{who} was sent {tele:?}");
        assert_eq!(param(&mut good, "FS_LINK_TO"), 5.0, "{who}");
    }

    // replay: a signed PARAM_SET accepted, a second one newer, the first
    // replayed (from its address and from another): the value is the second
    let mut signer = Signer::new(key, 3);
    let first = signer.frame(&param_set("NAV_CRUISE_SPD", 3.0, 1));
    let second = signer.frame(&param_set("NAV_CRUISE_SPD", 4.0, 1));
    let raw = UdpSocket::bind("127.0.0.1:0").unwrap();
    let other = UdpSocket::bind("127.0.0.1:0").unwrap();
    raw.send_to(&first, ("127.0.0.1", veh.port)).unwrap();
    veh.status(0.1);
    assert_eq!(param(&mut good, "NAV_CRUISE_SPD"), 3.0);
    raw.send_to(&second, ("127.0.0.1", veh.port)).unwrap();
    veh.status(0.1);
    assert_eq!(param(&mut good, "NAV_CRUISE_SPD"), 4.0);
    raw.send_to(&first, ("127.0.0.1", veh.port)).unwrap();
    other.send_to(&first, ("127.0.0.1", veh.port)).unwrap();
    other.send_to(&second, ("127.0.0.1", veh.port)).unwrap();
    veh.status(0.1);
    assert_eq!(
        param(&mut good, "NAV_CRUISE_SPD"),
        4.0,
        "a replay was obeyed"
    );
    // the replaying address became no peer: it is sent no telemetry (only
    // the refusal of the replayed PARAM_SET)
    veh.status(1.0);
    let sent = received(&other, SHORT);
    assert!(
        sent.iter().all(|m| matches!(m, MavMessage::STATUSTEXT(_))),
        "the replaying address was sent {sent:?}"
    );
    let r = veh.stop();
    // 8 frames of each bad station, 3 replays
    assert_eq!(r.refused_unsigned, 2 * 8 + 3, "{r:?}");
    assert_eq!(r.peers_max, 2, "{r:?}");
}

/// Arm the vehicle (its statuses say armed from then on).
fn arm(veh: &mut Vehicle, c: &mut Client) {
    let from = c.log.len();
    c.send(&long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1, 1, ARM));
    assert_eq!(
        ack_within(c, from, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, T),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    veh.armed = true;
    veh.status(0.1);
    veh.uplinks();
}

/// A vehicle armed and holding, a ground station heard.
fn armed_vehicle() -> (Vehicle, Client) {
    let mut veh = Vehicle::start(None);
    let mut c = Client::to_port(veh.port, None);
    c.heartbeat();
    veh.status(0.5);
    arm(&mut veh, &mut c);
    (veh, c)
}

#[test]
fn fence_parameters_and_takeoff_heights() {
    let mut veh = Vehicle::start(None);
    let mut c = Client::to_port(veh.port, None);
    c.heartbeat();
    veh.status(0.5);
    // the fence is in the parameter list with PX4's names
    let from = c.log.len();
    c.send(&MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA {
        target_system: 1,
        target_component: 1,
    }));
    veh.status(0.2);
    std::thread::sleep(Duration::from_millis(50));
    c.drain();
    let names = c.collect(from, |m| match m {
        MavMessage::PARAM_VALUE(p) => Some((
            p.param_id
                .to_str()
                .unwrap_or("")
                .trim_end_matches('\0')
                .to_string(),
            p.param_value,
        )),
        _ => None,
    });
    for (name, value) in [
        ("GF_MAX_HOR_DIST", 150.0),
        ("GF_MAX_VER_DIST", 60.0),
        ("GF_ACTION", 3.0),
    ] {
        assert!(
            names.iter().any(|(n, v)| n == name && *v == value),
            "{name}: {names:?}"
        );
    }
    // PX4's GF_ACTION 0 (none) and 4 (terminate) are not offered
    for v in [0.0, 4.0, 2.5] {
        c.send(&param_set("GF_ACTION", v, 1));
        assert_eq!(param(&mut c, "GF_ACTION"), 3.0);
    }
    c.send(&param_set("GF_MAX_VER_DIST", 500.0, 1));
    assert_eq!(param(&mut c, "GF_MAX_VER_DIST"), 60.0);

    let (mut veh, mut c) = (veh, c);
    arm(&mut veh, &mut c);

    // takeoff heights (PX4's param7: AMSL; home at 20 m): above the fence,
    // infinite, below ground refused
    for h in [81.0, f32::INFINITY, 15.0, 3e38] {
        let from = c.log.len();
        c.send(&long(
            MavCmd::MAV_CMD_NAV_TAKEOFF,
            1,
            1,
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, h],
        ));
        assert_eq!(
            ack_within(&mut c, from, MavCmd::MAV_CMD_NAV_TAKEOFF, T),
            Some(MavResult::MAV_RESULT_DENIED),
            "takeoff to {h} m"
        );
    }
    let from = c.log.len();
    c.send(&long(
        MavCmd::MAV_CMD_NAV_TAKEOFF,
        1,
        1,
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 80.0],
    ));
    assert_eq!(
        ack_within(&mut c, from, MavCmd::MAV_CMD_NAV_TAKEOFF, T),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    assert_eq!(veh.commands(), vec![Uplink::Takeoff(60.0)]);

    veh.stop();
}

#[test]
fn targets_gotos_and_missions_outside_the_fence_are_refused() {
    let (mut veh, mut c) = armed_vehicle();
    // local position targets: z = −3e38, 3e38 m away, 151 m out, NaN,
    // underground: none reaches the vehicle, each is told
    let from = c.log.len();
    for (x, y, z) in [
        (0.0, 0.0, -3e38),
        (3e38, 0.0, -10.0),
        (151.0, 0.0, -10.0),
        (f32::NAN, 0.0, -10.0),
        (0.0, 0.0, 5.0),
    ] {
        c.send(&position_target(x, y, z, 1));
    }
    veh.status(0.5);
    assert_eq!(veh.commands(), vec![]);
    c.drain();
    let refused = c
        .texts()
        .iter()
        .filter(|t| t.starts_with("guided refused"))
        .count();
    assert_eq!(refused, 5, "{:?}", c.collect(from, |_| Some(())).len());
    // inside the fence: taken
    c.send(&position_target(100.0, 100.0, -50.0, 1));
    veh.status(0.1);
    assert_eq!(
        veh.commands(),
        vec![Uplink::Guided(GuidedTarget::Position(
            Vector3::new(100.0, 100.0, -50.0),
            None
        ))]
    );

    // a guided goto (DO_REPOSITION) 300 km away, and one 100 m north
    for (lat, want) in [
        (599_146_000, MavResult::MAV_RESULT_DENIED),
        (570_155_000, MavResult::MAV_RESULT_ACCEPTED),
    ] {
        let from = c.log.len();
        c.send(&MavMessage::COMMAND_INT(COMMAND_INT_DATA {
            command: MavCmd::MAV_CMD_DO_REPOSITION,
            param1: -1.0,
            param4: f32::NAN,
            x: lat,
            y: 99_869_000,
            z: 10.0,
            frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            target_system: 1,
            target_component: 1,
            ..COMMAND_INT_DATA::DEFAULT
        }));
        assert_eq!(
            ack_within(&mut c, from, MavCmd::MAV_CMD_DO_REPOSITION, T),
            Some(want),
            "goto {lat}"
        );
    }
    match veh.commands().as_slice() {
        [Uplink::Guided(GuidedTarget::Position(p, None))] => {
            // 0.0009° of latitude: 100.2 m at 57° (the meridian radius
            // 6 380 420 m)
            assert!((p.x - 100.22).abs() < 0.1 && p.y.abs() < 1e-6, "{p}");
            assert!((p.z + 10.0).abs() < 1e-3, "{p}");
        }
        other => panic!("{other:?}"),
    }

    // missions: a waypoint 300 km away, one on the far side of the Earth,
    // one 70 m up, a takeoff to 80 m: MAV_MISSION_DENIED; inside: accepted
    let wp = |lat, lon, alt| {
        vec![
            item(0, MavCmd::MAV_CMD_NAV_TAKEOFF, 0, 0, 10.0),
            item(1, MavCmd::MAV_CMD_NAV_WAYPOINT, lat, lon, alt),
            item(2, MavCmd::MAV_CMD_NAV_LAND, 0, 0, 0.0),
        ]
    };
    let mut high_takeoff = wp(570_147_000, 99_869_000, 10.0);
    high_takeoff[0].z = 80.0;
    for (items, why) in [
        (wp(599_146_000, 99_869_000, 10.0), "300 km"),
        (wp(-570_146_000, -1_700_131_000, 10.0), "antipode"),
        (wp(570_147_000, 99_869_000, 70.0), "70 m up"),
        (high_takeoff, "takeoff 80 m"),
    ] {
        assert_eq!(
            upload(&mut c, &items),
            Some(MavMissionResult::MAV_MISSION_DENIED),
            "{why}"
        );
    }
    assert_eq!(
        upload(&mut c, &wp(570_147_000, 99_869_000, 10.0)),
        Some(MavMissionResult::MAV_MISSION_ACCEPTED)
    );
    let plans = veh
        .commands()
        .into_iter()
        .filter(|u| matches!(u, Uplink::Plan(_)))
        .count();
    assert_eq!(plans, 1, "a refused mission reached the vehicle");
    assert!(
        c.texts()
            .iter()
            .any(|t| t == "mission refused: item 1: beyond GF_MAX_HOR_DIST"),
        "{:?}",
        c.texts()
    );
    // a wider fence (GF_MAX_HOR_DIST 500) takes a goto 300 m out
    c.send(&param_set("GF_MAX_HOR_DIST", 500.0, 1));
    assert_eq!(param(&mut c, "GF_MAX_HOR_DIST"), 500.0);
    c.send(&position_target(300.0, 0.0, -10.0, 1));
    veh.status(0.1);
    let u = veh.commands();
    assert!(
        u.iter()
            .any(|x| matches!(x, Uplink::Config(c) if c.fence.max_hor_dist_m == 500.0)),
        "{u:?}"
    );
    assert!(u.contains(&Uplink::Guided(GuidedTarget::Position(
        Vector3::new(300.0, 0.0, -10.0),
        None
    ))));
    veh.stop();
}

/// The server's own replies reach the flight log, but a ground station
/// repeating a refused command cannot flood it: at most the burst of
/// `TEXT_LOG_BURST` (plus what `TEXT_LOG_RATE_HZ` adds while they arrive),
/// while refusals beyond the log's limit are still told on the link.
#[test]
fn refusals_are_logged_at_a_bounded_rate() {
    let mut veh = Vehicle::start(None);
    let mut gcs = Client::to_port(veh.port, None);
    gcs.heartbeat();
    veh.status(0.5);
    let t0 = Instant::now();
    for _ in 0..200 {
        // disarmed: each is refused with a text
        gcs.send(&long(MavCmd::MAV_CMD_NAV_LAND, 1, 1, [0.0; 7]));
    }
    veh.status(1.0);
    let elapsed_s = t0.elapsed().as_secs_f64();
    gcs.drain();
    let told = gcs
        .texts()
        .into_iter()
        .filter(|t| t == "refused: not armed")
        .count();
    assert_eq!(veh.commands(), vec![]);
    let logged = veh.logged_texts.len();
    let bound = TEXT_LOG_BURST + TEXT_LOG_RATE_HZ * elapsed_s + 1.0;
    assert!(
        logged >= 20 && (logged as f64) <= bound,
        "{logged} logged, bound {bound:.1}"
    );
    assert!(
        veh.logged_texts.iter().all(|t| t == "refused: not armed"),
        "{:?}",
        veh.logged_texts
    );
    let r = veh.stop();
    assert_eq!(r.texts_logged as usize, logged, "{r:?}");
    assert_eq!(r.texts_logged + r.texts_not_logged, 200, "{r:?}");
    assert!(
        told as f64 > bound,
        "{told} refusals told on the link, {logged} logged"
    );
}
