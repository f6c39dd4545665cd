//! `helicon sitl --gcs`: the lock-step SITL runtime path (pseudo-terminal
//! devices, the on-board threads, the control task paced by the IMU) with
//! the ground-station server started by the on-board program on a loopback
//! UDP port, and a MAVLink 2 client (the `mavlink` crate, as a ground
//! station speaks) in the test: heartbeat, arm and takeoff acknowledged, the
//! helicopter climbs to the commanded height — and does so unchanged while
//! a second ground station on another port sends garbage and commands for
//! other vehicles throughout.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

mod common;

use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{
    Connectable, Connection, MavConnection, MavHeader, UdpConfig, UdpMode, write_v2_msg,
};
use helicon_sim::closed_loop::{Termination, prepare};
use helicon_sim::log_csv::read_log_csv;
use helicon_sim::scenario::Scenario;
use helicon_sitl as sitl;
use std::net::UdpSocket;
use std::time::{Duration, Instant};

/// Hover of the physical Bergen Twin, the whole estimation chain; the
/// navigator owns the heading (the scenario's yaw reference is not flown).
fn scenario(duration_s: f64) -> Scenario {
    let text = format!(
        r#"
name = "gcs-sitl"
preset = "physical"
duration_s = {duration_s}

[plant]
max_yaw_error_rad = 1000.0

[sensors]
seed = 1

[controller]
input_max = [0.1, 0.7, 0.7, 0.4]
estimator = true
fusion = true
"#
    );
    Scenario::from_toml_str(&text, "gcs-sitl.toml").unwrap()
}

fn send(conn: &Connection<MavMessage>, msg: &MavMessage) {
    let h = MavHeader {
        system_id: 255,
        component_id: 190,
        sequence: 0,
    };
    conn.send(&h, msg).unwrap();
}

fn gcs_heartbeat(conn: &Connection<MavMessage>) {
    send(
        conn,
        &MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_GCS,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }),
    );
}

/// Send a command (with a ground-station heartbeat, as ground stations do)
/// until it is acknowledged; the result.
fn command(conn: &Connection<MavMessage>, cmd: MavCmd, param7: f32) -> Option<MavResult> {
    let start = Instant::now();
    let mut sent = None::<Instant>;
    while start.elapsed() < Duration::from_secs(10) {
        if sent.is_none_or(|s| s.elapsed() > Duration::from_millis(500)) {
            gcs_heartbeat(conn);
            send(
                conn,
                &MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
                    param1: if cmd == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM {
                        1.0
                    } else {
                        0.0
                    },
                    param7,
                    command: cmd,
                    target_system: 1,
                    target_component: 1,
                    ..COMMAND_LONG_DATA::default()
                }),
            );
            sent = Some(Instant::now());
        }
        if let Ok((_, MavMessage::COMMAND_ACK(a))) = conn.try_recv()
            && a.command == cmd
        {
            return Some(a.result);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    None
}

/// A second ground station's datagrams: noise, a 1-byte datagram, and
/// valid MAVLink frames no vehicle 1 may obey — a forced disarm for system
/// 99, a land for component 50 of system 1, a takeoff to 1 km for system 2.
fn hostile_datagrams() -> Vec<Vec<u8>> {
    let h = MavHeader {
        system_id: 254,
        component_id: 190,
        sequence: 0,
    };
    let cmd = |command, target_system, target_component, param2, param7| {
        let mut out = Vec::new();
        write_v2_msg(
            &mut out,
            h,
            &MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
                param2,
                param7,
                command,
                target_system,
                target_component,
                ..COMMAND_LONG_DATA::default()
            }),
        )
        .unwrap();
        out
    };
    vec![
        vec![0x55],
        vec![0xFD, 9, 0, 0, 1, 255, 190, 0, 0, 0, 1, 2, 3],
        (0..=255u8).collect(),
        cmd(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 99, 1, 21196.0, 0.0),
        cmd(MavCmd::MAV_CMD_NAV_LAND, 1, 50, 0.0, 0.0),
        cmd(MavCmd::MAV_CMD_NAV_TAKEOFF, 2, 1, 0.0, 1000.0),
    ]
}

#[test]
fn sitl_with_the_ground_station_arms_takes_off_and_climbs() {
    climb(false);
}

#[test]
fn sitl_a_second_peers_garbage_and_foreign_commands_leave_the_flight_alone() {
    climb(true);
}

/// Arm, take off to 5 m and hold; with `attack`, a second ground station
/// sends [`hostile_datagrams`] to the vehicle every few milliseconds of the
/// flight, and nothing of the flight may change.
#[allow(clippy::too_many_lines)] // one flight, its checks in order
fn climb(attack: bool) {
    // the ground station listens on a free port; the server sends to it
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = socket.local_addr().unwrap().port();
    let peek = socket.try_clone().unwrap();
    let conn = UdpConfig::from_socket(socket, UdpMode::Udpin)
        .unwrap()
        .connect::<MavMessage>()
        .unwrap();

    let s = scenario(30.0);
    let prepared = prepare(&s).unwrap();
    let mut opts = common::options("gcs");
    opts.keep_frames = false;
    opts.gcs = Some(format!("udpout:127.0.0.1:{port}"));
    opts.out_dir = opts
        .out_dir
        .with_extension(if attack { "attacked" } else { "plain" });
    let out_dir = opts.out_dir.clone();
    let flight = std::thread::spawn(move || sitl::run(&s, &prepared, &opts));
    // the vehicle's address, as a second station learns it from a datagram
    peek.set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    let vehicle = peek.peek_from(&mut [0u8; 300]).unwrap().1;
    let attacker = UdpSocket::bind("127.0.0.1:0").unwrap();
    attacker.set_nonblocking(true).unwrap();
    let hostile = hostile_datagrams();
    let rounds = std::cell::Cell::new(0u32);
    let attack_now = || {
        if attack {
            for d in &hostile {
                attacker.send_to(d, vehicle).unwrap();
            }
            rounds.set(rounds.get() + 1);
        }
    };
    attack_now();

    // the vehicle's heartbeat, disarmed
    let start = Instant::now();
    let hb = loop {
        assert!(start.elapsed() < Duration::from_secs(20), "no heartbeat");
        if let Ok((h, MavMessage::HEARTBEAT(hb))) = conn.try_recv()
            && h.system_id == 1
        {
            break hb;
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    assert!(
        !hb.base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
    );
    // a land while disarmed: refused, and the refusal is in the flight log
    assert_eq!(
        command(&conn, MavCmd::MAV_CMD_NAV_LAND, 0.0),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    // the server refuses to arm before a status with a navigation solution
    // (its first status precedes the first control step's telemetry; on a
    // loaded machine the client can be that early): ask again until then
    let start = Instant::now();
    let armed = loop {
        attack_now();
        let r = command(&conn, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0.0);
        if r != Some(MavResult::MAV_RESULT_DENIED) || start.elapsed() > Duration::from_secs(10) {
            break r;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    assert_eq!(armed, Some(MavResult::MAV_RESULT_ACCEPTED));
    // the server takes a takeoff once the vehicle reports itself armed
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < Duration::from_secs(10), "never armed");
        if let Ok((h, MavMessage::HEARTBEAT(hb))) = conn.try_recv()
            && h.system_id == 1
            && hb
                .base_mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
        {
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(
        // PX4's param7: AMSL (home at helicon_sitl::HOME's 20 m): 5 m up
        command(&conn, MavCmd::MAV_CMD_NAV_TAKEOFF, 25.0),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    // keep the link alive until the flight ends: lock-step SITL runs tens
    // of times faster than real time, so a heartbeat every 5 ms of wall time
    // is a fraction of a simulated second (the link-loss timeout is
    // seconds); the last LOCAL_POSITION_NED the vehicle sent
    let mut last_z = None;
    let mut armed_seen = false;
    let mut disarmed_after_arming = false;
    while !flight.is_finished() {
        gcs_heartbeat(&conn);
        attack_now();
        let t = Instant::now();
        while t.elapsed() < Duration::from_millis(5) {
            match conn.try_recv() {
                Ok((_, MavMessage::LOCAL_POSITION_NED(p))) => last_z = Some(f64::from(p.z)),
                Ok((_, MavMessage::HEARTBEAT(hb))) if hb.mavtype != MavType::MAV_TYPE_GCS => {
                    let armed = hb
                        .base_mode
                        .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                    disarmed_after_arming |= armed_seen && !armed;
                    armed_seen |= armed;
                }
                Ok(_) => {}
                Err(_) => std::thread::sleep(Duration::from_millis(1)),
            }
        }
    }
    let r = flight.join().unwrap().unwrap();
    assert_eq!(
        r.summary.termination,
        Termination::Completed,
        "{:?}",
        r.summary.reason
    );
    assert!(armed_seen, "no armed heartbeat");
    assert!(!disarmed_after_arming, "disarmed in flight");
    // the second station's commands were for others: not one answered
    let mut acks = 0;
    let mut b = [0u8; 512];
    while let Ok(n) = attacker.recv(&mut b) {
        let mut r = helicon_gcs::mavlink::MavlinkReader::new(&b[..n]);
        if let Ok((_, MavMessage::COMMAND_ACK(_))) = r.read_any_message::<MavMessage>() {
            acks += 1;
        }
    }
    assert_eq!(acks, 0, "a foreign command was answered");
    // the attack lasted the flight (a round every 5 ms of wall time)
    assert!(!attack || rounds.get() > 50, "{} rounds", rounds.get());
    assert_eq!(r.onboard.final_mode, "auto");
    // the truth (log.csv): on the ground until the takeoff, then up at the
    // navigator's climb speed (1 m/s by default; the crossing of 1 m and
    // 4 m within 20 %: the LQI's lag shapes the ramp's ends, not its middle)
    let log = read_log_csv(&r.log_csv).unwrap();
    let z = log.column("z").unwrap();
    let t = log.column("t_s").unwrap();
    assert!(z[0].abs() < 0.1, "z0 = {}", z[0]);
    let crossing = |h: f64| z.iter().position(|&z| -z > h).map(|i| t[i]).unwrap();
    let climb_m_s = 3.0 / (crossing(4.0) - crossing(1.0));
    assert!((climb_m_s - 1.0).abs() < 0.2, "climb {climb_m_s:.2} m/s");
    // the ground station's view (the navigation's estimate the navigator
    // holds through velocity references the LQI tracks): the commanded 5 m
    // within 0.5 m (0.2 m measured)
    let z_gcs = last_z.expect("no LOCAL_POSITION_NED");
    assert!((z_gcs + 5.0).abs() < 0.5, "reported height {:.2} m", -z_gcs);
    // the true height at the end: 5 m within 1 m, the GPS-aided vertical
    // navigation's error (the receiver's 3 m vertical σ at 5 Hz, filtered;
    // about 0.5 m measured here)
    let z_end = *z.last().unwrap();
    assert!((z_end + 5.0).abs() < 1.0, "true height {:.2} m", -z_end);
    eprintln!(
        "attack {attack} ({} rounds): climb {climb_m_s:.3} m/s, reported height {:.3} m, true height {:.3} m",
        rounds.get(),
        -z_gcs,
        -z_end
    );
    // the server's own refusal reached the flight log, as PX4 logs a
    // status text: a logging message at its severity
    let mut ulog = helicon_ulog::reader::UlogReader::open(&r.ulog).unwrap();
    let mut refusals = 0;
    while let Some(m) = ulog.next_message().unwrap() {
        if let helicon_ulog::reader::Message::Logging { level, text, .. } = m
            && text == "gcs: refused: not armed"
        {
            assert_eq!(level, Some(helicon_ulog::LogLevel::Warning));
            refusals += 1;
        }
    }
    assert!(refusals >= 1, "the refusal is not in the flight log");
    let _ = std::fs::remove_dir_all(out_dir);
}
