//! The output folder: manifest, `runs.csv` / `traces.csv` (written line by
//! line from the run store, see `slots.rs`), and [`merge`].

use super::landing::LandingCriteria;
use super::report::finish;
use super::slots::{Layout, Slot, Store};
use super::{FORMAT_VERSION, McError, McReport, RunRecord, Shard, TracePoint, metric_names};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::path::{Path, PathBuf};

pub(super) const MANIFEST: &str = "manifest.json";
pub(super) const RUNS: &str = "runs.csv";
pub(super) const TRACES: &str = "traces.csv";
pub(super) const CAMPAIGN: &str = "campaign.toml";
pub(super) const SCENARIO: &str = "scenario.toml";
pub(super) const PARAMS: &str = "params.toml";
pub(super) const TRACE_HEADER: &str = "index,t_s,vn,ve,vd,psi";

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
    /// Trace points a run's trace slot holds (format 3).
    #[serde(default)]
    pub(super) trace_points: usize,
    /// Runs with an index below this keep a trace (`None`: all).
    #[serde(default)]
    pub(super) trace_runs: Option<usize>,
    /// The take-off and landing criteria (campaigns with `[ground]` only:
    /// their records carry the ground metrics).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) landing: Option<LandingCriteria>,
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

/// Header of `runs.csv` for the dispersed keys; `ground`: a campaign with
/// `[ground]`, whose rows end with the ground metrics and the `landing`
/// verdict.
pub fn csv_header(dispersed: &[String], ground: bool) -> Vec<String> {
    let mut h: Vec<String> = vec!["index".into(), "wind_seed".into(), "sensor_seed".into()];
    h.extend(dispersed.iter().cloned());
    h.extend(["outcome", "termination", "reason", "t_end_s"].map(String::from));
    h.extend(metric_names(ground).map(String::from));
    if ground {
        h.push("landing".into());
    }
    h
}

/// The fields of a `runs.csv` row; with `landing` (a campaign with
/// `[ground]`), the run's verdict last.
pub(super) fn record_fields(r: &RunRecord, landing: Option<&LandingCriteria>) -> Vec<String> {
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
    if let Some(l) = landing {
        f.push(l.classify(r).words());
    }
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

pub(super) fn create(path: &Path) -> Result<BufWriter<File>, McError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| io_err(path, "write", e))
}

pub(super) fn finish_file(path: &Path, mut w: BufWriter<File>) -> Result<(), McError> {
    w.flush().map_err(|e| io_err(path, "write", e))?;
    let f = w
        .into_inner()
        .map_err(|e| io_err(path, "write", e.into_error()))?;
    f.sync_data().map_err(|e| io_err(path, "write", e))
}

/// The manifest of `dir`, if it has one, checked to be of this format version.
pub(super) fn read_manifest(dir: &Path) -> Result<Option<Manifest>, McError> {
    let p = dir.join(MANIFEST);
    let text = match helicon_config::read_text_bounded(&p, helicon_config::MAX_TEXT_BYTES) {
        Ok(t) => t,
        Err(e) => {
            let e = e.into_io();
            if e.kind() == std::io::ErrorKind::NotFound {
                return Ok(None);
            }
            return Err(io_err(&p, "read", e));
        }
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

/// How far a campaign (or shard) folder is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FolderProgress {
    /// Campaign name.
    pub name: String,
    /// Campaign hash.
    pub hash: String,
    /// The shard (`K/M`), if it is one.
    pub shard: Option<String>,
    /// Runs this folder is to hold (its shard's share of the campaign's).
    pub runs: usize,
    /// Runs in its store.
    pub done: usize,
    /// Every run done and the outputs written (`stats.json` newer than the
    /// last run stored).
    pub finished: bool,
}

/// The progress of the campaign folder `dir` (`None`: not one, no
/// `manifest.json`), read from its run store.
pub fn folder_progress(dir: &Path) -> Result<Option<FolderProgress>, McError> {
    let Some(m) = read_manifest(dir)? else {
        return Ok(None);
    };
    let layout = layout_of(&m, dir)?;
    let runs = Shard {
        k: layout.k,
        m: layout.m,
    }
    .count(m.runs);
    let store = match Store::open(dir, layout, false) {
        Ok(s) => Some(s),
        // a folder whose first run is not stored yet
        Err(McError::Config(crate::scenario::ScenarioError::Io { source, .. }))
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            None
        }
        Err(e) => return Err(e),
    };
    let mut done = 0;
    if let Some(store) = &store {
        let mut buf = Vec::new();
        for j in 0..runs.min(store.slots()?) {
            if matches!(store.get(j, &mut buf)?, Slot::Run(..)) {
                done += 1;
            }
        }
    }
    let modified = |f: &str| {
        std::fs::metadata(dir.join(f))
            .and_then(|m| m.modified())
            .ok()
    };
    let finished = done == runs
        && match (modified("stats.json"), modified(super::slots::RUNS_BIN)) {
            (Some(s), Some(r)) => s >= r,
            _ => false,
        };
    Ok(Some(FolderProgress {
        name: m.name,
        hash: m.hash,
        shard: m.shard,
        runs,
        done,
        finished,
    }))
}

/// The store layout of a folder's manifest.
pub(super) fn layout_of(m: &Manifest, dir: &Path) -> Result<Layout, McError> {
    let (k, mm) = match &m.shard {
        None => (0, 1),
        Some(s) => {
            let sh: Shard = s.parse().map_err(|e: String| McError::Csv {
                file: dir.join(MANIFEST).display().to_string(),
                line: 0,
                message: e,
            })?;
            (sh.k, sh.m)
        }
    };
    Ok(Layout {
        dispersions: m.dispersed.len(),
        trace_points: m.trace_points,
        k,
        m: mm,
        trace_runs: m.trace_runs.unwrap_or(usize::MAX),
        ground: m.landing.is_some(),
    })
}

/// One input folder of a merge: its store and its next run.
struct Cursor {
    store: Store,
    slots: usize,
    next: usize,
    /// The next run: its record, slot and trace length.
    head: Option<(RunRecord, usize, usize)>,
}

impl Cursor {
    fn advance(&mut self, buf: &mut Vec<u8>) -> Result<(), McError> {
        self.head = None;
        while self.next < self.slots {
            let j = self.next;
            self.next += 1;
            if let Slot::Run(r, tlen) = self.store.get(j, buf)? {
                self.head = Some((r, j, tlen));
                return Ok(());
            }
        }
        Ok(())
    }
}

/// Merge shard folders of one campaign into `out` (checks the format
/// version and the hashes; a run present in several folders must be
/// identical). Streamed: the folders' stores are read in index order side
/// by side (one run of each in memory) into `out`'s store, whose outputs
/// are then written as a campaign's are, so the merged folder equals the
/// unsharded campaign's.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<McReport, McError> {
    let first = dirs.first().ok_or(McError::NoFolders)?;
    let mut manifest0: Option<Manifest> = None;
    let mut cursors = Vec::with_capacity(dirs.len());
    let mut buf = Vec::new();
    for d in dirs {
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
        let store = Store::open(d, layout_of(&m, d)?, false)?;
        let slots = store.slots()?;
        let mut c = Cursor {
            store,
            slots,
            next: 0,
            head: None,
        };
        c.advance(&mut buf)?;
        cursors.push(c);
        if manifest0.is_none() {
            manifest0 = Some(m);
        }
    }
    let Some(m0) = manifest0 else {
        return Err(McError::NoFolders);
    };
    std::fs::create_dir_all(out).map_err(|e| io_err(out, "create the folder", e))?;
    // merging into a folder of the same campaign keeps its runs too
    let previous = check_manifest(out, &m0.hash)?;
    let mut manifest = Manifest {
        shard: None,
        runs: m0.runs.max(previous.as_ref().map_or(0, |p| p.runs)),
        ..m0
    };
    write_json(&out.join(MANIFEST), &manifest)?;
    for f in [CAMPAIGN, SCENARIO, PARAMS] {
        let src = first.join(f);
        let text = helicon_config::read_text_bounded(&src, helicon_config::MAX_TEXT_BYTES)
            .map_err(|e| io_err(&src, "read", e.into_io()))?;
        write_file(&out.join(f), &text)?;
    }
    let layout = layout_of(&manifest, out)?;
    let dest = Store::open(out, layout, true)?;
    let mut trace = Vec::new();
    let mut merged = 0usize;
    let index_of = |c: &Cursor| c.head.as_ref().map(|h| h.0.index);
    while let Some(i) = cursors.iter().filter_map(index_of).min() {
        let holders: Vec<usize> = (0..cursors.len())
            .filter(|&n| index_of(&cursors[n]) == Some(i))
            .collect();
        if let Some(&f) = holders.first()
            && let Some((r, j, tlen)) = &cursors[f].head
        {
            for &n in &holders[1..] {
                if cursors[n].head.as_ref().map(|h| &h.0) != Some(r) {
                    return Err(McError::Conflict {
                        index: i,
                        a: dirs[f].display().to_string(),
                        b: dirs[n].display().to_string(),
                    });
                }
            }
            cursors[f].store.trace(*j, *tlen, &mut trace)?;
            dest.put(i, r, &trace)?;
        }
        for n in holders {
            cursors[n].advance(&mut buf)?;
        }
        merged += 1;
        manifest.runs = manifest.runs.max(i + 1);
    }
    dest.sync()?;
    write_json(&out.join(MANIFEST), &manifest)?;
    let stats = finish(&manifest, &dest, out)?;
    Ok(McReport {
        flown: 0,
        skipped: merged.max(stats.runs),
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
