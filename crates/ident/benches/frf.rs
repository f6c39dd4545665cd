//! Frequency-response speed on a 100 s, 400 Hz log (40 000 samples, input
//! and output): the single-window estimate on the FFT bins (10 s Hann
//! windows, half overlap: cross and auto spectra, H, coherence, random
//! error) and the 5-window composite on 200 log-spaced frequencies
//! (windows 50, 25, 12.5, 6.25, 3.125 s). Compare with
//! `tools/bench_ident_scipy.py`, which times SciPy on the identical signal
//! and runs this bench in the same go.

#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use helicon_ident::frf::{
    WindowSpec, composite, cross_spectra_fft, cross_spectra_grid, log_grid, siso,
};
use std::hint::black_box;

/// The log of tools/bench_ident_scipy.py: x a logarithmic sweep 0.05 → 5 Hz
/// plus a deterministic disturbance, y = x through a first-order lag (pole
/// 0.98) plus another disturbance.
pub fn log_100s_400hz() -> (Vec<f64>, Vec<f64>, f64) {
    let (n, dt) = (40_000usize, 1.0 / 400.0);
    let (f0, f1, t1) = (0.05_f64, 5.0_f64, 100.0_f64);
    let k = (f1 / f0).ln() / t1;
    let x: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 * dt;
            let phase = 2.0 * std::f64::consts::PI * f0 * ((k * t).exp() - 1.0) / k;
            phase.sin() + 0.1 * (0.37 * (i as f64) * (i as f64) % 1.0 - 0.5)
        })
        .collect();
    let mut y = vec![0.0; n];
    let mut s = 0.0;
    for i in 0..n {
        s = 0.98 * s + 0.02 * x[i];
        y[i] = s + 0.05 * (0.71 * (i as f64) * (i as f64) % 1.0 - 0.5);
    }
    (x, y, dt)
}

fn bench(c: &mut Criterion) {
    let (x, y, dt) = log_100s_400hz();
    let mut g = c.benchmark_group("frf_100s_400hz");
    g.sample_size(20);
    g.bench_function("single_window_fft_4000", |b| {
        b.iter(|| {
            let cs = cross_spectra_fft(&[&x, &y], dt, WindowSpec::half_overlap(4000)).unwrap();
            black_box(siso(&cs, 0, 1).unwrap())
        })
    });
    let grid = log_grid(0.3, 30.0, 200).unwrap();
    let lens = [20_000usize, 10_000, 5_000, 2_500, 1_250];
    let secs: Vec<f64> = lens.iter().map(|l| *l as f64 * dt).collect();
    g.bench_function("composite_5_windows_200_points", |b| {
        b.iter(|| {
            let parts: Vec<_> = lens
                .iter()
                .map(|&l| {
                    siso(
                        &cross_spectra_grid(&[&x, &y], dt, WindowSpec::half_overlap(l), &grid)
                            .unwrap(),
                        0,
                        1,
                    )
                    .unwrap()
                })
                .collect();
            black_box(composite(&parts, &secs).unwrap())
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
