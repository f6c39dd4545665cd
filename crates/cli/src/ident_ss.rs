//! `helicon ident ss`: fit a linear state-space model with chosen free
//! entries (a model TOML) to one or several frequency responses of
//! `frf.csv` files (see docs/ident.md).

use crate::ident_cmd::{file_stem, fit_curves, read_frf, write_bode};
use anyhow::{Context, Result, bail};
use clap::Args;
use helicon_ident::cost::CostOptions;
use helicon_ident::frf::Frf;
use helicon_ident::ssfit::{Response, SsFit, SsSpec, fit_ss};
use nalgebra::DMatrix;
use serde_json::{Value, json};
use std::path::PathBuf;

/// `helicon ident ss`.
#[derive(Args, Debug)]
pub struct SsArgs {
    /// The model (TOML: states, inputs, outputs, [A] [B] [C] [D] rows,
    /// [delay_s], [[parameter]], [[response]]; see docs/ident.md).
    pub model: PathBuf,
    /// Points with a coherence γ² at or below this are left out (default:
    /// the model file's `min_coherence`, else 0.6).
    #[arg(long, allow_negative_numbers = true)]
    pub min_coherence: Option<f64>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Rows of a matrix as JSON arrays.
fn rows(m: &DMatrix<f64>) -> Value {
    Value::Array(
        m.row_iter()
            .map(|r| Value::Array(r.iter().map(|v| json!(v)).collect()))
            .collect(),
    )
}

/// `DIR/ss_fit.json`.
fn document(a: &SsArgs, spec: &SsSpec, fit: &SsFit, min_coherence: f64) -> Value {
    let params: Vec<Value> = fit
        .parameters
        .iter()
        .map(|p| {
            // An unidentifiable parameter has infinite bounds: JSON null.
            let fin = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
            json!({
                "name": p.name,
                "value": p.value,
                "cramer_rao": fin(p.cramer_rao),
                "cramer_rao_pct": fin(p.cramer_rao_pct),
                "insensitivity_pct": fin(p.insensitivity_pct),
                "meets_guidelines": p.flags.is_empty(),
                "identifiable": p.identifiable(),
                "flags": p.flags,
            })
        })
        .collect();
    let responses: Vec<Value> = fit
        .responses
        .iter()
        .zip(&spec.responses)
        .map(|(c, r)| {
            json!({
                "input": c.input,
                "output": c.output,
                "frf": r.frf.display().to_string(),
                "frf_output": r.frf_output,
                "omega_min_rad_s": r.omega_min_rad_s,
                "omega_max_rad_s": if r.omega_max_rad_s.is_finite() { json!(r.omega_max_rad_s) } else { Value::Null },
                "cost": c.cost,
                "n_points": c.n_points,
            })
        })
        .collect();
    let m = &fit.matrices;
    let corr: Vec<Value> = fit
        .correlation
        .row_iter()
        .map(|r| {
            Value::Array(
                r.iter()
                    .map(|v| if v.is_finite() { json!(v) } else { Value::Null })
                    .collect(),
            )
        })
        .collect();
    json!({
        "model": a.model.display().to_string(),
        "min_coherence": min_coherence,
        "cost": fit.cost,
        "cost_rule": "mean of the responses' J",
        "responses": responses,
        "parameters": params,
        "correlation": {
            "names": fit.parameters.iter().map(|p| p.name.clone()).collect::<Vec<_>>(),
            "matrix": corr,
        },
        "states": spec.model.states,
        "inputs": spec.model.inputs,
        "outputs": spec.model.outputs,
        "A": rows(&m.a),
        "B": rows(&m.b),
        "C": rows(&m.c),
        "D": rows(&m.d),
        "delay_s": m.delay_s,
        "evaluations": fit.evaluations,
    })
}

/// `helicon ident ss`.
pub fn run_ss(a: &SsArgs) -> Result<()> {
    let spec = SsSpec::from_file(&a.model)?;
    let min_coherence = a.min_coherence.unwrap_or(spec.min_coherence);
    if !(0.0..1.0).contains(&min_coherence) {
        bail!("--min-coherence {min_coherence}: must be in [0, 1)");
    }
    let model_file = a.model.display().to_string();
    let mut frfs: Vec<Frf> = Vec::with_capacity(spec.responses.len());
    let mut responses = Vec::with_capacity(spec.responses.len());
    for (i, r) in spec.responses.iter().enumerate() {
        let f = read_frf(&r.frf, &r.frf_output)
            .with_context(|| format!("{model_file}: `response[{i}].frf`"))?;
        let pos = |names: &[String], n: &str| names.iter().position(|s| s == n).unwrap_or(0);
        responses.push(Response {
            input: pos(&spec.model.inputs, &r.input),
            output: pos(&spec.model.outputs, &r.output),
            frf: f.clone(),
            omega_min_rad_s: r.omega_min_rad_s,
            omega_max_rad_s: r.omega_max_rad_s,
        });
        frfs.push(f);
    }
    let opts = CostOptions {
        min_coherence,
        ..CostOptions::default()
    };
    let fit = fit_ss(&spec.model, &responses, &opts).with_context(|| model_file.clone())?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create", a.out.display()))?;
    let json_path = a.out.join("ss_fit.json");
    let doc = document(a, &spec, &fit, min_coherence);
    std::fs::write(&json_path, serde_json::to_string_pretty(&doc)? + "\n")
        .with_context(|| format!("{}: cannot write", json_path.display()))?;
    println!(
        "{model_file}: J = {:.3} (mean over {} responses), {} evaluations",
        fit.cost,
        fit.responses.len(),
        fit.evaluations
    );
    for (i, (c, f)) in fit.responses.iter().zip(&frfs).enumerate() {
        let (u, o) = (responses[i].input, responses[i].output);
        // The model's curve where it is finite everywhere on the grid (jω
        // an eigenvalue of A would leave the estimate alone on the plot).
        let finite = f
            .omega_rad_s
            .iter()
            .all(|w| fit.matrices.response(*w).is_some());
        let overlay = finite.then(|| {
            fit_curves(f, |w| {
                fit.matrices
                    .response(w)
                    .map_or(helicon_ident::Complex64::new(0.0, 0.0), |h| h[(o, u)])
            })
        });
        let png = a.out.join(format!(
            "ss_{}_{}.png",
            file_stem(&c.input),
            file_stem(&c.output)
        ));
        let title = format!(
            "{} / {}: state-space fit, J = {:.3}",
            c.output, c.input, c.cost
        );
        let band = (responses[i].omega_min_rad_s, responses[i].omega_max_rad_s);
        write_bode(&png, &title, f, overlay.as_ref(), Some(band))?;
        println!(
            "  {} / {}: J = {:.3} over {} points; {}",
            c.output,
            c.input,
            c.cost,
            c.n_points,
            png.display()
        );
    }
    for p in &fit.parameters {
        println!(
            "  {:>10} = {:<14.6e} CR {}  I {}  {}",
            p.name,
            p.value,
            crate::ident_cmd::percent_cell(p.cramer_rao_pct),
            crate::ident_cmd::percent_cell(p.insensitivity_pct),
            if p.flags.is_empty() {
                "ok".to_string()
            } else {
                p.flags.join("; ")
            }
        );
    }
    println!("  {}", json_path.display());
    Ok(())
}
