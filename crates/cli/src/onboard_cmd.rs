//! `helicon onboard --config onboard.toml [--duration S]`: the on-board
//! program. Opens the devices of the configuration, aligns on the ground
//! from the sensors, and runs the sensor server, the 400 Hz control task,
//! the avionics and the logger until `--duration` or a signal (a device
//! lost is reopened, not the end); writes the ULog flight log
//! (`flight-<NNNN>-<UTC>.ulg`, the next number of the folder, never an
//! existing file) and beside it its timing report
//! (`flight-<NNNN>-<UTC>-timing.json`, created new, never replacing a file)
//! into the log folder. SIGINT or SIGTERM ends the run as its end would
//! (log closed, the timing report with `"stopped_by"`), exit status 130 or
//! 143.

use crate::console::Console;
use crate::signals::{Stop, signal_name};
use anyhow::{Context, Result};
use clap::Args;
use helicon_flight::config::OnboardConfig;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// `helicon onboard`.
#[derive(Args, Debug)]
pub struct OnboardArgs {
    /// The on-board configuration (TOML; see docs/onboard.md and examples/onboard.toml).
    #[arg(long)]
    pub config: PathBuf,
    /// Stop after this many seconds of control (finite, > 0).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Do not ask for SCHED_FIFO for the control task.
    #[arg(long)]
    pub no_sched_fifo: bool,
}

/// Run `helicon onboard`.
pub fn run(a: &OnboardArgs) -> Result<()> {
    let duration = match a.duration {
        Some(d) if d.is_finite() && d > 0.0 && d <= 1e7 => Some(Duration::from_secs_f64(d)),
        Some(d) => anyhow::bail!("--duration {d}: must be finite, > 0 and <= 1e7 s"),
        None => None,
    };
    let cfg = OnboardConfig::from_file(&a.config)?;
    let stop = Stop::install()?;
    let result = helicon_flight::onboard::run_until(&cfg, duration, !a.no_sched_fifo, stop.flag());
    if let (Err(helicon_flight::onboard::OnboardError::Stopped), Some(e)) = (
        &result,
        stop.stopped("no flight log was written (still aligning)"),
    ) {
        return Err(e.into());
    }
    let (report, log) =
        result.with_context(|| format!("{}: on-board program", a.config.display()))?;
    let path = timing_path(&log);
    // the report, and the signal that ended the run (null: it ran its
    // --duration)
    let mut doc = serde_json::to_value(&report).context("timing.json")?;
    if let Some(map) = doc.as_object_mut() {
        map.insert("stopped_by".into(), stop.received().map(signal_name).into());
    }
    let text = serde_json::to_string_pretty(&doc).context("timing.json")?;
    write_new(&path, &text)?;
    let mut con = Console::stdout();
    writeln!(
        con,
        "{} control steps, {} deadline misses, final mode {}; wake-up jitter p50 {:.0} µs \
         p99 {:.0} µs max {:.0} µs; sensor-to-servo p99 {:.0} µs",
        report.steps,
        report.deadline_misses,
        report.final_mode,
        report.wakeup_jitter.p50_us,
        report.wakeup_jitter.p99_us,
        report.wakeup_jitter.max_us,
        report.sensor_to_servo.p99_us
    );
    writeln!(con, "wrote {} and {}", log.display(), path.display());
    if let Some(e) = &report.error {
        anyhow::bail!("the on-board program stopped: {e}");
    }
    if let Some(e) = stop.stopped(format!(
        "{} and {} are complete",
        log.display(),
        path.display()
    )) {
        let _ = con.finish();
        return Err(e.into());
    }
    con.finish()?;
    Ok(())
}

/// The timing report of the flight log `log`, beside it:
/// `flight-0002-20261202T120000Z.ulg` → `flight-0002-20261202T120000Z-timing.json`
/// (each flight's own, as the log's name is unique).
fn timing_path(log: &Path) -> PathBuf {
    let stem = log
        .file_stem()
        .map_or_else(|| "flight".into(), |s| s.to_string_lossy().into_owned());
    log.with_file_name(format!("{stem}-timing.json"))
}

/// Write `text` to the new file `path` (an existing file is an error, not
/// replaced).
fn write_new(path: &Path, text: &str) -> Result<()> {
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .with_context(|| format!("{}: cannot create (never replaced)", path.display()))?;
    f.write_all(text.as_bytes())
        .and_then(|()| f.sync_all())
        .with_context(|| format!("{}: cannot write", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_timing_report_is_named_after_its_flight_log() {
        assert_eq!(
            timing_path(Path::new("logs/flight-0002-20261202T120000Z.ulg")),
            Path::new("logs/flight-0002-20261202T120000Z-timing.json")
        );
    }

    #[test]
    fn an_existing_timing_report_is_not_replaced() {
        let d = std::env::temp_dir().join(format!("helicon_timing_new_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("flight-0001-timing.json");
        write_new(&p, "{}").unwrap();
        let e = write_new(&p, "{\"x\": 1}").unwrap_err();
        assert!(format!("{e:#}").contains("cannot create"), "{e:#}");
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "{}");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
