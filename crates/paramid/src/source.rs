//! Where a log's columns come from: the simulator's `log.csv` (or any CSV
//! with `t_s` and the columns named), or the flight computer's ULog
//! (`flight.ulg`), read onto the control grid by
//! [`helicon_ulog::columns`] under the same names. A file is taken as ULog
//! when it starts with the ULog magic bytes, whatever its name.

use crate::error::Result;
use helicon_sim::log_csv::{LogReader, read_log_csv_with};
use helicon_ulog::columns::{available_columns, read_ulog_columns};
use std::io::Read;
use std::path::Path;

/// The ULog file magic (PX4 "ULog File Format": `ULog` then 0x01 0x12 0x35).
const ULOG_MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];

/// Whether the file at `path` is a ULog file (its first bytes). A file that
/// cannot be opened is not: the CSV reader then names the problem.
pub fn is_ulog(path: &Path) -> bool {
    let mut head = [0u8; 7];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok_and(|()| head == ULOG_MAGIC)
}

/// The columns of a log, by name.
#[derive(Debug, Clone, PartialEq)]
pub struct LogColumns {
    /// Names, `t_s` first.
    pub names: Vec<String>,
    /// Values, in the order of `names`.
    pub columns: Vec<Vec<f64>>,
    /// What a user should know about the reading (a ULog's filled samples,
    /// a cut); empty for a CSV.
    pub notes: Vec<String>,
}

impl LogColumns {
    /// The column `name` (present: the readers refuse a missing one).
    pub fn column(&self, name: &str) -> &[f64] {
        self.names
            .iter()
            .position(|n| n == name)
            .map_or(&[], |j| self.columns[j].as_slice())
    }
}

/// Read `t_s` and the columns `names` of the log at `path`: a ULog onto the
/// control grid of period `period_s`, a CSV as it is.
pub fn read_log(path: &Path, names: &[&str], period_s: f64) -> Result<LogColumns> {
    if is_ulog(path) {
        let u = read_ulog_columns(path, names, Some(period_s))?;
        let notes = u.notes();
        return Ok(LogColumns {
            names: u.names,
            columns: u.columns,
            notes,
        });
    }
    let table = read_log_csv_with(path, names)?;
    let mut out = LogColumns {
        names: vec!["t_s".into()],
        columns: vec![table.time_s().to_vec()],
        notes: Vec::new(),
    };
    for n in names.iter().filter(|n| **n != "t_s") {
        out.names.push((*n).to_string());
        out.columns.push(table.column(n)?.to_vec());
    }
    Ok(out)
}

/// The column names the log at `path` offers.
pub fn log_names(path: &Path) -> Result<Vec<String>> {
    if is_ulog(path) {
        return Ok(available_columns(path)?
            .into_iter()
            .map(String::from)
            .collect());
    }
    Ok(LogReader::open(path, &[])?.names().to_vec())
}
