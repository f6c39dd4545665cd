//! State-space fit speed: the hover u–q–θ model (3 states, X_θ = −g fixed),
//! 6 free parameters (X_u, M_u, M_q, M_δ, X_δ and the input delay), fitted
//! to 2 responses (u/δ and q/δ, 100 points each, 0.2–40 rad/s) from the
//! perturbed start of `crates/ident/tests/ssfit.rs`. The responses are the
//! model's own with γ² = 0.95 and a deterministic ±1 dB, ±5° ripple, so the
//! optimum is not at zero cost.

#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_ident::Complex64;
use helicon_ident::cost::CostOptions;
use helicon_ident::frf::{Frf, log_grid};
use helicon_ident::ssfit::{Response, SsSpec, fit_ss};
use std::hint::black_box;
use std::path::Path;

const MODEL: &str = r#"
states = ["u", "q", "theta"]
inputs = ["delta"]
outputs = ["u", "q"]
[A]
u = ["X_u", 0, -9.81]
q = ["M_u", "M_q", 0.0]
theta = [0, 1, 0]
[B]
u = ["X_d"]
q = ["M_d"]
theta = [0]
[C]
u = [1, 0, 0]
q = [0, 1, 0]
[delay_s]
delta = "tau"
[[parameter]]
name = "X_u"
start = -0.5
[[parameter]]
name = "M_u"
start = 0.08
[[parameter]]
name = "M_q"
start = -2.0
max = 0.0
[[parameter]]
name = "M_d"
start = 14.0
[[parameter]]
name = "X_d"
start = -3.0
[[parameter]]
name = "tau"
start = 0.05
min = 0.0
max = 0.2
[[response]]
input = "delta"
output = "u"
frf = "frf.csv"
[[response]]
input = "delta"
output = "q"
frf = "frf.csv"
"#;

fn bench(c: &mut Criterion) {
    let spec = SsSpec::from_toml_str(MODEL, "bench.toml", Path::new("")).unwrap();
    let truth = [-0.3, 0.05, -3.0, 20.0, -4.0, 0.02];
    let m = spec.model.matrices(&truth).unwrap();
    let grid = log_grid(0.2, 40.0, 100).unwrap();
    let responses: Vec<Response> = (0..2)
        .map(|o| Response {
            input: 0,
            output: o,
            frf: Frf {
                omega_rad_s: grid.clone(),
                h: grid
                    .iter()
                    .enumerate()
                    .map(|(k, w)| {
                        let ripple = (k as f64 * 1.7 + o as f64).sin();
                        m.response(*w).unwrap()[(o, 0)]
                            * Complex64::from_polar(
                                10f64.powf(ripple / 20.0),
                                (5.0 * ripple).to_radians(),
                            )
                    })
                    .collect(),
                coherence: vec![0.95; grid.len()],
                random_error: vec![0.05; grid.len()],
            },
            omega_min_rad_s: 0.0,
            omega_max_rad_s: f64::INFINITY,
        })
        .collect();
    let mut g = c.benchmark_group("ssfit");
    g.sample_size(20);
    g.bench_function("hover_3_states_6_parameters_2_responses", |b| {
        b.iter(|| black_box(fit_ss(&spec.model, &responses, &CostOptions::default()).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
