//! One mission item in MAVLink's two forms: `MISSION_ITEM_INT` (x and y
//! as integers: degrees × 1e7, or metres × 1e4 in local frames) and the
//! legacy `MISSION_ITEM` (floats), for the server, the ground-station
//! client and the QGC WPL files alike.

// ground stations still send the legacy MISSION_ITEM and the superseded
// body frames
#![allow(deprecated)]

use mavlink::dialects::common::{MISSION_ITEM_DATA, MISSION_ITEM_INT_DATA, MavFrame};

/// The scale of a mission item's x and y in `MISSION_ITEM_INT`: degrees ×
/// 10⁷ in the global frames, metres × 10⁴ in the local ones (common.xml).
pub fn int_scale(frame: MavFrame) -> f64 {
    match frame {
        MavFrame::MAV_FRAME_LOCAL_NED
        | MavFrame::MAV_FRAME_LOCAL_ENU
        | MavFrame::MAV_FRAME_LOCAL_OFFSET_NED
        | MavFrame::MAV_FRAME_BODY_NED
        | MavFrame::MAV_FRAME_BODY_OFFSET_NED
        | MavFrame::MAV_FRAME_BODY_FRD
        | MavFrame::MAV_FRAME_LOCAL_FRD
        | MavFrame::MAV_FRAME_LOCAL_FLU => 1e4,
        _ => 1e7,
    }
}

/// The legacy `MISSION_ITEM` (x, y as floats) of an item.
pub fn item_float(it: &MISSION_ITEM_INT_DATA) -> MISSION_ITEM_DATA {
    let k = int_scale(it.frame);
    MISSION_ITEM_DATA {
        param1: it.param1,
        param2: it.param2,
        param3: it.param3,
        param4: it.param4,
        x: (f64::from(it.x) / k) as f32,
        y: (f64::from(it.y) / k) as f32,
        z: it.z,
        seq: it.seq,
        command: it.command,
        target_system: it.target_system,
        target_component: it.target_component,
        frame: it.frame,
        current: it.current,
        autocontinue: it.autocontinue,
        mission_type: it.mission_type,
    }
}

/// The `MISSION_ITEM_INT` of a legacy `MISSION_ITEM` (a non-finite or
/// out-of-range x or y saturates, and the mission check refuses it).
pub fn item_int(it: &MISSION_ITEM_DATA) -> MISSION_ITEM_INT_DATA {
    let k = int_scale(it.frame);
    let int = |v: f32| {
        let v = (f64::from(v) * k).round();
        if v.is_nan() { i32::MAX } else { v as i32 }
    };
    MISSION_ITEM_INT_DATA {
        param1: it.param1,
        param2: it.param2,
        param3: it.param3,
        param4: it.param4,
        x: int(it.x),
        y: int(it.y),
        z: it.z,
        seq: it.seq,
        command: it.command,
        target_system: it.target_system,
        target_component: it.target_component,
        frame: it.frame,
        current: it.current,
        autocontinue: it.autocontinue,
        mission_type: it.mission_type,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// common.xml's scales: 57.0146° N is 570146000 in a global frame, 12.5 m
    /// is 125000 in a local one; the float form and back are the same item.
    #[test]
    fn the_two_forms_round_trip_with_common_xmls_scales() {
        for (frame, x, x_float) in [
            (
                MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                570_146_000,
                57.0146_f32,
            ),
            (MavFrame::MAV_FRAME_LOCAL_NED, 125_000, 12.5),
            (MavFrame::MAV_FRAME_LOCAL_FRD, 125_000, 12.5),
        ] {
            let it = MISSION_ITEM_INT_DATA {
                x,
                y: -x,
                frame,
                ..MISSION_ITEM_INT_DATA::default()
            };
            let f = item_float(&it);
            // f32 holds 7 digits: the latitude to 1e-6° (0.1 m)
            assert!(
                (f.x - x_float).abs() <= 1e-6 * x_float,
                "{frame:?}: {}",
                f.x
            );
            let back = item_int(&f);
            // the float's rounding: half an f32 step at x (at 57°, 1.9e-6° =
            // 19 units of 1e-7°, 0.2 m: the legacy form's own resolution)
            let half_ulp = f64::from(x_float) * f64::from(f32::EPSILON) / 2.0;
            let bound = (half_ulp * int_scale(frame)).ceil() as i32 + 1;
            assert!(
                (back.x - x).abs() <= bound && (back.y + x).abs() <= bound,
                "{frame:?}: {} {} (bound {bound})",
                back.x,
                back.y
            );
            assert_eq!(back.frame, frame);
        }
    }
}
