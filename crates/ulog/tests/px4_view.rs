//! The PX4 view of a flight log: PX4's topics written beside helicon's,
//! decimated to their intervals, the geodetic topics from the home, a
//! DROPOUT for missed control steps, the mode's `vehicle_status`, the land
//! detector's record, parameters at the start and changed in flight.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use helicon_devices::Geodetic;
use helicon_ulog::messages::{Control, HeliconGps, Mode, Navigation, SensorImu, Timing};
use helicon_ulog::px4::{self, SensorGps, VehicleLandDetected, VehicleStatus};
use helicon_ulog::reader::{Message, UlogReader};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, LogRecord, Record};
use std::collections::HashMap;

const HOME: (f64, f64, f64) = (57.0146, 9.9869, 20.0);

/// The log of 1 s at 400 Hz, steps 200..=209 missed, a GPS fix 100 m north
/// of home, a descent, a landing and a parameter change.
fn flight() -> Vec<u8> {
    let info = LogInfo {
        home: Some(Geodetic::new(HOME.0, HOME.1, HOME.2).unwrap()),
        control_period_us: Some(2500),
        parameters: vec![("HC_CTRL_DT_S".to_string(), 0.0025)],
        ..LogInfo::default()
    };
    let mut log = FlightLog::new(Vec::new(), &info, FlushPolicy::default()).unwrap();
    for k in (0..400u64).filter(|k| !(200..210).contains(k)) {
        let t = 2500 * k;
        let mut estimate = [0.0; 9];
        estimate[2] = 0.5; // ψ
        log.write(&LogRecord::Imu(SensorImu {
            timestamp: t,
            specific_force_body_m_s2: [0.0, 0.0, -9.81],
            gyro_body_rad_s: [0.01, 0.0, 0.0],
        }))
        .unwrap();
        log.write(&LogRecord::Control(Control {
            timestamp: t,
            sample: k,
            estimate,
            ..Control::default()
        }))
        .unwrap();
        log.write(&LogRecord::Navigation(Navigation {
            timestamp: t,
            attitude_rad: [0.0, 0.0, 0.5],
            ..Navigation::default()
        }))
        .unwrap();
        log.write(&LogRecord::Timing(Timing {
            timestamp: t,
            sample: k,
            compute_time_us: 250,
            ..Timing::default()
        }))
        .unwrap();
    }
    log.write(&LogRecord::Gps(HeliconGps {
        timestamp: 500_000,
        epoch_s: 0.45,
        position_ned_m: [100.0, 0.0, 0.0],
        fix_type: 3,
        ..HeliconGps::default()
    }))
    .unwrap();
    let descent = px4::StatusMode {
        arming_state: px4::ARMING_STATE_ARMED,
        nav_state: px4::NAV_STATE_DESCEND,
        failsafe: true,
    };
    log.write_mode(
        &Mode {
            timestamp: 997_500,
            mode: 3,
            previous: 2,
        },
        descent,
    )
    .unwrap();
    log.write(&LogRecord::LandDetected(VehicleLandDetected {
        timestamp: 997_500,
        ground_contact: true,
        maybe_landed: true,
        landed: true,
        ..VehicleLandDetected::default()
    }))
    .unwrap();
    log.parameter_changed("HC_CTRL_DT_S", 0.005, 997_500)
        .unwrap();
    log.finish().unwrap()
}

#[derive(Default)]
struct Read {
    records: HashMap<String, Vec<Vec<u8>>>,
    dropouts: Vec<u16>,
    /// Parameters: (name, value, in the data section)
    parameters: Vec<(String, String, bool)>,
    infos: Vec<String>,
}

fn read(bytes: &[u8]) -> Read {
    let mut r = UlogReader::new(bytes, "px4_view").unwrap();
    let mut names = HashMap::new();
    let mut out = Read::default();
    let mut data_section = false;
    while let Some(m) = r.next_message().unwrap() {
        match m {
            Message::AddLogged { msg_id, name, .. } => {
                data_section = true;
                names.insert(msg_id, name);
            }
            Message::Data { msg_id, payload } => out
                .records
                .entry(names[&msg_id].clone())
                .or_default()
                .push(payload.to_vec()),
            Message::Dropout { duration_ms } => out.dropouts.push(duration_ms),
            Message::Parameter(kv) => {
                out.parameters
                    .push((kv.name.clone(), kv.value.to_string(), data_section));
            }
            Message::Info(kv) => out.infos.push(kv.name.clone()),
            _ => {}
        }
    }
    out
}

#[test]
fn px4_topics_are_decimated_to_their_intervals() {
    let log = read(&flight());
    let n = |t: &str| log.records.get(t).map_or(0, Vec::len);
    // helicon's topics at the full rate: 390 steps
    assert_eq!(n("control"), 390);
    // PX4's at their intervals: slots from 0 up to 997.5 ms (a slot taken
    // by the first record at most a tenth of the interval or 1 ms early);
    // after the gap (500..522.5 ms) the schedule starts again at 525 ms,
    // costing one slot of 20 ms and two of 10 ms
    let counts: Vec<usize> = [
        "vehicle_attitude",
        "sensor_combined",
        "vehicle_local_position",
        "vehicle_global_position",
        "vehicle_status",
    ]
    .iter()
    .map(|t| n(t))
    .collect();
    // vehicle_status: the first, each second, and the descent
    assert_eq!(counts, vec![49, 98, 10, 5, 2]);
    assert_eq!(n("cpuload"), 1); // every 0.5 s: at 0.5 s (the window starts at 0)
    assert_eq!(n("sensor_gps"), 1);
    assert_eq!(n("vehicle_gps_position"), 1);
    assert_eq!(n("vehicle_land_detected"), 1);
    let att = px4::VehicleAttitude::decode(&log.records["vehicle_attitude"][1]).unwrap();
    // ψ = 0.5 about the down axis: q = (cos 0.25, 0, 0, sin 0.25)
    assert!((att.q[0] - 0.25f32.cos()).abs() < 1e-6 && (att.q[3] - 0.25f32.sin()).abs() < 1e-6);
    let load = px4::Cpuload::decode(&log.records["cpuload"][0]).unwrap();
    assert!((load.load - 0.1).abs() < 0.01, "{load:?}"); // 250 µs of 2500
}

#[test]
fn missed_control_steps_are_a_dropout() {
    let log = read(&flight());
    // steps 200..=209 missed: 11 periods from 199 to 210, 10 of them lost
    assert_eq!(log.dropouts, vec![25]);
}

#[test]
fn the_gps_fix_is_placed_from_the_home() {
    let log = read(&flight());
    // the same record under both topics (bytes: NaN fields)
    assert_eq!(
        log.records["sensor_gps"],
        log.records["vehicle_gps_position"]
    );
    let g = SensorGps::decode(&log.records["sensor_gps"][0]).unwrap();
    // 100 m north: the meridian's radius of curvature at the home's latitude
    let (a, f) = (6_378_137.0f64, 1.0 / 298.257_223_563);
    let e2 = f * (2.0 - f);
    let s = HOME.0.to_radians().sin();
    let m = a * (1.0 - e2) / (1.0 - e2 * s * s).powf(1.5);
    let dlat = (100.0 / m).to_degrees();
    assert!(
        (g.latitude_deg - (HOME.0 + dlat)).abs() < 1e-7,
        "{}",
        g.latitude_deg
    );
    assert!((g.longitude_deg - HOME.1).abs() < 1e-7);
    assert!((g.altitude_msl_m - HOME.2).abs() < 0.01);
    assert_eq!(g.fix_type, 3);
    assert_eq!(g.timestamp_sample, 450_000);
    assert_eq!(g.time_utc_usec, 0); // the UTC start unknown
    let lpos =
        px4::VehicleLocalPosition::decode(&log.records["vehicle_local_position"][0]).unwrap();
    assert_eq!((lpos.ref_lat, lpos.ref_lon), (HOME.0, HOME.1));
    assert!(lpos.xy_global && lpos.xy_valid);
}

#[test]
fn status_land_detector_parameters_and_info() {
    let log = read(&flight());
    let last = VehicleStatus::decode(log.records["vehicle_status"].last().unwrap()).unwrap();
    assert_eq!(last.nav_state, px4::NAV_STATE_DESCEND);
    assert!(last.failsafe);
    assert_eq!(last.arming_state, px4::ARMING_STATE_ARMED);
    assert_eq!(last.vehicle_type, px4::VEHICLE_TYPE_ROTARY_WING);
    assert_eq!(last.nav_state_timestamp, 997_500);
    let land = VehicleLandDetected::decode(&log.records["vehicle_land_detected"][0]).unwrap();
    assert!(land.landed && land.maybe_landed && land.ground_contact && !land.freefall);
    assert_eq!(
        log.parameters,
        vec![
            ("HC_CTRL_DT_S".to_string(), "0.0025".to_string(), false),
            ("HC_CTRL_DT_S".to_string(), "0.005".to_string(), true),
        ]
    );
    for key in [
        "sys_name",
        "ver_sw",
        "ver_hw",
        "sys_toolchain",
        "time_ref_utc",
    ] {
        assert!(log.infos.iter().any(|k| k == key), "{key}: {:?}", log.infos);
    }
}
