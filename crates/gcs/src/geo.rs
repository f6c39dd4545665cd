//! Mission items as the ground station sends them (`MISSION_ITEM_INT`) →
//! the navigator's items in the local NED frame about home, through the
//! WGS-84 geodesy of `helicon-devices` (no second implementation).
//!
//! | command | used fields |
//! |---|---|
//! | `MAV_CMD_NAV_TAKEOFF` | z: height |
//! | `MAV_CMD_NAV_WAYPOINT` | x, y, z; param1 hold (s); param2 acceptance radius (m, 0: default); param4 yaw (deg, NaN: along the leg) |
//! | `MAV_CMD_NAV_LAND` | x, y (both 0: where it is) |
//! | `MAV_CMD_NAV_RETURN_TO_LAUNCH` | — |
//! | `MAV_CMD_DO_CHANGE_SPEED` | param2: horizontal speed of the following legs (m/s) |
//!
//! Frames: `GLOBAL_RELATIVE_ALT(_INT)` (z above home), `GLOBAL(_INT)` (z on
//! the home's height datum), `LOCAL_NED` (x, y in metres × 10⁴ as
//! `MISSION_ITEM_INT` carries them, z down).

// ground stations still send the superseded REQUEST_DATA_STREAM, SET_MODE
// and the *_INT mission frames: they are understood
#![allow(deprecated)]

use crate::fence::{Fence, Zones};
use crate::navigator::{Item, ItemKind, Plan};
use helicon_devices::{Geodetic, LocalNed};
use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd, MavFrame, MavMissionResult};
use nalgebra::Vector3;

/// A mission item the navigator cannot fly.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("mission item {seq}: {rule}")]
pub struct MissionError {
    /// The item's sequence number.
    pub seq: u16,
    /// What is wrong.
    pub rule: &'static str,
    /// The answer MISSION_ACK carries.
    pub result: MavMissionResult,
}

fn err(seq: u16, rule: &'static str, result: MavMissionResult) -> MissionError {
    MissionError { seq, rule, result }
}

/// The NED position (m) of an item's x, y, z in its frame.
pub fn item_position_ned_m(
    home: &LocalNed,
    it: &MISSION_ITEM_INT_DATA,
) -> Result<Vector3<f64>, MissionError> {
    global_position_ned_m(home, it.frame, it.x, it.y, it.z).map_err(|(rule, result)| MissionError {
        seq: it.seq,
        rule,
        result,
    })
}

/// The NED position (m) about home of `x`, `y` (degrees × 10⁷, or in
/// `LOCAL_NED` metres × 10⁴) and `z` (m) in `frame`; the error names the
/// rule and the mission protocol's result for it.
pub fn global_position_ned_m(
    home: &LocalNed,
    frame: MavFrame,
    x: i32,
    y: i32,
    z: f32,
) -> Result<Vector3<f64>, (&'static str, MavMissionResult)> {
    let z = f64::from(z);
    if !z.is_finite() {
        return Err((
            "z is not finite",
            MavMissionResult::MAV_MISSION_INVALID_PARAM7,
        ));
    }
    let h0 = home.home().height_m;
    let global = |height_m: f64| {
        let lat = f64::from(x) * 1e-7;
        let lon = f64::from(y) * 1e-7;
        Geodetic::new(lat, lon, height_m)
            .map(|g| home.to_ned_m(&g))
            .map_err(|_| {
                (
                    "latitude, longitude or height out of range",
                    MavMissionResult::MAV_MISSION_INVALID_PARAM5_X,
                )
            })
    };
    match frame {
        MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT => {
            global(h0 + z)
        }
        MavFrame::MAV_FRAME_GLOBAL_INT | MavFrame::MAV_FRAME_GLOBAL => global(z),
        MavFrame::MAV_FRAME_LOCAL_NED => {
            Ok(Vector3::new(f64::from(x) * 1e-4, f64::from(y) * 1e-4, z))
        }
        _ => Err((
            "unsupported frame",
            MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME,
        )),
    }
}

/// The navigator's plan of a mission as uploaded (items in sequence order).
/// Every takeoff height, waypoint and landing point must lie inside the
/// fence, its uploaded zones included (refused `MAV_MISSION_DENIED`
/// otherwise, the limit named).
pub fn plan_of(
    home: &LocalNed,
    fence: &Fence,
    zones: &Zones,
    items: &[MISSION_ITEM_INT_DATA],
) -> Result<Plan, MissionError> {
    let mut plan = Plan::default();
    let mut speed: Option<f64> = None;
    let mut last_ned = Vector3::zeros();
    for it in items {
        let seq = it.seq;
        let p = |i: f32| f64::from(i);
        let kind = match it.command {
            MavCmd::MAV_CMD_DO_CHANGE_SPEED => {
                let s = p(it.param2);
                if s == -1.0 {
                    continue;
                }
                if !(s.is_finite() && s > 0.0 && s <= 15.0) {
                    return Err(err(
                        seq,
                        "speed must be in (0, 15] m/s",
                        MavMissionResult::MAV_MISSION_INVALID_PARAM2,
                    ));
                }
                speed = Some(s);
                continue;
            }
            MavCmd::MAV_CMD_NAV_TAKEOFF => ItemKind::Takeoff,
            MavCmd::MAV_CMD_NAV_WAYPOINT => ItemKind::Waypoint,
            MavCmd::MAV_CMD_NAV_LAND => ItemKind::Land,
            MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH => ItemKind::Return,
            _ => {
                return Err(err(
                    seq,
                    "unsupported command",
                    MavMissionResult::MAV_MISSION_UNSUPPORTED,
                ));
            }
        };
        let position = match kind {
            ItemKind::Takeoff => {
                let z = p(it.z);
                if !(z.is_finite() && z > 0.0) {
                    return Err(err(
                        seq,
                        "takeoff height must be positive",
                        MavMissionResult::MAV_MISSION_INVALID_PARAM7,
                    ));
                }
                Vector3::new(last_ned.x, last_ned.y, -z)
            }
            ItemKind::Land if it.x == 0 && it.y == 0 => Vector3::new(last_ned.x, last_ned.y, 0.0),
            ItemKind::Return => Vector3::zeros(),
            _ => item_position_ned_m(home, it)?,
        };
        if let Err(v) = fence.check_target_in(zones, &position) {
            return Err(MissionError {
                seq,
                rule: v.rule(),
                result: MavMissionResult::MAV_MISSION_DENIED,
            });
        }
        let hold_s = if kind == ItemKind::Waypoint {
            p(it.param1)
        } else {
            0.0
        };
        if !(hold_s.is_finite() && (0.0..=3600.0).contains(&hold_s)) {
            return Err(err(
                seq,
                "hold time must be in [0, 3600] s",
                MavMissionResult::MAV_MISSION_INVALID_PARAM1,
            ));
        }
        let radius = p(it.param2);
        let acceptance_m = match kind {
            ItemKind::Waypoint if radius > 0.0 && radius.is_finite() => Some(radius),
            ItemKind::Waypoint if radius == 0.0 => None,
            ItemKind::Waypoint => {
                return Err(err(
                    seq,
                    "acceptance radius must be finite and ≥ 0",
                    MavMissionResult::MAV_MISSION_INVALID_PARAM2,
                ));
            }
            _ => None,
        };
        let yaw = p(it.param4);
        let yaw_rad = match kind {
            ItemKind::Waypoint | ItemKind::Takeoff if yaw.is_finite() => Some(yaw.to_radians()),
            _ => None,
        };
        let item = Item {
            seq,
            kind,
            position_ned_m: position,
            speed_m_s: speed,
            yaw_rad,
            acceptance_m,
            hold_s,
        };
        if !plan.push(item) {
            return Err(err(
                seq,
                "too many items",
                MavMissionResult::MAV_MISSION_NO_SPACE,
            ));
        }
        last_ned = position;
    }
    Ok(plan)
}
