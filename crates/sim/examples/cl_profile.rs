//! Flies 10 s of a scenario once (for profilers such as
//! `valgrind --tool=callgrind`): `cargo run --release -p helicon-sim
//! --example cl_profile [SCENARIO.toml]` (default: the beyond-thesis
//! turbulence scenario).
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
    s.duration_s = 10.0;
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    println!("{:?}", f.summary.outcome);
}
