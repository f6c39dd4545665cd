//! ArduPilot's JSON physics interface against a stand-in for ArduPilot's
//! SITL written from the protocol's definition (`libraries/SITL/SIM_JSON.cpp`
//! and `examples/JSON/readme.md`: the binary servo packet, the JSON line
//! answered to the sender) and from ArduPilot's heli mixer
//! (`AP_MotorsHeli_Swash::calculate`/`rc_write`,
//! `SRV_Channels::set_output_pwm_trimmed`, `SRV_Channel::pwm_from_angle`,
//! `pwm_from_range`), over a real UDP socket on 127.0.0.1 with an
//! OS-chosen port.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

use helicon_model::state::ix;
use helicon_sim::closed_loop::{Hardware, Prepared, prepare, prepare_with_params};
use helicon_sim::scenario::Scenario;
use helicon_sitl::ardupilot::{
    ArduPilotMap, ArduPilotOptions, ArduPilotReport, ArduPilotSection, AutopilotOutputs,
    BERGEN_TWIN_TOML, Ending, ServoPacket,
};
use helicon_sitl::ground_start;
use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// The physical Bergen Twin, no wind, in the air at its trim.
fn air() -> (Scenario, Prepared) {
    let s = Scenario::from_toml_str(
        "name = \"ardupilot-air\"\npreset = \"physical\"\nduration_s = 600.0\n",
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

fn map(p: &Prepared) -> ArduPilotMap {
    let section = ArduPilotSection::from_toml_str(BERGEN_TWIN_TOML, "bergen_twin.toml").unwrap();
    ArduPilotMap::new(section, p.model.params(), "bergen_twin.toml").unwrap()
}

/// ArduPilot's heli outputs for the example's H3-120 swash (servo positions
/// −60°, 60°, 180°, trims 1500, none reversed), tail on SERVO4 (1000 / 1500
/// / 2000) and throttle (HeliRSC) on SERVO8 (1000 … 2000): `roll`, `pitch`
/// in −1 … 1, `c` the swash servos' scaled collective, `yaw` −1 … 1,
/// `throttle` 0 … 1. Written from ArduPilot's code, not from helicon's.
fn ardupilot_pwm(o: &AutopilotOutputs) -> [u16; 16] {
    let mut pwm = [0u16; 16];
    for (i, pos) in [-60.0f64, 60.0, 180.0].into_iter().enumerate() {
        let a = pos.to_radians();
        let roll_f = 0.45 * (a + std::f64::consts::FRAC_PI_2).cos();
        let pitch_f = 0.45 * a.cos();
        let out = roll_f * o.roll + pitch_f * o.pitch + o.collective;
        let servo = 2.0 * out - 1.0;
        let nominal = (1500.0 + 500.0 * servo) as u16; // (uint16_t) truncates
        pwm[i] = (i32::from(nominal) - 1500 + 1500).clamp(1000, 2000) as u16;
    }
    let yaw = o.yaw.clamp(-1.0, 1.0);
    pwm[3] = if yaw > 0.0 {
        1500 + (yaw * 500.0) as u16
    } else {
        1500 - (-yaw * 500.0) as u16
    };
    pwm[7] = 1000 + (o.throttle.clamp(0.0, 1.0) * 1000.0) as u16;
    pwm
}

/// The stand-in for ArduPilot's SITL.
struct Autopilot {
    sock: UdpSocket,
    to: SocketAddr,
    rate_hz: u16,
    count: u32,
}

impl Autopilot {
    fn new(to: SocketAddr, rate_hz: u16) -> Autopilot {
        let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
        sock.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        Autopilot {
            sock,
            to,
            rate_hz,
            count: 0,
        }
    }

    fn packet(&self, count: u32, pwm: &[u16; 16]) -> Vec<u8> {
        let mut all = [0u16; 32];
        all[..16].copy_from_slice(pwm);
        ServoPacket {
            frame_rate_hz: self.rate_hz,
            frame_count: count,
            pwm: all,
            channels: 16,
        }
        .encode()
    }

    /// Send `bytes`, wait for the reply line; its raw text.
    fn exchange(&self, bytes: &[u8]) -> String {
        self.sock.send_to(bytes, self.to).unwrap();
        let mut buf = [0u8; 2048];
        let (n, from) = self.sock.recv_from(&mut buf).expect("a reply");
        assert_eq!(from, self.to, "answered from the physics' address");
        String::from_utf8(buf[..n].to_vec()).unwrap()
    }

    /// One new frame: the reply as JSON.
    fn frame(&mut self, pwm: &[u16; 16]) -> serde_json::Value {
        let text = self.exchange(&self.packet(self.count, pwm));
        self.count += 1;
        parse(&text)
    }

    /// `bytes` get no answer within 200 ms.
    fn ignored(&self, bytes: &[u8]) {
        self.sock
            .set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
        self.sock.send_to(bytes, self.to).unwrap();
        let mut buf = [0u8; 2048];
        assert!(self.sock.recv_from(&mut buf).is_err(), "no reply");
        self.sock
            .set_read_timeout(Some(Duration::from_secs(5)))
            .unwrap();
    }
}

/// A reply line: "\n{…}\n" as the readme says.
fn parse(text: &str) -> serde_json::Value {
    assert!(text.starts_with('\n') && text.ends_with('\n'), "{text:?}");
    let v: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
    for k in ["timestamp", "position", "velocity", "attitude"] {
        assert!(v.get(k).is_some(), "{k} in {text}");
    }
    assert!(v["imu"]["gyro"].is_array() && v["imu"]["accel_body"].is_array());
    v
}

fn vec3(v: &serde_json::Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [
        a[0].as_f64().unwrap(),
        a[1].as_f64().unwrap(),
        a[2].as_f64().unwrap(),
    ]
}

/// Run the physics on its own thread while `client` talks to it.
fn serve<T>(
    scenario: &Scenario,
    prepared: &Prepared,
    options: ArduPilotOptions,
    client: impl FnOnce(SocketAddr) -> T,
) -> (ArduPilotReport, T) {
    let server = helicon_sitl::ardupilot::ArduPilotServer::bind("127.0.0.1:0").unwrap();
    let addr = server.local_addr();
    let m = map(prepared);
    let stop = Arc::new(AtomicBool::new(false));
    let options = ArduPilotOptions {
        stop: Some(stop.clone()),
        silence_timeout: options.silence_timeout.or(Some(Duration::from_secs(20))),
        ..options
    };
    std::thread::scope(|sc| {
        let h = sc.spawn(|| server.run(scenario, prepared, &m, &options).unwrap());
        let out = client(addr);
        stop.store(true, Ordering::Relaxed);
        (h.join().unwrap(), out)
    })
}

/// The PWM ArduPilot outputs to fly the model's trim, engine on.
fn trim_pwm(p: &Prepared) -> [u16; 16] {
    ardupilot_pwm(&map(p).outputs_for(&p.trim.u, 0.7))
}

/// Disarmed on the ground: swash at its trim, collective low, throttle at its minimum.
fn disarmed_pwm(p: &Prepared) -> [u16; 16] {
    let mut o = map(p).outputs_for(&p.trim.u, 0.0);
    o.collective = map(p)
        .outputs_for(&helicon_core::state::Input::zeros(), 0.0)
        .collective;
    ardupilot_pwm(&o)
}

/// N distinct frames step the model by exactly N/rate, at 400 and 1200 Hz
/// (each reply's timestamp is k/rate to the last bit: the number is written
/// in its shortest round-trip form and read back by serde_json exactly).
#[test]
fn lock_step_frame_accounting_at_400_and_1200_hz() {
    let (s, p) = ground();
    for rate in [400u16, 1200] {
        let n = u32::from(rate) / 2;
        let pwm = disarmed_pwm(&p);
        let (r, ()) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
            let mut ap = Autopilot::new(addr, rate);
            for k in 1..=n {
                let v = ap.frame(&pwm);
                assert_eq!(
                    v["timestamp"].as_f64().unwrap(),
                    f64::from(k) / f64::from(rate),
                    "frame {k} at {rate} Hz"
                );
            }
        });
        assert_eq!(r.counts.frames, u64::from(n));
        assert_eq!(r.counts.replies, u64::from(n));
        assert_eq!(r.counts.malformed(), 0);
        assert_eq!(r.frame_rate_hz, Some(rate));
        assert_eq!(r.model_time_s, f64::from(n) / f64::from(rate));
        assert_eq!(r.ending, Ending::Stopped);
        eprintln!(
            "{rate} Hz: {} frames in {:.3} s: {:.0} frames/s, {:.1}x real time (lock-step, stand-in included)",
            r.counts.frames, r.wall_s, r.frames_per_s, r.speed_x
        );
    }
}

/// A repeated frame is answered with the same state without a step; a
/// frame count going back restarts the simulation from the ground; the
/// malformed packets (wrong size, wrong magic, frame rate 0 and absurd,
/// PWM beyond 3000) are counted and get no answer; a 32-channel packet
/// (magic 29569) is read like a 16-channel one.
#[test]
fn repeated_restarted_and_malformed_frames() {
    let (s, p) = ground();
    let pwm = trim_pwm(&p);
    let (r, ()) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
        let mut ap = Autopilot::new(addr, 400);
        let mut last = String::new();
        for _ in 0..10 {
            last = ap.exchange(&ap.packet(ap.count, &pwm));
            ap.count += 1;
        }
        // frame 9 again: the same line, bit for bit
        let again = ap.exchange(&ap.packet(9, &pwm));
        assert_eq!(again, last);
        assert_eq!(parse(&again)["timestamp"].as_f64().unwrap(), 10.0 / 400.0);
        // malformed
        let good = ap.packet(10, &pwm);
        ap.ignored(&good[..39]);
        ap.ignored(&[good.clone(), vec![0, 0]].concat());
        let mut b = good.clone();
        b[0..2].copy_from_slice(&29569u16.to_le_bytes()); // 32-channel magic in 40 bytes
        ap.ignored(&b);
        let mut b = good.clone();
        b[0..2].copy_from_slice(&1234u16.to_le_bytes());
        ap.ignored(&b);
        for rate in [0u16, 65535] {
            let mut b = good.clone();
            b[2..4].copy_from_slice(&rate.to_le_bytes());
            ap.ignored(&b);
        }
        let mut b = good.clone();
        b[8..10].copy_from_slice(&3001u16.to_le_bytes());
        ap.ignored(&b);
        ap.ignored(&[]);
        // the next good frame steps once: nothing of the bad ones counted
        let v = parse(&ap.exchange(&good));
        assert_eq!(v["timestamp"].as_f64().unwrap(), 11.0 / 400.0);
        // 32 channels
        let mut all = [0u16; 32];
        all[..16].copy_from_slice(&pwm);
        let b32 = ServoPacket {
            frame_rate_hz: 400,
            frame_count: 11,
            pwm: all,
            channels: 32,
        }
        .encode();
        let v = parse(&ap.exchange(&b32));
        assert_eq!(v["timestamp"].as_f64().unwrap(), 12.0 / 400.0);
        // ArduPilot restarted: frame 0 again, from the ground start
        let v = parse(&ap.exchange(&ap.packet(0, &pwm)));
        assert_eq!(v["timestamp"].as_f64().unwrap(), 1.0 / 400.0);
        let v = parse(&ap.exchange(&ap.packet(1, &pwm)));
        assert_eq!(v["timestamp"].as_f64().unwrap(), 2.0 / 400.0);
    });
    let c = r.counts;
    assert_eq!(c.frames, 12 + 2);
    assert_eq!(c.repeats, 1);
    assert_eq!(c.restarts, 1);
    assert_eq!(c.bad_size, 3);
    assert_eq!(c.bad_magic, 2);
    assert_eq!(c.bad_frame_rate, 2);
    assert_eq!(c.bad_pwm, 1);
    assert_eq!(r.session_frames, 2);
    assert_eq!(r.model_time_s, 2.0 / 400.0);
}

/// A silent autopilot: no time passes while it is silent; the wait ends on
/// the stop flag, or after the silence timeout.
#[test]
fn a_silent_autopilot_stops_the_clock() {
    let (s, p) = ground();
    let pwm = disarmed_pwm(&p);
    let (r, ()) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
        let mut ap = Autopilot::new(addr, 400);
        for _ in 0..5 {
            ap.frame(&pwm);
        }
        std::thread::sleep(Duration::from_millis(400));
        let v = ap.frame(&pwm);
        assert_eq!(v["timestamp"].as_f64().unwrap(), 6.0 / 400.0);
    });
    assert_eq!((r.counts.frames, r.ending), (6, Ending::Stopped));
    // no autopilot at all: the silence timeout ends the run, nothing stepped
    let (r, ()) = serve(
        &s,
        &p,
        ArduPilotOptions {
            silence_timeout: Some(Duration::from_millis(300)),
            ..ArduPilotOptions::default()
        },
        |_| std::thread::sleep(Duration::from_millis(1000)),
    );
    assert_eq!((r.counts.frames, r.ending), (0, Ending::Silent));
    assert!(r.summary.is_none());
}

/// Sitting on the ground disarmed (throttle at its minimum) for 10 s at
/// 400 Hz: the skids do not creep (position within 1 mm, heading within
/// 1e-4 rad from 1 s to 10 s: the gear's friction anchors hold), the rotor
/// stays still, and the accelerometer reads (0, 0, −g) within 0.02 m/s²
/// (the gear's spring settles within the first second).
#[test]
fn on_the_ground_disarmed_it_does_not_creep() {
    let (s, p) = ground();
    let g = p.model.params().environment.g_m_s2;
    let pwm = disarmed_pwm(&p);
    let (r, (at1, at10)) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
        let mut ap = Autopilot::new(addr, 400);
        let mut at1 = None;
        let mut last = None;
        for k in 1..=4000 {
            let v = ap.frame(&pwm);
            if k == 400 {
                at1 = Some(v.clone());
            }
            last = Some(v);
        }
        (at1.unwrap(), last.unwrap())
    });
    let (p1, p10) = (vec3(&at1["position"]), vec3(&at10["position"]));
    for i in 0..3 {
        assert!((p10[i] - p1[i]).abs() < 1e-3, "creeps: {p1:?} → {p10:?}");
    }
    assert!(p10[2] < 0.0, "the centre of mass above the ground: {p10:?}");
    let (a1, a10) = (vec3(&at1["attitude"]), vec3(&at10["attitude"]));
    assert!((a10[2] - a1[2]).abs() < 1e-4, "turns: {a1:?} → {a10:?}");
    let f = vec3(&at10["imu"]["accel_body"]);
    assert!(
        f[0].abs() < 0.02 && f[1].abs() < 0.02 && (f[2] + g).abs() < 0.02,
        "{f:?}"
    );
    assert_eq!(r.rotor_speed_rad_s, Some(0.0));
}

/// In the air at the trim's PWM (quantized to ArduPilot's 1 µs and its
/// truncation): the hover. The Bergen Twin hovers rolled by its trim's φ
/// (about 3°: the main rotor's tilt balances the tail rotor's thrust), so
/// the accelerometer reads gravity's opposite in body axes, `g·(sin θ,
/// −sin φ cos θ, −cos φ cos θ)`, within 0.05 m/s² (the state at rest in
/// the air: no acceleration), |f| = g within 0.05 m/s², and the rates stay
/// below 0.01 rad/s at the start. It holds for 1 s (open loop — the hover
/// is not stable without a controller): attitude within 1° of the trim's,
/// speed within 0.2 m/s.
#[test]
fn a_trim_pwm_hover_holds() {
    let (s, p) = air();
    let g = p.model.params().environment.g_m_s2;
    let pwm = trim_pwm(&p);
    let (_, (first, last)) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
        let mut ap = Autopilot::new(addr, 400);
        let first = ap.frame(&pwm);
        let mut last = first.clone();
        for _ in 1..400 {
            last = ap.frame(&pwm);
        }
        (first, last)
    });
    let f = vec3(&first["imu"]["accel_body"]);
    let a0 = vec3(&first["attitude"]);
    let (phi, theta) = (a0[0], a0[1]);
    let expected = [
        g * theta.sin(),
        -g * phi.sin() * theta.cos(),
        -g * phi.cos() * theta.cos(),
    ];
    for i in 0..3 {
        assert!((f[i] - expected[i]).abs() < 0.05, "{f:?} vs {expected:?}");
    }
    let norm = f.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((norm - g).abs() < 0.05, "|f| = {norm}");
    for v in [&first, &last] {
        let w = vec3(&v["imu"]["gyro"]);
        let a = vec3(&v["attitude"]);
        let vel = vec3(&v["velocity"]);
        eprintln!("hover: gyro {w:?} attitude {a:?} velocity {vel:?} accel {f:?}");
        assert!((a[0] - phi).abs() < 1f64.to_radians() && (a[1] - theta).abs() < 1f64.to_radians());
        assert!(vel.iter().map(|x| x * x).sum::<f64>().sqrt() < 0.2);
    }
    let w = vec3(&first["imu"]["gyro"]);
    assert!(w.iter().all(|x| x.abs() < 0.01), "{w:?}");
}

/// From the trim in the air, ArduPilot's yaw output +0.2 (nose right)
/// shows in `gyro.z` as a positive rate within 0.2 s, and the heading
/// turns the same way.
#[test]
fn a_yaw_command_shows_in_gyro_z_with_its_sign() {
    let (s, p) = air();
    let m = map(&p);
    let mut o = m.outputs_for(&p.trim.u, 0.7);
    o.yaw += 0.2;
    let pwm = ardupilot_pwm(&o);
    let (_, (v0, v)) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
        let mut ap = Autopilot::new(addr, 400);
        let v0 = ap.frame(&pwm);
        let mut v = v0.clone();
        for _ in 1..80 {
            v = ap.frame(&pwm);
        }
        (v0, v)
    });
    let r = vec3(&v["imu"]["gyro"])[2];
    eprintln!("yaw +0.2 for 0.2 s: gyro.z = {r:.4} rad/s");
    assert!(r > 0.05, "gyro.z = {r}");
    assert!(vec3(&v["attitude"])[2] > vec3(&v0["attitude"])[2]);
}

/// A roll step of ArduPilot's output (+0.1 from the trim at t = 0.1 s,
/// through the H3-120 mixer and 1 µs PWM): roll right (φ, p > 0), and φ(t)
/// matches the simulator's own hardware (`helicon sim`'s plant, wind and
/// ground) flown in-process with the same command as the model's inputs
/// — without PWM — within 2 % of the peak |φ| + 1e-4 rad over 0.6 s: the
/// difference is the PWM's quantization (±0.5 µs of 500 µs per unit of
/// servo travel: about 0.3 % of a 0.1 step on each servo).
#[test]
fn a_cyclic_step_matches_the_model() {
    let (s, p) = air();
    let m = map(&p);
    let trim = m.outputs_for(&p.trim.u, 0.7);
    let mut step = trim;
    step.roll += 0.1;
    let rate = 400u16;
    let n = 240;
    let on = 40;
    let (_, phis) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
        let mut ap = Autopilot::new(addr, rate);
        (0..n)
            .map(|k| {
                let o = if k < on { &trim } else { &step };
                let v = ap.frame(&ardupilot_pwm(o));
                (vec3(&v["attitude"])[0], vec3(&v["imu"]["gyro"])[0])
            })
            .collect::<Vec<_>>()
    });
    let mut hw = Hardware::new_at(&s, &p, 1.0 / f64::from(rate))
        .unwrap()
        .without_heading_check();
    let mut model = Vec::new();
    for k in 0..n {
        hw.sense().unwrap();
        let u = m.input_from(if k < on { &trim } else { &step });
        hw.actuate(&u, None).unwrap();
        model.push(hw.state()[ix::PHI]);
    }
    let peak = model.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let worst = phis
        .iter()
        .zip(&model)
        .map(|((a, _), b)| (a - b).abs())
        .fold(0.0f64, f64::max);
    let (phi_end, p_end) = phis[n - 1];
    eprintln!(
        "roll step +0.1: φ after 0.5 s {phi_end:.4} rad (model {:.4}), p {p_end:.4} rad/s; worst |Δφ| {worst:.2e} rad, peak {peak:.4} rad",
        model[n - 1]
    );
    assert!(
        phi_end > 0.0 && p_end > 0.0,
        "rolls right: {phi_end} {p_end}"
    );
    assert!(worst <= 0.02 * peak + 1e-4, "{worst} vs peak {peak}");
}

/// The mixer inverted: ArduPilot's own forward mixer (written here from its
/// code) for a grid of roll, pitch, collective, yaw and throttle reads back
/// within the PWM's resolution (1 µs of 500 µs per unit of servo travel,
/// through a 0.45 × 0.866 cyclic factor: 0.003 in roll and pitch, 0.001 in
/// collective, 0.002 in yaw).
#[test]
fn the_decoder_inverts_ardupilots_mixer() {
    let (_, p) = air();
    let m = map(&p);
    for roll in [-0.5, -0.1, 0.0, 0.3] {
        for pitch in [-0.4, 0.0, 0.2] {
            for c in [0.3, 0.5, 0.7] {
                for yaw in [-0.5, 0.0, 0.25] {
                    let o = AutopilotOutputs {
                        roll,
                        pitch,
                        collective: c,
                        yaw,
                        throttle: 0.7,
                    };
                    let d = m.decode(&ardupilot_pwm(&o));
                    let e = d.outputs;
                    assert!((e.roll - roll).abs() < 3e-3, "{o:?} → {e:?}");
                    assert!((e.pitch - pitch).abs() < 3e-3, "{o:?} → {e:?}");
                    assert!((e.collective - c).abs() < 1e-3, "{o:?} → {e:?}");
                    assert!((e.yaw - yaw).abs() < 2e-3, "{o:?} → {e:?}");
                    assert!((e.throttle - 0.7).abs() < 1e-3);
                    assert!(d.engine_on);
                }
            }
        }
    }
    let off = m.decode(&ardupilot_pwm(&AutopilotOutputs::default()));
    assert!(!off.engine_on);
    // the trim survives the round trip through PWM within the model's resolution
    let back = m.decode(&trim_pwm(&p)).input;
    for i in 0..4 {
        assert!(
            (back[i] - p.trim.u[i]).abs() < 2e-3,
            "{i}: {back} vs {}",
            p.trim.u
        );
    }
}

/// ArduPilot's pitch output +0.1 (nose up) from the trim: θ and `gyro.y`
/// positive within 0.3 s.
#[test]
fn a_pitch_command_pitches_nose_up() {
    let (s, p) = air();
    let mut o = map(&p).outputs_for(&p.trim.u, 0.7);
    o.pitch += 0.1;
    let pwm = ardupilot_pwm(&o);
    let (_, (v0, v)) = serve(&s, &p, ArduPilotOptions::default(), |addr| {
        let mut ap = Autopilot::new(addr, 400);
        let v0 = ap.frame(&pwm);
        let mut v = v0.clone();
        for _ in 1..120 {
            v = ap.frame(&pwm);
        }
        (v0, v)
    });
    let q = vec3(&v["imu"]["gyro"])[1];
    let dtheta = vec3(&v["attitude"])[1] - vec3(&v0["attitude"])[1];
    eprintln!("pitch +0.1 for 0.3 s: gyro.y = {q:.4} rad/s, θ change {dtheta:.4} rad");
    assert!(q > 0.0 && dtheta > 0.0, "{q} {dtheta}");
}
