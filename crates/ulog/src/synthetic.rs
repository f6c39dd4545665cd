//! Synthetic flight logs, for tests and examples: `control` records at
//! stamps the caller chooses, with values a test can recompute
//! ([`synthetic_value`]), each optionally followed by one record of another
//! topic (a `servo_output`, an `excitation`). Written with the project's
//! own writer ([`FlightLog`]), so what a reader makes of them is what it
//! makes of a flight's log.

use crate::error::WriteError;
use crate::messages::{Control, FlightLog, LogInfo, LogRecord, ServoOutput};
use crate::writer::FlushPolicy;
use std::path::Path;

/// Field `i` of step `k` of a synthetic log: sin(0.37·k + i), a sequence in
/// [−1, 1] that looks random to the spectra and that a test recomputes.
pub fn synthetic_value(k: u64, i: usize) -> f64 {
    ((k as f64) * 0.37 + i as f64).sin()
}

/// The `servo_output` record of the step of `control`: the servos got its
/// commands, decided by `source` (0 the control law, 1 the pilot, 2 a
/// failsafe), stamped as the step.
pub fn servo_record(control: &Control, source: u8) -> LogRecord {
    LogRecord::Servo(ServoOutput {
        timestamp: control.timestamp,
        command: control.command,
        source,
    })
}

/// Write to `path` a flight log of the control steps `k` = 0 … `n` − 1
/// stamped `stamp(k)` µs (`None`: the step is not logged, a dropped
/// sample). Each step's `control` record has `t_s` its stamp, the commands
/// [`synthetic_value`]`(k, 0..4)`, the estimate `(k, 10..19)` and the
/// measurements `(k, 20..29)`; `edit(k, &mut control)` may change it before
/// it is written; then the record `after(k, &control)` gives, if any, is
/// written after it (the runtime writes a step's records `control` first).
pub fn write_control_log(
    path: &Path,
    n: u64,
    stamp: impl Fn(u64) -> Option<u64>,
    mut edit: impl FnMut(u64, &mut Control),
    mut after: impl FnMut(u64, &Control) -> Option<LogRecord>,
) -> Result<(), WriteError> {
    let mut log = FlightLog::create(path, &LogInfo::default(), FlushPolicy::default())?;
    for k in 0..n {
        let Some(ts) = stamp(k) else { continue };
        let mut control = Control {
            timestamp: ts,
            sample: k,
            t_s: ts as f64 * 1e-6,
            command: std::array::from_fn(|i| synthetic_value(k, i)),
            estimate: std::array::from_fn(|i| synthetic_value(k, i + 10)),
            measured: std::array::from_fn(|i| synthetic_value(k, i + 20)),
            ..Control::default()
        };
        edit(k, &mut control);
        log.write(&LogRecord::Control(control))?;
        if let Some(r) = after(k, &control) {
            log.write(&r)?;
        }
    }
    log.finish()?;
    Ok(())
}
