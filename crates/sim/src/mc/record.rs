//! What one run produces: its `runs.csv` row and its trace.

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
