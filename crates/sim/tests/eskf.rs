//! The ESKF navigation against the thesis's chain on the same flights.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::too_many_lines)] // tests

use helicon_sim::closed_loop::{Flight, Outcome, fly, prepare};
use helicon_sim::scenario::{EstimatorKind, Scenario};
use std::path::Path;

fn scenario(name: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    Scenario::from_file(&path).unwrap()
}

/// `demo.toml` without turbulence (steady 2 m/s wind), with `kind` and sensor `seed`.
fn demo(kind: EstimatorKind, seed: u64) -> Scenario {
    let mut s = scenario("demo.toml");
    s.wind.dryden = None;
    s.sensors.seed = seed;
    s.estimator.kind = kind;
    s.log.decimation = 1;
    s
}

/// Mean of (true − reference) of output `i` (vn ve vd) over [t0, t1).
fn mean_offset(f: &Flight, i: usize, t0: f64, t1: f64) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for r in f.log.iter().filter(|r| r.t_s >= t0 && r.t_s < t1) {
        s += r.output[i] - r.reference[i];
        n += 1.0;
    }
    s / n
}

/// The settled windows of the demo: after the vn step (1 s), the heading
/// step (6 s) and the climb step (12 s), each from 3 s after its step to the next.
const WINDOWS: [(f64, f64); 3] = [(4.0, 6.0), (9.0, 12.0), (15.0, 20.0)];

/// Per output (vn ve vd) and window: the mean true offset.
fn offsets(f: &Flight) -> [[f64; 3]; 3] {
    std::array::from_fn(|w| std::array::from_fn(|i| mean_offset(f, i, WINDOWS[w].0, WINDOWS[w].1)))
}

#[test]
#[ignore = "report: prints the figures of docs/navigation-eskf.md"]
fn report_steady_state_offsets() {
    for kind in [EstimatorKind::Thesis, EstimatorKind::Eskf] {
        let mut worst: f64 = 0.0;
        let mut sum = [[0.0; 3]; 3];
        let seeds = 20;
        for seed in 1..=seeds {
            let s = demo(kind, seed);
            let p = prepare(&s).unwrap();
            let f = fly(&s, &p, None).unwrap();
            assert_eq!(f.summary.outcome, Outcome::Completed);
            let o = offsets(&f);
            for w in 0..3 {
                for i in 0..3 {
                    worst = worst.max(o[w][i].abs());
                    sum[w][i] += o[w][i] / f64::from(seeds as u32);
                }
            }
            println!("{kind:?} seed {seed}: {o:.3?}");
        }
        println!("{kind:?}: mean over seeds {sum:.4?}, worst seed {worst:.3}");
    }
}
