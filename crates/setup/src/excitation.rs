//! Flight-test excitations (`[[excitation]]` of a scenario, of a mission
//! file or of `onboard.toml`): entries, each one of the [`crate::inputs`] (sweep, Schroeder multisine, doublet, 3211)
//! on one servo channel from a start time. The flight computer adds their sum
//! to the law's command before saturation (closed loop), or to the trim
//! inputs when `controller.feedback = false` (open loop), so the estimator
//! predicts with what was applied; `log.csv` records it (`exc_*`).

use crate::inputs::InputError;
use helicon_config::ConfigError;
use helicon_core::state::Input;
use serde::{Deserialize, Serialize};

/// The servo channels, in the order of the input vector.
pub const SERVOS: [&str; 4] = ["S_col", "S_lat", "S_lon", "S_tr"];

/// One `[[excitation]]` entry of a scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExcitationEntry {
    /// Servo channel: `S_col`, `S_lat`, `S_lon` or `S_tr`.
    pub servo: String,
    /// Start time of the input (s).
    #[serde(default)]
    pub t_s: f64,
    /// The input program (a table with `kind`); its
    /// amplitude is in the servo's unit (rad).
    pub input: crate::inputs::Input,
}

/// The prepared excitations of a scenario: the servo offsets at any time.
#[derive(Debug, Clone, Default)]
pub struct Excitations {
    entries: Vec<(usize, f64, crate::inputs::Input)>,
}

impl Excitations {
    /// Check and prepare `entries`; errors name `file` and the field
    /// (`excitation[1].input.duration_s`).
    pub fn new(entries: &[ExcitationEntry], file: &str) -> Result<Self, ConfigError> {
        let bad = |field: String, value: String, rule: String| ConfigError::Invalid {
            file: file.to_string(),
            field,
            value,
            rule,
        };
        let mut out = Vec::with_capacity(entries.len());
        for (i, e) in entries.iter().enumerate() {
            let Some(ch) = SERVOS.iter().position(|s| *s == e.servo) else {
                return Err(bad(
                    format!("excitation[{i}].servo"),
                    format!("{:?}", e.servo),
                    "must be S_col, S_lat, S_lon or S_tr".into(),
                ));
            };
            if !(e.t_s.is_finite() && e.t_s >= 0.0) {
                return Err(bad(
                    format!("excitation[{i}].t_s"),
                    e.t_s.to_string(),
                    "must be finite and >= 0 s".into(),
                ));
            }
            let mut input = e.input.clone();
            input.prepare().map_err(|err| match err {
                InputError::Invalid { field, value, rule } => {
                    // ident names fields `sweep.duration_s`: keep the field
                    let name = field.rsplit('.').next().unwrap_or(&field).to_string();
                    bad(format!("excitation[{i}].input.{name}"), value, rule)
                }
                other => bad(
                    format!("excitation[{i}].input"),
                    "-".into(),
                    other.to_string(),
                ),
            })?;
            out.push((ch, e.t_s, input));
        }
        Ok(Excitations { entries: out })
    }

    /// No entries.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The servo offsets at `t_s` (rad; the sum of the entries on each
    /// channel). Allocates nothing.
    pub fn at(&self, t_s: f64) -> Input {
        let mut u = Input::zeros();
        for (ch, t0, input) in &self.entries {
            u[*ch] += input.value(t_s - t0);
        }
        u
    }
}
