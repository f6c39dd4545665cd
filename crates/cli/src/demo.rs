//! `helicon demo`: the main job on the embedded Bergen Twin, closed loop.
//!
//! Hover trim → linearization (the unstable hover modes) → LQR with integral
//! action and Kalman predictor design (thesis chapters 14–15) → a 20 s
//! closed-loop flight of the nonlinear model with reference steps (2 m/s
//! north at 1 s, heading π/2 at 6 s, 1 m/s climb at 12 s) in Dryden
//! turbulence on a 2 m/s steady wind, with sensor models, attitude
//! determination, fusion and the state estimator in the loop. The scenario is
//! `scenarios/demo.toml`, embedded in the binary; the run folder is the same
//! as `helicon sim scenarios/demo.toml` writes.

use crate::console::Console;
use crate::model_cmd::ModelFlags;
use crate::sim_cmd::{
    RunReport, fly_and_write_step, overrides_from, overrides_label, prepare_step, print_run,
};
use anyhow::{Context, Result};
use clap::Args;
use helicon_model::InflowMode;
use helicon_model::linearize::linearize;
use helicon_model::state::ix;
use helicon_sim::scenario::Scenario;
use nalgebra::Vector3;
use std::path::PathBuf;

/// The demo scenario (also usable with `helicon sim scenarios/demo.toml`).
pub const DEMO_SCENARIO: &str = include_str!("../../../scenarios/demo.toml");

/// `helicon demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    #[command(flatten)]
    model: ModelFlags,
    /// Output folder.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Flight time (s); the reference steps are at 1, 6 and 12 s.
    #[arg(long)]
    duration: Option<f64>,
    /// Seed of the wind (and sensor) random streams.
    #[arg(long)]
    seed: Option<u64>,
}

/// The demo scenario with the command-line overrides applied.
pub fn demo_scenario(args: &DemoArgs) -> Result<Scenario> {
    let mut s = Scenario::from_toml_str(DEMO_SCENARIO, "scenarios/demo.toml (embedded)")?;
    s.preset = args.model.preset;
    let overrides = overrides_from(args.model.params.as_deref(), args.seed, args.duration)?;
    let origin = format!("helicon demo{}", overrides_label(&overrides));
    Ok(s.with_overrides(&overrides, &origin)?)
}

fn describe_references(s: &Scenario) -> String {
    let mut parts: Vec<String> = s
        .reference
        .iter()
        .map(|r| {
            let what = match r.output.as_str() {
                "vn" => format!("vn = {} m/s", r.value),
                "ve" => format!("ve = {} m/s", r.value),
                "vd" if r.value < 0.0 => format!("vd = {} m/s (climb)", r.value),
                "vd" => format!("vd = {} m/s", r.value),
                _ => format!("psi = {:.4} rad", r.value),
            };
            format!("{what} at {} s", r.t_s)
        })
        .collect();
    if parts.is_empty() {
        parts.push("hold hover".to_string());
    }
    parts.join(", ")
}

fn describe_wind(s: &Scenario) -> String {
    let mut parts = Vec::new();
    if let Some(w) = &s.wind.steady {
        parts.push(format!(
            "steady {:?} m/s NED",
            w.wind_ned_m_s.map(|v| (v * 100.0).round() / 100.0)
        ));
    }
    if let Some(d) = &s.wind.dryden {
        parts.push(format!(
            "Dryden turbulence (W20 = {} m/s, {} m altitude)",
            d.w20_m_s, d.altitude_m
        ));
    }
    if s.wind.thesis.is_some() {
        parts.push("thesis wind (14.38)-(14.42)".to_string());
    }
    if s.wind.gust.is_some() {
        parts.push("1-cosine gust".to_string());
    }
    if parts.is_empty() {
        "calm".to_string()
    } else {
        format!("{} (seed {})", parts.join(" + "), s.wind.seed)
    }
}

/// Run `helicon demo`.
pub fn run(args: &DemoArgs) -> Result<()> {
    let started = std::time::Instant::now();
    let scenario = demo_scenario(args)?;
    // the run folder is written whatever happens to stdout (`| head`)
    let mut con = Console::stdout();
    writeln!(
        con,
        "helicon demo: {}, {} preset, closed loop",
        crate::model_cmd::helicopter_label(args.model.params.as_deref()),
        scenario.preset.name()
    );

    // 1–3. Trim, linearize, design.
    let (prepared, prepare_s) = prepare_step(&scenario)?;
    let t = &prepared.trim;
    writeln!(
        con,
        "1. hover trim: {} Newton iterations, |residual| = {:.1e}; S = [{:.4}, {:.2e}, {:.2e}, {:.4}], roll {:.2} deg, lambda_mr = {:.5}",
        t.iterations,
        t.residual_norm,
        t.u[0],
        t.u[1],
        t.u[2],
        t.u[3],
        t.x[ix::PHI - 3].to_degrees(),
        t.aux.lambda_mr
    );
    let lm = linearize(
        &prepared.model,
        &t.x,
        &t.u,
        &Vector3::zeros(),
        InflowMode::Converged,
    )?;
    let poles = lm.poles()?;
    let unstable: Vec<String> = poles
        .iter()
        .filter(|p| p.value.re > 1e-8 && p.value.im >= 0.0)
        .map(|p| {
            if p.value.im > 1e-9 {
                format!("{:.4} ± {:.4}i", p.value.re, p.value.im)
            } else {
                format!("{:.4}", p.value.re)
            }
        })
        .collect();
    writeln!(
        con,
        "2. linearized (27 states, 4 inputs): unstable open-loop poles s = {} (1/s)",
        if unstable.is_empty() {
            "none".to_string()
        } else {
            unstable.join(", ")
        }
    );
    let g = &prepared.gains;
    let est_radius = g
        .estimator_poles
        .iter()
        .map(|z| z[0].hypot(z[1]))
        .fold(0.0, f64::max);
    let cl_radius = g.spectral_radius();
    writeln!(
        con,
        "3. designed at {:.0} Hz: LQR + integral action (Bryson, rho = {}, pincer alpha = {:.5}), closed-loop |z|max = {:.5}; Kalman predictor |z|max = {:.5} ({:.2} s)",
        1.0 / g.set.sample_time_s,
        g.config.rho,
        g.set.alpha,
        cl_radius,
        est_radius,
        prepare_s
    );

    // 4. Fly.
    writeln!(
        con,
        "4. closed-loop flight, {} s: {}; wind: {}; estimator {}, {}",
        helicon_sim::scenario::num(scenario.duration_s),
        describe_references(&scenario),
        describe_wind(&scenario),
        if scenario.controller.estimator {
            "in the loop"
        } else {
            "off (truth feedback)"
        },
        if scenario.controller.fusion {
            format!(
                "sensor models + attitude determination + fusion (sensor seed {})",
                scenario.sensors.seed
            )
        } else {
            "ideal measurements of the nine measured states".to_string()
        }
    );
    let (flight, files, fly_s, write_s) =
        fly_and_write_step(&args.out, &scenario, &prepared, "helicon demo")?;
    let report = RunReport {
        flight,
        files,
        prepare_s,
        fly_s,
        write_s,
    };
    print_run(&mut con, &report);
    if scenario.wind.dryden.is_some() || scenario.wind.thesis.is_some() {
        writeln!(
            con,
            "  (in turbulence the error rarely stays inside the 1 % band to the end: the RMS errors are the figures of merit)"
        );
    }
    let pngs: Vec<String> = report
        .files
        .plots
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    writeln!(
        con,
        "plots (PNG, and SVG alongside) in {}: {}",
        report.files.dir.display(),
        pngs.join(", ")
    );
    writeln!(con, "report: {}", report.files.report.display());
    writeln!(
        con,
        "demo done in {:.2} s. Fly your own: helicon sim scenarios/demo.toml --out out/mine",
        started.elapsed().as_secs_f64()
    );
    con.finish().context("writing to stdout")
}
