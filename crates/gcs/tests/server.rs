//! The server alone, the vehicle's ring ends in the test's hands: what the
//! ground station's commands put on the uplink, and every refusal answered
//! (never applied, never a dead server).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

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

fn uplinks(v: &mut VehicleEnd) -> Vec<Uplink> {
    std::thread::sleep(Duration::from_millis(20));
    let mut out = Vec::new();
    while let Ok(u) = v.uplink.pop() {
        out.push(u);
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
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 7.5]
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
    // a mode while armed (hold); an unknown one refused
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
    assert_eq!(
        r(
            &mut c,
            MavCmd::MAV_CMD_DO_SET_MODE,
            [1.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0]
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
