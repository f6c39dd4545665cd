//! An on-board mission file: a scenario file as the on-board program reads
//! it. It flies the scenario's flight plan (`[trim]` velocity and heading,
//! `[[reference]]` or `[trajectory]`) and its `[[excitation]]`; the
//! simulator's world and design sections (`preset`, `params`, `initial`,
//! `wind`, `sensors`, `navigation`, `estimator`, `controller`, `plant`,
//! `log`, `[[case]]`) are accepted and not read — on board the helicopter is
//! the world and `onboard.toml` configures the flight software. Any other key
//! is refused, so a misspelt section is an error, as in a scenario.

use crate::excitation::ExcitationEntry;
use crate::plan::{
    ReferenceChange, ReferenceSchedule, TrajectorySection, TrimSection, check_references,
    check_trim,
};
use helicon_config::ConfigError;
use serde::Deserialize;
use std::path::Path;

/// The part of a scenario file the on-board program flies.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissionFile {
    /// Name (used in messages).
    #[serde(default = "default_name")]
    pub name: String,
    /// The flight's duration in the simulator (s; the on-board program
    /// flies until it is stopped).
    #[serde(default)]
    pub duration_s: Option<f64>,
    /// The trim the references start from.
    #[serde(default)]
    pub trim: TrimSection,
    /// Reference changes.
    #[serde(default)]
    pub reference: Vec<ReferenceChange>,
    /// Jerk-limited references instead of `[[reference]]`.
    #[serde(default)]
    pub trajectory: Option<TrajectorySection>,
    /// Flight-test excitations added to the servo commands.
    #[serde(default)]
    pub excitation: Vec<ExcitationEntry>,
    // The simulator's sections, accepted and not read on board.
    #[serde(default, rename = "preset")]
    _preset: Option<toml::Value>,
    #[serde(default, rename = "params")]
    _params: Option<toml::Value>,
    #[serde(default, rename = "initial")]
    _initial: Option<toml::Value>,
    #[serde(default, rename = "wind")]
    _wind: Option<toml::Value>,
    #[serde(default, rename = "sensors")]
    _sensors: Option<toml::Value>,
    #[serde(default, rename = "navigation")]
    _navigation: Option<toml::Value>,
    #[serde(default, rename = "estimator")]
    _estimator: Option<toml::Value>,
    #[serde(default, rename = "controller")]
    _controller: Option<toml::Value>,
    #[serde(default, rename = "plant")]
    _plant: Option<toml::Value>,
    #[serde(default, rename = "log")]
    _log: Option<toml::Value>,
    #[serde(default, rename = "case")]
    _case: Option<toml::Value>,
}

fn default_name() -> String {
    "scenario".to_string()
}

impl MissionFile {
    /// Parse and check a mission file's text; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ConfigError> {
        let m: MissionFile = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        check_trim(&m.trim, file)?;
        check_references(&m.reference, file)?;
        if let Some(t) = &m.trajectory {
            if !m.reference.is_empty() {
                return Err(ConfigError::Parse {
                    file: file.to_string(),
                    message: "[trajectory] replaces [[reference]]: give one of them".into(),
                });
            }
            t.mission(&m.trim, file)?;
        }
        crate::excitation::Excitations::new(&m.excitation, file)?;
        Ok(m)
    }

    /// Read and check a mission file.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let (file, text) = ConfigError::read_file(path)?;
        Self::from_toml_str(&text, &file)
    }

    /// The references flown, ready for allocation-free lookups.
    pub fn reference_schedule(&self) -> ReferenceSchedule {
        ReferenceSchedule::new(&self.trim, &self.reference, self.trajectory.as_ref())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // a failed unwrap is a failed test
    use super::*;

    /// A scenario file reads as a mission: its plan flown, the simulator's
    /// sections accepted, a misspelt key refused naming the file.
    #[test]
    fn a_scenario_file_is_a_mission_file() {
        let text = "name = \"m\"\nduration_s = 5.0\npreset = \"thesis\"\n\
            [trim]\nyaw_rad = 0.5\n[[reference]]\nt_s = 1.0\noutput = \"vn\"\nvalue = 2.0\n\
            [wind]\nkind = \"none\"\n[plant]\nsubsteps = 2\n";
        let m = MissionFile::from_toml_str(text, "m.toml").unwrap();
        let r = m.reference_schedule();
        assert_eq!(r.at(0.0), [0.0, 0.0, 0.0, 0.5]);
        assert_eq!(r.at(2.0), [2.0, 0.0, 0.0, 0.5]);
        let e = MissionFile::from_toml_str("[[refrence]]\nt_s = 1.0\n", "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.toml") && e.contains("refrence"), "{e}");
        let e = MissionFile::from_toml_str(
            "[[reference]]\nt_s = 1.0\noutput = \"vx\"\nvalue = 1.0\n",
            "m.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("reference[0].output"), "{e}");
    }
}
