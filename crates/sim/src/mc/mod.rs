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

mod campaign;
mod draws;
mod record;
mod report;
mod runner;
mod stats;
mod store;

pub use campaign::*;
pub use draws::*;
pub use record::*;
pub use runner::*;
pub use stats::*;
pub use store::{csv_header, merge};

use crate::closed_loop::ClosedLoopError;
use crate::plot::PlotError;
use crate::scenario::ScenarioError;
use helicon_model::ParamError;

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
