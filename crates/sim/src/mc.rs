//! Monte Carlo campaigns: many closed-loop flights of one scenario with
//! dispersed model parameters, wind seeds and sensor seeds.
//!
//! # Campaign file (TOML)
//!
//! ```toml
//! name = "robustness-10"
//! runs = 1000                     # run indices 0..runs
//! seed = 2026                     # campaign seed
//! scenario = "robustness-scenario.toml"   # relative to this file, or an inline [scenario] table
//! design = "nominal"              # "nominal" (default) or "per-run"
//! disperse_wind_seed = true       # default true
//! disperse_sensor_seed = true     # default true
//! trace_rate_hz = 10.0            # outputs kept for the envelopes (0: none)
//!
//! [[dispersion]]
//! param = "body.mass_kg"          # any `helicon params` key, `section.key`
//! distribution = "normal"         # or "uniform"
//! kind = "relative"               # or "absolute"
//! sigma = 0.05                    # normal: standard deviation (fraction or SI)
//! truncate_sigma = 3.0            # normal: redraw beyond ±3σ (default 3; 0 = no truncation)
//!
//! [[dispersion]]
//! param = "main_rotor.omega_rad_s"
//! distribution = "uniform"
//! kind = "relative"
//! half_width = 0.1                # uniform on nominal·(1 ± 0.1)
//! ```
//!
//! # What one run is
//!
//! Run `i` draws everything from its own stream: `ChaCha8Rng` seeded with the
//! campaign seed and [`set_stream`](rand_chacha::ChaCha8Rng::set_stream)`(i)`.
//! In this order: the wind seed, the sensor seed (both always drawn, used
//! when dispersed), then one value per `[[dispersion]]` in file order. So a
//! run's result depends only on (campaign, i): bit-identical whatever the
//! thread count, the shard or the order runs finish.
//!
//! With `design = "nominal"` (the robustness question) the controller is
//! designed once, on the nominal parameters, and flown on each dispersed
//! plant; the flight starts at the dispersed plant's own trim at the design
//! point (as after a hover), so the integral action must find the new trim
//! inputs. With `design = "per-run"` each run trims, linearizes and designs on
//! its own parameters (how the design itself varies).
//!
//! A draw that breaks a parameter rule ([`Params::validate`], e.g. a negative
//! mass or `hinge_offset_m ≥ radius_m`) is **not redrawn**: the run is
//! recorded with outcome `invalid` and the rule as its reason, so the
//! reported distribution is the one written in the file. A trim or design
//! failure is outcome `error`; a divergence in flight is `diverged`. All
//! three count as failures.
//!
//! # Outputs (one folder)
//!
//! `campaign.toml` (the file as given), `manifest.json` (name, hash, runs),
//! `runs.csv` (one row per run, by index), `traces.csv` (vn, ve, vd, ψ of
//! every run at `trace_rate_hz`), `stats.json` / `stats.md` (p5/p50/p95 of
//! each metric over completed runs, failure fraction with reasons),
//! `hist_*.png` (metric histograms) and `envelope_*.png` (p5/p50/p95 of each
//! output over time). While running, finished runs are appended to
//! `runs.partial.csv` / `traces.partial.csv`; a rerun into the same folder
//! skips every run already recorded there (resume).
//!
//! # Sharding
//!
//! [`Shard`] `K/M` (0-based, `0 ≤ K < M`, as a Slurm array index) runs the
//! indices `i ≡ K (mod M)`; [`merge`] combines shard folders after checking
//! they hold the same campaign (the hash of everything that determines a
//! run's result: scenario, seed, design, dispersions; not `runs`).

use crate::closed_loop::{ClosedLoopError, Prepared, fly, fnv1a_hex, prepare_with_params};
use crate::plot::{LinePlot, PlotError, Series};
use crate::scenario::{OUTPUTS, Scenario, ScenarioError};
use helicon_model::Params;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{Model, ParamError};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Errors of a campaign (its file, its output folder, merging). A run that
/// fails is an outcome recorded in `runs.csv`, not an error.
#[derive(Debug, thiserror::Error)]
pub enum McError {
    /// A file could not be read or written.
    #[error("{file}: {message}")]
    Io {
        /// File.
        file: String,
        /// Message.
        message: String,
    },
    /// Invalid TOML or a field of the wrong type / unknown field.
    #[error("{file}: {message}")]
    Parse {
        /// File.
        file: String,
        /// Message (names the field).
        message: String,
    },
    /// A field out of range.
    #[error("{file}: `{field}` = {value}: {rule}")]
    Invalid {
        /// File.
        file: String,
        /// Field.
        field: String,
        /// Value as text.
        value: String,
        /// Rule.
        rule: String,
    },
    /// The base scenario.
    #[error("{0}")]
    Scenario(#[from] ScenarioError),
    /// The base parameters.
    #[error("{0}")]
    Params(#[from] ParamError),
    /// Preparing the nominal design.
    #[error("nominal design: {0}")]
    Prepare(#[from] ClosedLoopError),
    /// A results CSV that cannot be read back.
    #[error("{file}: line {line}: {message}")]
    Csv {
        /// File.
        file: String,
        /// Line (1-based).
        line: usize,
        /// Message.
        message: String,
    },
    /// Folders of different campaigns.
    #[error("{folder}: campaign hash {found} differs from {expected} (a different campaign)")]
    Mismatch {
        /// Folder.
        folder: String,
        /// Expected hash.
        expected: String,
        /// Hash found.
        found: String,
    },
    /// Two folders disagree on the same run.
    #[error("run {index} differs between {a} and {b}")]
    Conflict {
        /// Run index.
        index: usize,
        /// First folder.
        a: String,
        /// Second folder.
        b: String,
    },
    /// The thread pool could not be built.
    #[error("thread pool: {0}")]
    Threads(String),
    /// A plot.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// Probability distribution of a dispersion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DistributionKind {
    /// Gaussian with standard deviation `sigma` (optionally truncated).
    Normal,
    /// Uniform on ±`half_width`.
    Uniform,
}

/// How a draw modifies the nominal value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DispersionKind {
    /// value = nominal · (1 + d).
    Relative,
    /// value = nominal + d (SI units of the parameter).
    Absolute,
}

fn default_truncate() -> f64 {
    3.0
}

/// One `[[dispersion]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dispersion {
    /// Parameter key `section.key` (see `helicon params`).
    pub param: String,
    /// Distribution.
    pub distribution: DistributionKind,
    /// Relative or absolute.
    pub kind: DispersionKind,
    /// Standard deviation (normal).
    #[serde(default)]
    pub sigma: Option<f64>,
    /// Half width (uniform).
    #[serde(default)]
    pub half_width: Option<f64>,
    /// Normal only: redraw (same stream) beyond this many σ; 0 = untruncated.
    #[serde(default = "default_truncate")]
    pub truncate_sigma: f64,
}

/// Which parameters the controller is designed on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum DesignMode {
    /// Once, on the nominal parameters; flown on each dispersed plant.
    #[default]
    Nominal,
    /// Each run on its own dispersed parameters.
    PerRun,
}

fn yes() -> bool {
    true
}

fn default_trace_rate() -> f64 {
    10.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum ScenarioRef {
    Path(PathBuf),
    Inline(toml::Table),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct CampaignFile {
    #[serde(default)]
    name: Option<String>,
    runs: usize,
    seed: u64,
    scenario: ScenarioRef,
    #[serde(default)]
    design: DesignMode,
    #[serde(default = "yes")]
    disperse_wind_seed: bool,
    #[serde(default = "yes")]
    disperse_sensor_seed: bool,
    #[serde(default = "default_trace_rate")]
    trace_rate_hz: f64,
    #[serde(default)]
    dispersion: Vec<Dispersion>,
}

/// A loaded, validated campaign.
#[derive(Debug, Clone)]
pub struct Campaign {
    /// Name (defaults to the scenario's).
    pub name: String,
    /// Number of runs (indices `0..runs`).
    pub runs: usize,
    /// Campaign seed.
    pub seed: u64,
    /// The base scenario.
    pub scenario: Scenario,
    /// The nominal parameters (the scenario's parameter file, or the Bergen Twin).
    pub nominal: Params,
    /// Design mode.
    pub design: DesignMode,
    /// Give each run its own wind seed.
    pub disperse_wind_seed: bool,
    /// Give each run its own sensor seed.
    pub disperse_sensor_seed: bool,
    /// Rate of the kept output traces (Hz, 0 = none).
    pub trace_rate_hz: f64,
    /// Dispersions, in file order.
    pub dispersions: Vec<Dispersion>,
    /// The campaign file's text (copied into the output folder).
    pub source: String,
    /// Hash of everything that determines a run (not `runs`).
    pub hash: String,
}

/// Find a parameter by its `section.key`.
fn param_field(name: &str) -> Option<helicon_model::params::Field> {
    helicon_model::params::descriptors()
        .find(|d| {
            name.len() == d.section.len() + 1 + d.key.len()
                && name.starts_with(d.section)
                && name[d.section.len()..].starts_with('.')
                && name.ends_with(d.key)
        })
        .map(|d| d.field)
}

impl Campaign {
    /// Load a campaign file (the scenario path resolves against its folder).
    pub fn from_file(path: &Path) -> Result<Campaign, McError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| McError::Io {
            file: file.clone(),
            message: format!("cannot read: {e}"),
        })?;
        Self::from_toml_str(&text, &file, path.parent())
    }

    /// Parse campaign TOML; `file` names it in errors, `base_dir` resolves
    /// a scenario path.
    pub fn from_toml_str(
        text: &str,
        file: &str,
        base_dir: Option<&Path>,
    ) -> Result<Campaign, McError> {
        let raw: CampaignFile = toml::from_str(text).map_err(|e| McError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        let bad = |field: &str, value: String, rule: &str| McError::Invalid {
            file: file.to_string(),
            field: field.to_string(),
            value,
            rule: rule.to_string(),
        };
        let mut scenario = match &raw.scenario {
            ScenarioRef::Path(p) => {
                let full = match base_dir {
                    Some(b) if p.is_relative() => b.join(p),
                    _ => p.clone(),
                };
                Scenario::from_file(&full)?
            }
            ScenarioRef::Inline(t) => {
                let s = toml::to_string(t).map_err(|e| McError::Parse {
                    file: file.to_string(),
                    message: format!("[scenario]: {e}"),
                })?;
                let mut sc = Scenario::from_toml_str(&s, &format!("{file} [scenario]"))?;
                sc.base_dir = base_dir.map(Path::to_path_buf);
                sc
            }
        };
        let nominal = match &scenario.params {
            Some(p) => Params::from_file(&scenario.resolve(p))?,
            None => Params::bergen_twin(),
        };
        // the nominal parameters are what the runs use; make the scenario self-contained
        scenario.params = None;
        if !(raw.trace_rate_hz.is_finite() && raw.trace_rate_hz >= 0.0) {
            return Err(bad(
                "trace_rate_hz",
                raw.trace_rate_hz.to_string(),
                "must be finite and >= 0",
            ));
        }
        for (i, d) in raw.dispersion.iter().enumerate() {
            let at = |f: &str| format!("dispersion[{i}].{f}");
            if param_field(&d.param).is_none() {
                return Err(bad(
                    &at("param"),
                    d.param.clone(),
                    "not a parameter key (run `helicon params` for the list)",
                ));
            }
            let (width, wname, other) = match d.distribution {
                DistributionKind::Normal => (d.sigma, "sigma", d.half_width.map(|_| "half_width")),
                DistributionKind::Uniform => (d.half_width, "half_width", d.sigma.map(|_| "sigma")),
            };
            if let Some(o) = other {
                return Err(bad(
                    &at(o),
                    "given".into(),
                    &format!("not used by a {:?} distribution", d.distribution).to_lowercase(),
                ));
            }
            match width {
                None => {
                    return Err(bad(&at(wname), "missing".into(), "required"));
                }
                Some(w) if !(w.is_finite() && w >= 0.0) => {
                    return Err(bad(&at(wname), w.to_string(), "must be finite and >= 0"));
                }
                Some(_) => {}
            }
            if !(d.truncate_sigma.is_finite()
                && (d.truncate_sigma == 0.0 || d.truncate_sigma >= 0.5))
            {
                return Err(bad(
                    &at("truncate_sigma"),
                    d.truncate_sigma.to_string(),
                    "must be 0 (none) or >= 0.5",
                ));
            }
        }
        let name = raw.name.clone().unwrap_or_else(|| scenario.name.clone());
        let hash = campaign_hash(&raw, &scenario, &nominal);
        Ok(Campaign {
            name,
            runs: raw.runs,
            seed: raw.seed,
            scenario,
            nominal,
            design: raw.design,
            disperse_wind_seed: raw.disperse_wind_seed,
            disperse_sensor_seed: raw.disperse_sensor_seed,
            trace_rate_hz: raw.trace_rate_hz,
            dispersions: raw.dispersion,
            source: text.to_string(),
            hash,
        })
    }

    /// The draws of run `index`: seeds and dispersed values (pure; no flight).
    pub fn draw(&self, index: usize) -> Draw {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(index as u64);
        let wind_seed = rng.next_u64();
        let sensor_seed = rng.next_u64();
        let mut params = self.nominal;
        let mut values = Vec::with_capacity(self.dispersions.len());
        for d in &self.dispersions {
            let delta = match d.distribution {
                DistributionKind::Normal => {
                    let s = d.sigma.unwrap_or(0.0);
                    let mut z: f64 = StandardNormal.sample(&mut rng);
                    // bounded: P(|z| > 0.5) ≈ 0.62, so 64 tries fail with p < 1e-13
                    let mut tries = 0;
                    while d.truncate_sigma > 0.0 && z.abs() > d.truncate_sigma && tries < 64 {
                        z = StandardNormal.sample(&mut rng);
                        tries += 1;
                    }
                    if d.truncate_sigma > 0.0 {
                        z = z.clamp(-d.truncate_sigma, d.truncate_sigma);
                    }
                    s * z
                }
                DistributionKind::Uniform => {
                    let w = d.half_width.unwrap_or(0.0);
                    // 53 random bits → [0, 1)
                    let u = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
                    w * (2.0 * u - 1.0)
                }
            };
            let v = match param_field(&d.param) {
                Some(f) => {
                    let slot = f(&mut params);
                    *slot = match d.kind {
                        DispersionKind::Relative => *slot * (1.0 + delta),
                        DispersionKind::Absolute => *slot + delta,
                    };
                    *slot
                }
                None => f64::NAN,
            };
            values.push(v);
        }
        Draw {
            index,
            wind_seed: if self.disperse_wind_seed {
                wind_seed
            } else {
                self.scenario.wind.seed
            },
            sensor_seed: if self.disperse_sensor_seed {
                sensor_seed
            } else {
                self.scenario.sensors.seed
            },
            values,
            params,
        }
    }

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
                    let ts = s.sample_time_s;
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

fn campaign_hash(raw: &CampaignFile, scenario: &Scenario, nominal: &Params) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "seed={}", raw.seed);
    let _ = writeln!(s, "design={:?}", raw.design);
    let _ = writeln!(
        s,
        "seeds={} {}",
        raw.disperse_wind_seed, raw.disperse_sensor_seed
    );
    let _ = writeln!(s, "trace={}", raw.trace_rate_hz);
    for d in &raw.dispersion {
        let _ = writeln!(s, "{d:?}");
    }
    let _ = writeln!(
        s,
        "{}",
        toml::to_string(scenario).unwrap_or_else(|e| format!("{scenario:?} {e}"))
    );
    s.push_str(&nominal.to_toml());
    fnv1a_hex(&s)
}

/// The draws of one run.
#[derive(Debug, Clone)]
pub struct Draw {
    /// Run index.
    pub index: usize,
    /// Wind seed flown.
    pub wind_seed: u64,
    /// Sensor seed flown.
    pub sensor_seed: u64,
    /// Dispersed values, one per `[[dispersion]]`.
    pub values: Vec<f64>,
    /// The dispersed parameters (not yet validated).
    pub params: Params,
}

/// Metric columns of `runs.csv` (after the fixed columns and the dispersed values).
pub const METRIC_NAMES: [&str; 20] = [
    "vn_settling_s",
    "vn_overshoot_pct",
    "vn_rms",
    "vn_max_abs",
    "ve_settling_s",
    "ve_overshoot_pct",
    "ve_rms",
    "ve_max_abs",
    "vd_settling_s",
    "vd_overshoot_pct",
    "vd_rms",
    "vd_max_abs",
    "psi_settling_s",
    "psi_overshoot_pct",
    "psi_rms",
    "psi_max_abs",
    "effort_rms_S_col",
    "effort_rms_S_lat",
    "effort_rms_S_lon",
    "effort_rms_S_tr",
];

/// One row of `runs.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct RunRecord {
    /// Run index.
    pub index: usize,
    /// Wind seed.
    pub wind_seed: u64,
    /// Sensor seed.
    pub sensor_seed: u64,
    /// Dispersed values.
    pub values: Vec<f64>,
    /// `completed`, `diverged`, `invalid` (a draw broke a parameter rule) or
    /// `error` (trim / design failed).
    pub outcome: String,
    /// Why it failed (empty when completed).
    pub reason: String,
    /// Time reached (s).
    pub t_end_s: f64,
    /// Metrics in [`METRIC_NAMES`] order (`None`: not settled / not flown).
    pub metrics: Vec<Option<f64>>,
}

/// One kept sample of a run's outputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TracePoint {
    /// Time (s).
    pub t_s: f64,
    /// vn, ve, vd (m/s), ψ (rad).
    pub output: [f64; 4],
}

/// What a run produces.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// Its row.
    pub record: RunRecord,
    /// Its outputs at the trace rate.
    pub trace: Vec<TracePoint>,
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

const MANIFEST: &str = "manifest.json";
const RUNS: &str = "runs.csv";
const RUNS_PARTIAL: &str = "runs.partial.csv";
const TRACES: &str = "traces.csv";
const TRACES_PARTIAL: &str = "traces.partial.csv";

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Manifest {
    name: String,
    hash: String,
    runs: usize,
    seed: u64,
    shard: Option<String>,
    dispersed: Vec<String>,
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> McError {
    McError::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    }
}

fn write_file(path: &Path, text: &str) -> Result<(), McError> {
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

fn record_fields(r: &RunRecord) -> Vec<String> {
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

fn csv_line(fields: &[String]) -> Result<String, McError> {
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

fn trace_lines(index: usize, trace: &[TracePoint]) -> String {
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
fn read_records(path: &Path, ndisp: usize) -> Result<Vec<RunRecord>, McError> {
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

fn read_traces(path: &Path) -> Result<BTreeMap<usize, Vec<TracePoint>>, McError> {
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

fn check_manifest(dir: &Path, hash: &str) -> Result<Option<Manifest>, McError> {
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

/// Write `runs.csv`, `traces.csv`, statistics and plots from all records.
fn finish(
    manifest: &Manifest,
    records: &BTreeMap<usize, RunRecord>,
    traces: &BTreeMap<usize, Vec<TracePoint>>,
    out: &Path,
) -> Result<Stats, McError> {
    let mut text = csv_line(&csv_header(&manifest.dispersed))?;
    for r in records.values() {
        text.push_str(&csv_line(&record_fields(r))?);
    }
    write_file(&out.join(RUNS), &text)?;
    let mut t = String::from("index,t_s,vn,ve,vd,psi\n");
    for (k, v) in traces {
        t.push_str(&trace_lines(*k, v));
    }
    write_file(&out.join(TRACES), &t)?;
    let recs: Vec<&RunRecord> = records.values().collect();
    let stats = Stats::from_records(&manifest.name, &manifest.hash, &recs);
    write_file(
        &out.join("stats.json"),
        &serde_json::to_string_pretty(&stats).unwrap_or_default(),
    )?;
    write_file(&out.join("stats.md"), &stats.to_markdown())?;
    plots(&recs, traces, out)?;
    Ok(stats)
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

/// Percentiles of one metric over the completed runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MetricStats {
    /// Completed runs with a value (settling time: runs that settled).
    pub n: usize,
    /// 5th percentile.
    pub p5: Option<f64>,
    /// Median.
    pub p50: Option<f64>,
    /// 95th percentile.
    pub p95: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
}

/// Campaign statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stats {
    /// Campaign name.
    pub campaign: String,
    /// Campaign hash.
    pub hash: String,
    /// Runs recorded.
    pub runs: usize,
    /// Runs that flew the whole duration.
    pub completed: usize,
    /// Runs that did not (diverged, invalid draw, trim/design error).
    pub failed: usize,
    /// failed / runs.
    pub failure_fraction: f64,
    /// Failures by reason class (the reason without times and values).
    pub reasons: BTreeMap<String, usize>,
    /// Per metric, over completed runs.
    pub metrics: BTreeMap<String, MetricStats>,
}

/// Percentile (linear interpolation between order statistics, "type 7") of sorted data.
pub fn percentile(sorted: &[f64], p: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    Some(sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo]))
}

/// The class of a failure reason: the text before times and details, with
/// numbers replaced by `#` (so "body rate 10.02 rad/s beyond 10 rad/s" and
/// "body rate 10.04 …" count together).
pub fn reason_class(outcome: &str, reason: &str) -> String {
    let cut = [" at t = ", ": ", " ("]
        .iter()
        .filter_map(|p| reason.find(p))
        .min()
        .unwrap_or(reason.len());
    let mut head = String::with_capacity(cut);
    let mut in_number = false;
    for c in reason[..cut].trim().chars() {
        let numeric = c.is_ascii_digit() || (in_number && matches!(c, '.' | 'e' | '-' | '+'));
        if numeric {
            if !in_number {
                head.push('#');
            }
            in_number = true;
        } else {
            in_number = false;
            head.push(c);
        }
    }
    let head = head.replace("-#", "#").replace("+#", "#");
    let head = head.trim();
    if head.is_empty() {
        outcome.to_string()
    } else {
        format!("{outcome}: {head}")
    }
}

impl Stats {
    /// Statistics of records.
    pub fn from_records(name: &str, hash: &str, records: &[&RunRecord]) -> Stats {
        let runs = records.len();
        let completed: Vec<&&RunRecord> = records
            .iter()
            .filter(|r| r.outcome == "completed")
            .collect();
        let mut reasons = BTreeMap::new();
        for r in records.iter().filter(|r| r.outcome != "completed") {
            *reasons
                .entry(reason_class(&r.outcome, &r.reason))
                .or_insert(0) += 1;
        }
        let mut metrics = BTreeMap::new();
        for (j, m) in METRIC_NAMES.iter().enumerate() {
            let mut v: Vec<f64> = completed
                .iter()
                .filter_map(|r| r.metrics.get(j).copied().flatten())
                .filter(|v| v.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            let mean = if v.is_empty() {
                None
            } else {
                Some(v.iter().sum::<f64>() / v.len() as f64)
            };
            metrics.insert(
                (*m).to_string(),
                MetricStats {
                    n: v.len(),
                    p5: percentile(&v, 0.05),
                    p50: percentile(&v, 0.5),
                    p95: percentile(&v, 0.95),
                    mean,
                },
            );
        }
        let failed = runs - completed.len();
        Stats {
            campaign: name.to_string(),
            hash: hash.to_string(),
            runs,
            completed: completed.len(),
            failed,
            failure_fraction: if runs == 0 {
                0.0
            } else {
                failed as f64 / runs as f64
            },
            reasons,
            metrics,
        }
    }

    /// The statistics as a Markdown report.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Campaign `{}` ({})\n", self.campaign, self.hash);
        let _ = writeln!(
            s,
            "{} runs: {} completed, {} failed (failure fraction {:.3}).\n",
            self.runs, self.completed, self.failed, self.failure_fraction
        );
        if !self.reasons.is_empty() {
            let _ = writeln!(s, "| failure | runs |\n|---|---:|");
            for (k, v) in &self.reasons {
                let _ = writeln!(s, "| {k} | {v} |");
            }
            s.push('\n');
        }
        let _ = writeln!(
            s,
            "Over completed runs (settling: runs that settled, n):\n\n| metric | n | p5 | p50 | p95 |\n|---|---:|---:|---:|---:|"
        );
        let f = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{x:.4}"));
        for (k, m) in &self.metrics {
            let _ = writeln!(
                s,
                "| {k} | {} | {} | {} | {} |",
                m.n,
                f(m.p5),
                f(m.p50),
                f(m.p95)
            );
        }
        s
    }
}

fn plots(
    records: &[&RunRecord],
    traces: &BTreeMap<usize, Vec<TracePoint>>,
    out: &Path,
) -> Result<(), McError> {
    // histograms (as step outlines) of the rms and max errors and settling times
    for (j, m) in METRIC_NAMES.iter().enumerate() {
        if !(m.ends_with("_rms") || m.ends_with("_settling_s") || m.ends_with("_max_abs")) {
            continue;
        }
        let v: Vec<f64> = records
            .iter()
            .filter(|r| r.outcome == "completed")
            .filter_map(|r| r.metrics.get(j).copied().flatten())
            .filter(|v| v.is_finite())
            .collect();
        if v.len() < 2 {
            continue;
        }
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let bins = ((v.len() as f64).sqrt().ceil() as usize).clamp(5, 50);
        let w = if hi > lo {
            (hi - lo) / bins as f64
        } else {
            1.0
        };
        let mut counts = vec![0usize; bins];
        for x in &v {
            let b = (((x - lo) / w) as usize).min(bins - 1);
            counts[b] += 1;
        }
        let mut pts = vec![(lo, 0.0)];
        for (b, c) in counts.iter().enumerate() {
            let x0 = lo + b as f64 * w;
            pts.push((x0, *c as f64));
            pts.push((x0 + w, *c as f64));
        }
        pts.push((lo + bins as f64 * w, 0.0));
        LinePlot::new(&format!("{m} (completed runs)"), m, "runs")
            .series(Series::new(m, &pts))
            .write(&out.join(format!("hist_{m}.png")))?;
    }
    // envelopes: p5 / p50 / p95 over the runs at each trace time
    let Some(len) = traces.values().map(Vec::len).max() else {
        return Ok(());
    };
    if len < 2 {
        return Ok(());
    }
    let units = ["m/s", "m/s", "m/s", "rad"];
    for (o, name) in OUTPUTS.iter().enumerate() {
        let mut bands = [Vec::new(), Vec::new(), Vec::new()];
        for k in 0..len {
            let mut v: Vec<f64> = traces
                .values()
                .filter_map(|t| t.get(k).map(|p| p.output[o]))
                .filter(|v| v.is_finite())
                .collect();
            let t = traces
                .values()
                .find_map(|t| t.get(k).map(|p| p.t_s))
                .unwrap_or(0.0);
            v.sort_by(f64::total_cmp);
            for (b, p) in [0.05, 0.5, 0.95].iter().enumerate() {
                if let Some(x) = percentile(&v, *p) {
                    bands[b].push((t, x));
                }
            }
        }
        LinePlot::new(
            &format!("{name}: envelope over runs (runs still flying)"),
            "time [s]",
            &format!("{name} [{}]", units[o]),
        )
        .series(Series::new("p5", &bands[0]))
        .series(Series::new("p50", &bands[1]))
        .series(Series::new("p95", &bands[2]))
        .write(&out.join(format!("envelope_{name}.png")))?;
    }
    Ok(())
}
