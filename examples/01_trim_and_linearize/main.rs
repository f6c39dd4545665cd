//! Trim the nonlinear model anywhere and linearize it (thesis chapter 12).
#![allow(missing_docs)]

use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, Params, Preset};
use nalgebra::Vector3;

fn main() -> anyhow::Result<()> {
    // The Bergen Twin; `Params::from_file("my_heli.toml")` reads an edited copy
    // of `helicon params`.
    let params = Params::bergen_twin();
    let model = Model::new(params, Preset::Physical.options());

    for (name, v_ned) in [("hover", [0.0, 0.0, 0.0]), ("8 m/s north", [8.0, 0.0, 0.0])] {
        let target = TrimTarget {
            velocity_ned_m_s: Vector3::from(v_ned),
            yaw_rad: 0.0,
            wind_ned_m_s: Vector3::zeros(),
        };
        let t = trim(&model, &target, &TrimOptions::default())?;
        println!(
            "{name}: theta0 = {:.4} rad, pitch = {:.4} rad, roll = {:.4} rad, servos [S_col S_lat S_lon S_tr] = {:.4?}",
            t.x[19],
            t.x[1],
            t.x[0],
            t.u.as_slice()
        );
        let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged)?;
        println!("  slowest poles (rad/s, damping):");
        for p in lm.poles()?.iter().take(6) {
            println!(
                "    {:>9.4} {:+9.4}i   wn = {:.4}  zeta = {:+.3}",
                p.value.re, p.value.im, p.natural_frequency_rad_s, p.damping
            );
        }
        if name == "hover" {
            let ts = model.params().control.sample_time_s;
            let (phi, _gamma) = lm.discretize(ts)?;
            let rho = helicon_lti::analysis::spectral_radius(&phi)?;
            println!("  discretised at {ts} s: spectral radius of Phi = {rho:.6}");
        }
    }
    Ok(())
}
