//! `helicon trim` and `helicon linearize` (thesis chapter 12).

use crate::model_cmd::ModelFlags;
use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use helicon_model::linearize::{LinearModel, linearize};
use helicon_model::state::{INPUT_NAMES, REDUCED_STATE_NAMES};
use helicon_model::trim::{Trim, TrimOptions, TrimTarget, sweep, trim};
use helicon_model::{InflowMode, Model};
use nalgebra::{DMatrix, Vector3};
use serde_json::{Map, Value, json};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Flight-condition flags shared by trim and linearize.
#[derive(Args, Debug, Clone)]
pub struct ConditionFlags {
    #[command(flatten)]
    pub model: ModelFlags,
    /// Inertial velocity in NED, m/s: `N,E,D` (e.g. `5,0,0` for 5 m/s forward at yaw 0).
    #[arg(long, value_parser = parse_vec3, default_value = "0,0,0", allow_hyphen_values = true)]
    pub velocity_ned: Vector3<f64>,
    /// Heading ψ in rad.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub yaw: f64,
    /// Air-mass velocity in NED, m/s: `N,E,D`.
    #[arg(long, value_parser = parse_vec3, default_value = "0,0,0", allow_hyphen_values = true)]
    pub wind_ned: Vector3<f64>,
    /// Print the residual norm of every Newton iteration (stderr).
    #[arg(long)]
    pub verbose: bool,
}

fn parse_vec3(s: &str) -> Result<Vector3<f64>, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers N,E,D, got `{s}`"
        ));
    }
    let mut v = Vector3::zeros();
    for (i, p) in parts.iter().enumerate() {
        v[i] = p.trim().parse::<f64>().map_err(|e| format!("`{p}`: {e}"))?;
        if !v[i].is_finite() {
            return Err(format!("`{p}` is not finite"));
        }
    }
    Ok(v)
}

impl ConditionFlags {
    fn target(&self) -> TrimTarget {
        TrimTarget {
            velocity_ned_m_s: self.velocity_ned,
            yaw_rad: self.yaw,
            wind_ned_m_s: self.wind_ned,
        }
    }
}

/// Which variable a sweep varies.
#[derive(ValueEnum, Debug, Clone, Copy)]
pub enum SweepAxis {
    /// Forward speed (m/s) along the heading.
    Forward,
    /// Sideward speed (m/s), positive to the right of the heading.
    Sideward,
    /// Climb rate (m/s), positive up.
    Climb,
    /// Heading (rad).
    Yaw,
}

/// `helicon trim`.
#[derive(Args, Debug)]
pub struct TrimArgs {
    #[command(flatten)]
    cond: ConditionFlags,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Sweep a variable instead of a single trim (the other components come from
    /// --velocity-ned / --yaw); writes a CSV and plots to --out.
    #[arg(long, value_enum)]
    sweep: Option<SweepAxis>,
    /// Sweep start.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    from: f64,
    /// Sweep end.
    #[arg(long, default_value_t = 15.0, allow_hyphen_values = true)]
    to: f64,
    /// Sweep step (> 0).
    #[arg(long, default_value_t = 0.5)]
    step: f64,
    /// Output folder for a sweep.
    #[arg(long, default_value = "out/trim-sweep")]
    out: PathBuf,
}

/// `helicon linearize`.
#[derive(Args, Debug)]
pub struct LinearizeArgs {
    #[command(flatten)]
    cond: ConditionFlags,
    /// Emulate the thesis implementation's inflow (flapping on the trim λ, 7 plain
    /// Newton–Raphson steps for the forces), reproducing Appendix E.
    #[arg(long)]
    thesis_inflow: bool,
    /// Also write the ZOH discretization Phi.csv, Gamma.csv at this sample time (s).
    #[arg(long)]
    discrete: Option<f64>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

fn do_trim(model: &Model, cond: &ConditionFlags, initial: Option<&Trim>) -> Result<Trim> {
    let mut opts = TrimOptions::default();
    if let Some(t) = initial {
        opts.initial = Some((t.x, t.u));
    }
    let t = trim(model, &cond.target(), &opts)?;
    if cond.verbose {
        for (k, r) in t.history.iter().enumerate() {
            eprintln!("trim iteration {k:>2}: |residual|_inf = {r:.3e}");
        }
    }
    for v in &t.beyond_saturation {
        eprintln!(
            "warning: this condition needs {} = {:.4} beyond its saturation [{}, {}]",
            v.input, v.value, v.min, v.max
        );
    }
    Ok(t)
}

/// The trim as JSON: `{"state": {27 names}, "input": {4 names}, "lambda_mr", "lambda_tr", "residual_norm", ...}`.
pub fn trim_json(t: &Trim) -> Value {
    let mut state = Map::new();
    for (i, n) in REDUCED_STATE_NAMES.iter().enumerate() {
        state.insert((*n).to_string(), json!(t.x[i]));
    }
    let mut input = Map::new();
    for (i, n) in INPUT_NAMES.iter().enumerate() {
        input.insert((*n).to_string(), json!(t.u[i]));
    }
    json!({
        "state": state,
        "input": input,
        "lambda_mr": t.aux.lambda_mr,
        "lambda_tr": t.aux.lambda_tr,
        "residual_norm": t.residual_norm,
        "iterations": t.iterations,
        "velocity_ned_m_s": [t.target.velocity_ned_m_s.x, t.target.velocity_ned_m_s.y, t.target.velocity_ned_m_s.z],
        "yaw_rad": t.target.yaw_rad,
        "wind_ned_m_s": [t.target.wind_ned_m_s.x, t.target.wind_ned_m_s.y, t.target.wind_ned_m_s.z],
        "beyond_saturation": t.beyond_saturation.iter().map(|v| v.input).collect::<Vec<_>>(),
    })
}

/// Run `helicon trim`.
pub fn run_trim(args: &TrimArgs) -> Result<()> {
    let model = args.cond.model.model()?;
    if let Some(axis) = args.sweep {
        return run_sweep(&model, args, axis);
    }
    let t = do_trim(&model, &args.cond, None)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&trim_json(&t))?);
        return Ok(());
    }
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "trim ({} preset): v_ned = [{}, {}, {}] m/s, yaw = {} rad; {} Newton iterations, |residual|_inf = {:.2e}",
        args.cond.model.preset.name(),
        t.target.velocity_ned_m_s.x,
        t.target.velocity_ned_m_s.y,
        t.target.velocity_ned_m_s.z,
        t.target.yaw_rad,
        t.iterations,
        t.residual_norm
    )?;
    writeln!(out, "{:<14} {:>14}", "input", "value")?;
    for (i, n) in INPUT_NAMES.iter().enumerate() {
        writeln!(out, "{n:<14} {:>14.6e}", t.u[i])?;
    }
    writeln!(out, "{:<14} {:>14}", "state", "value")?;
    for (i, n) in REDUCED_STATE_NAMES.iter().enumerate() {
        writeln!(out, "{n:<14} {:>14.6e}", t.x[i])?;
    }
    writeln!(
        out,
        "{:<14} {:>14.6e}\n{:<14} {:>14.6e}",
        "lambda_mr", t.aux.lambda_mr, "lambda_tr", t.aux.lambda_tr
    )?;
    Ok(())
}

fn run_sweep(model: &Model, args: &TrimArgs, axis: SweepAxis) -> Result<()> {
    if !(args.step > 0.0 && args.step.is_finite() && args.from.is_finite() && args.to.is_finite()) {
        bail!("--step must be > 0 and --from/--to finite");
    }
    let count = ((args.to - args.from).abs() / args.step).round();
    if count > 100_000.0 {
        bail!("--from/--to/--step give {count} sweep points; at most 100000");
    }
    let n = count as usize;
    let dir = if args.to >= args.from { 1.0 } else { -1.0 };
    let values: Vec<f64> = (0..=n)
        .map(|k| args.from + dir * args.step * k as f64)
        .collect();
    let base = args.cond.target();
    let targets: Vec<TrimTarget> = values
        .iter()
        .map(|&s| {
            let mut t = base;
            let (c, sn) = (t.yaw_rad.cos(), t.yaw_rad.sin());
            match axis {
                SweepAxis::Forward => {
                    t.velocity_ned_m_s.x = s * c;
                    t.velocity_ned_m_s.y = s * sn;
                }
                SweepAxis::Sideward => {
                    t.velocity_ned_m_s.x = -s * sn;
                    t.velocity_ned_m_s.y = s * c;
                }
                SweepAxis::Climb => t.velocity_ned_m_s.z = -s,
                SweepAxis::Yaw => t.yaw_rad = s,
            }
            t
        })
        .collect();
    let results = sweep(model, &targets, &TrimOptions::default());
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let var = format!("{axis:?}").to_lowercase();
    let mut csv = format!(
        "{var},converged,residual_norm,{},{},lambda_mr,lambda_tr\n",
        INPUT_NAMES.join(","),
        REDUCED_STATE_NAMES.join(",")
    );
    let mut failed = 0;
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 8];
    for (s, r) in values.iter().zip(&results) {
        match r {
            Ok(t) => {
                let _ = write!(csv, "{s},true,{:e}", t.residual_norm);
                for v in t.u.iter().chain(t.x.iter()) {
                    let _ = write!(csv, ",{v:e}");
                }
                let _ = writeln!(csv, ",{:e},{:e}", t.aux.lambda_mr, t.aux.lambda_tr);
                for k in 0..4 {
                    series[k].push((*s, t.u[k]));
                }
                series[4].push((*s, t.x[0].to_degrees()));
                series[5].push((*s, t.x[1].to_degrees()));
                series[6].push((*s, t.aux.lambda_mr));
                series[7].push((*s, t.aux.lambda_tr));
            }
            Err(e) => {
                failed += 1;
                eprintln!("{var} = {s}: {e}");
                let _ = writeln!(csv, "{s},false,{}", ",".repeat(4 + 27 + 2));
            }
        }
    }
    let csv_path = args.out.join("sweep.csv");
    std::fs::write(&csv_path, csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    let unit = if matches!(axis, SweepAxis::Yaw) {
        "rad"
    } else {
        "m/s"
    };
    let xl = format!("{var} [{unit}]");
    use helicon_sim::plot::{LinePlot, Series};
    let mut p = LinePlot::new("Trim inputs", &xl, "servo command [-]");
    for k in 0..4 {
        p = p.series(Series::new(INPUT_NAMES[k], &series[k]));
    }
    for ext in ["png", "svg"] {
        p.write(&args.out.join(format!("inputs.{ext}")))?;
    }
    let p = LinePlot::new("Trim attitude", &xl, "angle [deg]")
        .series(Series::new("phi", &series[4]))
        .series(Series::new("theta", &series[5]));
    for ext in ["png", "svg"] {
        p.write(&args.out.join(format!("attitude.{ext}")))?;
    }
    let p = LinePlot::new("Trim inflow ratios", &xl, "lambda [-]")
        .series(Series::new("lambda_mr", &series[6]))
        .series(Series::new("lambda_tr", &series[7]));
    for ext in ["png", "svg"] {
        p.write(&args.out.join(format!("inflow.{ext}")))?;
    }
    println!(
        "swept {var} over {} points: {} converged, {failed} failed; wrote {}/sweep.csv and inputs/attitude/inflow plots",
        values.len(),
        values.len() - failed,
        args.out.display()
    );
    if failed > 0 {
        bail!("{failed} sweep point(s) did not trim");
    }
    Ok(())
}

/// Write a matrix as CSV with a header row of column names and a first column of row names.
pub fn write_named_csv(path: &Path, m: &DMatrix<f64>, rows: &[&str], cols: &[&str]) -> Result<()> {
    let mut s = format!("row,{}\n", cols.join(","));
    for (i, r) in rows.iter().enumerate() {
        s.push_str(r);
        for j in 0..m.ncols() {
            let _ = write!(s, ",{:e}", m[(i, j)]);
        }
        s.push('\n');
    }
    std::fs::write(path, s).with_context(|| format!("cannot write {}", path.display()))
}

/// Run `helicon linearize`.
pub fn run_linearize(args: &LinearizeArgs) -> Result<()> {
    let model = args.cond.model.model()?;
    let t = do_trim(&model, &args.cond, None)?;
    let inflow = if args.thesis_inflow {
        InflowMode::ThesisIteration {
            lambda_mr_in: t.aux.lambda_mr,
            lambda_tr_in: t.aux.lambda_tr,
            iterations: 7,
        }
    } else {
        InflowMode::Converged
    };
    let lm: LinearModel = linearize(&model, &t.x, &t.u, &args.cond.wind_ned, inflow)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    write_named_csv(
        &args.out.join("A.csv"),
        &lm.a_dyn(),
        &REDUCED_STATE_NAMES,
        &REDUCED_STATE_NAMES,
    )?;
    write_named_csv(
        &args.out.join("B.csv"),
        &lm.b_dyn(),
        &REDUCED_STATE_NAMES,
        &INPUT_NAMES,
    )?;
    let poles = lm.poles()?;
    let mut pc = String::from("real,imag,natural_frequency_rad_s,damping\n");
    for p in &poles {
        let _ = writeln!(
            pc,
            "{:e},{:e},{:e},{:e}",
            p.value.re, p.value.im, p.natural_frequency_rad_s, p.damping
        );
    }
    std::fs::write(args.out.join("poles.csv"), pc)?;
    let (a, b) = (lm.a_dyn(), lm.b_dyn());
    let tol = helicon_lti::analysis::STAIRCASE_TOL;
    let reach = helicon_lti::analysis::reachable_dimension(&a, &b, tol)?;
    let mut c = DMatrix::zeros(9, 27);
    for i in 0..9 {
        c[(i, i)] = 1.0;
    }
    let obs = helicon_lti::analysis::observable_dimension(&a, &c, tol)?;
    let mut summary = json!({
        "preset": args.cond.model.preset.name(),
        "inflow": if args.thesis_inflow { "thesis-iteration-7" } else { "converged" },
        "trim": trim_json(&t),
        "affine_residual_norm": lm.xdot0.amax(),
        "controllability_rank": reach.dimension,
        "observability_rank": obs.dimension,
        "observability_outputs": "C = [I9 0]: phi theta psi u v w p q r (15.2)",
        // a numerical zero (the heading integrator) is not unstable
        "unstable_poles": poles.iter().filter(|p| p.value.re > 1e-8).count(),
    });
    if let Some(ts) = args.discrete {
        let (phi, gamma) = lm.discretize(ts)?;
        write_named_csv(
            &args.out.join("Phi.csv"),
            &phi,
            &REDUCED_STATE_NAMES,
            &REDUCED_STATE_NAMES,
        )?;
        write_named_csv(
            &args.out.join("Gamma.csv"),
            &gamma,
            &REDUCED_STATE_NAMES,
            &INPUT_NAMES,
        )?;
        let dreach = helicon_lti::analysis::reachable_dimension(&phi, &gamma, tol)?;
        summary["discrete"] =
            json!({"sample_time_s": ts, "controllability_rank": dreach.dimension});
    }
    std::fs::write(
        args.out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    println!(
        "linearized at the trim ({} preset, {} inflow): wrote A.csv, B.csv, poles.csv{} and summary.json to {}",
        args.cond.model.preset.name(),
        if args.thesis_inflow {
            "thesis-emulated"
        } else {
            "converged"
        },
        if args.discrete.is_some() {
            ", Phi.csv, Gamma.csv"
        } else {
            ""
        },
        args.out.display()
    );
    println!(
        "{} unstable pole(s); controllable subspace {} of 27; affine residual {:.1e}",
        summary["unstable_poles"],
        reach.dimension,
        lm.xdot0.amax()
    );
    Ok(())
}
