//! Flying the envelope: the scenario's optional `[trajectory]` section
//! (jerk-limited references built on [`helicon_core::trajectory::Mission`])
//! and the gain schedule a scenario flies (`[controller] schedule` /
//! `schedule_file`).
//!
//! ```toml
//! [trajectory]                  # replaces [[reference]]
//! max_accel_m_s2 = 1.0          # speed channel: |dV/dt| and |d²V/dt²|
//! max_jerk_m_s3 = 0.5
//! max_yaw_accel_rad_s2 = 0.05   # yaw-rate channel
//! max_yaw_jerk_rad_s3 = 0.05
//! max_vertical_accel_m_s2 = 0.5 # down-velocity channel
//! max_vertical_jerk_m_s3 = 0.5
//! [[trajectory.speed]]          # ground speed along the heading (m/s)
//! t_s = 5.0
//! value = 15.0
//! [[trajectory.yaw_rate]]       # rad/s; the heading integrates it
//! t_s = 30.0
//! value = 0.2
//! [[trajectory.down]]           # down velocity (m/s)
//! ```
//!
//! Each channel starts at the trim (speed: the trim's forward speed; yaw
//! rate 0; down: the trim's down velocity) and moves to each leg's value
//! along the time-optimal S-curve; a leg must start after the previous one
//! of its channel has arrived. The velocity reference points along the
//! heading (coordinated flight).

use crate::scenario::{Scenario, ScenarioError};
use helicon_core::schedule::GainSchedule;
use helicon_gnc::schedule::{EnvelopeConfig, Schedule, ScheduleError, design_schedule};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

pub use helicon_setup::plan::{LegSection, MAX_YAW_RATE_RAD_S, TrajectorySection};

/// Designed schedules of this process, keyed by the envelope file's path
/// and text (a Monte Carlo campaign designs once, an edited file again).
type Cache = Vec<(PathBuf, String, Arc<(Schedule, GainSchedule)>)>;
static CACHE: Mutex<Cache> = Mutex::new(Vec::new());

/// The gain schedule a scenario flies, when it names one: `schedule` (an
/// envelope file, designed here on its own model — the nominal helicopter —
/// and cached per process) or `schedule_file` (a `helicon design` output).
pub fn scenario_schedule(
    scenario: &Scenario,
) -> Result<Option<Arc<(Schedule, GainSchedule)>>, ScheduleError> {
    let c = &scenario.controller;
    if let Some(f) = &c.schedule_file {
        let path = scenario.resolve(f);
        let s = Schedule::load(&path)?;
        let gs = s.gain_schedule(&path.display().to_string())?;
        return Ok(Some(Arc::new((s, gs))));
    }
    let Some(env) = &c.schedule else {
        return Ok(None);
    };
    let path = scenario.resolve(env);
    let text =
        helicon_config::read_text_bounded(&path, helicon_config::MAX_TEXT_BYTES).map_err(|e| {
            ScheduleError::Config(ScenarioError::Io {
                file: path.display().to_string(),
                action: "read",
                source: e.into_io(),
            })
        })?;
    if let Ok(cache) = CACHE.lock()
        && let Some((_, _, s)) = cache.iter().find(|(p, t, _)| *p == path && *t == text)
    {
        return Ok(Some(Arc::clone(s)));
    }
    let s = design_envelope(&path, &text)?;
    if let Ok(mut cache) = CACHE.lock() {
        cache.push((path, text, Arc::clone(&s)));
    }
    Ok(Some(s))
}

fn design_envelope(
    path: &Path,
    text: &str,
) -> Result<Arc<(Schedule, GainSchedule)>, ScheduleError> {
    let file = path.display().to_string();
    let mut cfg = EnvelopeConfig::from_toml_str(text, &file)?;
    cfg.base_dir = path.parent().map(Path::to_path_buf);
    let model = cfg.model()?;
    let s = design_schedule(&model, &cfg, &mut |_, _| {})?;
    let gs = s.gain_schedule(&file)?;
    Ok(Arc::new((s, gs)))
}

/// Tracking of one time segment of a flight.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SegmentRms {
    /// Segment start (s).
    pub t0_s: f64,
    /// Segment end (s).
    pub t1_s: f64,
    /// Kept log rows in the segment.
    pub rows: usize,
    /// RMS of the horizontal velocity error |r_h − v_h| (m/s).
    pub horizontal_m_s: f64,
    /// RMS of the down-velocity error (m/s).
    pub vertical_m_s: f64,
    /// RMS of the heading error, wrapped (rad).
    pub heading_rad: f64,
}

/// The tracking RMS of the log rows with `t0_s <= t < t1_s` (reference −
/// true output); `None` when no row falls inside (e.g. the flight stopped
/// before the segment).
pub fn segment_rms(log: &[crate::closed_loop::LogRow], t0_s: f64, t1_s: f64) -> Option<SegmentRms> {
    let mut acc = [0.0f64; 3];
    let mut n = 0usize;
    for r in log.iter().filter(|r| r.t_s >= t0_s && r.t_s < t1_s) {
        let (dn, de) = (r.reference[0] - r.output[0], r.reference[1] - r.output[1]);
        acc[0] += dn * dn + de * de;
        acc[1] += (r.reference[2] - r.output[2]).powi(2);
        acc[2] += helicon_core::frames::wrap_pi(r.reference[3] - r.output[3]).powi(2);
        n += 1;
    }
    (n > 0).then(|| {
        let m = |s: f64| (s / n as f64).sqrt();
        SegmentRms {
            t0_s,
            t1_s,
            rows: n,
            horizontal_m_s: m(acc[0]),
            vertical_m_s: m(acc[1]),
            heading_rad: m(acc[2]),
        }
    })
}

/// The mean tracking error of a window in the reference's own axes: along
/// the reference heading (positive: slower than the reference) and across
/// it (reference − output on the reference's right axis, FRD; positive:
/// the velocity points left of the reference, as it does when it lags a
/// right turn). A controller that tracks a
/// moving reference with a lag shows it here as a mean, which an RMS does
/// not separate from turbulence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentLag {
    /// Mean along-track velocity error (m/s).
    pub along_m_s: f64,
    /// Mean cross-track velocity error (m/s; positive: the velocity points
    /// left of the reference).
    pub cross_m_s: f64,
}

/// The mean along- and cross-track error of the log rows with
/// `t0_s <= t < t1_s`, in the axes of each row's reference heading; `None`
/// when no row falls inside.
pub fn segment_lag(log: &[crate::closed_loop::LogRow], t0_s: f64, t1_s: f64) -> Option<SegmentLag> {
    let (mut along, mut cross, mut n) = (0.0f64, 0.0f64, 0usize);
    for r in log.iter().filter(|r| r.t_s >= t0_s && r.t_s < t1_s) {
        let (s, c) = r.reference[3].sin_cos();
        let (dn, de) = (r.reference[0] - r.output[0], r.reference[1] - r.output[1]);
        along += c * dn + s * de;
        cross += -s * dn + c * de;
        n += 1;
    }
    (n > 0).then(|| SegmentLag {
        along_m_s: along / n as f64,
        cross_m_s: cross / n as f64,
    })
}
