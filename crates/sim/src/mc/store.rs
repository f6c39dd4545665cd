//! The output folder: manifest, `runs.csv` / `traces.csv` (and partial files), merge.

use super::report::finish;
use super::{METRIC_NAMES, McError, McReport, RunRecord, TracePoint};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub(super) const MANIFEST: &str = "manifest.json";
pub(super) const RUNS: &str = "runs.csv";
pub(super) const RUNS_PARTIAL: &str = "runs.partial.csv";
pub(super) const TRACES: &str = "traces.csv";
pub(super) const TRACES_PARTIAL: &str = "traces.partial.csv";

#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct Manifest {
    pub(super) name: String,
    pub(super) hash: String,
    pub(super) runs: usize,
    pub(super) seed: u64,
    pub(super) shard: Option<String>,
    pub(super) dispersed: Vec<String>,
}

pub(super) fn io_err(path: &Path, e: impl std::fmt::Display) -> McError {
    McError::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    }
}

pub(super) fn write_file(path: &Path, text: &str) -> Result<(), McError> {
    std::fs::write(path, text).map_err(|e| io_err(path, e))
}

/// Header of `runs.csv` for the dispersed parameter keys.
pub fn csv_header(dispersed: &[String]) -> Vec<String> {
    let mut h: Vec<String> = vec!["index".into(), "wind_seed".into(), "sensor_seed".into()];
    h.extend(dispersed.iter().cloned());
    h.extend(["outcome", "reason", "t_end_s"].map(String::from));
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
    f.push(r.outcome.clone());
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
    w.write_record(fields).map_err(|e| McError::Io {
        file: "<csv>".into(),
        message: e.to_string(),
    })?;
    let bytes = w.into_inner().map_err(|e| McError::Io {
        file: "<csv>".into(),
        message: e.to_string(),
    })?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
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

/// Read the records of a `runs.csv` (or partial) file; a missing file is empty.
/// A truncated last line (interrupted write) is ignored.
pub(super) fn read_records(path: &Path, ndisp: usize) -> Result<Vec<RunRecord>, McError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(io_err(path, e)),
    };
    let complete = text.ends_with('\n');
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text.as_bytes());
    let ncol = 3 + ndisp + 3 + METRIC_NAMES.len();
    let mut out = Vec::new();
    let rows: Vec<_> = rdr.records().collect();
    let nrows = rows.len();
    for (i, row) in rows.into_iter().enumerate() {
        let line = i + 1;
        let cerr = |message: String| McError::Csv {
            file: path.display().to_string(),
            line,
            message,
        };
        let row = row.map_err(|e| cerr(e.to_string()))?;
        if row.get(0) == Some("index") {
            continue;
        }
        if row.len() != ncol {
            if !complete && i + 1 == nrows {
                break;
            }
            return Err(cerr(format!("{} columns, expected {ncol}", row.len())));
        }
        let num = |j: usize| -> Result<f64, McError> {
            row[j]
                .parse::<f64>()
                .map_err(|_| cerr(format!("column {}: `{}` is not a number", j + 1, &row[j])))
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
        let mut metrics = Vec::with_capacity(METRIC_NAMES.len());
        for j in 0..METRIC_NAMES.len() {
            let c = o + 3 + j;
            metrics.push(if row[c].is_empty() {
                None
            } else {
                Some(num(c)?)
            });
        }
        out.push(RunRecord {
            index: int(0)? as usize,
            wind_seed: int(1)?,
            sensor_seed: int(2)?,
            values,
            outcome: row[o].to_string(),
            reason: row[o + 1].to_string(),
            t_end_s: num(o + 2)?,
            metrics,
        });
    }
    Ok(out)
}

pub(super) fn read_traces(path: &Path) -> Result<BTreeMap<usize, Vec<TracePoint>>, McError> {
    let mut out: BTreeMap<usize, Vec<TracePoint>> = BTreeMap::new();
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(out),
        Err(e) => return Err(io_err(path, e)),
    };
    for (i, line) in text.lines().enumerate() {
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
                v[j] = f[j + 1].parse().ok()?;
            }
            Some((idx, v))
        })();
        match parsed {
            Some((idx, v)) => out.entry(idx).or_default().push(TracePoint {
                t_s: v[0],
                output: [v[1], v[2], v[3], v[4]],
            }),
            // a torn last line of a partial file
            None if i + 1 == text.lines().count() && !text.ends_with('\n') => {}
            None => {
                return Err(McError::Csv {
                    file: path.display().to_string(),
                    line: i + 1,
                    message: "expected index,t_s,vn,ve,vd,psi".into(),
                });
            }
        }
    }
    Ok(out)
}

pub(super) fn check_manifest(dir: &Path, hash: &str) -> Result<Option<Manifest>, McError> {
    let p = dir.join(MANIFEST);
    let text = match std::fs::read_to_string(&p) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io_err(&p, e)),
    };
    let m: Manifest = serde_json::from_str(&text).map_err(|e| McError::Parse {
        file: p.display().to_string(),
        message: e.to_string(),
    })?;
    if m.hash != hash {
        return Err(McError::Mismatch {
            folder: dir.display().to_string(),
            expected: hash.to_string(),
            found: m.hash,
        });
    }
    Ok(Some(m))
}

/// Merge shard folders of one campaign into `out` (checks the hashes;
/// a run present in several folders must be identical).
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<McReport, McError> {
    let first = dirs.first().ok_or_else(|| McError::Invalid {
        file: "<merge>".into(),
        field: "folders".into(),
        value: "none".into(),
        rule: "give at least one shard folder".into(),
    })?;
    let mut records: BTreeMap<usize, (RunRecord, String)> = BTreeMap::new();
    let mut traces: BTreeMap<usize, Vec<TracePoint>> = BTreeMap::new();
    let mut hash: Option<String> = None;
    let mut manifest0: Option<Manifest> = None;
    for d in dirs {
        let p = d.join(MANIFEST);
        let text = std::fs::read_to_string(&p).map_err(|e| io_err(&p, e))?;
        let m: Manifest = serde_json::from_str(&text).map_err(|e| McError::Parse {
            file: p.display().to_string(),
            message: e.to_string(),
        })?;
        match &hash {
            None => hash = Some(m.hash.clone()),
            Some(h) if *h != m.hash => {
                return Err(McError::Mismatch {
                    folder: d.display().to_string(),
                    expected: h.clone(),
                    found: m.hash,
                });
            }
            Some(_) => {}
        }
        let nd = m.dispersed.len();
        for f in [RUNS, RUNS_PARTIAL] {
            for r in read_records(&d.join(f), nd)? {
                let folder = d.display().to_string();
                if let Some((prev, pf)) = records.get(&r.index) {
                    if *prev != r {
                        return Err(McError::Conflict {
                            index: r.index,
                            a: pf.clone(),
                            b: folder,
                        });
                    }
                } else {
                    records.insert(r.index, (r, folder));
                }
            }
        }
        for f in [TRACES, TRACES_PARTIAL] {
            for (k, v) in read_traces(&d.join(f))? {
                traces.insert(k, v);
            }
        }
        if manifest0.is_none() {
            manifest0 = Some(m);
        }
    }
    let Some(m0) = manifest0 else {
        return Err(McError::Invalid {
            file: "<merge>".into(),
            field: "folders".into(),
            value: "none".into(),
            rule: "give at least one shard folder".into(),
        });
    };
    std::fs::create_dir_all(out).map_err(|e| io_err(out, e))?;
    if let Some(m) = check_manifest(out, &m0.hash)? {
        // merging into a folder of the same campaign keeps its runs too
        for r in read_records(&out.join(RUNS), m.dispersed.len())? {
            records
                .entry(r.index)
                .or_insert((r, out.display().to_string()));
        }
        for (k, v) in read_traces(&out.join(TRACES))? {
            traces.entry(k).or_insert(v);
        }
    }
    let manifest = Manifest {
        shard: None,
        runs: m0.runs.max(records.keys().next_back().map_or(0, |k| k + 1)),
        ..m0
    };
    write_file(
        &out.join(MANIFEST),
        &serde_json::to_string_pretty(&manifest).unwrap_or_default(),
    )?;
    for f in ["campaign.toml", "scenario.toml"] {
        let src = first.join(f);
        let text = std::fs::read_to_string(&src).map_err(|e| io_err(&src, e))?;
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
