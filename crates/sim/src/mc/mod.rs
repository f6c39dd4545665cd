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
//! trace_runs = 1000               # traces only for runs 0..1000 (default: all)
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
//! A `[[dispersion]]` may also name a wind key of the scenario
//! ([`WindKey`]: `wind.steady.north_m_s`, `wind.dryden.w20_m_s`, …). A
//! campaign whose scenario has `[ground]` carries each run's ground
//! metrics ([`GROUND_METRIC_NAMES`]) and judges its take-off and landing by
//! the `[landing]` table ([`LandingCriteria`]; defaults in
//! [`LandingSection::resolve`]): the failure rate with its Wilson interval
//! is `stats.json`'s `ground` ([`GroundStats`]).
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
//! Every run ends with a typed [`RunTermination`]: its [`RunOutcome`] and
//! its class, the `outcome` and `termination` columns of `runs.csv`. A draw that breaks a parameter rule
//! ([`Params`](helicon_model::Params)`::validate`, e.g. a negative mass or
//! `hinge_offset_m ≥ radius_m`) is **not redrawn**: the run is recorded
//! `invalid`, classed by the parameter key, with the rule as its reason, so
//! the reported distribution is the one written in the file. A trim, design
//! or flight-setup failure is `error`, classed by the failing
//! [`ErrorStage`]; a divergence in flight is `diverged`, classed by the
//! flight's [`Termination`](crate::closed_loop::Termination). All three count
//! as failures.
//!
//! # Outputs (one folder)
//!
//! `campaign.toml` (the file as given), `scenario.toml` and `params.toml`
//! (the effective base scenario and nominal parameters), `manifest.json`
//! (format version, name, hash, runs, command-line overrides),
//! `runs.csv` (one row per run, by index), `traces.csv` (vn, ve, vd, ψ of
//! every traced run at `trace_rate_hz`), `stats.json` / `stats.md`
//! (p5/p50/p95 of each metric over completed runs, failures by typed class),
//! `hist_*.png` (metric histograms) and `envelope_*.png` (p5/p50/p95 of each
//! output over time), and the run store `runs.bin` / `traces.bin` /
//! `reasons.bin` (one binary slot per run, written as each run finishes); a
//! rerun into the same folder skips every run already in the store
//! (resume). The formats are those of [`FORMAT_VERSION`].
//!
//! # Memory and disk
//!
//! Memory does not grow with the number of runs: each run goes to the
//! store on disk when it finishes, and the outputs are written from the
//! store in passes in index order, with the statistics' percentiles exact
//! (radix selection over the store, not an estimate). What grows is the
//! disk: [`run`] refuses more runs than the output folder's file system
//! holds at [`Campaign::footprint`] each ([`disk_budget`]). `trace_runs`
//! keeps traces only for the runs with a lower index.
//!
//! # Sharding
//!
//! [`Shard`] `K/M` (0-based, `0 ≤ K < M`, as a Slurm array index) runs the
//! indices `i ≡ K (mod M)`; [`merge`] combines shard folders after checking
//! they hold the same campaign (the hash of everything that determines a
//! run's result: scenario, seed, design, dispersions; not `runs`).

mod campaign;
mod draws;
mod landing;
mod record;
mod report;
mod runner;
mod select;
mod slots;
mod stats;
mod store;

pub use campaign::*;
pub use draws::*;
pub use landing::*;
pub use record::*;
pub use runner::*;
pub use stats::*;
pub use store::{FolderProgress, csv_header, folder_progress, merge};

use crate::closed_loop::ClosedLoopError;
use crate::plot::PlotError;
use crate::scenario::ScenarioError;
use helicon_model::ParamError;

/// Version of the output-folder formats (`manifest.json`, `runs.csv`,
/// `stats.json`). A folder of another version is refused by resume and merge.
///
/// * 1: `runs.csv` with `outcome, reason` as free text; `stats.json`
///   `reasons` keyed by the reason text with numbers replaced by `#`.
/// * 2: typed outcomes: `runs.csv` gains a `termination` column (after
///   `outcome`: the flight's termination, the invalid parameter key or the
///   failing stage); `stats.json` has `format_version` and `failures` (a list
///   of `{outcome, termination, runs}`) instead of `reasons`; `manifest.json`
///   has `format_version` and `overrides`; `params.toml` is written.
/// * 3: the run store (`runs.bin`, `traces.bin`, `reasons.bin`: one binary
///   slot per run, written as runs finish and read back in index order)
///   replaces `runs.partial.csv` / `traces.partial.csv`; `manifest.json` has
///   `trace_points` and `trace_runs`. `runs.csv`, `traces.csv`, `stats.json`
///   and `stats.md` keep their columns and fields (means are now
///   compensated sums in index order: they may differ from version 2's in
///   the last digit).
pub const FORMAT_VERSION: u32 = 3;

/// Errors of a campaign (its file, its output folder, merging). A run that
/// fails is an outcome recorded in `runs.csv`, not an error.
#[derive(Debug, thiserror::Error)]
pub enum McError {
    /// The campaign file or its scenario (invalid TOML, an unknown field or
    /// a field out of range), or a file that could not be read or written:
    /// the toolkit's one configuration error shape (file, field or action,
    /// the `io::Error` kept as source).
    #[error(transparent)]
    Config(#[from] ScenarioError),
    /// The nominal parameters (the scenario's `params` file or `--params`).
    #[error(transparent)]
    Params(#[from] ParamError),
    /// Preparing the nominal design.
    #[error("nominal design: {0}")]
    Prepare(#[from] ClosedLoopError),
    /// A results file (`runs.csv`, `traces.csv`, `manifest.json`) that
    /// cannot be read back.
    #[error("{file}: line {line}: {message}")]
    Csv {
        /// File.
        file: String,
        /// Line (1-based; 0: the file as a whole).
        line: usize,
        /// Message.
        message: String,
    },
    /// A folder written in another format version (see [`FORMAT_VERSION`]).
    #[error(
        "{folder}: results in format version {found}, this helicon reads and writes version {expected}: use a new output folder (or rerun the campaign there)"
    )]
    Format {
        /// Folder.
        folder: String,
        /// Version found (1: before versions were recorded).
        found: u32,
        /// Version of this build.
        expected: u32,
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
    /// `merge` without a folder.
    #[error("merge: give at least one shard folder")]
    NoFolders,
    /// More runs than the disk holds (the run store and the text outputs).
    #[error(
        "{runs} runs: at most {max_runs} fit on the disk this campaign may use ({budget_mib} MiB {available}), at {bytes_per_run} bytes per run (its record and {trace_points}-point trace in the run store, runs.csv and traces.csv); use shards (--shard K/M on several machines, then `helicon mc merge`), fewer runs, `trace_runs` or a lower trace_rate_hz"
    )]
    TooManyRuns {
        /// Runs asked for (in this shard).
        runs: usize,
        /// Runs that fit.
        max_runs: usize,
        /// Disk bytes per run (traced or not, on average).
        bytes_per_run: u64,
        /// Trace samples kept per traced run.
        trace_points: u64,
        /// Disk budget (MiB).
        budget_mib: u64,
        /// Where the budget comes from.
        available: String,
    },
    /// A slot of the run store that cannot be what it claims.
    #[error("{file}: slot {slot}: {message}")]
    Store {
        /// File.
        file: String,
        /// Slot (0-based).
        slot: usize,
        /// Message.
        message: String,
    },
    /// A statistic that is not a finite number (never written as `null`).
    #[error("{file}: `{field}` = {value} is not finite; nothing written")]
    NonFinite {
        /// File that would have held it.
        file: String,
        /// Field.
        field: String,
        /// Value.
        value: f64,
    },
    /// Serialising a results file failed.
    #[error("{file}: cannot serialise: {message}")]
    Serialize {
        /// File.
        file: String,
        /// Message.
        message: String,
    },
    /// The thread pool could not be built.
    #[error("thread pool: {0}")]
    Threads(String),
    /// A plot.
    #[error(transparent)]
    Plot(#[from] PlotError),
}
