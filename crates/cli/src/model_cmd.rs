//! `helicon eval` and `helicon params`: the nonlinear model on the command line.

use anyhow::{Context, Result, bail};
use clap::Args;
use helicon_model::model::check_output;
use helicon_model::state::{NU, NX, STATE_NAMES};
use helicon_model::{Aux, Input, Model, Params, Preset, State};
use nalgebra::Vector3;
use serde_json::{Map, Value, json};
use std::io::{BufRead, BufWriter, Write};
use std::path::PathBuf;

/// Model selection flags shared by the model subcommands.
#[derive(Args, Debug, Clone)]
pub struct ModelFlags {
    /// Model preset: `physical` (printed equations, physical conventions) or
    /// `thesis` (what the thesis implementation computed).
    #[arg(long, default_value = "physical")]
    pub preset: Preset,
    /// Parameter file (TOML) overriding any subset of the embedded Bergen Twin.
    #[arg(long)]
    pub params: Option<PathBuf>,
}

/// The helicopter a command flies, for its printout: the Bergen Industrial
/// Twin, or the parameter file given (its keys over the Twin's).
pub fn helicopter_label(params: Option<&std::path::Path>) -> String {
    match params {
        None => "Bergen Industrial Twin".to_string(),
        Some(p) => format!(
            "the helicopter of {} (its keys over the Bergen Twin's)",
            p.display()
        ),
    }
}

impl ModelFlags {
    /// The parameters these flags select.
    pub fn load_params(&self) -> Result<Params> {
        Ok(match &self.params {
            Some(path) => Params::from_file(path)?,
            None => Params::bergen_twin(),
        })
    }

    /// The model these flags select.
    pub fn model(&self) -> Result<Model> {
        Ok(Model::new(self.load_params()?, self.preset.options()))
    }
}

/// `helicon eval`: evaluate ẋ = f(x, u, wind) for JSON lines.
#[derive(Args, Debug)]
pub struct EvalArgs {
    #[command(flatten)]
    model: ModelFlags,
    /// Read JSON lines from this file instead of standard input.
    #[arg(long)]
    input: Option<PathBuf>,
    /// On a bad line, write `{"line": N, "error": ...}` and go on (exit status 1 at the end).
    #[arg(long)]
    keep_going: bool,
}

/// `helicon params`: print the effective parameter set as TOML.
#[derive(Args, Debug)]
pub struct ParamsArgs {
    /// Parameter file (TOML) overriding any subset of the embedded Bergen Twin.
    #[arg(long)]
    params: Option<PathBuf>,
}

/// Run `helicon params`.
pub fn run_params(args: &ParamsArgs) -> Result<()> {
    let p = match &args.params {
        Some(path) => Params::from_file(path)?,
        None => Params::bergen_twin(),
    };
    let mut con = crate::console::Console::stdout();
    con.write_str(&p.to_toml());
    con.finish().context("writing to stdout")
}

fn vector<const N: usize>(v: &Value, field: &str) -> Result<[f64; N]> {
    let arr = v
        .as_array()
        .with_context(|| format!("field `{field}` must be an array of {N} numbers"))?;
    if arr.len() != N {
        bail!("field `{field}` must have {N} numbers, found {}", arr.len());
    }
    let mut out = [0.0; N];
    for (i, (o, e)) in out.iter_mut().zip(arr).enumerate() {
        *o = e
            .as_f64()
            .with_context(|| format!("field `{field}[{i}]` must be a number, found {e}"))?;
        if !o.is_finite() {
            bail!("field `{field}[{i}]` must be finite");
        }
    }
    Ok(out)
}

/// Parse one input line into (x, u, wind_ned).
fn parse_line(line: &str) -> Result<(State, Input, Vector3<f64>)> {
    let v: Value = serde_json::from_str(line).context("not valid JSON")?;
    let obj = v
        .as_object()
        .context("each line must be a JSON object with `x`, `u` and optional `wind_ned`")?;
    for key in obj.keys() {
        if !matches!(key.as_str(), "x" | "u" | "wind_ned") {
            bail!("unknown field `{key}` (expected `x`, `u`, `wind_ned`)");
        }
    }
    let xv = obj.get("x").context("missing field `x`")?;
    let x = match xv {
        Value::Array(_) => State::from_column_slice(&vector::<NX>(xv, "x")?),
        Value::Object(m) => {
            let mut x = State::zeros();
            for k in m.keys() {
                if !STATE_NAMES.contains(&k.as_str()) {
                    bail!(
                        "field `x.{k}` is not a state name (expected {})",
                        STATE_NAMES.join(" ")
                    );
                }
            }
            for (i, name) in STATE_NAMES.iter().enumerate() {
                let e = m
                    .get(*name)
                    .with_context(|| format!("missing field `x.{name}`"))?;
                x[i] = e
                    .as_f64()
                    .with_context(|| format!("field `x.{name}` must be a number, found {e}"))?;
            }
            x
        }
        _ => bail!(
            "field `x` must be an object keyed by the 30 state names or an array of 30 numbers"
        ),
    };
    let u = Input::from_column_slice(&vector::<NU>(
        obj.get("u").context("missing field `u`")?,
        "u",
    )?);
    let wind = match obj.get("wind_ned") {
        Some(w) => Vector3::from(vector::<3>(w, "wind_ned")?),
        None => Vector3::zeros(),
    };
    Ok((x, u, wind))
}

fn v3(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

/// The JSON output of one evaluation.
pub fn eval_json(xdot: &State, aux: &Aux) -> Value {
    let mut xd = Map::new();
    for (i, n) in STATE_NAMES.iter().enumerate() {
        xd.insert((*n).to_string(), json!(xdot[i]));
    }
    json!({
        "xdot": xd,
        "lambda_mr": aux.lambda_mr,
        "lambda_tr": aux.lambda_tr,
        "vi_mr_m_s": aux.vi_mr_m_s,
        "vi_tr_m_s": aux.vi_tr_m_s,
        "ct_mr": aux.ct_mr,
        "ct_tr": aux.ct_tr,
        "force_mr_hub_n": v3(&aux.force_mr_hub_n),
        "torque_mr_hub_nm": v3(&aux.torque_mr_hub_nm),
        "torque_mr_body_nm": v3(&aux.torque_mr_body_nm),
        "force_tr_y_n": aux.force_tr_y_n,
        "torque_tr_body_nm": v3(&aux.torque_tr_body_nm),
        "force_drag_body_n": v3(&aux.drag.force_body_n),
        "torque_drag_body_nm": v3(&aux.drag.torque_body_nm),
        "force_gravity_body_n": v3(&aux.force_gravity_body_n),
        "force_total_body_n": v3(&aux.force_total_body_n),
        "torque_total_body_nm": v3(&aux.torque_total_body_nm),
    })
}

/// Run `helicon eval`.
pub fn run_eval(args: &EvalArgs) -> Result<()> {
    let model = args.model.model()?;
    let source = args
        .input
        .as_ref()
        .map_or("<stdin>".to_string(), |p| p.display().to_string());
    let reader: Box<dyn BufRead> = match &args.input {
        Some(p) => Box::new(std::io::BufReader::new(crate::files::open_lines(p)?)),
        None => Box::new(std::io::stdin().lock()),
    };
    let mut out = BufWriter::new(std::io::stdout().lock());
    let mut failures = 0usize;
    for (n, line) in reader.lines().enumerate() {
        let lineno = n + 1;
        let line = line.with_context(|| format!("{source}: cannot read line {lineno}"))?;
        if line.trim().is_empty() {
            continue;
        }
        let result = parse_line(&line).and_then(|(x, u, w)| {
            let (xd, aux) = model.derivative(&x, &u, &w)?;
            // never print NaN/inf (JSON `null`) as a result
            check_output(&xd, &aux)?;
            Ok((xd, aux))
        });
        match result {
            Ok((xd, aux)) => writeln!(out, "{}", eval_json(&xd, &aux))?,
            Err(e) => {
                let msg = format!("{source}: line {lineno}: {e:#}");
                if !args.keep_going {
                    // the bad line is the error to report, even when the
                    // reader of stdout has gone
                    let _ = out.flush();
                    bail!(msg);
                }
                failures += 1;
                writeln!(out, "{}", json!({"line": lineno, "error": msg}))?;
            }
        }
    }
    out.flush()?;
    if failures > 0 {
        bail!("{source}: {failures} line(s) failed");
    }
    Ok(())
}
