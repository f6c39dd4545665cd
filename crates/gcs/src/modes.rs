//! The flight modes as ground stations know them: PX4's custom modes.
//!
//! The server announces `MAV_AUTOPILOT_PX4` and reports the navigator's mode
//! as the PX4 custom mode that flies the same way (HEARTBEAT `custom_mode` =
//! `main_mode << 16 | sub_mode << 24`, PX4's `px4_custom_mode` union).
//! QGroundControl's PX4 plugin, pymavlink/MAVProxy (`interpret_px4_mode`,
//! `px4_map`) and MAVSDK (`px4_custom_mode.h`) then name the modes, set them
//! and run their Fly-view actions (takeoff, land, return, pause, start
//! mission) with the commands PX4 answers. Why PX4's and not another's, and
//! the commands each station sends: `docs/gcs.md`.
//!
//! | navigator | PX4 mode | main, sub |
//! |---|---|---|
//! | `IDLE` | AUTO.READY | 4, 1 |
//! | `TAKEOFF` | AUTO.TAKEOFF | 4, 2 |
//! | `HOLD` | AUTO.LOITER (QGC: Hold) | 4, 3 |
//! | `MISSION` | AUTO.MISSION | 4, 4 |
//! | `RETURN` | AUTO.RTL | 4, 5 |
//! | `LAND` | AUTO.LAND | 4, 6 |
//! | `GUIDED` | OFFBOARD | 6, 0 |
//!
//! The flight software's own modes override the navigator's where the
//! navigator does not fly: the pilot's `manual` is MANUAL (1, 0), the
//! supervisor's `hold` AUTO.LOITER and its `descent` AUTO.LAND.

use crate::navigator::NavMode;

/// PX4's main mode MANUAL.
pub const MAIN_MANUAL: u8 = 1;
/// PX4's main mode POSCTL (position control).
pub const MAIN_POSCTL: u8 = 3;
/// PX4's main mode AUTO.
pub const MAIN_AUTO: u8 = 4;
/// PX4's main mode OFFBOARD.
pub const MAIN_OFFBOARD: u8 = 6;
/// AUTO sub mode READY.
pub const SUB_READY: u8 = 1;
/// AUTO sub mode TAKEOFF.
pub const SUB_TAKEOFF: u8 = 2;
/// AUTO sub mode LOITER (hold).
pub const SUB_LOITER: u8 = 3;
/// AUTO sub mode MISSION.
pub const SUB_MISSION: u8 = 4;
/// AUTO sub mode RTL.
pub const SUB_RTL: u8 = 5;
/// AUTO sub mode LAND.
pub const SUB_LAND: u8 = 6;

/// A PX4 custom mode of its main and sub mode.
pub const fn custom_mode(main: u8, sub: u8) -> u32 {
    ((main as u32) << 16) | ((sub as u32) << 24)
}

/// The main and sub mode of a PX4 custom mode.
pub const fn main_sub(custom_mode: u32) -> (u8, u8) {
    (
        ((custom_mode >> 16) & 0xFF) as u8,
        ((custom_mode >> 24) & 0xFF) as u8,
    )
}

/// The PX4 main and sub mode a navigator mode is reported as.
pub fn px4_of(mode: NavMode) -> (u8, u8) {
    match mode {
        NavMode::Idle => (MAIN_AUTO, SUB_READY),
        NavMode::Takeoff => (MAIN_AUTO, SUB_TAKEOFF),
        NavMode::Hold => (MAIN_AUTO, SUB_LOITER),
        NavMode::Mission => (MAIN_AUTO, SUB_MISSION),
        NavMode::Return => (MAIN_AUTO, SUB_RTL),
        NavMode::Land => (MAIN_AUTO, SUB_LAND),
        NavMode::Guided => (MAIN_OFFBOARD, 0),
    }
}

/// The PX4 main and sub mode reported for the navigator's mode while the
/// flight software is in `flight_mode` (its name): the pilot's and the
/// supervisor's modes override the navigator's.
pub fn reported(mode: NavMode, flight_mode: &str) -> (u8, u8) {
    match flight_mode {
        "manual" => (MAIN_MANUAL, 0),
        "hold" => (MAIN_AUTO, SUB_LOITER),
        "descent" => (MAIN_AUTO, SUB_LAND),
        _ => px4_of(mode),
    }
}

/// The navigator mode of a PX4 main and sub mode (`None`: a mode helicon
/// does not fly, e.g. MANUAL, ALTCTL, FOLLOW_TARGET).
pub fn nav_of(main: u8, sub: u8) -> Option<NavMode> {
    [
        NavMode::Idle,
        NavMode::Takeoff,
        NavMode::Hold,
        NavMode::Mission,
        NavMode::Return,
        NavMode::Land,
        NavMode::Guided,
    ]
    .into_iter()
    .find(|m| px4_of(*m) == (main, sub))
}

/// The navigator mode of a HEARTBEAT's custom mode, as a ground station
/// decodes it (`None`: not one of [`px4_of`]'s).
pub fn nav_of_custom(custom_mode: u32) -> Option<NavMode> {
    let (main, sub) = main_sub(custom_mode);
    nav_of(main, sub)
}

/// The name QGroundControl shows for a reported mode (its PX4 plugin's
/// names), for texts and the `helicon gcs` monitor.
pub fn qgc_name(main: u8, sub: u8) -> &'static str {
    match (main, sub) {
        (MAIN_MANUAL, _) => "Manual",
        (MAIN_POSCTL, _) => "Position",
        (MAIN_OFFBOARD, _) => "Offboard",
        (MAIN_AUTO, SUB_READY) => "Ready",
        (MAIN_AUTO, SUB_TAKEOFF) => "Takeoff",
        (MAIN_AUTO, SUB_LOITER) => "Hold",
        (MAIN_AUTO, SUB_MISSION) => "Mission",
        (MAIN_AUTO, SUB_RTL) => "Return",
        (MAIN_AUTO, SUB_LAND) => "Land",
        _ => "Unknown",
    }
}

/// The PX4 main and sub mode of a mode's name, any case: the navigator's
/// (`IDLE`, `TAKEOFF`, `HOLD`, `MISSION`, `RETURN`, `LAND`, `GUIDED`) or
/// the name QGroundControl shows ([`qgc_name`]: `Ready`, `Hold`, `Return`,
/// `Offboard`, `Manual`, …). `None`: no such mode.
pub fn parse_name(name: &str) -> Option<(u8, u8)> {
    const ALL: [NavMode; 7] = [
        NavMode::Idle,
        NavMode::Takeoff,
        NavMode::Hold,
        NavMode::Mission,
        NavMode::Return,
        NavMode::Land,
        NavMode::Guided,
    ];
    if let Some(m) = ALL.iter().find(|m| m.as_str().eq_ignore_ascii_case(name)) {
        return Some(px4_of(*m));
    }
    [
        (MAIN_MANUAL, 0),
        (MAIN_POSCTL, 0),
        (MAIN_OFFBOARD, 0),
        (MAIN_AUTO, SUB_READY),
        (MAIN_AUTO, SUB_TAKEOFF),
        (MAIN_AUTO, SUB_LOITER),
        (MAIN_AUTO, SUB_MISSION),
        (MAIN_AUTO, SUB_RTL),
        (MAIN_AUTO, SUB_LAND),
    ]
    .into_iter()
    .find(|(main, sub)| qgc_name(*main, *sub).eq_ignore_ascii_case(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_mode_round_trips_through_px4_numbers() {
        for m in [
            NavMode::Idle,
            NavMode::Takeoff,
            NavMode::Hold,
            NavMode::Mission,
            NavMode::Return,
            NavMode::Land,
            NavMode::Guided,
        ] {
            let (main, sub) = px4_of(m);
            assert_eq!(nav_of_custom(custom_mode(main, sub)), Some(m));
        }
        // PX4's numbers as pymavlink's px4_map and QGC's px4_custom_mode.h
        assert_eq!(custom_mode(MAIN_AUTO, SUB_LOITER), 0x0304_0000);
        assert_eq!(custom_mode(MAIN_AUTO, SUB_MISSION), 0x0404_0000);
        assert_eq!(custom_mode(MAIN_OFFBOARD, 0), 0x0006_0000);
        assert_eq!(nav_of(MAIN_MANUAL, 0), None);
        assert_eq!(reported(NavMode::Mission, "manual"), (MAIN_MANUAL, 0));
        assert_eq!(reported(NavMode::Mission, "descent"), (MAIN_AUTO, SUB_LAND));
    }

    #[test]
    fn names_parse_in_any_case() {
        assert_eq!(parse_name("HOLD"), Some((MAIN_AUTO, SUB_LOITER)));
        assert_eq!(parse_name("hold"), Some((MAIN_AUTO, SUB_LOITER)));
        assert_eq!(parse_name("Return"), Some((MAIN_AUTO, SUB_RTL)));
        assert_eq!(parse_name("mission"), Some((MAIN_AUTO, SUB_MISSION)));
        assert_eq!(parse_name("Manual"), Some((MAIN_MANUAL, 0)));
        assert_eq!(parse_name("guided"), Some((MAIN_OFFBOARD, 0)));
        assert_eq!(parse_name("Unknown"), None);
        assert_eq!(parse_name("ACRO"), None);
    }
}
