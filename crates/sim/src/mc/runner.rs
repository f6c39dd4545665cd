//! Flying runs: one run, a whole campaign (threads, shards, resume).

use super::report::finish;
use super::store::{
    MANIFEST, Manifest, RUNS, RUNS_PARTIAL, TRACES, TRACES_PARTIAL, check_manifest, csv_header,
    csv_line, io_err, read_records, read_traces, record_fields, trace_lines, write_file,
};
use super::{Campaign, DesignMode, METRIC_NAMES, McError, RunOutput, RunRecord, Stats, TracePoint};
use crate::closed_loop::{ClosedLoopError, Prepared, fly, prepare_with_params};
use crate::scenario::OUTPUTS;
use helicon_model::Model;
use helicon_model::ParamError;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::Path;
use std::sync::Mutex;

impl Campaign {
    /// Design (or not) on the nominal parameters: what every run shares.
    pub fn prepare_nominal(&self) -> Result<Prepared, McError> {
        Ok(prepare_with_params(&self.scenario, self.nominal)?)
    }

    /// Fly run `index` (its draws, its flight, its record and trace).
    pub fn run_one(&self, nominal: &Prepared, index: usize) -> RunOutput {
        let draw = self.draw(index);
        let mut record = RunRecord {
            index,
            wind_seed: draw.wind_seed,
            sensor_seed: draw.sensor_seed,
            values: draw.values.clone(),
            outcome: String::new(),
            reason: String::new(),
            t_end_s: 0.0,
            metrics: vec![None; METRIC_NAMES.len()],
        };
        let mut trace = Vec::new();
        if let Err(e) = draw.params.validate(&format!("run {index}")) {
            record.outcome = "invalid".into();
            record.reason = match e {
                ParamError::Invalid {
                    key, value, rule, ..
                } => format!("invalid draw: {key} = {value}: {rule}"),
                other => format!("invalid draw: {other}"),
            };
            return RunOutput { record, trace };
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
                    .map(|t| Prepared {
                        model,
                        trim: t,
                        gains: nominal.gains.clone(),
                    })
                    .map_err(ClosedLoopError::from)
            }
        };
        let prepared = match prepared {
            Ok(p) => p,
            Err(e) => {
                record.outcome = "error".into();
                record.reason = e.to_string();
                return RunOutput { record, trace };
            }
        };
        match fly(&scenario, &prepared, None) {
            Err(e) => {
                record.outcome = "error".into();
                record.reason = e.to_string();
            }
            Ok(flight) => {
                let s = &flight.summary;
                record.outcome = match s.outcome {
                    crate::closed_loop::Outcome::Completed => "completed".into(),
                    crate::closed_loop::Outcome::Diverged => "diverged".into(),
                };
                record.reason = s.reason.clone().unwrap_or_default();
                record.t_end_s = s.t_end_s;
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
                record.metrics = m;
                if self.trace_rate_hz > 0.0 {
                    let ts = scenario.controller.design.sample_time_s;
                    let every = ((1.0 / (self.trace_rate_hz * ts)).round() as usize).max(1);
                    trace = flight
                        .log
                        .iter()
                        .step_by(every)
                        .map(|r| TracePoint {
                            t_s: r.t_s,
                            output: r.output,
                        })
                        .collect();
                }
            }
        }
        RunOutput { record, trace }
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
    /// Override the campaign's number of runs.
    pub runs: Option<usize>,
    /// Worker threads (None: rayon's default, one per core).
    pub threads: Option<usize>,
    /// Only this shard.
    pub shard: Option<Shard>,
}

/// Progress callback: (runs done in this invocation, runs to do).
pub type McProgress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// What [`run`] and [`merge`] report.
#[derive(Debug, Clone)]
pub struct McReport {
    /// Runs flown by this call.
    pub flown: usize,
    /// Runs found already done (resume) or merged.
    pub skipped: usize,
    /// The statistics written.
    pub stats: Stats,
}

/// Run a campaign (or one shard of it) into `out`, skipping runs already
/// recorded there; writes every output and returns the statistics.
pub fn run(
    campaign: &Campaign,
    options: &RunOptions,
    out: &Path,
    progress: Option<McProgress<'_>>,
) -> Result<McReport, McError> {
    let runs = options.runs.unwrap_or(campaign.runs);
    std::fs::create_dir_all(out).map_err(|e| io_err(out, e))?;
    check_manifest(out, &campaign.hash)?;
    let manifest = Manifest {
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
    };
    write_file(
        &out.join(MANIFEST),
        &serde_json::to_string_pretty(&manifest).unwrap_or_default(),
    )?;
    write_file(&out.join("campaign.toml"), &campaign.source)?;
    write_file(
        &out.join("scenario.toml"),
        &toml::to_string(&campaign.scenario).map_err(|e| io_err(&out.join("scenario.toml"), e))?,
    )?;
    let nd = campaign.dispersions.len();
    // resume: what is already there
    let mut done: BTreeMap<usize, RunRecord> = BTreeMap::new();
    for f in [RUNS, RUNS_PARTIAL] {
        for r in read_records(&out.join(f), nd)? {
            done.insert(r.index, r);
        }
    }
    let mut traces = read_traces(&out.join(TRACES))?;
    for (k, v) in read_traces(&out.join(TRACES_PARTIAL))? {
        traces.insert(k, v);
    }
    let todo: Vec<usize> = (0..runs)
        .filter(|i| options.shard.is_none_or(|s| i % s.m == s.k))
        .filter(|i| !done.contains_key(i))
        .collect();
    let skipped = done.len();
    // rewrite the partial files with everything known so far (drops torn lines)
    let header = csv_line(&csv_header(&manifest.dispersed))?;
    let rp = out.join(RUNS_PARTIAL);
    let tp = out.join(TRACES_PARTIAL);
    let mut rtext = header.clone();
    for r in done.values() {
        rtext.push_str(&csv_line(&record_fields(r))?);
    }
    write_file(&rp, &rtext)?;
    let mut ttext = String::from("index,t_s,vn,ve,vd,psi\n");
    for (k, v) in &traces {
        ttext.push_str(&trace_lines(*k, v));
    }
    write_file(&tp, &ttext)?;
    let open = |p: &Path| {
        std::fs::OpenOptions::new()
            .append(true)
            .open(p)
            .map(std::io::BufWriter::new)
            .map_err(|e| io_err(p, e))
    };
    let writers = Mutex::new((open(&rp)?, open(&tp)?, Vec::<RunOutput>::new()));
    let nominal = campaign.prepare_nominal()?;
    let total = todo.len();
    let count = std::sync::atomic::AtomicUsize::new(0);
    let write_err: Mutex<Option<McError>> = Mutex::new(None);
    let work = || {
        todo.par_iter().for_each(|&i| {
            let o = campaign.run_one(&nominal, i);
            let lines = csv_line(&record_fields(&o.record)).map(|l| (l, trace_lines(i, &o.trace)));
            if let Ok(mut w) = writers.lock() {
                let res = lines.and_then(|(l, t)| {
                    w.0.write_all(l.as_bytes()).map_err(|e| io_err(&rp, e))?;
                    w.0.flush().map_err(|e| io_err(&rp, e))?;
                    w.1.write_all(t.as_bytes()).map_err(|e| io_err(&tp, e))?;
                    w.1.flush().map_err(|e| io_err(&tp, e))
                });
                if let Err(e) = res
                    && let Ok(mut slot) = write_err.lock()
                    && slot.is_none()
                {
                    *slot = Some(e);
                }
                w.2.push(o);
            }
            let c = count.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
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
    let (rw, tw, outputs) = writers
        .into_inner()
        .map_err(|_| McError::Threads("a worker panicked".into()))?;
    drop((rw, tw));
    let flown = outputs.len();
    for o in outputs {
        traces.insert(o.record.index, o.trace);
        done.insert(o.record.index, o.record);
    }
    let stats = finish(&manifest, &done, &traces, out)?;
    let _ = std::fs::remove_file(&rp);
    let _ = std::fs::remove_file(&tp);
    Ok(McReport {
        flown,
        skipped,
        stats,
    })
}
