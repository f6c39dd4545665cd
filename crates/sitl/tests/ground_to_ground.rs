//! From the ground to the ground with a ground station, lock-step SITL:
//! `helicon sitl --gcs`'s path (pseudo-terminal devices, the on-board
//! threads, the MAVLink server on loopback UDP) with the scenario put on the
//! ground ([`sitl::ground_start`]). A MAVLink client (the `mavlink` crate,
//! as a ground station speaks) waits a random 5–60 s of the vehicle's time
//! on the ground, uploads a mission (take-off, two waypoints, return),
//! arms, starts it at once (the take-off waits for the rotor), sees the
//! landing and the disarm, waits 30 s more and finds the helicopter on the
//! ground, upright, within 2 m of home — over several seeds (the wait, the
//! wind's gusts and the sensors' noise). The first seed then flies again:
//! arm, take off, land.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

mod common;

use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{Connectable, Connection, MavConnection, MavHeader, UdpConfig, UdpMode};
use helicon_model::state::ix;
use helicon_sim::closed_loop::{Termination, prepare_with_params};
use helicon_sim::scenario::Scenario;
use helicon_sitl as sitl;
use std::net::UdpSocket;
use std::time::{Duration, Instant};

/// The physical Bergen Twin with the whole estimation chain in a light
/// gusty wind; the navigator owns the heading.
fn scenario(seed: u64, duration_s: f64) -> Scenario {
    let text = format!(
        r#"
name = "ground-gcs-{seed}"
preset = "physical"
duration_s = {duration_s}

[wind]
seed = {seed}

[wind.steady]
wind_ned_m_s = [1.0, 0.5, 0.0]

[wind.dryden]
w20_m_s = 3.0
altitude_m = 10.0
airspeed_m_s = 2.0

[sensors]
seed = {seed}

[controller]
input_max = [0.1, 0.7, 0.7, 0.4]
estimator = true
fusion = true

[log]
decimation = 4
"#
    );
    Scenario::from_toml_str(&text, "ground-gcs.toml").unwrap()
}

struct Client {
    conn: Connection<MavMessage>,
    /// The vehicle's last on-board time (s).
    t_s: f64,
    landed_state: Option<MavLandedState>,
    armed: Option<bool>,
    texts: Vec<String>,
    last_hb: Instant,
}

impl Client {
    fn send(&self, msg: &MavMessage) {
        let h = MavHeader {
            system_id: 255,
            component_id: 190,
            sequence: 0,
        };
        self.conn.send(&h, msg).unwrap();
    }

    fn heartbeat(&mut self) {
        if self.last_hb.elapsed() > Duration::from_millis(5) {
            self.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                custom_mode: 0,
                mavtype: MavType::MAV_TYPE_GCS,
                autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
                base_mode: MavModeFlag::empty(),
                system_status: MavState::MAV_STATE_ACTIVE,
                mavlink_version: 3,
            }));
            self.last_hb = Instant::now();
        }
    }

    /// One message (or none within 1 ms), its state kept.
    fn poll(&mut self) -> Option<MavMessage> {
        self.heartbeat();
        match self.conn.try_recv() {
            Ok((h, m)) if h.system_id == 1 => {
                match &m {
                    MavMessage::ATTITUDE(a) => self.t_s = f64::from(a.time_boot_ms) * 1e-3,
                    MavMessage::EXTENDED_SYS_STATE(e) => self.landed_state = Some(e.landed_state),
                    MavMessage::HEARTBEAT(hb) => {
                        self.armed = Some(
                            hb.base_mode
                                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
                        );
                    }
                    MavMessage::STATUSTEXT(s) => self.texts.push(
                        s.text
                            .to_str()
                            .unwrap_or("")
                            .trim_end_matches('\0')
                            .to_string(),
                    ),
                    _ => {}
                }
                Some(m)
            }
            _ => {
                std::thread::sleep(Duration::from_micros(500));
                None
            }
        }
    }

    /// Poll until `done` or `limit_s` of the vehicle's time (a wall-time
    /// guard of 120 s), `false` on the limit.
    fn until(&mut self, limit_s: f64, mut done: impl FnMut(&Client) -> bool) -> bool {
        let wall = Instant::now();
        let t_end = self.t_s + limit_s;
        while self.t_s < t_end && wall.elapsed() < Duration::from_secs(120) {
            if done(self) {
                return true;
            }
            self.poll();
        }
        done(self)
    }

    /// A COMMAND_LONG, sent until acknowledged (every 200 ms of wall time).
    fn command(&mut self, cmd: MavCmd, p1: f32, p7: f32) -> MavResult {
        let wall = Instant::now();
        let mut sent: Option<Instant> = None;
        while wall.elapsed() < Duration::from_secs(20) {
            if sent.is_none_or(|s| s.elapsed() > Duration::from_millis(200)) {
                self.send(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
                    param1: p1,
                    param7: p7,
                    command: cmd,
                    target_system: 1,
                    target_component: 1,
                    ..COMMAND_LONG_DATA::default()
                }));
                sent = Some(Instant::now());
            }
            if let Some(MavMessage::COMMAND_ACK(a)) = self.poll()
                && a.command == cmd
            {
                return a.result;
            }
        }
        panic!("no COMMAND_ACK for {cmd:?}");
    }

    /// Upload `items` (the mission microservice: count, each item on
    /// request, the ack).
    fn upload(&mut self, items: &[MISSION_ITEM_INT_DATA]) {
        let count = MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
            count: items.len() as u16,
            target_system: 1,
            target_component: 1,
            ..MISSION_COUNT_DATA::default()
        });
        self.send(&count);
        let wall = Instant::now();
        let mut resent = Instant::now();
        while wall.elapsed() < Duration::from_secs(20) {
            match self.poll() {
                Some(MavMessage::MISSION_REQUEST_INT(r)) => {
                    let mut item = items[usize::from(r.seq)].clone();
                    item.seq = r.seq;
                    self.send(&MavMessage::MISSION_ITEM_INT(item));
                }
                Some(MavMessage::MISSION_ACK(a)) => {
                    assert_eq!(a.mavtype, MavMissionResult::MAV_MISSION_ACCEPTED);
                    return;
                }
                _ => {
                    if resent.elapsed() > Duration::from_secs(2) {
                        self.send(&count);
                        resent = Instant::now();
                    }
                }
            }
        }
        panic!("mission upload not acknowledged");
    }
}

/// A mission item in the local NED frame about home (m).
fn item(command: MavCmd, n_m: f64, e_m: f64, height_m: f32) -> MISSION_ITEM_INT_DATA {
    MISSION_ITEM_INT_DATA {
        x: (n_m * 1e4) as i32,
        y: (e_m * 1e4) as i32,
        // a take-off's z is its height, a local waypoint's the NED down
        z: if command == MavCmd::MAV_CMD_NAV_TAKEOFF {
            height_m
        } else {
            -height_m
        },
        command,
        target_system: 1,
        target_component: 1,
        frame: MavFrame::MAV_FRAME_LOCAL_NED,
        autocontinue: 1,
        param4: f32::NAN,
        ..MISSION_ITEM_INT_DATA::default()
    }
}

/// One flight from the ground to the ground; the measured figures.
#[allow(clippy::too_many_lines)] // one flight, its checks in order
fn flight(seed: u64, again: bool) -> (f64, f64, f64) {
    // the wait on the ground before arming: 5-60 s, drawn from the seed
    let wait_s =
        5.0 + (seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as f64 / (1u64 << 53) as f64 * 55.0;
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = socket.local_addr().unwrap().port();
    let conn = UdpConfig::from_socket(socket, UdpMode::Udpin)
        .unwrap()
        .connect::<MavMessage>()
        .unwrap();
    let (s, params) = sitl::ground_start(&scenario(seed, wait_s + 230.0)).unwrap();
    let prepared = prepare_with_params(&s, params).unwrap();
    let mut opts = common::options(&format!("ground{seed}"));
    opts.keep_frames = false;
    opts.gcs = Some(format!("udpout:127.0.0.1:{port}"));
    let run = std::thread::spawn(move || {
        let r = sitl::run(&s, &prepared, &opts);
        let _ = std::fs::remove_dir_all(&opts.out_dir);
        r
    });
    let mut c = Client {
        conn,
        t_s: 0.0,
        landed_state: None,
        armed: None,
        texts: Vec::new(),
        last_hb: Instant::now() - Duration::from_secs(1),
    };
    // on the ground, disarmed, for the whole wait
    assert!(c.until(5.0, |c| c.landed_state.is_some() && c.armed.is_some()));
    let mut stayed = true;
    c.until(wait_s, |c| {
        stayed &= c.landed_state == Some(MavLandedState::MAV_LANDED_STATE_ON_GROUND)
            && c.armed == Some(false);
        false
    });
    assert!(
        stayed,
        "seed {seed}: left the ground disarmed: {:?}",
        c.texts
    );
    c.upload(&[
        item(MavCmd::MAV_CMD_NAV_TAKEOFF, 0.0, 0.0, 5.0),
        item(MavCmd::MAV_CMD_NAV_WAYPOINT, 12.0, 0.0, 5.0),
        item(MavCmd::MAV_CMD_NAV_WAYPOINT, 12.0, 8.0, 6.0),
        item(MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH, 0.0, 0.0, 0.0),
    ]);
    assert_eq!(
        c.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0),
        MavResult::MAV_RESULT_ACCEPTED
    );
    assert!(c.until(2.0, |c| c.armed == Some(true)));
    let t_arm = c.t_s;
    assert_eq!(
        c.command(MavCmd::MAV_CMD_MISSION_START, 0.0, 0.0),
        MavResult::MAV_RESULT_ACCEPTED
    );
    // the take-off waits for the rotor: in the air only after the run-up
    assert!(
        c.until(30.0, |c| c.landed_state
            == Some(MavLandedState::MAV_LANDED_STATE_IN_AIR)),
        "seed {seed}: never in the air: {:?}",
        c.texts
    );
    let t_air = c.t_s;
    assert!(
        t_air - t_arm >= 8.0,
        "lift-off {:.2} s after arming",
        t_air - t_arm
    );
    // the mission, the return, the landing and the disarm
    assert!(
        c.until(120.0, |c| c.armed == Some(false)),
        "seed {seed}: not disarmed: {:?}",
        c.texts
    );
    for want in [
        "engine on: rotor spooling up",
        "rotor at speed: ready for take-off",
        "lift-off",
        "mode RETURN",
        "touchdown: on the ground",
        "disarmed",
    ] {
        assert!(
            c.texts.iter().any(|t| t == want),
            "seed {seed}: no `{want}`: {:?}",
            c.texts
        );
    }
    // 30 s more on the ground: it stays there
    let mut stayed = true;
    c.until(30.0, |c| {
        stayed &= c.landed_state == Some(MavLandedState::MAV_LANDED_STATE_ON_GROUND)
            && c.armed == Some(false);
        false
    });
    assert!(stayed, "seed {seed}: left the ground after landing");
    assert!(!run.is_finished(), "seed {seed}: the run ended by itself");
    if again {
        // and again: arm, take off (it waits for the run-up), land
        assert_eq!(
            c.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0),
            MavResult::MAV_RESULT_ACCEPTED
        );
        assert!(c.until(2.0, |c| c.armed == Some(true)));
        assert_eq!(
            c.command(MavCmd::MAV_CMD_NAV_TAKEOFF, 0.0, f32::NAN),
            MavResult::MAV_RESULT_ACCEPTED
        );
        assert!(
            c.until(30.0, |c| c.landed_state
                == Some(MavLandedState::MAV_LANDED_STATE_IN_AIR)),
            "seed {seed}: the second take-off did not lift off: {:?}",
            c.texts
        );
        c.until(8.0, |_| false);
        assert_eq!(
            c.command(MavCmd::MAV_CMD_NAV_LAND, 0.0, 0.0),
            MavResult::MAV_RESULT_ACCEPTED
        );
        assert!(
            c.until(60.0, |c| c.armed == Some(false)),
            "seed {seed}: not disarmed after the second landing: {:?}",
            c.texts
        );
        c.until(5.0, |_| false);
        assert!(!run.is_finished(), "seed {seed}: the run ended by itself");
    }
    let r = loop {
        c.heartbeat();
        if run.is_finished() {
            break run.join().unwrap().unwrap();
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    assert_eq!(
        r.summary.termination,
        Termination::Completed,
        "{:?}",
        r.summary.reason
    );
    let x0 = r.initial_state;
    let x = r.final_state;
    let offset_m = ((x[ix::X] - x0[ix::X]).powi(2) + (x[ix::Y] - x0[ix::Y]).powi(2)).sqrt();
    let tilt_rad = x[ix::PHI].abs().max(x[ix::THETA].abs());
    // on the ground: the skids' height (the CM as at the start within 5 cm)
    let height_m = x0[ix::Z] - x[ix::Z];
    println!(
        "seed {seed}: waited {wait_s:.1} s, lift-off {:.2} s after arming, landed {offset_m:.2} m from home, tilt {:.3} rad, CM {height_m:.3} m above its start",
        t_air - t_arm,
        tilt_rad
    );
    assert!(
        offset_m < 2.0,
        "seed {seed}: landed {offset_m:.2} m from home"
    );
    assert!(tilt_rad < 0.1, "seed {seed}: not upright: {tilt_rad}");
    assert!(
        height_m.abs() < 0.05,
        "seed {seed}: not on the ground: {height_m}"
    );
    (offset_m, tilt_rad, t_air - t_arm)
}

#[test]
fn from_the_ground_to_the_ground_with_a_ground_station() {
    for seed in [1, 2, 3] {
        flight(seed, seed == 1);
    }
}
