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
    eprintln!("{m:#?}");
    let weight = params.body.mass_kg * params.environment.g_m_s2;
    let first = f.ground.first().unwrap();
    let last = f.ground.last().unwrap();
    // starts at rest on the skids, rotor stopped
    assert_eq!(first.sample.omega_rad_s, 0.0);
    assert!(first.sample.clearance_m < 0.0);
    assert!(((first.sample.normal_n.iter().sum::<f64>() - weight) / weight).abs() < 1e-3);
    // on the ground before the take-off: spooled up to the governed speed,
    // still on the skids
    let before = f.ground.iter().rfind(|r| r.t_s < g.takeoff_s).unwrap();
    let omega_gov = params.main_rotor.omega_rad_s;
    assert!((before.sample.omega_rad_s - omega_gov).abs() < 1e-3 * omega_gov);
    assert!(((before.sample.normal_n.iter().sum::<f64>() - weight) / weight).abs() < 1e-3);
    // lift-off within the take-off ramp (plus a second), without sliding
    let t_lo = m.liftoff_time_s.unwrap();
    assert!(
        t_lo > g.takeoff_s && t_lo < g.takeoff_s + g.ramp_s + 1.0,
        "{t_lo}"
    );
    assert!(m.liftoff_drift_m.unwrap() < 0.1);
    assert!((m.liftoff_omega_rad_s.unwrap() - omega_gov).abs() < 0.01 * omega_gov);
    // it climbed: 1 m/s for 5 s
    let top = f
        .ground
        .iter()
        .map(|r| r.sample.clearance_m)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(top > 4.0, "{top}");
    // a soft landing at the commanded 0.5 m/s descent, hardly sliding
    let vz = m.touchdown_vertical_speed_m_s.unwrap();
    assert!(vz > 0.1 && vz < 0.6, "{vz}");
    assert!(m.touchdown_horizontal_speed_m_s.unwrap() < 0.2);
    assert!(m.touchdown_drift_m.unwrap() < 0.05);
    assert!(m.touchdown_peak_normal_n.unwrap() < 1.5 * weight);
    // resting at the end: the weight on the skids, the engine cut
    let n_end: f64 = last.sample.normal_n.iter().sum();
    assert!(
        ((n_end - weight) / weight).abs() < 1e-3,
        "{n_end} vs {weight}"
    );
    assert_eq!(last.sample.throttle, 0.0);
    assert!(m.final_omega_rad_s < 0.8 * omega_gov);
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
