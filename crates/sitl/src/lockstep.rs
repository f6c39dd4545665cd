//! What the two autopilot physics backends ([`crate::ardupilot`] and
//! [`crate::px4`]) share: one simulation session from the ground start,
//! stepped one autopilot frame at a time, with its truth log, and how a
//! run ends.

use helicon_core::state::Input;
use helicon_sim::closed_loop::{
    ClosedLoopError, Hardware, HardwareSample, Prepared, Summary, Termination,
};
use helicon_sim::log_csv::{LogCsvError, LogWriter};
use helicon_sim::scenario::Scenario;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Why a backend run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Ending {
    /// The stop flag.
    Stopped,
    /// No valid packet within the silence timeout.
    Silent,
    /// The frame limit was stepped.
    FrameLimit,
    /// The simulation ended: the scenario's duration flown, a model
    /// failure or an envelope limit (the summary says which).
    Simulation(Termination, Option<String>),
}

impl Ending {
    /// Why the session is cut short (`None`: the simulation ended itself).
    pub(crate) fn abort_reason(&self) -> Option<&'static str> {
        match self {
            Ending::Stopped => Some("stopped on request"),
            Ending::Silent => Some("the autopilot went silent"),
            Ending::FrameLimit => Some("the frame limit was reached"),
            Ending::Simulation(..) => None,
        }
    }

    /// One line for a console.
    pub fn describe(&self) -> String {
        match self {
            Ending::Stopped => "stopped".to_string(),
            Ending::Silent => "the autopilot went silent".to_string(),
            Ending::FrameLimit => "frame limit".to_string(),
            Ending::Simulation(t, why) => format!(
                "{t}{}",
                why.as_deref().map_or(String::new(), |w| format!(" ({w})"))
            ),
        }
    }
}

/// One simulation from its initial state, at one step.
pub(crate) struct Session<'a> {
    pub(crate) hw: Hardware<'a>,
    /// Steps per second (1 / the step).
    rate_hz: f64,
    /// Steps flown.
    pub(crate) frames: u64,
    /// The sample of the state now (sensed, not yet actuated).
    pub(crate) now: Option<HardwareSample>,
    writer: Option<LogWriter>,
    rows: usize,
}

/// A session's end, for the report.
pub(crate) struct Closed {
    pub(crate) frames: u64,
    pub(crate) model_time_s: f64,
    pub(crate) final_state: helicon_model::State,
    pub(crate) rotor_speed_rad_s: f64,
    pub(crate) summary: Summary,
    pub(crate) rows: usize,
}

impl<'a> Session<'a> {
    /// A simulation from the initial state at `step_s`, sensed at t = 0,
    /// its truth log at `log_csv` (every `stride`-th row).
    pub(crate) fn new(
        scenario: &'a Scenario,
        prepared: &'a Prepared,
        step_s: f64,
        log_csv: Option<&Path>,
        stride: usize,
    ) -> Result<Self, SessionError> {
        let mut hw = Hardware::new_at(scenario, prepared, step_s)?.without_heading_check();
        let now = hw.sense();
        let writer = match log_csv {
            Some(path) => Some(LogWriter::create(path)?.with_stride(stride.max(1))),
            None => None,
        };
        Ok(Session {
            hw,
            rate_hz: 1.0 / step_s,
            frames: 0,
            now,
            writer,
            rows: 0,
        })
    }

    /// Model time now (s).
    pub(crate) fn time_s(&self) -> f64 {
        self.frames as f64 / self.rate_hz
    }

    /// One step with `input`, the engine on or cut; then sensed (`now`
    /// `None` once the flight ended). Returns the flight's end, if it
    /// ended in this step.
    pub(crate) fn step(
        &mut self,
        input: &Input,
        engine_on: bool,
    ) -> Result<Option<(Termination, Option<String>)>, LogCsvError> {
        self.hw.set_throttle_hold(!engine_on);
        let mut end = None;
        if let Some(step) = self.hw.actuate(input, None) {
            if step.kept
                && let Some(w) = self.writer.as_mut()
            {
                w.write(&step.row)?;
                self.rows += 1;
            }
            end = step.end;
        }
        self.frames += 1;
        self.now = if end.is_none() { self.hw.sense() } else { None };
        if self.now.is_none() && end.is_none() {
            end = Some((Termination::Completed, None));
        }
        Ok(end)
    }

    /// Close the session: its log finished, cut short with `why` (at its
    /// model time) unless the simulation ended itself.
    pub(crate) fn close(mut self, why: Option<&str>) -> Result<Closed, LogCsvError> {
        let t = self.time_s();
        if let Some(why) = why {
            self.hw
                .abort(Termination::Stopped, format!("{why} at t = {t:.3} s"));
        }
        let rows = match self.writer {
            Some(w) => w.finish()?,
            None => 0,
        };
        Ok(Closed {
            frames: self.frames,
            model_time_s: t,
            final_state: *self.hw.state(),
            rotor_speed_rad_s: self.hw.rotor_speed_rad_s(),
            summary: self.hw.summary(),
            rows,
        })
    }

    /// Drop the session for a restart of the autopilot: its log finished
    /// (the next session writes it afresh). Returns its model time.
    pub(crate) fn restart(self) -> Result<f64, LogCsvError> {
        let t = self.time_s();
        if let Some(w) = self.writer {
            w.finish()?;
        }
        Ok(t)
    }
}

/// Errors of starting a session.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// Building the hardware.
    #[error(transparent)]
    Prepare(#[from] ClosedLoopError),
    /// The truth log.
    #[error(transparent)]
    Csv(#[from] LogCsvError),
}

/// The ground below the simulator's origin (the design point): home, on
/// the ground, for the autopilots (m, down).
pub(crate) fn ground_down_m(prepared: &Prepared) -> f64 {
    let p = prepared.model.params();
    if p.landing_gear.is_enabled() {
        p.landing_gear.ground_down_m
    } else {
        0.0
    }
}

/// Create `out_dir` and name its `log.csv`.
pub(crate) fn log_path(
    out_dir: Option<&Path>,
) -> Result<Option<PathBuf>, (PathBuf, std::io::Error)> {
    match out_dir {
        Some(d) => {
            std::fs::create_dir_all(d).map_err(|e| (d.to_path_buf(), e))?;
            Ok(Some(d.join("log.csv")))
        }
        None => Ok(None),
    }
}

/// The stop flag is set.
pub(crate) fn stopped(stop: Option<&Arc<AtomicBool>>) -> bool {
    stop.is_some_and(|f| f.load(Ordering::Relaxed))
}
