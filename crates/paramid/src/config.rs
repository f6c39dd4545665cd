//! The `IDENT.toml` file: what to identify from which flights.
//!
//! ```toml
//! cost = "thesis"            # (11.1) | "cifer"
//! optimiser = "lm"           # bounded Levenberg–Marquardt | "simplex" (Nelder–Mead)
//! min_coherence = 0.6        # points with γ² at or below are left out
//! w_kappa = 1.0              # w_κ, per dB²
//! w_chi = 0.01745            # w_χ, per deg²
//! auto_fix = true            # fix parameters failing CR ≤ 20 %, insensitivity ≤ 10 %
//! start = "params.toml"      # start parameters (default: the Bergen Twin)
//! windows_s = [24.0, 12.0, 6.0]
//! spectra = "welch"          # | "sweeps": one flat window per excitation (needs instruments)
//! sweep_pad_s = 2.0          # "sweeps": the window starts and ends this long before/after
//! sweep_taper_s = 2.0        # "sweeps": cosine tapers, inside the pads
//! points = 40                # log-spaced frequencies per response
//! min_points = 5             # responses with fewer coherent points are left out
//!
//! [[operating_point]]
//! name = "hover"
//! velocity_ned_m_s = [0.0, 0.0, 0.0]
//! log = "hover/log.csv"
//! conditioned_on = ["S_col", "S_lat", "S_lon", "S_tr"]   # the default
//! instruments = ["exc_col", "exc_lat", "exc_lon", "exc_tr"] # optional: H = G_eu⁻¹ G_ey
//!
//! [[response]]               # matched at every operating point (or per point)
//! input = "S_lon"
//! output = "meas_q"          # a log column; the model state is `q`
//! omega_min_rad_s = 1.5
//! omega_max_rad_s = 25.0
//!
//! [[parameter]]
//! key = "main_rotor.lift_slope_per_rad"
//! min = 3.0
//! max = 9.0
//! ```
//!
//! Every error names the file and the field (`operating_point[1].log`,
//! `parameter[0].max`, …).

use crate::keys;
use helicon_model::params::Descriptor;
use helicon_model::{ConfigError, INPUT_NAMES, Params, Preset, REDUCED_STATE_NAMES};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The cost's form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CostForm {
    /// Thesis (11.1): Σ w_κ W κ² + w_χ W χ², W = γ² (the partial coherence).
    Thesis,
    /// CIFER: per response (20/n_ω) Σ W_γ [W_g κ² + W_p χ²], W_γ = [1.58(1 − e^{−γ²})]².
    Cifer,
}

/// The optimiser.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Optimiser {
    /// Levenberg–Marquardt on bounded-transformed, scaled parameters.
    Lm,
    /// Nelder–Mead simplex on the same variables (MOSCA's choice).
    Simplex,
}

/// One response to match: servo `input` → log column `output`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Response {
    /// Servo command column (`S_col`, `S_lat`, `S_lon`, `S_tr`).
    pub input: String,
    /// Output column of the log (a model state, optionally prefixed
    /// `meas_` or `est_`).
    pub output: String,
    /// Lowest frequency, rad/s.
    pub omega_min_rad_s: f64,
    /// Highest frequency, rad/s.
    pub omega_max_rad_s: f64,
}

impl Response {
    /// The servo index of the input.
    pub fn input_index(&self) -> Option<usize> {
        INPUT_NAMES.iter().position(|n| *n == self.input)
    }

    /// The reduced-state row of the output (its name without `meas_`/`est_`).
    pub fn state_index(&self) -> Option<usize> {
        let s = self
            .output
            .strip_prefix("meas_")
            .or_else(|| self.output.strip_prefix("est_"))
            .unwrap_or(&self.output);
        REDUCED_STATE_NAMES.iter().position(|n| *n == s)
    }

    /// A short label `output/input`.
    pub fn label(&self) -> String {
        format!("{}/{}", self.output, self.input)
    }
}

fn default_servos() -> Vec<String> {
    INPUT_NAMES.iter().map(|s| s.to_string()).collect()
}

/// An operating point: a steady flight condition and its identification log.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperatingPoint {
    /// Name (reports).
    pub name: String,
    /// Inertial velocity NED, m/s, as the trim takes it.
    #[serde(default)]
    pub velocity_ned_m_s: [f64; 3],
    /// Heading, rad.
    #[serde(default)]
    pub yaw_rad: f64,
    /// The log (`log.csv` of `helicon sim`, or any CSV with `t_s` and the
    /// columns named), relative to the IDENT.toml.
    pub log: PathBuf,
    /// Start of the part of the log used, s (default: its start).
    #[serde(default)]
    pub t_start_s: Option<f64>,
    /// End of the part of the log used, s (default: its end).
    #[serde(default)]
    pub t_end_s: Option<f64>,
    /// The inputs every response is conditioned on (all four servos by
    /// default: a feedback law moves them all).
    #[serde(default = "default_servos")]
    pub conditioned_on: Vec<String>,
    /// Instrumental variables, one per `conditioned_on` input (e.g. the
    /// logged excitations `exc_col`, `exc_lat`, `exc_lon`, `exc_tr`): when
    /// given, the responses are H = G_eu⁻¹ G_ey instead of conditioned on
    /// the inputs, which removes the bias of a feedback law answering
    /// turbulence and sensor noise (see [`crate::data`]). Empty: conditioned.
    #[serde(default)]
    pub instruments: Vec<String>,
    /// Responses of this point (default: the file's `[[response]]`).
    #[serde(default)]
    pub response: Vec<Response>,
}

/// A parameter to identify, with its bounds.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterSpec {
    /// `helicon params` key, e.g. `main_rotor.lift_slope_per_rad`.
    pub key: String,
    /// Lower bound (SI).
    pub min: f64,
    /// Upper bound (SI).
    pub max: f64,
    /// A measurement of the parameter made elsewhere (a ground experiment),
    /// SI: entered in the cost as a prior residual with `prior_std`.
    #[serde(default)]
    pub prior: Option<f64>,
    /// The prior measurement's standard error (one σ, SI, > 0).
    #[serde(default)]
    pub prior_std: Option<f64>,
}

/// A time-domain verification flight (doublets not used in the fit).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Verification {
    /// The operating point it was flown at (its trim is the start).
    pub operating_point: String,
    /// The log, relative to the IDENT.toml.
    pub log: PathBuf,
    /// Outputs compared (model states, optionally `meas_`/`est_` columns).
    #[serde(default = "default_verify_outputs")]
    pub outputs: Vec<String>,
    /// Start of the compared part, s.
    #[serde(default)]
    pub t_start_s: Option<f64>,
    /// End of the compared part, s.
    #[serde(default)]
    pub t_end_s: Option<f64>,
    /// Where the replay starts: `"logged"` (the log's true 30-state at the
    /// window's first sample, a simulator log), `"estimate"` (the model's
    /// trim with the nine estimated states `est_*` of that sample, a real
    /// flight) or `"trim"` (the model's trim). Default: the best the log has.
    #[serde(default)]
    pub initial_state: Option<InitialState>,
    /// The wind flown: `"logged"` (columns `wind_n`, `wind_e`, `wind_d`, a
    /// simulator log) or `"still"`. Default: logged when the log has it.
    #[serde(default)]
    pub wind: Option<WindSource>,
}

/// Where a verification replay starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum InitialState {
    /// The logged true state (all 30 state columns) at the first sample;
    /// the logged servo commands are flown as they are.
    Logged,
    /// The model's trim with attitude, body velocity and rates replaced by
    /// the logged estimate (`est_*`) at the first sample; the logged servo
    /// commands are flown as they are.
    Estimate,
    /// The model's trim at the operating point; the logged servo commands
    /// are flown as perturbations from their first sample.
    Trim,
}

/// The wind a verification replay flies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum WindSource {
    /// The logged wind, NED, held over each step.
    Logged,
    /// Still air.
    Still,
}

fn default_verify_outputs() -> Vec<String> {
    vec!["p".into(), "q".into(), "r".into()]
}

fn default_min_coherence() -> f64 {
    0.6
}
fn one() -> f64 {
    1.0
}
fn default_w_chi() -> f64 {
    0.01745
}
fn default_windows() -> Vec<f64> {
    vec![24.0, 12.0, 6.0]
}
fn default_points() -> usize {
    40
}
fn default_min_points() -> usize {
    5
}
fn default_iterations() -> usize {
    100
}
fn default_cost() -> CostForm {
    CostForm::Thesis
}
fn default_optimiser() -> Optimiser {
    Optimiser::Lm
}
fn default_preset() -> String {
    "physical".into()
}
fn default_sweep_pad() -> f64 {
    2.0
}
fn default_sweep_taper() -> f64 {
    2.0
}

/// How the responses' spectra are estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Spectra {
    /// Overlapped Hann windows of `windows_s`, their composite (the default).
    #[default]
    Welch,
    /// One flat window per excitation (instrument), from `sweep_pad_s`
    /// before its first non-zero sample to `sweep_pad_s` after its last,
    /// with raised-cosine tapers of `sweep_taper_s` at the window's ends
    /// ([`helicon_ident::frf::Taper::Tukey`]): flat over everything the
    /// sweep excites, so without the Hann windows' bias; for flights whose
    /// sweeps are separated by quiet gaps (docs/paramid.md). The random
    /// error comes from the equation error's spectrum in the `windows_s`
    /// spectra ([`crate::data::sweep_instrumented`]).
    Sweeps,
}

/// The file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    #[serde(default = "default_preset")]
    preset: String,
    #[serde(default)]
    start: Option<PathBuf>,
    #[serde(default = "default_cost")]
    cost: CostForm,
    #[serde(default = "default_optimiser")]
    optimiser: Optimiser,
    #[serde(default = "default_min_coherence")]
    min_coherence: f64,
    #[serde(default = "one")]
    w_kappa: f64,
    #[serde(default = "default_w_chi")]
    w_chi: f64,
    #[serde(default)]
    auto_fix: bool,
    #[serde(default = "default_iterations")]
    max_iterations: usize,
    #[serde(default = "default_windows")]
    windows_s: Vec<f64>,
    #[serde(default)]
    spectra: Spectra,
    #[serde(default = "default_sweep_pad")]
    sweep_pad_s: f64,
    #[serde(default = "default_sweep_taper")]
    sweep_taper_s: f64,
    #[serde(default = "default_points")]
    points: usize,
    #[serde(default = "default_min_points")]
    min_points: usize,
    #[serde(default)]
    operating_point: Vec<OperatingPoint>,
    #[serde(default)]
    response: Vec<Response>,
    #[serde(default)]
    parameter: Vec<ParameterSpec>,
    #[serde(default)]
    verification: Vec<Verification>,
}

/// A parameter resolved against the table and the start values.
#[derive(Clone, Copy)]
pub struct Parameter {
    /// Its descriptor.
    pub descriptor: &'static Descriptor,
    /// Start value (from the start parameters).
    pub start: f64,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// A measurement made elsewhere and its standard error (SI), entered in
    /// the cost as a prior residual ([`crate::cost::Cost::residuals`]).
    pub prior: Option<(f64, f64)>,
}

impl std::fmt::Debug for Parameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Parameter")
            .field("key", &self.key())
            .field("start", &self.start)
            .field("min", &self.min)
            .field("max", &self.max)
            .field("prior", &self.prior)
            .finish()
    }
}

impl Parameter {
    /// `section.key`.
    pub fn key(&self) -> String {
        keys::full_key(self.descriptor)
    }
}

/// A checked IDENT.toml: every operating point has its responses, every
/// parameter its descriptor and a start inside its bounds.
#[derive(Debug, Clone)]
pub struct IdentConfig {
    /// The file (for messages).
    pub file: String,
    /// Model preset.
    pub preset: Preset,
    /// Start parameters.
    pub start: Params,
    /// Cost form.
    pub cost: CostForm,
    /// Optimiser.
    pub optimiser: Optimiser,
    /// Coherence threshold.
    pub min_coherence: f64,
    /// w_κ (thesis) or W_g (CIFER).
    pub w_kappa: f64,
    /// w_χ (thesis) or W_p (CIFER).
    pub w_chi: f64,
    /// Fix the parameters failing the guidelines and fit again.
    pub auto_fix: bool,
    /// Optimiser iteration budget (LM: Jacobian evaluations; simplex: ×20 cost evaluations).
    pub max_iterations: usize,
    /// Composite window lengths, s (with [`Spectra::Sweeps`], the spectra
    /// the random error comes from).
    pub windows_s: Vec<f64>,
    /// How the responses are estimated.
    pub spectra: Spectra,
    /// [`Spectra::Sweeps`]: the window's margin before and after each
    /// excitation, s.
    pub sweep_pad_s: f64,
    /// [`Spectra::Sweeps`]: the raised-cosine tapers at the window's ends
    /// (within the margin), s.
    pub sweep_taper_s: f64,
    /// Frequencies per response.
    pub points: usize,
    /// A response with fewer points above the coherence threshold is left
    /// out (a few isolated coherent points of an off-axis response are
    /// chance, not signal).
    pub min_points: usize,
    /// Operating points (paths resolved), each with its responses.
    pub operating_points: Vec<OperatingPoint>,
    /// Parameters.
    pub parameters: Vec<Parameter>,
    /// Verification flights (paths resolved).
    pub verification: Vec<Verification>,
}

fn invalid(file: &str, field: impl Into<String>, value: f64, rule: &str) -> ConfigError {
    ConfigError::invalid(file, field, value, rule)
}

fn text_invalid(file: &str, field: impl Into<String>, value: &str, rule: &str) -> ConfigError {
    ConfigError::Invalid {
        file: file.to_string(),
        field: field.into(),
        value: format!("{value:?}"),
        rule: rule.to_string(),
    }
}

impl IdentConfig {
    /// Read and check an IDENT.toml; relative paths are taken from its folder.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let (file, text) = helicon_model::ConfigError::read_file(path)?;
        let base = path.parent().unwrap_or(Path::new("."));
        Self::from_toml_str(&text, &file, base)
    }

    /// Parse and check IDENT.toml text; `file` names it in errors, `base`
    /// is the folder relative paths are taken from.
    pub fn from_toml_str(text: &str, file: &str, base: &Path) -> Result<Self, ConfigError> {
        let raw: Raw = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        let preset: Preset = raw
            .preset
            .parse()
            .map_err(|_| text_invalid(file, "preset", &raw.preset, "must be physical or thesis"))?;
        let start = match &raw.start {
            Some(p) => {
                let path = base.join(p);
                Params::from_file(&path).map_err(|e| ConfigError::Parse {
                    file: file.to_string(),
                    message: format!("`start`: {e}"),
                })?
            }
            None => Params::bergen_twin(),
        };
        check_numbers(&raw, file)?;
        let operating_points = check_points(&raw, file, base)?;
        let parameters = check_parameters(&raw, file, &start)?;
        let mut verification = raw.verification.clone();
        for (i, v) in verification.iter_mut().enumerate() {
            let f = |s: &str| format!("verification[{i}].{s}");
            if !operating_points.iter().any(|o| o.name == v.operating_point) {
                return Err(text_invalid(
                    file,
                    f("operating_point"),
                    &v.operating_point,
                    "must name an [[operating_point]]",
                ));
            }
            v.log = base.join(&v.log);
            if v.outputs.is_empty() {
                return Err(text_invalid(
                    file,
                    f("outputs"),
                    "[]",
                    "needs at least one output",
                ));
            }
            for (k, o) in v.outputs.iter().enumerate() {
                let r = Response {
                    input: INPUT_NAMES[0].into(),
                    output: o.clone(),
                    omega_min_rad_s: 1.0,
                    omega_max_rad_s: 2.0,
                };
                if r.state_index().is_none() {
                    return Err(text_invalid(
                        file,
                        f(&format!("outputs[{k}]")),
                        o,
                        "must be a model state (p, q, r, u, …), optionally prefixed meas_ or est_",
                    ));
                }
            }
            check_span(file, &f("t_start_s"), v.t_start_s, v.t_end_s)?;
        }
        Ok(IdentConfig {
            file: file.to_string(),
            preset,
            start,
            cost: raw.cost,
            optimiser: raw.optimiser,
            min_coherence: raw.min_coherence,
            w_kappa: raw.w_kappa,
            w_chi: raw.w_chi,
            auto_fix: raw.auto_fix,
            max_iterations: raw.max_iterations,
            windows_s: raw.windows_s,
            spectra: raw.spectra,
            sweep_pad_s: raw.sweep_pad_s,
            sweep_taper_s: raw.sweep_taper_s,
            points: raw.points,
            min_points: raw.min_points,
            operating_points,
            parameters,
            verification,
        })
    }

    /// Number of responses over all operating points.
    pub fn response_count(&self) -> usize {
        self.operating_points.iter().map(|o| o.response.len()).sum()
    }
}

fn check_span(file: &str, field: &str, a: Option<f64>, b: Option<f64>) -> Result<(), ConfigError> {
    for v in [a, b].into_iter().flatten() {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(file, field, v, "must be finite and >= 0"));
        }
    }
    if let (Some(a), Some(b)) = (a, b) {
        if b <= a {
            return Err(invalid(file, field, a, "must be before t_end_s"));
        }
    }
    Ok(())
}

fn check_numbers(raw: &Raw, file: &str) -> Result<(), ConfigError> {
    if !(raw.min_coherence.is_finite() && (0.0..1.0).contains(&raw.min_coherence)) {
        return Err(invalid(
            file,
            "min_coherence",
            raw.min_coherence,
            "must be in [0, 1)",
        ));
    }
    for (name, v) in [("w_kappa", raw.w_kappa), ("w_chi", raw.w_chi)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(file, name, v, "must be finite and >= 0"));
        }
    }
    if raw.w_kappa + raw.w_chi <= 0.0 {
        return Err(invalid(
            file,
            "w_kappa",
            raw.w_kappa,
            "w_kappa and w_chi cannot both be 0",
        ));
    }
    if !(1..=100_000).contains(&raw.max_iterations) {
        return Err(invalid(
            file,
            "max_iterations",
            raw.max_iterations as f64,
            "must be in 1..=100000",
        ));
    }
    if !(2..=2000).contains(&raw.points) {
        return Err(invalid(
            file,
            "points",
            raw.points as f64,
            "must be in 2..=2000",
        ));
    }
    if !(1..=raw.points).contains(&raw.min_points) {
        return Err(invalid(
            file,
            "min_points",
            raw.min_points as f64,
            "must be in 1..=points",
        ));
    }
    if raw.windows_s.is_empty() {
        return Err(text_invalid(
            file,
            "windows_s",
            "[]",
            "needs at least one window length",
        ));
    }
    for (i, w) in raw.windows_s.iter().enumerate() {
        if !(w.is_finite() && *w > 0.0) {
            return Err(invalid(
                file,
                format!("windows_s[{i}]"),
                *w,
                "must be finite and > 0",
            ));
        }
    }
    if !(raw.sweep_pad_s.is_finite() && raw.sweep_pad_s > 0.0 && raw.sweep_pad_s <= 60.0) {
        return Err(invalid(
            file,
            "sweep_pad_s",
            raw.sweep_pad_s,
            "must be in (0, 60] s",
        ));
    }
    if !(raw.sweep_taper_s.is_finite()
        && raw.sweep_taper_s >= 0.0
        && raw.sweep_taper_s <= raw.sweep_pad_s)
    {
        return Err(invalid(
            file,
            "sweep_taper_s",
            raw.sweep_taper_s,
            "must be in [0, sweep_pad_s]: the tapers lie in the margins, outside the excitation",
        ));
    }
    if raw.spectra == Spectra::Sweeps {
        if let Some(i) = raw
            .operating_point
            .iter()
            .position(|o| o.instruments.is_empty())
        {
            return Err(text_invalid(
                file,
                format!("operating_point[{i}].instruments"),
                "[]",
                "spectra = \"sweeps\" needs the excitations as instruments (one window each)",
            ));
        }
    }
    Ok(())
}

fn check_response(
    file: &str,
    field: &str,
    r: &Response,
    cond: &[String],
) -> Result<(), ConfigError> {
    if r.input_index().is_none() {
        return Err(text_invalid(
            file,
            format!("{field}.input"),
            &r.input,
            "must be S_col, S_lat, S_lon or S_tr",
        ));
    }
    if !cond.contains(&r.input) {
        return Err(text_invalid(
            file,
            format!("{field}.input"),
            &r.input,
            "must be one of the operating point's conditioned_on inputs",
        ));
    }
    if r.state_index().is_none() {
        return Err(text_invalid(
            file,
            format!("{field}.output"),
            &r.output,
            "must be a model state (p, q, r, u, v, w, phi, …), optionally prefixed meas_ or est_",
        ));
    }
    let (lo, hi) = (r.omega_min_rad_s, r.omega_max_rad_s);
    if !(lo.is_finite() && lo > 0.0) {
        return Err(invalid(
            file,
            format!("{field}.omega_min_rad_s"),
            lo,
            "must be finite and > 0",
        ));
    }
    if !(hi.is_finite() && hi > lo) {
        return Err(invalid(
            file,
            format!("{field}.omega_max_rad_s"),
            hi,
            "must be finite and > omega_min_rad_s",
        ));
    }
    Ok(())
}

fn check_points(raw: &Raw, file: &str, base: &Path) -> Result<Vec<OperatingPoint>, ConfigError> {
    if raw.operating_point.is_empty() {
        return Err(text_invalid(
            file,
            "operating_point",
            "[]",
            "needs at least one [[operating_point]]",
        ));
    }
    for (i, r) in raw.response.iter().enumerate() {
        check_response(file, &format!("response[{i}]"), r, &default_servos())?;
    }
    let mut out = Vec::with_capacity(raw.operating_point.len());
    for (i, op) in raw.operating_point.iter().enumerate() {
        let f = |s: &str| format!("operating_point[{i}].{s}");
        let mut op = op.clone();
        if op.name.trim().is_empty() {
            return Err(text_invalid(file, f("name"), &op.name, "must not be empty"));
        }
        if out.iter().any(|o: &OperatingPoint| o.name == op.name) {
            return Err(text_invalid(
                file,
                f("name"),
                &op.name,
                "names must be unique",
            ));
        }
        for (k, v) in op.velocity_ned_m_s.iter().enumerate() {
            if !(v.is_finite() && v.abs() <= 100.0) {
                return Err(invalid(
                    file,
                    f(&format!("velocity_ned_m_s[{k}]")),
                    *v,
                    "must be finite, |v| <= 100 m/s",
                ));
            }
        }
        if !op.yaw_rad.is_finite() {
            return Err(invalid(file, f("yaw_rad"), op.yaw_rad, "must be finite"));
        }
        check_span(file, &f("t_start_s"), op.t_start_s, op.t_end_s)?;
        if op.conditioned_on.is_empty() {
            return Err(text_invalid(
                file,
                f("conditioned_on"),
                "[]",
                "needs at least one input",
            ));
        }
        for (k, c) in op.conditioned_on.iter().enumerate() {
            if op.conditioned_on[..k].contains(c) {
                return Err(text_invalid(
                    file,
                    f(&format!("conditioned_on[{k}]")),
                    c,
                    "given twice",
                ));
            }
        }
        if !op.instruments.is_empty() && op.instruments.len() != op.conditioned_on.len() {
            return Err(invalid(
                file,
                f("instruments"),
                op.instruments.len() as f64,
                "needs one instrument per conditioned_on input",
            ));
        }
        for (k, c) in op.instruments.iter().enumerate() {
            if op.instruments[..k].contains(c) || op.conditioned_on.contains(c) {
                return Err(text_invalid(
                    file,
                    f(&format!("instruments[{k}]")),
                    c,
                    "given twice, or also an input",
                ));
            }
        }
        if op.response.is_empty() {
            op.response = raw.response.clone();
        }
        if op.response.is_empty() {
            return Err(text_invalid(
                file,
                f("response"),
                "[]",
                "no responses: give [[response]] or [[operating_point.response]]",
            ));
        }
        for (k, r) in op.response.iter().enumerate() {
            check_response(file, &f(&format!("response[{k}]")), r, &op.conditioned_on)?;
            if op.response[..k]
                .iter()
                .any(|q| q.input == r.input && q.output == r.output)
            {
                return Err(text_invalid(
                    file,
                    f(&format!("response[{k}].output")),
                    &r.output,
                    "response given twice",
                ));
            }
        }
        op.log = base.join(&op.log);
        out.push(op);
    }
    Ok(out)
}

fn check_parameters(raw: &Raw, file: &str, start: &Params) -> Result<Vec<Parameter>, ConfigError> {
    if raw.parameter.is_empty() {
        return Err(text_invalid(
            file,
            "parameter",
            "[]",
            "needs at least one [[parameter]] to identify",
        ));
    }
    let mut out: Vec<Parameter> = Vec::with_capacity(raw.parameter.len());
    for (i, p) in raw.parameter.iter().enumerate() {
        let f = |s: &str| format!("parameter[{i}].{s}");
        let d = keys::find(&p.key).ok_or_else(|| {
            text_invalid(
                file,
                f("key"),
                &p.key,
                "not a parameter key (run `helicon params` for the list)",
            )
        })?;
        if !keys::is_continuous(d) {
            return Err(text_invalid(
                file,
                f("key"),
                &p.key,
                "a count or a switch cannot be identified",
            ));
        }
        if out.iter().any(|q| std::ptr::eq(q.descriptor, d)) {
            return Err(text_invalid(file, f("key"), &p.key, "given twice"));
        }
        let s = keys::get(start, d);
        for (name, v) in [("min", p.min), ("max", p.max)] {
            d.check(v)
                .map_err(|rule| invalid(file, f(name), v, &rule))?;
        }
        if p.min >= p.max {
            return Err(invalid(file, f("min"), p.min, "must be < max"));
        }
        if !(p.min < s && s < p.max) {
            return Err(invalid(
                file,
                f("min"),
                p.min,
                &format!("the start value {s} must lie strictly between min and max"),
            ));
        }
        if s == 0.0 {
            return Err(invalid(
                file,
                f("key"),
                s,
                "the start value is 0: parameters are scaled by their start, give a non-zero start",
            ));
        }
        let prior = match (p.prior, p.prior_std) {
            (None, None) => None,
            (Some(v), Some(sd)) => {
                d.check(v)
                    .map_err(|rule| invalid(file, f("prior"), v, &rule))?;
                if !(p.min < v && v < p.max) {
                    return Err(invalid(
                        file,
                        f("prior"),
                        v,
                        "must lie strictly between min and max",
                    ));
                }
                if !(sd.is_finite() && sd > 0.0 && sd < p.max - p.min) {
                    return Err(invalid(
                        file,
                        f("prior_std"),
                        sd,
                        "must be finite, > 0 and below max − min",
                    ));
                }
                Some((v, sd))
            }
            (Some(v), None) => {
                return Err(invalid(
                    file,
                    f("prior_std"),
                    v,
                    "a prior needs its prior_std",
                ));
            }
            (None, Some(sd)) => {
                return Err(invalid(file, f("prior"), sd, "prior_std without a prior"));
            }
        };
        out.push(Parameter {
            descriptor: d,
            start: s,
            min: p.min,
            max: p.max,
            prior,
        });
    }
    Ok(out)
}
