//! Flying runs: one run, a whole campaign (threads, shards, resume), and the
//! disk bound on the number of runs.

use super::report::finish;
use super::slots::{Layout, Slot, Store};
use super::store::{
    CAMPAIGN, MANIFEST, Manifest, PARAMS, SCENARIO, check_manifest, io_err, write_file, write_json,
};
use super::{
    Campaign, DesignMode, ErrorStage, FORMAT_VERSION, GROUND_METRIC_NAMES, McError, RunOutput,
    RunRecord, RunTermination, Stats, TracePoint, WindKey, ground_values, metric_count,
    metric_names,
};
use crate::closed_loop::{
    ClosedLoopError, LogRow, ParameterHash, Prepared, Termination, fly, prepare_with_params,
};
use crate::scenario::{OUTPUTS, ScenarioError};
use helicon_model::Model;
use helicon_model::ParamError;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// What a campaign needs per run and per flight, from its scenario, trace
/// rate and `trace_runs`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunFootprint {
    /// Trace samples a traced run keeps (an upper bound).
    pub trace_points: u64,
    /// Bytes on disk per traced run: its slot and trace slot in the run
    /// store and its rows of `runs.csv` and `traces.csv` (an estimate of
    /// the text, at 26 bytes a number).
    pub disk_bytes_per_traced_run: u64,
    /// Bytes on disk per run without a trace.
    pub disk_bytes_per_run: u64,
    /// Bytes of memory of one flight in progress (its full log); a campaign
    /// holds one per thread, whatever its number of runs.
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

    /// Does run `index` keep a trace (`trace_rate_hz > 0` and, with
    /// `trace_runs`, an index below it)?
    pub fn traced(&self, index: usize) -> bool {
        self.trace_every_rows() > 0 && self.trace_runs.is_none_or(|n| index < n)
    }

    /// The disk and memory a campaign needs (upper bounds, from the sizes
    /// of the slots and types).
    pub fn footprint(&self) -> RunFootprint {
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
        let layout = self.layout(Shard { k: 0, m: 1 });
        // the metrics and, with [ground], the `landing` column
        let ground = self.landing.is_some();
        let numbers =
            (4 + self.dispersions.len() + metric_count(ground) + usize::from(ground)) as u64;
        let run_slot = layout.bytes_per_run() - 40 * trace_points;
        let disk_bytes_per_run = run_slot + 26 * numbers + 60;
        let disk_bytes_per_traced_run = disk_bytes_per_run + trace_points * (40 + 6 * 26);
        let bytes_per_flight = (rows as u64).saturating_mul(std::mem::size_of::<LogRow>() as u64);
        RunFootprint {
            trace_points,
            disk_bytes_per_traced_run,
            disk_bytes_per_run,
            bytes_per_flight,
        }
    }

    /// The run store layout of a shard of this campaign.
    pub(super) fn layout(&self, shard: Shard) -> Layout {
        let ts = self.nominal.control.sample_time_s;
        let samples = (self.scenario.duration_s / ts).round() + 1.0;
        let d = self.scenario.log.decimation.max(1) as f64;
        let rows = (samples / d).ceil() + 1.0;
        let every = self.trace_every_rows();
        let trace_points = if every == 0 {
            0
        } else {
            (rows / every as f64).ceil() as usize
        };
        Layout {
            dispersions: self.dispersions.len(),
            trace_points,
            k: shard.k,
            m: shard.m,
            trace_runs: self.trace_runs.unwrap_or(usize::MAX),
            ground: self.landing.is_some(),
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
        let ground = self.landing.is_some();
        let not_flown = |termination: RunTermination, reason: String| RunOutput {
            record: RunRecord {
                index,
                wind_seed: draw.wind_seed,
                sensor_seed: draw.sensor_seed,
                values: draw.values.clone(),
                termination,
                reason,
                t_end_s: 0.0,
                metrics: vec![None; metric_count(ground)],
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
        if let Err(e) = crate::wind::Wind::from_config(&draw.wind) {
            let key = match &e {
                helicon_model::ConfigError::Invalid { field, .. } => {
                    WindKey::parse(&format!("wind.{field}"))
                }
                _ => None,
            };
            return match key {
                Some(k) => not_flown(
                    RunTermination::InvalidDraw(k.key().to_string()),
                    format!("invalid draw: {e}"),
                ),
                None => not_flown(
                    RunTermination::Error(ErrorStage::Parameters),
                    format!("checking the drawn wind: {e}"),
                ),
            };
        }
        let mut scenario = self.scenario.clone();
        scenario.wind = draw.wind.clone();
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
                        parameter_hash: ParameterHash::default(),
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
        let mut m = Vec::with_capacity(metric_count(ground));
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
        if ground {
            match &s.ground {
                Some(g) => m.extend(ground_values(g)),
                None => m.extend([None; GROUND_METRIC_NAMES.len()]),
            }
        }
        let mut termination = RunTermination::Flight(s.termination);
        let mut reason = s.reason.clone().unwrap_or_default();
        let mut bad = Vec::new();
        for (v, name) in m.iter_mut().zip(metric_names(ground)) {
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
        let trace = if every == 0 || !self.traced(index) {
            Vec::new()
        } else {
            let t: Vec<TracePoint> = flight
                .log
                .iter()
                .step_by(every)
                .map(|r| TracePoint {
                    t_s: r.t_s,
                    output: r.output,
                })
                .take_while(|p| p.t_s.is_finite() && p.output.iter().all(|v| v.is_finite()))
                .collect();
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
    /// Disk space the campaign may use (bytes); None: the free space of the
    /// output folder's file system ([`disk_budget`]).
    pub disk_budget_bytes: Option<u64>,
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

/// The free space (bytes) of the file system that will hold `out` (its
/// nearest existing folder), and where the figure comes from.
pub fn disk_budget(out: &Path) -> (u64, String) {
    let mut p = if out.is_absolute() {
        out.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(out))
            .unwrap_or_else(|_| out.to_path_buf())
    };
    loop {
        if p.is_dir() {
            break;
        }
        if !p.pop() {
            break;
        }
    }
    match rustix::fs::statvfs(&p) {
        Ok(s) => {
            let b = s.f_bavail.saturating_mul(s.f_frsize);
            (b, format!("free on the file system of {}", p.display()))
        }
        Err(_) => (
            u64::MAX,
            "unbounded: the free space could not be read".into(),
        ),
    }
}

/// The runs of `shard` (or all) among `0..runs` must fit on the disk.
fn check_disk(
    campaign: &Campaign,
    options: &RunOptions,
    runs: usize,
    shard: Shard,
    out: &Path,
) -> Result<(), McError> {
    let (budget, available) = match options.disk_budget_bytes {
        Some(b) => (b, "the budget given".to_string()),
        None => disk_budget(out),
    };
    let f = campaign.footprint();
    let runs_here = shard.count(runs) as u64;
    let traced = campaign
        .trace_runs
        .map_or(runs_here, |n| shard.count(n.min(runs)) as u64);
    let traced = if f.trace_points == 0 { 0 } else { traced };
    let need = traced
        .saturating_mul(f.disk_bytes_per_traced_run)
        .saturating_add((runs_here - traced).saturating_mul(f.disk_bytes_per_run));
    if need > budget {
        let per = need / runs_here.max(1);
        return Err(McError::TooManyRuns {
            runs: shard.count(runs),
            max_runs: usize::try_from(budget / per.max(1)).unwrap_or(usize::MAX),
            bytes_per_run: per,
            trace_points: f.trace_points,
            budget_mib: budget >> 20,
            available,
        });
    }
    Ok(())
}

/// Run a campaign (or one shard of it) into `out`, skipping runs already
/// recorded there; writes every output and returns the statistics.
///
/// Checked before anything is flown: the number of runs against the disk
/// budget, the output folder (created, writable, of this campaign and
/// format) and the nominal design. Each finished run goes to the run store
/// at once (any thread, any order); memory does not grow with the number of
/// runs. A write that fails during the campaign stops it: no further run is
/// started, and the error is returned (the runs stored so far stay for a
/// resume).
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
    check_disk(campaign, options, runs, shard, out)?;
    std::fs::create_dir_all(out).map_err(|e| io_err(out, "create the folder", e))?;
    check_manifest(out, &campaign.hash)?;
    let layout = campaign.layout(shard);
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
        trace_points: layout.trace_points,
        trace_runs: campaign.trace_runs,
        landing: campaign.landing,
    };
    write_json(&out.join(MANIFEST), &manifest)?;
    write_file(&out.join(CAMPAIGN), &campaign.source)?;
    let scenario_toml = toml::to_string(&campaign.scenario).map_err(|e| McError::Serialize {
        file: out.join(SCENARIO).display().to_string(),
        message: e.to_string(),
    })?;
    write_file(&out.join(SCENARIO), &scenario_toml)?;
    write_file(&out.join(PARAMS), &campaign.nominal.to_toml())?;
    let store = Store::open(out, layout, true)?;
    // resume: the runs already in the store (read again, never collected)
    let mut buf = Vec::new();
    let mut skipped = 0;
    for j in 0..runs_here.min(store.slots()?) {
        if matches!(store.get(j, &mut buf)?, Slot::Run(..)) {
            skipped += 1;
        }
    }
    let nominal = campaign.prepare_nominal()?;
    // each run's work is bounded as `helicon sim` bounds a flight's
    campaign.scenario.check_work(
        &format!("campaign `{}` scenario", campaign.name),
        nominal.gains.set.sample_time_s,
    )?;
    let total = runs_here - skipped;
    let count = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let first_err: Mutex<Option<McError>> = Mutex::new(None);
    let fail = |e: McError| {
        stop.store(true, Ordering::Relaxed);
        if let Ok(mut slot) = first_err.lock()
            && slot.is_none()
        {
            *slot = Some(e);
        }
    };
    let work = || {
        (0..runs_here)
            .into_par_iter()
            .for_each_init(Vec::new, |buf, j| {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                match store.get(j, buf) {
                    Ok(Slot::Run(..)) => return,
                    Ok(Slot::Empty) => {}
                    Err(e) => return fail(e),
                }
                let o = campaign.run_one(&nominal, shard.index(j));
                if let Err(e) = store.put(j, &o.record, &o.trace) {
                    return fail(e);
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
    if let Some(e) = first_err.into_inner().ok().flatten() {
        return Err(e);
    }
    store.sync()?;
    let stats = finish(&manifest, &store, out)?;
    Ok(McReport {
        flown: count.into_inner(),
        skipped,
        stats,
    })
}
