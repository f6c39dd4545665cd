//! On the helicopter: sweeps on each servo of the linearised hover model
//! (thesis Appendix E, 27 states, the matrices shared with the lti crate's
//! fixtures), flown in closed loop (a discrete LQR makes the unstable hover
//! flyable, so the servos move together: correlated inputs), one sweep per
//! servo from rest to rest. The conditioned four-input responses from the
//! applied servo inputs to p, q, r and w recover the model's own frequency
//! responses C(zI − Φ)⁻¹Γ, z = e^{jωT}, from its A, B (ZOH at 400 Hz), to
//! 1e-3 noise-free.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::Complex64;
use helicon_ident::frf::{CrossSpectra, WindowSpec, conditioned, cross_spectra_grid, log_grid};
use helicon_ident::inputs::Sweep;
use nalgebra::{DMatrix, DVector};

fn read_named_csv(name: &str) -> DMatrix<f64> {
    let path = format!(
        "{}/../lti/tests/fixtures/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .skip(1)
                .map(|c| c.trim().parse().unwrap())
                .collect()
        })
        .collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

/// Reduced-state indices of the outputs p, q, r, w.
const OUTPUTS: [(usize, &str); 4] = [(6, "p"), (7, "q"), (8, "r"), (5, "w")];
const SERVOS: [&str; 4] = ["S_col", "S_lat", "S_lon", "S_tr"];

#[test]
fn servo_sweeps_in_closed_loop_recover_the_hover_model_responses() {
    let (a, b) = (
        read_named_csv("thesis_A.csv"),
        read_named_csv("thesis_B.csv"),
    );
    let dt = 1.0 / 400.0;
    let (phi, gamma) = helicon_lti::c2d(&a, &b, dt).unwrap();
    let q = DMatrix::identity(27, 27);
    let r = DMatrix::identity(4, 4) * 10.0;
    let k = helicon_lti::dlqr(&phi, &gamma, &q, &r, None).unwrap().k;
    let sweep = Sweep::new(0.01, 0.5, 30.0, 80.0).unwrap();
    // 40 s at rest after the sweep: the closed loop settles to 1e-9 of its peak.
    let n = (120.0 / dt) as usize;
    let grid = log_grid(0.5, 30.0, 60).unwrap();
    let mut parts = Vec::new();
    for servo in 0..4 {
        let mut x = DVector::zeros(27);
        let mut ch: Vec<Vec<f64>> = (0..8).map(|_| Vec::with_capacity(n)).collect();
        let mut peak = 0.0_f64;
        for i in 0..n {
            let mut u = -(&k * &x);
            u[servo] += sweep.value(i as f64 * dt);
            for j in 0..4 {
                ch[j].push(u[j]);
                ch[4 + j].push(x[OUTPUTS[j].0]);
            }
            x = &phi * &x + &gamma * &u;
            peak = peak.max(x.amax());
        }
        assert!(
            x.amax() < 1e-9 * peak,
            "servo {servo}: not at rest at the end ({:e})",
            x.amax() / peak
        );
        let refs: Vec<&[f64]> = ch.iter().map(Vec::as_slice).collect();
        parts.push(cross_spectra_grid(&refs, dt, WindowSpec::whole_record(n), &grid).unwrap());
    }
    let cs = CrossSpectra::merge(&parts).unwrap();
    let mut worst = 0.0_f64;
    let mut worst_single = 0.0_f64;
    for (o, (row, out)) in OUTPUTS.iter().enumerate() {
        let (frfs, _) = conditioned(&cs, &[0, 1, 2, 3], 4 + o).unwrap();
        for (s, f) in frfs.iter().enumerate() {
            assert_eq!(f.len(), grid.len(), "{out}/{}", SERVOS[s]);
            // The model's own response from A, B (discretised): C (zI − Φ)⁻¹ Γ.
            let model: Vec<Complex64> = grid
                .iter()
                .map(|w| {
                    let z = Complex64::from_polar(1.0, w * dt);
                    let m = DMatrix::from_fn(27, 27, |i, j| {
                        (if i == j { z } else { Complex64::new(0.0, 0.0) })
                            - Complex64::new(phi[(i, j)], 0.0)
                    });
                    let g = DVector::from_fn(27, |i, _| Complex64::new(gamma[(i, s)], 0.0));
                    m.lu().solve(&g).unwrap()[*row]
                })
                .collect();
            let scale = model.iter().map(|v| v.norm()).fold(0.0, f64::max);
            let rel = (0..grid.len())
                .map(|i| (f.h[i] - model[i]).norm() / model[i].norm().max(1e-3 * scale))
                .fold(0.0, f64::max);
            // Unconditioned, the feedback-correlated servos bias the estimate.
            let single = helicon_ident::frf::siso(&cs, s, 4 + o).unwrap();
            let rel_single = (0..single.len())
                .map(|i| (single.h[i] - model[i]).norm() / model[i].norm().max(1e-3 * scale))
                .fold(0.0, f64::max);
            println!(
                "{out}/{}: peak |H| {scale:.3e}, worst relative error {rel:.2e} (single-input {rel_single:.2e})",
                SERVOS[s]
            );
            worst = worst.max(rel);
            worst_single = worst_single.max(rel_single);
        }
    }
    assert!(worst < 1e-3, "{worst}");
    assert!(worst_single > 0.1, "{worst_single}");
}
