//! The parameter table the ground station reads and sets (MAVLink parameter
//! protocol): the navigator's tuning, the link-loss failsafe and the
//! geofence (PX4's `GF_*` names and codes), every value
//! a `REAL32` with a range. A set is validated as a whole tuning (e.g. the
//! cruise speed may not exceed the largest speed); a refused value is
//! answered with the unchanged one.

use crate::fence::{Fence, FenceAction};
use crate::navigator::{LinkLossAction, NavigatorConfig};

/// The parameters: name (≤ 16 characters, as MAVLink carries them), the
/// navigator field it sets, unit and meaning.
pub const PARAMS: [(&str, &str); 17] = [
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
    (
        "GF_MAX_HOR_DIST",
        "fence.max_hor_dist_m: largest horizontal distance from home (m)",
    ),
    (
        "GF_MAX_VER_DIST",
        "fence.max_ver_dist_m: largest height above home (m)",
    ),
    (
        "GF_ACTION",
        "fence.action: 1 warning, 2 hold, 3 return and land, 5 land",
    ),
];

const FS_LINK_ACT: usize = 13;
const GF_MAX_HOR_DIST: usize = 14;
const GF_ACTION: usize = 16;

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

    fn values(&self) -> [f64; PARAMS.len()] {
        let c = &self.config;
        let mut all = [0.0; PARAMS.len()];
        all[..FS_LINK_ACT].copy_from_slice(&c.values());
        all[FS_LINK_ACT] = f64::from(c.link_loss_action.code());
        all[GF_MAX_HOR_DIST] = c.fence.max_hor_dist_m;
        all[GF_MAX_HOR_DIST + 1] = c.fence.max_ver_dist_m;
        all[GF_ACTION] = f64::from(c.fence.action.code());
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
        let code = (v.fract() == 0.0 && (0.0..=255.0).contains(&v)).then_some(v as u8);
        let link_loss_action = if i == FS_LINK_ACT {
            code.and_then(LinkLossAction::from_code)
                .ok_or_else(|| reject("must be 0 (hold), 1 (return) or 2 (land)".into()))?
        } else {
            self.config.link_loss_action
        };
        let fence_action = if i == GF_ACTION {
            code.and_then(FenceAction::from_code).ok_or_else(|| {
                reject("must be 1 (warning), 2 (hold), 3 (return) or 5 (land)".into())
            })?
        } else {
            self.config.fence.action
        };
        let mut numeric = [0.0; 13];
        numeric.copy_from_slice(&all[..FS_LINK_ACT]);
        let fence = Fence {
            max_hor_dist_m: all[GF_MAX_HOR_DIST],
            max_ver_dist_m: all[GF_MAX_HOR_DIST + 1],
            action: fence_action,
        };
        let candidate = NavigatorConfig::from_values(numeric, link_loss_action, fence);
        match candidate.validate() {
            Ok(()) => {
                self.config = candidate;
                Ok(i)
            }
            Err(e) => {
                let (lo, hi) = NavigatorConfig::RANGES
                    .iter()
                    .chain(Fence::RANGES.iter())
                    .find(|(f, _, _)| *f == e.field.trim_start_matches("fence."))
                    .map_or((f64::NAN, f64::NAN), |(_, l, h)| (*l, *h));
                Err(reject(format!("{} (range [{lo}, {hi}])", e)))
            }
        }
    }
}
