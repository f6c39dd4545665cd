//! How a flight ended and how well it flew: [`Outcome`], [`Termination`],
//! the [`Summary`] and the bounded [`SummaryAccumulator`] it is computed from.

use super::*;

/// How a flight ended, in one word.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    /// Flew the whole duration.
    Completed,
    /// Stopped early (see the termination and the reason).
    Diverged,
    /// Stopped before the end on request (a signal to `helicon sim` or
    /// `helicon sitl`): what was flown is kept, whole.
    Stopped,
}

impl Outcome {
    /// The word written in `summary.json` and `runs.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Completed => "completed",
            Outcome::Diverged => "diverged",
            Outcome::Stopped => "stopped",
        }
    }
}

/// Why a flight ended: the machine-readable kind (`"termination"` in
/// `summary.json`); the `reason` next to it is the sentence with times and values.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// Flew the whole duration.
    Completed,
    /// The true state became NaN or infinite.
    NonFiniteState,
    /// Roll or pitch beyond `[plant] max_attitude_rad`.
    AttitudeLimit,
    /// A body rate beyond `[plant] max_rate_rad_s`.
    RateLimit,
    /// The heading left its reference by more than `[plant] max_yaw_error_rad`.
    HeadingLost,
    /// The plant model failed to evaluate (e.g. the inflow did not converge).
    ModelFailure,
    /// The on-board navigation or estimator failed.
    NavigationFailure,
    /// Stopped on request before the end (a signal): not a divergence.
    Stopped,
}

impl Termination {
    /// Every kind, in declaration order.
    pub const ALL: [Termination; 8] = [
        Termination::Completed,
        Termination::NonFiniteState,
        Termination::AttitudeLimit,
        Termination::RateLimit,
        Termination::HeadingLost,
        Termination::ModelFailure,
        Termination::NavigationFailure,
        Termination::Stopped,
    ];

    /// The flight's outcome for this termination.
    pub fn outcome(self) -> Outcome {
        match self {
            Termination::Completed => Outcome::Completed,
            Termination::Stopped => Outcome::Stopped,
            _ => Outcome::Diverged,
        }
    }

    /// The snake_case name written in files.
    pub fn as_str(self) -> &'static str {
        match self {
            Termination::Completed => "completed",
            Termination::NonFiniteState => "non_finite_state",
            Termination::AttitudeLimit => "attitude_limit",
            Termination::RateLimit => "rate_limit",
            Termination::HeadingLost => "heading_lost",
            Termination::ModelFailure => "model_failure",
            Termination::NavigationFailure => "navigation_failure",
            Termination::Stopped => "stopped",
        }
    }
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Termination {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Termination::ALL
            .into_iter()
            .find(|t| t.as_str() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Termination::ALL.iter().map(|t| t.as_str()).collect();
                format!("unknown termination `{s}` (one of {})", names.join(", "))
            })
    }
}

/// Summary of a flight.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// "completed", "diverged" or "stopped".
    pub outcome: Outcome,
    /// Why it ended, machine-readable (`completed`, `attitude_limit`, …).
    pub termination: Termination,
    /// Why it stopped early, as a sentence (None when completed).
    pub reason: Option<String>,
    /// Time reached (s).
    pub t_end_s: f64,
    /// Metrics per output `vn`, `ve`, `vd`, `psi`.
    pub metrics: std::collections::BTreeMap<String, OutputMetrics>,
    /// RMS of u − u_trim per input.
    pub control_effort_rms: [f64; 4],
    /// Time each input spent saturated (s).
    pub saturation_time_s: [f64; 4],
    /// RMS estimation error of the nine measured states (truth − estimate).
    pub estimator_error_rms: [f64; 9],
    /// Model preset.
    pub preset: String,
    /// Wind seed.
    pub wind_seed: u64,
    /// Sensor seed.
    pub sensor_seed: u64,
    /// FNV-1a hash of the effective parameter TOML.
    pub parameter_hash: String,
    /// helicon version.
    pub version: String,
    /// The flight software's sample time (s): the helicopter's `control.sample_time_s`.
    pub sample_time_s: f64,
    /// The settling metrics used every `metrics_stride`-th kept log row (1
    /// unless the flight outgrew [`METRIC_TRACE_CAP`] rows).
    pub metrics_stride: usize,
    /// Closed-loop poles of the design: largest |z|.
    pub design_spectral_radius: f64,
    /// Pincer α of the design.
    pub design_alpha: f64,
    /// Take-off and landing metrics (`[ground]` scenarios only; not written
    /// otherwise, so the summaries of other flights are unchanged).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground: Option<crate::ground::GroundMetrics>,
}

/// Make a heading-error sequence continuous (no 2π jumps) and shift it by the
/// multiple of 2π that brings its final value nearest zero, so a turn through
/// π in either direction is measured the way the helicopter actually went.
fn unwrap_heading_error(e: &mut [f64]) {
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut prev: Option<f64> = None;
    for v in e.iter_mut() {
        let w = wrap_pi(*v);
        *v = match prev {
            None => w,
            Some(p) => p + wrap_pi(w - p),
        };
        prev = Some(*v);
    }
    if let Some(&last) = e.last() {
        let shift = two_pi * (last / two_pi).round();
        for v in e.iter_mut() {
            *v -= shift;
        }
    }
}

/// What the summary needs from the kept log rows, gathered as they are
/// flown so that its memory does not grow with the duration: sums for the
/// RMS figures (every row) and the output errors and references for the
/// settling metrics, kept for every row up to [`METRIC_TRACE_CAP`] rows and
/// thinned evenly beyond (every second row dropped, the stride doubled).
#[derive(Debug, Clone)]
pub struct SummaryAccumulator {
    rows: usize,
    effort: [f64; 4],
    saturated_rows: [usize; 4],
    estimator: [f64; 9],
    u_trim: Input,
    s_min: [f64; 4],
    s_max: [f64; 4],
    stride: usize,
    cap: usize,
    trace_t: Vec<f64>,
    trace_e: [Vec<f64>; 4],
    trace_r: [Vec<f64>; 4],
}

/// The number of rows of output errors and references the summary keeps in
/// memory (each 72 bytes): 2¹⁹ rows, 38 MB, every row of a 1310 s flight at
/// 400 Hz.
pub const METRIC_TRACE_CAP: usize = 1 << 19;

impl SummaryAccumulator {
    pub(super) fn new(prepared: &Prepared) -> Self {
        let servos = prepared.model.params().servos;
        SummaryAccumulator {
            rows: 0,
            effort: [0.0; 4],
            saturated_rows: [0; 4],
            estimator: [0.0; 9],
            u_trim: prepared.gains.set.u_trim,
            s_min: servos.map(|s| s.s_min),
            s_max: servos.map(|s| s.s_max),
            stride: 1,
            cap: METRIC_TRACE_CAP,
            trace_t: Vec::new(),
            trace_e: Default::default(),
            trace_r: Default::default(),
        }
    }

    pub(super) fn push(&mut self, r: &LogRow) {
        for i in 0..4 {
            self.effort[i] += (r.u[i] - self.u_trim[i]).powi(2);
            if r.u[i] <= self.s_min[i] + 1e-12 || r.u[i] >= self.s_max[i] - 1e-12 {
                self.saturated_rows[i] += 1;
            }
        }
        for i in 0..9 {
            let mut d = r.x[i + REDUCED_OFFSET] - r.estimate9[i];
            if i == 2 {
                d = wrap_pi(d);
            }
            self.estimator[i] += d * d;
        }
        if self.rows % self.stride == 0 {
            if self.trace_t.len() == self.cap {
                self.thin();
            }
            if self.rows % self.stride == 0 {
                self.trace_t.push(r.t_s);
                for j in 0..4 {
                    self.trace_e[j].push(r.reference[j] - r.output[j]);
                    self.trace_r[j].push(r.reference[j]);
                }
            }
        }
        self.rows += 1;
    }

    /// Drop every second kept row and double the stride.
    fn thin(&mut self) {
        let keep = |v: &mut Vec<f64>| {
            let mut i = 0;
            v.retain(|_| {
                i += 1;
                (i - 1) % 2 == 0
            });
        };
        keep(&mut self.trace_t);
        for e in self.trace_e.iter_mut().chain(&mut self.trace_r) {
            keep(e);
        }
        self.stride *= 2;
    }

    /// The output errors kept: one every `stride()` rows.
    pub fn stride(&self) -> usize {
        self.stride
    }
}

pub(super) fn summarize(
    scenario: &Scenario,
    prepared: &Prepared,
    acc: &SummaryAccumulator,
    reason: Option<(Termination, String)>,
    t_end: f64,
) -> Summary {
    let termination = reason.as_ref().map_or(Termination::Completed, |r| r.0);
    let reason = reason.map(|r| r.1);
    let t = &acc.trace_t;
    let mut metrics = std::collections::BTreeMap::new();
    let mut excitations = Vec::with_capacity(4);
    for (j, name) in OUTPUTS.iter().enumerate() {
        let mut e: Vec<f64> = acc.trace_e[j].clone();
        if j == 3 {
            unwrap_heading_error(&mut e);
        }
        // heading statistics on the wrapped error (a half turn either way is the same heading)
        let wrapped: Option<Vec<f64>> = (j == 3).then(|| e.iter().map(|v| wrap_pi(*v)).collect());
        // excitation: the last reference change on this output, else the initial error
        let mut t_exc = 0.0;
        // a heading error is its size within ±π (2π − 1 rad is a 1 rad error)
        let size_of = |d: f64| if j == 3 { wrap_pi(d).abs() } else { d.abs() };
        let mut size = e.first().map_or(0.0, |v| size_of(*v));
        let mut changes: Vec<_> = scenario
            .reference
            .iter()
            .filter(|c| c.output == *name && c.t_s <= t_end)
            .collect();
        changes.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        if let Some(c) = changes.last() {
            let before = scenario.reference_at(c.t_s - 1e-9)[j];
            t_exc = c.t_s + c.ramp_s;
            size = size_of(c.value - before);
        } else if let Some((_, t_end_move, moved)) =
            crate::metrics::last_reference_move(t, &acc.trace_r[j], j == 3)
        {
            // a reference shaped in flight (a trajectory, a mission): its
            // last move as flown
            t_exc = t_end_move;
            size = moved;
        }
        excitations.push((e, t_exc, size, wrapped));
    }
    let band_scale = excitations.iter().fold(0.0f64, |m, x| m.max(x.2));
    for (name, (e, t_exc, size, wrapped)) in OUTPUTS.iter().zip(excitations) {
        let mut m = output_metrics(t, &e, t_exc, size, band_scale);
        if let Some(w) = wrapped {
            let stats = output_metrics(t, &w, t_exc, size, band_scale);
            m.rms_error = stats.rms_error;
            m.max_abs_error = stats.max_abs_error;
            // settled within ±π of the reference: the same heading
            if m.settling_time_s.is_none() {
                m.settling_time_s = stats.settling_time_s;
            }
        }
        if reason.is_some() {
            // a run that stopped early never settled
            m.settling_time_s = None;
        }
        metrics.insert((*name).to_string(), m);
    }
    let nrow = acc.rows.max(1) as f64;
    let ts = prepared.gains.set.sample_time_s;
    let row_s = ts * scenario.log.decimation.max(1) as f64;
    let sat = acc.saturated_rows.map(|n| n as f64 * row_s);
    let effort = acc.effort;
    let est = acc.estimator;
    let rho = prepared.gains.spectral_radius();
    Summary {
        scenario: scenario.name.clone(),
        outcome: termination.outcome(),
        termination,
        reason,
        t_end_s: t_end,
        metrics,
        control_effort_rms: effort.map(|v| (v / nrow).sqrt()),
        saturation_time_s: sat,
        estimator_error_rms: est.map(|v| (v / nrow).sqrt()),
        preset: scenario.preset.name().to_string(),
        wind_seed: scenario.wind.seed,
        sensor_seed: scenario.sensors.seed,
        parameter_hash: prepared.parameter_hash.of(prepared.model.params()),
        version: env!("CARGO_PKG_VERSION").to_string(),
        sample_time_s: ts,
        metrics_stride: acc.stride,
        design_spectral_radius: rho,
        design_alpha: prepared.gains.set.alpha,
        ground: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(k: usize) -> LogRow {
        LogRow {
            t_s: k as f64,
            x: State::zeros(),
            u: Input::zeros(),
            reference: [k as f64, 0.0, 0.0, 0.0],
            output: [0.0; 4],
            estimate9: [0.0; 9],
            measured9: [0.0; 9],
            wind_ned: [0.0; 3],
            lambda: [0.0; 2],
            thrust: [0.0; 2],
            inflow_residual: [0.0; 2],
            imu_health: [0.0; 3],
            excitation: [0.0; 4],
        }
    }

    #[test]
    fn metric_trace_is_bounded_and_evenly_thinned() {
        let mut acc = SummaryAccumulator {
            rows: 0,
            effort: [0.0; 4],
            saturated_rows: [0; 4],
            estimator: [0.0; 9],
            u_trim: Input::zeros(),
            s_min: [-1.0; 4],
            s_max: [1.0; 4],
            stride: 1,
            cap: 8,
            trace_t: Vec::new(),
            trace_e: Default::default(),
            trace_r: Default::default(),
        };
        for k in 0..100 {
            acc.push(&row(k));
            assert!(acc.trace_t.len() <= 8);
        }
        // 100 rows into 8 slots: stride 16, rows 0, 16, …, 96 kept
        assert_eq!(acc.stride(), 16);
        assert_eq!(acc.trace_t, [0.0, 16.0, 32.0, 48.0, 64.0, 80.0, 96.0]);
        assert_eq!(acc.trace_e[0], acc.trace_t);
        assert_eq!(acc.trace_r[0].len(), acc.trace_t.len());
        // the RMS sums still see every row
        assert_eq!(acc.rows, 100);
    }
}
