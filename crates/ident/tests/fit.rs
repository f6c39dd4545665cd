//! Transfer-function fits against known systems: exact recovery from an
//! analytic response; recovery within the Cramér–Rao bounds from a response
//! estimated from a noisy sweep; the time-domain verification on a doublet
//! (Theil coefficient) telling a good fit from a wrong one.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::{SecondOrder, noise};
use helicon_ident::fit::{CostOptions, TfStructure, coherence_weight, fit_tf, simulate, theil};
use helicon_ident::frf::{Frf, WindowSpec, composite, cross_spectra_grid, log_grid, siso};
use helicon_ident::inputs::{Doublet, Sweep};

const DT: f64 = 0.01;
const SYS: SecondOrder = SecondOrder {
    wn: 8.0,
    zeta: 0.3,
    delay_s: 0.05,
};
const ST: TfStructure = TfStructure {
    num_order: 0,
    den_order: 2,
    delay: true,
};

/// [b0, a1, a0, τ] of SYS.
fn truth() -> [f64; 4] {
    [64.0, 2.0 * 0.3 * 8.0, 64.0, 0.05]
}

#[test]
fn coherence_weight_is_the_cifer_one() {
    // [1.58 (1 − e^{−γ²})]²: 0.9975 at γ² = 1, 0.5082 at γ² = 0.6 (values
    // from Python's math.exp); e^{−γ⁴} would give 0.3045 at 0.6.
    assert!((coherence_weight(1.0) - 0.9975025271911028).abs() < 1e-14);
    assert!((coherence_weight(0.6) - 0.5081944939273663).abs() < 1e-14);
}

#[test]
fn analytic_response_gives_back_the_coefficients() {
    let grid = log_grid(0.5, 40.0, 80).unwrap();
    let frf = Frf {
        h: grid.iter().map(|w| SYS.h(*w)).collect(),
        coherence: vec![1.0; grid.len()],
        random_error: vec![0.01; grid.len()],
        omega_rad_s: grid,
    };
    let fit = fit_tf(&frf, ST, &CostOptions::default(), None).unwrap();
    println!("{:?} J = {:e}", fit.params, fit.cost);
    for (p, t) in fit.params.iter().zip(truth()) {
        assert!((p - t).abs() < 1e-6 * t.abs().max(1.0), "{p} vs {t}");
    }
    assert!(fit.cost < 1e-12);
    assert_eq!(fit.names, vec!["b0", "a1", "a0", "tau_s"]);
    assert_eq!(fit.den[0], 1.0);
    // Improper or over-parameterised structures are refused.
    let bad = TfStructure {
        num_order: 3,
        den_order: 2,
        delay: false,
    };
    assert!(fit_tf(&frf, bad, &CostOptions::default(), None).is_err());
}

fn noisy_sweep_frf(seed: u64) -> (Frf, Vec<f64>, Vec<f64>) {
    let sweep = Sweep::new(1.0, 0.5, 40.0, 160.0).unwrap();
    let n = (160.0 / DT) as usize + 1;
    let x: Vec<f64> = (0..n).map(|i| sweep.value(i as f64 * DT)).collect();
    let clean = SYS.simulate(&|t| sweep.value(t), DT, n, 10);
    let y: Vec<f64> = clean
        .iter()
        .zip(noise(seed, 0.05, n))
        .map(|(a, b)| a + b)
        .collect();
    let grid = log_grid(0.7, 40.0, 150).unwrap();
    let lens = [8000usize, 4000, 2000, 1000];
    let parts: Vec<Frf> = lens
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
    (composite(&parts, &secs).unwrap(), x, y)
}

#[test]
fn noisy_sweep_fit_is_within_its_cramer_rao_bounds() {
    let mut worst = 0.0_f64;
    for seed in [21, 22, 23] {
        let (frf, _, _) = noisy_sweep_frf(seed);
        let fit = fit_tf(&frf, ST, &CostOptions::default(), None).unwrap();
        // The cost of the true system on this response, computed here from
        // the formula: the optimum can only be lower.
        let (mut jt, mut nn) = (0.0, 0);
        for k in 0..frf.len() {
            if frf.coherence[k] > 0.6 {
                nn += 1;
                let r = frf.h[k] / SYS.h(frf.omega_rad_s[k]);
                let (dm, dp) = (20.0 * r.norm().log10(), r.arg().to_degrees());
                jt += coherence_weight(frf.coherence[k]) * (dm * dm + 0.01745 * dp * dp);
            }
        }
        let j_truth = 20.0 * jt / nn as f64;
        assert_eq!(nn, fit.n_points);
        assert!(
            fit.cost <= j_truth * (1.0 + 1e-9),
            "{} > {j_truth}",
            fit.cost
        );
        for (i, t) in truth().iter().enumerate() {
            let z = (fit.params[i] - t).abs() / fit.cramer_rao[i];
            worst = worst.max(z);
            println!(
                "seed {seed} {}: {:.5} ± {:.5} (CR {:.2} %, I {:.2} %) truth {t}, {z:.2} bounds",
                fit.names[i],
                fit.params[i],
                fit.cramer_rao[i],
                fit.cramer_rao_pct[i],
                fit.insensitivity_pct[i]
            );
            assert!(fit.insensitivity_pct[i] <= fit.cramer_rao_pct[i] + 1e-12);
        }
        println!(
            "seed {seed}: J = {:.3} (truth {j_truth:.3}), {} points",
            fit.cost, fit.n_points
        );
    }
    // Within 3 bounds for every parameter of every seed.
    assert!(worst < 3.0, "{worst}");
}

#[test]
fn doublet_verification_tells_a_good_fit_from_a_wrong_one() {
    let (frf, _, _) = noisy_sweep_frf(31);
    let fit = fit_tf(&frf, ST, &CostOptions::default(), None).unwrap();
    let d = Doublet {
        amplitude: 1.0,
        pulse_s: 0.4,
    };
    let n = 600;
    // The doublet held over each sample (as the simulation holds it), measured with noise.
    let u: Vec<f64> = (0..n).map(|i| d.value(i as f64 * DT - 0.5)).collect();
    let held = |t: f64| d.value((t / DT).floor() * DT - 0.5);
    let y_true = SYS.simulate(&held, DT, n, 10);
    let y: Vec<f64> = y_true
        .iter()
        .zip(noise(32, 0.02, n))
        .map(|(a, b)| a + b)
        .collect();
    let good = theil(&y, &simulate(&fit, &u, DT).unwrap()).unwrap();
    // The noise alone: Theil of the true response against the measurement.
    let floor = theil(&y, &y_true).unwrap();
    let mut wrong = fit.clone();
    wrong.den[2] *= 1.5; // ωn 22 % high
    wrong.num[0] *= 1.5;
    let bad = theil(&y, &simulate(&wrong, &u, DT).unwrap()).unwrap();
    println!("Theil: fit {good:.4}, truth {floor:.4}, wrong {bad:.4}");
    assert!(good < 0.1 && good < floor + 0.02, "{good} {floor}");
    assert!(bad > 2.0 * good, "{bad}");
    assert!(theil(&[0.0; 3], &[0.0; 3]).is_err());
}
