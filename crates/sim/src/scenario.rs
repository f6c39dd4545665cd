//! Closed-loop scenarios (TOML): model, initial condition, references, wind,
//! sensors, controller and plant settings.
//!
//! ```toml
//! name = "thesis-fig14-5"
//! preset = "thesis"            # or "physical"
//! duration_s = 10.0
//! [trim]                        # the operating point the controller is designed at
//! velocity_ned_m_s = [0.0, 0.0, 0.0]
//! yaw_rad = 0.0
//! [initial]                     # deviations from the trim (state names, or vn/ve/vd)
//! psi = 1.0
//! [[reference]]                 # steps (ramp_s = 0) or ramps on vn, ve, vd, psi
//! t_s = 1.0
//! output = "vn"
//! value = 2.0
//! [controller]                  # gnc::design::ControllerConfig plus switches
//! input_max = [0.1, 0.7, 0.7, 0.04]
//! [wind]                        # sim::wind::WindConfig
//! [sensors]                     # sim::sensors::SensorConfig (used when fusion = true)
//! ```

use crate::sensors::SensorConfig;
use crate::wind::WindConfig;
use helicon_gnc::design::ControllerConfig;
use helicon_model::Preset;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Errors reading or checking a scenario: the toolkit's one configuration
/// error shape (file, field, value, rule; the `io::Error` kept as source).
pub type ScenarioError = helicon_model::ConfigError;

pub use helicon_setup::estimator::{EstimatorKind, EstimatorSection};
pub use helicon_setup::plan::{
    MAX_HEADING_RAD, MAX_SPEED_M_S, OUTPUTS, ReferenceChange, ReferenceSchedule, TrimSection,
    check_references, check_trim,
};

/// How the plant's inflow is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PlantInflow {
    /// Converged inflow (the safeguarded solver).
    #[default]
    Converged,
    /// The thesis implementation: N plain Newton–Raphson steps per derivative
    /// evaluation, warm-started from the previous evaluation's λ (Appendix F).
    ThesisIteration,
}

/// The inflow used to linearize the model for the design.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum DesignInflow {
    /// Converged inflow.
    #[default]
    Converged,
    /// The thesis emulation (Appendix E).
    ThesisIteration,
}

/// Controller section: design settings plus the thesis's switches.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSection {
    /// Design settings.
    #[serde(flatten)]
    pub design: ControllerConfig,
    /// Feedback on (off: trim inputs held).
    #[serde(default = "yes")]
    pub feedback: bool,
    /// State estimator on (off: true state fed back).
    #[serde(default = "yes")]
    pub estimator: bool,
    /// Sensor models + attitude determination + fusion produce the
    /// measurement (off: the ideal nine measured states).
    #[serde(default)]
    pub fusion: bool,
    /// Load gains from this file instead of designing (relative to the scenario).
    #[serde(default)]
    pub gains_file: Option<PathBuf>,
    /// Inflow of the linearization used for the design.
    #[serde(default)]
    pub design_inflow: DesignInflow,
    /// Fly a gain schedule designed from this envelope file (relative to
    /// the scenario; designed on the envelope's own, nominal, model) instead
    /// of the single design at `[trim]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub schedule: Option<PathBuf>,
    /// Fly this gain-schedule file (`helicon design --schedule` output,
    /// relative to the scenario).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub schedule_file: Option<PathBuf>,
}

fn yes() -> bool {
    true
}

impl Default for ControllerSection {
    fn default() -> Self {
        ControllerSection {
            design: ControllerConfig::default(),
            feedback: true,
            estimator: true,
            fusion: false,
            gains_file: None,
            design_inflow: DesignInflow::Converged,
            schedule: None,
            schedule_file: None,
        }
    }
}

/// Plant integration settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantSection {
    /// RK4 sub-steps per controller sample.
    pub substeps: u32,
    /// Plant inflow computation.
    pub inflow: PlantInflow,
    /// Newton–Raphson steps for `thesis-iteration`.
    pub inflow_iterations: u32,
    /// Divergence: |φ| or |θ| beyond this (rad) stops the run.
    pub max_attitude_rad: f64,
    /// Divergence: any body rate beyond this (rad/s) stops the run.
    pub max_rate_rad_s: f64,
    /// Divergence: the heading more than this (rad, unwrapped) away from its
    /// reference — the helicopter spins away (thesis Figure F.4).
    pub max_yaw_error_rad: f64,
}

impl Default for PlantSection {
    fn default() -> Self {
        PlantSection {
            substeps: 1,
            inflow: PlantInflow::Converged,
            inflow_iterations: 7,
            max_attitude_rad: 1.2,
            max_rate_rad_s: 10.0,
            max_yaw_error_rad: 3.0 * std::f64::consts::PI,
        }
    }
}

/// Log settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogSection {
    /// Keep every n-th sample (and the last) in the flight log and
    /// `log.csv`; the metrics are computed on the kept samples.
    pub decimation: u32,
    /// Also keep every sensor frame the flight software was given, with the
    /// truth it was sampled from (`sensors.csv`, the sensor-log format that
    /// `helicon fuse` replays); needs `fusion = true`.
    pub sensors: bool,
    /// The largest `log.csv` to write (bytes, ≥ 1; `helicon sim` and
    /// `helicon sitl`, whose `--max-log-bytes` overrides it; unset: the
    /// command's default, 1 GB). Its size is estimated before the flight;
    /// a larger log is thinned to fit or the flight refused.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_bytes: Option<u64>,
}

impl Default for LogSection {
    fn default() -> Self {
        LogSection {
            decimation: 1,
            sensors: false,
            max_bytes: None,
        }
    }
}

/// A closed-loop scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Name (used in reports).
    #[serde(default = "default_name")]
    pub name: String,
    /// Model preset.
    #[serde(default, with = "preset_serde")]
    pub preset: Preset,
    /// Parameter file overriding the Bergen Twin (relative to the scenario).
    #[serde(default)]
    pub params: Option<PathBuf>,
    /// Flight time (s).
    pub duration_s: f64,
    /// Trim / design point.
    #[serde(default)]
    pub trim: TrimSection,
    /// Initial deviations from the trim: reduced-state names, or `vn`, `ve`,
    /// `vd` for NED velocity deviations.
    #[serde(default)]
    pub initial: BTreeMap<String, f64>,
    /// Reference changes.
    #[serde(default)]
    pub reference: Vec<ReferenceChange>,
    /// Jerk-limited mission references instead of `[[reference]]`
    /// ([`helicon_setup::plan::TrajectorySection`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<helicon_setup::plan::TrajectorySection>,
    /// Flight-test excitations added to the servo commands
    /// ([`crate::excitation::ExcitationEntry`]). Not written when empty, so
    /// the effective scenarios (and campaign hashes) without them are
    /// unchanged.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub excitation: Vec<crate::excitation::ExcitationEntry>,
    /// Wind.
    #[serde(default)]
    pub wind: WindConfig,
    /// Sensors (used when `controller.fusion`).
    #[serde(default)]
    pub sensors: SensorConfig,
    /// Navigation filter tuning (used when `controller.fusion`).
    #[serde(default)]
    pub navigation: crate::navigation::NavigationConfig,
    /// Navigation kind and tuning. Not written when default, so the
    /// effective scenarios (and campaign hashes) of thesis-chain flights
    /// are those of before the section existed.
    #[serde(default, skip_serializing_if = "EstimatorSection::is_default")]
    pub estimator: EstimatorSection,
    /// Controller.
    #[serde(default)]
    pub controller: ControllerSection,
    /// Plant.
    #[serde(default)]
    pub plant: PlantSection,
    /// Log.
    #[serde(default)]
    pub log: LogSection,
    /// Start on the ground, take off and land ([`crate::ground`]). Not
    /// written when absent, so the effective scenarios (and campaign
    /// hashes) without it are unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<crate::ground::GroundSection>,
    /// The expanded `[[case]]` entries (see [`Scenario::cases`]); not a TOML key.
    #[serde(skip)]
    pub variants: Vec<Scenario>,
    /// Folder of the scenario file (for relative paths); not in the TOML.
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

fn default_name() -> String {
    "scenario".to_string()
}

mod preset_serde {
    use helicon_model::Preset;
    use serde::{Deserialize, Deserializer, Serializer};
    pub fn serialize<S: Serializer>(p: &Preset, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(p.name())
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Preset, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// Command-line overrides of a scenario (`helicon sim --params --seed
/// --duration`), applied to the scenario and each of its `[[case]]`s.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScenarioOverrides {
    /// Plant parameter file instead of the scenario's `params` (an absolute
    /// path, or relative to the working directory: not the scenario's folder).
    pub params: Option<PathBuf>,
    /// Seed of both the wind (`wind.seed`) and the sensor (`sensors.seed`)
    /// random streams.
    pub seed: Option<u64>,
    /// Flight time (s) instead of `duration_s`.
    pub duration_s: Option<f64>,
}

/// Merge `over` into `base`: tables key by key (recursively), other values replace.
fn deep_merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => deep_merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// Longest flight (s): one day.
pub const MAX_DURATION_S: f64 = 86_400.0;

/// Largest `plant.substeps`: RK4 at the 400 Hz control rate is already
/// accurate for this model (its fastest modes are the ~20 rad/s flapping
/// and servo dynamics, h·|λ| ≈ 0.05), so more sub-steps only multiply the
/// run time; 1000 leaves room for convergence studies.
pub const MAX_SUBSTEPS: u32 = 1000;

/// Largest `plant.inflow_iterations`: the thesis's Newton–Raphson inflow
/// (Appendix F) is run a fixed few steps per derivative; 100 is far beyond
/// convergence and keeps one derivative evaluation bounded.
pub const MAX_INFLOW_ITERATIONS: u32 = 100;

/// Largest total of plant RK4 steps in one flight ([`Scenario::check_work`]).
pub const MAX_PLANT_STEPS: f64 = 1e8;

/// Largest |initial deviation| (rad, rad/s or m/s).
const MAX_INITIAL_DEVIATION: f64 = 100.0;

/// A number for a message: shortest round-trip text, in exponent form when
/// extreme (`1e-300`, not 300 digits; `2.5`, `86400`).
pub fn num(v: f64) -> String {
    helicon_model::config_error::format_number(v)
}

impl Scenario {
    /// Parse and validate TOML text; `file` names the source in errors.
    ///
    /// A scenario may hold `[[case]]` entries (like the thesis's figures with
    /// sub-plots (a)–(d)): each has a `name` and any scenario keys, deep-merged
    /// over the rest of the file (tables merge key by key, other values
    /// replace). Each case is validated as a complete scenario.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scenario, ScenarioError> {
        let parse = |m: String| ScenarioError::Parse {
            file: file.to_string(),
            message: m,
        };
        let mut table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| parse(e.to_string()))?;
        let cases = match table.remove("case") {
            None => Vec::new(),
            Some(toml::Value::Array(a)) => a,
            Some(_) => return Err(parse("`case` must be an array of tables ([[case]])".into())),
        };
        let base: Scenario = toml::Value::Table(table.clone())
            .try_into()
            .map_err(|e: toml::de::Error| parse(e.to_string()))?;
        let mut variants = Vec::with_capacity(cases.len());
        let mut names = std::collections::BTreeSet::new();
        for (i, c) in cases.into_iter().enumerate() {
            let toml::Value::Table(mut ct) = c else {
                return Err(parse(format!("case[{i}] must be a table")));
            };
            let name = match ct.remove("name") {
                Some(toml::Value::String(n)) if !n.is_empty() => n,
                _ => return Err(parse(format!("case[{i}].name must be a non-empty string"))),
            };
            if !names.insert(name.clone()) {
                return Err(parse(format!("case[{i}].name `{name}` is not unique")));
            }
            let mut merged = table.clone();
            deep_merge(&mut merged, ct);
            let mut v: Scenario = toml::Value::Table(merged)
                .try_into()
                .map_err(|e: toml::de::Error| parse(format!("case `{name}`: {e}")))?;
            v.name = format!("{}-{name}", base.name);
            v.validate(&format!("{file} (case `{name}`)"))?;
            variants.push(v);
        }
        let mut s = base;
        s.validate(file)?;
        s.variants = variants;
        Ok(s)
    }

    /// Load a scenario file (relative paths inside resolve against its folder).
    pub fn from_file(path: &Path) -> Result<Scenario, ScenarioError> {
        let (file, text) = helicon_model::ConfigError::read_file(path)?;
        let mut s = Self::from_toml_str(&text, &file)?;
        s.base_dir = path.parent().map(Path::to_path_buf);
        for v in &mut s.variants {
            v.base_dir = s.base_dir.clone();
        }
        Ok(s)
    }

    /// Apply command-line overrides to the scenario and its cases and
    /// validate the result; errors name `origin` (e.g. `s.toml (--duration)`).
    pub fn with_overrides(
        mut self,
        o: &ScenarioOverrides,
        origin: &str,
    ) -> Result<Scenario, ScenarioError> {
        let apply = |s: &mut Scenario| -> Result<(), ScenarioError> {
            if let Some(p) = &o.params {
                s.params = Some(p.clone());
            }
            if let Some(seed) = o.seed {
                s.wind.seed = seed;
                s.sensors.seed = seed;
            }
            if let Some(d) = o.duration_s {
                s.duration_s = d;
            }
            s.validate(origin)
        };
        apply(&mut self)?;
        for v in &mut self.variants {
            apply(v)?;
        }
        Ok(self)
    }

    /// The concrete scenarios to fly: one per `[[case]]` (named
    /// `<name>-<case>`), or the scenario itself when it has none.
    pub fn cases(&self) -> Vec<Scenario> {
        if self.variants.is_empty() {
            vec![self.clone()]
        } else {
            self.variants.clone()
        }
    }

    /// Resolve a path relative to the scenario's folder.
    pub fn resolve(&self, p: &Path) -> PathBuf {
        match (&self.base_dir, p.is_relative()) {
            (Some(b), true) => b.join(p),
            _ => p.to_path_buf(),
        }
    }

    /// Check ranges and names. Every error names the file and the field
    /// (`file: \`wind.dryden.w20_m_s\` = -1.0: finite, >= 0`), once.
    #[allow(clippy::too_many_lines)] // every section's rules, in file order
    pub fn validate(&self, file: &str) -> Result<(), ScenarioError> {
        let bad = |field: &str, value: String, rule: &str| ScenarioError::Invalid {
            file: file.to_string(),
            field: field.to_string(),
            value,
            rule: rule.to_string(),
        };
        let section = |message: String| ScenarioError::Parse {
            file: file.to_string(),
            message,
        };
        if !(self.duration_s.is_finite()
            && self.duration_s > 0.0
            && self.duration_s <= MAX_DURATION_S)
        {
            return Err(bad(
                "duration_s",
                num(self.duration_s),
                "must be finite, > 0 and <= 86400 s (one day)",
            ));
        }
        check_trim(&self.trim, file)?;
        for (k, v) in &self.initial {
            let known = helicon_model::REDUCED_STATE_NAMES.contains(&k.as_str())
                || matches!(k.as_str(), "vn" | "ve" | "vd");
            if !known {
                return Err(bad(
                    &format!("initial.{k}"),
                    num(*v),
                    "not a state name (reduced states, or vn/ve/vd)",
                ));
            }
            if !(v.is_finite() && v.abs() <= MAX_INITIAL_DEVIATION) {
                return Err(bad(
                    &format!("initial.{k}"),
                    num(*v),
                    "must be finite and within +-100 (rad, rad/s or m/s: far beyond \
                     the divergence limits of [plant])",
                ));
            }
        }
        check_references(&self.reference, file)?;
        if let Err(e) = self.controller.design.validate() {
            return Err(match e {
                helicon_gnc::design::DesignError::Config { field, value, rule } => {
                    bad(&format!("controller.{field}"), num(value), rule)
                }
                other => section(format!("[controller]: {other}")),
            });
        }
        if !(1..=MAX_SUBSTEPS).contains(&self.plant.substeps) {
            return Err(bad(
                "plant.substeps",
                self.plant.substeps.to_string(),
                "must be 1..=1000 (RK4 at the 400 Hz control rate is already \
                 accurate; more sub-steps only multiply the run time)",
            ));
        }
        if !(1..=MAX_INFLOW_ITERATIONS).contains(&self.plant.inflow_iterations) {
            return Err(bad(
                "plant.inflow_iterations",
                self.plant.inflow_iterations.to_string(),
                "must be 1..=100 (the thesis inflow iteration needs at least one \
                 Newton-Raphson step; it converges in a handful)",
            ));
        }
        for (f, v) in [
            ("plant.max_attitude_rad", self.plant.max_attitude_rad),
            ("plant.max_rate_rad_s", self.plant.max_rate_rad_s),
            ("plant.max_yaw_error_rad", self.plant.max_yaw_error_rad),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(f, num(v), "must be finite and > 0"));
            }
        }
        if self.log.decimation == 0 {
            return Err(bad("log.decimation", "0".into(), "must be >= 1"));
        }
        if self.log.max_bytes == Some(0) {
            return Err(bad("log.max_bytes", "0".into(), "must be >= 1 (bytes)"));
        }
        if let Err(e) = self.navigation.validate() {
            return Err(match e {
                helicon_core::fusion::FusionError::InvalidConfig {
                    field,
                    value,
                    allowed,
                } => bad(field, num(value), &format!("allowed: {allowed}")),
                other => section(format!("[navigation]: {other}")),
            });
        }
        if let Err(e) = self.estimator.eskf.validate() {
            return Err(match e {
                helicon_core::fusion::FusionError::InvalidConfig {
                    field,
                    value,
                    allowed,
                } => bad(field, num(value), &format!("allowed: {allowed}")),
                other => section(format!("[estimator.eskf]: {other}")),
            });
        }
        if self.estimator.kind == EstimatorKind::Eskf
            && !(self.controller.estimator && self.controller.fusion)
        {
            return Err(bad(
                "estimator.kind",
                "\"eskf\"".into(),
                "needs the sensors in the loop: controller.estimator = true and \
                 controller.fusion = true",
            ));
        }
        self.sensors
            .validate(file)
            .map_err(|e| e.within(file, "sensors"))?;
        self.validate_envelope(file)?;
        if let Some(g) = &self.ground {
            g.validate(file, self.duration_s)?;
        }
        crate::excitation::Excitations::new(&self.excitation, file)?;
        crate::wind::Wind::from_config(&self.wind).map_err(|e| e.within(file, "wind"))?;
        Ok(())
    }

    /// Bound the work of a flight: at least one controller sample
    /// (`duration_s >= sample_time_s`), and at most [`MAX_PLANT_STEPS`] (1e8)
    /// plant RK4 steps `duration_s / sample_time_s x substeps`: about 5
    /// minutes of RK4 alone at 2.6 µs a step on the reference machine
    /// (`helicon bench`); the documented longest flight, 86400 s at 400 Hz,
    /// fits with up to 2 sub-steps. `sample_time_s` is the controller's, from
    /// the parameters (known only once they are loaded); `file` names the
    /// scenario in the error.
    pub fn check_work(&self, file: &str, sample_time_s: f64) -> Result<(), ScenarioError> {
        let bad = |rule: String| ScenarioError::Invalid {
            file: file.to_string(),
            field: "duration_s".to_string(),
            value: num(self.duration_s),
            rule,
        };
        let one_sample = self.duration_s >= sample_time_s;
        if !one_sample {
            return Err(bad(format!(
                "must be at least one controller sample (sample_time_s = {})",
                num(sample_time_s)
            )));
        }
        let steps = (self.duration_s / sample_time_s).ceil() * f64::from(self.plant.substeps);
        if !(steps.is_finite() && steps <= MAX_PLANT_STEPS) {
            return Err(bad(format!(
                "duration_s / sample_time_s x plant.substeps = {} / {} x {} = {steps:e} \
                 plant steps exceeds the limit of {MAX_PLANT_STEPS:e} (about 5 minutes of \
                 computing); shorten the flight or lower plant.substeps",
                num(self.duration_s),
                num(sample_time_s),
                self.plant.substeps
            )));
        }
        Ok(())
    }

    /// The additive envelope options: `[trajectory]` (not with
    /// `[[reference]]`) and one of `controller.schedule`,
    /// `controller.schedule_file`, `controller.gains_file`.
    fn validate_envelope(&self, file: &str) -> Result<(), ScenarioError> {
        if let Some(t) = &self.trajectory {
            if !self.reference.is_empty() {
                return Err(ScenarioError::Parse {
                    file: file.to_string(),
                    message: "[trajectory] replaces [[reference]]: give one of them".into(),
                });
            }
            t.mission(&self.trim, file)?;
        }
        let c = &self.controller;
        let given = [
            c.schedule.is_some(),
            c.schedule_file.is_some(),
            c.gains_file.is_some(),
        ];
        if given.iter().filter(|g| **g).count() > 1 {
            return Err(ScenarioError::Parse {
                file: file.to_string(),
                message: "[controller]: give at most one of `schedule`, `schedule_file` and \
                          `gains_file`"
                    .into(),
            });
        }
        Ok(())
    }

    /// The reference changes sorted by time, ready for allocation-free
    /// lookups in the flight loop.
    pub fn reference_schedule(&self) -> ReferenceSchedule {
        ReferenceSchedule::new(&self.trim, &self.reference, self.trajectory.as_ref())
    }

    /// The reference at time t: (vn, ve, vd, psi), starting from the trim.
    pub fn reference_at(&self, t_s: f64) -> [f64; 4] {
        self.reference_schedule().at(t_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scenario, String> {
        Scenario::from_toml_str(text, "s.toml").map_err(|e| e.to_string())
    }

    #[test]
    fn bounds_name_the_field_once_with_short_numbers() {
        for (text, want) in [
            (
                "duration_s = 1.0\n[plant]\nsubsteps = 1000000000\n",
                "s.toml: `plant.substeps` = 1000000000: must be 1..=1000",
            ),
            (
                "duration_s = 1.0\n[plant]\ninflow_iterations = 0\n",
                "s.toml: `plant.inflow_iterations` = 0: must be 1..=100",
            ),
            (
                "duration_s = 1.0\n[[reference]]\nt_s = 0.1\noutput = \"vn\"\nvalue = 1e300\n",
                "s.toml: `reference[0].value` = 1e300: must be finite and within +-100 m/s",
            ),
            (
                "duration_s = 1.0\n[[reference]]\nt_s = 0.1\noutput = \"psi\"\nvalue = 101.0\n",
                "s.toml: `reference[0].value` = 101: must be finite and within +-100 rad",
            ),
            (
                "duration_s = 1e-300\n[[reference]]\nt_s = 0.1\noutput = \"psi\"\nvalue = 1.0\n",
                "",
            ),
            (
                "duration_s = 1.0\n[wind.dryden]\nw20_m_s = -1.0\n",
                "s.toml: `wind.dryden.w20_m_s` = -1: allowed: >= 0",
            ),
            (
                "duration_s = 1.0\n[sensors.gps]\nrate_hz = 50.0\n",
                "s.toml: `sensors.gps.rate_hz` = 50: allowed: 1..=10",
            ),
        ] {
            match parse(text) {
                Ok(_) => assert!(want.is_empty(), "accepted: {text}"),
                Err(e) => assert!(!want.is_empty() && e.starts_with(want), "{e}"),
            }
        }
        // the edges are accepted
        assert!(
            parse("duration_s = 1.0\n[plant]\nsubsteps = 1000\ninflow_iterations = 100\n").is_ok()
        );
    }

    #[test]
    fn work_needs_one_sample_and_at_most_1e8_steps() {
        let s = parse("duration_s = 86400.0\n[plant]\nsubsteps = 2\n").unwrap();
        // 86400 s at 400 Hz with 2 sub-steps: 6.9e7 steps
        assert!(s.check_work("s.toml", 0.0025).is_ok());
        let s = parse("duration_s = 86400.0\n[plant]\nsubsteps = 3\n").unwrap();
        let e = s.check_work("s.toml", 0.0025).unwrap_err().to_string();
        assert!(
            e.contains("1.0368e8 plant steps exceeds the limit of 1e8"),
            "{e}"
        );
        let s = parse("duration_s = 1e-300\n").unwrap();
        let e = s.check_work("s.toml", 0.0025).unwrap_err().to_string();
        assert!(
            e.starts_with("s.toml: `duration_s` = 1e-300: must be at least one controller sample"),
            "{e}"
        );
    }

    #[test]
    fn overrides_apply_to_every_case_and_are_validated() {
        let s = parse(
            "duration_s = 1.0\n[wind]\nseed = 1\n[sensors]\nseed = 2\n[[case]]\nname = \"a\"\n[[case]]\nname = \"b\"\n",
        )
        .unwrap();
        let o = ScenarioOverrides {
            params: Some(PathBuf::from("/p.toml")),
            seed: Some(9),
            duration_s: Some(0.5),
        };
        let s = s.with_overrides(&o, "s.toml (with …)").unwrap();
        for c in std::iter::once(&s).chain(&s.variants) {
            assert_eq!((c.wind.seed, c.sensors.seed), (9, 9));
            assert_eq!(c.duration_s, 0.5);
            assert_eq!(c.params.as_deref(), Some(Path::new("/p.toml")));
        }
        let bad = ScenarioOverrides {
            duration_s: Some(f64::NAN),
            ..ScenarioOverrides::default()
        };
        let e = s
            .with_overrides(&bad, "s.toml (with --duration NaN)")
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("s.toml (with --duration NaN): `duration_s` = NaN"),
            "{e}"
        );
    }

    #[test]
    fn estimator_kind_is_chosen_and_checked() {
        let s = parse("duration_s = 1.0\n").unwrap();
        assert_eq!(s.estimator.kind, EstimatorKind::Thesis);
        let ok = "duration_s = 1.0\n[controller]\nfusion = true\n[estimator]\nkind = \"eskf\"\n";
        assert_eq!(parse(ok).unwrap().estimator.kind, EstimatorKind::Eskf);
        // the ESKF needs the sensors in the loop
        let e = parse("duration_s = 1.0\n[estimator]\nkind = \"eskf\"\n").unwrap_err();
        assert!(e.contains("s.toml") && e.contains("estimator.kind"), "{e}");
        let e = parse("duration_s = 1.0\n[estimator]\nkind = \"ukf\"\n").unwrap_err();
        assert!(e.contains("s.toml") && e.contains("eskf"), "{e}");
        let e = parse(&format!("{ok}[estimator.eskf]\ngate_nis = -1.0\n")).unwrap_err();
        assert!(
            e.contains("s.toml") && e.contains("estimator.eskf.gate_nis"),
            "{e}"
        );
        let e = parse(&format!("{ok}[estimator.eskf]\nbogus = 1.0\n")).unwrap_err();
        assert!(e.contains("s.toml") && e.contains("bogus"), "{e}");
        // the default section is not written (effective scenarios and
        // campaign hashes unchanged); a chosen one round-trips
        let plain = toml::to_string(&parse("duration_s = 1.0\n").unwrap()).unwrap();
        assert!(!plain.contains("estimator]"), "{plain}");
        let eskf = parse(ok).unwrap();
        let text = toml::to_string(&eskf).unwrap();
        assert_eq!(parse(&text).unwrap().estimator, eskf.estimator);
    }

    #[test]
    fn numbers_print_short() {
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(86400.0), "86400");
        assert_eq!(num(0.0025), "0.0025");
        assert_eq!(num(-1.0), "-1");
        assert_eq!(num(f64::NAN), "NaN");
    }
}
