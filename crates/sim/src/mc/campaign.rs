//! The campaign file: dispersions, design mode, loading and validation, hash.

use super::McError;
use super::landing::{LandingCriteria, LandingSection};
use crate::closed_loop::fnv1a_hex;
use crate::scenario::{Scenario, ScenarioError};
use helicon_model::Params;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
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
    trace_runs: Option<usize>,
    #[serde(default)]
    dispersion: Vec<Dispersion>,
    #[serde(default)]
    landing: Option<LandingSection>,
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
    /// Keep traces only for the runs with an index below this (`None`: all).
    pub trace_runs: Option<usize>,
    /// Dispersions, in file order.
    pub dispersions: Vec<Dispersion>,
    /// The take-off and landing criteria: present exactly when the
    /// scenario has a `[ground]` section (the file's `[landing]` table, or
    /// the defaults).
    pub landing: Option<LandingCriteria>,
    /// The campaign file's text (copied into the output folder).
    pub source: String,
    /// Hash of everything that determines a run (not `runs`); recomputed by
    /// [`Campaign::with_overrides`].
    pub hash: String,
    /// Command-line overrides applied after loading (`--seed 7`, …), as
    /// recorded in `manifest.json`.
    pub overrides: Vec<String>,
}

/// Overrides of a loaded campaign (`helicon mc --seed/--duration/--params`).
#[derive(Debug, Clone, Default)]
pub struct CampaignOverrides {
    /// Campaign seed instead of the file's `seed`.
    pub seed: Option<u64>,
    /// Flight duration (s) instead of the scenario's `duration_s`.
    pub duration_s: Option<f64>,
    /// Nominal plant parameters (a `helicon params` TOML file) instead of
    /// the scenario's `params` file or the Bergen Twin.
    pub params: Option<PathBuf>,
    /// Keep traces only for the runs with an index below this.
    pub trace_runs: Option<usize>,
}

/// A dispersed value of the scenario's wind: a `[[dispersion]]` key
/// `wind.…` instead of a parameter key. Relative and absolute kinds work as
/// for parameters, around the base scenario's value (the steady wind's
/// components are 0 when the scenario has no `[wind.steady]`; the thesis
/// and Dryden values need their section in the scenario).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WindKey {
    /// `wind.steady.north_m_s`: the steady wind's north component (m/s, where the air moves to).
    SteadyNorth,
    /// `wind.steady.east_m_s`: its east component (m/s).
    SteadyEast,
    /// `wind.steady.down_m_s`: its down component (m/s).
    SteadyDown,
    /// `wind.thesis.max_gust_m_s`: the thesis wind's gust amplitude (m/s).
    ThesisMaxGust,
    /// `wind.thesis.turbulence_sigma_m_s`: the thesis wind's turbulence σ (m/s).
    ThesisTurbulenceSigma,
    /// `wind.dryden.w20_m_s`: the Dryden turbulence's wind speed at 20 ft (m/s).
    DrydenW20,
}

impl WindKey {
    /// Every wind key.
    pub const ALL: [WindKey; 6] = [
        WindKey::SteadyNorth,
        WindKey::SteadyEast,
        WindKey::SteadyDown,
        WindKey::ThesisMaxGust,
        WindKey::ThesisTurbulenceSigma,
        WindKey::DrydenW20,
    ];

    /// The key as written in `[[dispersion]]` and `runs.csv`.
    pub fn key(self) -> &'static str {
        match self {
            WindKey::SteadyNorth => "wind.steady.north_m_s",
            WindKey::SteadyEast => "wind.steady.east_m_s",
            WindKey::SteadyDown => "wind.steady.down_m_s",
            WindKey::ThesisMaxGust => "wind.thesis.max_gust_m_s",
            WindKey::ThesisTurbulenceSigma => "wind.thesis.turbulence_sigma_m_s",
            WindKey::DrydenW20 => "wind.dryden.w20_m_s",
        }
    }

    /// The wind key of `name`, if it is one.
    pub fn parse(name: &str) -> Option<WindKey> {
        WindKey::ALL.into_iter().find(|k| k.key() == name)
    }

    /// The value it disperses in `wind` (`None`: its section is absent; the
    /// steady wind is created at rest when absent).
    pub fn slot(self, wind: &mut crate::wind::WindConfig) -> Option<&mut f64> {
        use crate::wind::SteadyWindConfig;
        fn steady(i: usize, w: &mut crate::wind::WindConfig) -> Option<&mut f64> {
            w.steady
                .get_or_insert(SteadyWindConfig {
                    wind_ned_m_s: [0.0; 3],
                })
                .wind_ned_m_s
                .get_mut(i)
        }
        match self {
            WindKey::SteadyNorth => steady(0, wind),
            WindKey::SteadyEast => steady(1, wind),
            WindKey::SteadyDown => steady(2, wind),
            WindKey::ThesisMaxGust => wind.thesis.as_mut().map(|t| &mut t.max_gust_m_s),
            WindKey::ThesisTurbulenceSigma => {
                wind.thesis.as_mut().map(|t| &mut t.turbulence_sigma_m_s)
            }
            WindKey::DrydenW20 => wind.dryden.as_mut().map(|d| &mut d.w20_m_s),
        }
    }
}

/// Why `key` cannot be dispersed in `scenario`, if it cannot.
fn key_rule(key: &str, scenario: &Scenario) -> Option<&'static str> {
    match WindKey::parse(key) {
        Some(w) => w.slot(&mut scenario.wind.clone()).is_none().then_some(
            "the scenario has no such wind section to disperse (add it to its [wind])",
        ),
        None => param_field(key).is_none().then_some(
            "not a parameter key (run `helicon params` for the list) nor a wind key (wind.steady.north_m_s, wind.steady.east_m_s, wind.steady.down_m_s, wind.thesis.max_gust_m_s, wind.thesis.turbulence_sigma_m_s, wind.dryden.w20_m_s)",
        ),
    }
}

/// Is `name` a key a `[[dispersion]]` may disperse (a parameter or a wind key)?
pub(super) fn dispersion_key_known(name: &str) -> bool {
    param_field(name).is_some() || WindKey::parse(name).is_some()
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
        let (file, text) = helicon_model::ConfigError::read_file(path)?;
        Self::from_toml_str(&text, &file, path.parent())
    }

    /// Parse campaign TOML; `file` names it in errors, `base_dir` resolves
    /// a scenario path.
    pub fn from_toml_str(
        text: &str,
        file: &str,
        base_dir: Option<&Path>,
    ) -> Result<Campaign, McError> {
        let raw: CampaignFile = toml::from_str(text).map_err(|e| ScenarioError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        let bad = |field: &str, value: String, rule: &str| ScenarioError::Invalid {
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
                let s = toml::to_string(t).map_err(|e| ScenarioError::Parse {
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
        if raw.runs == 0 {
            return Err(bad("runs", "0".into(), "must be >= 1").into());
        }
        if !(raw.trace_rate_hz.is_finite() && raw.trace_rate_hz >= 0.0) {
            return Err(bad(
                "trace_rate_hz",
                raw.trace_rate_hz.to_string(),
                "must be finite and >= 0",
            )
            .into());
        }
        let mut first_of: BTreeMap<&str, usize> = BTreeMap::new();
        for (i, d) in raw.dispersion.iter().enumerate() {
            let at = |f: &str| format!("dispersion[{i}].{f}");
            if let Some(rule) = key_rule(&d.param, &scenario) {
                return Err(bad(&at("param"), d.param.clone(), rule).into());
            }
            if let Some(j) = first_of.insert(&d.param, i) {
                // two runs.csv columns of one name could not be read back
                return Err(bad(
                    &at("param"),
                    d.param.clone(),
                    &format!(
                        "already dispersed by dispersion[{j}]: a key is dispersed once (merge the two entries)"
                    ),
                )
                .into());
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
                )
                .into());
            }
            match width {
                None => {
                    return Err(bad(&at(wname), "missing".into(), "required").into());
                }
                Some(w) if !(w.is_finite() && w >= 0.0) => {
                    return Err(bad(&at(wname), w.to_string(), "must be finite and >= 0").into());
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
                )
                .into());
            }
        }
        let landing = match (&scenario.ground, &raw.landing) {
            (Some(g), l) => Some(l.unwrap_or_default().resolve(file, g.takeoff_s)?),
            (None, Some(_)) => {
                return Err(bad(
                    "landing",
                    "given".into(),
                    "needs a scenario with a [ground] section (take-offs and landings to judge)",
                )
                .into());
            }
            (None, None) => None,
        };
        let name = raw.name.clone().unwrap_or_else(|| scenario.name.clone());
        let mut c = Campaign {
            name,
            runs: raw.runs,
            seed: raw.seed,
            scenario,
            nominal,
            design: raw.design,
            disperse_wind_seed: raw.disperse_wind_seed,
            disperse_sensor_seed: raw.disperse_sensor_seed,
            trace_rate_hz: raw.trace_rate_hz,
            trace_runs: raw.trace_runs,
            dispersions: raw.dispersion,
            landing,
            source: text.to_string(),
            hash: String::new(),
            overrides: Vec::new(),
        };
        c.hash = c.compute_hash(file)?;
        Ok(c)
    }

    /// Apply command-line overrides (validated like the fields they replace;
    /// errors name the option) and recompute the hash: a campaign flown with
    /// another seed, duration or parameter set is another campaign.
    pub fn with_overrides(mut self, o: &CampaignOverrides) -> Result<Campaign, McError> {
        if let Some(seed) = o.seed {
            self.seed = seed;
            self.overrides.push(format!("--seed {seed}"));
        }
        if let Some(d) = o.duration_s {
            let mut sc = self.scenario.clone();
            sc.duration_s = d;
            sc.validate("--duration")?;
            self.scenario = sc;
            self.overrides.push(format!("--duration {d}"));
        }
        if let Some(p) = &o.params {
            self.nominal = Params::from_file(p)?;
            self.overrides.push(format!("--params {}", p.display()));
        }
        if let Some(n) = o.trace_runs {
            self.trace_runs = Some(n);
            self.overrides.push(format!("--trace-runs {n}"));
        }
        if !self.overrides.is_empty() {
            self.hash = self.compute_hash("<overrides>")?;
        }
        Ok(self)
    }

    /// FNV-1a of everything that determines a run's result: seed, design,
    /// seed flags, trace rate, dispersions, the effective scenario and the
    /// full nominal parameter set (not `runs`, not the name).
    fn compute_hash(&self, file: &str) -> Result<String, McError> {
        let mut s = String::new();
        let _ = writeln!(s, "seed={}", self.seed);
        let _ = writeln!(s, "design={:?}", self.design);
        let _ = writeln!(
            s,
            "seeds={} {}",
            self.disperse_wind_seed, self.disperse_sensor_seed
        );
        let _ = writeln!(s, "trace={}", self.trace_rate_hz);
        if let Some(n) = self.trace_runs {
            // only when given: the hashes of campaigns without it are unchanged
            let _ = writeln!(s, "trace_runs={n}");
        }
        for d in &self.dispersions {
            let _ = writeln!(s, "{d:?}");
        }
        if let Some(l) = &self.landing {
            // only with [ground]: the hashes of the other campaigns are unchanged
            let _ = writeln!(s, "landing={l:?}");
        }
        let sc = toml::to_string(&self.scenario).map_err(|e| McError::Serialize {
            file: format!("{file} [scenario]"),
            message: e.to_string(),
        })?;
        let _ = writeln!(s, "{sc}");
        s.push_str(&self.nominal.to_toml());
        Ok(fnv1a_hex(&s))
    }
}
