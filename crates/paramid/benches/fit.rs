//! Speed of the identification: the noise-free 2-operating-point,
//! 16-response, 10-parameter fit of `tests/noise_free.rs` (truth-a from the
//! nominal Bergen Twin, bounded Levenberg–Marquardt), and one evaluation of
//! the cost (two trims, two linearisations, 640 frequency points).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_model::Params;
use helicon_paramid::config::IdentConfig;
use helicon_paramid::cost::Cost;
use helicon_paramid::data::from_model;
use helicon_paramid::fit::{FitOptions, identify};
use std::path::Path;

fn bench(c: &mut Criterion) {
    let cfg = IdentConfig::from_toml_str(
        include_str!("../fixtures/noise_free.toml"),
        "noise_free.toml",
        Path::new("."),
    )
    .unwrap();
    let truth = Params::from_toml_str(
        include_str!("../../../params/truths/truth-a.toml"),
        "truth-a.toml",
    )
    .unwrap();
    let data = from_model(&cfg, &truth).unwrap();
    let cost = Cost::new(&cfg, &data).unwrap();
    let start: Vec<f64> = cfg.parameters.iter().map(|p| p.start).collect();
    let mut g = c.benchmark_group("paramid");
    g.sample_size(10);
    g.bench_function("cost_2op_16resp", |b| {
        b.iter(|| cost.residuals(&start).unwrap())
    });
    g.bench_function("fit_2op_16resp_10par_lm", |b| {
        b.iter(|| {
            identify(
                &cost,
                &FitOptions {
                    optimiser: helicon_paramid::config::Optimiser::Lm,
                    max_iterations: 100,
                    auto_fix: false,
                },
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
