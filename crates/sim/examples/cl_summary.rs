//! Flies every case of a scenario and prints each summary (development aid):
//! `cargo run --release -p helicon-sim --example cl_summary -- SCENARIO.toml`.
#![allow(missing_docs, clippy::unwrap_used)]
use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let scenario = Scenario::from_file(std::path::Path::new(&path)).unwrap();
    for s in scenario.cases() {
        let t0 = std::time::Instant::now();
        let p = prepare(&s).unwrap();
        let f = fly(&s, &p, None).unwrap();
        let m = &f.summary.metrics;
        println!(
            "{}: {:?} {:?} t_end {:.3} ({:.0} ms)",
            s.name,
            f.summary.outcome,
            f.summary.reason,
            f.summary.t_end_s,
            t0.elapsed().as_secs_f64() * 1e3
        );
        for k in ["vn", "ve", "vd", "psi"] {
            let x = &m[k];
            println!(
                "  {k:>3}: settle {:?} overshoot {:.1}% rms {:.4} max {:.4}",
                x.settling_time_s.map(|v| (v * 1000.0).round() / 1000.0),
                x.overshoot_pct,
                x.rms_error,
                x.max_abs_error
            );
        }
    }
}
