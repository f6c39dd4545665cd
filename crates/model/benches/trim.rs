//! Benchmarks of trim (cold start) and linearization (issue 3 targets:
//! hover trim ≤ 5 ms, one linearization ≤ 2 ms).
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, Preset};
use nalgebra::Vector3;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let model = Model::bergen_twin(Preset::Thesis);
    c.bench_function("trim/hover_cold_start", |b| {
        b.iter(|| {
            trim(
                black_box(&model),
                &TrimTarget::hover(),
                &TrimOptions::default(),
            )
            .unwrap()
        })
    });
    let fwd = TrimTarget {
        velocity_ned_m_s: Vector3::new(10.0, 0.0, 0.0),
        ..TrimTarget::hover()
    };
    c.bench_function("trim/forward_10ms_cold_start", |b| {
        b.iter(|| trim(black_box(&model), &fwd, &TrimOptions::default()).unwrap())
    });
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    c.bench_function("linearize/hover_converged", |b| {
        b.iter(|| {
            linearize(
                black_box(&model),
                &t.x,
                &t.u,
                &Vector3::zeros(),
                InflowMode::Converged,
            )
            .unwrap()
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
