//! `helicon control …`: thin CLI over `helicon-lti` (DARE, dlqr, Kalman, c2d).
//!
//! Inputs are CSV files of plain numbers, one matrix row per line (comma-separated, or
//! whitespace-separated when a line has no comma). A header row whose cells are all
//! non-numeric is skipped, and so is a first column of row names (as in
//! `../shared/reference/thesis_A.csv`). Empty lines and lines starting with `#` are ignored.
//! Output is JSON on stdout with matrices as nested row lists; poles are `[re, im]` pairs.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use nalgebra::{Complex, DMatrix};
use serde_json::{Value, json};

/// Linear control design: Riccati, LQR, Kalman, discretization.
#[derive(Args, Debug)]
pub struct ControlArgs {
    #[command(subcommand)]
    command: ControlCommand,
}

#[derive(Subcommand, Debug)]
enum ControlCommand {
    /// Solve X = AᵀXA − AᵀXB(R + BᵀXB)⁻¹BᵀXA + Q → {"X", "residual", "iterations"}.
    Dare(DareArgs),
    /// Discrete LQR (optionally pincer α, thesis (14.18)–(14.22)) → {"K", "S", "poles", "residual"}.
    Dlqr(DlqrArgs),
    /// Steady-state Kalman predictor gain (thesis (15.8)) → {"L", "P", "M", "poles", "residual"}.
    Kalman(KalmanArgs),
    /// Zero-order-hold discretization → {"Phi", "Gamma"}.
    C2d(C2dArgs),
}

#[derive(Args, Debug)]
struct DareArgs {
    /// State matrix A (n×n), CSV.
    #[arg(long)]
    a: PathBuf,
    /// Input matrix B (n×m), CSV.
    #[arg(long)]
    b: PathBuf,
    /// State weight Q (n×n, symmetric PSD), CSV.
    #[arg(long)]
    q: PathBuf,
    /// Input weight R (m×m, symmetric PD), CSV.
    #[arg(long)]
    r: PathBuf,
    /// Optional cross weight N (n×m), CSV.
    #[arg(long)]
    n: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct DlqrArgs {
    #[command(flatten)]
    dare: DareArgs,
    /// Prescribed degree of stability α ≥ 1 (pincer): closed-loop poles inside |z| < 1/α.
    #[arg(long)]
    alpha: Option<f64>,
}

#[derive(Args, Debug)]
struct KalmanArgs {
    /// State matrix Φ (n×n), CSV.
    #[arg(long)]
    a: PathBuf,
    /// Output matrix C (p×n), CSV.
    #[arg(long)]
    c: PathBuf,
    /// Process-noise covariance Qn (n×n, or w×w with --g), CSV.
    #[arg(long)]
    qn: PathBuf,
    /// Measurement-noise covariance Rn (p×p), CSV.
    #[arg(long)]
    rn: PathBuf,
    /// Optional process-noise input matrix G (n×w), CSV; default identity.
    #[arg(long)]
    g: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct C2dArgs {
    /// Continuous state matrix A (n×n), CSV.
    #[arg(long)]
    a: PathBuf,
    /// Continuous input matrix B (n×m), CSV.
    #[arg(long)]
    b: PathBuf,
    /// Sample time in seconds.
    #[arg(long)]
    ts: f64,
}

/// Runs a `helicon control` subcommand, printing JSON to stdout.
pub fn run(args: ControlArgs) -> Result<()> {
    let out = match args.command {
        ControlCommand::Dare(a) => dare(&a)?,
        ControlCommand::Dlqr(a) => dlqr(&a)?,
        ControlCommand::Kalman(a) => kalman(&a)?,
        ControlCommand::C2d(a) => c2d(&a)?,
    };
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}

fn rows_json(m: &DMatrix<f64>) -> Value {
    Value::Array(
        (0..m.nrows())
            .map(|i| json!(m.row(i).iter().copied().collect::<Vec<f64>>()))
            .collect(),
    )
}

fn poles_json(p: &[Complex<f64>]) -> Value {
    Value::Array(p.iter().map(|z| json!([z.re, z.im])).collect())
}

/// Is this cell a number (finite or not)?
fn numeric(cell: &str) -> bool {
    cell.trim().parse::<f64>().is_ok()
}

/// Reads a matrix from a CSV file; errors name the file, line and column (1-based).
pub fn read_matrix(path: &Path) -> Result<DMatrix<f64>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read matrix file {}", path.display()))?;
    parse_matrix(&text, &path.display().to_string())
}

/// Parses matrix CSV text; `name` is used in error messages.
pub fn parse_matrix(text: &str, name: &str) -> Result<DMatrix<f64>> {
    let mut lines: Vec<(usize, Vec<&str>)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = if line.contains(',') {
            line.split(',').map(str::trim).collect()
        } else {
            line.split_whitespace().collect()
        };
        lines.push((i + 1, cells));
    }
    if lines.is_empty() {
        bail!("{name}: no matrix rows found (empty file)");
    }
    // Header row: every cell non-numeric (and non-empty).
    let header = lines[0].1.iter().all(|c| !c.is_empty() && !numeric(c));
    let data: &[(usize, Vec<&str>)] = if header { &lines[1..] } else { &lines[..] };
    if data.is_empty() {
        bail!("{name}: only a header row, no data rows");
    }
    // Row-name column: the first cell of every data row is non-numeric text.
    let names = data.iter().all(|(_, c)| !c[0].is_empty() && !numeric(c[0]))
        && data.iter().any(|(_, c)| c.len() > 1);
    let skip = usize::from(names);
    let ncols = data[0].1.len() - skip;
    let first_line = data[0].0;
    if ncols == 0 {
        bail!("{name}: line {first_line} has no numeric columns");
    }
    let mut values = Vec::with_capacity(data.len() * ncols);
    for (line_no, cells) in data {
        let k = cells.len() - skip;
        if k != ncols {
            bail!(
                "{name}: line {line_no} has {k} columns, expected {ncols} (as on line {first_line}); \
                 ragged rows are not a matrix"
            );
        }
        for (j, cell) in cells.iter().enumerate().skip(skip) {
            let col = j + 1;
            let v: f64 = cell.parse().map_err(|_| {
                anyhow::anyhow!(
                    "{name}: line {line_no}, column {col}: cannot parse {cell:?} as a number"
                )
            })?;
            if !v.is_finite() {
                bail!("{name}: line {line_no}, column {col}: non-finite value {cell:?}");
            }
            values.push(v);
        }
    }
    Ok(DMatrix::from_row_slice(data.len(), ncols, &values))
}

fn expect_shape(m: &DMatrix<f64>, path: &Path, rows: usize, cols: usize, what: &str) -> Result<()> {
    if m.nrows() != rows || m.ncols() != cols {
        bail!(
            "{}: {what} is {}x{}, expected {rows}x{cols}",
            path.display(),
            m.nrows(),
            m.ncols()
        );
    }
    Ok(())
}

struct DareData {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    n: Option<DMatrix<f64>>,
}

fn load_dare(args: &DareArgs) -> Result<DareData> {
    let a = read_matrix(&args.a)?;
    let nx = a.nrows();
    expect_shape(&a, &args.a, nx, nx, "A (must be square)")?;
    let b = read_matrix(&args.b)?;
    let m = b.ncols();
    expect_shape(&b, &args.b, nx, m, "B (rows must match A)")?;
    let q = read_matrix(&args.q)?;
    expect_shape(&q, &args.q, nx, nx, "Q")?;
    let r = read_matrix(&args.r)?;
    expect_shape(&r, &args.r, m, m, "R")?;
    let n = match &args.n {
        Some(p) => {
            let n = read_matrix(p)?;
            expect_shape(&n, p, nx, m, "N")?;
            Some(n)
        }
        None => None,
    };
    Ok(DareData { a, b, q, r, n })
}

fn dare(args: &DareArgs) -> Result<Value> {
    let d = load_dare(args)?;
    let s = helicon_lti::dare(&d.a, &d.b, &d.q, &d.r, d.n.as_ref()).context("solving the DARE")?;
    Ok(json!({
        "X": rows_json(&s.x),
        "residual": s.residual,
        "iterations": s.iterations,
        "closed_loop_spectral_radius": s.closed_loop_spectral_radius,
    }))
}

fn dlqr(args: &DlqrArgs) -> Result<Value> {
    let d = load_dare(&args.dare)?;
    let l = match args.alpha {
        Some(alpha) => helicon_lti::dlqr_pincer(&d.a, &d.b, &d.q, &d.r, d.n.as_ref(), alpha)
            .context("pincer dlqr (DARE for αΦ, αΓ)")?,
        None => helicon_lti::dlqr(&d.a, &d.b, &d.q, &d.r, d.n.as_ref()).context("dlqr")?,
    };
    Ok(json!({
        "K": rows_json(&l.k),
        "S": rows_json(&l.s),
        "poles": poles_json(&l.poles),
        "residual": l.residual,
    }))
}

fn kalman(args: &KalmanArgs) -> Result<Value> {
    let a = read_matrix(&args.a)?;
    let nx = a.nrows();
    expect_shape(&a, &args.a, nx, nx, "A (must be square)")?;
    let c = read_matrix(&args.c)?;
    let p = c.nrows();
    expect_shape(&c, &args.c, p, nx, "C (columns must match A)")?;
    let g = match &args.g {
        Some(path) => {
            let g = read_matrix(path)?;
            expect_shape(&g, path, nx, g.ncols(), "G (rows must match A)")?;
            Some(g)
        }
        None => None,
    };
    let w = g.as_ref().map_or(nx, |g| g.ncols());
    let qn = read_matrix(&args.qn)?;
    expect_shape(&qn, &args.qn, w, w, "Qn")?;
    let rn = read_matrix(&args.rn)?;
    expect_shape(&rn, &args.rn, p, p, "Rn")?;
    let k = helicon_lti::dlqe(&a, g.as_ref(), &c, &qn, &rn).context("steady-state Kalman gain")?;
    Ok(json!({
        "L": rows_json(&k.l),
        "P": rows_json(&k.p),
        "M": rows_json(&k.m),
        "poles": poles_json(&k.poles),
        "residual": k.residual,
    }))
}

fn c2d(args: &C2dArgs) -> Result<Value> {
    let a = read_matrix(&args.a)?;
    let nx = a.nrows();
    expect_shape(&a, &args.a, nx, nx, "A (must be square)")?;
    let b = read_matrix(&args.b)?;
    expect_shape(&b, &args.b, nx, b.ncols(), "B (rows must match A)")?;
    let (phi, gamma) = helicon_lti::c2d(&a, &b, args.ts).context("c2d")?;
    Ok(json!({ "Phi": rows_json(&phi), "Gamma": rows_json(&gamma) }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_plain_header_and_names() {
        let m = parse_matrix("1, 2\n3,4\n", "x").unwrap();
        assert_eq!(m, DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]));
        let m = parse_matrix("row,a,b\na,1,2\nb,3,4\n", "x").unwrap();
        assert_eq!(m, DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]));
        let m = parse_matrix("# comment\n1 2\n\n3 4\n", "x").unwrap();
        assert_eq!(m, DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]));
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse_matrix("1,2\n3,x\n", "f.csv").unwrap_err().to_string();
        assert!(e.contains("f.csv: line 2, column 2"), "{e}");
        let e = parse_matrix("1,2\n3\n", "f.csv").unwrap_err().to_string();
        assert!(e.contains("line 2 has 1 columns, expected 2"), "{e}");
        let e = parse_matrix("1,NaN\n", "f.csv").unwrap_err().to_string();
        assert!(e.contains("line 1, column 2: non-finite"), "{e}");
        assert!(parse_matrix("\n\n", "f.csv").is_err());
    }
}
