//! Standard output that never panics on a closed pipe.
//!
//! `println!` panics when the reader has gone (`helicon sim … | head -1`).
//! Every subcommand writes its stdout through a [`Console`] instead: the
//! first write error is kept, later writes are skipped, and
//! [`Console::finish`] returns it, so the command's work (run folders,
//! every case of a multi-case scenario) is done whatever happens to stdout.
//! `main` turns a broken pipe into a quiet exit with status 0.

use std::fmt;
use std::io::{self, Write};

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

/// `eprintln!` without the panic when stderr is a closed pipe
/// (`helicon … 2>&1 | head -1`): a note that cannot be shown is dropped.
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}
pub(crate) use note;
