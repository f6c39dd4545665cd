//! Prints a coarse trace of a scenario's closed-loop flight (development aid):
//! `cargo run --release -p helicon-sim --example cl_trace -- SCENARIO.toml [every]`.
#![allow(missing_docs, clippy::unwrap_used)]
use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let every: usize = std::env::args().nth(2).map_or(100, |s| s.parse().unwrap());
    let s = Scenario::from_file(std::path::Path::new(&path)).unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    for r in f.log.iter().step_by(every) {
        println!(
            "{:5.3} psi {:8.4} vn {:7.3} ve {:7.3} vd {:7.3} lam {:8.4} {:8.4} thr {:7.2} {:7.2} th_tr {:6.3} u {:?}",
            r.t_s,
            r.output[3],
            r.output[0],
            r.output[1],
            r.output[2],
            r.lambda[0],
            r.lambda[1],
            r.thrust[0],
            r.thrust[1],
            r.x[25],
            r.u.as_slice()
                .iter()
                .map(|v| (v * 1000.0).round() / 1000.0)
                .collect::<Vec<_>>()
        );
    }
    println!(
        "{:?} {:?} t_end {}",
        f.summary.outcome, f.summary.reason, f.summary.t_end_s
    );
}
