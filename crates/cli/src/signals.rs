//! SIGINT and SIGTERM end a long run (`helicon sim`, `sitl`, `onboard`)
//! cleanly: the first sets a stop flag that the run checks each step; the
//! run then closes its logs and writes the files a normal end writes,
//! marked as stopped, and the process exits with the shell's convention for
//! a death by that signal, 128 + its number (130 for SIGINT, 143 for
//! SIGTERM). A second signal while stopping exits at once with that code.

use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The stop flag of a run and the signal that set it.
#[derive(Debug, Clone)]
pub struct Stop {
    flag: Arc<AtomicBool>,
    signal: Arc<AtomicUsize>,
}

/// A run ended by a signal: its files are complete; `main` exits with
/// [`Stopped::exit_code`].
#[derive(Debug)]
pub struct Stopped {
    /// The signal's number.
    pub signal: i32,
    /// Its name (`SIGINT`).
    pub name: &'static str,
    /// What was written.
    pub what: String,
}

impl std::fmt::Display for Stopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "stopped by {}; {}", self.name, self.what)
    }
}

impl std::error::Error for Stopped {}

impl Stopped {
    /// 128 + the signal's number.
    pub fn exit_code(&self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(1)
    }
}

/// The name of the signals a run stops on.
pub fn signal_name(signal: i32) -> &'static str {
    match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        _ => "a signal",
    }
}

impl Stop {
    /// Install the handlers of SIGINT and SIGTERM.
    pub fn install() -> anyhow::Result<Self> {
        let flag = Arc::new(AtomicBool::new(false));
        let signal = Arc::new(AtomicUsize::new(0));
        for sig in [SIGINT, SIGTERM] {
            let code = 128 + sig;
            // the second signal (the flag already set) exits at once;
            // registered first, so the first signal only sets the flag
            signal_hook::flag::register_conditional_shutdown(sig, code, flag.clone())?;
            signal_hook::flag::register_usize(sig, signal.clone(), sig as usize)?;
            signal_hook::flag::register(sig, flag.clone())?;
        }
        Ok(Stop { flag, signal })
    }

    /// The flag a run checks each step.
    pub fn flag(&self) -> &Arc<AtomicBool> {
        &self.flag
    }

    /// The signal received, if any.
    pub fn received(&self) -> Option<i32> {
        if !self.flag.load(Ordering::SeqCst) {
            return None;
        }
        i32::try_from(self.signal.load(Ordering::SeqCst))
            .ok()
            .filter(|s| *s != 0)
            .or(Some(SIGINT))
    }

    /// The error ending a stopped run, naming what it wrote.
    pub fn stopped(&self, what: impl Into<String>) -> Option<Stopped> {
        self.received().map(|signal| Stopped {
            signal,
            name: signal_name(signal),
            what: what.into(),
        })
    }
}

/// Name the signal in the summary of a flight it stopped: `reason`
/// `stopped by SIGINT at t = 12.345 s` (the flight loop says only that it
/// was asked to stop).
pub fn mark_stopped(stop: &Stop, summary: &mut helicon_sim::closed_loop::Summary) {
    if summary.outcome != helicon_sim::closed_loop::Outcome::Stopped {
        return;
    }
    if let Some(sig) = stop.received() {
        summary.reason = Some(format!(
            "stopped by {} at t = {:.3} s",
            signal_name(sig),
            summary.t_end_s
        ));
    }
}
