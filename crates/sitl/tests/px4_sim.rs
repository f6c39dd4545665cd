//! PX4's simulator interface against a stand-in for PX4's SITL written
//! from the protocol (`SimulatorMavlink.cpp`: a TCP client on the
//! simulator's port that sends a HEARTBEAT on connecting, reads HIL_SENSOR
//! / HIL_GPS / HIL_STATE_QUATERNION and answers each sensor step with
//! HIL_ACTUATOR_CONTROLS, `controls` all 0 while disarmed, the armed flag
//! in `mode`) and from PX4's helicopter allocation
//! (`ActuatorEffectivenessHelicopter::updateSetpoint`), over a real socket
//! on 127.0.0.1 with an OS-chosen port, through the `mavlink` crate.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

use helicon_gcs::mavlink::dialects::common::{
    HEARTBEAT_DATA, HIL_ACTUATOR_CONTROLS_DATA, HIL_SENSOR_DATA, HilActuatorControlsFlags,
    MavAutopilot, MavMessage, MavModeFlag, MavState, MavType,
};
use helicon_gcs::mavlink::{MavHeader, MavlinkReader, write_v2_msg};
use helicon_model::state::ix;
use helicon_sim::closed_loop::{Prepared, prepare, prepare_with_params};
use helicon_sim::scenario::Scenario;
use helicon_sitl::ground_start;
use helicon_sitl::px4::{
    BERGEN_TWIN_TOML, CHANNELS, Ending, Px4Map, Px4Options, Px4Outputs, Px4Report, Px4Section,
    Px4Server,
};
use std::io::Write;
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

const G: f64 = 9.81;

/// The physical Bergen Twin, no wind, in the air at its trim.
fn air() -> (Scenario, Prepared) {
    let s = Scenario::from_toml_str(
        "name = \"px4-air\"\npreset = \"physical\"\nduration_s = 600.0\n",
        "test",
    )
    .unwrap();
    let p = prepare(&s).unwrap();
    (s, p)
}

/// The same on the ground, rotor stopped (`helicon sitl`'s ground start).
fn ground() -> (Scenario, Prepared) {
    let (air, _) = air();
    let (s, params) = ground_start(&air).unwrap();
    let p = prepare_with_params(&s, params).unwrap();
    (s, p)
}

fn map(p: &Prepared) -> Px4Map {
    let section = Px4Section::from_toml_str(BERGEN_TWIN_TOML, "bergen_twin.toml").unwrap();
    Px4Map::new(section, p.model.params(), "bergen_twin.toml").unwrap()
}

/// PX4's helicopter allocation for the example's outputs (Motor 1 on
/// output 1, the tail servo on 2, swash servos on 3 … 5 at 300°, 60°,
/// 180°, arm lengths 1, no trims), written from PX4's code, not helicon's.
fn px4_controls(o: &Px4Outputs) -> [f32; CHANNELS] {
    let mut c = [0f32; CHANNELS];
    c[0] = o.throttle as f32;
    c[1] = o.tail as f32;
    for (i, a) in [300.0f64, 60.0, 180.0].into_iter().enumerate() {
        let a = a.to_radians();
        c[2 + i] = (o.collective + o.pitch * a.cos() - o.roll * a.sin()) as f32;
    }
    c
}

/// The stand-in for PX4's SITL.
struct Px4 {
    stream: TcpStream,
    reader: MavlinkReader<TcpStream>,
    seq: u8,
}

impl Px4 {
    /// Connect and say hello as PX4 does (a HEARTBEAT from its sender thread).
    fn connect(to: SocketAddr) -> Px4 {
        let stream = TcpStream::connect(to).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(20)))
            .unwrap();
        stream.set_nodelay(true).unwrap();
        let reader = MavlinkReader::new(stream.try_clone().unwrap());
        let mut px4 = Px4 {
            stream,
            reader,
            seq: 0,
        };
        px4.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_HELICOPTER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_STANDBY,
            mavlink_version: 3,
        }));
        px4
    }

    fn send(&mut self, m: &MavMessage) {
        let h = MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: self.seq,
        };
        self.seq = self.seq.wrapping_add(1);
        write_v2_msg(&mut self.stream, h, m).unwrap();
    }

    /// The next HIL_SENSOR, and the other messages read before it.
    fn sensor(&mut self) -> (HIL_SENSOR_DATA, Vec<MavMessage>) {
        let mut others = Vec::new();
        loop {
            let (_, m) = self.reader.read_any_message::<MavMessage>().unwrap();
            match m {
                MavMessage::HIL_SENSOR(s) => return (s, others),
                other => others.push(other),
            }
        }
    }

    /// Answer a sensor step.
    fn controls(&mut self, controls: [f32; CHANNELS], armed: bool) {
        let mode = if armed {
            MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED
        } else {
            MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        };
        // PX4 sends zeros while disarmed
        let controls = if armed { controls } else { [0.0; CHANNELS] };
        self.send(&MavMessage::HIL_ACTUATOR_CONTROLS(
            HIL_ACTUATOR_CONTROLS_DATA {
                time_usec: 0,
                flags: HilActuatorControlsFlags::HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP,
                controls,
                mode,
            },
        ));
    }
}

/// Run the server on its own thread against `client`.
fn serve<T: Send>(
    s: &Scenario,
    p: &Prepared,
    options: Px4Options,
    client: impl FnOnce(SocketAddr) -> T + Send,
) -> (Px4Report, T) {
    let server = Px4Server::bind("127.0.0.1:0").unwrap();
    let to = server.local_addr();
    let m = map(p);
    std::thread::scope(|scope| {
        let h = scope.spawn(|| server.run(s, p, &m, &options).unwrap());
        let out = client(to);
        (h.join().unwrap(), out)
    })
}

/// Lock-step from the first contact on (no free-running before the first
/// actuator message: the counts are exact whatever the machine's load).
fn bounded(max_steps: u64) -> Px4Options {
    Px4Options {
        max_steps: Some(max_steps),
        silence_timeout: Some(Duration::from_secs(20)),
        free_run_until_first_actuator: false,
        ..Px4Options::default()
    }
}

/// N actuator messages step the model N times; each sensor step's
/// time_usec is k·4000 µs exactly; on the ground, disarmed, the helicopter
/// sits: specific force (0, 0, −g) in FRD, no rates, the field north and
/// down, the ISA pressure at home's 10 m, the GPS at home with a 3-D fix;
/// and after 2 s it is where it was, rotor stopped.
#[test]
fn lock_step_accounting_units_and_sitting_disarmed() {
    let (s, p) = ground();
    let n = 500u64;
    let (r, (first, firsts, last, others)) = serve(&s, &p, bounded(n), |to| {
        let mut px4 = Px4::connect(to);
        let (first, firsts) = px4.sensor();
        let mut others = Vec::new();
        let mut last = first.clone();
        for k in 1..=n {
            px4.controls([0.0; CHANNELS], false);
            let (sn, o) = px4.sensor();
            assert_eq!(sn.time_usec, k * 4000, "step {k}");
            others.extend(o);
            last = sn;
        }
        (first, firsts, last, others)
    });
    eprintln!(
        "px4 lock-step: {} steps in {:.3} s wall: {:.0} steps/s, {:.1}x real time",
        r.counts.steps, r.wall_s, r.steps_per_s, r.speed_x
    );
    assert_eq!(r.ending, Ending::FrameLimit);
    assert_eq!(r.counts.steps, n);
    assert_eq!(r.counts.actuator_messages, n);
    assert_eq!(r.counts.armed_messages, 0);
    assert_eq!(r.counts.sensor_messages, n + 1);
    assert_eq!(r.counts.connections, 1);
    assert_eq!(r.counts.other_messages, 1, "the HEARTBEAT");
    assert_eq!(r.counts.malformed() + r.counts.junk_bytes, 0);
    assert!((r.model_time_s - n as f64 * 0.004).abs() < 1e-12);
    assert_eq!(first.time_usec, 0);
    assert_eq!(first.id, 0);
    assert_eq!(first.fields_updated.bits() & 0x1BFF, 0x1BFF);
    for sn in [&first, &last] {
        assert!(
            f64::from(sn.xacc).abs() < 0.2 && f64::from(sn.yacc).abs() < 0.2,
            "{sn:?}"
        );
        assert!((f64::from(sn.zacc) + G).abs() < 0.2, "{sn:?}");
        assert!(f64::from(sn.xgyro).abs() < 1e-3 && f64::from(sn.zgyro).abs() < 1e-3);
        // the field at home: 0.1619 G horizontal, 0.484 G down; level: z is down
        let h = f64::from(sn.xmag).hypot(f64::from(sn.ymag));
        assert!(
            (h - 0.1619).abs() < 0.01 && (f64::from(sn.zmag) - 0.484).abs() < 0.01,
            "{sn:?}"
        );
        // ISA at 10 m: 1012.05 hPa, 14.94 °C
        assert!((f64::from(sn.abs_pressure) - 1012.05).abs() < 0.1, "{sn:?}");
        // (the centre of mass sits 0.3 m above the ground on its gear)
        let alt = f64::from(sn.pressure_alt);
        assert!((10.0..10.6).contains(&alt), "{sn:?}");
        assert!((f64::from(sn.temperature) - 14.94).abs() < 0.1, "{sn:?}");
    }
    // the heading of the ground start is the field's angle in the body
    let psi = r.final_state.unwrap()[ix::PSI];
    let mag_heading = (-f64::from(first.ymag)).atan2(f64::from(first.xmag));
    let decl = 0.0113f64.atan2(0.1615);
    let d = (mag_heading + decl - psi).rem_euclid(std::f64::consts::TAU);
    assert!(
        d.min(std::f64::consts::TAU - d) < 0.01,
        "{mag_heading} {psi}"
    );
    // nothing before the first sensors; GPS, ground truth and heartbeat
    // follow each step's HIL_SENSOR (read with the next step's)
    assert!(firsts.is_empty(), "{firsts:?}");
    let gps = others
        .iter()
        .find_map(|m| match m {
            MavMessage::HIL_GPS(g) => Some(g.clone()),
            _ => None,
        })
        .expect("HIL_GPS with the first step");
    assert_eq!(gps.time_usec, 0);
    assert_eq!(gps.fix_type, 3);
    assert!(gps.satellites_visible >= 6);
    assert!(
        (gps.lat - 570_140_000).abs() < 20 && (gps.lon - 99_870_000).abs() < 20,
        "{gps:?}"
    );
    assert!((10_000..10_600).contains(&gps.alt), "{gps:?}");
    let count = |f: fn(&MavMessage) -> bool| others.iter().filter(|m| f(m)).count();
    // 10 Hz GPS at t = 0, 0.1, … 1.9 s read (the one at 2.0 s follows the last sensors)
    assert_eq!(count(|m| matches!(m, MavMessage::HIL_GPS(_))), 20);
    assert_eq!(
        count(|m| matches!(m, MavMessage::HIL_STATE_QUATERNION(_))),
        500
    );
    assert_eq!(count(|m| matches!(m, MavMessage::HEARTBEAT(_))), 2);
    assert_eq!(r.counts.gps_messages, 21);
    // sitting: still on the ground, rotor stopped
    let x0 = Hardware0::initial(&s, &p);
    let x = r.final_state.unwrap();
    for i in [ix::X, ix::Y, ix::Z] {
        assert!((x[i] - x0[i]).abs() < 0.02, "{i}: {} vs {}", x[i], x0[i]);
    }
    assert!(r.rotor_speed_rad_s.unwrap().abs() < 1.0);
}

/// The initial state of a session.
struct Hardware0;
impl Hardware0 {
    fn initial(s: &Scenario, p: &Prepared) -> helicon_model::State {
        let hw = helicon_sim::closed_loop::Hardware::new_at(s, p, 0.01).unwrap();
        *hw.state()
    }
}

/// In the air at the trim, PX4's controls for the trim hold the hover
/// (accel ≈ (0, 0, −g)); a tail step to the right turns the nose right:
/// a positive yaw rate in gyro z (FRD), the truth's r.
#[test]
fn a_tail_step_shows_in_gyro_z() {
    let (s, p) = air();
    let m = map(&p);
    let trim = m.outputs_for(&p.trim.u, 1.0);
    let (r, (hover, turned)) = serve(&s, &p, bounded(400), |to| {
        let mut px4 = Px4::connect(to);
        let _ = px4.sensor();
        let mut hover = None;
        let mut turned = None;
        for k in 1..=400 {
            let mut o = trim;
            if k > 100 {
                o.tail = trim.tail + 0.3;
            }
            px4.controls(px4_controls(&o), true);
            let (sn, _) = px4.sensor();
            if k == 100 {
                hover = Some(sn.clone());
            }
            turned = Some(sn);
        }
        (hover.unwrap(), turned.unwrap())
    });
    assert_eq!(r.counts.armed_messages, 400);
    assert!((f64::from(hover.zacc) + G).abs() < 0.5, "{hover:?}");
    assert!(f64::from(hover.zgyro).abs() < 0.05, "{hover:?}");
    let rate = f64::from(turned.zgyro);
    assert!(rate > 0.1, "yaw rate {rate} rad/s");
    let x = r.final_state.unwrap();
    assert!(
        (rate - x[ix::R]).abs() < 1e-3,
        "{rate} vs truth {}",
        x[ix::R]
    );
}

/// Junk bytes, a frame with a broken checksum and one of an unknown
/// message id are counted by kind and ignored: only the valid actuator
/// messages step.
#[test]
fn malformed_bytes_are_counted_and_ignored() {
    let (s, p) = ground();
    let (r, bad_len) = serve(&s, &p, bounded(2), |to| {
        let mut px4 = Px4::connect(to);
        let _ = px4.sensor();
        px4.stream
            .write_all(&[0x01, 0x02, 0x03, 0x04, 0x05])
            .unwrap();
        // a valid HIL_ACTUATOR_CONTROLS with its checksum broken
        let mut frame = Vec::new();
        write_v2_msg(
            &mut frame,
            MavHeader {
                system_id: 1,
                component_id: 1,
                sequence: 7,
            },
            &MavMessage::HIL_ACTUATOR_CONTROLS(HIL_ACTUATOR_CONTROLS_DATA {
                time_usec: 0x1122_3344,
                flags: HilActuatorControlsFlags::empty(),
                controls: [0.25; CHANNELS],
                mode: MavModeFlag::empty(),
            }),
        )
        .unwrap();
        let n = frame.len();
        frame[n - 1] ^= 0x5A;
        assert!(
            !frame[1..].iter().any(|&b| b == 0xFD || b == 0xFE),
            "the test frame must not hold a start marker"
        );
        px4.stream.write_all(&frame).unwrap();
        // a MAVLink 2 frame of message id 0x0ABCDE (no such message)
        px4.stream
            .write_all(&[0xFD, 2, 0, 0, 0, 1, 1, 0xDE, 0xBC, 0x0A, 9, 9, 0x12, 0x34])
            .unwrap();
        px4.controls([0.0; CHANNELS], false);
        let (a, _) = px4.sensor();
        assert_eq!(a.time_usec, 4000);
        px4.controls([0.0; CHANNELS], false);
        let (b, _) = px4.sensor();
        assert_eq!(b.time_usec, 8000);
        n
    });
    assert_eq!(r.counts.steps, 2);
    // the junk, and the broken frame after its start marker (resynchronizing)
    assert_eq!(
        r.counts.junk_bytes as usize,
        5 + bad_len - 1,
        "{:?}",
        r.counts
    );
    assert_eq!(r.counts.bad_crc, 1, "{:?}", r.counts);
    assert_eq!(r.counts.unknown_id, 1, "{:?}", r.counts);
}

/// A silent autopilot stops the clock: after 10 steps and silence, the
/// run ends (silence timeout) with 10 steps of model time, no more.
#[test]
fn silence_advances_nothing() {
    let (s, p) = ground();
    let options = Px4Options {
        silence_timeout: Some(Duration::from_millis(300)),
        free_run_until_first_actuator: false,
        ..Px4Options::default()
    };
    let (r, px4) = serve(&s, &p, options, |to| {
        let mut px4 = Px4::connect(to);
        let _ = px4.sensor();
        for _ in 0..10 {
            px4.controls([0.0; CHANNELS], false);
            let _ = px4.sensor();
        }
        px4 // kept open, silent, until the run ended
    });
    drop(px4);
    assert_eq!(r.ending, Ending::Silent);
    assert_eq!(r.counts.steps, 10);
    assert!((r.model_time_s - 0.04).abs() < 1e-12, "{}", r.model_time_s);
}

/// A reconnection (PX4 restarted) starts the simulation again from its
/// initial state: the first sensors of the new connection are those of
/// the first, at time_usec 0.
#[test]
fn a_reconnection_resets_the_vehicle() {
    let (s, p) = air();
    let (r, (first_a, moved, first_b)) = serve(&s, &p, bounded(300 + 20), |to| {
        let mut a = Px4::connect(to);
        let (first_a, _) = a.sensor();
        // disarmed in the air: the rotor is cut, the helicopter falls
        let mut moved = first_a.clone();
        for _ in 0..300 {
            a.controls([0.0; CHANNELS], false);
            moved = a.sensor().0;
        }
        drop(a);
        let mut b = Px4::connect(to);
        let (first_b, _) = b.sensor();
        for _ in 0..20 {
            b.controls([0.0; CHANNELS], false);
            let _ = b.sensor();
        }
        (first_a, moved, first_b)
    });
    assert_eq!(r.counts.connections, 2);
    assert_eq!(r.session_steps, 20);
    assert_eq!(moved.time_usec, 300 * 4000);
    assert!(
        (moved.pressure_alt - first_a.pressure_alt).abs() > 0.5,
        "{moved:?}"
    );
    assert_eq!(first_b.time_usec, 0);
    assert_eq!(first_b, first_a);
}

/// Before PX4's first actuator message the model free-runs on the wall
/// clock (the default), one sensor step per period, disarmed; from the
/// first actuator message on it is lock-step: each answer one step, and
/// silence stops the clock.
#[test]
fn free_running_until_the_first_actuator_message_then_lock_step() {
    let (s, p) = ground();
    let options = Px4Options {
        silence_timeout: Some(Duration::from_millis(300)),
        ..Px4Options::default()
    };
    let (r, (times, _open)) = serve(&s, &p, options, |to| {
        let mut px4 = Px4::connect(to);
        // no answer: the sensors keep coming, 4000 µs apart
        let mut times = Vec::new();
        for _ in 0..4 {
            times.push(px4.sensor().0.time_usec);
        }
        // answering: the next steps follow, one per answer
        for _ in 0..5 {
            px4.controls([0.0; CHANNELS], false);
            times.push(px4.sensor().0.time_usec);
        }
        (times, px4) // kept open, silent, until the run ended
    });
    // every sensor step read in order, 4000 µs apart, free or answered
    for w in times.windows(2) {
        assert_eq!(w[1] - w[0], 4000, "{times:?}");
    }
    assert_eq!(r.ending, Ending::Silent);
    assert!(r.counts.free_steps >= 3, "{:?}", r.counts);
    assert_eq!(r.counts.steps, r.counts.free_steps + 5, "{:?}", r.counts);
    // the last read: the last step, or the one before it when a free step
    // was in flight as the first answer went out (its answer then unread)
    let last = times[times.len() - 1];
    let n = r.counts.steps;
    assert!(last == n * 4000 || last == (n - 1) * 4000, "{times:?} {n}");
}
