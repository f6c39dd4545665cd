//! The parameter table the ground station reads and sets (MAVLink parameter
//! protocol): the navigator's tuning and the link-loss failsafe, every value
//! a `REAL32` with a range. A set is validated as a whole tuning (e.g. the
//! cruise speed may not exceed the largest speed); a refused value is
//! answered with the unchanged one.

use crate::navigator::{LinkLossAction, NavigatorConfig};

/// The parameters: name (≤ 16 characters, as MAVLink carries them), the
/// navigator field it sets, unit and meaning.
pub const PARAMS: [(&str, &str); 14] = [
    (
        "NAV_CRUISE_SPD",
        "cruise_speed_m_s: horizontal speed of legs without their own (m/s)",
    ),
    (
        "NAV_MAX_SPD",
        "max_speed_m_s: largest horizontal speed (m/s)",
    ),
    (
        "NAV_MAX_ACC",
        "max_accel_m_s2: largest change of the velocity reference (m/s²)",
    ),
    (
        "NAV_CLIMB_SPD",
        "climb_speed_m_s: largest upward speed (m/s)",
    ),
    (
        "NAV_DESC_SPD",
        "descent_speed_m_s: largest downward and landing speed (m/s)",
    ),
    (
        "NAV_POS_GAIN",
        "position_gain_1_s: velocity per metre of position error (1/s)",
    ),
    (
        "NAV_YAWRATE_MAX",
        "yaw_rate_max_rad_s: largest heading rate (rad/s)",
    ),
    (
        "NAV_ACC_RAD",
        "acceptance_radius_m: default waypoint acceptance radius (m)",
    ),
    (
        "NAV_TKOFF_ALT",
        "takeoff_height_m: takeoff height when a command gives none (m)",
    ),
    (
        "NAV_LANDED_ALT",
        "landed_height_m: height at which a landing is complete (m)",
    ),
    (
        "NAV_GUIDED_TO",
        "guided_timeout_s: age after which a guided velocity is dropped (s)",
    ),
    (
        "FS_LINK_TO",
        "link_loss_timeout_s: heartbeat silence that is a link loss (s)",
    ),
    (
        "FS_LINK_HOLD",
        "link_loss_hold_s: hold before the link-loss action (s)",
    ),
    (
        "FS_LINK_ACT",
        "link_loss_action: 0 hold, 1 return and land, 2 land",
    ),
];

/// A refused parameter set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// No such parameter.
    #[error("no parameter {0}")]
    Unknown(String),
    /// The value breaks a rule.
    #[error("{name} = {value}: {rule}")]
    Rejected {
        /// The parameter.
        name: &'static str,
        /// The value refused.
        value: f32,
        /// Why.
        rule: String,
    },
}

/// The table's values (the navigator tuning).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamTable {
    config: NavigatorConfig,
}

impl ParamTable {
    /// The table of a tuning.
    pub fn new(config: NavigatorConfig) -> Self {
        ParamTable { config }
    }

    /// The tuning.
    pub fn config(&self) -> &NavigatorConfig {
        &self.config
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        PARAMS.len()
    }

    /// Never empty.
    pub fn is_empty(&self) -> bool {
        false
    }

    fn values(&self) -> [f64; 14] {
        let v = self.config.values();
        let mut all = [0.0; 14];
        all[..13].copy_from_slice(&v);
        all[13] = f64::from(self.config.link_loss_action.code());
        all
    }

    /// Name and value of the parameter at `index`.
    pub fn get(&self, index: usize) -> Option<(&'static str, f32)> {
        let name = PARAMS.get(index)?.0;
        Some((name, self.values()[index] as f32))
    }

    /// The index of a name.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        PARAMS.iter().position(|(n, _)| *n == name)
    }

    /// Set a parameter: the whole tuning is validated before anything
    /// changes. Returns the index set.
    pub fn set(&mut self, name: &str, value: f32) -> Result<usize, ParamError> {
        let i = self
            .index_of(name)
            .ok_or_else(|| ParamError::Unknown(name.to_string()))?;
        let pname = PARAMS[i].0;
        let reject = |rule: String| ParamError::Rejected {
            name: pname,
            value,
            rule,
        };
        let v = f64::from(value);
        let mut all = self.values();
        all[i] = v;
        let action = if i == 13 {
            let code = if v.fract() == 0.0 && (0.0..=255.0).contains(&v) {
                LinkLossAction::from_code(v as u8)
            } else {
                None
            };
            code.ok_or_else(|| reject("must be 0 (hold), 1 (return) or 2 (land)".into()))?
        } else {
            self.config.link_loss_action
        };
        let mut numeric = [0.0; 13];
        numeric.copy_from_slice(&all[..13]);
        let candidate = NavigatorConfig::from_values(numeric, action);
        match candidate.validate() {
            Ok(()) => {
                self.config = candidate;
                Ok(i)
            }
            Err(e) => {
                let (lo, hi) = NavigatorConfig::RANGES
                    .iter()
                    .find(|(f, _, _)| *f == e.field)
                    .map_or((f64::NAN, f64::NAN), |(_, l, h)| (*l, *h));
                Err(reject(format!("{} (range [{lo}, {hi}])", e)))
            }
        }
    }
}
