//! `helicon gcs` against the ground-station server (fed a vehicle status by
//! the test): it hears the helicopter and prints its state; a bad address
//! or duration is an error naming it. And flying: `helicon sitl --gcs`
//! (lock-step) flown by a `helicon gcs` script piped to its stdin — arm,
//! takeoff, mission upload and download, parameters, land; a refused
//! command and a bad mission file fail the script; `tcp:` against a
//! listener in the test; vehicles kept apart by system id.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::Reference;
use helicon_core::state::Input;
use helicon_devices::Geodetic;
use helicon_gcs::link::{Downlink, FlightMode, VehicleEvent, VehicleStatus, channel};
use helicon_gcs::mavlink::dialects::common::{
    HEARTBEAT_DATA, MavAutopilot, MavMessage, MavModeFlag, MavState, MavType,
};
use helicon_gcs::mavlink::{MavHeader, write_v2_msg};
use helicon_gcs::navigator::{NavEvent, NavMode, NavigatorConfig};
use helicon_gcs::server::{self, ServerConfig, default_rates_hz};
use nalgebra::Vector3;
use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

fn status(t_s: f64) -> VehicleStatus {
    VehicleStatus {
        t_s,
        armed: true,
        nav_mode: NavMode::Mission,
        flight_mode: FlightMode {
            name: "auto",
            law_flies: true,
        },
        attitude_rad: Vector3::new(0.0, 0.0, 0.5),
        rates_rad_s: Vector3::zeros(),
        position_ned_m: Vector3::new(3.0, 4.0, -10.0),
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

#[test]
fn gcs_monitor_hears_the_helicopter() {
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let (mut v, s) = channel(4096);
    let h = server::spawn(
        ServerConfig {
            address: format!("udpout:127.0.0.1:{port}"),
            system_id: 1,
            home: Geodetic::new(57.0146, 9.9869, 20.0).unwrap(),
            navigator: NavigatorConfig::default(),
            signing_key: None,
            rates_hz: default_rates_hz(),
        },
        s,
    )
    .unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args([
            "gcs",
            &format!("udpin:127.0.0.1:{port}"),
            "--duration-s",
            "2.5",
        ])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // the vehicle's status at 10 Hz for 2 s (on-board time = wall time here)
    let t0 = std::time::Instant::now();
    let mut k = 0;
    while t0.elapsed().as_secs_f64() < 2.2 {
        let t = t0.elapsed().as_secs_f64();
        let _ = v.downlink.push(Downlink::Status(status(t)));
        if k == 5 {
            let _ = v.downlink.push(Downlink::Event(
                t,
                VehicleEvent::Nav(NavEvent::Mode(NavMode::Mission)),
            ));
        }
        k += 1;
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let out = child.wait_with_output().unwrap();
    let _ = h.stop();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("MAV_TYPE_HELICOPTER ARMED    MISSION"),
        "{text}"
    );
    assert!(text.contains("N    3.00 E    4.00 D  -10.00 m"), "{text}");
    assert!(text.contains("mode MISSION"), "{text}");
}

#[test]
fn gcs_monitor_bad_input_named() {
    for (args, want) in [
        (vec!["gcs", "tcpin:1.2.3.4:5"], "address `tcpin:1.2.3.4:5`"),
        (
            vec!["gcs", "udpin:127.0.0.1:0", "--duration-s", "nan"],
            "--duration NaN",
        ),
        (
            vec!["gcs", "udpin:127.0.0.1:0", "--timeout", "0"],
            "--timeout 0",
        ),
        (
            vec!["gcs", "udpin:nohost:x", "--duration-s", "1"],
            "address `udpin:nohost:x`",
        ),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
            .args(&args)
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}

fn free_udp_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
        .display()
        .to_string()
}

/// `helicon sitl` of the demo scenario flown from the ground (lock-step,
/// at most 300 simulated s) with its server sending to `port`.
fn sitl(port: u16, out: &Path) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args([
            "sitl",
            &repo("scenarios/demo.toml"),
            "--out",
            &out.display().to_string(),
            "--gcs",
            &format!("udpout:127.0.0.1:{port}"),
            "--duration",
            "300",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap()
}

/// `helicon gcs udpin:127.0.0.1:PORT` with `script` on its stdin, run in
/// `cwd`.
fn gcs(port: u16, script: &str, extra: &[&str], cwd: &Path) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .current_dir(cwd)
        .args(["gcs", &format!("udpin:127.0.0.1:{port}")])
        .args(extra)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(script.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

/// Stop a SITL run (SIGINT: it ends as after Ctrl-C) and wait for it.
fn stop(mut child: std::process::Child) {
    let _ = nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(i32::try_from(child.id()).unwrap()),
        nix::sys::signal::Signal::SIGINT,
    );
    let _ = child.wait();
}

#[test]
fn gcs_script_flies_the_sitl() {
    // the documented script (docs/gcs.md), run as there: from a folder
    // holding examples/gcs/
    let dir = helicon_test_support::tmpdir("gcs_script");
    let dir_path = dir.to_path_buf();
    let examples = dir_path.join("examples/gcs");
    std::fs::create_dir_all(&examples).unwrap();
    for f in ["square.waypoints", "first_flight.gcs"] {
        std::fs::copy(repo(&format!("examples/gcs/{f}")), examples.join(f)).unwrap();
    }
    let script = std::fs::read_to_string(examples.join("first_flight.gcs")).unwrap();
    let port = free_udp_port();
    let vehicle = sitl(port, &dir_path.join("out"));
    let out = gcs(port, &script, &["--timeout", "30"], &dir_path);
    stop(vehicle);
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}\n{err}");
    for want in [
        "param get NAV_TKOFF_ALT: NAV_TKOFF_ALT = 5",
        "arm: MAV_RESULT_ACCEPTED",
        "wait armed: done",
        "takeoff 3: MAV_RESULT_ACCEPTED",
        "wait mode HOLD: done",
        "mission upload examples/gcs/square.waypoints: MAV_MISSION_ACCEPTED (4 items)",
        "mission download square-back.waypoints: 4 items",
        "param set NAV_MAX_SPD 4: NAV_MAX_SPD = 4",
        "mission start: MAV_RESULT_ACCEPTED",
        "reached mission item 3",
        "wait mission done: done",
        "wait landed: done",
        "wait disarmed: done",
    ] {
        assert!(text.contains(want), "no `{want}` in\n{text}\n{err}");
    }
    // the mission downloaded is the file uploaded, byte for byte
    assert_eq!(
        std::fs::read_to_string(dir_path.join("square-back.waypoints")).unwrap(),
        std::fs::read_to_string(examples.join("square.waypoints")).unwrap()
    );
}

#[test]
fn gcs_refusal_and_bad_mission_fail_the_script() {
    let dir = helicon_test_support::tmpdir("gcs_refusal");
    let dir_path = dir.to_path_buf();
    let bad = dir_path.join("bad.waypoints");
    std::fs::write(
        &bad,
        "QGC WPL 110\n0\t1\t3\t22\t0\t0\t0\t0\t0\t0\t3\t1\n1\t0\t3\t16\t0\t0\t0\t0\t57.01\tnan\t3\t1\n",
    )
    .unwrap();
    let port = free_udp_port();
    let vehicle = sitl(port, &dir_path.join("out"));
    // land while disarmed: refused; then a mission file with a NaN
    let script = format!(
        "land\nmission upload {}\nmode ACRO\nparam get NO_SUCH_PARAM\n",
        bad.display()
    );
    let out = gcs(port, &script, &["--timeout", "10"], &dir_path);
    stop(vehicle);
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{text}\n{err}");
    assert!(
        err.contains("error: land: refused: MAV_RESULT_DENIED"),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "{}:3: y (longitude) `nan`: not finite",
            bad.display()
        )),
        "{err}"
    );
    assert!(err.contains("mode `ACRO`"), "{err}");
    assert!(err.contains("4 command(s) failed"), "{err}");
}

fn heartbeat_frame(sysid: u8, seq: u8, armed: bool) -> Vec<u8> {
    let mut b = Vec::new();
    write_v2_msg(
        &mut b,
        MavHeader {
            system_id: sysid,
            component_id: 1,
            sequence: seq,
        },
        &MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: helicon_gcs::modes::custom_mode(4, 3),
            mavtype: MavType::MAV_TYPE_HELICOPTER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode: if armed {
                MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED
                    | MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            } else {
                MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            },
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }),
    )
    .unwrap();
    b
}

#[test]
fn gcs_tcp_client_hears_a_vehicle() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let server = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        for k in 0..12u8 {
            // split a frame across writes: the client reassembles it (the
            // client may have ended: a failed write ends the stream)
            let f = heartbeat_frame(7, k, true);
            let (a, b) = f.split_at(5);
            if s.write_all(a).is_err() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
            if s.write_all(b).is_err() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(80));
        }
    });
    let out = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(["gcs", &format!("tcp:127.0.0.1:{port}"), "--duration", "1.5"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    server.join().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("vehicle 7: MAV_TYPE_HELICOPTER ARMED    HOLD"),
        "{text}"
    );
}

#[test]
fn gcs_keeps_vehicles_apart_and_tells_a_quiet_one() {
    let port = free_udp_port();
    let child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args([
            "gcs",
            &format!("udpin:127.0.0.1:{port}"),
            "--duration",
            "5.5",
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let a = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let b = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = format!("127.0.0.1:{port}");
    // vehicle 2 speaks for the first second only; vehicle 3 throughout
    for k in 0..50u8 {
        if k < 10 {
            a.send_to(&heartbeat_frame(2, k, true), &to).unwrap();
        }
        b.send_to(&heartbeat_frame(3, k, false), &to).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("vehicle 2: MAV_TYPE_HELICOPTER ARMED"),
        "{text}"
    );
    assert!(
        text.contains("vehicle 3: MAV_TYPE_HELICOPTER disarmed"),
        "{text}"
    );
    assert!(text.contains("vehicle 2: no heartbeat for"), "{text}");
    // the last lines: vehicle 2 quiet, not its last state repeated
    let last2 = text.lines().rfind(|l| l.starts_with("vehicle 2:")).unwrap();
    assert!(last2.contains("no heartbeat for"), "{last2}");
}

/// A fake vehicle `sysid` on its own socket: heartbeats every 50 ms for
/// `for_s`, a `PARAM_REQUEST_READ` addressed to it answered with 7.5;
/// returns the parameter requests it received.
fn fake_vehicle(sysid: u8, to: String, for_s: f64) -> std::thread::JoinHandle<usize> {
    use helicon_gcs::mavlink::dialects::common::PARAM_VALUE_DATA;
    std::thread::spawn(move || {
        let s = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        s.set_read_timeout(Some(std::time::Duration::from_millis(50)))
            .unwrap();
        let t0 = std::time::Instant::now();
        let mut requests = 0;
        let mut k = 0u8;
        let mut buf = [0u8; 2048];
        while t0.elapsed().as_secs_f64() < for_s {
            s.send_to(&heartbeat_frame(sysid, k, false), &to).unwrap();
            k = k.wrapping_add(1);
            let Ok(n) = s.recv(&mut buf) else { continue };
            let mut r = helicon_gcs::mavlink::MavlinkReader::new(&buf[..n]);
            while let Ok((_, m)) = r.read_any_message::<MavMessage>() {
                if let MavMessage::PARAM_REQUEST_READ(p) = m {
                    requests += 1;
                    if p.target_system == sysid {
                        let mut out = Vec::new();
                        write_v2_msg(
                            &mut out,
                            MavHeader {
                                system_id: sysid,
                                component_id: 1,
                                sequence: k,
                            },
                            &MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
                                param_value: 7.5,
                                param_id: p.param_id,
                                ..PARAM_VALUE_DATA::DEFAULT
                            }),
                        )
                        .unwrap();
                        s.send_to(&out, &to).unwrap();
                    }
                }
            }
        }
        requests
    })
}

#[test]
fn gcs_commands_go_to_the_vehicle_chosen() {
    let dir = helicon_test_support::tmpdir("gcs_vehicle");
    let port = free_udp_port();
    let to = format!("127.0.0.1:{port}");
    let two = fake_vehicle(2, to.clone(), 3.0);
    let three = fake_vehicle(3, to, 3.0);
    let out = gcs(
        port,
        "vehicle 3\nparam get NAV_TKOFF_ALT\n",
        &["--timeout", "2"],
        &dir.to_path_buf(),
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}\n{err}");
    assert!(
        text.contains("vehicle 3: commands go to vehicle 3"),
        "{text}"
    );
    assert!(
        text.contains("param get NAV_TKOFF_ALT: NAV_TKOFF_ALT = 7.5"),
        "{text}"
    );
    // vehicle 2 (another address on the same port) was sent nothing of it
    assert_eq!(two.join().unwrap(), 0);
    assert!(three.join().unwrap() >= 1);
}

/// A QGC WPL mission of waypoints 3 m above home, each (north, east) in
/// metres from home.
fn waypoints(points: &[(f64, f64)]) -> String {
    let (lat0, lon0) = (57.014_636, 9.986_9);
    let mut s = String::from("QGC WPL 110\n");
    for (k, (n, e)) in points.iter().enumerate() {
        let lat = lat0 + n / 111_320.0;
        let lon = lon0 + e / (111_320.0 * lat0.to_radians().cos());
        s += &format!(
            "{k}\t{}\t3\t16\t0\t0\t0\t0\t{lat:.8}\t{lon:.8}\t3.0\t1\n",
            u8::from(k == 0)
        );
    }
    s
}

#[test]
fn gcs_waits_for_the_mission_started_last() {
    // one mission flown to its end, a second uploaded and started: its
    // `wait mission done` ends at the second's last item, not at once on
    // the first's completion
    let dir = helicon_test_support::tmpdir("gcs_two_missions");
    let dir_path = dir.to_path_buf();
    std::fs::write(
        dir_path.join("a.waypoints"),
        waypoints(&[(0.0, 4.0), (0.0, 0.0)]),
    )
    .unwrap();
    std::fs::write(
        dir_path.join("b.waypoints"),
        waypoints(&[(4.0, 0.0), (4.0, 4.0), (0.0, 0.0)]),
    )
    .unwrap();
    let script = "arm\nwait armed\ntakeoff 3\nwait mode HOLD\n\
                  mission upload a.waypoints\nmission start\nwait mission done\n\
                  mission upload b.waypoints\nmission start\nwait mission done\n\
                  land\nwait landed\nquit\n";
    let port = free_udp_port();
    let vehicle = sitl(port, &dir_path.join("out"));
    let out = gcs(port, script, &["--timeout", "40"], &dir_path);
    stop(vehicle);
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}\n{err}");
    let at = |want: &str, from: usize| {
        text[from..]
            .find(want)
            .map(|i| from + i)
            .unwrap_or_else(|| panic!("no `{want}` after byte {from} in\n{text}\n{err}"))
    };
    let first = at(
        "mission upload a.waypoints: MAV_MISSION_ACCEPTED (2 items)",
        0,
    );
    let first_last = at("reached mission item 1", first);
    let first_done = at("wait mission done: done", first);
    assert!(first_last < first_done, "{text}");
    let second = at(
        "mission upload b.waypoints: MAV_MISSION_ACCEPTED (3 items)",
        first_done,
    );
    let started = at("mission start: MAV_RESULT_ACCEPTED", second);
    let second_last = at("reached mission item 2", started);
    let second_done = at("wait mission done: done", started);
    assert!(
        second_last < second_done,
        "the second wait ended before the second mission's last item:\n{text}"
    );
    at("wait landed: done", second_done);
}
