//! Flying the envelope: the shipped mission with the gain schedule (a
//! shortened run: hover → 15 m/s with a climb → cruise, two seeds), the
//! jerk-limited reference in the log, and the scenario rules of the new
//! sections.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::envelope::{segment_lag, segment_rms};
use helicon_sim::scenario::Scenario;
use std::path::Path;

fn mission() -> Scenario {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/envelope-mission.toml");
    Scenario::from_file(&p).unwrap()
}

/// The first 32 s of the mission (acceleration to 15 m/s with a 2 m/s
/// climb, cruise) with sensors, navigation and the predictor in Dryden
/// turbulence, two seeds: completed; the log's references are the
/// jerk-limited ones (15 m/s at 22 s, |Δ ref| per sample within the
/// acceleration limit); tracking RMS within twice the 20-seed campaign's
/// worst seed (docs/envelope.md, ESKF navigation: horizontal 0.069 /
/// 0.061 m/s, vertical 0.176 / 0.255 m/s in the acceleration / cruise
/// segments).
#[test]
fn shortened_mission_flies_with_the_schedule() {
    for seed in [1u64, 2] {
        let mut s = mission();
        s.duration_s = 32.0;
        s.wind.seed = seed;
        s.sensors.seed = seed;
        let p = prepare(&s).unwrap();
        assert!(p.schedule.is_some());
        let f = fly(&s, &p, None).unwrap();
        assert!(
            f.summary.reason.is_none(),
            "seed {seed}: {:?}",
            f.summary.reason
        );
        let at = |t: f64| f.log.iter().find(|r| r.t_s >= t).unwrap();
        assert!((at(25.0).reference[0] - 15.0).abs() < 1e-9);
        assert!(at(4.9).reference[0].abs() < 1e-12);
        let dt = f.log[1].t_s - f.log[0].t_s;
        for w in f.log.windows(2) {
            let dv = (w[1].reference[0] - w[0].reference[0]).abs();
            assert!(
                dv <= 1.0 * dt * (1.0 + 1e-9),
                "reference acceleration {}",
                dv / dt
            );
        }
        let acc = segment_rms(&f.log, 5.0, 22.0).unwrap();
        assert!(
            acc.horizontal_m_s < 0.14 && acc.vertical_m_s < 0.35,
            "{acc:?}"
        );
        let cruise = segment_rms(&f.log, 22.0, 32.0).unwrap();
        assert!(
            cruise.horizontal_m_s < 0.12 && cruise.vertical_m_s < 0.5,
            "{cruise:?}"
        );
        // the summary's step of a shaped reference is its last move as
        // flown: vd out to −2 m/s and back by 25 s (its size how far it
        // went); vn's is the turn begun at 30 s, still under way when the
        // record ends: not settled
        let m = |o: &str| f.summary.metrics[o];
        let (vn, vd) = (m("vn"), m("vd"));
        assert!((vd.excitation - 2.0).abs() < 1e-6, "{vd:?}");
        assert!((vd.excitation_time_s - 25.0).abs() < 0.02, "{vd:?}");
        assert!(
            vn.excitation_time_s > 31.9 && vn.settling_time_s.is_none(),
            "{vn:?}"
        );
    }
    // ended before the turn: vn's last move is the acceleration 0 → 15 m/s
    // arriving at 22 s; ψ never moved
    let mut s = mission();
    s.duration_s = 29.0;
    let f = fly(&s, &prepare(&s).unwrap(), None).unwrap();
    let vn = f.summary.metrics["vn"];
    assert!((vn.excitation - 15.0).abs() < 1e-6, "{vn:?}");
    assert!((vn.excitation_time_s - 22.0).abs() < 0.02, "{vn:?}");
    assert!(vn.settling_time_s.is_some(), "{vn:?}");
    assert!(f.summary.metrics["psi"].excitation < 1e-3);
}

/// The single hover design against the schedule on the whole mission, the
/// same two seeds for both (paired): where it degrades and why. With the
/// hover design the reference acts only through the integrators, and the
/// trim of each new operating point (pitch −6.2° and S_lon +0.035 at
/// 15 m/s, the bank of the turn) has to be wound up by them: a type-1 loop
/// following a ramp, so a constant lag. The schedule puts the trims in.
/// Measured over 20 seeds (docs/envelope.md): in the accelerations the
/// hover design lags 0.66 m/s along track (schedule 0.01) and its
/// horizontal RMS is 0.69 against 0.06 m/s; in the 0.2 rad/s turn its
/// velocity points 1.70 m/s off the reference (schedule 0.02), RMS 1.88
/// against 0.16 m/s and heading 7.2° against 1.8°. Where the operating
/// point holds (the cruises) the two agree within 0.03 m/s: the hover
/// design's frozen-point instability at 15 m/s (|z| = 1.000026) is too slow
/// to show.
#[test]
fn hover_design_lags_the_schedule_where_the_operating_point_moves() {
    let segment = |name: &str| match name {
        "accelerate" => (5.0, 22.0),
        "cruise" => (22.0, 30.0),
        "turn" => (30.0, 50.7),
        "cruise after turn" => (50.7, 75.0),
        _ => (75.0, 92.0), // decelerate
    };
    for seed in [1u64, 2] {
        let mut s = mission();
        s.duration_s = 92.0;
        s.wind.seed = seed;
        s.sensors.seed = seed;
        let mut h = s.clone();
        h.controller.schedule = None;
        let fs = fly(&s, &prepare(&s).unwrap(), None).unwrap();
        let fh = fly(&h, &prepare(&h).unwrap(), None).unwrap();
        assert!(fs.summary.reason.is_none(), "{:?}", fs.summary.reason);
        assert!(fh.summary.reason.is_none(), "{:?}", fh.summary.reason);
        let rms = |f: &helicon_sim::closed_loop::Flight, seg: &str| {
            let (a, b) = segment(seg);
            segment_rms(&f.log, a, b).unwrap()
        };
        let lag = |f: &helicon_sim::closed_loop::Flight, seg: &str| {
            let (a, b) = segment(seg);
            segment_lag(&f.log, a, b).unwrap()
        };
        for seg in ["accelerate", "turn", "decelerate"] {
            let (rs, rh) = (rms(&fs, seg), rms(&fh, seg));
            eprintln!(
                "seed {seed} {seg}: horizontal RMS schedule {:.3}, hover {:.3} m/s; lag {:?} / {:?}",
                rs.horizontal_m_s,
                rh.horizontal_m_s,
                lag(&fs, seg),
                lag(&fh, seg)
            );
            assert!(rh.horizontal_m_s > 5.0 * rs.horizontal_m_s, "{seg}");
        }
        // the mechanism: a lag along track while the speed ramps …
        let (ls, lh) = (lag(&fs, "accelerate"), lag(&fh, "accelerate"));
        assert!(
            lh.along_m_s > 0.5 && ls.along_m_s.abs() < 0.1,
            "{ls:?} {lh:?}"
        );
        let (ls, lh) = (lag(&fs, "decelerate"), lag(&fh, "decelerate"));
        assert!(
            lh.along_m_s < -0.5 && ls.along_m_s.abs() < 0.1,
            "{ls:?} {lh:?}"
        );
        // … and behind the turn while the velocity reference rotates
        let (ls, lh) = (lag(&fs, "turn"), lag(&fh, "turn"));
        assert!(
            lh.cross_m_s > 1.4 && ls.cross_m_s.abs() < 0.1,
            "{ls:?} {lh:?}"
        );
        let (ts, th) = (rms(&fs, "turn").heading_rad, rms(&fh, "turn").heading_rad);
        assert!(th > 2.0 * ts, "heading RMS in the turn {ts} {th}");
        // where the operating point holds, they agree
        for seg in ["cruise", "cruise after turn"] {
            let d = rms(&fh, seg).horizontal_m_s - rms(&fs, seg).horizontal_m_s;
            eprintln!("seed {seed} {seg}: hover − schedule horizontal RMS {d:.4} m/s");
            assert!(d.abs() < 0.03, "{seg}: {d}");
        }
    }
}

fn err(text: &str) -> String {
    Scenario::from_toml_str(text, "s.toml")
        .unwrap_err()
        .to_string()
}

/// The new sections' rules name the file and the field.
#[test]
fn trajectory_and_schedule_rules() {
    let e = err(
        "duration_s = 10.0\n[trajectory]\nspeed = [{ t_s = 1.0, value = 15.0 }, { t_s = 2.0, value = 0.0 }]\n",
    );
    assert!(
        e.starts_with("s.toml: `trajectory.speed`") && e.contains("previous"),
        "{e}"
    );
    let e = err("duration_s = 10.0\n[trajectory]\nyaw_rate = [{ t_s = 1.0, value = 5.0 }]\n");
    assert!(
        e.starts_with("s.toml: `trajectory.yaw_rate[0].value` = 5"),
        "{e}"
    );
    let e = err("duration_s = 10.0\n[trajectory]\nmax_jerk_m_s3 = 0.0\n");
    assert!(
        e.starts_with("s.toml: `trajectory.max_jerk_m_s3` = 0"),
        "{e}"
    );
    let e = err(
        "duration_s = 10.0\n[trajectory]\n[[reference]]\nt_s = 1.0\noutput = \"vn\"\nvalue = 1.0\n",
    );
    assert!(e.contains("[trajectory] replaces [[reference]]"), "{e}");
    let e = err("duration_s = 10.0\n[trim]\nvelocity_ned_m_s = [0.0, 3.0, 0.0]\n[trajectory]\n");
    assert!(e.starts_with("s.toml: `trim.velocity_ned_m_s`"), "{e}");
    let e =
        err("duration_s = 10.0\n[controller]\nschedule = \"a.toml\"\ngains_file = \"g.json\"\n");
    assert!(e.contains("at most one of `schedule`"), "{e}");
    // a missing envelope file is an error naming it when the scenario is prepared
    let s = Scenario::from_toml_str(
        "duration_s = 1.0\n[controller]\nschedule = \"/nonexistent/envelope.toml\"\n",
        "s.toml",
    )
    .unwrap();
    let e = prepare(&s).unwrap_err().to_string();
    assert!(e.contains("/nonexistent/envelope.toml"), "{e}");
}
