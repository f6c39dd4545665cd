//! Servo identification speed on the bench test `helicon ident servo-bench`
//! writes (the Bergen Twin's collective servo, 17.7 s at 400 Hz, 7080
//! samples, 2 mrad noise): the whole fit (grid start, the fit without and
//! the four fits with a rate limit, standard errors), and one simulation of
//! the servo over the log (the fit's unit of work).

#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_ident::servo::{BenchInput, ServoFitOptions, ServoModel, fit_servo};
use helicon_model::Params;
use helicon_model::actuators::servo_response;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let s = Params::bergen_twin().servos[0];
    let dt = 1.0 / 400.0;
    let cmd = BenchInput::new(s.s_min, s.s_max)
        .unwrap()
        .sample(dt)
        .unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let d = Normal::new(0.0, 0.002).unwrap();
    let y: Vec<f64> = servo_response(&s, &cmd, dt, [s.gain_rad * cmd[0], 0.0])
        .iter()
        .map(|x| x[0] + d.sample(&mut rng))
        .collect();
    let opts = ServoFitOptions {
        s_min: s.s_min,
        s_max: s.s_max,
        ..ServoFitOptions::default()
    };
    let mut g = c.benchmark_group("servo");
    g.sample_size(10);
    g.bench_function("fit_servo 7080 samples", |b| {
        b.iter(|| fit_servo(black_box(&cmd), black_box(&y), dt, &opts).unwrap())
    });
    let m = ServoModel {
        gain_rad: s.gain_rad,
        omega_n_rad_s: s.omega_n_rad_s,
        zeta: s.zeta,
        rate_max_rad_s: s.rate_max_rad_s,
        s_min: s.s_min,
        s_max: s.s_max,
    };
    g.bench_function("simulate 7080 samples", |b| {
        b.iter(|| m.simulate(black_box(&cmd), dt, 1, [0.07, 0.0]))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
