#![allow(missing_docs, clippy::unwrap_used)]
use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let s = Scenario::from_file(std::path::Path::new(&path)).unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    for r in f.log.iter().step_by(100) {
        println!(
            "{:5.2} psi {:8.4} vn {:8.4} ve {:8.4} vd {:8.4} u {:?}",
            r.t_s,
            r.output[3],
            r.output[0],
            r.output[1],
            r.output[2],
            r.u.as_slice()
                .iter()
                .map(|v| (v * 1000.0).round() / 1000.0)
                .collect::<Vec<_>>()
        );
    }
}
