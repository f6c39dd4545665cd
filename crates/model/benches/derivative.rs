//! Benchmarks of the model's hot path: one derivative evaluation and one
//! RK4 step, both presets, hover and forward flight.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_model::{Input, Model, Preset, State};
use nalgebra::Vector3;
use std::hint::black_box;

fn hover_state() -> (State, Input) {
    let mut x = State::zeros();
    x[3] = 0.0573;
    x[12] = 0.016;
    x[22] = 0.1295;
    x[25] = 0.1114;
    (x, Input::new(0.185, 0.0003, -0.0008, 0.159))
}

fn bench(c: &mut Criterion) {
    for preset in [Preset::Physical, Preset::Thesis] {
        let model = Model::bergen_twin(preset);
        let (mut x, u) = hover_state();
        let w = Vector3::new(0.0, 0.0, 0.0);
        c.bench_function(&format!("derivative/{}/hover", preset.name()), |b| {
            b.iter(|| model.derivative(black_box(&x), black_box(&u), black_box(&w)))
        });
        x[6] = 10.0;
        c.bench_function(&format!("derivative/{}/forward_10ms", preset.name()), |b| {
            b.iter(|| model.derivative(black_box(&x), black_box(&u), black_box(&w)))
        });
        c.bench_function(&format!("rk4_step/{}/forward_10ms", preset.name()), |b| {
            b.iter(|| model.step(black_box(&x), black_box(&u), black_box(&w), 1.0 / 400.0))
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
