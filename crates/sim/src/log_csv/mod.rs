//! `log.csv`, the closed-loop time series: one column table ([`LOG_SCHEMA`])
//! from which the header and every row are generated, a streaming writer
//! ([`LogWriter`]) and a typed reader ([`read_log_csv`], [`LogReader`]).
//!
//! # Format (version [`LOG_FORMAT_VERSION`])
//!
//! - UTF-8, one header line of column names, then one line per sample, cells
//!   separated by `,`, every line (the last one too) ending with `\n`;
//! - every cell is a finite decimal number: `[+-]digits[.digits][(e|E)[+-]digits]`
//!   (no `inf`, `NaN`, empty cells, `0.` or `.5`);
//! - `t_s` (time, s) is the first column and strictly increasing;
//! - the writer prints the shortest text that reads back to the same `f64`
//!   (plain notation for 1e-4 ≤ |v| < 1e9, exponent notation otherwise), so a
//!   log is an exact record of the run.
//!
//! The columns of a helicon run are [`LOG_SCHEMA`] (83, SI units). The reader
//! matches columns by name: a file with extra columns, or another order, reads
//! as well, so tools can require only the columns they use
//! ([`read_log_csv_with`]).
//!
//! Reading checks what it parses and names the file, the line (1-based, the
//! header is line 1) and the column of a bad cell; see [`LogCsvError`].

use crate::closed_loop::LogRow;
use helicon_core::frames::wrap_pi;
use helicon_model::state::REDUCED_OFFSET;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

mod writer;
pub use writer::{
    LOG_RING_ROWS, LogSizeEstimate, LogWriter, RowText, estimate_log_size, header_bytes, row_bytes,
    strided_rows, write_log,
};

/// Version of the `log.csv` layout: raised when a column of [`LOG_SCHEMA`]
/// is renamed, removed, reordered or changes unit or meaning.
pub const LOG_FORMAT_VERSION: u32 = 3;

/// The nine measured states of the thesis (15.2), in order.
pub const MEASURED_NAMES: [&str; 9] = ["phi", "theta", "psi", "u", "v", "w", "p", "q", "r"];

/// Where a column's value comes from in a [`LogRow`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogSource {
    /// `t_s`.
    Time,
    /// True state `x[i]` (of the 30).
    State(usize),
    /// Servo command `u[i]` sent to the plant (after saturation).
    Input(usize),
    /// Reference `[vn, ve, vd, psi][i]`.
    Reference(usize),
    /// True output `[vn, ve, vd, psi][i]`.
    Output(usize),
    /// Estimator value of measured state `i` (absolute).
    Estimate(usize),
    /// Truth − estimate of measured state `i` (yaw wrapped to (−π, π]).
    EstimateError(usize),
    /// Measurement given to the controller, measured state `i`.
    Measured(usize),
    /// Air-mass velocity NED, component `i`.
    Wind(usize),
    /// Inflow ratio `[main, tail][i]`.
    Inflow(usize),
    /// `[main-rotor thrust −hFz, tail-rotor side force tFy][i]`.
    RotorForce(usize),
    /// The flight software's IMU health `[vibration RMS, gravity residual,
    /// flags][i]` (zeros without sensor models).
    ImuHealth(usize),
    /// The servo excitation `[S_col, S_lat, S_lon, S_tr][i]` added to the
    /// law's command (`[[excitation]]`; zeros without).
    Excitation(usize),
}

impl LogSource {
    /// The value of this column in a row.
    #[inline]
    pub fn value(self, r: &LogRow) -> f64 {
        match self {
            LogSource::Time => r.t_s,
            LogSource::State(i) => r.x[i],
            LogSource::Input(i) => r.u[i],
            LogSource::Reference(i) => r.reference[i],
            LogSource::Output(i) => r.output[i],
            LogSource::Estimate(i) => r.estimate9[i],
            LogSource::EstimateError(i) => estimator_error(r, i),
            LogSource::Measured(i) => r.measured9[i],
            LogSource::Wind(i) => r.wind_ned[i],
            LogSource::Inflow(i) => r.lambda[i],
            LogSource::RotorForce(i) => r.thrust[i],
            LogSource::ImuHealth(i) => r.imu_health[i],
            LogSource::Excitation(i) => r.excitation[i],
        }
    }
}

/// Truth − estimate of measured state `i` of a row (yaw wrapped to (−π, π]).
pub fn estimator_error(r: &LogRow, i: usize) -> f64 {
    let d = r.x[i + REDUCED_OFFSET] - r.estimate9[i];
    if i == 2 { wrap_pi(d) } else { d }
}

/// One column of `log.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LogColumn {
    /// Header name.
    pub name: &'static str,
    /// SI unit (`1` for dimensionless).
    pub unit: &'static str,
    /// Where the value comes from.
    pub source: LogSource,
}

impl LogColumn {
    /// The value of this column in a row.
    #[inline]
    pub fn value(&self, r: &LogRow) -> f64 {
        self.source.value(r)
    }
}

const fn col(name: &'static str, unit: &'static str, source: LogSource) -> LogColumn {
    LogColumn { name, unit, source }
}

use LogSource as S;

/// Number of columns of `log.csv`.
pub const LOG_COLUMNS: usize = 83;

/// The columns of `log.csv`, in order: the one table the header, every row,
/// the reader's units and the documentation come from.
pub static LOG_SCHEMA: [LogColumn; LOG_COLUMNS] = [
    col("t_s", "s", S::Time),
    // the 30 true states (helicon_model::state::STATE_NAMES)
    col("x", "m", S::State(0)),
    col("y", "m", S::State(1)),
    col("z", "m", S::State(2)),
    col("phi", "rad", S::State(3)),
    col("theta", "rad", S::State(4)),
    col("psi", "rad", S::State(5)),
    col("u", "m/s", S::State(6)),
    col("v", "m/s", S::State(7)),
    col("w", "m/s", S::State(8)),
    col("p", "rad/s", S::State(9)),
    col("q", "rad/s", S::State(10)),
    col("r", "rad/s", S::State(11)),
    col("a0", "rad", S::State(12)),
    col("a1", "rad", S::State(13)),
    col("b1", "rad", S::State(14)),
    col("a0_dot", "rad/s", S::State(15)),
    col("a1_dot", "rad/s", S::State(16)),
    col("b1_dot", "rad/s", S::State(17)),
    col("a1sb", "rad", S::State(18)),
    col("b1sb", "rad", S::State(19)),
    col("a1sb_dot", "rad/s", S::State(20)),
    col("b1sb_dot", "rad/s", S::State(21)),
    col("theta0", "rad", S::State(22)),
    col("A1", "rad", S::State(23)),
    col("B1", "rad", S::State(24)),
    col("theta_tr", "rad", S::State(25)),
    col("theta0_dot", "rad/s", S::State(26)),
    col("A1_dot", "rad/s", S::State(27)),
    col("B1_dot", "rad/s", S::State(28)),
    col("theta_tr_dot", "rad/s", S::State(29)),
    // servo commands after saturation (INPUT_NAMES)
    col("S_col", "1", S::Input(0)),
    col("S_lat", "1", S::Input(1)),
    col("S_lon", "1", S::Input(2)),
    col("S_tr", "1", S::Input(3)),
    // references
    col("ref_vn", "m/s", S::Reference(0)),
    col("ref_ve", "m/s", S::Reference(1)),
    col("ref_vd", "m/s", S::Reference(2)),
    col("ref_psi", "rad", S::Reference(3)),
    // true NED velocity
    col("vn", "m/s", S::Output(0)),
    col("ve", "m/s", S::Output(1)),
    col("vd", "m/s", S::Output(2)),
    // estimator values of the nine measured states (15.2)
    col("est_phi", "rad", S::Estimate(0)),
    col("est_theta", "rad", S::Estimate(1)),
    col("est_psi", "rad", S::Estimate(2)),
    col("est_u", "m/s", S::Estimate(3)),
    col("est_v", "m/s", S::Estimate(4)),
    col("est_w", "m/s", S::Estimate(5)),
    col("est_p", "rad/s", S::Estimate(6)),
    col("est_q", "rad/s", S::Estimate(7)),
    col("est_r", "rad/s", S::Estimate(8)),
    // truth − estimate
    col("err_phi", "rad", S::EstimateError(0)),
    col("err_theta", "rad", S::EstimateError(1)),
    col("err_psi", "rad", S::EstimateError(2)),
    col("err_u", "m/s", S::EstimateError(3)),
    col("err_v", "m/s", S::EstimateError(4)),
    col("err_w", "m/s", S::EstimateError(5)),
    col("err_p", "rad/s", S::EstimateError(6)),
    col("err_q", "rad/s", S::EstimateError(7)),
    col("err_r", "rad/s", S::EstimateError(8)),
    // measurements given to the controller
    col("meas_phi", "rad", S::Measured(0)),
    col("meas_theta", "rad", S::Measured(1)),
    col("meas_psi", "rad", S::Measured(2)),
    col("meas_u", "m/s", S::Measured(3)),
    col("meas_v", "m/s", S::Measured(4)),
    col("meas_w", "m/s", S::Measured(5)),
    col("meas_p", "rad/s", S::Measured(6)),
    col("meas_q", "rad/s", S::Measured(7)),
    col("meas_r", "rad/s", S::Measured(8)),
    // wind, inflow, rotor forces
    col("wind_n", "m/s", S::Wind(0)),
    col("wind_e", "m/s", S::Wind(1)),
    col("wind_d", "m/s", S::Wind(2)),
    col("lambda_mr", "1", S::Inflow(0)),
    col("lambda_tr", "1", S::Inflow(1)),
    col("thrust_mr_n", "N", S::RotorForce(0)),
    col("force_tr_y_n", "N", S::RotorForce(1)),
    // the flight software's IMU health (helicon_core::imu_health)
    col("imu_vib_rms_m_s2", "m/s^2", S::ImuHealth(0)),
    col("imu_gravity_residual_m_s2", "m/s^2", S::ImuHealth(1)),
    col("imu_health_flags", "1", S::ImuHealth(2)),
    // the servo excitation added before saturation ([[excitation]])
    col("exc_col", "1", S::Excitation(0)),
    col("exc_lat", "1", S::Excitation(1)),
    col("exc_lon", "1", S::Excitation(2)),
    col("exc_tr", "1", S::Excitation(3)),
];

/// The `log.csv` header, in column order.
pub fn log_header() -> Vec<String> {
    LOG_SCHEMA.iter().map(|c| c.name.to_string()).collect()
}

/// The schema column of this name.
pub fn log_column(name: &str) -> Option<&'static LogColumn> {
    LOG_SCHEMA.iter().find(|c| c.name == name)
}

/// The unit of a `log.csv` column of the schema (`None` for other names).
pub fn log_unit(name: &str) -> Option<&'static str> {
    log_column(name).map(|c| c.unit)
}

/// What is wrong with one cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellProblem {
    /// Nothing between the commas.
    Empty,
    /// A number cut short: `0.`, `1e`, `1e-`, `-`.
    Truncated,
    /// `inf`, `NaN` or a number too large for an `f64`.
    NonFinite,
    /// Anything else that is not a decimal number.
    NotANumber,
}

impl std::fmt::Display for CellProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CellProblem::Empty => "empty cell",
            CellProblem::Truncated => "truncated number",
            CellProblem::NonFinite => "non-finite number",
            CellProblem::NotANumber => "not a number",
        })
    }
}

/// Errors writing or reading `log.csv`. Every variant names the file; cell
/// errors also the line (1-based, the header is line 1) and the column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LogCsvError {
    /// Opening, reading or writing failed.
    #[error("{path}: {message}")]
    Io {
        /// File.
        path: String,
        /// Message.
        message: String,
    },
    /// The file has no header line.
    #[error("{path}: empty file (no header line)")]
    Empty {
        /// File.
        path: String,
    },
    /// A line is not UTF-8.
    #[error("{path}:{line}: not UTF-8 text")]
    NotUtf8 {
        /// File.
        path: String,
        /// Line.
        line: usize,
    },
    /// A header name is empty.
    #[error("{path}:1: column {column} has an empty name")]
    EmptyName {
        /// File.
        path: String,
        /// Column number (1-based).
        column: usize,
    },
    /// The same name twice in the header.
    #[error("{path}:1: column `{name}` appears twice (columns {first} and {second})")]
    DuplicateColumn {
        /// File.
        path: String,
        /// Name.
        name: String,
        /// First occurrence (1-based).
        first: usize,
        /// Second occurrence (1-based).
        second: usize,
    },
    /// Required columns are not in the header.
    #[error("{path}: missing column(s) {}", names.join(", "))]
    MissingColumns {
        /// File.
        path: String,
        /// The names missing.
        names: Vec<String>,
    },
    /// An empty line.
    #[error("{path}:{line}: empty line")]
    EmptyLine {
        /// File.
        path: String,
        /// Line.
        line: usize,
    },
    /// The last line does not end with a newline: the file was cut off.
    #[error("{path}:{line}: the last line has no end of line: the file is truncated")]
    Truncated {
        /// File.
        path: String,
        /// Line.
        line: usize,
    },
    /// A line with more or fewer cells than the header.
    #[error("{path}:{line}: {found} cells, the header has {expected}")]
    RowLength {
        /// File.
        path: String,
        /// Line.
        line: usize,
        /// Cells found.
        found: usize,
        /// Columns in the header.
        expected: usize,
    },
    /// A cell that is not a finite decimal number.
    #[error("{path}:{line}: column {column} (`{name}`): {problem} `{text}`")]
    BadCell {
        /// File.
        path: String,
        /// Line.
        line: usize,
        /// Column number (1-based).
        column: usize,
        /// Column name.
        name: String,
        /// The cell as written (at most 40 characters).
        text: String,
        /// What is wrong.
        problem: CellProblem,
    },
    /// `t_s` does not increase.
    #[error("{path}:{line}: t_s = {t_s} s does not increase (previous {previous_s} s)")]
    TimeNotIncreasing {
        /// File.
        path: String,
        /// Line.
        line: usize,
        /// Time on this line (s).
        t_s: f64,
        /// Time on the previous line (s).
        previous_s: f64,
    },
    /// Writing: a non-finite value (the file would not read back).
    #[error(
        "{path}:{line}: column `{name}` is {value} at t = {t_s} s: a log holds finite numbers only"
    )]
    NonFiniteValue {
        /// File.
        path: String,
        /// Line it would have been written on.
        line: usize,
        /// Column name.
        name: String,
        /// The value.
        value: f64,
        /// Time of the row (s).
        t_s: f64,
    },
}

fn io_err(path: &str, e: impl std::fmt::Display) -> LogCsvError {
    LogCsvError::Io {
        path: path.to_string(),
        message: e.to_string(),
    }
}

/// Parse one cell strictly: `[+-]digits[.digits][(e|E)[+-]digits]`, finite.
pub fn parse_cell(text: &str) -> Result<f64, CellProblem> {
    let b = text.as_bytes();
    if b.is_empty() {
        return Err(CellProblem::Empty);
    }
    let digits = |mut i: usize| {
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut i = usize::from(b[0] == b'+' || b[0] == b'-');
    let j = digits(i);
    if j == i {
        let rest = text[i..].to_ascii_lowercase();
        return Err(if i == b.len() {
            CellProblem::Truncated
        } else if matches!(rest.as_str(), "inf" | "infinity" | "nan") {
            CellProblem::NonFinite
        } else {
            CellProblem::NotANumber
        });
    }
    i = j;
    if i < b.len() && b[i] == b'.' {
        let j = digits(i + 1);
        if j == i + 1 {
            return Err(if j == b.len() {
                CellProblem::Truncated
            } else {
                CellProblem::NotANumber
            });
        }
        i = j;
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        i += 1;
        if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
            i += 1;
        }
        let j = digits(i);
        if j == i {
            return Err(if j == b.len() {
                CellProblem::Truncated
            } else {
                CellProblem::NotANumber
            });
        }
        i = j;
    }
    if i != b.len() {
        return Err(CellProblem::NotANumber);
    }
    let v: f64 = text.parse().map_err(|_| CellProblem::NotANumber)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CellProblem::NonFinite)
    }
}

/// Streaming `log.csv` reader: the header is read and checked on open, then
/// [`LogReader::next_row`] parses the selected columns of one line at a time
/// (memory independent of the file length). Every line's cell count and the
/// `t_s` column are checked; only the selected cells are parsed.
#[derive(Debug)]
pub struct LogReader<R: BufRead = BufReader<LogFile>> {
    label: String,
    input: R,
    names: Vec<String>,
    /// For each header column: its slot in the caller's row, if selected.
    slot: Vec<Option<usize>>,
    row: Vec<f64>,
    t_index: usize,
    line: usize,
    buf: Vec<u8>,
    last_t: f64,
}

/// The file a [`LogReader`] opens: regular files only (a FIFO or a device
/// would never end), lines and size bounded (`helicon_config`'s limits).
pub type LogFile = helicon_config::LineBounded<helicon_config::Bounded<File>>;

impl LogReader<BufReader<LogFile>> {
    /// Open `path`, check its header and select the columns `select` (in
    /// that order; each must be in the header, `t_s` always must).
    pub fn open(path: &Path, select: &[&str]) -> Result<Self, LogCsvError> {
        let label = path.display().to_string();
        let file = helicon_config::open_lines_bounded(
            path,
            helicon_config::MAX_DATA_BYTES,
            helicon_config::MAX_LINE_BYTES,
        )
        .map_err(|e| io_err(&label, e.into_io()))?;
        Self::from_reader(BufReader::with_capacity(1 << 16, file), &label, select)
    }
}

impl<R: BufRead> LogReader<R> {
    /// As [`LogReader::open`] from any buffered reader; `label` names it in errors.
    pub fn from_reader(input: R, label: &str, select: &[&str]) -> Result<Self, LogCsvError> {
        let mut r = Self {
            label: label.to_string(),
            input,
            names: Vec::new(),
            slot: Vec::new(),
            row: Vec::new(),
            t_index: 0,
            line: 0,
            buf: Vec::new(),
            last_t: f64::NEG_INFINITY,
        };
        if !r.read_line()? {
            return Err(LogCsvError::Empty { path: r.label });
        }
        let label = r.label.clone();
        let header = r.line_text()?.to_string();
        let header = header.strip_prefix('\u{feff}').unwrap_or(&header);
        let mut names: Vec<String> = Vec::new();
        for (j, raw) in header.split(',').enumerate() {
            let name = raw.trim();
            if name.is_empty() {
                return Err(LogCsvError::EmptyName {
                    path: label,
                    column: j + 1,
                });
            }
            if let Some(first) = names.iter().position(|n| n == name) {
                return Err(LogCsvError::DuplicateColumn {
                    path: label,
                    name: name.to_string(),
                    first: first + 1,
                    second: j + 1,
                });
            }
            names.push(name.to_string());
        }
        r.t_index = names.iter().position(|n| n == "t_s").unwrap_or(0);
        r.names = names;
        r.select(select)?;
        Ok(r)
    }

    /// Change the selection: the columns `select` (in that order; each must
    /// be in the header, and `t_s` always must).
    pub fn select(&mut self, select: &[&str]) -> Result<(), LogCsvError> {
        let mut missing: Vec<String> = Vec::new();
        for s in std::iter::once(&"t_s").chain(select) {
            if !self.names.iter().any(|n| n == s) && !missing.iter().any(|m| m == s) {
                missing.push((*s).to_string());
            }
        }
        if !missing.is_empty() {
            return Err(LogCsvError::MissingColumns {
                path: self.label.clone(),
                names: missing,
            });
        }
        self.slot = self
            .names
            .iter()
            .map(|n| select.iter().position(|s| s == n))
            .collect();
        self.row = vec![0.0; select.len()];
        Ok(())
    }

    /// The file's column names, in file order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The last line read (1-based; the header is line 1).
    pub fn line(&self) -> usize {
        self.line
    }

    /// Read the next line into `buf`; false at the end of the file.
    fn read_line(&mut self) -> Result<bool, LogCsvError> {
        self.buf.clear();
        let n = self
            .input
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| io_err(&self.label, e))?;
        if n == 0 {
            return Ok(false);
        }
        self.line += 1;
        if self.buf.last() != Some(&b'\n') {
            return Err(LogCsvError::Truncated {
                path: self.label.clone(),
                line: self.line,
            });
        }
        self.buf.pop();
        if self.buf.last() == Some(&b'\r') {
            self.buf.pop();
        }
        Ok(true)
    }

    fn line_text(&self) -> Result<&str, LogCsvError> {
        std::str::from_utf8(&self.buf).map_err(|_| LogCsvError::NotUtf8 {
            path: self.label.clone(),
            line: self.line,
        })
    }

    /// Parse the next row: its selected cells, in the order selected, or
    /// `None` at the end of the file.
    pub fn next_row(&mut self) -> Result<Option<&[f64]>, LogCsvError> {
        if !self.read_line()? {
            return Ok(None);
        }
        if self.buf.is_empty() {
            return Err(LogCsvError::EmptyLine {
                path: self.label.clone(),
                line: self.line,
            });
        }
        let text = std::str::from_utf8(&self.buf).map_err(|_| LogCsvError::NotUtf8 {
            path: self.label.clone(),
            line: self.line,
        })?;
        let ncols = self.names.len();
        let mut found = 0;
        let mut t = f64::NAN;
        for (j, cell) in text.split(',').enumerate() {
            found = j + 1;
            if j >= ncols {
                continue;
            }
            let slot = self.slot[j];
            if slot.is_none() && j != self.t_index {
                continue;
            }
            let cell = cell.trim();
            let v = parse_cell(cell).map_err(|problem| LogCsvError::BadCell {
                path: self.label.clone(),
                line: self.line,
                column: j + 1,
                name: self.names[j].clone(),
                text: cell.chars().take(40).collect(),
                problem,
            })?;
            if let Some(s) = slot {
                self.row[s] = v;
            }
            if j == self.t_index {
                t = v;
            }
        }
        if found != ncols {
            return Err(LogCsvError::RowLength {
                path: self.label.clone(),
                line: self.line,
                found,
                expected: ncols,
            });
        }
        if t <= self.last_t {
            return Err(LogCsvError::TimeNotIncreasing {
                path: self.label.clone(),
                line: self.line,
                t_s: t,
                previous_s: self.last_t,
            });
        }
        self.last_t = t;
        Ok(Some(&self.row))
    }
}

/// A whole `log.csv` in memory, column by column.
#[derive(Debug, Clone, PartialEq)]
pub struct LogTable {
    /// The file read.
    pub path: PathBuf,
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
}

impl LogTable {
    /// Column names, in file order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of data rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// The column `name`, if present.
    pub fn get(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|j| self.columns[j].as_slice())
    }

    /// The column `name`; its absence is an error naming the file.
    pub fn column(&self, name: &str) -> Result<&[f64], LogCsvError> {
        self.get(name).ok_or_else(|| LogCsvError::MissingColumns {
            path: self.path.display().to_string(),
            names: vec![name.to_string()],
        })
    }

    /// The time vector `t_s` (s), strictly increasing.
    pub fn time_s(&self) -> &[f64] {
        self.get("t_s").unwrap_or(&[])
    }

    /// The unit of a column: the schema's for a helicon column, `None` for
    /// a name the schema does not know.
    pub fn unit(&self, name: &str) -> Option<&'static str> {
        log_unit(name)
    }
}

/// Read a helicon `log.csv`: every column of [`LOG_SCHEMA`] must be there
/// (extra columns are kept).
pub fn read_log_csv(path: &Path) -> Result<LogTable, LogCsvError> {
    let all: Vec<&str> = LOG_SCHEMA.iter().map(|c| c.name).collect();
    read_log_csv_with(path, &all)
}

/// Read a `log.csv` with at least the columns `required` (and `t_s`); every
/// column of the file is read and checked.
pub fn read_log_csv_with(path: &Path, required: &[&str]) -> Result<LogTable, LogCsvError> {
    // the required columns first (their absence is the clearer error), then all
    let mut reader = LogReader::open(path, required)?;
    let names = reader.names().to_vec();
    let all: Vec<&str> = names.iter().map(String::as_str).collect();
    reader.select(&all)?;
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); all.len()];
    while let Some(row) = reader.next_row()? {
        for (c, v) in columns.iter_mut().zip(row) {
            c.push(*v);
        }
    }
    Ok(LogTable {
        path: path.to_path_buf(),
        names,
        columns,
    })
}
