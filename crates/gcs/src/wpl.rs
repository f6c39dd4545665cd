//! Mission files in the QGC WPL 110 text format (QGroundControl's legacy
//! format, the one MAVProxy's and pymavlink's `mavwp` read and write).
//!
//! The first line is the header `QGC WPL 110`; every other non-blank line
//! is one mission item of 12 tab-separated columns:
//!
//! | column | field |
//! |---|---|
//! | 1 | index (the item's sequence number, 0, 1, … in order) |
//! | 2 | current (1: the current item) |
//! | 3 | frame (`MAV_FRAME` number) |
//! | 4 | command (`MAV_CMD` number) |
//! | 5–8 | param1 … param4 |
//! | 9, 10 | x, y: latitude and longitude (degrees), or in a local frame metres |
//! | 11 | z: altitude (m, in the frame's datum) |
//! | 12 | autocontinue (0 or 1) |
//!
//! Every line is an item: a first line is not taken for a home position
//! (helicon's vehicles are PX4-like: their mission starts at item 0).
//! Lines starting with `#` are comments. Items read become
//! `MISSION_ITEM_INT`s (latitude and longitude × 10⁷, local metres × 10⁴,
//! as MAVLink carries them); numbers must be finite.

// the *_INT mission frames are understood though superseded
#![allow(deprecated)]

use crate::mission_item::int_scale;
use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd, MavFrame, MavMissionType};
use num_traits::{FromPrimitive, ToPrimitive};
use std::path::Path;

/// The header line of a QGC WPL 110 file.
pub const HEADER: &str = "QGC WPL 110";

/// The number of columns of an item line.
pub const COLUMNS: usize = 12;

/// A mission file that cannot be read or written: the file, the line (1 is
/// the header; 0: the file as a whole) and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}: {message}")]
pub struct WplError {
    /// The file (as given).
    pub file: String,
    /// The line number (1-based; 0: not a line's fault).
    pub line: usize,
    /// What is wrong (the column named where one is).
    pub message: String,
}

const NAMES: [&str; COLUMNS] = [
    "index",
    "current",
    "frame",
    "command",
    "param1",
    "param2",
    "param3",
    "param4",
    "x (latitude)",
    "y (longitude)",
    "z (altitude)",
    "autocontinue",
];

/// Parse the text of a QGC WPL 110 file (`file` names it in errors).
pub fn parse(text: &str, file: &str) -> Result<Vec<MISSION_ITEM_INT_DATA>, WplError> {
    let err = |line: usize, message: String| WplError {
        file: file.to_string(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == HEADER => {}
        Some((_, h)) => {
            return Err(err(
                1,
                format!("header `{}`: expected `{HEADER}`", h.trim()),
            ));
        }
        None => return Err(err(1, format!("empty file: expected `{HEADER}`"))),
    }
    let mut items = Vec::new();
    for (i, line) in lines {
        let n = i + 1;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let cols: Vec<&str> = t.split_whitespace().collect();
        if cols.len() != COLUMNS {
            return Err(err(
                n,
                format!("{} columns, expected {COLUMNS}", cols.len()),
            ));
        }
        let mut v = [0.0f64; COLUMNS];
        for (k, c) in cols.iter().enumerate() {
            let x: f64 = c
                .parse()
                .map_err(|_| err(n, format!("{} `{c}`: not a number", NAMES[k])))?;
            if !x.is_finite() {
                return Err(err(n, format!("{} `{c}`: not finite", NAMES[k])));
            }
            v[k] = x;
        }
        let whole = |k: usize, max: f64| -> Result<f64, WplError> {
            let x = v[k];
            if x.fract() == 0.0 && (0.0..=max).contains(&x) {
                Ok(x)
            } else {
                Err(err(
                    n,
                    format!(
                        "{} `{}`: expected a whole number 0…{max}",
                        NAMES[k], cols[k]
                    ),
                ))
            }
        };
        let seq = whole(0, f64::from(u16::MAX))? as u16;
        if usize::from(seq) != items.len() {
            return Err(err(
                n,
                format!(
                    "index {seq}: expected {} (items in order from 0)",
                    items.len()
                ),
            ));
        }
        let current = whole(1, 1.0)? as u8;
        let frame_n = whole(2, 255.0)? as u8;
        let frame = MavFrame::from_u8(frame_n)
            .ok_or_else(|| err(n, format!("frame {frame_n}: not a MAV_FRAME")))?;
        let command_n = whole(3, f64::from(u16::MAX))? as u16;
        let command = MavCmd::from_u16(command_n)
            .ok_or_else(|| err(n, format!("command {command_n}: not a MAV_CMD")))?;
        let autocontinue = whole(11, 1.0)? as u8;
        let int = |k: usize| -> Result<i32, WplError> {
            let x = (v[k] * int_scale(frame)).round();
            if x.abs() <= f64::from(i32::MAX) {
                Ok(x as i32)
            } else {
                Err(err(n, format!("{} `{}`: out of range", NAMES[k], cols[k])))
            }
        };
        let (x, y) = (int(8)?, int(9)?);
        let float = |k: usize| -> Result<f32, WplError> {
            let x = v[k] as f32;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(err(n, format!("{} `{}`: out of range", NAMES[k], cols[k])))
            }
        };
        items.push(MISSION_ITEM_INT_DATA {
            param1: float(4)?,
            param2: float(5)?,
            param3: float(6)?,
            param4: float(7)?,
            x,
            y,
            z: float(10)?,
            seq,
            command,
            target_system: 0,
            target_component: 0,
            frame,
            current,
            autocontinue,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
        });
    }
    Ok(items)
}

/// Read a QGC WPL 110 file: a regular file of at most
/// [`helicon_config::files::MAX_TEXT_BYTES`] (a FIFO, a device such as
/// `/dev/zero` or a longer file is refused before it is read past the
/// limit).
pub fn read(path: &Path) -> Result<Vec<MISSION_ITEM_INT_DATA>, WplError> {
    let file = path.display().to_string();
    let text =
        helicon_config::files::read_text_bounded(path, helicon_config::files::MAX_TEXT_BYTES)
            .map_err(|e| WplError {
                file: file.clone(),
                line: 0,
                message: match e {
                    helicon_config::ConfigError::Io { source, .. } => source.to_string(),
                    other => other.to_string(),
                },
            })?;
    parse(&text, &file)
}

/// The QGC WPL 110 text of `items` (`file` names it in errors: a number
/// that is not finite cannot be written). Items are numbered in order.
pub fn to_text(items: &[MISSION_ITEM_INT_DATA], file: &str) -> Result<String, WplError> {
    let mut s = format!("{HEADER}\n");
    for (i, it) in items.iter().enumerate() {
        let p = [it.param1, it.param2, it.param3, it.param4, it.z];
        if let Some(k) = p.iter().position(|x| !x.is_finite()) {
            return Err(WplError {
                file: file.to_string(),
                line: i + 2,
                message: format!(
                    "item {}: {} is {}, which QGC WPL 110 cannot carry",
                    it.seq,
                    ["param1", "param2", "param3", "param4", "z (altitude)"][k],
                    p[k]
                ),
            });
        }
        let k = int_scale(it.frame);
        s += &format!(
            "{i}\t{}\t{}\t{}\t{:.8}\t{:.8}\t{:.8}\t{:.8}\t{:.8}\t{:.8}\t{:.6}\t{}\n",
            it.current,
            it.frame.to_u8().unwrap_or(0),
            it.command.to_u16().unwrap_or(0),
            it.param1,
            it.param2,
            it.param3,
            it.param4,
            f64::from(it.x) / k,
            f64::from(it.y) / k,
            it.z,
            it.autocontinue
        );
    }
    Ok(s)
}

/// Write `items` to a QGC WPL 110 file.
pub fn write(path: &Path, items: &[MISSION_ITEM_INT_DATA]) -> Result<(), WplError> {
    let file = path.display().to_string();
    let text = to_text(items, &file)?;
    std::fs::write(path, text).map_err(|e| WplError {
        file,
        line: 0,
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "QGC WPL 110
0\t1\t3\t22\t0.00000000\t0.00000000\t0.00000000\t0.00000000\t0.00000000\t0.00000000\t3.000000\t1
# a comment, then a blank line

1\t0\t3\t16\t2.00000000\t0.50000000\t0.00000000\t90.00000000\t57.01462700\t9.98690000\t3.000000\t1
2\t0\t1\t16\t0.00000000\t0.00000000\t0.00000000\t0.00000000\t1.50000000\t-2.25000000\t-3.000000\t1
3\t0\t3\t21\t0.00000000\t0.00000000\t0.00000000\t0.00000000\t0.00000000\t0.00000000\t0.000000\t1
";

    #[test]
    fn reads_the_columns_and_round_trips() {
        let items = parse(TEXT, "m.waypoints").unwrap();
        assert_eq!(items.len(), 4);
        assert_eq!(items[0].command, MavCmd::MAV_CMD_NAV_TAKEOFF);
        assert_eq!(items[0].current, 1);
        assert_eq!(items[1].frame, MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT);
        assert_eq!(items[1].x, 570_146_270);
        assert_eq!(items[1].y, 99_869_000);
        assert_eq!(items[1].param1, 2.0);
        assert_eq!(items[1].param4, 90.0);
        // a local frame: metres × 10⁴
        assert_eq!(items[2].frame, MavFrame::MAV_FRAME_LOCAL_NED);
        assert_eq!((items[2].x, items[2].y), (15_000, -22_500));
        assert_eq!(items[3].seq, 3);
        let text = to_text(&items, "m.waypoints").unwrap();
        // comments and blank lines are not kept; every value is
        let kept: String = TEXT
            .lines()
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(|l| format!("{l}\n"))
            .collect();
        assert_eq!(text, kept);
        assert_eq!(parse(&text, "again").unwrap(), items);
    }

    #[test]
    fn errors_name_the_file_line_and_field() {
        let bad = |text: &str| parse(text, "bad.waypoints").unwrap_err().to_string();
        assert_eq!(
            bad("QGC WPL 120\n"),
            "bad.waypoints:1: header `QGC WPL 120`: expected `QGC WPL 110`"
        );
        assert!(bad("").starts_with("bad.waypoints:1: empty file"));
        let e = bad("QGC WPL 110\n\n0\t0\t3\t16\t0\t0\t0\t0\t57\t9\n");
        assert_eq!(e, "bad.waypoints:3: 10 columns, expected 12");
        let e = bad("QGC WPL 110\n0\t0\t3\t16\t0\t0\t0\tnan\t57\t9\t3\t1\n");
        assert_eq!(e, "bad.waypoints:2: param4 `nan`: not finite");
        let e = bad("QGC WPL 110\n0\t0\t3\t16\t0\t0\t0\t0\t57\t9\tinf\t1\n");
        assert_eq!(e, "bad.waypoints:2: z (altitude) `inf`: not finite");
        let e = bad("QGC WPL 110\n0\t0\t3\t16\t0\t0\t0\t0\tx\t9\t3\t1\n");
        assert_eq!(e, "bad.waypoints:2: x (latitude) `x`: not a number");
        let e = bad("QGC WPL 110\n1\t0\t3\t16\t0\t0\t0\t0\t57\t9\t3\t1\n");
        assert!(e.starts_with("bad.waypoints:2: index 1: expected 0"), "{e}");
        let e = bad("QGC WPL 110\n0\t0\t3\t9999\t0\t0\t0\t0\t57\t9\t3\t1\n");
        assert_eq!(e, "bad.waypoints:2: command 9999: not a MAV_CMD");
        let e = bad("QGC WPL 110\n0\t2\t3\t16\t0\t0\t0\t0\t57\t9\t3\t1\n");
        assert!(e.starts_with("bad.waypoints:2: current `2`"), "{e}");
        let e = bad("QGC WPL 110\n0\t0\t3\t16\t0\t0\t0\t0\t1e30\t9\t3\t1\n");
        assert!(
            e.starts_with("bad.waypoints:2: x (latitude) `1e30`: out of range"),
            "{e}"
        );
    }

    #[test]
    fn a_nan_is_not_written() {
        let mut items = parse(TEXT, "m").unwrap();
        items[1].param4 = f32::NAN;
        let e = to_text(&items, "out.waypoints").unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.to_string().contains("param4 is NaN"), "{e}");
    }

    #[test]
    fn a_missing_file_is_named() {
        let e = read(Path::new("/nonexistent/m.waypoints")).unwrap_err();
        assert!(
            e.to_string().starts_with("/nonexistent/m.waypoints:0: "),
            "{e}"
        );
    }
}
