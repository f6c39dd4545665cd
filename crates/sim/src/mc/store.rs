//! The output folder: manifest, `runs.csv` / `traces.csv` (and their partial
//! files), written and read back line by line (nothing holds a whole file in
//! memory), and [`merge`].

use super::report::finish;
use super::{
    FORMAT_VERSION, METRIC_NAMES, McError, McReport, RunOutcome, RunRecord, RunTermination,
    TracePoint,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Seek, SeekFrom, Write as _};
use std::path::{Path, PathBuf};

pub(super) const MANIFEST: &str = "manifest.json";
pub(super) const RUNS: &str = "runs.csv";
pub(super) const RUNS_PARTIAL: &str = "runs.partial.csv";
pub(super) const TRACES: &str = "traces.csv";
pub(super) const TRACES_PARTIAL: &str = "traces.partial.csv";
pub(super) const CAMPAIGN: &str = "campaign.toml";
pub(super) const SCENARIO: &str = "scenario.toml";
pub(super) const PARAMS: &str = "params.toml";
const TRACE_HEADER: &str = "index,t_s,vn,ve,vd,psi";

/// Folders written before the version was recorded.
fn version_1() -> u32 {
    1
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct Manifest {
    #[serde(default = "version_1")]
    pub(super) format_version: u32,
    pub(super) name: String,
    pub(super) hash: String,
    pub(super) runs: usize,
    pub(super) seed: u64,
    pub(super) shard: Option<String>,
    pub(super) dispersed: Vec<String>,
    #[serde(default)]
    pub(super) overrides: Vec<String>,
}

/// An I/O error on `path` while doing `action`.
pub(super) fn io_err(path: &Path, action: &'static str, source: std::io::Error) -> McError {
    McError::Config(crate::scenario::ScenarioError::Io {
        file: path.display().to_string(),
        action,
        source,
    })
}

pub(super) fn write_file(path: &Path, text: &str) -> Result<(), McError> {
    std::fs::write(path, text).map_err(|e| io_err(path, "write", e))
}

/// Write `value` as pretty JSON; a serialisation failure is an error (never
/// an empty file).
pub(super) fn write_json(path: &Path, value: &impl Serialize) -> Result<(), McError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| McError::Serialize {
        file: path.display().to_string(),
        message: e.to_string(),
    })?;
    write_file(path, &text)
}

/// Header of `runs.csv` for the dispersed parameter keys.
pub fn csv_header(dispersed: &[String]) -> Vec<String> {
    let mut h: Vec<String> = vec!["index".into(), "wind_seed".into(), "sensor_seed".into()];
    h.extend(dispersed.iter().cloned());
    h.extend(["outcome", "termination", "reason", "t_end_s"].map(String::from));
    h.extend(METRIC_NAMES.iter().map(|s| (*s).to_string()));
    h
}

pub(super) fn record_fields(r: &RunRecord) -> Vec<String> {
    let mut f = vec![
        r.index.to_string(),
        r.wind_seed.to_string(),
        r.sensor_seed.to_string(),
    ];
    // `{}` on f64 is the shortest text that reads back to the same bits
    f.extend(r.values.iter().map(|v| v.to_string()));
    f.push(r.outcome().as_str().to_string());
    f.push(r.termination.as_str().to_string());
    f.push(r.reason.clone());
    f.push(r.t_end_s.to_string());
    f.extend(
        r.metrics
            .iter()
            .map(|m| m.map(|v| v.to_string()).unwrap_or_default()),
    );
    f
}

pub(super) fn csv_line(fields: &[String]) -> Result<String, McError> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    let ser = |e: String| McError::Serialize {
        file: "<runs.csv row>".into(),
        message: e,
    };
    w.write_record(fields).map_err(|e| ser(e.to_string()))?;
    let bytes = w.into_inner().map_err(|e| ser(e.to_string()))?;
    String::from_utf8(bytes).map_err(|e| ser(e.to_string()))
}

pub(super) fn trace_lines(index: usize, trace: &[TracePoint]) -> String {
    let mut s = String::with_capacity(trace.len() * 64);
    for p in trace {
        let _ = writeln!(
            s,
            "{index},{},{},{},{},{}",
            p.t_s, p.output[0], p.output[1], p.output[2], p.output[3]
        );
    }
    s
}

fn create(path: &Path) -> Result<BufWriter<File>, McError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| io_err(path, "write", e))
}

fn finish_file(path: &Path, mut w: BufWriter<File>) -> Result<(), McError> {
    w.flush().map_err(|e| io_err(path, "write", e))?;
    let f = w
        .into_inner()
        .map_err(|e| io_err(path, "write", e.into_error()))?;
    f.sync_data().map_err(|e| io_err(path, "write", e))
}

/// Write a `runs.csv` (header and one row per record, by index), streamed.
pub(super) fn write_runs_csv<'a>(
    path: &Path,
    dispersed: &[String],
    records: impl IntoIterator<Item = &'a RunRecord>,
) -> Result<(), McError> {
    let mut w = create(path)?;
    w.write_all(csv_line(&csv_header(dispersed))?.as_bytes())
        .map_err(|e| io_err(path, "write", e))?;
    for r in records {
        w.write_all(csv_line(&record_fields(r))?.as_bytes())
            .map_err(|e| io_err(path, "write", e))?;
    }
    finish_file(path, w)
}

/// Write a `traces.csv`, streamed.
pub(super) fn write_traces_csv(
    path: &Path,
    traces: &BTreeMap<usize, Vec<TracePoint>>,
) -> Result<(), McError> {
    let mut w = create(path)?;
    writeln!(w, "{TRACE_HEADER}").map_err(|e| io_err(path, "write", e))?;
    for (k, v) in traces {
        w.write_all(trace_lines(*k, v).as_bytes())
            .map_err(|e| io_err(path, "write", e))?;
    }
    finish_file(path, w)
}

/// Open a results file for reading: `None` when it does not exist; with it,
/// whether it ends with a newline (every line is written whole, so a last
/// line without one was torn by an interrupted write and is ignored).
fn open_results(path: &Path) -> Result<Option<(BufReader<File>, bool)>, McError> {
    let mut f = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io_err(path, "read", e)),
    };
    let rd = |e| io_err(path, "read", e);
    let len = f.metadata().map_err(rd)?.len();
    let complete = if len == 0 {
        true
    } else {
        f.seek(SeekFrom::End(-1)).map_err(rd)?;
        let mut last = [0u8; 1];
        f.read_exact(&mut last).map_err(rd)?;
        f.seek(SeekFrom::Start(0)).map_err(rd)?;
        last[0] == b'\n'
    };
    Ok(Some((BufReader::new(f), complete)))
}

/// Check a `runs.csv` header against the campaign's columns.
fn check_header(row: &csv::StringRecord, expected: &[String]) -> Result<(), String> {
    let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
    for (j, name) in row.iter().enumerate() {
        if let Some(first) = seen.insert(name, j) {
            return Err(format!(
                "column `{name}` appears twice in the header (columns {} and {})",
                first + 1,
                j + 1
            ));
        }
    }
    if row.iter().ne(expected.iter().map(String::as_str)) {
        return Err(format!(
            "the header differs from this campaign's columns (expected `{}`)",
            expected.join(",")
        ));
    }
    Ok(())
}

/// Read the records of a `runs.csv` (or partial) file; a missing file is
/// empty, a torn last line (interrupted write) is ignored. The header must be
/// the campaign's; outcome and termination are read back typed, and every
/// number must be finite except a dispersed value (an invalid draw may be
/// ±inf).
pub(super) fn read_records(path: &Path, dispersed: &[String]) -> Result<Vec<RunRecord>, McError> {
    let Some((reader, complete)) = open_results(path)? else {
        return Ok(Vec::new());
    };
    let header = csv_header(dispersed);
    let ndisp = dispersed.len();
    let ncol = header.len();
    let rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(reader);
    let mut rows = rdr.into_records().enumerate().peekable();
    let mut out = Vec::new();
    while let Some((i, row)) = rows.next() {
        if !complete && rows.peek().is_none() {
            break;
        }
        let cerr = |line: usize, message: String| McError::Csv {
            file: path.display().to_string(),
            line,
            message,
        };
        let row = row.map_err(|e| {
            let line = e.position().map_or(i + 1, |p| p.line() as usize);
            cerr(line, e.to_string())
        })?;
        let line = row.position().map_or(i + 1, |p| p.line() as usize);
        let cerr = |message: String| cerr(line, message);
        if row.get(0) == Some("index") {
            check_header(&row, &header).map_err(cerr)?;
            continue;
        }
        if row.len() != ncol {
            return Err(cerr(format!("{} columns, expected {ncol}", row.len())));
        }
        let num = |j: usize| -> Result<f64, McError> {
            row[j]
                .parse::<f64>()
                .map_err(|_| cerr(format!("column {}: `{}` is not a number", j + 1, &row[j])))
        };
        let finite = |j: usize| -> Result<f64, McError> {
            let v = num(j)?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(cerr(format!(
                    "column {} ({}): `{}` is not a finite number",
                    j + 1,
                    header[j],
                    &row[j]
                )))
            }
        };
        let int = |j: usize| -> Result<u64, McError> {
            row[j].parse::<u64>().map_err(|_| {
                cerr(format!(
                    "column {}: `{}` is not a whole number",
                    j + 1,
                    &row[j]
                ))
            })
        };
        let mut values = Vec::with_capacity(ndisp);
        for j in 0..ndisp {
            values.push(num(3 + j)?);
        }
        let o = 3 + ndisp;
        let outcome: RunOutcome = row[o]
            .parse()
            .map_err(|e: String| cerr(format!("column {} (outcome): {e}", o + 1)))?;
        let termination = RunTermination::parse(outcome, &row[o + 1])
            .map_err(|e| cerr(format!("column {} (termination): {e}", o + 2)))?;
        let mut metrics = Vec::with_capacity(METRIC_NAMES.len());
        for j in 0..METRIC_NAMES.len() {
            let c = o + 4 + j;
            metrics.push(if row[c].is_empty() {
                None
            } else {
                Some(finite(c)?)
            });
        }
        out.push(RunRecord {
            index: usize::try_from(int(0)?)
                .map_err(|_| cerr("column 1: index too large for this machine".into()))?,
            wind_seed: int(1)?,
            sensor_seed: int(2)?,
            values,
            termination,
            reason: row[o + 2].to_string(),
            t_end_s: finite(o + 3)?,
            metrics,
        });
    }
    Ok(out)
}

/// Read a `traces.csv` (or partial) file into `out` (a run's points replace
/// any it already had); a missing file adds nothing, a torn last line is
/// ignored.
pub(super) fn read_traces_into(
    path: &Path,
    out: &mut BTreeMap<usize, Vec<TracePoint>>,
    replace: bool,
) -> Result<(), McError> {
    let Some((reader, complete)) = open_results(path)? else {
        return Ok(());
    };
    let mut file: BTreeMap<usize, Vec<TracePoint>> = BTreeMap::new();
    let mut lines = reader.lines().enumerate().peekable();
    while let Some((i, line)) = lines.next() {
        let line = line.map_err(|e| io_err(path, "read", e))?;
        if !complete && lines.peek().is_none() {
            break;
        }
        if i == 0 && line.starts_with("index") {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        let parsed: Option<(usize, [f64; 5])> = (|| {
            if f.len() != 6 {
                return None;
            }
            let idx = f[0].parse().ok()?;
            let mut v = [0.0; 5];
            for j in 0..5 {
                v[j] = f[j + 1].parse().ok().filter(|x: &f64| x.is_finite())?;
            }
            Some((idx, v))
        })();
        let Some((idx, v)) = parsed else {
            return Err(McError::Csv {
                file: path.display().to_string(),
                line: i + 1,
                message: format!("expected {TRACE_HEADER} (finite numbers)"),
            });
        };
        file.entry(idx).or_default().push(TracePoint {
            t_s: v[0],
            output: [v[1], v[2], v[3], v[4]],
        });
    }
    for (k, v) in file {
        if replace {
            out.insert(k, v);
        } else {
            out.entry(k).or_insert(v);
        }
    }
    Ok(())
}

/// The manifest of `dir`, if it has one, checked to be of this format version.
pub(super) fn read_manifest(dir: &Path) -> Result<Option<Manifest>, McError> {
    let p = dir.join(MANIFEST);
    let text = match std::fs::read_to_string(&p) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io_err(&p, "read", e)),
    };
    let m: Manifest = serde_json::from_str(&text).map_err(|e| McError::Csv {
        file: p.display().to_string(),
        line: e.line(),
        message: e.to_string(),
    })?;
    if m.format_version != FORMAT_VERSION {
        return Err(McError::Format {
            folder: dir.display().to_string(),
            found: m.format_version,
            expected: FORMAT_VERSION,
        });
    }
    Ok(Some(m))
}

/// The manifest of `dir` if it has one, which must be of campaign `hash`.
pub(super) fn check_manifest(dir: &Path, hash: &str) -> Result<Option<Manifest>, McError> {
    let Some(m) = read_manifest(dir)? else {
        return Ok(None);
    };
    if m.hash != hash {
        return Err(McError::Mismatch {
            folder: dir.display().to_string(),
            expected: hash.to_string(),
            found: m.hash,
        });
    }
    Ok(Some(m))
}

/// Merge shard folders of one campaign into `out` (checks the format
/// version and the hashes; a run present in several folders must be
/// identical).
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<McReport, McError> {
    let first = dirs.first().ok_or(McError::NoFolders)?;
    // each run with the folder (index into `dirs`, or `dirs.len()` for `out`) it came from
    let mut records: BTreeMap<usize, (RunRecord, usize)> = BTreeMap::new();
    let mut traces: BTreeMap<usize, Vec<TracePoint>> = BTreeMap::new();
    let mut manifest0: Option<Manifest> = None;
    for (n, d) in dirs.iter().enumerate() {
        let m = read_manifest(d)?.ok_or_else(|| {
            io_err(
                &d.join(MANIFEST),
                "read",
                std::io::Error::new(std::io::ErrorKind::NotFound, "not a campaign folder"),
            )
        })?;
        if let Some(m0) = &manifest0
            && m0.hash != m.hash
        {
            return Err(McError::Mismatch {
                folder: d.display().to_string(),
                expected: m0.hash.clone(),
                found: m.hash,
            });
        }
        for f in [RUNS, RUNS_PARTIAL] {
            for r in read_records(&d.join(f), &m.dispersed)? {
                match records.get(&r.index) {
                    Some((prev, pn)) if *prev != r => {
                        return Err(McError::Conflict {
                            index: r.index,
                            a: dirs[*pn].display().to_string(),
                            b: d.display().to_string(),
                        });
                    }
                    Some(_) => {}
                    None => {
                        records.insert(r.index, (r, n));
                    }
                }
            }
        }
        for f in [TRACES, TRACES_PARTIAL] {
            read_traces_into(&d.join(f), &mut traces, true)?;
        }
        if manifest0.is_none() {
            manifest0 = Some(m);
        }
    }
    let Some(m0) = manifest0 else {
        return Err(McError::NoFolders);
    };
    std::fs::create_dir_all(out).map_err(|e| io_err(out, "create the folder", e))?;
    if let Some(m) = check_manifest(out, &m0.hash)? {
        // merging into a folder of the same campaign keeps its runs too
        for r in read_records(&out.join(RUNS), &m.dispersed)? {
            records.entry(r.index).or_insert((r, dirs.len()));
        }
        read_traces_into(&out.join(TRACES), &mut traces, false)?;
    }
    let manifest = Manifest {
        shard: None,
        runs: m0.runs.max(records.keys().next_back().map_or(0, |k| k + 1)),
        ..m0
    };
    write_json(&out.join(MANIFEST), &manifest)?;
    for f in [CAMPAIGN, SCENARIO, PARAMS] {
        let src = first.join(f);
        let text = std::fs::read_to_string(&src).map_err(|e| io_err(&src, "read", e))?;
        write_file(&out.join(f), &text)?;
    }
    let recs: BTreeMap<usize, RunRecord> = records.into_iter().map(|(k, (r, _))| (k, r)).collect();
    let n = recs.len();
    let stats = finish(&manifest, &recs, &traces, out)?;
    Ok(McReport {
        flown: 0,
        skipped: n,
        stats,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A value whose serialisation fails.
    struct Unserialisable;

    impl Serialize for Unserialisable {
        fn serialize<S: serde::Serializer>(&self, _: S) -> Result<S::Ok, S::Error> {
            Err(serde::ser::Error::custom("refused"))
        }
    }

    #[test]
    fn a_serialisation_failure_is_an_error_and_writes_nothing() {
        let d = std::env::temp_dir().join(format!("helicon-mc-json-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("stats.json");
        let e = write_json(&p, &Unserialisable).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, McError::Serialize { .. }), "{msg}");
        assert!(
            msg.contains("stats.json") && msg.contains("refused"),
            "{msg}"
        );
        assert!(!p.exists(), "no empty file");
        let _ = std::fs::remove_dir_all(&d);
    }
}
