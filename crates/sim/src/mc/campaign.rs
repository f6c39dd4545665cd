//! The campaign file: dispersions, design mode, loading and validation, hash.

use super::McError;
use crate::closed_loop::fnv1a_hex;
use crate::scenario::Scenario;
use helicon_model::Params;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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
pub(super) fn param_field(name: &str) -> Option<helicon_model::params::Field> {
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
