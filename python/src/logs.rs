//! Closed-loop flights in memory, as `helicon sim` flies them: the same
//! overrides (`--params`, `--seed`, `--duration`), the same preparation
//! (trim, linearize, design or load the gains), the same work bound, and
//! the flight's log as the columns of `log.csv` ([`LOG_SCHEMA`], same
//! names, same values: `log.csv` prints each number in its shortest
//! round-trip form, so a parsed `log.csv` equals these columns bit for bit).

use crate::error::{Error, Result};
use helicon_model::Params;
use helicon_sim::closed_loop::{Flight, LogRow, fly_until, prepare, prepare_with_params};
use helicon_sim::log_csv::LOG_SCHEMA;
use helicon_sim::scenario::{Scenario, ScenarioOverrides, num};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// The plant parameters of a flight.
#[derive(Debug, Clone, Default)]
pub enum ParamsSource {
    /// The scenario's `params` file, or the Bergen Twin.
    #[default]
    Scenario,
    /// A parameter file (as `helicon sim --params FILE`).
    File(PathBuf),
    /// These parameters.
    Value(Box<Params>),
}

/// Overrides of a scenario (the CLI's `--params`, `--seed`, `--duration`).
#[derive(Debug, Clone, Default)]
pub struct SimOptions {
    /// Flight time (s) instead of `duration_s`.
    pub duration_s: Option<f64>,
    /// Seed of the wind and sensor random streams.
    pub seed: Option<u64>,
    /// Plant parameters.
    pub params: ParamsSource,
}

/// The scenario with the overrides applied and validated, and the label
/// errors name it by (`file (with seed=7)`).
pub fn with_options(
    scenario: Scenario,
    source: &str,
    o: &SimOptions,
) -> Result<(Scenario, String)> {
    let params = match &o.params {
        ParamsSource::File(p) => Some(std::path::absolute(p).map_err(|e| {
            Error::new(format!(
                "params {}: cannot resolve the path: {e}",
                p.display()
            ))
        })?),
        _ => None,
    };
    let mut given = Vec::new();
    if let Some(p) = &params {
        given.push(format!("params={}", p.display()));
    }
    if let ParamsSource::Value(_) = o.params {
        given.push("params=Params(...)".to_string());
    }
    if let Some(s) = o.seed {
        given.push(format!("seed={s}"));
    }
    if let Some(d) = o.duration_s {
        given.push(format!("duration={}", num(d)));
    }
    let label = if given.is_empty() {
        source.to_string()
    } else {
        format!("{source} (with {})", given.join(", "))
    };
    let overrides = ScenarioOverrides {
        params,
        seed: o.seed,
        duration_s: o.duration_s,
    };
    Ok((scenario.with_overrides(&overrides, &label)?, label))
}

/// A scenario file.
pub fn load_scenario(path: &Path) -> Result<Scenario> {
    Ok(Scenario::from_file(path)?)
}

/// One flown case.
#[derive(Debug, Clone)]
pub struct CaseResult {
    /// The case's scenario name (`<scenario>-<case>` for a `[[case]]`).
    pub name: String,
    /// The case label (the `[[case]]` name, or the scenario name).
    pub label: String,
    /// The columns of `log.csv`, in [`LOG_SCHEMA`] order.
    pub columns: Vec<Vec<f64>>,
    /// `summary.json`.
    pub summary: Value,
    /// `completed` or `diverged`.
    pub outcome: String,
}

/// The column names of `log.csv`, in order.
pub fn column_names() -> Vec<&'static str> {
    LOG_SCHEMA.iter().map(|c| c.name).collect()
}

/// The SI unit of each `log.csv` column, in order.
pub fn column_units() -> Vec<&'static str> {
    LOG_SCHEMA.iter().map(|c| c.unit).collect()
}

/// A flight log as the columns of `log.csv`.
pub fn columns(log: &[LogRow]) -> Vec<Vec<f64>> {
    LOG_SCHEMA
        .iter()
        .map(|c| log.iter().map(|r| c.value(r)).collect())
        .collect()
}

/// The cases of `scenario` (one when it has no `[[case]]`), with their labels.
pub fn cases(scenario: &Scenario) -> Vec<(String, Scenario)> {
    let prefix = format!("{}-", scenario.name);
    scenario
        .cases()
        .into_iter()
        .map(|c| {
            let label = if scenario.variants.is_empty() {
                c.name.clone()
            } else {
                c.name.strip_prefix(&prefix).unwrap_or(&c.name).to_string()
            };
            (label, c)
        })
        .collect()
}

/// Prepare and fly one case (`source` names it in errors), keeping the log
/// in memory. A divergence is an outcome, not an error. Once `stop` is set
/// (from another thread) the flight ends after the sample being flown, with
/// the outcome `stopped`.
pub fn fly_case(
    label: &str,
    case: &Scenario,
    params: &ParamsSource,
    source: &str,
    stop: &AtomicBool,
) -> Result<CaseResult> {
    let prepared = match params {
        ParamsSource::Value(p) => prepare_with_params(case, **p),
        _ => prepare(case),
    }
    .map_err(|e| {
        Error::from(e).context(&format!(
            "scenario `{}`: preparing the design point and gains",
            case.name
        ))
    })?;
    case.check_work(source, prepared.gains.set.sample_time_s)?;
    let flight: Flight = fly_until(case, &prepared, None, stop).map_err(|e| {
        Error::from(e).context(&format!("scenario `{}`: setting up the flight", case.name))
    })?;
    let summary = serde_json::to_value(&flight.summary)
        .map_err(|e| Error::new(format!("scenario `{}`: the summary: {e}", case.name)))?;
    Ok(CaseResult {
        name: case.name.clone(),
        label: label.to_string(),
        columns: columns(&flight.log),
        outcome: flight.summary.outcome.as_str().to_string(),
        summary,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(text: &str) -> Scenario {
        Scenario::from_toml_str(text, "test.toml").unwrap()
    }

    #[test]
    fn a_short_hover_flies_and_logs_every_column() {
        let s = scenario("name = \"h\"\nduration_s = 0.05\n");
        let (s, label) = with_options(
            s,
            "test.toml",
            &SimOptions {
                seed: Some(3),
                ..SimOptions::default()
            },
        )
        .unwrap();
        assert_eq!(label, "test.toml (with seed=3)");
        let cs = cases(&s);
        assert_eq!(cs.len(), 1);
        let r = fly_case(
            &cs[0].0,
            &cs[0].1,
            &ParamsSource::Scenario,
            &label,
            &AtomicBool::new(false),
        )
        .unwrap();
        assert_eq!(r.columns.len(), column_names().len());
        assert_eq!(r.outcome, "completed");
        assert_eq!(r.summary["wind_seed"], serde_json::json!(3));
        let t = &r.columns[0];
        assert!(t.len() >= 20 && t.windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn bad_overrides_name_the_field() {
        let s = scenario("duration_s = 1.0\n");
        let e = with_options(
            s,
            "x.toml",
            &SimOptions {
                duration_s: Some(-1.0),
                ..SimOptions::default()
            },
        )
        .unwrap_err();
        assert!(e.message().contains("duration_s"), "{e}");
    }
}
