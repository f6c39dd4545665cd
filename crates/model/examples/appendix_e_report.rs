//! Prints (markdown) the comparison of the thesis-emulation hover linear model
//! with Appendix E and Table 14.1, for docs/trim-linearize.md:
//! `cargo run --release -p helicon-model --example appendix_e_report`.
#![allow(clippy::unwrap_used, missing_docs)]

use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, Preset, REDUCED_STATE_NAMES};
use nalgebra::Vector3;

fn read(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .skip(1)
        .map(|l| l.split(',').skip(1).map(|c| c.parse().unwrap()).collect())
        .collect()
}

fn main() {
    let model = Model::bergen_twin(Preset::Thesis);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let inflow = InflowMode::ThesisIteration {
        lambda_mr_in: t.aux.lambda_mr,
        lambda_tr_in: t.aux.lambda_tr,
        iterations: 7,
    };
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), inflow).unwrap();
    let a = read(include_str!("../../../reference/thesis_A.csv"));
    let mut errs: Vec<(f64, usize, usize)> = vec![];
    for i in 0..27 {
        for j in 0..27 {
            if a[i][j].abs() > 1e-2 {
                errs.push(((lm.a[(i, j)] - a[i][j]).abs() / a[i][j].abs(), i, j));
            }
        }
    }
    errs.sort_by(|x, y| y.0.total_cmp(&x.0));
    let n = errs.len();
    let median = errs[n / 2].0;
    let within = |tol: f64| errs.iter().filter(|e| e.0 <= tol).count();
    println!(
        "Entries with |a| > 1e-2: {n}; median relative error {:.2e}; within 0.3 %: {}; within 1 %: {}; within 1.5 %: {}\n",
        median,
        within(0.003),
        within(0.01),
        within(0.015)
    );
    println!("| entry (row / column) | Appendix E | helicon | rel. error |\n|---|---|---|---|");
    for &(e, i, j) in errs.iter().take(10) {
        println!(
            "| d({})/d({}) | {} | {:.5} | {:.2} % |",
            REDUCED_STATE_NAMES[i],
            REDUCED_STATE_NAMES[j],
            a[i][j],
            lm.a[(i, j)],
            100.0 * e
        );
    }
    println!("\n| Table 14.1 | helicon (thesis emulation) | distance / abs(pole) |\n|---|---|---|");
    let poles = lm.poles().unwrap();
    for line in include_str!("../../../reference/thesis_poles.csv")
        .lines()
        .skip(1)
    {
        let c: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        let best = poles
            .iter()
            .min_by(|p, q| {
                let d = |z: &helicon_lti::analysis::Pole| {
                    (z.value.re - c[0]).powi(2) + (z.value.im - c[1]).powi(2)
                };
                d(p).total_cmp(&d(q))
            })
            .unwrap();
        let dist = ((best.value.re - c[0]).powi(2) + (best.value.im - c[1]).powi(2)).sqrt();
        let mag = (c[0] * c[0] + c[1] * c[1]).sqrt();
        let rel = if mag > 0.0 {
            format!("{:.2} %", 100.0 * dist / mag)
        } else {
            format!("{dist:.1e} (abs)")
        };
        let ours = if best.value.im.abs() > 1e-9 {
            format!("{:.4} ± {:.4}i", best.value.re, best.value.im.abs())
        } else {
            format!("{:.4}", best.value.re)
        };
        let theirs = if c[1] != 0.0 {
            format!("{} ± {}i", c[0], c[1])
        } else {
            format!("{}", c[0])
        };
        println!("| {theirs} | {ours} | {rel} |");
    }
}
