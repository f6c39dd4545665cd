//! `helicon control …`: thin CLI over `helicon-lti` (DARE, dlqr, Kalman, c2d).
//!
//! Inputs are CSV files of plain numbers, one matrix row per line (comma-separated, or
//! whitespace-separated when a line has no comma). A header row whose cells are all
//! non-numeric is skipped, and so is a first column of row names (as in
//! `reference/thesis_A.csv`). Empty lines and lines starting with `#` are ignored.
//! A file ending in `.json` holds a nested row list (`[[1, 2], [3, 4]]`, or a bare number
//! for 1×1); `FILE.json#Key` takes the field `Key` of a JSON object, e.g. the `Phi` of a
//! previous `helicon control c2d` output.
//! Output is JSON on stdout with matrices as nested row lists; poles are `[re, im]` pairs.
//!
//! Every error names the file (and line/column, or JSON row/column) or the option it is
//! about; the library's typed errors are mapped back to the file the matrix came from.
//! Outputs are checked for NaN/∞ before anything is printed (JSON has no NaN: it would
//! print `null`). Output goes through a `std::io::Write` handle and write errors are
//! returned, so a closed pipe is an `io::Error` (BrokenPipe) the binary exits on quietly.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand};
use helicon_lti::LtiError;
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
    #[arg(long, alias = "ts")] // `--ts`: the old spelling
    dt: f64,
}

/// Runs a `helicon control` subcommand, printing JSON to stdout.
///
/// # Errors
/// Bad input (naming the file or option), a library error, or a failed write to stdout
/// (an `io::Error` in the chain, e.g. BrokenPipe when the reader went away).
pub fn run(args: ControlArgs) -> Result<()> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    run_to(args, &mut out)
}

/// As [`run`], writing to `out`.
///
/// # Errors
/// As [`run`].
pub fn run_to(args: ControlArgs, out: &mut dyn Write) -> Result<()> {
    let value = match args.command {
        ControlCommand::Dare(a) => dare(&a)?,
        ControlCommand::Dlqr(a) => dlqr(&a)?,
        ControlCommand::Kalman(a) => kalman(&a)?,
        ControlCommand::C2d(a) => c2d(&a)?,
    };
    let text = serde_json::to_string_pretty(&value)?;
    writeln!(out, "{text}")
        .and_then(|()| out.flush())
        .context("writing the result to stdout")?;
    Ok(())
}

/// A finite matrix as nested row lists; a NaN/∞ entry is an error (JSON would print null).
fn rows_json(what: &str, m: &DMatrix<f64>) -> Result<Value> {
    if let Some((k, v)) = m.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        let (i, j) = (k % m.nrows().max(1), k / m.nrows().max(1));
        bail!(
            "output {what} has a non-finite entry {v} at row {}, column {}; nothing printed",
            i + 1,
            j + 1
        );
    }
    Ok(Value::Array(
        (0..m.nrows())
            .map(|i| json!(m.row(i).iter().copied().collect::<Vec<f64>>()))
            .collect(),
    ))
}

/// A finite scalar; NaN/∞ is an error.
fn scalar_json(what: &str, v: f64) -> Result<Value> {
    if !v.is_finite() {
        bail!("output {what} is not finite ({v}); nothing printed");
    }
    Ok(json!(v))
}

/// Poles as `[re, im]` pairs, all finite.
fn poles_json(p: &[Complex<f64>]) -> Result<Value> {
    if let Some(z) = p.iter().find(|z| !(z.re.is_finite() && z.im.is_finite())) {
        bail!("output pole {z} is not finite; nothing printed");
    }
    Ok(Value::Array(
        p.iter().map(|z| json!([z.re, z.im])).collect(),
    ))
}

/// Is this cell a number (finite or not)?
fn numeric(cell: &str) -> bool {
    cell.trim().parse::<f64>().is_ok()
}

/// Where the entries of a loaded matrix came from, for error messages.
#[derive(Debug, Clone, PartialEq)]
enum Origin {
    /// CSV: the 1-based line of each matrix row, and the number of skipped leading columns
    /// (row names).
    Csv { lines: Vec<usize>, skip: usize },
    /// JSON: row/column of the nested list.
    Json,
}

/// A matrix read from a file, remembering the file and where each entry came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    /// The matrix.
    pub m: DMatrix<f64>,
    /// The file as the user named it (with `#Key` for a JSON field).
    pub name: String,
    origin: Origin,
}

impl Loaded {
    /// "line L, column C" (CSV) or "row R, column C" (JSON) of entry (i, j), 0-based in.
    fn at(&self, i: usize, j: usize) -> String {
        match &self.origin {
            Origin::Csv { lines, skip } => match lines.get(i) {
                Some(l) => format!("line {l}, column {}", j + 1 + skip),
                None => format!("row {}, column {}", i + 1, j + 1),
            },
            Origin::Json => format!("row {}, column {}", i + 1, j + 1),
        }
    }
}

/// Reads a matrix from a CSV file, a `.json` file, or a `FILE.json#Key` field; errors name
/// the file and the line and column (CSV) or row and column (JSON), 1-based.
pub fn read_matrix(path: &Path) -> Result<Loaded> {
    let shown = path.display().to_string();
    // FILE.json#Key, unless a file of that literal name exists.
    if !path.exists()
        && let Some((file, key)) = shown.rsplit_once('#')
        && file.to_ascii_lowercase().ends_with(".json")
    {
        let text = crate::files::read_text(Path::new(file))
            .with_context(|| format!("cannot read matrix file {file}"))?;
        let m = parse_json_matrix(&text, &shown, Some(key))?;
        return Ok(Loaded {
            m,
            name: shown,
            origin: Origin::Json,
        });
    }
    let text = crate::files::read_text(path)
        .with_context(|| format!("cannot read matrix file {shown}"))?;
    if shown.to_ascii_lowercase().ends_with(".json") {
        let m = parse_json_matrix(&text, &shown, None)?;
        return Ok(Loaded {
            m,
            name: shown,
            origin: Origin::Json,
        });
    }
    let (m, lines, skip) = parse_csv(&text, &shown)?;
    Ok(Loaded {
        m,
        name: shown,
        origin: Origin::Csv { lines, skip },
    })
}

/// Parses matrix CSV text; returns the matrix, the 1-based line of each row and the number
/// of skipped row-name columns.
fn parse_csv(text: &str, name: &str) -> Result<(DMatrix<f64>, Vec<usize>, usize)> {
    // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first cell.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
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
                anyhow!("{name}: line {line_no}, column {col}: cannot parse {cell:?} as a number")
            })?;
            if !v.is_finite() {
                bail!("{name}: line {line_no}, column {col}: non-finite value {cell:?}");
            }
            values.push(v);
        }
    }
    let rows: Vec<usize> = data.iter().map(|(l, _)| *l).collect();
    Ok((
        DMatrix::from_row_slice(data.len(), ncols, &values),
        rows,
        skip,
    ))
}

/// A short description of a JSON value for error messages.
fn json_kind(v: &Value) -> String {
    match v {
        Value::Null => "null".to_string(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("{s:?}"),
        Value::Array(_) => "a list".to_string(),
        Value::Object(_) => "an object".to_string(),
    }
}

/// Parses a JSON matrix: a nested row list, or a bare number (1×1); with `key`, the field
/// `key` of a JSON object. `name` is used in error messages.
pub fn parse_json_matrix(text: &str, name: &str, key: Option<&str>) -> Result<DMatrix<f64>> {
    let doc: Value = serde_json::from_str(text).map_err(|e| {
        anyhow!(
            "{name}: line {}, column {}: not valid JSON: {e}",
            e.line(),
            e.column()
        )
    })?;
    let v = match key {
        None => &doc,
        Some(k) => {
            let Value::Object(map) = &doc else {
                bail!(
                    "{name}: field {k:?} asked for, but the file is {} not an object",
                    json_kind(&doc)
                );
            };
            map.get(k).ok_or_else(|| {
                let fields: Vec<&str> = map.keys().map(String::as_str).collect();
                anyhow!("{name}: no field {k:?} (fields: {})", fields.join(", "))
            })?
        }
    };
    let number = |x: &Value, at: &str| -> Result<f64> {
        match x.as_f64() {
            Some(f) if f.is_finite() => Ok(f),
            _ => bail!(
                "{name}: {at}: expected a finite number, found {}",
                json_kind(x)
            ),
        }
    };
    let rows = match v {
        Value::Number(_) => return Ok(DMatrix::from_element(1, 1, number(v, "value")?)),
        Value::Array(rows) => rows,
        other => bail!(
            "{name}: expected a list of rows like [[1, 2], [3, 4]], found {}",
            json_kind(other)
        ),
    };
    if rows.is_empty() {
        bail!("{name}: no matrix rows (empty list)");
    }
    let mut ncols = None;
    let mut values = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        let Value::Array(cells) = row else {
            bail!(
                "{name}: row {}: expected a list of numbers, found {} (a matrix is a list of rows)",
                i + 1,
                json_kind(row)
            );
        };
        let n = *ncols.get_or_insert(cells.len());
        if cells.is_empty() {
            bail!("{name}: row {}: empty row", i + 1);
        }
        if cells.len() != n {
            bail!(
                "{name}: row {} has {} columns, expected {n} (as row 1); ragged rows are not a matrix",
                i + 1,
                cells.len()
            );
        }
        for (j, x) in cells.iter().enumerate() {
            values.push(number(x, &format!("row {}, column {}", i + 1, j + 1))?);
        }
    }
    Ok(DMatrix::from_row_slice(
        rows.len(),
        ncols.unwrap_or(0),
        &values,
    ))
}

fn expect_shape(l: &Loaded, rows: usize, cols: usize, what: &str) -> Result<()> {
    if l.m.nrows() != rows || l.m.ncols() != cols {
        bail!(
            "{}: {what} is {}x{}, expected {rows}x{cols}",
            l.name,
            l.m.nrows(),
            l.m.ncols()
        );
    }
    Ok(())
}

/// Where a library argument came from: a loaded file or a command-line option.
enum Src<'a> {
    File(&'a Loaded),
    Opt(&'static str),
}

/// Maps a library error back to the file or option of the argument it names. `names`
/// pairs the library's argument names ("A", "Qn", "alpha", …) with their sources.
fn explain(e: LtiError, doing: &str, names: &[(&str, Src<'_>)]) -> anyhow::Error {
    let source = |arg: &str| names.iter().find(|(n, _)| *n == arg).map(|(_, s)| s);
    let located = match (e.argument().and_then(source), &e) {
        (
            Some(Src::File(l)),
            LtiError::NonFinite { row, col, .. } | LtiError::TooLarge { row, col, .. },
        ) => Some(format!("{}: {}", l.name, l.at(*row, *col))),
        (Some(Src::File(l)), _) => Some(l.name.clone()),
        (Some(Src::Opt(o)), _) => Some((*o).to_string()),
        (None, LtiError::NotStabilizable { pair, .. } | LtiError::NotDetectable { pair, .. }) => {
            // Name the files of the matrices in the pair, e.g. "(A, C)" → A and C.
            let files: Vec<String> = pair
                .split(|c: char| !c.is_ascii_alphanumeric())
                .filter_map(|tok| match source(tok) {
                    Some(Src::File(l)) => Some(format!("{tok} from {}", l.name)),
                    _ => None,
                })
                .collect();
            (!files.is_empty()).then(|| files.join(", "))
        }
        _ => None,
    };
    let err = anyhow::Error::new(e);
    let err = match located {
        Some(loc) => err.context(loc),
        None => err,
    };
    err.context(doing.to_string())
}

struct DareData {
    a: Loaded,
    b: Loaded,
    q: Loaded,
    r: Loaded,
    n: Option<Loaded>,
}

impl DareData {
    /// Library argument names → files (for [`explain`]).
    fn names(&self) -> Vec<(&'static str, Src<'_>)> {
        let mut v = vec![
            ("A", Src::File(&self.a)),
            ("B", Src::File(&self.b)),
            ("Q", Src::File(&self.q)),
            ("R", Src::File(&self.r)),
            ("alpha", Src::Opt("--alpha")),
        ];
        if let Some(n) = &self.n {
            v.push(("N", Src::File(n)));
        }
        v
    }
}

fn load_dare(args: &DareArgs) -> Result<DareData> {
    let a = read_matrix(&args.a)?;
    let nx = a.m.nrows();
    expect_shape(&a, nx, nx, "A (must be square)")?;
    let b = read_matrix(&args.b)?;
    let m = b.m.ncols();
    expect_shape(&b, nx, m, "B (rows must match A)")?;
    let q = read_matrix(&args.q)?;
    expect_shape(&q, nx, nx, "Q")?;
    let r = read_matrix(&args.r)?;
    expect_shape(&r, m, m, "R")?;
    let n = match &args.n {
        Some(p) => {
            let n = read_matrix(p)?;
            expect_shape(&n, nx, m, "N")?;
            Some(n)
        }
        None => None,
    };
    Ok(DareData { a, b, q, r, n })
}

fn dare(args: &DareArgs) -> Result<Value> {
    let d = load_dare(args)?;
    let s = helicon_lti::dare(&d.a.m, &d.b.m, &d.q.m, &d.r.m, d.n.as_ref().map(|n| &n.m))
        .map_err(|e| explain(e, "solving the DARE", &d.names()))?;
    Ok(json!({
        "X": rows_json("X", &s.x)?,
        "residual": scalar_json("residual", s.residual)?,
        "iterations": s.iterations,
        "closed_loop_spectral_radius": scalar_json("closed_loop_spectral_radius", s.closed_loop_spectral_radius)?,
    }))
}

fn dlqr(args: &DlqrArgs) -> Result<Value> {
    let d = load_dare(&args.dare)?;
    let n = d.n.as_ref().map(|n| &n.m);
    let l = match args.alpha {
        Some(alpha) => helicon_lti::dlqr_pincer(&d.a.m, &d.b.m, &d.q.m, &d.r.m, n, alpha)
            .map_err(|e| explain(e, "pincer dlqr (DARE for αΦ, αΓ)", &d.names()))?,
        None => helicon_lti::dlqr(&d.a.m, &d.b.m, &d.q.m, &d.r.m, n)
            .map_err(|e| explain(e, "dlqr", &d.names()))?,
    };
    Ok(json!({
        "K": rows_json("K", &l.k)?,
        "S": rows_json("S", &l.s)?,
        "poles": poles_json(&l.poles)?,
        "residual": scalar_json("residual", l.residual)?,
    }))
}

fn kalman(args: &KalmanArgs) -> Result<Value> {
    let a = read_matrix(&args.a)?;
    let nx = a.m.nrows();
    expect_shape(&a, nx, nx, "A (must be square)")?;
    let c = read_matrix(&args.c)?;
    let p = c.m.nrows();
    expect_shape(&c, p, nx, "C (columns must match A)")?;
    let g = match &args.g {
        Some(path) => {
            let g = read_matrix(path)?;
            expect_shape(&g, nx, g.m.ncols(), "G (rows must match A)")?;
            Some(g)
        }
        None => None,
    };
    let w = g.as_ref().map_or(nx, |g| g.m.ncols());
    let qn = read_matrix(&args.qn)?;
    expect_shape(&qn, w, w, "Qn")?;
    let rn = read_matrix(&args.rn)?;
    expect_shape(&rn, p, p, "Rn")?;
    let mut names = vec![
        ("A", Src::File(&a)),
        ("C", Src::File(&c)),
        ("Qn", Src::File(&qn)),
        ("Rn", Src::File(&rn)),
    ];
    if let Some(g) = &g {
        names.push(("G", Src::File(g)));
    }
    let k = helicon_lti::dlqe(&a.m, g.as_ref().map(|g| &g.m), &c.m, &qn.m, &rn.m)
        .map_err(|e| explain(e, "steady-state Kalman gain", &names))?;
    Ok(json!({
        "L": rows_json("L", &k.l)?,
        "P": rows_json("P", &k.p)?,
        "M": rows_json("M", &k.m)?,
        "poles": poles_json(&k.poles)?,
        "residual": scalar_json("residual", k.residual)?,
    }))
}

fn c2d(args: &C2dArgs) -> Result<Value> {
    let a = read_matrix(&args.a)?;
    let nx = a.m.nrows();
    expect_shape(&a, nx, nx, "A (must be square)")?;
    let b = read_matrix(&args.b)?;
    expect_shape(&b, nx, b.m.ncols(), "B (rows must match A)")?;
    let names = [
        ("A", Src::File(&a)),
        ("B", Src::File(&b)),
        ("sample time Ts", Src::Opt("--dt")),
    ];
    let (phi, gamma) =
        helicon_lti::c2d(&a.m, &b.m, args.dt).map_err(|e| explain(e, "c2d", &names))?;
    Ok(json!({ "Phi": rows_json("Phi", &phi)?, "Gamma": rows_json("Gamma", &gamma)? }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_matrix(text: &str, name: &str) -> Result<DMatrix<f64>> {
        Ok(parse_csv(text, name)?.0)
    }

    #[test]
    fn csv_bom_and_line_numbers() {
        let (m, lines, skip) = parse_csv("\u{feff}row,a\n# c\nx,1\n\ny,2\n", "f").unwrap();
        assert_eq!(m, DMatrix::from_row_slice(2, 1, &[1.0, 2.0]));
        assert_eq!((lines, skip), (vec![3, 5], 1));
    }

    #[test]
    fn json_matrices_and_errors() {
        let m = parse_json_matrix("[[1, 2], [3, 4.5]]", "f.json", None).unwrap();
        assert_eq!(m, DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.5]));
        assert_eq!(
            parse_json_matrix("0.1", "f.json", None).unwrap(),
            DMatrix::from_element(1, 1, 0.1)
        );
        let m = parse_json_matrix(
            r#"{"Phi": [[1]], "Gamma": [[2]]}"#,
            "f.json#Gamma",
            Some("Gamma"),
        )
        .unwrap();
        assert_eq!(m[(0, 0)], 2.0);
        let err =
            |t: &str, k: Option<&str>| parse_json_matrix(t, "f.json", k).unwrap_err().to_string();
        assert!(
            err("[[1, 2], [3, null]]", None)
                .contains("f.json: row 2, column 2: expected a finite number, found null")
        );
        assert!(err("[[1, 2], [3]]", None).contains("row 2 has 1 columns, expected 2"));
        assert!(err("[[1, 2],\n [3, 4]", None).contains("f.json: line 2"));
        assert!(err("[[1e400]]", None).contains("f.json: line 1"));
        assert!(err("[1, 2]", None).contains("row 1: expected a list of numbers"));
        assert!(err("[]", None).contains("empty list"));
        assert!(err("[[]]", None).contains("row 1: empty row"));
        assert!(
            err(r#"{"Phi": [[1]]}"#, Some("Gamma")).contains("no field \"Gamma\" (fields: Phi)")
        );
        assert!(err("[[1]]", Some("Phi")).contains("not an object"));
        assert!(err(r#"{"a": 1}"#, None).contains("expected a list of rows"));
    }

    #[test]
    fn library_errors_point_at_the_file_line_and_column() {
        let l = Loaded {
            m: DMatrix::zeros(2, 2),
            name: "A.csv".to_string(),
            origin: Origin::Csv {
                lines: vec![2, 4],
                skip: 1,
            },
        };
        let e = LtiError::TooLarge {
            what: "A",
            row: 1,
            col: 0,
            value: 1e308,
            max: 1e100,
        };
        let msg = format!("{:#}", explain(e, "solving", &[("A", Src::File(&l))]));
        assert!(
            msg.starts_with("solving: A.csv: line 4, column 2: A has an entry"),
            "{msg}"
        );
        let e = LtiError::NotDetectable {
            pair: "(A, C)",
            re: 1.0,
            im: 0.0,
            ratio: 0.0,
        };
        let c = Loaded {
            name: "C.csv".to_string(),
            ..l.clone()
        };
        let msg = format!(
            "{:#}",
            explain(e, "kalman", &[("A", Src::File(&l)), ("C", Src::File(&c))])
        );
        assert!(
            msg.contains("A from A.csv, C from C.csv: (A, C) is not detectable"),
            "{msg}"
        );
        let e = LtiError::Parameter {
            what: "alpha",
            value: 1e300,
            allowed: "x".to_string(),
        };
        let msg = format!(
            "{:#}",
            explain(e, "dlqr", &[("alpha", Src::Opt("--alpha"))])
        );
        assert!(msg.contains("dlqr: --alpha: parameter alpha = "), "{msg}");
    }

    /// A writer whose reader went away.
    struct ClosedPipe;
    impl Write for ClosedPipe {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::ErrorKind::BrokenPipe.into())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Err(std::io::ErrorKind::BrokenPipe.into())
        }
    }

    #[test]
    fn closed_pipe_is_an_io_error_not_a_panic() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(subcommand)]
            c: Cmd,
        }
        #[derive(clap::Subcommand)]
        enum Cmd {
            Control(ControlArgs),
        }
        let dir = std::env::temp_dir().join(format!("helicon_control_pipe_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = dir.join("A.csv");
        let b = dir.join("B.csv");
        std::fs::write(&a, "0,1\n0,0\n").unwrap();
        std::fs::write(&b, "0\n1\n").unwrap();
        let cli = Cli::parse_from([
            "x",
            "control",
            "c2d",
            "--a",
            a.to_str().unwrap(),
            "--b",
            b.to_str().unwrap(),
            "--ts",
            "0.1",
        ]);
        let Cmd::Control(args) = cli.c;
        let e = run_to(args, &mut ClosedPipe).unwrap_err();
        assert!(
            e.chain().any(|c| c
                .downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)),
            "{e:#}"
        );
    }

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
