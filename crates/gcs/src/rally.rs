//! Rally points (MAVLink's `MAV_MISSION_TYPE_RALLY`): safe landing places
//! beside home. A return (the RTL mode, the link-loss and geofence
//! failsafes, a mission's return item) flies to the nearest of home and the
//! rally points, horizontally, at the height it has, and lands there, as
//! PX4's default return for a multicopter does (`RTL_TYPE` 0: "home or
//! rally point, whichever is closest").
//!
//! An upload holds `MAV_CMD_NAV_RALLY_POINT` items in a global frame (or
//! `LOCAL_NED`), each inside the geofence, its zones included; at most
//! [`MAX_RALLY_POINTS`]. The set is fixed-size: it crosses the uplink ring
//! boxed, and the navigator picks the nearest without allocating.

// ground stations still send the superseded *_INT mission frames
#![allow(deprecated)]

use crate::fence::{Fence, Zones};
use crate::geo::{MissionError, item_position_ned_m};
use helicon_devices::LocalNed;
use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd, MavMissionResult};
use nalgebra::Vector3;

/// The most rally points one upload may hold.
pub const MAX_RALLY_POINTS: usize = 16;

/// The uploaded rally points, NED about home (m; the landing place's
/// horizontal position: a return lands on the ground below it).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RallyPoints {
    points_ned_m: [Vector3<f64>; MAX_RALLY_POINTS],
    len: usize,
}

impl RallyPoints {
    /// The rally points of an upload (items in sequence order): every item
    /// a `MAV_CMD_NAV_RALLY_POINT` inside the fence and its zones, at most
    /// [`MAX_RALLY_POINTS`]; the error names the item and the rule, with
    /// the result `MISSION_ACK` carries.
    pub fn from_items(
        home: &LocalNed,
        fence: &Fence,
        zones: &Zones,
        items: &[MISSION_ITEM_INT_DATA],
    ) -> Result<Self, MissionError> {
        let mut out = RallyPoints::default();
        for it in items {
            let refuse = |rule: &'static str, result: MavMissionResult| MissionError {
                seq: it.seq,
                rule,
                result,
            };
            if it.command != MavCmd::MAV_CMD_NAV_RALLY_POINT {
                return Err(refuse(
                    "not a rally point (MAV_CMD_NAV_RALLY_POINT)",
                    MavMissionResult::MAV_MISSION_UNSUPPORTED,
                ));
            }
            if out.len == MAX_RALLY_POINTS {
                return Err(refuse(
                    "too many rally points",
                    MavMissionResult::MAV_MISSION_NO_SPACE,
                ));
            }
            let p = item_position_ned_m(home, it)?;
            if let Err(v) = fence.check_target_in(zones, &p) {
                return Err(refuse(v.rule(), MavMissionResult::MAV_MISSION_DENIED));
            }
            out.points_ned_m[out.len] = p;
            out.len += 1;
        }
        Ok(out)
    }

    /// The rally points (NED about home, m).
    pub fn points_ned_m(&self) -> &[Vector3<f64>] {
        &self.points_ned_m[..self.len]
    }

    /// No rally point: a return flies home.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Where a return from `from_ned_m` lands: the horizontally nearest of
    /// home (the origin) and the rally points, on the ground (z = 0), with
    /// the index of the rally point chosen (`None`: home). Home wins a tie.
    pub fn nearest(&self, from_ned_m: &Vector3<f64>) -> (Vector3<f64>, Option<usize>) {
        let mut best = (Vector3::zeros(), None);
        let mut best_d = from_ned_m.xy().norm();
        for (i, p) in self.points_ned_m().iter().enumerate() {
            let d = (p.xy() - from_ned_m.xy()).norm();
            if d < best_d {
                best_d = d;
                best = (Vector3::new(p.x, p.y, 0.0), Some(i));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use helicon_devices::Geodetic;
    use mavlink::dialects::common::MavFrame;

    fn home() -> LocalNed {
        LocalNed::new(Geodetic::new(57.0146, 9.9869, 20.0).unwrap())
    }

    fn rally(seq: u16, north_m: f64, east_m: f64) -> MISSION_ITEM_INT_DATA {
        let h = home();
        let g = h.to_geodetic(&Vector3::new(north_m, east_m, -10.0));
        MISSION_ITEM_INT_DATA {
            seq,
            frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            command: MavCmd::MAV_CMD_NAV_RALLY_POINT,
            x: (g.latitude_deg * 1e7).round() as i32,
            y: (g.longitude_deg * 1e7).round() as i32,
            z: 10.0,
            ..MISSION_ITEM_INT_DATA::DEFAULT
        }
    }

    #[test]
    fn the_nearest_of_home_and_the_rally_points_on_the_ground() {
        let r = RallyPoints::from_items(
            &home(),
            &Fence::default(),
            &Zones::default(),
            &[rally(0, 80.0, 0.0), rally(1, 0.0, -60.0)],
        )
        .unwrap();
        assert_eq!(r.points_ned_m().len(), 2);
        // 1e-7 degree of latitude is 1.1 cm: the round trip within 2 cm
        assert!((r.points_ned_m()[0] - Vector3::new(80.0, 0.0, -10.0)).norm() < 0.02);
        let (p, i) = r.nearest(&Vector3::new(70.0, 5.0, -20.0));
        assert_eq!(i, Some(0));
        assert!((p - Vector3::new(80.0, 0.0, 0.0)).norm() < 0.02 && p.z == 0.0);
        assert_eq!(r.nearest(&Vector3::new(-5.0, -50.0, -20.0)).1, Some(1));
        // home nearer than both
        assert_eq!(
            r.nearest(&Vector3::new(10.0, 10.0, -20.0)),
            (Vector3::zeros(), None)
        );
        assert_eq!(
            RallyPoints::default().nearest(&Vector3::new(80.0, 0.0, -5.0)),
            (Vector3::zeros(), None)
        );
    }

    #[test]
    fn outside_the_fence_another_command_or_too_many_are_refused() {
        let (h, f, z) = (home(), Fence::default(), Zones::default());
        // the default fence's radius is 150 m
        let e = RallyPoints::from_items(&h, &f, &z, &[rally(0, 10.0, 0.0), rally(1, 400.0, 0.0)])
            .unwrap_err();
        assert_eq!((e.seq, e.result), (1, MavMissionResult::MAV_MISSION_DENIED));
        let mut wp = rally(0, 10.0, 0.0);
        wp.command = MavCmd::MAV_CMD_NAV_WAYPOINT;
        let e = RallyPoints::from_items(&h, &f, &z, &[wp]).unwrap_err();
        assert_eq!(e.result, MavMissionResult::MAV_MISSION_UNSUPPORTED);
        let many: Vec<_> = (0..=MAX_RALLY_POINTS as u16)
            .map(|k| rally(k, f64::from(k), 0.0))
            .collect();
        let e = RallyPoints::from_items(&h, &f, &z, &many).unwrap_err();
        assert_eq!(
            (usize::from(e.seq), e.result),
            (MAX_RALLY_POINTS, MavMissionResult::MAV_MISSION_NO_SPACE)
        );
        let mut nan = rally(0, 10.0, 0.0);
        nan.z = f32::NAN;
        assert!(RallyPoints::from_items(&h, &f, &z, &[nan]).is_err());
    }
}
