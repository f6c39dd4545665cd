//! DARE benchmarks on the thesis hover model (27 states, 400 Hz) and its integral-augmented
//! version (31 states), thesis weights (14.23), (14.27), (14.35), (14.36), ρ = 10, pincer α
//! from ts = 5 s (14.22). Target: ≤ 2 ms each (issue 4). Compare with
//! `tools/bench_scipy_dare.py` (same problems, SciPy `solve_discrete_are`).

#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_lti::*;
use nalgebra::DMatrix;
use std::hint::black_box;

fn read_named_csv(path: &str) -> DMatrix<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .skip(1)
                .map(|c| c.trim().parse::<f64>().unwrap())
                .collect()
        })
        .collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

fn bench(c: &mut Criterion) {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures");
    let a = read_named_csv(&format!("{dir}/thesis_A.csv"));
    let b = read_named_csv(&format!("{dir}/thesis_B.csv"));
    let ts = 1.0 / 400.0;
    let (phi, gamma) = c2d(&a, &b, ts).unwrap();
    let hs = DMatrix::from_fn(4, 27, |i, j| if j == i + 2 { 1.0 } else { 0.0 });
    let (q1, r) = bryson_weights(&hs, &[3.0; 4], &[0.1, 0.7, 0.7, 0.04], 10.0).unwrap();
    let alpha = alpha_from_settling_time(ts, 5.0).unwrap();
    let aug = augment_integral(&phi, &gamma, &hs).unwrap();
    let qy = bryson(&[3.0; 4]).unwrap();
    let qi = &qy * 1e-4;
    let q1i = aug.he.transpose() * &qy * &aug.he + aug.hi.transpose() * &qi * &aug.hi;
    let (pa, ga) = (&aug.phi * alpha, &aug.gamma * alpha);

    c.bench_function("dare_thesis_27", |bch| {
        bch.iter(|| dare(black_box(&phi), black_box(&gamma), &q1, &r, None).unwrap())
    });
    c.bench_function("dare_thesis_27_pincer", |bch| {
        let (pp, gg) = (&phi * alpha, &gamma * alpha);
        bch.iter(|| dare(black_box(&pp), black_box(&gg), &q1, &r, None).unwrap())
    });
    c.bench_function("dare_thesis_31_integral_pincer", |bch| {
        bch.iter(|| dare(black_box(&pa), black_box(&ga), &q1i, &r, None).unwrap())
    });
    // Strict mode: PBH stabilizability/detectability checks before solving.
    let opts = DareOptions {
        check_structure: true,
        ..DareOptions::default()
    };
    c.bench_function("dare_thesis_31_integral_pincer_strict", |bch| {
        bch.iter(|| dare_with(black_box(&pa), black_box(&ga), &q1i, &r, None, &opts).unwrap())
    });
    c.bench_function("c2d_thesis_27", |bch| {
        bch.iter(|| c2d(black_box(&a), &b, ts).unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
