//! The geofence: a cylinder about home — a largest horizontal distance and a
//! largest height above home — and the ground at home as the floor. The one
//! implementation every check uses: the ground-station server refuses
//! position targets, guided gotos, mission waypoints and takeoff heights
//! outside it, and the navigator acts on a breach of the estimate.
//!
//! The names and codes are PX4's where PX4 has them: `GF_MAX_HOR_DIST`,
//! `GF_MAX_VER_DIST` (m) and `GF_ACTION` (1 warning, 2 hold, 3 return, 5
//! land; PX4's 0 "none" and 4 "terminate" are not offered: a fence that
//! does nothing is not a fence, and a helicopter is not terminated).
//!
//! Positions are NED about home (m): the height above home is `−d`.

use nalgebra::Vector3;

/// What a breach of the fence does (PX4's `GF_ACTION` codes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FenceAction {
    /// Tell the operator only (code 1).
    Warn,
    /// Hold where the breach was seen (code 2).
    Hold,
    /// Return home (at most at the fence's height) and land (code 3).
    Return,
    /// Land where it is (code 5).
    Land,
}

impl FenceAction {
    /// The parameter's code (PX4's `GF_ACTION`).
    pub fn code(self) -> u8 {
        match self {
            FenceAction::Warn => 1,
            FenceAction::Hold => 2,
            FenceAction::Return => 3,
            FenceAction::Land => 5,
        }
    }

    /// The action of a code (`None`: not offered).
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(FenceAction::Warn),
            2 => Some(FenceAction::Hold),
            3 => Some(FenceAction::Return),
            5 => Some(FenceAction::Land),
            _ => None,
        }
    }
}

/// The fence (the `[gcs.navigator.fence]` section; every field optional).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Fence {
    /// Largest horizontal distance from home (m; `GF_MAX_HOR_DIST`).
    pub max_hor_dist_m: f64,
    /// Largest height above home (m; `GF_MAX_VER_DIST`).
    pub max_ver_dist_m: f64,
    /// What a breach does (`GF_ACTION`).
    pub action: FenceAction,
}

impl Default for Fence {
    /// 150 m about home and 60 m up: a miniature helicopter flown in sight
    /// (its attitude is still readable by eye at 150 m), well under the
    /// 120 m ceiling of open-category flying; a breach returns and lands.
    fn default() -> Self {
        Fence {
            max_hor_dist_m: 150.0,
            max_ver_dist_m: 60.0,
            action: FenceAction::Return,
        }
    }
}

/// Which limit a position breaks.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum FenceViolation {
    /// A coordinate is NaN or infinite.
    #[error("position is not finite")]
    NotFinite,
    /// Farther from home than `GF_MAX_HOR_DIST`.
    #[error("{} m from home, beyond GF_MAX_HOR_DIST {limit_m:.0} m", metres(*distance_m))]
    Horizontal {
        /// Horizontal distance from home (m).
        distance_m: f64,
        /// The limit (m).
        limit_m: f64,
    },
    /// Higher above home than `GF_MAX_VER_DIST`.
    #[error("{} m above home, beyond GF_MAX_VER_DIST {limit_m:.0} m", metres(*height_m))]
    Vertical {
        /// Height above home (m).
        height_m: f64,
        /// The limit (m).
        limit_m: f64,
    },
    /// Below the ground at home.
    #[error("{} m below home", metres(*depth_m))]
    BelowHome {
        /// Depth below home (m).
        depth_m: f64,
    },
}

/// A distance as the operator reads it (status texts are 50 characters):
/// whole metres, or in exponent form beyond 100 km.
fn metres(m: f64) -> String {
    if m.abs() < 1e5 {
        format!("{m:.1}")
    } else {
        format!("{m:.1e}")
    }
}

impl FenceViolation {
    /// The violation is of the horizontal limit (for the protocol's field
    /// of the error: x/y rather than z).
    pub fn is_horizontal(&self) -> bool {
        matches!(self, FenceViolation::Horizontal { .. })
    }
}

/// A fence setting outside its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field} = {value}: {rule}")]
pub struct FenceRangeError {
    /// The field.
    pub field: &'static str,
    /// The value refused.
    pub value: f64,
    /// The rule.
    pub rule: &'static str,
}

/// Targets may lie this far below home (m): a landing target is the ground
/// (d = 0), and a rounding of a geodetic height must not refuse it.
pub const BELOW_HOME_TOLERANCE_M: f64 = 0.5;

impl Fence {
    /// The ranges of the numeric fields `(field, low, high)` (m): at least a
    /// hover's room, at most what is flown in sight.
    pub const RANGES: [(&'static str, f64, f64); 2] = [
        ("max_hor_dist_m", 5.0, 1000.0),
        ("max_ver_dist_m", 2.0, 120.0),
    ];

    /// Check the limits against [`Fence::RANGES`].
    pub fn validate(&self) -> Result<(), FenceRangeError> {
        for ((field, lo, hi), v) in Self::RANGES
            .iter()
            .zip([self.max_hor_dist_m, self.max_ver_dist_m])
        {
            if !(v.is_finite() && v >= *lo && v <= *hi) {
                return Err(FenceRangeError {
                    field,
                    value: v,
                    rule: "outside its range (see the parameter table)",
                });
            }
        }
        Ok(())
    }

    /// Whether a target position (NED about home, m) may be flown to: finite,
    /// inside the cylinder, not below home. The horizontal limit is named
    /// first: a point far away on the ellipsoid lies below home's local
    /// level (300 km away, 7 km below), but its fault is the distance.
    pub fn check_target(&self, position_ned_m: &Vector3<f64>) -> Result<(), FenceViolation> {
        if !position_ned_m.iter().all(|v| v.is_finite()) {
            return Err(FenceViolation::NotFinite);
        }
        if let Some(v) = self.outside(position_ned_m) {
            return Err(v);
        }
        if position_ned_m.z > BELOW_HOME_TOLERANCE_M {
            return Err(FenceViolation::BelowHome {
                depth_m: position_ned_m.z,
            });
        }
        Ok(())
    }

    /// Whether a height above home (m) may be flown to (a takeoff).
    pub fn check_height(&self, height_m: f64) -> Result<(), FenceViolation> {
        self.check_target(&Vector3::new(0.0, 0.0, -height_m))
    }

    /// The limit an estimated position (NED about home, m) breaks, if any:
    /// the horizontal distance and the height (the floor is the landing's
    /// business, not a breach). A non-finite estimate is no breach here:
    /// the flight software refuses such samples itself.
    pub fn outside(&self, position_ned_m: &Vector3<f64>) -> Option<FenceViolation> {
        let distance_m = position_ned_m.xy().norm();
        if distance_m > self.max_hor_dist_m {
            return Some(FenceViolation::Horizontal {
                distance_m,
                limit_m: self.max_hor_dist_m,
            });
        }
        let height_m = -position_ned_m.z;
        if height_m > self.max_ver_dist_m {
            return Some(FenceViolation::Vertical {
                height_m,
                limit_m: self.max_ver_dist_m,
            });
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cylinder_and_the_floor() {
        let f = Fence::default();
        assert!(f.check_target(&Vector3::new(100.0, 100.0, -59.0)).is_ok());
        // 150 m: on the fence is inside; 3-4-5 triangle: 90² + 120² = 150²
        assert!(f.check_target(&Vector3::new(90.0, 120.0, -10.0)).is_ok());
        assert!(matches!(
            f.check_target(&Vector3::new(90.0, 120.1, -10.0)),
            Err(FenceViolation::Horizontal { .. })
        ));
        assert!(matches!(
            f.check_target(&Vector3::new(0.0, 0.0, -3e38)),
            Err(FenceViolation::Vertical { .. })
        ));
        assert!(matches!(
            f.check_target(&Vector3::new(0.0, 0.0, 3.0)),
            Err(FenceViolation::BelowHome { .. })
        ));
        assert_eq!(
            f.check_target(&Vector3::new(f64::NAN, 0.0, 0.0)),
            Err(FenceViolation::NotFinite)
        );
        assert!(f.check_height(60.0).is_ok() && f.check_height(60.5).is_err());
        assert!(f.outside(&Vector3::new(0.0, 0.0, 5.0)).is_none());
    }

    #[test]
    fn ranges_and_codes() {
        assert!(Fence::default().validate().is_ok());
        for (h, v) in [(4.0, 60.0), (150.0, 121.0), (f64::NAN, 60.0)] {
            let f = Fence {
                max_hor_dist_m: h,
                max_ver_dist_m: v,
                ..Fence::default()
            };
            assert!(f.validate().is_err(), "{h} {v}");
        }
        for c in 0..=255u8 {
            if let Some(a) = FenceAction::from_code(c) {
                assert_eq!(a.code(), c);
            } else {
                assert!(matches!(c, 0 | 4 | 6..=255));
            }
        }
    }
}
