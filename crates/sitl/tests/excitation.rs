//! Flight-test excitation (`[[excitation]]`) under lock-step SITL: the
//! on-board program flies the scenario's inputs exactly as `helicon sim`
//! does, logs them in the ULog (`excitation`), and the pilot's switch
//! stops them.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::{Ulog, options, scenario};
use helicon_sim::closed_loop::{Termination, prepare};
use helicon_sim::log_csv::LogWriter;
use helicon_sim::log_csv::read_log_csv;
use helicon_sitl as sitl;

const EXC: [&str; 4] = ["exc_col", "exc_lat", "exc_lon", "exc_tr"];

/// `ident-hover-sweep` (114 s) flown shortened to 7 s, its four sweeps
/// moved closer so each channel is excited within the flight.
fn sweep_scenario() -> helicon_sim::scenario::Scenario {
    let mut s = scenario("ident-hover-sweep.toml", 7.0);
    for (e, t) in s.excitation.iter_mut().zip([1.0, 2.5, 4.0, 5.5]) {
        e.t_s = t;
    }
    s
}

/// The excitation depends on on-board time only, k·Ts on both sides (SITL
/// starts armed, so its clock starts at 0 as the simulator's): the `exc_*`
/// columns are equal bit for bit, every frame. The commands the plant got
/// are the on-board law's plus the excitation at the avionics protocol's
/// resolution (the existing SITL test's bound).
#[test]
fn sitl_flies_the_scenarios_excitation_as_helicon_sim() {
    let s = sweep_scenario();
    let prepared = prepare(&s).unwrap();
    let r = sitl::run(&s, &prepared, &options("excitation")).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let flown = helicon_sim::closed_loop::fly(&s, &prepared, None).unwrap();
    let sim_csv = std::env::temp_dir().join(format!("helicon_exc_sim_{}.csv", std::process::id()));
    let mut w = LogWriter::create(&sim_csv).unwrap();
    for row in &flown.log {
        w.write(row).unwrap();
    }
    w.finish().unwrap();
    let (a, b) = (
        read_log_csv(&r.log_csv).unwrap(),
        read_log_csv(&sim_csv).unwrap(),
    );
    let _ = std::fs::remove_file(&sim_csv);
    assert_eq!(a.time_s().len(), 2801);
    assert_eq!(a.time_s(), b.time_s());
    let mut excited = [0usize; 4];
    for (i, c) in EXC.iter().enumerate() {
        let (x, y) = (a.column(c).unwrap(), b.column(c).unwrap());
        assert_eq!(x, y, "{c}");
        excited[i] = y.iter().filter(|v| **v != 0.0).count();
    }
    // every channel excited for the second and more it is given
    assert!(excited.iter().all(|n| *n > 500), "{excited:?}");

    // the ULog: one record per control step, its offset the log.csv's
    let log = Ulog::read(&r.ulog);
    let active = log.bools("excitation", "active");
    assert_eq!(active.len(), 2801);
    assert!(active.iter().all(|a| *a));
    for (i, c) in EXC.iter().enumerate() {
        let off = log.f64s("excitation", &format!("offset[{i}]"));
        assert_eq!(off, a.column(c).unwrap(), "{c}");
    }
    // the servos got the law's command with the excitation (1e-4 counts)
    let cmd = log.f64s("control", "command[2]");
    for (k, u) in r.received.iter().enumerate() {
        assert!((u[2] - cmd[k]).abs() <= 0.5e-4 + 1e-12, "servo {k}");
    }
}

/// The pilot's switch stops the excitation for the rest of the flight.
#[test]
fn the_pilots_switch_stops_the_excitation() {
    let s = sweep_scenario();
    let prepared = prepare(&s).unwrap();
    let mut o = options("excitation_manual");
    o.pilot.manual_from_s = Some(2.0);
    let r = sitl::run(&s, &prepared, &o).unwrap();
    let log = Ulog::read(&r.ulog);
    let t: Vec<f64> = log
        .u64s("excitation", "timestamp")
        .iter()
        .map(|t| *t as f64 * 1e-6)
        .collect();
    let active = log.bools("excitation", "active");
    let lon = log.f64s("excitation", "offset[2]");
    let csv = read_log_csv(&r.log_csv).unwrap();
    let exc_lon = csv.column("exc_lon").unwrap();
    let mut before = 0;
    for k in 0..t.len() {
        if t[k] < 2.0 - 1e-9 {
            assert!(active[k], "t = {}", t[k]);
            before += usize::from(lon[k] != 0.0);
        } else {
            assert!(!active[k] && lon[k] == 0.0, "t = {}", t[k]);
            assert_eq!(exc_lon[k], 0.0);
        }
    }
    assert!(before > 300, "{before} excited samples before the switch");
    assert_eq!(r.onboard.final_mode, "manual");
}
