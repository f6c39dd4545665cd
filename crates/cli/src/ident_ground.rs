//! `helicon ident ground KIND READINGS.csv`: the ground experiments of thesis
//! §11.1 as calculators (see docs/ground-and-servo.md and
//! `helicon_model::ground`).

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use helicon_model::Params;
use helicon_model::ground::{KINDS, Kind, Readings, calculate};
use helicon_sim::plot::{Figure, Panel, Series};
use std::path::PathBuf;

/// `helicon ident ground`.
#[derive(Args, Debug)]
pub struct GroundArgs {
    /// The experiment: rotor-drag, main-lift-slope, tail-lift-slope,
    /// blade-spring, bell-gain, hiller-gain, tail-fin-loss, stabilizer-lift-slope.
    pub kind: String,
    /// The readings (CSV: the kind's two columns, one reading per row; `#` lines are comments).
    #[arg(required_unless_present = "template")]
    pub readings: Option<PathBuf>,
    /// Parameter file (TOML) with the helicopter's geometry (default: the Bergen Twin).
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Print a template readings CSV for KIND and exit.
    #[arg(long)]
    pub template: bool,
    /// Output folder: DIR/ground_<kind>.json and DIR/ground_<kind>.png.
    #[arg(long, required_unless_present = "template")]
    pub out: Option<PathBuf>,
}

/// Run `helicon ident ground`.
pub fn run(a: &GroundArgs) -> Result<()> {
    let kind = Kind::from_name(&a.kind).ok_or_else(|| {
        anyhow!(
            "unknown ground experiment `{}`: one of {}",
            a.kind,
            KINDS.map(Kind::name).join(", ")
        )
    })?;
    let mut con = crate::console::Console::stdout();
    if a.template {
        con.write_str(&kind.template());
        return con.finish().context("writing to stdout");
    }
    let (Some(path), Some(out)) = (&a.readings, &a.out) else {
        bail!("READINGS and --out are needed (or --template)");
    };
    let params = match &a.params {
        Some(p) => Params::from_file(p)?,
        None => Params::bergen_twin(),
    };
    let file = path.display().to_string();
    let text = crate::files::read_text(path)?;
    let readings = Readings::parse_csv(&text, &file, kind)?;
    let r = calculate(&readings, &params)?;
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    let stem = format!("ground_{}", kind.name().replace('-', "_"));
    let (section, name) = r.key.split_once('.').unwrap_or(("", r.key));
    let doc = serde_json::json!({
        "kind": kind.name(),
        "readings": file,
        "params": a.params.as_ref().map(|p| p.display().to_string()),
        "key": r.key,
        "value": r.value,
        "std_error": r.std_error,
        "std_error_pct": 100.0 * r.std_error / r.value.abs(),
        "unit": r.unit,
        "n_readings": r.n_readings,
        "error_variable": r.error_variable,
        "residual_rms": r.residual_rms,
        "intercept": r.intercept.map(|[v, s]| serde_json::json!({"value": v, "std_error": s})),
        "constants": r.constants.iter().map(|(k, v)| serde_json::json!({"key": k, "value": v})).collect::<Vec<_>>(),
        "params_toml": format!("[{section}]\n{name} = {}\n", r.value),
    });
    let json_path = out.join(format!("{stem}.json"));
    std::fs::write(&json_path, serde_json::to_string_pretty(&doc)? + "\n")
        .with_context(|| format!("{}: cannot write", json_path.display()))?;
    let png = out.join(format!("{stem}.png"));
    plot(&png, kind, &r)?;
    writeln!(
        con,
        "{file}: {} = {} {} ({} readings, {:.2} %)",
        r.key,
        helicon_sim::plot::value_pm(r.value, r.std_error),
        r.unit,
        r.n_readings,
        100.0 * r.std_error / r.value.abs()
    );
    writeln!(con, "  {}\n  {}", json_path.display(), png.display());
    con.finish().context("writing to stdout")
}

/// The readings and the fitted relation against the set variable.
fn plot(png: &std::path::Path, kind: Kind, r: &helicon_model::ground::GroundResult) -> Result<()> {
    let mut pts = r.points.clone();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let read: Vec<(f64, f64)> = pts.iter().map(|p| (p[0], p[1])).collect();
    let fit: Vec<(f64, f64)> = r.curve.iter().map(|p| (p[0], p[1])).collect();
    let [x, y] = kind.columns();
    Figure::new(
        &format!(
            "{}: {} = {} {}",
            kind.name(),
            r.key,
            helicon_sim::plot::value_pm(r.value, r.std_error),
            r.unit
        ),
        &helicon_sim::plot::column_label(x),
    )
    .panel(
        Panel::new(&helicon_sim::plot::column_label(y))
            .series(Series::new("readings", &read).markers())
            .series(Series::new("fit", &fit)),
    )
    .write(png)
    .with_context(|| png.display().to_string())
}
