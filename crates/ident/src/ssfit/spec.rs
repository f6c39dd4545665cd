//! The model file of a state-space fit (TOML): the model, the responses to
//! fit and where they are, read and checked with errors that name the file and
//! the field (format in docs/ident.md).

use super::{Cell, FreeParameter, SsModel};
use crate::error::{IdentError, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A response named in a model file: the input and output, the frf.csv that
/// holds it, its `output` value there, and the band.
#[derive(Debug, Clone, PartialEq)]
pub struct ResponseSpec {
    /// Input name (one of the model's inputs).
    pub input: String,
    /// Output name (one of the model's outputs).
    pub output: String,
    /// The frf.csv, relative paths resolved from the model file's folder.
    pub frf: PathBuf,
    /// The response's `output` value in the frf.csv (default: `output`).
    pub frf_output: String,
    /// Lowest frequency used, rad/s (default 0).
    pub omega_min_rad_s: f64,
    /// Highest frequency used, rad/s (default ∞).
    pub omega_max_rad_s: f64,
}

/// A model file: the model, the responses to fit and the coherence threshold.
#[derive(Debug, Clone, PartialEq)]
pub struct SsSpec {
    /// The model.
    pub model: SsModel,
    /// The responses.
    pub responses: Vec<ResponseSpec>,
    /// Points with γ² at or below this are left out (default 0.6).
    pub min_coherence: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpec {
    states: Vec<String>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    #[serde(rename = "A")]
    a: BTreeMap<String, Vec<toml::Value>>,
    #[serde(rename = "B")]
    b: BTreeMap<String, Vec<toml::Value>>,
    #[serde(rename = "C")]
    c: BTreeMap<String, Vec<toml::Value>>,
    #[serde(rename = "D", default)]
    d: Option<BTreeMap<String, Vec<toml::Value>>>,
    #[serde(default)]
    delay_s: BTreeMap<String, toml::Value>,
    #[serde(default)]
    min_coherence: Option<f64>,
    #[serde(default)]
    parameter: Vec<RawParameter>,
    #[serde(default)]
    response: Vec<RawResponse>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawParameter {
    name: String,
    start: f64,
    min: Option<f64>,
    max: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawResponse {
    input: String,
    output: String,
    frf: String,
    frf_output: Option<String>,
    omega_min_rad_s: Option<f64>,
    omega_max_rad_s: Option<f64>,
}

impl SsSpec {
    /// Read a model file (relative `frf` paths resolved from its folder).
    pub fn from_file(path: &Path) -> Result<SsSpec> {
        let file = path.display().to_string();
        let text = helicon_model::config_error::read_text_bounded(
            path,
            helicon_model::config_error::MAX_TEXT_BYTES,
        )
        .map_err(|e| IdentError::Parse {
            file: file.clone(),
            message: format!("cannot read: {}", e.into_io()),
        })?;
        let base = path.parent().unwrap_or(Path::new(""));
        SsSpec::from_toml_str(&text, &file, base)
    }

    /// Parse a model file's text; `file` names it in errors, `base` is the
    /// folder relative `frf` paths start from.
    pub fn from_toml_str(text: &str, file: &str, base: &Path) -> Result<SsSpec> {
        let raw: RawSpec = toml::from_str(text).map_err(|e| IdentError::Parse {
            file: file.to_string(),
            // a misspelt key shown with the nearest valid one
            message: helicon_config::with_suggestion(e.to_string().trim_end()),
        })?;
        let model = model_from_raw(&raw, file)?;
        let err = |field: String, rule: String| IdentError::file(file, field, rule);
        // The structural checks, their field names mapped to the file's.
        model.check_fields().map_err(|(field, rule)| {
            let field = rename_field(&model, &field);
            IdentError::file(file, field, rule)
        })?;
        let min_coherence = raw.min_coherence.unwrap_or(0.6);
        if !(0.0..1.0).contains(&min_coherence) {
            return Err(err(
                "min_coherence".into(),
                format!("{min_coherence}: must be in [0, 1)"),
            ));
        }
        if raw.response.is_empty() {
            return Err(err(
                "response".into(),
                "at least one [[response]] is needed".into(),
            ));
        }
        let responses = raw
            .response
            .into_iter()
            .enumerate()
            .map(|(i, r)| response_spec(file, base, &model, i, r))
            .collect::<Result<Vec<_>>>()?;
        Ok(SsSpec {
            model,
            responses,
            min_coherence,
        })
    }
}

/// The model of a parsed file (cells resolved to numbers or parameters).
fn model_from_raw(raw: &RawSpec, file: &str) -> Result<SsModel> {
    let err = |field: String, rule: String| IdentError::file(file, field, rule);
    let names: Vec<&str> = raw.parameter.iter().map(|p| p.name.as_str()).collect();
    let cell = |field: String, v: &toml::Value| -> Result<Cell> {
        match v {
            toml::Value::Integer(i) => Ok(Cell::Fixed(*i as f64)),
            toml::Value::Float(x) if x.is_finite() => Ok(Cell::Fixed(*x)),
            toml::Value::Float(x) => Err(err(field, format!("{x}: must be finite"))),
            toml::Value::String(s) => names
                .iter()
                .position(|n| n == s)
                .map(Cell::Free)
                .ok_or_else(|| {
                    err(
                        field,
                        format!(
                            "`{s}` is not a declared parameter (parameters: {})",
                            names.join(", ")
                        ),
                    )
                }),
            other => Err(err(
                field,
                format!("{other}: a cell is a number or a parameter name"),
            )),
        }
    };
    let matrix = |name: &str,
                  table: &BTreeMap<String, Vec<toml::Value>>,
                  rows: &[String],
                  row_what: &str,
                  cols: &[String],
                  col_what: &str|
     -> Result<Vec<Vec<Cell>>> {
        if let Some(k) = table.keys().find(|k| !rows.contains(k)) {
            return Err(err(
                format!("{name}.{k}"),
                format!("not one of the {row_what} ({})", rows.join(", ")),
            ));
        }
        rows.iter()
            .map(|r| {
                let row = table.get(r).ok_or_else(|| {
                    err(
                        format!("{name}.{r}"),
                        format!(
                            "missing: {name} needs a row for each of the {row_what} ({})",
                            rows.join(", ")
                        ),
                    )
                })?;
                if row.len() != cols.len() {
                    return Err(err(
                        format!("{name}.{r}"),
                        format!(
                            "{} cells for {} {col_what} ({}): {name} must be {} × {}",
                            row.len(),
                            cols.len(),
                            cols.join(", "),
                            rows.len(),
                            cols.len()
                        ),
                    ));
                }
                row.iter()
                    .enumerate()
                    .map(|(j, v)| cell(format!("{name}.{r}[{j}]"), v))
                    .collect()
            })
            .collect()
    };
    let (st, inp, out) = (&raw.states, &raw.inputs, &raw.outputs);
    let a = matrix("A", &raw.a, st, "states", st, "states")?;
    let b = matrix("B", &raw.b, st, "states", inp, "inputs")?;
    let c = matrix("C", &raw.c, out, "outputs", st, "states")?;
    let d = match &raw.d {
        Some(t) => matrix("D", t, out, "outputs", inp, "inputs")?,
        None => vec![vec![Cell::Fixed(0.0); inp.len()]; out.len()],
    };
    if let Some(k) = raw.delay_s.keys().find(|k| !inp.contains(k)) {
        return Err(err(
            format!("delay_s.{k}"),
            format!("not one of the inputs ({})", inp.join(", ")),
        ));
    }
    let delay_s = inp
        .iter()
        .map(|i| match raw.delay_s.get(i) {
            Some(v) => cell(format!("delay_s.{i}"), v),
            None => Ok(Cell::Fixed(0.0)),
        })
        .collect::<Result<Vec<_>>>()?;
    let model = SsModel {
        states: raw.states.clone(),
        inputs: raw.inputs.clone(),
        outputs: raw.outputs.clone(),
        a,
        b,
        c,
        d,
        delay_s,
        parameters: raw
            .parameter
            .iter()
            .map(|p| FreeParameter {
                name: p.name.clone(),
                start: p.start,
                min: p.min,
                max: p.max,
            })
            .collect(),
    };
    Ok(model)
}

/// `A[1][2]` → `A.q[2]` (rows by name as in the file); other fields unchanged.
fn rename_field(model: &SsModel, field: &str) -> String {
    let rows = |m: &str| match m {
        "A" | "B" => Some(&model.states),
        "C" | "D" => Some(&model.outputs),
        _ => None,
    };
    let mut parts = field.splitn(2, '[');
    let head = parts.next().unwrap_or("");
    let rest = parts.next().unwrap_or("");
    if let Some(names) = rows(head)
        && let Some((i, tail)) = rest.split_once(']')
        && let Ok(i) = i.parse::<usize>()
        && let Some(n) = names.get(i)
    {
        return format!("{head}.{n}{tail}");
    }
    if head == "delay_s"
        && let Some((i, _)) = rest.split_once(']')
        && let Ok(i) = i.parse::<usize>()
        && let Some(n) = model.inputs.get(i)
    {
        return format!("delay_s.{n}");
    }
    field.to_string()
}

fn response_spec(
    file: &str,
    base: &Path,
    model: &SsModel,
    i: usize,
    r: RawResponse,
) -> Result<ResponseSpec> {
    let f = |s: &str| format!("response[{i}].{s}");
    let err = |field: String, rule: String| IdentError::file(file, field, rule);
    if !model.inputs.contains(&r.input) {
        return Err(err(
            f("input"),
            format!(
                "`{}` is not one of the inputs ({})",
                r.input,
                model.inputs.join(", ")
            ),
        ));
    }
    if !model.outputs.contains(&r.output) {
        return Err(err(
            f("output"),
            format!(
                "`{}` is not one of the outputs ({})",
                r.output,
                model.outputs.join(", ")
            ),
        ));
    }
    if r.frf.trim().is_empty() {
        return Err(err(f("frf"), "an empty path".into()));
    }
    let lo = r.omega_min_rad_s.unwrap_or(0.0);
    let hi = r.omega_max_rad_s.unwrap_or(f64::INFINITY);
    if !(lo.is_finite() && lo >= 0.0) {
        return Err(err(
            f("omega_min_rad_s"),
            format!("{lo}: must be finite and ≥ 0"),
        ));
    }
    if hi.is_nan() || hi <= lo {
        return Err(err(
            f("omega_max_rad_s"),
            format!("{hi}: must be above omega_min_rad_s = {lo}"),
        ));
    }
    let path = Path::new(&r.frf);
    Ok(ResponseSpec {
        frf: if path.is_absolute() {
            path.to_path_buf()
        } else {
            base.join(path)
        },
        frf_output: r.frf_output.unwrap_or_else(|| r.output.clone()),
        input: r.input,
        output: r.output,
        omega_min_rad_s: lo,
        omega_max_rad_s: hi,
    })
}
