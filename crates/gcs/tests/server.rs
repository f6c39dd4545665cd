//! The server alone, the vehicle's ring ends in the test's hands: what the
//! ground station's commands put on the uplink, and every refusal answered
//! (never applied, never a dead server).
#![allow(clippy::unwrap_used, clippy::expect_used)]
// test helpers: a failed unwrap is a failed test
// the field tools send the superseded SET_MODE, MISSION_REQUEST and GET_* commands
#![allow(deprecated)]

mod common;

use common::client::{Client, item};
use helicon_core::Reference;
use helicon_core::state::Input;
use helicon_devices::Geodetic;
use helicon_gcs::link::{Downlink, FlightMode, Uplink, VehicleEnd, VehicleStatus, channel};
use helicon_gcs::mavlink::MessageData;
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::navigator::{NavMode, NavigatorConfig};
use helicon_gcs::server::{self, ServerConfig, ServerHandle, default_rates_hz};
use nalgebra::Vector3;
use std::time::{Duration, Instant};

fn status(t_s: f64, armed: bool, nav_mode: NavMode) -> VehicleStatus {
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

fn start() -> (Client, VehicleEnd, ServerHandle) {
    let c = Client::new(None);
    let (mut v, s) = channel(256);
    let h = server::spawn(
        ServerConfig {
            address: c.server_address(),
            system_id: 1,
            home: Geodetic::new(57.0146, 9.9869, 20.0).unwrap(),
            navigator: NavigatorConfig::default(),
            signing_key: None,
            rates_hz: default_rates_hz(),
        },
        s,
    )
    .unwrap();
    v.downlink
        .push(Downlink::Status(status(0.0, false, NavMode::Idle)))
        .unwrap();
    (c, v, h)
}

/// Wait for the server to have handled what was pushed.
fn settle(h: &ServerHandle, n: u64) {
    let t = Instant::now();
    while h.processed() < n {
        assert!(t.elapsed() < Duration::from_secs(3));
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// The uplinks but the server's texts for the flight log.
fn uplinks(v: &mut VehicleEnd) -> Vec<Uplink> {
    std::thread::sleep(Duration::from_millis(20));
    let mut out = Vec::new();
    while let Ok(u) = v.uplink.pop() {
        if !matches!(u, Uplink::Text(_)) {
            out.push(u);
        }
    }
    out
}

fn mission_ack(c: &mut Client, items: &[MISSION_ITEM_INT_DATA]) -> MavMissionResult {
    let mut cursor = c.log.len();
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: items.len() as u16,
        target_system: 1,
        target_component: 1,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    loop {
        let (i, m) = c
            .wait_index(cursor, Duration::from_secs(3), |m| {
                matches!(
                    m,
                    MavMessage::MISSION_REQUEST_INT(_) | MavMessage::MISSION_ACK(_)
                )
            })
            .expect("request or ack");
        cursor = i + 1;
        match m {
            MavMessage::MISSION_REQUEST_INT(r) => {
                // addressed to the requester (system 255, component 190)
                assert_eq!((r.target_system, r.target_component), (255, 190));
                c.send(&MavMessage::MISSION_ITEM_INT(items[r.seq as usize].clone()));
            }
            MavMessage::MISSION_ACK(a) => return a.mavtype,
            _ => unreachable!(),
        }
    }
}

#[test]
fn commands_reach_the_uplink_and_refusals_are_answered() {
    let (mut c, mut v, h) = start();
    settle(&h, 1);
    // the client answers the server once it has heard it (udpin)
    assert!(
        c.wait(0, Duration::from_secs(3), |m| matches!(
            m,
            MavMessage::HEARTBEAT(_)
        ))
        .is_some()
    );
    c.heartbeat();
    let r = |c: &mut Client, cmd, p| c.command(cmd, p);
    let z = [0.0f32; 7];
    // not armed: takeoff and mission start denied
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_NAV_TAKEOFF, z),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_MISSION_START, z),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    // the takeoff queued behind the arm is accepted; 1 km is not
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_NAV_TAKEOFF,
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1000.0]
        ),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_NAV_TAKEOFF,
            // PX4's param7: AMSL (home 20 m), 7.5 m above home
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 27.5]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let u = uplinks(&mut v);
    assert!(u.contains(&Uplink::GcsHeartbeat), "{u:?}");
    let commands: Vec<_> = u
        .into_iter()
        .filter(|x| *x != Uplink::GcsHeartbeat)
        .collect();
    assert_eq!(commands, vec![Uplink::Arm(true), Uplink::Takeoff(7.5)]);

    // flying: disarm refused unless forced
    v.downlink
        .push(Downlink::Status(status(1.0, true, NavMode::Mission)))
        .unwrap();
    settle(&h, 2);
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, z),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    // a mode while armed (PX4's AUTO.LOITER: main 4, sub 3); an unknown
    // one, and one helicon does not fly (POSCTL), refused
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_DO_SET_MODE,
            [1.0, 99.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_DO_SET_MODE,
            [1.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_DO_SET_MODE,
            [1.0, 4.0, 3.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    // after a (forced) disarm, modes are refused
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [0.0, 21196.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    // message intervals: faster than 100 Hz refused, unknown ids unsupported
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            [ATTITUDE_DATA::ID as f32, 1000.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            [9999.0, 20_000.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_UNSUPPORTED)
    );
    // (AUTO.RTL)
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_DO_SET_MODE,
            [1.0, 4.0, 5.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    let u: Vec<_> = uplinks(&mut v)
        .into_iter()
        .filter(|x| *x != Uplink::GcsHeartbeat)
        .collect();
    assert_eq!(u, vec![Uplink::Hold, Uplink::Arm(false)]);
    let report = h.stop();
    assert_eq!(report.send_errors, 0);
}

#[test]
fn missions_refused_with_their_reason_and_the_old_one_kept() {
    let (mut c, mut v, h) = start();
    settle(&h, 1);
    // the client answers the server once it has heard it (udpin)
    assert!(
        c.wait(0, Duration::from_secs(3), |m| matches!(
            m,
            MavMessage::HEARTBEAT(_)
        ))
        .is_some()
    );
    c.heartbeat();
    let good = vec![
        item(0, MavCmd::MAV_CMD_NAV_TAKEOFF, 0, 0, 10.0),
        item(
            1,
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            570_147_000,
            99_869_000,
            10.0,
        ),
        item(2, MavCmd::MAV_CMD_NAV_LAND, 0, 0, 0.0),
    ];
    assert_eq!(
        mission_ack(&mut c, &good),
        MavMissionResult::MAV_MISSION_ACCEPTED
    );
    let u = uplinks(&mut v);
    let Some(Uplink::Plan(p)) = u.iter().find(|x| matches!(x, Uplink::Plan(_))) else {
        panic!("no plan: {u:?}");
    };
    assert_eq!(p.len(), 3);
    // 0.0001° of latitude north of home: the WGS-84 meridian radius at
    // 57.0146° is M = a(1−e²)/(1−e²sin²φ)^1.5 = 6 380 420 m, so 11.136 m
    let wp = p.get(1).unwrap().position_ned_m;
    assert!(
        (wp.x - 11.14).abs() < 0.02 && wp.y.abs() < 1e-6 && (wp.z + 10.0).abs() < 1e-3,
        "{wp}"
    );

    let mut bad_cmd = good.clone();
    bad_cmd[1].command = MavCmd::MAV_CMD_DO_JUMP;
    let mut bad_lat = good.clone();
    bad_lat[1].x = 950_000_000;
    let mut bad_frame = good.clone();
    bad_frame[1].frame = MavFrame::MAV_FRAME_BODY_FRD;
    let mut bad_alt = good.clone();
    bad_alt[0].z = f32::NAN;
    let mut bad_radius = good.clone();
    bad_radius[1].param2 = -1.0;
    for (items, want) in [
        (bad_cmd, MavMissionResult::MAV_MISSION_UNSUPPORTED),
        (bad_lat, MavMissionResult::MAV_MISSION_INVALID_PARAM5_X),
        (bad_frame, MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME),
        (bad_alt, MavMissionResult::MAV_MISSION_INVALID_PARAM7),
        (bad_radius, MavMissionResult::MAV_MISSION_INVALID_PARAM2),
    ] {
        assert_eq!(mission_ack(&mut c, &items), want);
    }
    assert!(
        c.texts()
            .iter()
            .any(|t| t.starts_with("mission refused: item 1")),
        "{:?}",
        c.texts()
    );
    // nothing refused reached the vehicle; the accepted mission is still the one sent back
    assert!(
        !uplinks(&mut v).iter().any(|x| matches!(x, Uplink::Plan(_))),
        "a refused mission was applied"
    );
    let from = c.log.len();
    c.send(&MavMessage::MISSION_REQUEST_LIST(
        MISSION_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
            ..MISSION_REQUEST_LIST_DATA::DEFAULT
        },
    ));
    match c.wait(from, Duration::from_secs(3), |m| {
        matches!(m, MavMessage::MISSION_COUNT(_))
    }) {
        Some(MavMessage::MISSION_COUNT(n)) => assert_eq!(n.count, 3),
        other => panic!("{other:?}"),
    }
    // a count beyond the capacity is refused before any item
    let from = c.log.len();
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: 1000,
        target_system: 1,
        target_component: 1,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    match c.wait(from, Duration::from_secs(3), |m| {
        matches!(m, MavMessage::MISSION_ACK(_))
    }) {
        Some(MavMessage::MISSION_ACK(a)) => {
            assert_eq!(a.mavtype, MavMissionResult::MAV_MISSION_NO_SPACE)
        }
        other => panic!("{other:?}"),
    }
    let report = h.stop();
    assert_eq!(report.send_errors, 0);
}

/// Push statuses from `t0` to `t1` (s) every 0.1 s, the client reading
/// all the while (its socket's buffer would overflow).
fn fly_time(c: &mut Client, v: &mut VehicleEnd, h: &ServerHandle, t: (f64, f64), mode: NavMode) {
    let mut now = t.0;
    while now <= t.1 + 1e-9 {
        let before = h.processed();
        v.downlink
            .push(Downlink::Status(status(now, false, mode)))
            .unwrap();
        settle(h, before + 1);
        c.drain();
        now += 0.1;
    }
    std::thread::sleep(Duration::from_millis(20));
    c.drain();
}

#[test]
fn what_the_field_tools_ask_for_is_answered() {
    let (mut c, mut v, h) = start();
    settle(&h, 1);
    let hb = c
        .wait(0, Duration::from_secs(3), |m| {
            matches!(m, MavMessage::HEARTBEAT(_))
        })
        .expect("heartbeat");
    let MavMessage::HEARTBEAT(hb) = hb else {
        unreachable!()
    };
    // PX4's autopilot and its AUTO.READY for the idle navigator
    assert_eq!(hb.autopilot, MavAutopilot::MAV_AUTOPILOT_PX4);
    assert_eq!(hb.custom_mode, 0x0104_0000);
    assert!(
        hb.base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
    );
    c.heartbeat();
    let r = |c: &mut Client, cmd, p| c.command(cmd, p);
    let mut p = [0.0f32; 7];

    // AUTOPILOT_VERSION: the capabilities the stations choose by
    let from = c.log.len();
    p[0] = AUTOPILOT_VERSION_DATA::ID as f32;
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_REQUEST_MESSAGE, p),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let caps = c
        .collect(from, |m| match m {
            MavMessage::AUTOPILOT_VERSION(a) => Some(a.capabilities),
            _ => None,
        })
        .pop()
        .expect("AUTOPILOT_VERSION");
    assert!(caps.contains(
        MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_INT
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_COMMAND_INT
            | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MAVLINK2
    ));
    // fence uploads are offered (QGC then uploads its geofence)
    assert!(caps.contains(MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_FENCE));
    // no battery monitor: BATTERY_STATUS refused
    p[0] = BATTERY_STATUS_DATA::ID as f32;
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_REQUEST_MESSAGE, p),
        Some(MavResult::MAV_RESULT_UNSUPPORTED)
    );
    // the home, and a stream's interval
    let from = c.log.len();
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_GET_HOME_POSITION, [0.0; 7]),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    p[0] = ATTITUDE_DATA::ID as f32;
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_GET_MESSAGE_INTERVAL, p),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let home = c.collect(from, |m| match m {
        MavMessage::HOME_POSITION(hp) => Some((hp.latitude, hp.altitude)),
        _ => None,
    });
    assert_eq!(home, vec![(570_146_000, 20_000)]);
    let iv = c.collect(from, |m| match m {
        MavMessage::MESSAGE_INTERVAL(i) => Some((u32::from(i.message_id), i.interval_us)),
        _ => None,
    });
    assert_eq!(iv, vec![(ATTITUDE_DATA::ID, 100_000)]);

    // QGroundControl's takeoff: NAV_TAKEOFF disarmed on the ground is
    // accepted and shown as AUTO.TAKEOFF; the arming then flies it
    let mut t = [0.0f32; 7];
    t[6] = f32::NAN;
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_NAV_TAKEOFF, t),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let from = c.log.len();
    fly_time(&mut c, &mut v, &h, (0.1, 1.2), NavMode::Idle);
    let modes = c.collect(from, |m| match m {
        MavMessage::HEARTBEAT(hb) => Some(hb.custom_mode),
        _ => None,
    });
    assert_eq!(modes.last(), Some(&0x0204_0000), "{modes:x?}");
    assert_eq!(
        uplinks(&mut v)
            .into_iter()
            .filter(|x| *x != Uplink::GcsHeartbeat)
            .count(),
        0
    );
    t[0] = 1.0;
    t[6] = 0.0;
    assert_eq!(
        r(&mut c, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, t),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let u: Vec<_> = uplinks(&mut v)
        .into_iter()
        .filter(|x| *x != Uplink::GcsHeartbeat)
        .collect();
    assert_eq!(u, vec![Uplink::Arm(true), Uplink::Takeoff(5.0)]);
    // a SET_MODE (QGC's way) is acknowledged as DO_SET_MODE
    let from = c.log.len();
    c.send(&MavMessage::SET_MODE(SET_MODE_DATA {
        custom_mode: 0x0304_0000,
        target_system: 1,
        base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
    }));
    let ack = c.wait(
        from,
        Duration::from_secs(3),
        |m| matches!(m, MavMessage::COMMAND_ACK(a) if a.command == MavCmd::MAV_CMD_DO_SET_MODE),
    );
    assert!(
        matches!(ack, Some(MavMessage::COMMAND_ACK(a)) if a.result == MavResult::MAV_RESULT_ACCEPTED
            && (a.target_system, a.target_component) == (255, 190))
    );
    assert_eq!(
        uplinks(&mut v)
            .into_iter()
            .filter(|x| *x != Uplink::GcsHeartbeat)
            .collect::<Vec<_>>(),
        vec![Uplink::Hold]
    );
    h.stop();
}

#[test]
fn mission_types_and_the_upload_timeout_follow_the_microservice() {
    let (mut c, mut v, h) = start();
    settle(&h, 1);
    assert!(
        c.wait(0, Duration::from_secs(3), |m| matches!(
            m,
            MavMessage::HEARTBEAT(_)
        ))
        .is_some()
    );
    c.heartbeat();
    let items = vec![
        item(0, MavCmd::MAV_CMD_NAV_TAKEOFF, 0, 0, 10.0),
        item(
            1,
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            570_147_000,
            99_869_000,
            10.0,
        ),
    ];
    assert_eq!(
        mission_ack(&mut c, &items),
        MavMissionResult::MAV_MISSION_ACCEPTED
    );
    let acks = |c: &Client, from| {
        c.collect(from, |m| match m {
            MavMessage::MISSION_ACK(a) => Some((a.mavtype, a.mission_type, a.target_component)),
            _ => None,
        })
    };
    // an upload of type ALL is refused in its type, a fence clear
    // accepted in its; the flight mission stays
    let from = c.log.len();
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: 4,
        target_system: 1,
        target_component: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_ALL,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    c.send(&MavMessage::MISSION_CLEAR_ALL(MISSION_CLEAR_ALL_DATA {
        target_system: 1,
        target_component: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
    }));
    c.send(&MavMessage::MISSION_REQUEST_LIST(
        MISSION_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
        },
    ));
    // the legacy MISSION_REQUEST is answered with a MISSION_ITEM
    c.send(&MavMessage::MISSION_REQUEST(MISSION_REQUEST_DATA {
        seq: 1,
        target_system: 1,
        target_component: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
    }));
    let item1 = c.wait(from, Duration::from_secs(3), |m| {
        matches!(m, MavMessage::MISSION_ITEM(_))
    });
    let Some(MavMessage::MISSION_ITEM(it)) = item1 else {
        panic!("no MISSION_ITEM");
    };
    assert_eq!(it.seq, 1);
    assert!((f64::from(it.x) - 57.0147).abs() < 1e-5, "{}", it.x);
    let fence = MavMissionType::MAV_MISSION_TYPE_FENCE;
    let all = MavMissionType::MAV_MISSION_TYPE_ALL;
    assert_eq!(
        acks(&c, from),
        vec![
            (MavMissionResult::MAV_MISSION_UNSUPPORTED, all, 190),
            (MavMissionResult::MAV_MISSION_ACCEPTED, fence, 190)
        ]
    );
    let counts = c.collect(from, |m| match m {
        MavMessage::MISSION_COUNT(n) => Some(n.count),
        _ => None,
    });
    assert_eq!(counts, vec![2]);

    // an upload whose items never come: requested again every 1.5 s, then
    // cancelled after five repeats
    let from = c.log.len();
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: 2,
        target_system: 1,
        target_component: 1,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    std::thread::sleep(Duration::from_millis(50));
    fly_time(&mut c, &mut v, &h, (0.1, 12.0), NavMode::Idle);
    let requests = c.collect(from, |m| match m {
        MavMessage::MISSION_REQUEST_INT(r) => Some((r.seq, r.target_system, r.target_component)),
        _ => None,
    });
    assert_eq!(requests, vec![(0, 255, 190); 6]);
    assert_eq!(
        acks(&c, from),
        vec![(
            MavMissionResult::MAV_MISSION_OPERATION_CANCELLED,
            MavMissionType::MAV_MISSION_TYPE_MISSION,
            190
        )]
    );
    assert!(
        c.texts()
            .iter()
            .any(|t| t == "mission upload cancelled: no item 0")
    );
    h.stop();
}

/// A status of the land detector's `landed` state, disarmed.
fn ground_status(t_s: f64, landed: helicon_gcs::link::LandedState) -> VehicleStatus {
    let mut s = status(t_s, false, NavMode::Idle);
    s.ground.landed = landed;
    s
}

#[test]
fn arming_off_the_ground_is_refused_with_its_reason() {
    use helicon_gcs::link::LandedState;
    let (mut c, mut v, h) = start();
    // the land detector says in the air (a kill in flight: disarmed, falling)
    v.downlink
        .push(Downlink::Status(ground_status(0.1, LandedState::InAir)))
        .unwrap();
    settle(&h, 2);
    assert!(
        c.wait(0, Duration::from_secs(3), |m| matches!(
            m,
            MavMessage::HEARTBEAT(_)
        ))
        .is_some()
    );
    c.heartbeat();
    let arm = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let from = c.log.len();
    assert_eq!(
        c.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    // the reason, as a warning, to the ground station that asked
    let texts = c.collect(from, |m| match m {
        MavMessage::STATUSTEXT(s) => Some((
            s.severity,
            s.text
                .to_str()
                .unwrap_or("")
                .trim_end_matches('\0')
                .to_string(),
        )),
        _ => None,
    });
    assert!(
        texts.contains(&(
            MavSeverity::MAV_SEVERITY_WARNING,
            "refused: arm off the ground".to_string()
        )),
        "{texts:?}"
    );
    // nothing reached the vehicle
    let u: Vec<_> = uplinks(&mut v)
        .into_iter()
        .filter(|x| *x != Uplink::GcsHeartbeat)
        .collect();
    assert!(u.is_empty(), "{u:?}");
    // on the ground the same command arms
    v.downlink
        .push(Downlink::Status(ground_status(0.2, LandedState::OnGround)))
        .unwrap();
    settle(&h, 3);
    assert_eq!(
        c.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let u: Vec<_> = uplinks(&mut v)
        .into_iter()
        .filter(|x| *x != Uplink::GcsHeartbeat)
        .collect();
    assert_eq!(u, vec![Uplink::Arm(true)]);
    let report = h.stop();
    assert_eq!(report.send_errors, 0);
}

#[test]
fn the_landed_state_is_sent_at_once_on_each_change() {
    use helicon_gcs::link::LandedState;
    let (mut c, mut v, h) = start();
    settle(&h, 1);
    // statuses every 0.1 s for 5 s: on the ground, a take-off of 0.2 s from
    // 2.5 s (shorter than the stream's 1 s period and off its grid), then
    // in the air
    let mut pushed = 1;
    for k in 1..50 {
        let t = f64::from(k) * 0.1;
        let landed = if t < 2.45 {
            LandedState::OnGround
        } else if t < 2.65 {
            LandedState::Takeoff
        } else {
            LandedState::InAir
        };
        v.downlink
            .push(Downlink::Status(ground_status(t, landed)))
            .unwrap();
        pushed += 1;
        settle(&h, pushed);
        c.drain();
    }
    std::thread::sleep(Duration::from_millis(20));
    c.drain();
    let seen = c.collect(0, |m| match m {
        MavMessage::EXTENDED_SYS_STATE(e) => Some(e.landed_state),
        _ => None,
    });
    use MavLandedState::*;
    // undefined at 0 s (the first status has no land detector), the change
    // to on the ground at once (0.1 s) and then 1 Hz (1.1, 2.1 s); the
    // changes at 2.5 and 2.7 s at once; then 1 Hz from the last change (3.7,
    // 4.7 s): exact, the server's grid is on on-board time (at 1 Hz alone
    // the take-off would not be seen)
    assert_eq!(
        seen,
        vec![
            MAV_LANDED_STATE_UNDEFINED,
            MAV_LANDED_STATE_ON_GROUND,
            MAV_LANDED_STATE_ON_GROUND,
            MAV_LANDED_STATE_ON_GROUND,
            MAV_LANDED_STATE_TAKEOFF,
            MAV_LANDED_STATE_IN_AIR,
            MAV_LANDED_STATE_IN_AIR,
            MAV_LANDED_STATE_IN_AIR,
        ]
    );
    let report = h.stop();
    assert_eq!(report.send_errors, 0);
}
