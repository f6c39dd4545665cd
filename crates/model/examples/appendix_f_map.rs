//! Appendix F explained: the thesis's inflow iteration (7.56)/(D.41) is a
//! Newton–Raphson map with C_T treated as constant in the derivative. At the
//! root λ* its slope is F'(λ*) = 1 − g'(λ*)/f'(λ*) (g' the full derivative,
//! f' the printed one); |F'| > 1 means the warm-started iteration runs away
//! from the root. Prints the tail rotor's slope in hover against the tail
//! collective: `cargo run --release -p helicon-model --example appendix_f_map`.
#![allow(clippy::unwrap_used, missing_docs)]

use helicon_model::Params;
use helicon_model::tail_rotor::{TailRotorConsts, inflow_problem, thrust_y};
use nalgebra::Vector3;

fn main() {
    let p = Params::bergen_twin();
    let c = TailRotorConsts::new(&p);
    let mu = Vector3::zeros();
    println!("| θtr (rad) | λtr* | tFy (N) | slope F'(λ*) | 7 steps from λ* + 1e-3 |");
    println!("|---|---|---|---|---|");
    for k in 0..=12 {
        let theta = -0.05 + 0.025 * k as f64;
        let prob = inflow_problem(&c, &mu, theta, 0.0, 0.0);
        let sol = prob.solve().unwrap();
        let l = sol.lambda;
        let s2 = prob.mu_inplane2 + l * l;
        let s = s2.sqrt();
        let ct = prob.ct(l);
        let g1 = 1.0 + prob.ct1 / (2.0 * s) - ct * l / (2.0 * s2 * s);
        let f1 = 1.0 - ct * l / (2.0 * s2 * s);
        let slope = 1.0 - g1 / f1;
        let it = prob.thesis_iterate(l + 1e-3, 7);
        println!(
            "| {theta:.3} | {l:.4} | {:.2} | {slope:.2} | {:.4} |",
            thrust_y(&c, &mu, theta, 0.0, 0.0, l),
            it
        );
    }
}
