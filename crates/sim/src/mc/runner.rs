//! Flying runs: one run, a whole campaign (threads, shards, resume), and the
//! memory bound on the number of runs.

use super::report::finish;
use super::store::{
    CAMPAIGN, MANIFEST, Manifest, PARAMS, RUNS, RUNS_PARTIAL, SCENARIO, TRACES, TRACES_PARTIAL,
    check_manifest, csv_line, io_err, read_records, read_traces_into, record_fields, trace_lines,
    write_file, write_json, write_runs_csv, write_traces_csv,
};
use super::{
    Campaign, DesignMode, ErrorStage, FORMAT_VERSION, METRIC_NAMES, McError, RunOutput, RunRecord,
    RunTermination, Stats, TracePoint,
};
use crate::closed_loop::{
    ClosedLoopError, LogRow, Prepared, Termination, fly, prepare_with_params,
};
pub use crate::resources::memory_budget;
use crate::scenario::{OUTPUTS, ScenarioError};
use helicon_model::Model;
use helicon_model::ParamError;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Memory a campaign needs, from its scenario and trace rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunMemory {
    /// Trace samples kept per run.
    pub trace_points: u64,
    /// Bytes kept per run until the statistics are written: its record, its
    /// trace, their map entries and its share of the statistics' buffers.
    pub bytes_per_run: u64,
    /// Bytes of one flight in progress (its full log).
    pub bytes_per_flight: u64,
}

impl Campaign {
    /// Design (or not) on the nominal parameters: what every run shares.
    pub fn prepare_nominal(&self) -> Result<Prepared, McError> {
        Ok(prepare_with_params(&self.scenario, self.nominal)?)
    }

    /// Log rows between two kept trace samples (0: no trace). The flight log
    /// holds every `[log] decimation`-th controller sample.
    fn trace_every_rows(&self) -> usize {
        if self.trace_rate_hz <= 0.0 {
            return 0;
        }
        let ts = self.nominal.control.sample_time_s;
        let d = self.scenario.log.decimation.max(1) as f64;
        let every = (1.0 / (self.trace_rate_hz * ts * d)).round();
        // `as` saturates; an absurdly slow trace rate keeps the first sample only
        (every as usize).max(1)
    }

    /// The memory of one run kept until the end, and of one flight in
    /// progress (upper bounds, from the sizes of the types).
    pub fn run_memory(&self) -> RunMemory {
        let ts = self.nominal.control.sample_time_s;
        let samples = (self.scenario.duration_s / ts).round() + 1.0;
        let d = self.scenario.log.decimation.max(1) as f64;
        let rows = (samples / d).ceil() + 1.0;
        let every = self.trace_every_rows();
        let trace_points = if every == 0 {
            0
        } else {
            (rows / every as f64).ceil() as u64
        };
        let map_node = 64; // a BTreeMap entry's share of its node, with slack
        let record = std::mem::size_of::<RunRecord>()
            + self.dispersions.len() * std::mem::size_of::<f64>()
            + METRIC_NAMES.len() * std::mem::size_of::<Option<f64>>()
            + 160 // the reason sentence of a failed run
            + map_node;
        let trace = std::mem::size_of::<Vec<TracePoint>>() + map_node;
        // the statistics: a reference per run, one value per metric
        let stats = std::mem::size_of::<usize>() + METRIC_NAMES.len() * std::mem::size_of::<f64>();
        let bytes_per_run = (record + trace + stats) as u64
            + trace_points * std::mem::size_of::<TracePoint>() as u64;
        let bytes_per_flight = (rows as u64).saturating_mul(std::mem::size_of::<LogRow>() as u64);
        RunMemory {
            trace_points,
            bytes_per_run,
            bytes_per_flight,
        }
    }

    /// Fly run `index` (its draws, its flight, its record and trace).
    ///
    /// Never a non-finite number in the record: a metric that comes out NaN
    /// or infinite is left empty and named in the reason; a completed flight
    /// with one is recorded as an `error` at stage `metrics` (a value it
    /// should have is missing). A trace stops before its first non-finite
    /// sample.
    #[allow(clippy::too_many_lines)] // one run's stages in order: draw, prepare, fly, record
    pub fn run_one(&self, nominal: &Prepared, index: usize) -> RunOutput {
        let draw = self.draw(index);
        let not_flown = |termination: RunTermination, reason: String| RunOutput {
            record: RunRecord {
                index,
                wind_seed: draw.wind_seed,
                sensor_seed: draw.sensor_seed,
                values: draw.values.clone(),
                termination,
                reason,
                t_end_s: 0.0,
                metrics: vec![None; METRIC_NAMES.len()],
            },
            trace: Vec::new(),
        };
        if let Err(e) = draw.params.validate(&format!("run {index}")) {
            return match e {
                ParamError::Invalid {
                    key, value, rule, ..
                } => not_flown(
                    RunTermination::InvalidDraw(key.clone()),
                    format!("invalid draw: {key} = {value}: {rule}"),
                ),
                other => not_flown(
                    RunTermination::Error(ErrorStage::Parameters),
                    format!("checking the drawn parameters: {other}"),
                ),
            };
        }
        let mut scenario = self.scenario.clone();
        scenario.wind.seed = draw.wind_seed;
        scenario.sensors.seed = draw.sensor_seed;
        let prepared = match self.design {
            DesignMode::PerRun => prepare_with_params(&scenario, draw.params),
            DesignMode::Nominal => {
                let model = Model::new(draw.params, scenario.preset.options());
                let target = TrimTarget {
                    velocity_ned_m_s: Vector3::from(scenario.trim.velocity_ned_m_s),
                    yaw_rad: scenario.trim.yaw_rad,
                    wind_ned_m_s: Vector3::zeros(),
                };
                trim(&model, &target, &TrimOptions::default())
                    .and_then(|t| t.require_physical(&model))
                    .map(|t| Prepared {
                        model,
                        trim: t,
                        gains: nominal.gains.clone(),
                        schedule: nominal.schedule.clone(),
                    })
                    .map_err(ClosedLoopError::from)
            }
        };
        let prepared = match prepared {
            Ok(p) => p,
            Err(e) => {
                let stage = match e {
                    ClosedLoopError::Trim(_) => ErrorStage::Trim,
                    _ => ErrorStage::Design,
                };
                return not_flown(RunTermination::Error(stage), e.to_string());
            }
        };
        let flight = match fly(&scenario, &prepared, None) {
            Ok(f) => f,
            Err(e) => {
                return not_flown(
                    RunTermination::Error(ErrorStage::FlightSetup),
                    e.to_string(),
                );
            }
        };
        let s = &flight.summary;
        let mut m = Vec::with_capacity(METRIC_NAMES.len());
        for o in OUTPUTS {
            let om = s.metrics.get(o);
            m.push(om.and_then(|v| v.settling_time_s));
            m.push(om.map(|v| v.overshoot_pct));
            m.push(om.map(|v| v.rms_error));
            m.push(om.map(|v| v.max_abs_error));
        }
        for e in s.control_effort_rms {
            m.push(Some(e));
        }
        let mut termination = RunTermination::Flight(s.termination);
        let mut reason = s.reason.clone().unwrap_or_default();
        let mut bad = Vec::new();
        for (v, name) in m.iter_mut().zip(METRIC_NAMES) {
            if let Some(x) = *v
                && !x.is_finite()
            {
                bad.push(format!("{name} = {x}"));
                *v = None;
            }
        }
        if !bad.is_empty() {
            let note = format!("not finite, left empty: {}", bad.join(", "));
            if s.termination == Termination::Completed {
                termination = RunTermination::Error(ErrorStage::Metrics);
                reason = format!("flight completed but metrics {note}");
            } else {
                reason = format!("{reason}; metrics {note}");
            }
        }
        let every = self.trace_every_rows();
        let trace = if every == 0 {
            Vec::new()
        } else {
            let mut t: Vec<TracePoint> = flight
                .log
                .iter()
                .step_by(every)
                .map(|r| TracePoint {
                    t_s: r.t_s,
                    output: r.output,
                })
                .take_while(|p| p.t_s.is_finite() && p.output.iter().all(|v| v.is_finite()))
                .collect();
            // kept until the end of the campaign: no spare capacity
            t.shrink_to_fit();
            t
        };
        RunOutput {
            record: RunRecord {
                index,
                wind_seed: draw.wind_seed,
                sensor_seed: draw.sensor_seed,
                values: draw.values,
                termination,
                reason,
                t_end_s: s.t_end_s,
                metrics: m,
            },
            trace,
        }
    }
}

/// A shard `K/M`: the runs with index ≡ K (mod M), K 0-based.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K, 0 ≤ K < M.
    pub k: usize,
    /// M ≥ 1.
    pub m: usize,
}

impl Shard {
    /// How many of the indices `0..runs` are in this shard.
    pub fn count(self, runs: usize) -> usize {
        if runs > self.k {
            (runs - self.k - 1) / self.m + 1
        } else {
            0
        }
    }

    /// The `j`-th index of the shard.
    pub fn index(self, j: usize) -> usize {
        self.k + j * self.m
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (k, m) = s
            .split_once('/')
            .ok_or_else(|| format!("shard `{s}`: expected K/M, e.g. 0/4"))?;
        let k: usize = k
            .trim()
            .parse()
            .map_err(|_| format!("shard `{s}`: K is not a whole number"))?;
        let m: usize = m
            .trim()
            .parse()
            .map_err(|_| format!("shard `{s}`: M is not a whole number"))?;
        if m == 0 || k >= m {
            return Err(format!("shard `{s}`: need 0 <= K < M (K is 0-based)"));
        }
        Ok(Shard { k, m })
    }
}

/// Options of [`run`].
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Override the campaign's number of runs (≥ 1).
    pub runs: Option<usize>,
    /// Worker threads (None: rayon's default, one per core).
    pub threads: Option<usize>,
    /// Only this shard.
    pub shard: Option<Shard>,
    /// Memory the campaign may use (bytes); None: [`memory_budget`].
    pub memory_budget_bytes: Option<u64>,
}

/// Progress callback: (runs done in this invocation, runs to do).
pub type McProgress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// What [`run`] and [`merge`](super::merge) report.
#[derive(Debug, Clone)]
pub struct McReport {
    /// Runs flown by this call.
    pub flown: usize,
    /// Runs found already done (resume) or merged.
    pub skipped: usize,
    /// The statistics written.
    pub stats: Stats,
}

/// The runs of `shard` (or all) among `0..runs` must fit in the budget.
fn check_memory(
    campaign: &Campaign,
    options: &RunOptions,
    runs_here: usize,
) -> Result<(), McError> {
    let (budget, available) = match options.memory_budget_bytes {
        Some(b) => (b, "the budget given".to_string()),
        None => memory_budget(),
    };
    let mem = campaign.run_memory();
    let threads = options
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1) as u64;
    let working = mem.bytes_per_flight.saturating_mul(threads);
    let max_runs = budget.saturating_sub(working) / mem.bytes_per_run.max(1);
    if runs_here as u64 > max_runs {
        return Err(McError::TooManyRuns {
            runs: runs_here,
            max_runs: usize::try_from(max_runs).unwrap_or(usize::MAX),
            bytes_per_run: mem.bytes_per_run,
            trace_points: mem.trace_points,
            working_mib: working >> 20,
            budget_mib: budget >> 20,
            available,
        });
    }
    Ok(())
}

/// The output of runs flown in this call, collected under one lock with
/// the appenders of the partial files.
struct Sink {
    runs: std::io::BufWriter<std::fs::File>,
    traces: std::io::BufWriter<std::fs::File>,
    records: BTreeMap<usize, RunRecord>,
    trace_map: BTreeMap<usize, Vec<TracePoint>>,
}

/// Run a campaign (or one shard of it) into `out`, skipping runs already
/// recorded there; writes every output and returns the statistics.
///
/// Checked before anything is flown: the number of runs against the memory
/// budget, the output folder (created, writable, of this campaign and
/// format) and the nominal design. A write that fails during the campaign
/// stops it: no further run is started, and the error is returned (the
/// runs recorded so far stay in the partial files for a resume).
#[allow(clippy::too_many_lines)] // one budget computation with its explanation; splitting scatters the arithmetic
pub fn run(
    campaign: &Campaign,
    options: &RunOptions,
    out: &Path,
    progress: Option<McProgress<'_>>,
) -> Result<McReport, McError> {
    let runs = options.runs.unwrap_or(campaign.runs);
    if runs == 0 {
        return Err(ScenarioError::Invalid {
            file: "run options".into(),
            field: "runs".into(),
            value: "0".into(),
            rule: "must be >= 1".into(),
        }
        .into());
    }
    let shard = options.shard.unwrap_or(Shard { k: 0, m: 1 });
    let runs_here = shard.count(runs);
    check_memory(campaign, options, runs_here)?;
    std::fs::create_dir_all(out).map_err(|e| io_err(out, "create the folder", e))?;
    check_manifest(out, &campaign.hash)?;
    let manifest = Manifest {
        format_version: FORMAT_VERSION,
        name: campaign.name.clone(),
        hash: campaign.hash.clone(),
        runs,
        seed: campaign.seed,
        shard: options.shard.map(|s| format!("{}/{}", s.k, s.m)),
        dispersed: campaign
            .dispersions
            .iter()
            .map(|d| d.param.clone())
            .collect(),
        overrides: campaign.overrides.clone(),
    };
    write_json(&out.join(MANIFEST), &manifest)?;
    write_file(&out.join(CAMPAIGN), &campaign.source)?;
    let scenario_toml = toml::to_string(&campaign.scenario).map_err(|e| McError::Serialize {
        file: out.join(SCENARIO).display().to_string(),
        message: e.to_string(),
    })?;
    write_file(&out.join(SCENARIO), &scenario_toml)?;
    write_file(&out.join(PARAMS), &campaign.nominal.to_toml())?;
    // resume: what is already there
    let mut done: BTreeMap<usize, RunRecord> = BTreeMap::new();
    for f in [RUNS, RUNS_PARTIAL] {
        for r in read_records(&out.join(f), &manifest.dispersed)? {
            done.insert(r.index, r);
        }
    }
    let mut traces = BTreeMap::new();
    read_traces_into(&out.join(TRACES), &mut traces, true)?;
    read_traces_into(&out.join(TRACES_PARTIAL), &mut traces, true)?;
    let skipped = done.len();
    // rewrite the partial files with everything known so far (drops torn lines)
    let rp = out.join(RUNS_PARTIAL);
    let tp = out.join(TRACES_PARTIAL);
    write_runs_csv(&rp, &manifest.dispersed, done.values())?;
    write_traces_csv(&tp, &traces)?;
    let open = |p: &Path| {
        std::fs::OpenOptions::new()
            .append(true)
            .open(p)
            .map(std::io::BufWriter::new)
            .map_err(|e| io_err(p, "write", e))
    };
    let sink = Mutex::new(Sink {
        runs: open(&rp)?,
        traces: open(&tp)?,
        records: BTreeMap::new(),
        trace_map: BTreeMap::new(),
    });
    let nominal = campaign.prepare_nominal()?;
    // each run's work is bounded as `helicon sim` bounds a flight's
    campaign.scenario.check_work(
        &format!("campaign `{}` scenario", campaign.name),
        nominal.gains.set.sample_time_s,
    )?;
    let total = runs_here
        - (0..runs_here)
            .filter(|&j| done.contains_key(&shard.index(j)))
            .count();
    let count = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let write_err: Mutex<Option<McError>> = Mutex::new(None);
    let work = || {
        (0..runs_here)
            .into_par_iter()
            .map(|j| shard.index(j))
            .filter(|i| !done.contains_key(i))
            .for_each(|i| {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let o = campaign.run_one(&nominal, i);
                let lines =
                    csv_line(&record_fields(&o.record)).map(|l| (l, trace_lines(i, &o.trace)));
                let res = match sink.lock() {
                    Ok(mut s) => lines.and_then(|(l, t)| {
                        s.runs
                            .write_all(l.as_bytes())
                            .and_then(|()| s.runs.flush())
                            .map_err(|e| io_err(&rp, "write", e))?;
                        s.traces
                            .write_all(t.as_bytes())
                            .and_then(|()| s.traces.flush())
                            .map_err(|e| io_err(&tp, "write", e))?;
                        s.records.insert(i, o.record);
                        s.trace_map.insert(i, o.trace);
                        Ok(())
                    }),
                    Err(_) => Err(McError::Threads("a worker panicked".into())),
                };
                if let Err(e) = res {
                    stop.store(true, Ordering::Relaxed);
                    if let Ok(mut slot) = write_err.lock()
                        && slot.is_none()
                    {
                        *slot = Some(e);
                    }
                    return;
                }
                let c = count.fetch_add(1, Ordering::Relaxed) + 1;
                if let Some(p) = progress {
                    p(c, total);
                }
            });
    };
    match options.threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t.max(1))
            .build()
            .map_err(|e| McError::Threads(e.to_string()))?
            .install(work),
        None => work(),
    }
    if let Some(e) = write_err.into_inner().ok().flatten() {
        return Err(e);
    }
    let sink = sink
        .into_inner()
        .map_err(|_| McError::Threads("a worker panicked".into()))?;
    let flown = sink.records.len();
    done.extend(sink.records);
    traces.extend(sink.trace_map);
    drop((sink.runs, sink.traces));
    let stats = finish(&manifest, &done, &traces, out)?;
    let _ = std::fs::remove_file(&rp);
    let _ = std::fs::remove_file(&tp);
    Ok(McReport {
        flown,
        skipped,
        stats,
    })
}
