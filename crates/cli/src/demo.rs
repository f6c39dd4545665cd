//! `helicon demo`: the main job on the embedded Bergen Twin.
//!
//! Until the closed loop lands, the demo does the open-loop part of the
//! pipeline for real: hover trim → linearization → poles, then flies the
//! nonlinear model open loop from the exact trim (it must stay put) and from
//! the thesis's printed 3-digit trim (it drifts away through the unstable
//! hover mode), logging both and plotting them.

use crate::model_cmd::ModelFlags;
use anyhow::{Context, Result};
use clap::Args;
use helicon_model::integrate::DEFAULT_STEP_S;
use helicon_model::linearize::linearize;
use helicon_model::state::{STATE_NAMES, expand, ix};
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Input, Model, State};
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// `helicon demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    #[command(flatten)]
    model: ModelFlags,
    /// Output folder.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Open-loop flight time (s).
    #[arg(long, default_value_t = 20.0)]
    duration: f64,
}

struct Run {
    t: Vec<f64>,
    x: Vec<State>,
}

fn fly(model: &Model, x0: &State, u: &Input, duration_s: f64) -> Result<Run> {
    let n = (duration_s / DEFAULT_STEP_S).round() as usize;
    let mut run = Run {
        t: Vec::with_capacity(n + 1),
        x: Vec::with_capacity(n + 1),
    };
    let mut x = *x0;
    run.t.push(0.0);
    run.x.push(x);
    for k in 0..n {
        match model.step(&x, u, &Vector3::zeros(), DEFAULT_STEP_S) {
            Ok((next, _)) => x = next,
            Err(e) => {
                eprintln!(
                    "open-loop flight stopped at t = {:.3} s: {e}",
                    k as f64 * DEFAULT_STEP_S
                );
                break;
            }
        }
        if x[ix::THETA].abs() > 1.2 || x[ix::PHI].abs() > 1.2 {
            eprintln!(
                "open-loop flight stopped at t = {:.3} s: attitude beyond 1.2 rad",
                (k + 1) as f64 * DEFAULT_STEP_S
            );
            run.t.push((k + 1) as f64 * DEFAULT_STEP_S);
            run.x.push(x);
            break;
        }
        run.t.push((k + 1) as f64 * DEFAULT_STEP_S);
        run.x.push(x);
    }
    Ok(run)
}

fn write_log(path: &Path, run: &Run) -> Result<()> {
    let mut s = format!("t_s,{}\n", STATE_NAMES.join(","));
    for (t, x) in run.t.iter().zip(&run.x) {
        let _ = write!(s, "{t}");
        for v in x.iter() {
            let _ = write!(s, ",{v:e}");
        }
        s.push('\n');
    }
    std::fs::write(path, s).with_context(|| format!("cannot write {}", path.display()))
}

/// Run `helicon demo`.
pub fn run(args: &DemoArgs) -> Result<()> {
    let started = std::time::Instant::now();
    let model = args.model.model()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    println!(
        "helicon demo: Bergen Industrial Twin, {} preset",
        args.model.preset.name()
    );

    // 1. Trim.
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default())?;
    println!(
        "1. hover trim: {} Newton iterations from a cold start, |residual| = {:.1e}; S = [{:.4}, {:.2e}, {:.2e}, {:.4}], roll {:.2} deg, lambda_mr = {:.5}",
        t.iterations,
        t.residual_norm,
        t.u[0],
        t.u[1],
        t.u[2],
        t.u[3],
        t.x[ix::PHI - 3].to_degrees(),
        t.aux.lambda_mr
    );

    // 2. Linearize and find the unstable mode.
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged)?;
    let poles = lm.poles()?;
    let unstable: Vec<_> = poles.iter().filter(|p| p.value.re > 1e-8).collect();
    println!(
        "2. linearized (27 states, 4 inputs): {} poles, {} unstable:",
        poles.len(),
        unstable.len()
    );
    for p in unstable.iter().filter(|p| p.value.im >= 0.0) {
        let doubling = std::f64::consts::LN_2 / p.value.re;
        if p.value.im > 1e-9 {
            println!(
                "   s = {:.4} ± {:.4}i  (oscillatory, period {:.1} s, amplitude doubles every {doubling:.1} s)",
                p.value.re,
                p.value.im,
                2.0 * std::f64::consts::PI / p.value.im
            );
        } else {
            println!(
                "   s = {:.4}  (aperiodic divergence, doubles every {doubling:.1} s)",
                p.value.re
            );
        }
    }

    // 3. Fly open loop from the exact trim and from the printed thesis trim.
    let x_exact = expand(&t.x, [0.0; 3]);
    let exact = fly(&model, &x_exact, &t.u, args.duration)?;
    let drift_exact = exact
        .x
        .iter()
        .map(|x| (x - x_exact).amax())
        .fold(0.0, f64::max);
    let mut x_printed = x_exact;
    for (i, v) in [
        (ix::PHI, 0.0573),
        (ix::THETA, -0.000658),
        (ix::A0, 0.016),
        (ix::A1, 0.000641),
        (ix::B1, 2.16e-6),
        (ix::A1SB, 0.000574),
        (ix::B1SB, -0.000206),
        (ix::THETA0, 0.129),
        (ix::A1_SWASH, 0.000206),
        (ix::B1_SWASH, -0.000574),
        (ix::THETA_TR, 0.111),
    ] {
        x_printed[i] = v;
    }
    let u_printed = Input::new(0.185, 0.000294, -0.00082, 0.159);
    let printed = fly(&model, &x_printed, &u_printed, args.duration)?;
    let last = printed.x.last().copied().unwrap_or(x_printed);
    let t_end = printed.t.last().copied().unwrap_or(0.0);
    println!(
        "3. open loop for {:.0} s from the exact trim: largest state change {:.1e} (it stays put)",
        exact.t.last().copied().unwrap_or(0.0),
        drift_exact
    );
    println!(
        "   from the thesis's printed 3-digit trim (12.10)/(12.11): after {t_end:.1} s position NED = [{:.2}, {:.2}, {:.2}] m, \
         velocity = [{:.2}, {:.2}, {:.2}] m/s, roll/pitch = [{:.1}, {:.1}] deg",
        last[ix::X],
        last[ix::Y],
        last[ix::Z],
        last[ix::U],
        last[ix::V],
        last[ix::W],
        last[ix::PHI].to_degrees(),
        last[ix::THETA].to_degrees()
    );
    write_log(&args.out.join("open_loop_exact_trim.csv"), &exact)?;
    write_log(&args.out.join("open_loop_printed_trim.csv"), &printed)?;

    use helicon_sim::plot::{LinePlot, Series};
    let series = |i: usize, scale: f64| -> Vec<(f64, f64)> {
        printed
            .t
            .iter()
            .zip(&printed.x)
            .map(|(t, x)| (*t, x[i] * scale))
            .collect()
    };
    let (u, v, w) = (series(ix::U, 1.0), series(ix::V, 1.0), series(ix::W, 1.0));
    let p = LinePlot::new(
        "Open loop from the printed thesis trim: body velocity",
        "time [s]",
        "velocity [m/s]",
    )
    .series(Series::new("u", &u))
    .series(Series::new("v", &v))
    .series(Series::new("w", &w));
    let (phi, theta) = (
        series(ix::PHI, 180.0 / std::f64::consts::PI),
        series(ix::THETA, 180.0 / std::f64::consts::PI),
    );
    let q = LinePlot::new(
        "Open loop from the printed thesis trim: attitude",
        "time [s]",
        "angle [deg]",
    )
    .series(Series::new("phi", &phi))
    .series(Series::new("theta", &theta));
    for ext in ["png", "svg"] {
        p.write(&args.out.join(format!("open_loop_velocity.{ext}")))?;
        q.write(&args.out.join(format!("open_loop_attitude.{ext}")))?;
    }
    println!(
        "4. wrote logs (CSV) and plots (PNG/SVG) to {} in {:.2} s",
        args.out.display(),
        started.elapsed().as_secs_f64()
    );
    println!(
        "   (the closed loop, estimator and sensors join the demo with the closed-loop issue)"
    );
    Ok(())
}
