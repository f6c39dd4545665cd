//! From the ground to the ground through ArduPilot's JSON interface, with a
//! small autopilot stand-in in the loop (not ArduPilot's firmware: a few
//! lines of attitude, rate and vertical-speed feedback acting through
//! ArduPilot's heli mixer and PWM, as ArduPilot's outputs would): disarmed
//! on the skids 1 s, the throttle (HeliRSC) to 70 % — the model's engine
//! starts and its governor spools the rotor up —, 8 s of run-up on the
//! ground, a climb at 1 m/s for 3 s, a hover, a descent at 0.5 m/s to the
//! ground, the throttle cut. It checks what ArduPilot would see through the
//! protocol: the helicopter stays put while the rotor spools up, lifts off,
//! climbs about 3 m, lands upright within 1 m of where it started, and the
//! rotor winds down after the cut.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

use helicon_sim::closed_loop::prepare_with_params;
use helicon_sim::scenario::Scenario;
use helicon_sitl::ardupilot::{
    ArduPilotMap, ArduPilotOptions, ArduPilotSection, ArduPilotServer, AutopilotOutputs,
    BERGEN_TWIN_TOML, ServoPacket,
};
use std::net::UdpSocket;
use std::time::Duration;

/// ArduPilot's outputs as PWM (H3-120, trims 1500, tail 1000/1500/2000 on
/// SERVO4, HeliRSC 1000 … 2000 on SERVO8), from ArduPilot's mixer.
fn pwm(o: &AutopilotOutputs) -> [u16; 32] {
    let mut pwm = [0u16; 32];
    for (i, pos) in [-60.0f64, 60.0, 180.0].into_iter().enumerate() {
        let a = pos.to_radians();
        let out = 0.45 * ((a + std::f64::consts::FRAC_PI_2).cos() * o.roll + a.cos() * o.pitch)
            + o.collective;
        pwm[i] = ((1500.0 + 500.0 * (2.0 * out - 1.0)) as u16).clamp(1000, 2000);
    }
    let yaw = o.yaw.clamp(-1.0, 1.0);
    pwm[3] = (1500.0 + 500.0 * yaw) as u16;
    pwm[7] = 1000 + (o.throttle.clamp(0.0, 1.0) * 1000.0) as u16;
    pwm
}

/// The stand-in's gains: attitude (rad/s per rad), rate damping, heading,
/// yaw-rate damping (per unit of the model's rate per output, 2.1 and 20 rad/s).
const KA: f64 = 2.5;
const KR: f64 = 0.2;
const KPSI: f64 = 4.0;
const KYR: f64 = 8.0;

fn vec3(v: &serde_json::Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [
        a[0].as_f64().unwrap(),
        a[1].as_f64().unwrap(),
        a[2].as_f64().unwrap(),
    ]
}

/// Every second of the flight's trace (time, NED position, attitude).
type Trace = [(f64, [f64; 3], [f64; 3])];

fn print_trace(trace: &Trace) {
    for (t, pos, att) in trace.iter().step_by(10) {
        eprintln!(
            "t {t:5.1} s  NED [{:7.3} {:7.3} {:7.3}] m  att [{:6.3} {:6.3} {:6.3}] rad",
            pos[0], pos[1], pos[2], att[0], att[1], att[2]
        );
    }
}

#[test]
fn arm_spool_up_take_off_hover_land_through_the_protocol() {
    let air = Scenario::from_toml_str(
        "name = \"ardupilot-flight\"\npreset = \"physical\"\nduration_s = 600.0\n",
        "test",
    )
    .unwrap();
    let (s, params) = helicon_sitl::ground_start(&air).unwrap();
    let p = prepare_with_params(&s, params).unwrap();
    let section = ArduPilotSection::from_toml_str(BERGEN_TWIN_TOML, "b.toml").unwrap();
    let map = ArduPilotMap::new(section, p.model.params(), "b.toml").unwrap();
    let trim = map.outputs_for(&p.trim.u, 0.7);
    let (phi_trim, theta_trim) = (
        p.trim.x[helicon_model::state::ix::PHI],
        p.trim.x[helicon_model::state::ix::THETA],
    );
    let server = ArduPilotServer::bind("127.0.0.1:0").unwrap();
    let to = server.local_addr();
    let options = ArduPilotOptions {
        silence_timeout: Some(Duration::from_secs(2)),
        ..ArduPilotOptions::default()
    };
    let rate = 400.0;
    let (report, trace) = std::thread::scope(|sc| {
        let h = sc.spawn(|| server.run(&s, &p, &map, &options).unwrap());
        let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
        sock.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let mut buf = [0u8; 2048];
        let mut state: Option<serde_json::Value> = None;
        let mut trace = Vec::new();
        let mut vd_ref_int = 0.0;
        let mut yaw_hold = None;
        let mut yaw_int = 0.0;
        let mut vel_int = [0.0f64; 2];
        let mut start: Option<[f64; 3]> = None;
        for k in 0..(32.0 * rate) as u32 {
            let t = f64::from(k) / rate;
            // the flight plan
            let throttle = if (1.0..29.0).contains(&t) { 0.7 } else { 0.0 };
            let vd_ref = if (9.0..12.0).contains(&t) {
                -1.0
            } else if (15.0..24.0).contains(&t) {
                0.5
            } else {
                0.0
            };
            let mut o = AutopilotOutputs { throttle, ..trim };
            if let Some(v) = &state {
                let att = vec3(&v["attitude"]);
                let gyro = vec3(&v["imu"]["gyro"]);
                let vel = vec3(&v["velocity"]);
                let flying = (9.0..24.0).contains(&t);
                if flying {
                    // position and velocity held: the angles' references
                    let p_now = vec3(&v["position"]);
                    let home = *start.get_or_insert(p_now);
                    let vn_ref = -0.4 * (p_now[0] - home[0]);
                    let ve_ref = -0.4 * (p_now[1] - home[1]);
                    let (en, ee) = (vel[0] - vn_ref, vel[1] - ve_ref);
                    let (c, sn) = (att[2].cos(), att[2].sin());
                    let (ex, ey) = (c * en + sn * ee, -sn * en + c * ee);
                    vel_int[0] += ex / rate;
                    vel_int[1] += ey / rate;
                    let phi_ref = phi_trim - 0.08 * ey - 0.03 * vel_int[1];
                    let theta_ref = theta_trim + 0.08 * ex + 0.03 * vel_int[0];
                    // attitude, the rates damped
                    o.roll = trim.roll + (KA * (phi_ref - att[0]) - KR * gyro[0]) / 2.1;
                    o.pitch = trim.pitch + (KA * (theta_ref - att[1]) - KR * gyro[1]) / 2.1;
                    // heading held, with an integrator
                    let psi0 = *yaw_hold.get_or_insert(att[2]);
                    let e_psi = att[2] - psi0;
                    yaw_int += e_psi / rate;
                    o.yaw = trim.yaw + (-KPSI * e_psi - 2.0 * yaw_int - KYR * gyro[2]) / 20.0;
                    // vertical speed: collective, with an integrator
                    let e = vel[2] - vd_ref;
                    vd_ref_int += e / rate;
                    o.collective = trim.collective + 0.05 * e + 0.05 * vd_ref_int;
                } else {
                    // on the ground: collective low, cyclic centred
                    o.collective = map
                        .outputs_for(&helicon_core::state::Input::zeros(), 0.0)
                        .collective;
                    yaw_hold = None;
                    yaw_int = 0.0;
                    vel_int = [0.0; 2];
                    vd_ref_int = 0.0;
                }
            }
            let pkt = ServoPacket {
                frame_rate_hz: 400,
                frame_count: k,
                pwm: pwm(&o),
                channels: 16,
            };
            sock.send_to(&pkt.encode(), to).unwrap();
            let (n, _) = sock.recv_from(&mut buf).unwrap();
            let v: serde_json::Value =
                serde_json::from_str(std::str::from_utf8(&buf[..n]).unwrap().trim()).unwrap();
            if k % 40 == 0 {
                trace.push((t, vec3(&v["position"]), vec3(&v["attitude"])));
            }
            state = Some(v);
        }
        let r = h.join().unwrap();
        (r, trace)
    });
    print_trace(&trace);
    let at = |time: f64| {
        trace
            .iter()
            .find(|(t, _, _)| *t >= time)
            .map(|(_, p, a)| (*p, *a))
            .unwrap()
    };
    let (p0, _) = at(0.0);
    let (p_runup, a_runup) = at(8.9);
    let (p_top, _) = at(14.0);
    let (p_end, a_end) = at(31.9);
    // the run-up on the skids: no lift-off, no creep beyond 5 cm, no spin
    assert!((p_runup[2] - p0[2]).abs() < 0.05, "{p0:?} → {p_runup:?}");
    assert!(((p_runup[0] - p0[0]).powi(2) + (p_runup[1] - p0[1]).powi(2)).sqrt() < 0.05);
    assert!(a_runup[2].abs() < 0.1, "turned on the ground: {a_runup:?}");
    // climbed (1 m/s for 3 s: 2 … 4 m)
    let climb = p0[2] - p_top[2];
    assert!((2.0..4.0).contains(&climb), "climbed {climb} m");
    // landed upright near the start, the rotor winding down after the cut
    assert!(
        (p_end[2] - p0[2]).abs() < 0.05,
        "not on the ground: {p_end:?}"
    );
    assert!(((p_end[0] - p0[0]).powi(2) + (p_end[1] - p0[1]).powi(2)).sqrt() < 1.0);
    assert!(a_end[0].abs() < 0.1 && a_end[1].abs() < 0.1, "{a_end:?}");
    let omega_gov = p.model.params().main_rotor.omega_rad_s;
    let omega = report.rotor_speed_rad_s.unwrap();
    assert!(omega < omega_gov, "rotor {omega} rad/s after the cut");
    eprintln!(
        "{} frames, {:.0} frames/s, {:.1}x real time; rotor {omega:.1} rad/s 3 s after the cut",
        report.counts.frames, report.frames_per_s, report.speed_x
    );
}
