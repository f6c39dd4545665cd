//! Standard output that never panics on a closed pipe.
//!
//! `println!` panics when the reader has gone (`helicon sim … | head -1`).
//! Every subcommand writes its stdout through a [`Console`] instead: the
//! first write error is kept, later writes are skipped, and
//! [`Console::finish`] returns it, so the command's work (run folders,
//! every case of a multi-case scenario) is done whatever happens to stdout.
//! `main` turns a broken pipe into a quiet exit with status 0.
//!
//! Slow work shows itself on stderr through [`spinner`] and [`bar`]: drawn
//! only when stderr is a terminal (nothing in a pipe, a file or a test), and
//! cleared when done, so the command's own lines are all that stays.

use std::borrow::Cow;
use std::fmt;
use std::io::{self, Write};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// A spinner on stderr saying `message` and the time spent, ticking on its
/// own (10 times a second) until `finish_and_clear`; hidden when stderr is
/// not a terminal.
pub fn spinner(message: impl Into<Cow<'static, str>>) -> ProgressBar {
    let s = ProgressBar::new_spinner();
    s.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    s.set_message(message);
    s.enable_steady_tick(Duration::from_millis(100));
    s
}

/// A bar on stderr of `len` steps saying `message`, its percentage, the time
/// spent and the time left; hidden when stderr is not a terminal.
pub fn bar(len: u64, message: impl Into<Cow<'static, str>>) -> ProgressBar {
    let b = ProgressBar::new(len);
    b.set_style(
        ProgressStyle::with_template(
            "{msg} [{bar:40.cyan/blue}] {percent:>3}% {elapsed_precise} (eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    b.set_message(message);
    b
}

/// Buffered, locked standard output that remembers its first error.
pub struct Console {
    out: io::BufWriter<io::StdoutLock<'static>>,
    error: Option<io::Error>,
}

impl Console {
    /// Lock standard output.
    pub fn stdout() -> Console {
        Console {
            out: io::BufWriter::new(io::stdout().lock()),
            error: None,
        }
    }

    /// `write!`/`writeln!` target: writes unless an earlier write failed,
    /// then flushes (the progress bars on stderr interleave with the lines).
    pub fn write_fmt(&mut self, args: fmt::Arguments<'_>) {
        if self.error.is_some() {
            return;
        }
        if let Err(e) = self.out.write_fmt(args).and_then(|()| self.out.flush()) {
            self.error = Some(e);
        }
    }

    /// Write raw text (a whole document such as a TOML file).
    pub fn write_str(&mut self, s: &str) {
        self.write_fmt(format_args!("{s}"));
    }

    /// Flush and return the first write error, if any.
    pub fn finish(mut self) -> io::Result<()> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.out.flush()
    }
}

/// A status line on stderr for a flight on the wall clock: once a second
/// the simulated time read from [`SimStatus::clock`] (s, as `f64::to_bits`,
/// set by the flight), of `duration_s`, and the real-time factor since the
/// line started; removed when dropped. Nothing when not `shown` or when
/// stderr is not a terminal.
pub struct SimStatus {
    clock: std::sync::Arc<std::sync::atomic::AtomicU64>,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl SimStatus {
    /// Start the status line of a flight of `duration_s` (if `shown`).
    pub fn start(shown: bool, duration_s: f64) -> Self {
        use std::io::IsTerminal;
        use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
        let clock = std::sync::Arc::new(AtomicU64::new(0));
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        if !(shown && io::stderr().is_terminal()) {
            return SimStatus {
                clock,
                stop,
                thread: None,
            };
        }
        let (done, time) = (stop.clone(), clock.clone());
        let thread = std::thread::spawn(move || {
            let line = spinner("flying");
            let wall0 = std::time::Instant::now();
            let sim0 = f64::from_bits(time.load(Ordering::Relaxed));
            let mut next_s = 1.0;
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(100));
                let wall_s = wall0.elapsed().as_secs_f64();
                if wall_s < next_s {
                    continue;
                }
                next_s += 1.0;
                let t_s = f64::from_bits(time.load(Ordering::Relaxed));
                line.set_message(format!(
                    "flying: t = {t_s:.1} s of {duration_s} s, {:.2}x real time",
                    (t_s - sim0) / wall_s
                ));
            }
            line.finish_and_clear();
        });
        SimStatus {
            clock,
            stop,
            thread: Some(thread),
        }
    }

    /// The simulated time the flight sets (its `f64::to_bits`).
    pub fn clock(&self) -> std::sync::Arc<std::sync::atomic::AtomicU64> {
        self.clock.clone()
    }

    /// Run `flight`, then remove the line.
    pub fn during<R>(self, flight: impl FnOnce() -> R) -> R {
        flight()
    }
}

impl Drop for SimStatus {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// `eprintln!` without the panic when stderr is a closed pipe
/// (`helicon … 2>&1 | head -1`): a note that cannot be shown is dropped.
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}
pub(crate) use note;
