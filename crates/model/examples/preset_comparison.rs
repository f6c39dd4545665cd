//! Prints (markdown) how the hover poles move from the `thesis` preset to the
//! `physical` preset, one modelling option at a time. Used for
//! docs/trim-linearize.md: `cargo run --release -p helicon-model --example preset_comparison`.
#![allow(clippy::unwrap_used, missing_docs)]

use helicon_model::linearize::linearize;
use helicon_model::options::{FrontPlaneQ, SbVelocityScale, WindSign};
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, ModelOptions, Params, Preset};
use nalgebra::Vector3;

fn slow_poles(opts: ModelOptions, emulate: bool) -> (Vec<String>, f64, f64) {
    let model = Model::new(Params::bergen_twin(), opts);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let inflow = if emulate {
        InflowMode::ThesisIteration {
            lambda_mr_in: t.aux.lambda_mr,
            lambda_tr_in: t.aux.lambda_tr,
            iterations: 7,
        }
    } else {
        InflowMode::Converged
    };
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), inflow).unwrap();
    let poles = lm.poles().unwrap();
    let s = poles
        .iter()
        .filter(|p| {
            p.value.im >= 0.0
                && p.natural_frequency_rad_s < 25.0
                && p.natural_frequency_rad_s > 1e-6
        })
        .map(|p| {
            if p.value.im > 1e-9 {
                format!("{:.4}±{:.3}i", p.value.re, p.value.im)
            } else {
                format!("{:.4}", p.value.re)
            }
        })
        .collect();
    (s, t.u[0], t.x[0])
}

fn main() {
    let thesis = Preset::Thesis.options();
    let mut rows: Vec<(&str, ModelOptions, bool)> = vec![
        (
            "thesis preset, thesis inflow emulation (Appendix E)",
            thesis,
            true,
        ),
        ("thesis preset, converged inflow", thesis, false),
    ];
    let mut o = thesis;
    o.flap_accel = true;
    rows.push((
        "+ body-acceleration flap torques (6.36), hz̈ of (6.40)",
        o,
        false,
    ));
    o.sb_velocity = SbVelocityScale::Physical;
    rows.push(("+ physical stabilizer-bar velocities (R, not Ro)", o, false));
    o.front_plane_q = FrontPlaneQ::Printed;
    rows.push(("+ front plane −q·κh,fp (7.62) = physical preset", o, false));
    o.wind = WindSign::Physical;
    assert_eq!(o, Preset::Physical.options());
    println!("| model | S_col | φ (rad) | hover poles with |s| < 25 rad/s |");
    println!("|---|---|---|---|");
    for (name, opts, emu) in rows {
        let (p, scol, phi) = slow_poles(opts, emu);
        println!("| {name} | {scol:.5} | {phi:.5} | {} |", p.join(", "));
    }
}
