//! `helicon trim` and `helicon linearize` (thesis chapter 12).

use crate::model_cmd::ModelFlags;
use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use helicon_model::linearize::{EQUILIBRIUM_TOL, LinearModel, linearize};
use helicon_model::state::{INPUT_NAMES, REDUCED_STATE_NAMES};
use helicon_model::trim::{
    Allowed, Trim, TrimOptions, TrimTarget, Validity, Violation, discontinuities, sweep, trim,
};
use helicon_model::{InflowMode, Model};
use helicon_sim::scenario::{MAX_HEADING_RAD, MAX_SPEED_M_S};
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
    #[arg(long, value_parser = parse_heading, default_value_t = 0.0, allow_hyphen_values = true)]
    pub yaw: f64,
    /// Air-mass velocity in NED, m/s: `N,E,D`.
    #[arg(long, value_parser = parse_vec3, default_value = "0,0,0", allow_hyphen_values = true)]
    pub wind_ned: Vector3<f64>,
    /// Print the residual norm of every Newton iteration (stderr).
    #[arg(long)]
    pub verbose: bool,
    /// Accept a trim outside the physical ranges (servo ranges, blade stall,
    /// small flapping, advance ratio, vortex-ring region) or, for
    /// `linearize`, an operating point that is not an equilibrium: report it
    /// and exit 0 instead of failing.
    #[arg(long)]
    pub allow_unphysical: bool,
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
        if v[i].abs() > MAX_SPEED_M_S {
            return Err(format!(
                "`{p}` m/s is beyond +-100 m/s (a miniature helicopter flies far inside)"
            ));
        }
    }
    Ok(v)
}

/// A heading (rad): finite, within +-100 rad (as a scenario's).
fn parse_heading(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("`{s}`: {e}"))?;
    if !(v.is_finite() && v.abs() <= MAX_HEADING_RAD) {
        return Err(format!("`{s}` must be finite and within +-100 rad"));
    }
    Ok(v)
}

/// A sample time (s): finite and > 0.
fn parse_sample_time(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("`{s}`: {e}"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("`{s}` must be finite and > 0 s"));
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
    #[arg(long, value_parser = parse_sample_time, allow_hyphen_values = true)]
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
            crate::console::note!("trim iteration {k:>2}: |residual|_inf = {r:.3e}");
        }
    }
    Ok(t)
}

/// Print the violations of a trim on stderr (`what` names the point).
fn report_violations(what: &str, v: &Validity) {
    for x in &v.violations {
        crate::console::note!("{what}: unphysical: {x}");
    }
}

/// A violation as JSON.
fn violation_json(v: &Violation) -> Value {
    let (kind, min, max) = match v.allowed {
        Allowed::Within { min, max } => ("within", min, max),
        Allowed::Outside { min, max } => ("outside", min, max),
    };
    json!({
        "quantity": v.quantity,
        "value": v.value,
        "allowed": {"kind": kind, "min": min, "max": max},
        "reason": v.reason,
    })
}

/// The validity report as JSON: `{"physical": bool, "violations": [...]}`.
pub fn validity_json(v: &Validity) -> Value {
    json!({
        "physical": v.is_physical(),
        "violations": v.violations.iter().map(violation_json).collect::<Vec<_>>(),
    })
}

/// The trim as JSON: `{"state": {27 names}, "input": {4 names}, "lambda_mr",
/// "lambda_tr", "residual_norm", ..., "validity": {"physical", "violations"}}`.
pub fn trim_json(t: &Trim, model: &Model) -> Value {
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
        "validity": validity_json(&t.validity(model)),
    })
}

/// Run `helicon trim`.
pub fn run_trim(args: &TrimArgs) -> Result<()> {
    let model = args.cond.model.model()?;
    if let Some(axis) = args.sweep {
        return run_sweep(&model, args, axis);
    }
    let t = do_trim(&model, &args.cond, None)?;
    let validity = t.validity(&model);
    // a failed write to stdout (a closed pipe) is returned after the
    // validity verdict, so `helicon trim … | head -1` still fails on an
    // unphysical trim
    let printed = if args.json {
        let text = serde_json::to_string_pretty(&trim_json(&t, &model))?;
        writeln!(std::io::stdout().lock(), "{text}").map_err(anyhow::Error::from)
    } else {
        print_trim(&t, args)
    };
    report_violations("trim", &validity);
    if !validity.is_physical() && !args.cond.allow_unphysical {
        bail!(
            "the trim is not physical ({} violation(s) above); --allow-unphysical accepts it",
            validity.violations.len()
        );
    }
    printed
}

fn print_trim(t: &Trim, args: &TrimArgs) -> Result<()> {
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

#[allow(clippy::too_many_lines)] // the sweep: solve, classify, write CSV/JSON, plot, in order
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
    let unit = if matches!(axis, SweepAxis::Yaw) {
        "rad"
    } else {
        "m/s"
    };
    let validity: Vec<Option<Validity>> = results
        .iter()
        .map(|r| r.as_ref().ok().map(|t| t.validity(model)))
        .collect();
    let jumps = discontinuities(&results);
    // the quantities that jumped into each point from the previous one
    let mut jumped: Vec<Vec<&str>> = vec![Vec::new(); values.len()];
    for d in &jumps {
        jumped[d.index] = d.quantities.iter().map(|q| q.0).collect();
    }
    let mut csv = format!(
        "{var},converged,residual_norm,{},{},lambda_mr,lambda_tr,physical,violations,jump_from_previous\n",
        INPUT_NAMES.join(","),
        REDUCED_STATE_NAMES.join(",")
    );
    let mut failed = 0;
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 8];
    let mut points = Vec::with_capacity(values.len());
    for (k, (s, r)) in values.iter().zip(&results).enumerate() {
        match r {
            Ok(t) => {
                let v = validity[k].clone().unwrap_or_default();
                let _ = write!(csv, "{s},true,{:e}", t.residual_norm);
                for v in t.u.iter().chain(t.x.iter()) {
                    let _ = write!(csv, ",{v:e}");
                }
                let _ = writeln!(
                    csv,
                    ",{:e},{:e},{},{},{}",
                    t.aux.lambda_mr,
                    t.aux.lambda_tr,
                    v.is_physical(),
                    v.violations
                        .iter()
                        .map(csv_violation)
                        .collect::<Vec<_>>()
                        .join(";"),
                    jumped[k].join(";")
                );
                let mut p = trim_json(t, model);
                p[var.as_str()] = json!(s);
                p["converged"] = json!(true);
                p["jump_from_previous"] = json!(jumped[k]);
                points.push(p);
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
                crate::console::note!("{var} = {s}: {e}");
                let _ = writeln!(csv, "{s},false,{}", ",".repeat(4 + 27 + 2 + 3));
                points.push(json!({var.as_str(): s, "converged": false, "error": e.to_string()}));
            }
        }
    }
    let csv_path = args.out.join("sweep.csv");
    std::fs::write(&csv_path, csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    let json_path = args.out.join("sweep.json");
    std::fs::write(
        &json_path,
        serde_json::to_string_pretty(&json!({
            "variable": var,
            "unit": unit,
            "preset": args.cond.model.preset.name(),
            "points": points,
            "jumps": jumps.iter().map(|d| json!({
                "from": values[d.index - 1],
                "to": values[d.index],
                "quantities": d.quantities.iter().map(|(n, c)| json!({"quantity": n, "change": c})).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        }))?,
    )
    .with_context(|| format!("cannot write {}", json_path.display()))?;
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
        .series(Series::new("φ", &series[4]))
        .series(Series::new("θ", &series[5]));
    for ext in ["png", "svg"] {
        p.write(&args.out.join(format!("attitude.{ext}")))?;
    }
    let p = LinePlot::new("Trim inflow ratios", &xl, "λ [-]")
        .series(Series::new("λ_mr", &series[6]))
        .series(Series::new("λ_tr", &series[7]));
    for ext in ["png", "svg"] {
        p.write(&args.out.join(format!("inflow.{ext}")))?;
    }
    let unphysical = validity
        .iter()
        .flatten()
        .filter(|v| !v.is_physical())
        .count();
    let mut summary = format!(
        "swept {var} over {} points: {} converged, {failed} failed, {unphysical} unphysical",
        values.len(),
        values.len() - failed,
    );
    if unphysical > 0 {
        let _ = write!(summary, ": {}", violation_summary(&values, &validity, unit));
    }
    let _ = write!(summary, "; {} jump(s)", jumps.len());
    for d in &jumps {
        let names: Vec<&str> = d.quantities.iter().map(|q| q.0).collect();
        let _ = write!(
            summary,
            ", {} -> {} {unit} ({})",
            values[d.index - 1],
            values[d.index],
            names.join(" ")
        );
    }
    // a closed stdout is reported after the verdicts below
    let printed = writeln!(
        std::io::stdout().lock(),
        "{summary}; wrote {}/sweep.csv, sweep.json and inputs/attitude/inflow plots",
        args.out.display()
    );
    if failed > 0 {
        bail!("{failed} sweep point(s) did not trim");
    }
    if unphysical > 0 && !args.cond.allow_unphysical {
        bail!(
            "{unphysical} sweep point(s) are not physical (see `violations` in sweep.csv); --allow-unphysical accepts them"
        );
    }
    Ok(printed?)
}

/// A violation for a CSV cell (no commas): `S_col=3.5e-1 (allowed -0.1..0.3)`.
fn csv_violation(v: &Violation) -> String {
    let allowed = match v.allowed {
        Allowed::Within { min, max } => format!("{min}..{max}"),
        Allowed::Outside { min, max } => format!("<={min} or >={max}"),
    };
    format!("{}={:.6e} (allowed {allowed})", v.quantity, v.value)
}

/// "S_col beyond [-0.1, 0.3] at -20..-11 and 7.5..20 m/s; descent_ratio_mr
/// not <= 0.25 or >= 2 at -8..-1.5 m/s": per quantity, the runs of
/// consecutive sweep points where it is out of range.
fn violation_summary(values: &[f64], validity: &[Option<Validity>], unit: &str) -> String {
    let mut quantities: Vec<(&str, Allowed)> = Vec::new();
    for v in validity.iter().flatten() {
        for x in &v.violations {
            if !quantities.iter().any(|q| q.0 == x.quantity) {
                quantities.push((x.quantity, x.allowed));
            }
        }
    }
    let mut parts = Vec::new();
    for (q, allowed) in quantities {
        let bad: Vec<bool> = validity
            .iter()
            .map(|v| {
                v.as_ref()
                    .is_some_and(|v| v.violations.iter().any(|x| x.quantity == q))
            })
            .collect();
        let mut runs = Vec::new();
        let mut k = 0;
        while k < bad.len() {
            if bad[k] {
                let start = k;
                while k + 1 < bad.len() && bad[k + 1] {
                    k += 1;
                }
                runs.push(if start == k {
                    format!("{}", values[start])
                } else {
                    format!("{}..{}", values[start], values[k])
                });
            }
            k += 1;
        }
        let range = match allowed {
            Allowed::Within { .. } => format!("beyond {allowed}"),
            Allowed::Outside { .. } => format!("not {allowed}"),
        };
        parts.push(format!("{q} {range} at {} {unit}", runs.join(" and ")));
    }
    parts.join("; ")
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
    let validity = t.validity(&model);
    report_violations("trim", &validity);
    if !validity.is_physical() && !args.cond.allow_unphysical {
        bail!(
            "refusing to linearize: the trim is not physical ({} violation(s) above); --allow-unphysical linearizes anyway",
            validity.violations.len()
        );
    }
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
    if !lm.is_equilibrium() {
        let (name, value) = lm.worst_residual();
        let msg = format!(
            "the operating point is not an equilibrium: affine residual |xdot0|_inf = {:.3e} (d{name}/dt = {value:.3e}) > {EQUILIBRIUM_TOL:e}",
            lm.xdot0.amax()
        );
        if !args.cond.allow_unphysical {
            bail!("refusing to linearize: {msg}; --allow-unphysical linearizes anyway");
        }
        crate::console::note!("warning: {msg}");
    }
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
        "trim": trim_json(&t, &model),
        "affine_residual_norm": lm.xdot0.amax(),
        "equilibrium": lm.is_equilibrium(),
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
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
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
    )?;
    writeln!(
        out,
        "{} unstable pole(s); controllable subspace {} of 27; affine residual {:.1e}",
        summary["unstable_poles"],
        reach.dimension,
        lm.xdot0.amax()
    )?;
    Ok(())
}
