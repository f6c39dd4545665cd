//! Flies 10 s of a scenario once (for profilers such as
//! `valgrind --tool=callgrind`): `cargo run --release -p helicon-sim
//! --example cl_profile [SCENARIO.toml [DURATION_S [FLIGHTS]]]` (default:
//! the beyond-thesis turbulence scenario, 10 s, one flight; several flights
//! of one preparation as `helicon bench` flies them, e.g. to count the
//! per-flight start-up and finish with `--toggle-collect='*fly_with*'`).
#![allow(missing_docs, clippy::unwrap_used)]
use helicon_sim::closed_loop::{fly, prepare};
use helicon_sim::scenario::Scenario;
fn main() {
    let path = std::env::args().nth(1).map_or_else(
        || {
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../scenarios/beyond-physical-turbulence.toml")
        },
        std::path::PathBuf::from,
    );
    let mut s = Scenario::from_file(&path).unwrap();
    let arg = |i: usize, default: f64| {
        std::env::args()
            .nth(i)
            .map_or(default, |a| a.parse::<f64>().unwrap())
    };
    s.duration_s = arg(2, 10.0);
    let flights = arg(3, 1.0) as usize;
    let p = prepare(&s).unwrap();
    for _ in 0..flights {
        let f = fly(&s, &p, None).unwrap();
        println!("{:?}", f.summary.outcome);
    }
}
