//! The ground-station server and the navigator flown in lock-step SITL with
//! a MAVLink client in the test: the simulation pauses while the client
//! waits for an answer, and the server streams on on-board time, so every
//! figure here is per simulated second.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::client::{Client, item};
use common::harness::{Harness, scenario};
use helicon_devices::{Geodetic, LocalNed};
use helicon_gcs::mavlink::MessageData;
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::navigator::NavigatorConfig;
use helicon_gcs::server::ServerConfig;
use helicon_sim::closed_loop::prepare;
use nalgebra::Vector3;
use std::time::Duration;

const HOME: (f64, f64, f64) = (57.0146, 9.9869, 20.0);
const T: Duration = Duration::from_secs(3);

fn home() -> Geodetic {
    Geodetic::new(HOME.0, HOME.1, HOME.2).unwrap()
}

fn server_config(client: &Client, key: Option<[u8; 32]>) -> ServerConfig {
    ServerConfig {
        address: client.server_address(),
        system_id: 1,
        home: home(),
        navigator: NavigatorConfig::default(),
        signing_key: key,
        rates_hz: helicon_gcs::server::default_rates_hz(),
    }
}

fn param_name(id: &helicon_gcs::mavlink::types::CharArray<16>) -> String {
    id.to_str().unwrap_or("").trim_end_matches('\0').to_string()
}

/// Fly `seconds` in batches of 50 ms, the client reading and sending its
/// heartbeat every 0.5 s (when `heartbeats`).
fn fly(h: &mut Harness, c: &mut Client, seconds: f64, heartbeats: bool) {
    let batches = (seconds / 0.05).round() as usize;
    for _ in 0..batches {
        if heartbeats && h.k % 200 == 0 {
            c.heartbeat();
        }
        assert!(h.run(0.05), "flight ended: {:?}", h.ended);
        c.drain();
    }
}

fn rate_hz(times_ms: &[u32]) -> f64 {
    let n = times_ms.len();
    assert!(n > 10, "{n} messages");
    (n - 1) as f64 / (f64::from(times_ms[n - 1] - times_ms[0]) * 1e-3)
}

fn upload(c: &mut Client, items: &[MISSION_ITEM_INT_DATA]) -> MavMissionResult {
    upload_of(c, items, MavMissionType::MAV_MISSION_TYPE_MISSION)
}

fn upload_of(
    c: &mut Client,
    items: &[MISSION_ITEM_INT_DATA],
    mission_type: MavMissionType,
) -> MavMissionResult {
    let mut cursor = c.log.len();
    c.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: items.len() as u16,
        target_system: 1,
        target_component: 1,
        mission_type,
        ..MISSION_COUNT_DATA::DEFAULT
    }));
    loop {
        let (i, m) = c
            .wait_index(cursor, T, |m| {
                matches!(
                    m,
                    MavMessage::MISSION_REQUEST_INT(_) | MavMessage::MISSION_ACK(_)
                )
            })
            .expect("mission request or ack");
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

fn download(c: &mut Client) -> Vec<MISSION_ITEM_INT_DATA> {
    download_of(c, MavMissionType::MAV_MISSION_TYPE_MISSION)
}

fn download_of(c: &mut Client, mission_type: MavMissionType) -> Vec<MISSION_ITEM_INT_DATA> {
    let from = c.log.len();
    c.send(&MavMessage::MISSION_REQUEST_LIST(
        MISSION_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
            mission_type,
        },
    ));
    let Some(MavMessage::MISSION_COUNT(n)) =
        c.wait(from, T, |m| matches!(m, MavMessage::MISSION_COUNT(_)))
    else {
        panic!("no MISSION_COUNT");
    };
    (0..n.count)
        .map(|seq| {
            let from = c.log.len();
            c.send(&MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                seq,
                target_system: 1,
                target_component: 1,
                mission_type,
            }));
            match c.wait(
                from,
                T,
                |m| matches!(m, MavMessage::MISSION_ITEM_INT(i) if i.seq == seq),
            ) {
                Some(MavMessage::MISSION_ITEM_INT(i)) => i,
                _ => panic!("item {seq} not sent"),
            }
        })
        .collect()
}

#[test]
#[allow(clippy::too_many_lines)] // one flight, its checks in order
fn heartbeat_params_mission_flown_and_landed_rates_as_requested() {
    let s = scenario(200.0);
    let prepared = prepare(&s).unwrap();
    let mut c = Client::new(None);
    let mut h = Harness::new(
        &s,
        &prepared,
        server_config(&c, None),
        NavigatorConfig::default(),
        4,
    );
    fly(&mut h, &mut c, 1.5, true);

    // heartbeat: a helicopter, the autopilot component, disarmed
    let hb = c.collect(0, |m| match m {
        MavMessage::HEARTBEAT(x) => Some(x.clone()),
        _ => None,
    });
    assert!(
        !hb.is_empty(),
        "no heartbeat; log {}; server {:?}",
        c.log.len(),
        h.stop()
    );
    assert_eq!(hb[0].mavtype, MavType::MAV_TYPE_HELICOPTER);
    assert!(
        !hb[0]
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
    );
    let (hdr, _) = c
        .log
        .iter()
        .find(|(_, m)| matches!(m, MavMessage::HEARTBEAT(_)))
        .unwrap();
    assert_eq!(hdr.component_id, MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8);
    assert_eq!(hdr.system_id, 1);

    // the parameter list, complete
    let from = c.log.len();
    c.send(&MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA {
        target_system: 1,
        target_component: 1,
    }));
    let _ = c.wait(
        from,
        T,
        |m| matches!(m, MavMessage::PARAM_VALUE(p) if p.param_index == 16),
    );
    let params = c.collect(from, |m| match m {
        MavMessage::PARAM_VALUE(p) => Some((
            p.param_index,
            param_name(&p.param_id),
            p.param_value,
            p.param_count,
        )),
        _ => None,
    });
    assert_eq!(params.len(), 17);
    for (i, (idx, name, _, count)) in params.iter().enumerate() {
        assert_eq!(usize::from(*idx), i);
        assert_eq!(*count, 17);
        assert_eq!(name, helicon_gcs::params::PARAMS[i].0);
    }
    // a SET answered with the new value; a refused one with the old value
    let set = |c: &mut Client, name: &str, v: f32| {
        let from = c.log.len();
        c.send(&MavMessage::PARAM_SET(PARAM_SET_DATA {
            param_value: v,
            target_system: 1,
            target_component: 1,
            param_id: name.into(),
            param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
        }));
        match c.wait(
            from,
            T,
            |m| matches!(m, MavMessage::PARAM_VALUE(p) if param_name(&p.param_id) == name),
        ) {
            Some(MavMessage::PARAM_VALUE(p)) => p.param_value,
            _ => panic!("{name}: no PARAM_VALUE"),
        }
    };
    assert_eq!(set(&mut c, "NAV_CRUISE_SPD", 2.5), 2.5);
    assert_eq!(set(&mut c, "NAV_MAX_ACC", 100.0), 1.0);
    assert_eq!(set(&mut c, "FS_LINK_ACT", 1.5), 1.0);
    assert!(
        c.texts()
            .iter()
            .any(|t| t.starts_with("refused NAV_MAX_ACC")),
        "{:?}",
        c.texts()
    );

    // message intervals: ATTITUDE at 50 Hz, LOCAL_POSITION_NED at 25 Hz
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            [ATTITUDE_DATA::ID as f32, 20_000.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            [
                LOCAL_POSITION_NED_DATA::ID as f32,
                40_000.0,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0
            ]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let rates_from = c.log.len();

    // the mission: takeoff to 10 m, 3 m/s, four waypoints of a 20 m square, land
    let local = LocalNed::new(home());
    let ll = |n: f64, e: f64| {
        let g = local.to_geodetic(&Vector3::new(n, e, 0.0));
        (
            (g.latitude_deg * 1e7).round() as i32,
            (g.longitude_deg * 1e7).round() as i32,
        )
    };
    let corners = [(20.0, 0.0), (20.0, 20.0), (0.0, 20.0), (0.0, 0.0)];
    let mut items = vec![item(0, MavCmd::MAV_CMD_NAV_TAKEOFF, 0, 0, 10.0)];
    let mut speed = item(1, MavCmd::MAV_CMD_DO_CHANGE_SPEED, 0, 0, 0.0);
    speed.param2 = 3.0;
    items.push(speed);
    for (i, (n, e)) in corners.iter().enumerate() {
        let (la, lo) = ll(*n, *e);
        items.push(item(
            2 + i as u16,
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            la,
            lo,
            10.0,
        ));
    }
    items.push(item(6, MavCmd::MAV_CMD_NAV_LAND, 0, 0, 0.0));
    assert_eq!(
        upload(&mut c, &items),
        MavMissionResult::MAV_MISSION_ACCEPTED
    );
    let back = download(&mut c);
    assert_eq!(back.len(), items.len());
    for (a, b) in back.iter().zip(&items) {
        assert_eq!(
            (a.seq, a.command, a.x, a.y, a.z.to_bits()),
            (b.seq, b.command, b.x, b.y, b.z.to_bits())
        );
    }

    // a start while disarmed on the ground is PX4's (and QGC's start
    // mission): accepted, flown at the arming; arm; start
    assert_eq!(
        c.command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly(&mut h, &mut c, 0.1, true);
    assert!(h.vehicle().armed());
    assert_eq!(
        c.command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );

    // fly until landed (disarmed), noting the true position at each REACHED
    let mut reached: Vec<(u16, Vector3<f64>)> = Vec::new();
    let mut seen = c.log.len();
    let mut max_h_speed: f64 = 0.0;
    while h.t_s < 190.0 {
        fly(&mut h, &mut c, 0.05, true);
        for (_, m) in &c.log[seen..] {
            match m {
                MavMessage::MISSION_ITEM_REACHED(r) => reached.push((r.seq, h.truth_ned_m)),
                MavMessage::LOCAL_POSITION_NED(p) => {
                    max_h_speed = max_h_speed.max(f64::from(p.vx).hypot(f64::from(p.vy)));
                }
                _ => {}
            }
        }
        seen = c.log.len();
        if !h.vehicle().armed() {
            break;
        }
    }
    assert!(
        !h.vehicle().armed(),
        "not landed by {} s; reached {reached:?}",
        h.t_s
    );
    let seqs: Vec<u16> = reached.iter().map(|r| r.0).collect();
    assert_eq!(seqs, vec![0, 2, 3, 4, 5, 6], "{reached:?}");
    for (k, (n, e)) in corners.iter().enumerate() {
        let p = reached[k + 1].1;
        let miss = (p - Vector3::new(*n, *e, -10.0)).norm();
        // reached within 1 m of the estimate; the estimate's own error (GPS
        // noise) and the 50 ms batch add up to 1 m more
        assert!(
            miss < 2.0,
            "waypoint {}: true position {p}, {miss:.2} m off",
            k + 2
        );
        println!("waypoint {}: {miss:.2} m from the true position", k + 2);
    }
    assert!(h.truth_ned_m.z > -0.6, "landed at d = {}", h.truth_ned_m.z);
    assert!(
        h.truth_ned_m.xy().norm() < 2.0,
        "landed at {}",
        h.truth_ned_m
    );
    assert!(
        max_h_speed < 3.6,
        "estimated speed {max_h_speed} beyond the 3 m/s leg"
    );
    println!(
        "landed at t = {:.1} s, {} m from home, top speed {max_h_speed:.2} m/s",
        h.t_s,
        h.truth_ned_m.xy().norm()
    );
    let texts = c.texts();
    for want in ["armed", "mode MISSION", "mode LAND", "landed", "disarmed"] {
        assert!(
            texts.iter().any(|t| t == want),
            "no STATUSTEXT {want}: {texts:?}"
        );
    }
    // MISSION_CURRENT is streamed (1 Hz) and sent on each new item: the
    // items in order, none skipped
    let mut currents = c.collect(0, |m| match m {
        MavMessage::MISSION_CURRENT(x) => Some(x.seq),
        _ => None,
    });
    currents.dedup();
    assert_eq!(currents, vec![0, 2, 3, 4, 5, 6]);

    // the rates, per simulated second, against those asked for
    let times = |id| {
        c.collect(rates_from, move |m| match (m, id) {
            (MavMessage::ATTITUDE(a), 0) => Some(a.time_boot_ms),
            (MavMessage::LOCAL_POSITION_NED(a), 1) => Some(a.time_boot_ms),
            (MavMessage::GLOBAL_POSITION_INT(a), 2) => Some(a.time_boot_ms),
            _ => None,
        })
    };
    let (att, lpn, gpi) = (rate_hz(&times(0)), rate_hz(&times(1)), rate_hz(&times(2)));
    println!(
        "rates: ATTITUDE {att:.3} Hz (50 asked), LOCAL_POSITION_NED {lpn:.3} Hz (25), GLOBAL_POSITION_INT {gpi:.3} Hz (5 default)"
    );
    // on-board time: exact up to the 10 ms status grid over the flight
    assert!((att - 50.0).abs() < 0.05, "{att}");
    assert!((lpn - 25.0).abs() < 0.05, "{lpn}");
    assert!((gpi - 5.0).abs() < 0.05, "{gpi}");
    let report = h.stop();
    assert_eq!(report.send_errors, 0);
    println!(
        "server: {report:?}; control step max {:.1} µs, mean {:.1} µs",
        h.max_step_s * 1e6,
        h.sum_step_s / h.k as f64 * 1e6
    );
}

fn position_target_velocity(vn: f32, ve: f32) -> MavMessage {
    MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
        vx: vn,
        vy: ve,
        type_mask: PositionTargetTypemask::POSITION_TARGET_TYPEMASK_X_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Y_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Z_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AX_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AY_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_AZ_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE
            | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE,
        target_system: 1,
        target_component: 1,
        coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
        ..SET_POSITION_TARGET_LOCAL_NED_DATA::DEFAULT
    })
}

/// Arm, take off to 5 m above home and fly 10 s (the climb and the hold).
fn arm_and_take_off_to_5_m(h: &mut Harness, c: &mut Client) {
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly(h, c, 0.1, true);
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_NAV_TAKEOFF,
            // PX4's param7: AMSL, home at 20 m: 5 m above it
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 25.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly(h, c, 10.0, true);
}

#[test]
fn guided_velocity_followed_then_link_loss_returns_and_lands() {
    let s = scenario(120.0);
    let prepared = prepare(&s).unwrap();
    let mut c = Client::new(None);
    let nav = NavigatorConfig {
        link_loss_timeout_s: 3.0,
        link_loss_hold_s: 2.0,
        ..NavigatorConfig::default()
    };
    let mut cfg = server_config(&c, None);
    cfg.navigator = nav;
    let mut h = Harness::new(&s, &prepared, cfg, nav, 4);
    fly(&mut h, &mut c, 0.5, true);
    arm_and_take_off_to_5_m(&mut h, &mut c);
    assert!(
        (h.truth_ned_m.z + 5.0).abs() < 0.5,
        "takeoff to 5 m: d = {}",
        h.truth_ned_m.z
    );

    // guided: 1.5 m/s north, 0.5 m/s west, for 10 s, targets at 5 Hz; the
    // true mean velocity over the last 6 s (the first seconds ramp at 1 m/s²)
    let mut p4 = h.truth_ned_m;
    let mut t4 = h.t_s;
    let mut from4 = c.log.len();
    for i in 0..50 {
        if i == 20 {
            (p4, t4, from4) = (h.truth_ned_m, h.t_s, c.log.len());
        }
        c.send(&position_target_velocity(1.5, -0.5));
        fly(&mut h, &mut c, 0.2, true);
    }
    let v = (h.truth_ned_m - p4) / (h.t_s - t4);
    let est = c.collect(from4, |m| match m {
        MavMessage::LOCAL_POSITION_NED(p) => Some(Vector3::new(
            f64::from(p.vx),
            f64::from(p.vy),
            f64::from(p.vz),
        )),
        _ => None,
    });
    let est_mean = est.iter().sum::<Vector3<f64>>() / est.len() as f64;
    println!(
        "guided: mean estimated velocity {:.3} N, {:.3} E, {:.3} D",
        est_mean.x, est_mean.y, est_mean.z
    );
    println!(
        "guided: mean true velocity {:.3} N, {:.3} E, {:.3} D (1.5, -0.5, 0 asked)",
        v.x, v.y, v.z
    );
    // the law tracks the estimate within 0.05 m/s; the truth differs by the
    // navigation's own velocity error (GPS/IMU fusion, ≈ 0.2 m/s here)
    let asked = Vector3::new(1.5, -0.5, 0.0);
    assert!((est_mean - asked).amax() < 0.05, "{est_mean}");
    assert!((v - asked).amax() < 0.25, "{v}");

    // link loss: no more heartbeats (nor targets) → hold, return, land near home
    let from = c.log.len();
    let t_loss = h.t_s;
    while h.vehicle().armed() && h.t_s < t_loss + 90.0 {
        fly(&mut h, &mut c, 0.5, false);
    }
    let texts = c.collect(from, |m| match m {
        MavMessage::STATUSTEXT(s) => Some(
            s.text
                .to_str()
                .unwrap_or("")
                .trim_end_matches('\0')
                .to_string(),
        ),
        _ => None,
    });
    println!("{texts:?}");
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with("failsafe: ground-station link lost")),
        "{texts:?}"
    );
    for want in ["mode HOLD", "mode RETURN", "mode LAND", "landed"] {
        assert!(texts.iter().any(|t| t == want), "no {want}: {texts:?}");
    }
    assert!(!h.vehicle().armed());
    assert!(
        h.truth_ned_m.xy().norm() < 2.0,
        "landed at {}",
        h.truth_ned_m
    );
    assert!(h.truth_ned_m.z > -0.6);
}

#[test]
fn commands_signed_with_a_wrong_key_or_unsigned_are_refused() {
    let s = scenario(10.0);
    let prepared = prepare(&s).unwrap();
    let key = [7u8; 32];
    // the server listens (udpin); every station that speaks is a peer
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut cfg = server_config(&Client::new(None), Some(key));
    cfg.address = format!("udpin:127.0.0.1:{port}");
    let mut good = Client::to_port(port, Some(key));
    let mut h = Harness::new(&s, &prepared, cfg, NavigatorConfig::default(), 4);
    fly(&mut h, &mut good, 0.5, true);
    assert!(
        good.log
            .iter()
            .any(|(_, m)| matches!(m, MavMessage::HEARTBEAT(_)))
    );
    for (who, key) in [("wrong key", Some([8u8; 32])), ("unsigned", None)] {
        let mut client = Client::to_port(port, key);
        let r = client.command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        );
        assert_eq!(r, Some(MavResult::MAV_RESULT_DENIED), "{who}");
        assert!(
            client
                .texts()
                .iter()
                .any(|t| t.starts_with("refused: command not signed")),
            "{who}: {:?}",
            client.texts()
        );
        fly(&mut h, &mut good, 0.1, true);
        assert!(!h.vehicle().armed(), "{who} armed the vehicle");
    }
    let r = good.command(
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    assert_eq!(r, Some(MavResult::MAV_RESULT_ACCEPTED));
    fly(&mut h, &mut good, 0.1, true);
    assert!(h.vehicle().armed());
    let report = h.stop();
    assert_eq!(report.refused_unsigned, 2);
}

#[test]
fn a_guided_flight_out_of_the_fence_returns_and_lands() {
    let s = scenario(90.0);
    let prepared = prepare(&s).unwrap();
    let mut c = Client::new(None);
    let mut h = Harness::new(
        &s,
        &prepared,
        server_config(&c, None),
        NavigatorConfig::default(),
        4,
    );
    fly(&mut h, &mut c, 0.5, true);
    // a 12 m fence, set over MAVLink (the parameter reaches the navigator)
    let from = c.log.len();
    c.send(&MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: 12.0,
        target_system: 1,
        target_component: 1,
        param_id: "GF_MAX_HOR_DIST".into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    }));
    assert!(
        c.wait(
            from,
            T,
            |m| matches!(m, MavMessage::PARAM_VALUE(p) if p.param_value == 12.0)
        )
        .is_some()
    );
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly(&mut h, &mut c, 0.1, true);
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_NAV_TAKEOFF,
            // PX4's param7: AMSL, home at 20 m: 5 m above it
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 25.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly(&mut h, &mut c, 8.0, true);
    // guided: 1.5 m/s north until the fence acts
    let from = c.log.len();
    let mut farthest: f64 = 0.0;
    let mut breach_at = None;
    for _ in 0..300 {
        if breach_at.is_none() {
            c.send(&position_target_velocity(1.5, 0.0));
        }
        fly(&mut h, &mut c, 0.2, true);
        farthest = farthest.max(h.truth_ned_m.xy().norm());
        if breach_at.is_none()
            && c.texts()
                .iter()
                .any(|t| t == "fence breached (GF_MAX_HOR_DIST): return")
        {
            breach_at = Some(h.truth_ned_m);
            // a station still streaming does not fly it out again
            c.send(&position_target_velocity(1.5, 0.0));
        }
        if !h.vehicle().armed() {
            break;
        }
    }
    let texts = c.collect(from, |m| match m {
        MavMessage::STATUSTEXT(s) => Some(
            s.text
                .to_str()
                .unwrap_or("")
                .trim_end_matches('\0')
                .to_string(),
        ),
        _ => None,
    });
    let breach_at = breach_at.unwrap_or_else(|| panic!("no breach: {texts:?}"));
    println!(
        "fence 12 m: breach seen at {:.2} m (truth), farthest {farthest:.2} m; {texts:?}",
        breach_at.xy().norm()
    );
    for want in [
        "mode RETURN",
        "guided refused: mode RETURN (set HOLD first)",
        "mode LAND",
        "landed",
    ] {
        assert!(texts.iter().any(|t| t == want), "no {want}: {texts:?}");
    }
    let returned = texts.iter().position(|t| t == "mode RETURN").unwrap();
    assert!(
        !texts[returned..].iter().any(|t| t == "mode GUIDED"),
        "{texts:?}"
    );
    assert!(!h.vehicle().armed());
    // the estimate crossed 12 m; the truth differs by the navigation's
    // error; the stop from 1.5 m/s at 1 m/s² is 1.1 m
    assert!(farthest < 15.0, "{farthest}");
    assert!(
        h.truth_ned_m.xy().norm() < 2.0,
        "landed at {}",
        h.truth_ned_m
    );
}

#[test]
fn with_signing_unsigned_heartbeats_do_not_hold_off_the_link_loss_failsafe() {
    let s = scenario(60.0);
    let prepared = prepare(&s).unwrap();
    let key = [9u8; 32];
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let nav = NavigatorConfig {
        link_loss_timeout_s: 2.0,
        link_loss_hold_s: 1.0,
        ..NavigatorConfig::default()
    };
    let mut cfg = server_config(&Client::new(None), Some(key));
    cfg.address = format!("udpin:127.0.0.1:{port}");
    cfg.navigator = nav;
    let mut good = Client::to_port(port, Some(key));
    let mut h = Harness::new(&s, &prepared, cfg, nav, 4);
    fly(&mut h, &mut good, 0.5, true);
    assert_eq!(
        good.command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly(&mut h, &mut good, 0.1, true);
    assert_eq!(
        good.command(
            MavCmd::MAV_CMD_NAV_TAKEOFF,
            // PX4's param7: AMSL, home at 20 m: 5 m above it
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 25.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly(&mut h, &mut good, 8.0, true);
    // the signed station falls silent; an unsigned one sends a heartbeat
    // every 50 ms of flight, claiming to be a ground station
    let mut spoof = Client::to_port(port, None);
    let from = good.log.len();
    let t_silent = h.t_s;
    let mut lost_at = None;
    while h.vehicle().armed() && h.t_s < t_silent + 40.0 {
        spoof.heartbeat();
        assert!(h.run(0.05), "flight ended: {:?}", h.ended);
        good.drain();
        if lost_at.is_none()
            && good
                .texts()
                .iter()
                .any(|t| t.starts_with("failsafe: ground-station link lost"))
        {
            lost_at = Some(h.t_s);
        }
    }
    let lost_at = lost_at.unwrap_or_else(|| {
        panic!(
            "no link loss: {:?}, armed {}, lost {}, mode {:?}, t {:.1}",
            good.texts(),
            h.vehicle().armed(),
            h.vehicle().navigator().link_lost(),
            h.vehicle().navigator().mode(),
            h.t_s - t_silent
        )
    });
    println!(
        "link loss {:.2} s after the signed station fell silent, unsigned heartbeats throughout",
        lost_at - t_silent
    );
    // the timeout after the last signed heartbeat (sent every 0.5 s)
    assert!(
        lost_at - t_silent > 1.4 && lost_at - t_silent < 2.7,
        "link loss {:.2} s after the silence",
        lost_at - t_silent
    );
    let texts = good.collect(from, |m| match m {
        MavMessage::STATUSTEXT(s) => Some(
            s.text
                .to_str()
                .unwrap_or("")
                .trim_end_matches('\0')
                .to_string(),
        ),
        _ => None,
    });
    // (already holding after the takeoff: the failsafe's hold is no change)
    for want in ["mode RETURN", "mode LAND", "landed"] {
        assert!(texts.iter().any(|t| t == want), "no {want}: {texts:?}");
    }
    assert!(!h.vehicle().armed());
    spoof.drain();
    assert!(
        spoof
            .log
            .iter()
            .all(|(_, m)| matches!(m, MavMessage::STATUSTEXT(_))),
        "the unsigned station was sent telemetry"
    );
    let report = h.stop();
    assert!(report.refused_unsigned > 100, "{report:?}");
}

/// A hostile station on the server's port while the vehicle flies in
/// lock-step: a 1-byte datagram, 300 bytes of junk, an arm command for
/// another vehicle (system 99) and a takeoff to 3e38 m. The junk is counted
/// and dropped, the command for another vehicle gets no answer and is not
/// obeyed, the takeoff is refused with the protocol's result; the station
/// that flies keeps its telemetry at its rate and arms when it asks.
#[test]
fn a_hostile_station_neither_steals_the_link_nor_commands_the_vehicle() {
    let s = scenario(10.0);
    let prepared = prepare(&s).unwrap();
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut cfg = server_config(&Client::new(None), None);
    cfg.address = format!("udpin:127.0.0.1:{port}");
    let mut good = Client::to_port(port, None);
    let mut h = Harness::new(&s, &prepared, cfg, NavigatorConfig::default(), 4);
    fly(&mut h, &mut good, 2.0, true);
    let attitude_ms = |c: &Client, from: usize| {
        c.collect(from, |m| match m {
            MavMessage::ATTITUDE(a) => Some(a.time_boot_ms),
            _ => None,
        })
    };
    let before = rate_hz(&attitude_ms(&good, 0));
    let from = good.log.len();

    let raw = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let server = format!("127.0.0.1:{port}");
    raw.send_to(&[0xFD], &server).unwrap();
    raw.send_to(&[0x55; 300], &server).unwrap();
    let mut evil = Client::to_port(port, None);
    evil.send(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: 1.0,
        param2: 0.0,
        param3: 0.0,
        param4: 0.0,
        param5: 0.0,
        param6: 0.0,
        param7: 0.0,
        command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        target_system: 99,
        target_component: 1,
        confirmation: 0,
    }));
    fly(&mut h, &mut good, 0.5, true);
    evil.drain();
    assert!(
        !evil
            .log
            .iter()
            .any(|(_, m)| matches!(m, MavMessage::COMMAND_ACK(_))),
        "a command for system 99 was answered"
    );
    assert!(
        !h.vehicle().armed(),
        "armed by a command for another vehicle"
    );
    let r = evil.command(
        MavCmd::MAV_CMD_NAV_TAKEOFF,
        [0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 3e38],
    );
    assert!(
        r.is_some() && r != Some(MavResult::MAV_RESULT_ACCEPTED),
        "a takeoff to 3e38 m: {r:?}"
    );
    fly(&mut h, &mut good, 2.0, true);
    assert!(!h.vehicle().armed());
    // the flying station's telemetry went on at its rate
    let after = rate_hz(&attitude_ms(&good, from));
    eprintln!(
        "ATTITUDE to the flying station: {before:.2} Hz before the attack, {after:.2} Hz after"
    );
    assert!((after - before).abs() < 0.05 * before, "{before} {after}");
    let r = good.command(
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    assert_eq!(r, Some(MavResult::MAV_RESULT_ACCEPTED));
    fly(&mut h, &mut good, 0.1, true);
    assert!(h.vehicle().armed());
    let report = h.stop();
    eprintln!(
        "server: {} garbage datagrams, {} for another vehicle",
        report.garbage_datagrams, report.other_target
    );
    assert_eq!(report.garbage_datagrams, 2);
    assert_eq!(report.other_target, 1);
}

/// Rally points in lock-step SITL: uploaded and downloaded as the mission
/// protocol's `MAV_MISSION_TYPE_RALLY`; a return from 30 m north flies to
/// the rally point 45 m north (15 m away, home 30 m) and lands there, as
/// PX4's default multicopter return picks the nearest of home and the
/// rally points.
#[test]
fn a_return_lands_at_the_nearest_rally_point() {
    let s = scenario(120.0);
    let prepared = prepare(&s).unwrap();
    let mut c = Client::new(None);
    let cfg = server_config(&c, None);
    let mut h = Harness::new(&s, &prepared, cfg, NavigatorConfig::default(), 4);
    fly(&mut h, &mut c, 0.5, true);
    let home_ned = LocalNed::new(home());
    let g = home_ned.to_geodetic(&Vector3::new(45.0, 0.0, 0.0));
    let rally = MISSION_ITEM_INT_DATA {
        seq: 0,
        frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
        command: MavCmd::MAV_CMD_NAV_RALLY_POINT,
        x: (g.latitude_deg * 1e7).round() as i32,
        y: (g.longitude_deg * 1e7).round() as i32,
        z: 10.0,
        target_system: 1,
        target_component: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_RALLY,
        ..MISSION_ITEM_INT_DATA::DEFAULT
    };
    assert_eq!(
        upload_of(
            &mut c,
            std::slice::from_ref(&rally),
            MavMissionType::MAV_MISSION_TYPE_RALLY
        ),
        MavMissionResult::MAV_MISSION_ACCEPTED
    );
    let back = download_of(&mut c, MavMissionType::MAV_MISSION_TYPE_RALLY);
    assert_eq!(back.len(), 1);
    assert_eq!(
        (
            back[0].x,
            back[0].y,
            back[0].z,
            back[0].command,
            back[0].mission_type
        ),
        (rally.x, rally.y, rally.z, rally.command, rally.mission_type)
    );
    // the flight mission is another type: still empty
    assert!(download(&mut c).is_empty());
    arm_and_take_off_to_5_m(&mut h, &mut c);
    // guided north at 2 m/s until 30 m north
    while h.truth_ned_m.x < 30.0 && h.t_s < 60.0 {
        c.send(&position_target_velocity(2.0, 0.0));
        fly(&mut h, &mut c, 0.2, true);
    }
    let from = h.truth_ned_m;
    assert_eq!(
        c.command(
            MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH,
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let t0 = h.t_s;
    while h.vehicle().armed() && h.t_s < t0 + 60.0 {
        fly(&mut h, &mut c, 0.5, true);
    }
    let landed = h.truth_ned_m;
    println!(
        "return from ({:.1}, {:.1}) m: landed at ({:.2}, {:.2}) m NE, the rally point at (45, 0)",
        from.x, from.y, landed.x, landed.y
    );
    assert!(!h.vehicle().armed(), "not landed within 60 s");
    assert!(
        (landed.xy() - nalgebra::Vector2::new(45.0, 0.0)).norm() < 2.0,
        "landed at {landed}"
    );
}
