//! The ground station's cost to the control task: one `Vehicle::step`
//! (uplink drained, navigator flying a mission leg, status pushed) with the
//! status at every sample (400 Hz, the fullest telemetry), while the server
//! thread streams every message at 100 Hz over UDP to a local socket.
#![allow(clippy::unwrap_used, missing_docs)] // bench: criterion macros generate undocumented items

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_core::navigation::NavigationSolution;
use helicon_core::state::Input;
use helicon_core::{Reference, Telemetry};
use helicon_devices::Geodetic;
use helicon_gcs::link::{FlightMode, Vehicle, channel};
use helicon_gcs::navigator::{Events, Item, ItemKind, NavInput, Navigator, NavigatorConfig, Plan};
use helicon_gcs::server::{self, ServerConfig};
use nalgebra::{SVector, Vector3};
use std::hint::black_box;

fn telemetry(t_s: f64) -> Telemetry {
    Telemetry {
        sample: 0,
        t_s,
        reference: Reference {
            velocity_ned_m_s: Vector3::zeros(),
            yaw_rad: 0.0,
        },
        command: Input::zeros(),
        saturated: [false; 4],
        tracking_error: SVector::zeros(),
        integral: SVector::zeros(),
        estimate: SVector::zeros(),
        measured: SVector::zeros(),
        navigation: Some(NavigationSolution {
            position_ned_m: Vector3::new(1.0, 2.0, -10.0),
            velocity_ned_m_s: Vector3::new(1.0, 0.0, 0.0),
            attitude_rad: Vector3::zeros(),
            position_sigma_m: Vector3::repeat(0.5),
            attitude_fix: true,
            gps_fused: true,
            imu_bias: None,
            rejected_updates: 0,
        }),
    }
}

fn bench_vehicle_step(c: &mut Criterion) {
    let sink = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = sink.local_addr().unwrap().port();
    let (vehicle_end, server_end) = channel(8192);
    let config = ServerConfig {
        address: format!("udpout:127.0.0.1:{port}"),
        system_id: 1,
        home: Geodetic::new(57.0146, 9.9869, 20.0).unwrap(),
        navigator: NavigatorConfig::default(),
        signing_key: None,
        rates_hz: [100.0; helicon_gcs::server::STREAMS.len()],
    };
    let handle = server::spawn(config, server_end).unwrap();
    let mut plan = Plan::default();
    plan.push(Item {
        seq: 0,
        kind: ItemKind::Waypoint,
        position_ned_m: Vector3::new(1.0e6, 0.0, -10.0),
        speed_m_s: Some(3.0),
        yaw_rad: None,
        acceptance_m: None,
        hold_s: 0.0,
    });
    // a long mission leg: the navigator's full guidance every sample
    let mut nav = Navigator::new(NavigatorConfig::default()).unwrap();
    nav.set_plan(plan);
    let at = NavInput {
        t_s: 0.0,
        position_ned_m: Vector3::new(1.0, 2.0, -10.0),
        yaw_rad: 0.0,
        on_ground: None,
    };
    assert!(nav.start_mission(&at, &mut Events::default()));
    let mut v = Vehicle::new(nav, vehicle_end, 1);
    let mode = FlightMode {
        name: "auto",
        law_flies: true,
    };
    let servo = Input::zeros();
    let mut t = 0.0;
    c.bench_function("vehicle_step_status_every_sample", |b| {
        b.iter(|| {
            t += 0.0025;
            let tel = telemetry(t);
            black_box(v.step(black_box(t), Some(&tel), mode, &servo, 0.0))
        })
    });
    let report = handle.stop();
    println!(
        "server: {report:?}; statuses dropped (ring full): {}",
        v.dropped()
    );
}

criterion_group!(benches, bench_vehicle_step);
criterion_main!(benches);
