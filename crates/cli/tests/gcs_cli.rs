//! `helicon gcs` against the ground-station server (fed a vehicle status by
//! the test): it hears the helicopter and prints its state; a bad address
//! or duration is an error naming it.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::Reference;
use helicon_core::state::Input;
use helicon_devices::Geodetic;
use helicon_gcs::link::{Downlink, FlightMode, VehicleEvent, VehicleStatus, channel};
use helicon_gcs::navigator::{NavEvent, NavMode, NavigatorConfig};
use helicon_gcs::server::{self, ServerConfig, default_rates_hz};
use nalgebra::Vector3;
use std::process::Command;

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
        (vec!["gcs", "tcp:1.2.3.4:5"], "address `tcp:1.2.3.4:5`"),
        (
            vec!["gcs", "udpin:127.0.0.1:0", "--duration-s", "nan"],
            "--duration-s NaN",
        ),
        (
            vec!["gcs", "udpin:nohost:x", "--duration-s", "1"],
            "address `udpin:nohost:x`",
        ),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}
