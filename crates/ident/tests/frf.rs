//! Frequency responses against analytic references.
//!
//! - A second-order system with a delay, driven by a sweep, output noise:
//!   the estimate lies within its random error of the analytic response (the
//!   normalised error |Ĥ − H| / (|H| ε) is Rayleigh-distributed with σ = 1
//!   if ε is right: median 1.18, 95th percentile 2.45), and the coherence
//!   drops where the noise dominates (above the sweep's top frequency).
//! - Two correlated inputs into a known two-input discrete system: the
//!   conditioned estimates recover each path within their random error where
//!   the single-input estimate is biased by many random errors.
//! - The composite of five windows stays within its error bound.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::{SecondOrder, noise, percentile};
use helicon_ident::Complex64;
use helicon_ident::frf::{WindowSpec, composite, conditioned, cross_spectra_grid, log_grid, siso};
use helicon_ident::inputs::Sweep;

const DT: f64 = 0.01;

fn normalised_errors(
    f: &helicon_ident::frf::Frf,
    truth: impl Fn(f64) -> Complex64,
    min_coh: f64,
) -> Vec<f64> {
    (0..f.len())
        .filter(|&k| f.coherence[k] > min_coh)
        .map(|k| {
            let h = truth(f.omega_rad_s[k]);
            (f.h[k] - h).norm() / (h.norm() * f.random_error[k])
        })
        .collect()
}

fn sweep_record(noise_sigma: f64, seed: u64) -> (SecondOrder, Vec<f64>, Vec<f64>) {
    let sys = SecondOrder {
        wn: 8.0,
        zeta: 0.3,
        delay_s: 0.05,
    };
    let sweep = Sweep::new(1.0, 0.5, 40.0, 160.0).unwrap();
    // 5 s at rest after the sweep: the output rings down (e^{−ζωn·5} = 6e-6).
    let n = (165.0 / DT) as usize + 1;
    let x: Vec<f64> = (0..n).map(|i| sweep.value(i as f64 * DT)).collect();
    let clean = sys.simulate(&|t| sweep.value(t), DT, n, 10);
    let y: Vec<f64> = clean
        .iter()
        .zip(noise(seed, noise_sigma, n))
        .map(|(a, b)| a + b)
        .collect();
    (sys, x, y)
}

#[test]
fn second_order_plus_delay_from_a_noisy_sweep_is_within_its_random_error() {
    let (sys, x, y) = sweep_record(0.2, 7);
    let grid = log_grid(1.0, 120.0, 150).unwrap();
    let spec = WindowSpec::half_overlap(2000); // 20 s windows, 15 of them
    let cs = cross_spectra_grid(&[&x, &y], DT, spec, &grid).unwrap();
    let f = siso(&cs, 0, 1).unwrap();
    let e = normalised_errors(&f, |w| sys.h(w), 0.6);
    let (p50, p95) = (percentile(&e, 0.5), percentile(&e, 0.95));
    println!("points {} median {p50:.3} p95 {p95:.3}", e.len());
    assert!(e.len() > 80, "{} points with γ² > 0.6", e.len());
    // Within the random error as a distribution: neither too large (a biased
    // estimate) nor much too small (an error bound far too loose).
    assert!(p50 > 0.5 && p50 < 1.8, "median {p50}");
    assert!(p95 < 3.5, "95th percentile {p95}");
    // Coherence high where the sweep excites, low above ω_max = 40 rad/s
    // where only noise is left.
    let coh = |lo: f64, hi: f64| {
        let v: Vec<f64> = (0..f.len())
            .filter(|&k| (lo..hi).contains(&f.omega_rad_s[k]))
            .map(|k| f.coherence[k])
            .collect();
        percentile(&v, 0.5)
    };
    let (c_low, c_high) = (coh(1.0, 15.0), coh(60.0, 120.0));
    println!("median γ² 1–15 rad/s {c_low:.4}, 60–120 rad/s {c_high:.4}");
    assert!(c_low > 0.95, "{c_low}");
    assert!(c_high < 0.3, "{c_high}");
}

#[test]
fn noise_free_sweep_recovers_the_analytic_response() {
    let (sys, x, y) = sweep_record(0.0, 0);
    let grid = log_grid(1.0, 30.0, 100).unwrap();
    let rel = |spec: WindowSpec| {
        let f = siso(
            &cross_spectra_grid(&[&x, &y], DT, spec, &grid).unwrap(),
            0,
            1,
        )
        .unwrap();
        assert!(f.coherence.iter().all(|c| *c > 0.99));
        (0..f.len())
            .map(|k| (f.h[k] - sys.h(f.omega_rad_s[k])).norm() / sys.h(f.omega_rad_s[k]).norm())
            .fold(0.0, f64::max)
    };
    // One untapered window over the record (at rest at both ends): Y = H·X
    // up to the RK4 truncation and aliasing, 1e-6.
    let whole = rel(WindowSpec::whole_record(x.len()));
    // Hann windows on a sweep: the taper changes across the system's memory,
    // a bias of ~1 % around the resonance (what the composite's and the
    // fits' tolerances must allow for).
    let hann = rel(WindowSpec::half_overlap(4000));
    println!("noise-free worst relative error: whole record {whole:e}, 40 s Hann windows {hann:e}");
    assert!(whole < 1e-6, "{whole}");
    assert!(hann < 5e-2, "{hann}");
}

#[test]
fn composite_of_five_windows_is_within_its_error_bound() {
    let (sys, x, y) = sweep_record(0.05, 11);
    let grid = log_grid(0.7, 30.0, 200).unwrap();
    let lens = [8000usize, 4000, 2000, 1000, 500];
    let parts: Vec<_> = lens
        .iter()
        .map(|&l| {
            siso(
                &cross_spectra_grid(&[&x, &y], DT, WindowSpec::half_overlap(l), &grid).unwrap(),
                0,
                1,
            )
            .unwrap()
        })
        .collect();
    let secs: Vec<f64> = lens.iter().map(|l| *l as f64 * DT).collect();
    let c = composite(&parts, &secs).unwrap();
    // Below 4π/80 s = 0.157 rad/s no window would do; all grid points are above.
    assert_eq!(c.len(), 200);
    let e = normalised_errors(&c, |w| sys.h(w), 0.6);
    let p95 = percentile(&e, 0.95);
    println!(
        "composite: {} points, median {:.3}, p95 {p95:.3}",
        e.len(),
        percentile(&e, 0.5)
    );
    // ε of the composite is an upper bound: 95 % of points within 3.5 bounds.
    assert!(p95 < 3.5, "{p95}");
    // The composite is no worse than the longest window's estimate alone.
    let single = normalised_errors(&parts[0], |w| sys.h(w), 0.6);
    let rel = |f: &helicon_ident::frf::Frf| {
        let v: Vec<f64> = (0..f.len())
            .map(|k| (f.h[k] - sys.h(f.omega_rad_s[k])).norm() / sys.h(f.omega_rad_s[k]).norm())
            .collect();
        percentile(&v, 0.5)
    };
    println!(
        "median relative error: composite {:.4}, 80 s window {:.4} ({} pts)",
        rel(&c),
        rel(&parts[0]),
        single.len()
    );
    assert!(rel(&c) <= 1.2 * rel(&parts[0]));
}

/// H1(z) = 0.5 z⁻¹ / (1 − 0.8 z⁻¹), H2(z) = −0.6 + 0.3 z⁻², at ω rad/s.
fn paths(w: f64) -> (Complex64, Complex64) {
    let z1 = Complex64::from_polar(1.0, -w * DT);
    (0.5 * z1 / (1.0 - 0.8 * z1), -0.6 + 0.3 * z1 * z1)
}

#[test]
fn conditioned_responses_recover_each_path_of_correlated_inputs() {
    let n = 60_000;
    let (r1, r2, v) = (noise(1, 1.0, n), noise(2, 1.0, n), noise(3, 0.1, n));
    // u2 correlated with u1 (as servos moved by one feedback law).
    let u1 = r1.clone();
    let u2: Vec<f64> = (0..n).map(|i| 0.8 * r1[i] + 0.6 * r2[i]).collect();
    let mut y = vec![0.0; n];
    let mut s1 = 0.0;
    for i in 0..n {
        let y1 = s1; // 0.5 z⁻¹/(1 − 0.8 z⁻¹): s1 holds the state
        s1 = 0.8 * s1 + 0.5 * u1[i];
        let y2 = -0.6 * u2[i] + if i >= 2 { 0.3 * u2[i - 2] } else { 0.0 };
        y[i] = y1 + y2 + v[i];
    }
    // From two periods per 10 s window up to 0.8 Nyquist.
    let grid = log_grid(1.3, 250.0, 120).unwrap();
    let cs =
        cross_spectra_grid(&[&u1, &u2, &y], DT, WindowSpec::half_overlap(1000), &grid).unwrap();
    let (fr, mult) = conditioned(&cs, &[0, 1], 2).unwrap();
    assert!(mult.iter().all(|g| *g > 0.5), "multiple coherence");
    assert_eq!((fr[0].len(), fr[1].len()), (120, 120));
    // Judged where the partial coherence exceeds 0.6 (the random-error
    // formula is a small-error approximation).
    let e1 = normalised_errors(&fr[0], |w| paths(w).0, 0.6);
    let e2 = normalised_errors(&fr[1], |w| paths(w).1, 0.6);
    println!(
        "points with partial γ² > 0.6: {} and {}",
        e1.len(),
        e2.len()
    );
    assert!(e1.len() > 60 && e2.len() > 60);
    for (name, e) in [("H1", &e1), ("H2", &e2)] {
        let (p50, p95) = (percentile(e, 0.5), percentile(e, 0.95));
        println!("conditioned {name}: median {p50:.3} p95 {p95:.3}");
        assert!(p50 > 0.5 && p50 < 1.8 && p95 < 3.5, "{name}: {p50} {p95}");
    }
    // The single-input estimate of path 1 carries H2·G12/G11: biased by far
    // more than its random error.
    let single = siso(&cs, 0, 2).unwrap();
    let es = normalised_errors(&single, |w| paths(w).0, 0.0);
    let p50 = percentile(&es, 0.5);
    println!("single-input H1: median normalised error {p50:.1}");
    assert!(p50 > 10.0, "{p50}");
    // Fully correlated inputs: no point is estimable, none is returned.
    let (fr, _) = conditioned(
        &cross_spectra_grid(
            &[&u1, &u1.clone(), &y],
            DT,
            WindowSpec::half_overlap(1000),
            &grid,
        )
        .unwrap(),
        &[0, 1],
        2,
    )
    .unwrap();
    assert!(fr[0].is_empty() && fr[1].is_empty());
}
