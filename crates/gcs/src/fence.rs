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
//!
//! **Zones.** A ground station may upload zones into the same fence
//! (`MAV_MISSION_TYPE_FENCE`: polygons and circles, inclusion and
//! exclusion, a return point; [`Zones::from_items`]). PX4's rule: a point
//! is inside the fence when it is inside the cylinder, inside at least one
//! inclusion zone if there are any, and outside every exclusion zone. The
//! zones are horizontal (their altitude is the cylinder's); they are held
//! on the local tangent plane about home (north, east in m), where a point
//! in a polygon is decided by the even-odd rule.

// the *_INT frames ground stations still send are understood
#![allow(deprecated)]

use crate::geo::global_position_ned_m;
use helicon_devices::LocalNed;
use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd, MavFrame, MavMissionResult};
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
    /// Outside every inclusion zone uploaded.
    #[error("outside the fence's inclusion zones")]
    OutsideInclusion,
    /// Inside an exclusion zone uploaded.
    #[error("inside the fence's exclusion zone {zone}")]
    InsideExclusion {
        /// The zone's index among the zones (upload order).
        zone: usize,
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
        matches!(
            self,
            FenceViolation::Horizontal { .. }
                | FenceViolation::OutsideInclusion
                | FenceViolation::InsideExclusion { .. }
        )
    }

    /// The violation in a few words (a mission refusal's text).
    pub fn rule(&self) -> &'static str {
        match self {
            FenceViolation::NotFinite => "position not finite",
            FenceViolation::Horizontal { .. } => "beyond GF_MAX_HOR_DIST",
            FenceViolation::Vertical { .. } => "above GF_MAX_VER_DIST",
            FenceViolation::BelowHome { .. } => "below home",
            FenceViolation::OutsideInclusion => "outside the fence's inclusion zones",
            FenceViolation::InsideExclusion { .. } => "inside a fence exclusion zone",
        }
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

/// The most zones one fence upload may hold.
pub const MAX_FENCE_ZONES: usize = 16;

/// The most polygon vertices one fence upload may hold (over its polygons).
pub const MAX_FENCE_VERTICES: usize = 64;

/// The most items of one fence upload: every vertex, circle and the return
/// point.
pub const MAX_FENCE_ITEMS: usize = MAX_FENCE_VERTICES + MAX_FENCE_ZONES + 1;

/// A zone's shape on the local tangent plane about home.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ZoneShape {
    /// A polygon: `count` vertices from `first` in [`Zones`]' vertex table.
    Polygon {
        /// Index of its first vertex.
        first: usize,
        /// Its vertex count (at least 3).
        count: usize,
    },
    /// A circle.
    Circle {
        /// Its centre (north, east about home, m).
        centre_ne_m: [f64; 2],
        /// Its radius (m, positive).
        radius_m: f64,
    },
}

/// One zone of the fence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Zone {
    /// An inclusion zone (the vehicle must be inside one) or an exclusion
    /// zone (it must be outside).
    pub inclusion: bool,
    /// Its shape.
    pub shape: ZoneShape,
}

/// The zones uploaded into the fence: fixed capacity, no allocation (the
/// navigator holds a copy and checks its estimate against it each sample).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Zones {
    zones: [Option<Zone>; MAX_FENCE_ZONES],
    vertices_ne_m: [[f64; 2]; MAX_FENCE_VERTICES],
    /// The fence's return point (NED about home, m), when uploaded.
    pub return_point_ned_m: Option<Vector3<f64>>,
}

impl Default for Zones {
    fn default() -> Self {
        Zones {
            zones: [None; MAX_FENCE_ZONES],
            vertices_ne_m: [[0.0; 2]; MAX_FENCE_VERTICES],
            return_point_ned_m: None,
        }
    }
}

/// A fence item refused: its sequence number, the rule, the protocol's
/// result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("fence item {seq}: {rule}")]
pub struct ZoneError {
    /// The item's sequence number.
    pub seq: u16,
    /// What is wrong.
    pub rule: &'static str,
    /// The answer MISSION_ACK carries.
    pub result: MavMissionResult,
}

/// Whether a point lies in a polygon (even-odd rule; on an edge counts as
/// either, as floating point decides).
fn in_polygon(p: [f64; 2], vertices: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let mut j = vertices.len().wrapping_sub(1);
    for (i, vi) in vertices.iter().enumerate() {
        let vj = vertices[j];
        if (vi[1] > p[1]) != (vj[1] > p[1]) {
            let t = (p[1] - vi[1]) / (vj[1] - vi[1]);
            if p[0] < vi[0] + t * (vj[0] - vi[0]) {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// The point of a fence item (NED about home, m; on home's level: the
/// altitude is not used): a global frame, latitude and longitude in range.
fn fence_point_ned_m(
    home: &LocalNed,
    it: &MISSION_ITEM_INT_DATA,
) -> Result<Vector3<f64>, ZoneError> {
    let fail = |rule: &'static str, result: MavMissionResult| ZoneError {
        seq: it.seq,
        rule,
        result,
    };
    if !matches!(
        it.frame,
        MavFrame::MAV_FRAME_GLOBAL
            | MavFrame::MAV_FRAME_GLOBAL_INT
            | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT
            | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    ) {
        return Err(fail(
            "unsupported frame (a global one is needed)",
            MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME,
        ));
    }
    if it.x.unsigned_abs() > 900_000_000 {
        return Err(fail(
            "latitude out of range",
            MavMissionResult::MAV_MISSION_INVALID_PARAM5_X,
        ));
    }
    if it.y.unsigned_abs() > 1_800_000_000 {
        return Err(fail(
            "longitude out of range",
            MavMissionResult::MAV_MISSION_INVALID_PARAM6_Y,
        ));
    }
    // the altitude is not used: the point on home's level
    global_position_ned_m(
        home,
        MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
        it.x,
        it.y,
        0.0,
    )
    .map_err(|(rule, result)| fail(rule, result))
}

impl Zones {
    /// No zone and no return point.
    pub fn is_empty(&self) -> bool {
        self.zones[0].is_none() && self.return_point_ned_m.is_none()
    }

    /// The zones, in upload order.
    pub fn zones(&self) -> impl Iterator<Item = &Zone> {
        self.zones.iter().map_while(Option::as_ref)
    }

    fn contains(&self, z: &Zone, p: [f64; 2]) -> bool {
        match z.shape {
            ZoneShape::Polygon { first, count } => {
                in_polygon(p, &self.vertices_ne_m[first..first + count])
            }
            ZoneShape::Circle {
                centre_ne_m: c,
                radius_m,
            } => (p[0] - c[0]).hypot(p[1] - c[1]) <= radius_m,
        }
    }

    /// The zone rule a position (NED about home, m) breaks, if any (PX4's:
    /// inside at least one inclusion zone if there are any, outside every
    /// exclusion zone). A non-finite position is no breach here.
    pub fn outside(&self, position_ned_m: &Vector3<f64>) -> Option<FenceViolation> {
        let p = [position_ned_m.x, position_ned_m.y];
        if !(p[0].is_finite() && p[1].is_finite()) {
            return None;
        }
        let mut any_inclusion = false;
        let mut included = false;
        for (i, z) in self.zones().enumerate() {
            let inside = self.contains(z, p);
            if z.inclusion {
                any_inclusion = true;
                included |= inside;
            } else if inside {
                return Some(FenceViolation::InsideExclusion { zone: i });
            }
        }
        (any_inclusion && !included).then_some(FenceViolation::OutsideInclusion)
    }

    /// The zones of a fence upload (`MAV_MISSION_TYPE_FENCE` items in
    /// sequence order) about `home`:
    /// `MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION/EXCLUSION` (param1 the
    /// polygon's vertex count, every vertex of a polygon consecutive),
    /// `MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION/EXCLUSION` (param1 the radius,
    /// m), `MAV_CMD_NAV_FENCE_RETURN_POINT` (at most one); x, y latitude and
    /// longitude (degrees × 10⁷) in a global frame; the altitude is not
    /// used. The first fault refuses the upload.
    pub fn from_items(
        home: &LocalNed,
        items: &[MISSION_ITEM_INT_DATA],
    ) -> Result<Zones, ZoneError> {
        let mut z = Zones::default();
        let mut n_zones = 0;
        let mut n_vertices = 0;
        // the polygon being read: (command, vertex count, vertices read)
        let mut open: Option<(MavCmd, usize, usize)> = None;
        for it in items {
            let fail = |rule: &'static str, result: MavMissionResult| ZoneError {
                seq: it.seq,
                rule,
                result,
            };
            let polygon = matches!(
                it.command,
                MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
                    | MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
            );
            let circle = matches!(
                it.command,
                MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
                    | MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
            );
            if !(polygon || circle || it.command == MavCmd::MAV_CMD_NAV_FENCE_RETURN_POINT) {
                return Err(fail(
                    "not a fence item",
                    MavMissionResult::MAV_MISSION_UNSUPPORTED,
                ));
            }
            if let Some((cmd, count, _)) = open
                && (it.command != cmd || f64::from(it.param1) != count as f64)
            {
                return Err(fail(
                    "polygon cut short: its vertices' counts disagree",
                    MavMissionResult::MAV_MISSION_INVALID_PARAM1,
                ));
            }
            let ned = fence_point_ned_m(home, it)?;
            let ne = [ned.x, ned.y];
            if polygon {
                let (cmd, count, read) = match open {
                    Some(o) => o,
                    None => {
                        let c = f64::from(it.param1);
                        if !(c.is_finite() && c.fract() == 0.0 && c >= 3.0) {
                            return Err(fail(
                                "a polygon needs a vertex count (param1) of at least 3",
                                MavMissionResult::MAV_MISSION_INVALID_PARAM1,
                            ));
                        }
                        if c > (MAX_FENCE_VERTICES - n_vertices) as f64
                            || n_zones >= MAX_FENCE_ZONES
                        {
                            return Err(fail(
                                "too many fence vertices or zones",
                                MavMissionResult::MAV_MISSION_NO_SPACE,
                            ));
                        }
                        (it.command, c as usize, 0)
                    }
                };
                z.vertices_ne_m[n_vertices + read] = ne;
                if read + 1 == count {
                    z.zones[n_zones] = Some(Zone {
                        inclusion: cmd == MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                        shape: ZoneShape::Polygon {
                            first: n_vertices,
                            count,
                        },
                    });
                    n_zones += 1;
                    n_vertices += count;
                    open = None;
                } else {
                    open = Some((cmd, count, read + 1));
                }
            } else if circle {
                let r = f64::from(it.param1);
                if !(r.is_finite() && r > 0.0) {
                    return Err(fail(
                        "a circle needs a positive radius (param1)",
                        MavMissionResult::MAV_MISSION_INVALID_PARAM1,
                    ));
                }
                if n_zones >= MAX_FENCE_ZONES {
                    return Err(fail(
                        "too many fence zones",
                        MavMissionResult::MAV_MISSION_NO_SPACE,
                    ));
                }
                z.zones[n_zones] = Some(Zone {
                    inclusion: it.command == MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
                    shape: ZoneShape::Circle {
                        centre_ne_m: ne,
                        radius_m: r,
                    },
                });
                n_zones += 1;
            } else {
                if z.return_point_ned_m.is_some() {
                    return Err(fail(
                        "a second return point",
                        MavMissionResult::MAV_MISSION_INVALID,
                    ));
                }
                z.return_point_ned_m = Some(ned);
            }
        }
        if open.is_some() {
            return Err(ZoneError {
                seq: items.last().map_or(0, |i| i.seq),
                rule: "polygon cut short: fewer vertices than its count",
                result: MavMissionResult::MAV_MISSION_INVALID_PARAM1,
            });
        }
        Ok(z)
    }
}

impl Fence {
    /// [`Fence::check_target`] and the zones' rule.
    pub fn check_target_in(
        &self,
        zones: &Zones,
        position_ned_m: &Vector3<f64>,
    ) -> Result<(), FenceViolation> {
        self.check_target(position_ned_m)?;
        zones.outside(position_ned_m).map_or(Ok(()), Err)
    }

    /// [`Fence::check_height`] (at home) and the zones' rule.
    pub fn check_height_in(&self, zones: &Zones, height_m: f64) -> Result<(), FenceViolation> {
        self.check_target_in(zones, &Vector3::new(0.0, 0.0, -height_m))
    }

    /// [`Fence::outside`] and the zones' rule (the breach monitor's check).
    pub fn outside_in(
        &self,
        zones: &Zones,
        position_ned_m: &Vector3<f64>,
    ) -> Option<FenceViolation> {
        self.outside(position_ned_m)
            .or_else(|| zones.outside(position_ned_m))
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

    use helicon_devices::Geodetic;
    use mavlink::dialects::common::MavMissionType;

    const LAT: i32 = 570_146_000;
    const LON: i32 = 99_869_000;

    fn home() -> LocalNed {
        LocalNed::new(Geodetic::new(57.0146, 9.9869, 20.0).unwrap())
    }

    /// A fence item at home offset by (dlat, dlon) × 10⁻⁷ degrees.
    fn fi(seq: u16, command: MavCmd, param1: f32, dlat: i32, dlon: i32) -> MISSION_ITEM_INT_DATA {
        MISSION_ITEM_INT_DATA {
            param1,
            x: LAT + dlat,
            y: LON + dlon,
            seq,
            command,
            frame: MavFrame::MAV_FRAME_GLOBAL_INT,
            mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
            ..MISSION_ITEM_INT_DATA::DEFAULT
        }
    }

    const INC: MavCmd = MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION;
    const EXC: MavCmd = MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION;
    const CINC: MavCmd = MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION;
    const CEXC: MavCmd = MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION;

    /// A square of ±d × 10⁻⁷ degrees about home, from `seq`.
    fn square(seq: u16, cmd: MavCmd, d: i32) -> Vec<MISSION_ITEM_INT_DATA> {
        [(-d, -d), (-d, d), (d, d), (d, -d)]
            .iter()
            .enumerate()
            .map(|(i, (a, b))| fi(seq + i as u16, cmd, 4.0, *a, *b))
            .collect()
    }

    fn refused(items: &[MISSION_ITEM_INT_DATA]) -> (u16, MavMissionResult) {
        let e = Zones::from_items(&home(), items).unwrap_err();
        (e.seq, e.result)
    }

    #[test]
    fn the_zone_rule_is_px4s() {
        // an inclusion square of ±0.001° (±111 m north, ±61 m east) with an
        // exclusion circle of 10 m about (50 m N, 0)
        let mut items = square(0, INC, 10_000);
        items.push(fi(4, CEXC, 10.0, 4_496, 0));
        let z = Zones::from_items(&home(), &items).unwrap();
        assert_eq!(z.zones().count(), 2);
        let p = |n: f64, e: f64| Vector3::new(n, e, -5.0);
        assert_eq!(z.outside(&p(0.0, 0.0)), None);
        assert_eq!(z.outside(&p(100.0, 50.0)), None);
        assert_eq!(
            z.outside(&p(0.0, 70.0)),
            Some(FenceViolation::OutsideInclusion)
        );
        assert_eq!(
            z.outside(&p(-120.0, 0.0)),
            Some(FenceViolation::OutsideInclusion)
        );
        assert_eq!(
            z.outside(&p(50.0, 3.0)),
            Some(FenceViolation::InsideExclusion { zone: 1 })
        );
        // two inclusion zones: inside either is inside
        let mut items = square(0, INC, 1_000);
        items.push(fi(4, CINC, 20.0, 9_000, 0));
        let z = Zones::from_items(&home(), &items).unwrap();
        assert_eq!(z.outside(&p(0.0, 0.0)), None);
        assert_eq!(z.outside(&p(100.0, 5.0)), None);
        assert_eq!(
            z.outside(&p(50.0, 0.0)),
            Some(FenceViolation::OutsideInclusion)
        );
        // exclusion zones alone: everywhere else is inside
        let z = Zones::from_items(&home(), &square(0, EXC, 1_000)).unwrap();
        assert_eq!(z.outside(&p(500.0, 0.0)), None);
        assert!(z.outside(&p(1.0, 1.0)).is_some());
        // no zones: nothing
        assert_eq!(Zones::default().outside(&p(1e6, 0.0)), None);
        // the cylinder and the zones together
        let f = Fence::default();
        let z = Zones::from_items(&home(), &square(0, INC, 1_000)).unwrap();
        assert!(f.check_target_in(&z, &p(1.0, 1.0)).is_ok());
        assert_eq!(
            f.check_target_in(&z, &p(20.0, 0.0)),
            Err(FenceViolation::OutsideInclusion)
        );
        assert!(f.check_height_in(&z, 10.0).is_ok());
        assert!(f.outside_in(&z, &p(20.0, 0.0)).is_some());
        assert!(f.outside_in(&z, &Vector3::new(0.0, 0.0, -61.0)).is_some());
        // a concave polygon (an L): its notch is outside
        let l = [(0, 0), (0, 2), (1, 2), (1, 1), (2, 1), (2, 0)];
        let items: Vec<_> = l
            .iter()
            .enumerate()
            .map(|(i, (a, b))| fi(i as u16, INC, 6.0, a * 4_496, b * 8_250))
            .collect();
        let z = Zones::from_items(&home(), &items).unwrap();
        assert_eq!(z.outside(&p(25.0, 25.0)), None);
        assert_eq!(
            z.outside(&p(75.0, 75.0)),
            Some(FenceViolation::OutsideInclusion)
        );
    }

    #[test]
    fn bad_uploads_are_refused_with_their_result() {
        use MavMissionResult::*;
        // a polygon of 2 vertices
        assert_eq!(
            refused(&[fi(0, INC, 2.0, 0, 0), fi(1, INC, 2.0, 10, 10)]),
            (0, MAV_MISSION_INVALID_PARAM1)
        );
        // a vertex count that is not a whole number, or NaN
        assert_eq!(
            refused(&[fi(0, INC, 3.5, 0, 0)]),
            (0, MAV_MISSION_INVALID_PARAM1)
        );
        assert_eq!(
            refused(&[fi(0, INC, f32::NAN, 0, 0)]),
            (0, MAV_MISSION_INVALID_PARAM1)
        );
        // inconsistent counts within a polygon
        let mut sq = square(0, INC, 1_000);
        sq[2].param1 = 5.0;
        assert_eq!(refused(&sq), (2, MAV_MISSION_INVALID_PARAM1));
        // a polygon cut short by another item, or by the end
        let mut sq = square(0, INC, 1_000);
        sq[3] = fi(3, CINC, 10.0, 0, 0);
        assert_eq!(refused(&sq), (3, MAV_MISSION_INVALID_PARAM1));
        assert_eq!(
            refused(&square(0, INC, 1_000)[..3]),
            (2, MAV_MISSION_INVALID_PARAM1)
        );
        // inclusion and exclusion vertices mixed in one polygon
        let mut sq = square(0, INC, 1_000);
        sq[1].command = EXC;
        assert_eq!(refused(&sq), (1, MAV_MISSION_INVALID_PARAM1));
        // latitude and longitude out of range
        let mut it = fi(0, CINC, 10.0, 0, 0);
        it.x = 900_000_001;
        assert_eq!(refused(&[it]), (0, MAV_MISSION_INVALID_PARAM5_X));
        let mut it = fi(0, CINC, 10.0, 0, 0);
        it.y = -1_800_000_001;
        assert_eq!(refused(&[it]), (0, MAV_MISSION_INVALID_PARAM6_Y));
        let mut it = fi(0, CINC, 10.0, 0, 0);
        it.x = i32::MIN;
        assert_eq!(refused(&[it]), (0, MAV_MISSION_INVALID_PARAM5_X));
        // a radius of 0, negative or not finite
        for r in [0.0, -5.0, f32::NAN, f32::INFINITY] {
            assert_eq!(
                refused(&[fi(0, CEXC, r, 0, 0)]),
                (0, MAV_MISSION_INVALID_PARAM1),
                "{r}"
            );
        }
        // an unsupported frame, an item that is no fence item
        let mut it = fi(0, CINC, 10.0, 0, 0);
        it.frame = MavFrame::MAV_FRAME_LOCAL_NED;
        assert_eq!(refused(&[it]), (0, MAV_MISSION_UNSUPPORTED_FRAME));
        assert_eq!(
            refused(&[fi(0, MavCmd::MAV_CMD_NAV_WAYPOINT, 0.0, 0, 0)]),
            (0, MAV_MISSION_UNSUPPORTED)
        );
        // two return points
        let rp = MavCmd::MAV_CMD_NAV_FENCE_RETURN_POINT;
        assert_eq!(
            refused(&[fi(0, rp, 0.0, 0, 0), fi(1, rp, 0.0, 0, 0)]),
            (1, MAV_MISSION_INVALID)
        );
        // too many vertices, too many zones
        let big: Vec<_> = (0..65).map(|i| fi(i, INC, 65.0, i32::from(i), 0)).collect();
        assert_eq!(refused(&big), (0, MAV_MISSION_NO_SPACE));
        let many: Vec<_> = (0..17).map(|i| fi(i, CINC, 5.0, 0, 0)).collect();
        assert_eq!(refused(&many), (16, MAV_MISSION_NO_SPACE));
        // a return point alone is accepted and kept
        let z = Zones::from_items(&home(), &[fi(0, rp, 0.0, 4_496, 0)]).unwrap();
        assert!(!z.is_empty() && z.zones().count() == 0);
        assert!((z.return_point_ned_m.unwrap().x - 50.0).abs() < 0.5);
        // nothing uploaded: empty
        assert!(Zones::from_items(&home(), &[]).unwrap().is_empty());
    }
}
