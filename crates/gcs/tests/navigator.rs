//! The navigator against a point-mass vehicle whose velocity follows the
//! reference with a first-order lag (τ = 0.3 s, about the LQI's velocity
//! response): every limit is checked on the reference itself, every arrival
//! on the vehicle's position.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_gcs::fence::{Fence, FenceAction};
use helicon_gcs::navigator::{
    Events, GuidedTarget, Item, ItemKind, LinkLossAction, NavEvent, NavInput, NavMode, Navigator,
    NavigatorConfig, Plan,
};
use nalgebra::Vector3;

const DT: f64 = 0.0025; // 400 Hz, the control task's rate
const TAU: f64 = 0.3;

struct Sim {
    nav: Navigator,
    t: f64,
    p: Vector3<f64>,
    v: Vector3<f64>,
    yaw: f64,
    events: Vec<(f64, NavEvent, Vector3<f64>)>,
    prev_ref: Vector3<f64>,
    prev_yaw: f64,
    max_dv: f64,
    max_dyaw: f64,
    max_h_speed: f64,
    max_up: f64,
    max_down: f64,
}

impl Sim {
    fn new(config: NavigatorConfig) -> Self {
        Sim {
            nav: Navigator::new(config).unwrap(),
            t: 0.0,
            p: Vector3::zeros(),
            v: Vector3::zeros(),
            yaw: 0.0,
            events: Vec::new(),
            prev_ref: Vector3::zeros(),
            prev_yaw: 0.0,
            max_dv: 0.0,
            max_dyaw: 0.0,
            max_h_speed: 0.0,
            max_up: 0.0,
            max_down: 0.0,
        }
    }

    fn at(&self) -> NavInput {
        NavInput {
            t_s: self.t,
            position_ned_m: self.p,
            yaw_rad: self.yaw,
            on_ground: None,
        }
    }

    fn record(&mut self, ev: &Events) {
        for e in ev.iter() {
            self.events.push((self.t, e, self.p));
        }
    }

    fn run(&mut self, seconds: f64, silence: impl Fn(f64) -> Option<f64>) {
        let n = (seconds / DT).round() as usize;
        for _ in 0..n {
            let mut ev = Events::default();
            let at = self.at();
            self.nav.link(&at, silence(self.t), &mut ev);
            self.nav.fence(&at, &mut ev);
            let r = self.nav.step(&at, &mut ev);
            self.record(&ev);
            let dv = (r.velocity_ned_m_s - self.prev_ref).norm();
            if self.nav.mode() != NavMode::Idle {
                // (landed: disarmed, the reference drops to zero at once)
                self.max_dv = self.max_dv.max(dv);
            }
            self.max_dyaw = self.max_dyaw.max((r.yaw_rad - self.prev_yaw).abs());
            self.prev_ref = r.velocity_ned_m_s;
            self.prev_yaw = r.yaw_rad;
            self.max_h_speed = self.max_h_speed.max(r.velocity_ned_m_s.xy().norm());
            self.max_up = self.max_up.max(-r.velocity_ned_m_s.z);
            self.max_down = self.max_down.max(r.velocity_ned_m_s.z);
            self.v += (r.velocity_ned_m_s - self.v) * (DT / TAU);
            self.p += self.v * DT;
            self.yaw += (r.yaw_rad - self.yaw) * (DT / TAU);
            self.t += DT;
        }
    }

    fn has(&self, e: NavEvent) -> Option<(f64, Vector3<f64>)> {
        self.events
            .iter()
            .find(|(_, x, _)| *x == e)
            .map(|(t, _, p)| (*t, *p))
    }
}

fn no_link(_: f64) -> Option<f64> {
    None
}

#[test]
fn takeoff_climbs_within_limits_then_holds() {
    let c = NavigatorConfig::default();
    let mut s = Sim::new(c);
    let mut ev = Events::default();
    assert!(s.nav.takeoff(&s.at(), 5.0, &mut ev));
    s.record(&ev);
    s.run(20.0, no_link);
    assert_eq!(s.nav.mode(), NavMode::Hold);
    // the takeoff ends within 0.3 m of the height and the hold keeps it
    assert!((s.p.z + 5.0).abs() < 0.1, "d = {}", s.p.z);
    assert!(s.p.xy().norm() < 1e-9);
    // limits on the reference (a small margin for floating point)
    assert!(s.max_up <= c.climb_speed_m_s + 1e-12, "{}", s.max_up);
    assert!(s.max_dv <= c.max_accel_m_s2 * DT + 1e-12, "{}", s.max_dv);
}

fn mission() -> Plan {
    let mut plan = Plan::default();
    let wp = |seq, n, e, speed: Option<f64>, yaw: Option<f64>| Item {
        seq,
        kind: ItemKind::Waypoint,
        position_ned_m: Vector3::new(n, e, -10.0),
        speed_m_s: speed,
        yaw_rad: yaw,
        acceptance_m: None,
        hold_s: 0.5,
    };
    assert!(plan.push(Item {
        seq: 0,
        kind: ItemKind::Takeoff,
        position_ned_m: Vector3::new(0.0, 0.0, -10.0),
        speed_m_s: None,
        yaw_rad: None,
        acceptance_m: Some(0.5),
        hold_s: 0.0,
    }));
    assert!(plan.push(wp(1, 20.0, 0.0, Some(3.0), None)));
    assert!(plan.push(wp(2, 20.0, 20.0, None, Some(1.5))));
    assert!(plan.push(wp(3, 0.0, 20.0, Some(1.0), None)));
    assert!(plan.push(wp(4, 0.0, 0.0, None, Some(-3.0))));
    assert!(plan.push(Item {
        seq: 5,
        kind: ItemKind::Land,
        position_ned_m: Vector3::zeros(),
        speed_m_s: None,
        yaw_rad: None,
        acceptance_m: None,
        hold_s: 0.0,
    }));
    plan
}

#[test]
fn four_waypoint_mission_reached_in_order_then_landed() {
    let c = NavigatorConfig::default();
    let mut s = Sim::new(c);
    s.nav.set_plan(mission());
    let mut ev = Events::default();
    assert!(s.nav.start_mission(&s.at(), &mut ev));
    s.record(&ev);
    s.run(200.0, no_link);
    let targets = [
        (1, Vector3::new(20.0, 0.0, -10.0)),
        (2, Vector3::new(20.0, 20.0, -10.0)),
        (3, Vector3::new(0.0, 20.0, -10.0)),
        (4, Vector3::new(0.0, 0.0, -10.0)),
    ];
    let mut last_t = 0.0;
    for (seq, target) in targets {
        let (t, p) = s
            .has(NavEvent::Reached(seq))
            .unwrap_or_else(|| panic!("waypoint {seq} not reached"));
        assert!(t > last_t, "waypoint {seq} out of order");
        last_t = t;
        // reached: within the acceptance radius (1 m)
        assert!((p - target).norm() <= c.acceptance_radius_m, "{seq}: {p}");
    }
    let (t_landed, p_landed) = s.has(NavEvent::Landed).expect("landed");
    assert!(t_landed > last_t);
    assert!(p_landed.z >= -c.landed_height_m && p_landed.xy().norm() < 1.0);
    assert_eq!(s.nav.mode(), NavMode::Idle);
    // the leg speeds: 3 m/s at most (the largest leg speed), within max
    assert!(s.max_h_speed <= 3.0 + 1e-9, "{}", s.max_h_speed);
    assert!(s.max_h_speed > 2.9, "the 3 m/s leg never reached its speed");
    assert!(s.max_dv <= c.max_accel_m_s2 * DT + 1e-12);
    assert!(s.max_dyaw <= c.yaw_rate_max_rad_s * DT + 1e-12);
    assert!(s.max_down <= c.descent_speed_m_s + 1e-12);
}

#[test]
fn heading_turns_the_short_way_at_the_rate_limit() {
    let mut s = Sim::new(NavigatorConfig::default());
    s.yaw = 3.0;
    let mut ev = Events::default();
    s.nav.hold(&s.at(), &mut ev);
    let mut plan = Plan::default();
    plan.push(Item {
        seq: 0,
        kind: ItemKind::Waypoint,
        position_ned_m: Vector3::zeros(),
        speed_m_s: None,
        yaw_rad: Some(-3.0),
        acceptance_m: None,
        hold_s: 100.0,
    });
    s.nav.set_plan(plan);
    s.nav.start_mission(&s.at(), &mut ev);
    s.run(0.4, no_link);
    // short way: from 3.0 up through π (2π − 6.0 = 0.283 rad), at 0.5 rad/s
    let expected = 3.0 + 0.5 * 0.4;
    assert!(
        (s.prev_yaw - expected).abs() < 0.5 * DT * 2.0,
        "{}",
        s.prev_yaw
    );
    s.run(2.0, no_link);
    assert!((helicon_core::frames::wrap_pi(s.prev_yaw + 3.0)).abs() < 1e-9);
}

#[test]
fn link_loss_holds_then_returns_and_lands() {
    let c = NavigatorConfig {
        link_loss_timeout_s: 2.0,
        link_loss_hold_s: 3.0,
        link_loss_action: LinkLossAction::Return,
        ..NavigatorConfig::default()
    };
    let mut s = Sim::new(c);
    let mut ev = Events::default();
    s.p = Vector3::new(10.0, -5.0, -8.0);
    s.nav.set_plan(mission());
    s.nav.start_mission(&s.at(), &mut ev);
    // heartbeats until t = 4 s, then silence
    let silence = |t: f64| Some(if t < 4.0 { 0.0 } else { t - 4.0 });
    s.run(60.0, silence);
    let (t_lost, _) = s.has(NavEvent::LinkLost).expect("link loss");
    assert!((t_lost - 6.0).abs() < 2.0 * DT, "{t_lost}");
    let (t_hold, _) = s.has(NavEvent::Mode(NavMode::Hold)).expect("hold");
    assert!((t_hold - t_lost).abs() < 1e-9);
    assert!(s.has(NavEvent::Reached(1)).is_none(), "the mission went on");
    let (t_ret, _) = s.has(NavEvent::Mode(NavMode::Return)).expect("return");
    assert!((t_ret - t_lost - 3.0).abs() < 2.0 * DT, "{t_ret}");
    let (_, p) = s.has(NavEvent::Landed).expect("landed");
    assert!(p.xy().norm() <= c.acceptance_radius_m + 0.1, "{p}");
}

#[test]
fn no_failsafe_before_first_contact_nor_on_the_ground() {
    let mut s = Sim::new(NavigatorConfig::default());
    s.run(10.0, Some);
    assert!(s.has(NavEvent::LinkLost).is_none());
    let mut ev = Events::default();
    s.nav.hold(&s.at(), &mut ev);
    s.run(1.0, no_link);
    assert!(s.has(NavEvent::LinkLost).is_none());
}

#[test]
fn guided_velocity_followed_then_times_out_to_hold() {
    let c = NavigatorConfig::default();
    let mut s = Sim::new(c);
    let mut ev = Events::default();
    s.p.z = -10.0;
    let target = Vector3::new(1.5, -1.0, 0.0);
    assert!(
        s.nav
            .guided(&s.at(), GuidedTarget::Velocity(target, None), &mut ev)
    );
    s.run(0.9, no_link);
    assert_eq!(s.nav.mode(), NavMode::Guided);
    // the reference ramps at the acceleration limit: 1.8 m/s at 1 m/s² is reached in 1.8 s
    let ramp = target.norm().min(c.max_accel_m_s2 * 0.9);
    assert!((s.prev_ref.norm() - ramp).abs() < 0.01, "{}", s.prev_ref);
    s.run(0.2, no_link);
    assert_eq!(s.nav.mode(), NavMode::Hold);
    // a too fast target is limited to the largest speed
    let mut ev = Events::default();
    s.nav.guided(
        &s.at(),
        GuidedTarget::Velocity(Vector3::new(30.0, 0.0, 0.0), None),
        &mut ev,
    );
    for _ in 0..20 {
        s.nav.guided(
            &s.at(),
            GuidedTarget::Velocity(Vector3::new(30.0, 0.0, 0.0), None),
            &mut ev,
        );
        s.run(0.5, no_link);
    }
    assert!(
        (s.prev_ref.x - c.max_speed_m_s).abs() < 1e-9,
        "{}",
        s.prev_ref
    );
    assert!(!s.nav.guided(
        &s.at(),
        GuidedTarget::Velocity(Vector3::new(f64::NAN, 0.0, 0.0), None),
        &mut ev
    ));
}

#[test]
fn invalid_tuning_refused_and_old_kept() {
    let mut nav = Navigator::new(NavigatorConfig::default()).unwrap();
    for (field, bad) in [
        ("max_accel_m_s2", f64::NAN),
        ("max_accel_m_s2", 0.0),
        ("cruise_speed_m_s", 100.0),
    ] {
        let mut c = NavigatorConfig::default();
        match field {
            "max_accel_m_s2" => c.max_accel_m_s2 = bad,
            _ => c.cruise_speed_m_s = bad,
        }
        let e = nav.set_config(c).unwrap_err();
        assert_eq!(e.field, field);
    }
    let c = NavigatorConfig {
        cruise_speed_m_s: 6.0,
        ..NavigatorConfig::default()
    };
    assert_eq!(
        nav.set_config(c).unwrap_err().rule,
        "greater than max_speed_m_s"
    );
    assert_eq!(*nav.config(), NavigatorConfig::default());
}

#[test]
fn plan_refuses_non_finite_items_and_overflow() {
    let mut plan = Plan::default();
    let item = Item {
        seq: 0,
        kind: ItemKind::Waypoint,
        position_ned_m: Vector3::new(f64::INFINITY, 0.0, 0.0),
        speed_m_s: None,
        yaw_rad: None,
        acceptance_m: None,
        hold_s: 0.0,
    };
    assert!(!plan.push(item));
    let ok = Item {
        position_ned_m: Vector3::zeros(),
        ..item
    };
    for _ in 0..helicon_gcs::navigator::MAX_MISSION_ITEMS {
        assert!(plan.push(ok));
    }
    assert!(!plan.push(ok));
}

#[test]
fn gcs_section_checked_field_by_field() {
    use helicon_gcs::config::GcsSection;
    let home = helicon_devices::Geodetic::new(57.0, 10.0, 20.0).unwrap();
    let ok = GcsSection::from_toml_str(
        "address = \"udpin:0.0.0.0:14550\"\nsigning_key_hex = \"000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f\"\n[rates_hz]\nATTITUDE = 50.0\n[navigator]\ncruise_speed_m_s = 3.0\nlink_loss_action = \"land\"\n[navigator.fence]\nmax_hor_dist_m = 300.0\naction = \"hold\"\n",
        "onboard.toml",
    )
    .unwrap();
    let c = ok.server_config(home, "onboard.toml").unwrap();
    assert_eq!(c.signing_key.unwrap()[31], 31);
    assert_eq!(c.rates_hz[2], 50.0);
    assert_eq!(c.navigator.cruise_speed_m_s, 3.0);
    assert_eq!(c.navigator.link_loss_action, LinkLossAction::Land);
    assert_eq!(c.navigator.fence.max_hor_dist_m, 300.0);
    assert_eq!(c.navigator.fence.max_ver_dist_m, 60.0);
    assert_eq!(c.navigator.fence.action, FenceAction::Hold);
    for (text, field) in [
        ("address = \"tcp:1.2.3.4:5\"", "gcs.address"),
        ("system_id = 255", "gcs.system_id"),
        ("signing_key_hex = \"00zz\"", "gcs.signing_key_hex"),
        ("[rates_hz]\nATTITUDE = 1000.0", "gcs.rates_hz.ATTITUDE"),
        ("[rates_hz]\nBOGUS = 1.0", "gcs.rates_hz.BOGUS"),
        (
            "[navigator]\nmax_accel_m_s2 = 0.0",
            "gcs.navigator.max_accel_m_s2",
        ),
        (
            "[navigator.fence]\nmax_hor_dist_m = 1e9",
            "gcs.navigator.fence.max_hor_dist_m",
        ),
        (
            "[navigator.fence]\nmax_ver_dist_m = nan",
            "gcs.navigator.fence.max_ver_dist_m",
        ),
    ] {
        let e = GcsSection::from_toml_str(text, "onboard.toml")
            .unwrap()
            .server_config(home, "onboard.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("onboard.toml: `") && e.contains(field),
            "{text}: {e}"
        );
    }
    for text in [
        "adress = \"x\"",
        "[navigator]\nlink_loss_action = \"fly\"",
        "[navigator]\nspeed = 1.0",
        "[navigator.fence]\naction = \"terminate\"",
        "[navigator.fence]\nradius = 1.0",
    ] {
        let e = GcsSection::from_toml_str(text, "onboard.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("onboard.toml: [gcs]"), "{text}: {e}");
    }
}

/// A guided velocity out of a small fence (20 m, 15 m up): each GF_ACTION
/// acts once, at the crossing, and a return lands at home.
#[test]
fn fence_breach_acts_as_gf_action_says() {
    let fenced = |action| NavigatorConfig {
        guided_timeout_s: 10.0,
        fence: Fence {
            max_hor_dist_m: 20.0,
            max_ver_dist_m: 15.0,
            action,
        },
        ..NavigatorConfig::default()
    };
    for action in [
        FenceAction::Return,
        FenceAction::Hold,
        FenceAction::Land,
        FenceAction::Warn,
    ] {
        let mut s = Sim::new(fenced(action));
        s.p = Vector3::new(0.0, 0.0, -5.0);
        let mut ev = Events::default();
        let out = GuidedTarget::Velocity(Vector3::new(3.0, 0.0, 0.0), None);
        assert!(s.nav.guided(&s.at(), out, &mut ev));
        s.record(&ev);
        let mut farthest: f64 = 0.0;
        for _ in 0..120 {
            s.run(0.5, no_link);
            farthest = farthest.max(s.p.xy().norm());
            if action == FenceAction::Warn && s.p.x > 22.0 {
                break;
            }
        }
        let breaches: Vec<_> = s
            .events
            .iter()
            .filter(|(_, e, _)| matches!(e, NavEvent::FenceBreach(_)))
            .collect();
        assert_eq!(breaches.len(), 1, "{action:?}: {breaches:?}");
        let (t_b, e, p_b) = breaches[0];
        assert_eq!(*e, NavEvent::FenceBreach(true));
        // at the crossing: 20 m within one step's travel
        assert!((p_b.xy().norm() - 20.0).abs() < 3.0 * DT * 1.01, "{p_b}");
        let mode_after = s
            .events
            .iter()
            .find(|(t, e, _)| *t >= *t_b && matches!(e, NavEvent::Mode(_)))
            .map(|(_, e, _)| *e);
        match action {
            FenceAction::Return => {
                assert_eq!(mode_after, Some(NavEvent::Mode(NavMode::Return)));
                let (_, p) = s.has(NavEvent::Landed).expect("landed");
                assert!(p.xy().norm() <= 1.1, "landed at {p}");
                // braking from 3 m/s at 1 m/s² (4.5 m) and the lag
                assert!(farthest < 26.0, "{farthest}");
            }
            FenceAction::Hold => {
                assert_eq!(mode_after, Some(NavEvent::Mode(NavMode::Hold)));
                assert_eq!(s.nav.mode(), NavMode::Hold);
                assert!(farthest < 26.0, "{farthest}");
            }
            FenceAction::Land => {
                assert_eq!(mode_after, Some(NavEvent::Mode(NavMode::Land)));
                let (_, p) = s.has(NavEvent::Landed).expect("landed");
                assert!(p.x > 20.0 && p.x < 26.0, "landed at {p}");
            }
            FenceAction::Warn => {
                assert_eq!(mode_after, None);
                assert_eq!(s.nav.mode(), NavMode::Guided);
            }
        }
    }
    // the height: a climb at 1 m/s through 15 m returns at 15 m at most
    let mut s = Sim::new(fenced(FenceAction::Return));
    s.p = Vector3::new(5.0, 0.0, -8.0);
    let mut ev = Events::default();
    let up = GuidedTarget::Velocity(Vector3::new(0.0, 0.0, -1.0), None);
    assert!(s.nav.guided(&s.at(), up, &mut ev));
    let mut highest: f64 = 0.0;
    for _ in 0..750 {
        s.run(0.1, no_link);
        highest = highest.max(-s.p.z);
    }
    let (t_b, p_b) = s.has(NavEvent::FenceBreach(false)).expect("height breach");
    assert!((p_b.z + 15.0).abs() < 0.01, "{p_b}");
    let (t_r, _) = s.has(NavEvent::Mode(NavMode::Return)).expect("return");
    assert!((t_r - t_b).abs() < 1e-9);
    // the return flies at the fence's height at most: the overshoot is the
    // climb's stopping (1 m/s at 1 m/s², 0.5 m, slower here as the one
    // acceleration limit also starts the leg home), and the lag (0.3 m);
    // 16.2 m measured
    assert!(highest < 16.5, "{highest}");
    let (_, p) = s.has(NavEvent::Landed).expect("landed");
    assert!(p.xy().norm() <= 1.1, "landed at {p}");
    // targets outside the fence are not flown, whoever asks
    let mut s = Sim::new(fenced(FenceAction::Return));
    let mut ev = Events::default();
    s.nav.hold(&s.at(), &mut ev);
    for p in [
        Vector3::new(21.0, 0.0, -5.0),
        Vector3::new(0.0, 0.0, -16.0),
        Vector3::new(0.0, 0.0, -3e38),
    ] {
        assert!(
            !s.nav
                .guided(&s.at(), GuidedTarget::Position(p, None), &mut ev)
        );
    }
    assert!(!s.nav.takeoff(&s.at(), 16.0, &mut ev));
    assert_eq!(s.nav.mode(), NavMode::Hold);
    // a return or a landing is not left by a guided target (a stream on its
    // way when the fence acted), only by a mode change
    let near = GuidedTarget::Velocity(Vector3::new(1.0, 0.0, 0.0), None);
    for mode in [NavMode::Return, NavMode::Land] {
        match mode {
            NavMode::Return => s.nav.return_home(&s.at(), &mut ev),
            _ => s.nav.land(&s.at(), &mut ev),
        }
        assert!(!s.nav.guided(&s.at(), near, &mut ev));
        assert_eq!(s.nav.mode(), mode);
        s.nav.hold(&s.at(), &mut ev);
        assert!(s.nav.guided(&s.at(), near, &mut ev));
        assert_eq!(s.nav.mode(), NavMode::Guided);
    }
}

/// An uploaded zone is the fence too: the breach monitor acts at an
/// exclusion circle's edge, and a position target inside it is refused.
#[test]
fn an_uploaded_exclusion_zone_is_breached_at_its_edge() {
    use helicon_devices::{Geodetic, LocalNed};
    use helicon_gcs::fence::Zones;
    use helicon_gcs::mavlink::dialects::common::*;
    let home = LocalNed::new(Geodetic::new(57.0146, 9.9869, 20.0).unwrap());
    // a 5 m exclusion circle 15 m north of home (15 m ≈ 1349 × 10⁻⁷ deg)
    let circle = MISSION_ITEM_INT_DATA {
        param1: 5.0,
        x: 570_146_000 + 1_349,
        y: 99_869_000,
        command: MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION,
        frame: MavFrame::MAV_FRAME_GLOBAL,
        mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
        ..MISSION_ITEM_INT_DATA::DEFAULT
    };
    let zones = Zones::from_items(&home, &[circle]).unwrap();
    let config = NavigatorConfig {
        guided_timeout_s: 10.0,
        fence: Fence {
            action: FenceAction::Hold,
            ..Fence::default()
        },
        ..NavigatorConfig::default()
    };
    let mut s = Sim::new(config);
    s.nav.set_zones(zones);
    s.p = Vector3::new(0.0, 0.0, -5.0);
    let mut ev = Events::default();
    let inside = GuidedTarget::Position(Vector3::new(15.0, 0.0, -5.0), None);
    assert!(
        !s.nav.guided(&s.at(), inside, &mut ev),
        "a target in the zone flown"
    );
    let north = GuidedTarget::Velocity(Vector3::new(2.0, 0.0, 0.0), None);
    assert!(s.nav.guided(&s.at(), north, &mut ev));
    s.record(&ev);
    s.run(10.0, no_link);
    let (_, p) = s.has(NavEvent::FenceBreach(true)).expect("a breach");
    // at the circle's edge, 10 m north, within a step's travel
    assert!((p.x - 10.0).abs() < 0.05, "{p}");
    assert_eq!(s.nav.mode(), NavMode::Hold);
    assert!(s.p.x < 15.0, "flew into the zone: {}", s.p);
}
