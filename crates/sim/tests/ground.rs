//! From the ground to the ground: the shipped `ground-to-ground` scenario
//! flown by the closed loop (spool-up on the skids, take-off, a short
//! mission, landing, engine cut), its metrics, and the `[ground]` section's
//! checks.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_sim::closed_loop::{Outcome, fly, prepare};
use helicon_sim::scenario::Scenario;
use std::path::Path;

fn shipped() -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ground-to-ground.toml");
    Scenario::from_file(&path).unwrap()
}

#[test]
fn ground_to_ground_flies_spools_takes_off_and_lands() {
    let s = shipped();
    let g = s.ground.unwrap();
    let p = prepare(&s).unwrap();
    let params = *p.model.params();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(
        f.summary.outcome,
        Outcome::Completed,
        "{:?}",
        f.summary.reason
    );
    let m = f.summary.ground.unwrap();
    let cfg = g.landing_config();
    let weight = params.body.mass_kg * params.environment.g_m_s2;
    let first = f.ground.first().unwrap();
    let last = f.ground.last().unwrap();
    // starts at rest on the skids, rotor stopped, the on-board logic disarmed
    assert_eq!(first.sample.omega_rad_s, 0.0);
    assert!(first.sample.clearance_m < 0.0);
    assert!(((first.sample.normal_n.iter().sum::<f64>() - weight) / weight).abs() < 1e-3);
    // the on-board take-off waits for its run-up timer after the arming
    // (the operator's auto at takeoff_s comes first): it begins the sample
    // after arm + runup_s (one control period, 2.5 ms)
    let ts = params.control.sample_time_s;
    let t_to = m.takeoff_start_s.unwrap();
    assert!(t_to > g.takeoff_s);
    assert!(
        (t_to - (g.spool_up_s + cfg.runup_s)).abs() <= ts + 1e-9,
        "{t_to}"
    );
    // on the ground before it: spooled up to the governed speed (the
    // governor's 5 s soft start is within the 8 s run-up), on the skids
    let before = f.ground.iter().rfind(|r| r.t_s < t_to).unwrap();
    let omega_gov = params.main_rotor.omega_rad_s;
    assert!((before.sample.omega_rad_s - omega_gov).abs() < 1e-3 * omega_gov);
    assert!(((before.sample.normal_n.iter().sum::<f64>() - weight) / weight).abs() < 1e-3);
    assert_eq!(before.sample.blend, 0.0);
    // lift-off within the take-off ramp (plus a second), without sliding;
    // the on-board detector sees it after (0.3 m up or a 0.3 m/s climb)
    let t_lo = m.liftoff_time_s.unwrap();
    assert!(t_lo > t_to && t_lo < t_to + g.ramp_s + 1.0, "{t_lo}");
    assert_eq!(m.arm_to_liftoff_s.unwrap(), t_lo - g.spool_up_s);
    assert!(m.liftoff_detected_s.unwrap() > t_lo);
    assert!(m.liftoff_drift_m.unwrap() < 0.1);
    assert!((m.liftoff_omega_rad_s.unwrap() - omega_gov).abs() < 0.01 * omega_gov);
    // it climbed: 1 m/s from the take-off to 12 s
    let top = f
        .ground
        .iter()
        .map(|r| r.sample.clearance_m)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(top > 1.5, "{top}");
    // a soft landing at the commanded 0.5 m/s descent, hardly sliding
    let vz = m.touchdown_vertical_speed_m_s.unwrap();
    assert!(vz > 0.1 && vz < 0.6, "{vz}");
    assert!(m.touchdown_horizontal_speed_m_s.unwrap() < 0.2);
    assert!(m.touchdown_drift_m.unwrap() < 0.05);
    assert!(m.touchdown_peak_normal_n.unwrap() < 1.5 * weight);
    // the land detector's three stages after the touchdown (each a third
    // of trigger_s at least, the descent asked a trigger time first), then
    // the disarm shutdown_delay_s later
    let t_td = m.touchdown_time_s.unwrap();
    let t_landed = m.landed_detected_s.unwrap();
    assert!(t_landed - t_td > cfg.trigger_s, "{t_landed}");
    let t_disarm = m.disarm_time_s.unwrap();
    assert!((t_disarm - t_landed - g.shutdown_delay_s).abs() <= ts + 1e-9);
    // resting at the end: the weight on the skids, the engine cut
    let n_end: f64 = last.sample.normal_n.iter().sum();
    assert!(
        ((n_end - weight) / weight).abs() < 1e-3,
        "{n_end} vs {weight}"
    );
    assert_eq!(last.sample.throttle, 0.0);
    assert!(m.final_omega_rad_s < 0.8 * omega_gov);
}

/// The on-board spool state runs through every state once, in order —
/// armed at the first sample (`spool_up_s = 0`), disarmed again
/// `spooldown_s` after the disarm — and the land detector ends landed; the
/// log's codes are the on-board ones.
#[test]
fn the_ground_log_follows_the_on_board_states_in_order() {
    use helicon_flight::landing::{LandStage, SpoolState};
    let s = shipped();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    let mut seen: Vec<f64> = Vec::new();
    for r in &f.ground {
        if seen.last() != Some(&r.sample.spool_state) {
            seen.push(r.sample.spool_state);
        }
    }
    let want: Vec<f64> = SpoolState::ALL[1..]
        .iter()
        .chain(&SpoolState::ALL[..1])
        .map(|s| f64::from(s.code()))
        .collect();
    assert_eq!(seen, want, "{seen:?}");
    let last = f.ground.last().unwrap();
    assert_eq!(last.sample.land_stage, f64::from(LandStage::Landed.code()));
    assert!(
        f.ground
            .iter()
            .any(|r| r.sample.land_stage == f64::from(LandStage::Air.code()))
    );
}

/// The figures docs/model-ground.md quotes for the shipped flight, to the
/// digits it prints (a tolerance of half its last digit).
#[test]
fn ground_to_ground_gives_the_documented_figures() {
    let s = shipped();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    let m = f.summary.ground.unwrap();
    eprintln!("{m:#?}");
    let near = |x: Option<f64>, want: f64, half: f64, what: &str| {
        let x = x.unwrap();
        assert!((x - want).abs() <= half, "{what}: {x} vs the docs' {want}");
    };
    near(m.takeoff_start_s, 8.00, 0.005, "take-off start");
    near(m.liftoff_time_s, 9.81, 0.005, "lift-off");
    near(m.arm_to_liftoff_s, 9.81, 0.005, "arm to lift-off");
    near(m.liftoff_detected_s, 10.12, 0.005, "lift-off detected");
    near(m.liftoff_drift_m, 0.0115, 0.00005, "lift-off drift");
    near(m.liftoff_omega_rad_s, 99.9, 0.05, "lift-off rotor speed");
    near(m.touchdown_time_s, 26.22, 0.005, "touchdown");
    near(m.touchdown_vertical_speed_m_s, 0.256, 0.0005, "down");
    near(m.touchdown_horizontal_speed_m_s, 0.045, 0.0005, "across");
    near(m.touchdown_offset_m, 8.05, 0.005, "offset");
    near(m.touchdown_drift_m, 0.019, 0.0005, "slide");
    near(
        m.landed_detected_s.map(|t| t - m.touchdown_time_s.unwrap()),
        2.325,
        0.0005,
        "landed after touchdown",
    );
    near(
        m.disarm_time_s.map(|t| t - m.landed_detected_s.unwrap()),
        2.00,
        0.005,
        "disarm after landed",
    );
    near(Some(m.final_omega_rad_s), 54.3, 0.05, "final rotor speed");
}

#[test]
fn ground_section_errors_name_the_field() {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ground-to-ground.toml"),
    )
    .unwrap();
    let with = |extra: &str, key: &str, value: &str| {
        let text = base.replace(&format!("{key} = {value}\n"), extra);
        Scenario::from_toml_str(&text, "g.toml")
            .unwrap_err()
            .to_string()
    };
    let e = with("takeoff_s = -1.0\n", "takeoff_s", "7.0");
    assert!(
        e.contains("g.toml") && e.contains("ground.takeoff_s"),
        "{e}"
    );
    let e = with("ramp_s = 0.0\n", "ramp_s", "2.0");
    assert!(e.contains("ground.ramp_s"), "{e}");
    let e = with("spool_up_s = 8.0\n", "spool_up_s", "0.0");
    assert!(
        e.contains("ground.takeoff_s") && e.contains("spool_up_s"),
        "{e}"
    );
    let e = with("on_ground = true\nbogus = 1\n", "on_ground", "true");
    assert!(e.contains("bogus"), "{e}");
    // on the ground without a landing gear: refused before the flight
    let mut s = shipped();
    s.params = None;
    let e = prepare(&s).unwrap_err().to_string();
    assert!(
        e.contains("ground.on_ground") && e.contains("landing_gear.enabled"),
        "{e}"
    );
}

#[test]
fn a_ground_too_close_to_the_design_point_is_refused_naming_the_field() {
    let mut s = shipped();
    let dir = std::env::temp_dir().join(format!("helicon-ground-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let params = dir.join("near.toml");
    std::fs::write(
        &params,
        "[landing_gear]\nenabled = true\nground_down_m = 0.3\n[drivetrain]\nenabled = true\n",
    )
    .unwrap();
    s.params = Some(params);
    let e = prepare(&s).unwrap_err().to_string();
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        e.contains("landing_gear.ground_down_m") && e.contains("0.3"),
        "{e}"
    );
}

/// `on_ground = false`: the flight starts in the air at the design point,
/// the on-board ground logic armed and flying (no arming, no take-off), the
/// engine governed; the descent ends on the ground and the land detector
/// lands it there.
#[test]
fn a_start_in_the_air_flies_the_law_and_the_land_detector_lands_it() {
    use helicon_flight::landing::{LandStage, SpoolState};
    let mut s = shipped();
    s.ground.as_mut().unwrap().on_ground = false;
    s.duration_s = 60.0;
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(
        f.summary.outcome,
        Outcome::Completed,
        "{:?}",
        f.summary.reason
    );
    let m = f.summary.ground.unwrap();
    eprintln!("{m:#?}");
    let first = f.ground.first().unwrap();
    assert_eq!(
        first.sample.spool_state,
        f64::from(SpoolState::Flying.code())
    );
    assert_eq!(first.sample.blend, 1.0);
    assert!(first.sample.clearance_m > 4.0);
    assert!(m.arm_time_s.is_none() && m.takeoff_start_s.is_none());
    assert!(m.touchdown_time_s.is_some(), "{m:?}");
    assert!(m.landed_detected_s.unwrap() > m.touchdown_time_s.unwrap());
    let last = f.ground.last().unwrap();
    assert_eq!(last.sample.land_stage, f64::from(LandStage::Landed.code()));
}
