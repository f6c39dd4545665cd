//! Published DARE cases: MATLAB `dare` documentation examples (to all printed digits) and
//! the DAREX collection (P. Benner, A. J. Laub, V. Mehrmann, "A collection of benchmark
//! examples for the numerical solution of algebraic Riccati equations II: discrete-time
//! case", TU Chemnitz-Zwickau SPC 95_23, 1995; SLICOT BB02AD), where the exact solution is
//! known in closed form. The data below is typed from the collection's definitions.
#![allow(clippy::too_many_lines, clippy::panic, clippy::cast_possible_wrap)] // tests: long scenarios, panics are failures
#![allow(clippy::unwrap_used)] // test helpers outside #[test] fns

mod common;

use common::{mat, rel_err};
use helicon_lti::*;
use nalgebra::DMatrix;

/// Every entry of `x` rounds to the printed value: |x − printed| ≤ ½ unit of the last
/// printed digit (`half_ulp`).
fn assert_printed(x: &DMatrix<f64>, printed: &DMatrix<f64>, half_ulp: f64) {
    for i in 0..x.nrows() {
        for j in 0..x.ncols() {
            let d = (x[(i, j)] - printed[(i, j)]).abs();
            assert!(
                d <= half_ulp,
                "X[{i},{j}] = {} vs printed {}",
                x[(i, j)],
                printed[(i, j)]
            );
        }
    }
}

#[test]
fn matlab_dare_doc_example_1() {
    let a = mat(2, 2, &[-0.9, -0.3, 0.7, 0.1]);
    let b = mat(2, 1, &[1.0, 1.0]);
    let q = mat(2, 2, &[1.0, 0.0, 0.0, 3.0]);
    let r = mat(1, 1, &[0.1]);
    let s = dare(&a, &b, &q, &r, None).unwrap();
    assert_printed(&s.x, &mat(2, 2, &[4.7687, 0.9438, 0.9438, 3.2369]), 0.5e-4);
    assert!(s.residual < 1e-14, "{:e}", s.residual);
}

#[test]
fn matlab_dare_doc_example_2() {
    let a = mat(2, 2, &[4.0, 1.7, 0.9, 38.0]);
    let b = mat(2, 1, &[8.0, 21.0]);
    let c = mat(1, 2, &[10.0, -1.0]);
    let q = c.transpose() * &c;
    let r = mat(1, 1, &[3.0]);
    let s = dare(&a, &b, &q, &r, None).unwrap();
    let printed = mat(2, 2, &[1704.70115, -5616.08147, -5616.08147, 19597.56409]);
    assert_printed(&s.x, &printed, 0.5e-5);
}

fn darex_check(
    name: &str,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
    exact: &DMatrix<f64>,
    tol: f64,
) -> f64 {
    let s = dare(a, b, q, r, n).unwrap_or_else(|e| panic!("{name}: {e}"));
    let e = rel_err(&s.x, exact);
    println!(
        "{name}: rel err {e:e}, residual {:e}, iterations {}, newton {}",
        s.residual, s.iterations, s.newton_steps
    );
    assert!(e < tol, "{name}: rel err {e:e} ≥ {tol:e}");
    e
}

/// DAREX 1: X = (1+√5)/2 [9 6; 6 4]. Well conditioned: 1e-14 (a few ε).
#[test]
fn darex_01() {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    darex_check(
        "darex01",
        &mat(2, 2, &[4.0, 3.0, -4.5, -3.5]),
        &mat(2, 1, &[1.0, -1.0]),
        &mat(2, 2, &[9.0, 6.0, 6.0, 4.0]),
        &mat(1, 1, &[1.0]),
        None,
        &(mat(2, 2, &[9.0, 6.0, 6.0, 4.0]) * g),
        1e-14,
    );
}

/// DAREX 5: singular (nilpotent) A, X = [1 2; 2 2+√5]. Tests that SDA needs no A⁻¹.
#[test]
fn darex_05_singular_a() {
    darex_check(
        "darex05",
        &mat(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        &mat(2, 1, &[0.0, 1.0]),
        &mat(2, 2, &[1.0, 2.0, 2.0, 4.0]),
        &mat(1, 1, &[1.0]),
        None,
        &mat(2, 2, &[1.0, 2.0, 2.0, 2.0 + 5f64.sqrt()]),
        1e-14,
    );
}

/// DAREX 12 with d = 1e6 (badly scaled A = [0 d; 0 0]): X = diag(1, 1 + d²). Relative to
/// ‖X‖ = 1e12 the small entry X₁₁ = 1 is at the 1e-12 level, so we check the max-norm
/// relative error < 1e-13 and X₁₁ separately to 1e-6 absolute.
#[test]
fn darex_12_bad_scaling() {
    let d = 1e6;
    let x = mat(2, 2, &[1.0, 0.0, 0.0, 1.0 + d * d]);
    let a = mat(2, 2, &[0.0, d, 0.0, 0.0]);
    let s = dare(
        &a,
        &mat(2, 1, &[0.0, 1.0]),
        &DMatrix::identity(2, 2),
        &mat(1, 1, &[1.0]),
        None,
    )
    .unwrap();
    let e = rel_err(&s.x, &x);
    println!("darex12: rel err {e:e}, X11 {}", s.x[(0, 0)]);
    assert!(e < 1e-13, "{e:e}");
    assert!((s.x[(0, 0)] - 1.0).abs() < 1e-6, "X11 {}", s.x[(0, 0)]);
}

/// DAREX 13 with d = 1e6: Q = R = d I, A = U diag(0,1,3) U, U = I − (2/3)·11ᵀ,
/// X = d U diag(1, (1+√5)/2, (9+√85)/2) U. Well conditioned after scaling: 1e-13.
#[test]
fn darex_13() {
    let d = 1e6;
    let u = DMatrix::<f64>::identity(3, 3) - DMatrix::from_element(3, 3, 2.0 / 3.0);
    let diag = |v: [f64; 3]| DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&v));
    let a = &u * diag([0.0, 1.0, 3.0]) * &u;
    let x = &u * diag([1.0, (1.0 + 5f64.sqrt()) / 2.0, (9.0 + 85f64.sqrt()) / 2.0]) * &u * d;
    let eye = DMatrix::<f64>::identity(3, 3);
    darex_check(
        "darex13",
        &a,
        &eye,
        &(&eye * d),
        &(&eye * d),
        None,
        &x,
        1e-13,
    );
}

/// DAREX 14 (tau = 1e8: a pole at 1 − 1e-8, nearly on the unit circle; X₁₁ ≈ 1e16 from the
/// closed form). Conditioning ~ 1/(1−|λ|) costs ~8 digits in a backward-stable method, so
/// 1e-7 relative is the honest bound.
#[test]
fn darex_14_near_unit_circle() {
    let (tau, dd_, k, r) = (1e8, 1.0, 1.0, 0.25);
    let alpha = 1.0 - dd_ / tau;
    let beta = k * dd_ / tau;
    let mut a = DMatrix::<f64>::zeros(4, 4);
    a[(0, 0)] = alpha;
    a[(1, 0)] = 1.0;
    a[(2, 1)] = 1.0;
    a[(3, 2)] = 1.0;
    let b = mat(4, 1, &[beta, 0.0, 0.0, 0.0]);
    let mut q = DMatrix::<f64>::zeros(4, 4);
    q[(3, 3)] = 1.0;
    let d = (alpha + 1.0) * (alpha - 1.0);
    let ddd = (r * tau / k / dd_) * tau / k / dd_;
    let mut x = DMatrix::<f64>::identity(4, 4);
    x[(0, 0)] = ddd * d / 2.0 + 0.5 + (0.25 * (ddd * d + 1.0).powi(2) + ddd).sqrt();
    darex_check("darex14", &a, &b, &q, &mat(1, 1, &[r]), None, &x, 1e-7);
}

/// DAREX 15, n = 100: shift matrix A (nilpotent, singular), B = e_n, Q = I, X = diag(1..n).
/// Integer solution: 1e-13.
#[test]
fn darex_15_shift_n100() {
    let n = 100;
    let a = DMatrix::from_fn(n, n, |i, j| if j == i + 1 { 1.0 } else { 0.0 });
    let b = DMatrix::from_fn(n, 1, |i, _| if i == n - 1 { 1.0 } else { 0.0 });
    let x = DMatrix::from_fn(n, n, |i, j| if i == j { (i + 1) as f64 } else { 0.0 });
    darex_check(
        "darex15",
        &a,
        &b,
        &DMatrix::identity(n, n),
        &mat(1, 1, &[1.0]),
        None,
        &x,
        1e-13,
    );
}

/// DAREX 10 has a cross term S (our N): check the residual and that the same X comes out
/// of the explicit substitution (A − B R⁻¹ Nᵀ, Q − N R⁻¹ Nᵀ) solved without N.
#[test]
fn darex_10_cross_term() {
    let mut a = DMatrix::<f64>::zeros(6, 6);
    for blk in 0..2 {
        a[(3 * blk, 3 * blk + 1)] = 1.0;
        a[(3 * blk + 1, 3 * blk + 2)] = 1.0;
    }
    let b = DMatrix::from_fn(6, 2, |i, j| {
        if (i, j) == (2, 0) || (i, j) == (5, 1) {
            1.0
        } else {
            0.0
        }
    });
    let c = mat(
        2,
        6,
        &[1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0, 0.0],
    );
    let dm = mat(2, 2, &[1.0, 0.0, 1.0, 0.0]);
    let q = c.transpose() * &c;
    let r = DMatrix::identity(2, 2) + dm.transpose() * &dm;
    let s = c.transpose() * &dm;
    let sol = dare(&a, &b, &q, &r, Some(&s)).unwrap();
    assert!(sol.residual < 1e-14, "{:e}", sol.residual);
    let rinv = r.clone().try_inverse().unwrap();
    let sol2 = dare(
        &(&a - &b * &rinv * s.transpose()),
        &b,
        &(&q - &s * &rinv * s.transpose()),
        &r,
        None,
    )
    .unwrap();
    assert!(rel_err(&sol.x, &sol2.x) < 1e-13);
}
