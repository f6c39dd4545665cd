//! The control task's hot path allocates nothing in steady state: the
//! supervisor, the flight computer, the log records of the step, the rings
//! to the logger, and the logger's ULog encoding (counted per thread with a
//! wrapping allocator, over the 4400 samples after the first second).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

use helicon_flight::config::{FailsafeConfig, StaleLimits};
use helicon_flight::control::{ControlTask, Tick};
use helicon_flight::records::{FlightRecord, step_records, write_record};
use helicon_flight::safety::{RcInput, Supervisor};
use helicon_sim::closed_loop::{Hardware, flight_computer, imu_health_at, prepare};
use helicon_sim::excitation::Excitations;
use helicon_sim::scenario::Scenario;
use helicon_ulog::messages::Timing;
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo};
use std::path::Path;

#[test]
fn a_control_step_and_its_log_allocate_nothing() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml");
    let mut s = Scenario::from_file(&path).unwrap();
    s.duration_s = 12.0;
    let prepared = prepare(&s).unwrap();
    let mut hw = Hardware::new(&s, &prepared).unwrap();
    let x0 = *hw.state();
    let computer = flight_computer(&prepared.onboard_setup(&s, &x0)).unwrap();
    let mut sup = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0);
    sup.arm();
    let health = imu_health_at(
        prepared.model.params().environment.g_m_s2,
        prepared.gains.set.sample_time_s,
        &s.sensors,
        "demo",
    )
    .unwrap();
    let mut task =
        ControlTask::new(computer, sup, prepared.gains.set.u_trim).with_imu_health(health);
    let (mut tx, mut rx) = rtrb::RingBuffer::<FlightRecord>::new(4096);
    let mut log =
        FlightLog::new(std::io::sink(), &LogInfo::default(), FlushPolicy::default()).unwrap();
    let rc = RcInput {
        servo: prepared.gains.set.u_trim,
        manual: false,
        armed: true,
        failsafe: false,
        kill: false,
        out_of_range: false,
    };
    // the flight-test excitation of ident-hover-sweep (S_lon sweep from 1 s)
    let sweep = Scenario::from_file(&path.with_file_name("ident-hover-sweep.toml")).unwrap();
    let excitation = Excitations::new(&sweep.excitation, "ident-hover-sweep").unwrap();
    let mut counted = 0;
    let mut steps = 0;
    let mut records = 0;
    while let Some(sample) = hw.sense() {
        let tick = Tick {
            now_s: sample.t_s,
            frame: Some(sample.frame),
            deadline_missed: false,
            rc: (sample.k % 8 == 0).then_some(rc),
            reference: sample.reference,
            gps_quality: None,
        };
        let before = allocations();
        let out = task.step_with(&tick, &excitation);
        let timing = Timing {
            timestamp: (sample.t_s * 1e6).round() as u64,
            sample: steps,
            ..Timing::default()
        };
        step_records(&tick, &out, timing, &mut |r| tx.push(r).unwrap()).unwrap();
        while let Ok(r) = rx.pop() {
            write_record(&mut log, &r).unwrap();
            records += 1;
        }
        // the first second warms up (the writer's buffer reaches its size)
        if sample.t_s >= 1.0 {
            counted += allocations() - before;
        }
        steps += 1;
        let step = hw.actuate(&out.servo, out.telemetry.as_ref()).unwrap();
        if step.end.is_some() {
            break;
        }
    }
    assert_eq!(steps, 4801);
    // per step: IMU, IMU health, control, navigation, excitation, servo, timing; magnetometer at
    // 100 Hz, GPS at 5 Hz, receiver at 50 Hz
    assert!(records > 7 * 4800, "{records} records");
    assert_eq!(counted, 0, "allocations in 4400 steady-state control steps");
}

/// The ground station's part of a step (`Mission::Ground`: the uplink
/// drained, the navigator on the last telemetry, the status pushed, the
/// arm handed to the supervisor) allocates nothing either: a takeoff flown
/// with a heartbeat every sample, over the samples after the first second.
#[test]
fn a_ground_station_step_allocates_nothing() {
    use helicon_flight::mission::{LastStep, Mission, References};
    use helicon_gcs::link::{Downlink, Uplink, Vehicle, channel};
    use helicon_gcs::navigator::{Navigator, NavigatorConfig};

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml");
    let mut s = Scenario::from_file(&path).unwrap();
    s.duration_s = 4.0;
    let prepared = prepare(&s).unwrap();
    let mut hw = Hardware::new(&s, &prepared).unwrap();
    let x0 = *hw.state();
    let computer = flight_computer(&prepared.onboard_setup(&s, &x0)).unwrap();
    let sup = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0);
    let u_trim = prepared.gains.set.u_trim;
    let mut task = ControlTask::new(computer, sup, u_trim);
    let (vehicle_end, mut server_end) = channel(64);
    let nav = Navigator::new(NavigatorConfig::default()).unwrap();
    let mut mission = Mission::new(References::Ground(Box::new(Vehicle::new(
        nav,
        vehicle_end,
        1,
    ))));
    let mut last = LastStep {
        telemetry: None,
        mode: task.mode(),
        servo: u_trim,
        load: 0.0,
    };
    server_end.uplink.push(Uplink::Arm(true)).unwrap();
    let mut counted = 0;
    let mut statuses = 0;
    while let Some(sample) = hw.sense() {
        server_end.uplink.push(Uplink::GcsHeartbeat).unwrap();
        if sample.k == 40 {
            server_end.uplink.push(Uplink::Takeoff(5.0)).unwrap();
        }
        let before = allocations();
        let reference = mission.step(sample.t_s, &last, &mut task);
        let out = task.step(&Tick {
            now_s: sample.t_s,
            frame: Some(sample.frame),
            deadline_missed: false,
            rc: None,
            reference,
            gps_quality: None,
        });
        if sample.t_s >= 1.0 {
            counted += allocations() - before;
        }
        if out.telemetry.is_some() {
            last.telemetry = out.telemetry;
        }
        last.mode = out.mode;
        last.servo = out.servo;
        while let Ok(d) = server_end.downlink.pop() {
            if matches!(d, Downlink::Status(_)) {
                statuses += 1;
            }
        }
        let step = hw.actuate(&out.servo, out.telemetry.as_ref()).unwrap();
        if step.end.is_some() {
            break;
        }
    }
    // armed by the ground station, climbing at the end
    assert_eq!(task.mode().as_str(), "auto");
    let References::Ground(v) = mission.references() else {
        unreachable!()
    };
    assert_eq!(v.navigator().mode(), helicon_gcs::NavMode::Takeoff);
    assert!(hw.state()[2] < -1.0, "z = {}", hw.state()[2]);
    assert!(statuses > 1500, "{statuses} statuses");
    assert_eq!(
        counted, 0,
        "allocations in steady-state ground-station steps"
    );
}
