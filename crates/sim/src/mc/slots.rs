//! The run store of a campaign folder: one fixed-size binary slot per run
//! in `runs.bin`, its trace in a slot of `traces.bin`, and the reason of a
//! failed run appended to `reasons.bin`. Written as runs finish, by any
//! thread, in any order (positioned writes, no lock); read in index order
//! (slot `j` holds run `K + j·M` of shard `K/M`). Nothing of it is held in
//! memory: a campaign of a million runs keeps a few slots.
//!
//! # Layout (little-endian)
//!
//! `runs.bin`, slot of `RUN_HEAD + 8·(dispersions + metrics)` bytes (the
//! metrics: 20, and 31 with the ground metrics of a campaign with `[ground]`):
//!
//! | bytes | field |
//! |---|---|
//! | 0..8 | FNV-1a 64 checksum of bytes 8.. of the slot, the reason's bytes and the trace's bytes |
//! | 8..16 | run index |
//! | 16..24, 24..32 | wind seed, sensor seed |
//! | 32..40 | `t_end_s` (f64 bits) |
//! | 40..48, 48..52 | offset and length of the reason in `reasons.bin` |
//! | 52..56 | trace points in `traces.bin` |
//! | 56 | outcome (index in [`RunOutcome::ALL`]) |
//! | 57 | length of the termination word |
//! | 58..120 | the termination word (the `termination` column), zero-padded |
//! | 120..128 | zero |
//! | 128.. | the dispersed values, then the metrics (f64 bits; a missing metric is NaN, which a recorded metric never is) |
//!
//! `traces.bin`, slot of `40 · trace_points` bytes: `t_s, vn, ve, vd, ψ`
//! per point. A slot of zeros, a torn write or a slot whose reason or trace
//! does not match its checksum is a run not done: flown again on resume.

use super::{McError, RunOutcome, RunRecord, RunTermination, TracePoint, metric_count};
use std::fs::{File, OpenOptions};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

pub(super) const RUNS_BIN: &str = "runs.bin";
pub(super) const TRACES_BIN: &str = "traces.bin";
pub(super) const REASONS_BIN: &str = "reasons.bin";
const RUN_HEAD: usize = 128;
const WORD: usize = 62;
const POINT: usize = 40;
/// A missing metric.
const NONE_BITS: u64 = 0x7ff8_0000_0000_0001;

/// FNV-1a 64 over several byte strings.
fn fnv(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for &b in *p {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

fn u64_at(b: &[u8], o: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[o..o + 8]);
    u64::from_le_bytes(a)
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[o..o + 4]);
    u32::from_le_bytes(a)
}

/// Which runs a store holds and how big their slots are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Layout {
    /// Dispersed values per run.
    pub(super) dispersions: usize,
    /// Trace points a slot of `traces.bin` holds.
    pub(super) trace_points: usize,
    /// Slot `j` holds run `k + j·m`.
    pub(super) k: usize,
    /// See `k`.
    pub(super) m: usize,
    /// Runs with an index below this have a trace (`usize::MAX`: all).
    pub(super) trace_runs: usize,
    /// A campaign with `[ground]`: each slot holds the ground metrics too.
    pub(super) ground: bool,
}

impl Layout {
    fn run_slot(&self) -> usize {
        RUN_HEAD + 8 * (self.dispersions + metric_count(self.ground))
    }

    fn trace_slot(&self) -> usize {
        POINT * self.trace_points
    }

    /// The run index of slot `j`.
    pub(super) fn index(&self, j: usize) -> usize {
        self.k + j * self.m
    }

    /// Does run `index` keep a trace?
    pub(super) fn traced(&self, index: usize) -> bool {
        index < self.trace_runs && self.trace_points > 0
    }

    /// Bytes on disk per run (its slot and, if traced, its trace slot).
    pub(super) fn bytes_per_run(&self) -> u64 {
        (self.run_slot() + self.trace_slot()) as u64
    }
}

/// An open run store.
pub(super) struct Store {
    layout: Layout,
    dir: PathBuf,
    runs: File,
    traces: File,
    reasons: File,
    reasons_end: AtomicU64,
}

/// What reading a slot found.
pub(super) enum Slot {
    /// Never written, torn, or not matching its checksum: not done.
    Empty,
    /// A run, with its trace's length.
    Run(RunRecord, usize),
}

impl Store {
    /// Open (creating the files if `create`) the store of `dir`.
    pub(super) fn open(dir: &Path, layout: Layout, create: bool) -> Result<Store, McError> {
        let open = |name: &str| -> Result<File, McError> {
            let p = dir.join(name);
            OpenOptions::new()
                .read(true)
                .write(create)
                .create(create)
                .truncate(false)
                .open(&p)
                .map_err(|e| super::store::io_err(&p, if create { "write" } else { "read" }, e))
        };
        let runs = open(RUNS_BIN)?;
        let traces = open(TRACES_BIN)?;
        let reasons = open(REASONS_BIN)?;
        let p = dir.join(REASONS_BIN);
        let end = reasons
            .metadata()
            .map_err(|e| super::store::io_err(&p, "read", e))?
            .len();
        Ok(Store {
            layout,
            dir: dir.to_path_buf(),
            runs,
            traces,
            reasons,
            reasons_end: AtomicU64::new(end),
        })
    }

    /// The layout.
    pub(super) fn layout(&self) -> Layout {
        self.layout
    }

    fn err(&self, name: &str, action: &'static str, e: std::io::Error) -> McError {
        super::store::io_err(&self.dir.join(name), action, e)
    }

    /// Slots in `runs.bin` (written or not: up to the last one written).
    pub(super) fn slots(&self) -> Result<usize, McError> {
        let len = self
            .runs
            .metadata()
            .map_err(|e| self.err(RUNS_BIN, "read", e))?
            .len();
        Ok(usize::try_from(len).unwrap_or(usize::MAX) / self.layout.run_slot())
    }

    /// Write run `record` (slot `j`) and its trace. The reason and the trace
    /// go first, the slot with its checksum last: a slot that reads back
    /// valid has both.
    pub(super) fn put(
        &self,
        j: usize,
        record: &RunRecord,
        trace: &[TracePoint],
    ) -> Result<(), McError> {
        let l = &self.layout;
        let bad = |message: String| McError::Store {
            file: self.dir.join(RUNS_BIN).display().to_string(),
            slot: j,
            message,
        };
        if record.index != l.index(j) {
            return Err(bad(format!(
                "run {} in the slot of run {}",
                record.index,
                l.index(j)
            )));
        }
        let word = record.termination.as_str().as_bytes();
        if word.len() > WORD {
            return Err(bad(format!(
                "termination `{}` longer than {WORD} bytes",
                record.termination.as_str()
            )));
        }
        if record.values.len() != l.dispersions || record.metrics.len() != metric_count(l.ground) {
            return Err(bad("record of another campaign layout".into()));
        }
        let trace = if l.traced(record.index) { trace } else { &[] };
        if trace.len() > l.trace_points {
            return Err(bad(format!(
                "{} trace points, the store holds {}",
                trace.len(),
                l.trace_points
            )));
        }
        let mut tb = Vec::with_capacity(trace.len() * POINT);
        for p in trace {
            tb.extend_from_slice(&p.t_s.to_bits().to_le_bytes());
            for v in p.output {
                tb.extend_from_slice(&v.to_bits().to_le_bytes());
            }
        }
        if !tb.is_empty() {
            self.traces
                .write_all_at(&tb, (j * l.trace_slot()) as u64)
                .map_err(|e| self.err(TRACES_BIN, "write", e))?;
        }
        let reason = record.reason.as_bytes();
        let reason_len = u32::try_from(reason.len()).map_err(|_| bad("reason too long".into()))?;
        let off = if reason.is_empty() {
            0
        } else {
            let off = self
                .reasons_end
                .fetch_add(reason.len() as u64, Ordering::Relaxed);
            self.reasons
                .write_all_at(reason, off)
                .map_err(|e| self.err(REASONS_BIN, "write", e))?;
            off
        };
        let mut s = vec![0u8; l.run_slot()];
        s[8..16].copy_from_slice(&(record.index as u64).to_le_bytes());
        s[16..24].copy_from_slice(&record.wind_seed.to_le_bytes());
        s[24..32].copy_from_slice(&record.sensor_seed.to_le_bytes());
        s[32..40].copy_from_slice(&record.t_end_s.to_bits().to_le_bytes());
        s[40..48].copy_from_slice(&off.to_le_bytes());
        s[48..52].copy_from_slice(&reason_len.to_le_bytes());
        s[52..56].copy_from_slice(&(trace.len() as u32).to_le_bytes());
        s[56] = RunOutcome::ALL
            .iter()
            .position(|o| *o == record.outcome())
            .unwrap_or(0) as u8;
        s[57] = word.len() as u8;
        s[58..58 + word.len()].copy_from_slice(word);
        let mut o = RUN_HEAD;
        for v in &record.values {
            s[o..o + 8].copy_from_slice(&v.to_bits().to_le_bytes());
            o += 8;
        }
        for m in &record.metrics {
            let b = m.map_or(NONE_BITS, f64::to_bits);
            s[o..o + 8].copy_from_slice(&b.to_le_bytes());
            o += 8;
        }
        let h = fnv(&[&s[8..], reason, &tb]);
        s[0..8].copy_from_slice(&h.to_le_bytes());
        self.runs
            .write_all_at(&s, (j * l.run_slot()) as u64)
            .map_err(|e| self.err(RUNS_BIN, "write", e))
    }

    /// Read slot `j` into `buf` (reused between calls).
    pub(super) fn get(&self, j: usize, buf: &mut Vec<u8>) -> Result<Slot, McError> {
        let l = &self.layout;
        let size = l.run_slot();
        buf.resize(size, 0);
        if !read_full(&self.runs, buf, (j * size) as u64)
            .map_err(|e| self.err(RUNS_BIN, "read", e))?
        {
            return Ok(Slot::Empty);
        }
        let h = u64_at(buf, 0);
        if h == 0 && buf.iter().all(|&b| b == 0) {
            return Ok(Slot::Empty);
        }
        let off = u64_at(buf, 40);
        let rlen = u32_at(buf, 48) as usize;
        let tlen = u32_at(buf, 52) as usize;
        let mut reason = vec![0u8; rlen];
        if rlen > 0
            && !read_full(&self.reasons, &mut reason, off)
                .map_err(|e| self.err(REASONS_BIN, "read", e))?
        {
            return Ok(Slot::Empty);
        }
        let mut tb = vec![0u8; tlen.min(l.trace_points) * POINT];
        if !tb.is_empty()
            && !read_full(&self.traces, &mut tb, (j * l.trace_slot()) as u64)
                .map_err(|e| self.err(TRACES_BIN, "read", e))?
        {
            return Ok(Slot::Empty);
        }
        if fnv(&[&buf[8..], &reason, &tb]) != h || tlen > l.trace_points {
            return Ok(Slot::Empty);
        }
        let bad = |message: String| McError::Store {
            file: self.dir.join(RUNS_BIN).display().to_string(),
            slot: j,
            message,
        };
        let index = usize::try_from(u64_at(buf, 8)).map_err(|_| bad("index too large".into()))?;
        if index != l.index(j) {
            return Err(bad(format!(
                "holds run {index}, expected run {}",
                l.index(j)
            )));
        }
        let outcome = *RunOutcome::ALL
            .get(usize::from(buf[56]))
            .ok_or_else(|| bad(format!("outcome code {}", buf[56])))?;
        let wlen = usize::from(buf[57]).min(WORD);
        let word = std::str::from_utf8(&buf[58..58 + wlen]).map_err(|e| bad(e.to_string()))?;
        let termination = RunTermination::parse(outcome, word).map_err(bad)?;
        let reason = String::from_utf8(reason).map_err(|e| bad(e.to_string()))?;
        let f = |o: usize| f64::from_bits(u64_at(buf, o));
        let values = (0..l.dispersions).map(|i| f(RUN_HEAD + 8 * i)).collect();
        let m0 = RUN_HEAD + 8 * l.dispersions;
        let metrics = (0..metric_count(l.ground))
            .map(|i| Some(f(m0 + 8 * i)).filter(|v| !v.is_nan()))
            .collect();
        Ok(Slot::Run(
            RunRecord {
                index,
                wind_seed: u64_at(buf, 16),
                sensor_seed: u64_at(buf, 24),
                values,
                termination,
                reason,
                t_end_s: f(32),
                metrics,
            },
            tlen,
        ))
    }

    /// The trace of slot `j` (`len` points, as [`Store::get`] said) into `out`.
    pub(super) fn trace(
        &self,
        j: usize,
        len: usize,
        out: &mut Vec<TracePoint>,
    ) -> Result<(), McError> {
        out.clear();
        if len == 0 {
            return Ok(());
        }
        let mut b = vec![0u8; len * POINT];
        if !read_full(&self.traces, &mut b, (j * self.layout.trace_slot()) as u64)
            .map_err(|e| self.err(TRACES_BIN, "read", e))?
        {
            return Err(McError::Store {
                file: self.dir.join(TRACES_BIN).display().to_string(),
                slot: j,
                message: "trace shorter than its run says".into(),
            });
        }
        for c in b.chunks_exact(POINT) {
            let f = |i: usize| f64::from_bits(u64_at(c, 8 * i));
            out.push(TracePoint {
                t_s: f(0),
                output: [f(1), f(2), f(3), f(4)],
            });
        }
        Ok(())
    }

    /// Flush everything to the disk.
    pub(super) fn sync(&self) -> Result<(), McError> {
        for (f, n) in [
            (&self.runs, RUNS_BIN),
            (&self.traces, TRACES_BIN),
            (&self.reasons, REASONS_BIN),
        ] {
            f.sync_data().map_err(|e| self.err(n, "write", e))?;
        }
        Ok(())
    }
}

/// Read `buf.len()` bytes at `off`; `false` when the file ends first.
fn read_full(f: &File, buf: &mut [u8], off: u64) -> std::io::Result<bool> {
    match f.read_exact_at(buf, off) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => Ok(false),
        Err(e) => Err(e),
    }
}
