//! The writer of `log.csv`: each number in its shortest round-trip text,
//! the rows formatted and written on a thread of their own
//! ([`LogWriter`]: the flight's thread only copies a row into a ring), and
//! the size estimate a flight checks against its limit before it flies.

use super::{LOG_SCHEMA, LogCsvError, estimator_error, io_err};
use crate::closed_loop::LogRow;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Write one number: shortest round-trip text, plain notation for ordinary
/// magnitudes and exponent notation for very small or large ones. The text
/// is that of `format!("{v}")` (plain) and `format!("{v:e}")` (exponent),
/// the reference implementation [`put_fmt`]; the digits come from `zmij`
/// (the same shortest round-trip digits, several times faster than going
/// through `core::fmt`), whose text is decimal notation in [1e-5, 1e16)
/// and `d.ddde±x` beyond. `v` must be finite.
///
/// The one difference of the two digit generators is a tie: an exact value
/// halfway between two shortest candidates, where `core::fmt` takes the
/// larger magnitude and `zmij` the even last digit (2236729633436452.25 is
/// one). Writing |v| = m·2^e with m odd and I = 10·d + 5 the odd midpoint
/// of the n shortest digits d, a tie is |v| = I·10^q: the powers of two
/// cancel only if e = q ≥ 0, or e = q = −s < 0 with m·5^s = I < 10^19,
/// which needs s ≤ 27. So a value that is not a multiple of 2^−27
/// ([`tie_possible`]) never ties; the others (0.5, 2.0, integers: exact
/// binary fractions) are written by `core::fmt`.
fn put(line: &mut String, v: f64, buf: &mut zmij::Buffer) {
    let a = v.abs();
    if a == 0.0 {
        line.push_str(if v.is_sign_negative() { "-0" } else { "0" });
        return;
    }
    if tie_possible(v) {
        put_fmt(line, v);
        return;
    }
    let s = buf.format_finite(v);
    if (1e-4..1e9).contains(&a) {
        // decimal notation, as `{v}` (which has no `.0`)
        line.push_str(s.strip_suffix(".0").unwrap_or(s));
    } else if a < 1e-5 {
        // `d.ddde-x`, as `{v:e}`
        line.push_str(s);
    } else {
        relayout_exp(line, s);
    }
}

/// `zmij`'s decimal (or `e+x`) text of a number beyond the plain range, in
/// `{v:e}` form: the significant digits `d.ddd`, then `e` and the exponent.
fn relayout_exp(line: &mut String, s: &str) {
    let (neg, body) = match s.strip_prefix('-') {
        Some(b) => (true, b),
        None => (false, s),
    };
    let (mant, exp) = match body.split_once('e') {
        Some((m, e)) => (m, e.trim_start_matches('+').parse::<i32>().unwrap_or(0)),
        None => (body, 0),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    let mut digits = [0u8; 40];
    let mut n = 0;
    let mut lead = 0i32;
    for &b in int.as_bytes().iter().chain(frac.as_bytes()) {
        if n == 0 && b == b'0' {
            lead += 1;
        } else if n < digits.len() {
            digits[n] = b;
            n += 1;
        }
    }
    while n > 1 && digits[n - 1] == b'0' {
        n -= 1;
    }
    // a float's integer digits number at most 309: the cast cannot wrap
    let e10 = i32::try_from(int.len()).unwrap_or(i32::MAX) - 1 - lead + exp;
    if neg {
        line.push('-');
    }
    line.push(char::from(digits[0]));
    if n > 1 {
        line.push('.');
        for &b in &digits[1..n] {
            line.push(char::from(b));
        }
    }
    line.push('e');
    line.push_str(itoa_i32(e10).as_str());
}

/// Can |v| = m·2^e tie (see [`put`]): is it a multiple of 2^−27?
fn tie_possible(v: f64) -> bool {
    let bits = v.to_bits() & !(1u64 << 63);
    let (be, frac) = ((bits >> 52) as i32, bits & ((1u64 << 52) - 1));
    let (m, e) = if be == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), be - 1075)
    };
    // trailing_zeros of a u64 is at most 64: the cast cannot wrap
    m != 0 && i32::try_from(m.trailing_zeros()).unwrap_or(64) + e >= -27
}

/// A small integer as text, without allocating.
struct SmallInt {
    b: [u8; 12],
    start: usize,
}

impl SmallInt {
    fn as_str(&self) -> &str {
        std::str::from_utf8(&self.b[self.start..]).unwrap_or("0")
    }
}

fn itoa_i32(v: i32) -> SmallInt {
    let mut b = [0u8; 12];
    let mut i = b.len();
    let neg = v < 0;
    let mut u = v.unsigned_abs();
    loop {
        i -= 1;
        b[i] = b'0' + (u % 10) as u8;
        u /= 10;
        if u == 0 {
            break;
        }
    }
    if neg {
        i -= 1;
        b[i] = b'-';
    }
    SmallInt { b, start: i }
}

/// The reference text of one number (what [`put`] must write).
fn put_fmt(line: &mut String, v: f64) {
    use std::fmt::Write as _;
    let a = v.abs();
    // writing into a String cannot fail
    let _ = if a == 0.0 || (1e-4..1e9).contains(&a) {
        write!(line, "{v}")
    } else {
        write!(line, "{v:e}")
    };
}

/// Streaming `log.csv` writer: the header on [`LogWriter::create`], one line
/// per [`LogWriter::write`], buffered, memory independent of the number of
/// rows. Call [`LogWriter::finish`] at the end (dropping the writer flushes
/// but cannot report an error). With [`LogWriter::with_stride`] it writes
/// every n-th row given (and the last one, at [`LogWriter::finish`]).
#[derive(Debug)]
pub struct LogWriter {
    path: PathBuf,
    label: String,
    /// Rows go to the formatter thread through this ring (taken by
    /// [`Self::finish`]).
    ring: Option<rtrb::Producer<LogRow>>,
    /// The formatter thread: its rows written, or the first write error.
    worker: Option<std::thread::JoinHandle<Result<usize, LogCsvError>>>,
    /// Set by the formatter thread when a write failed (it then stops).
    failed: std::sync::Arc<std::sync::atomic::AtomicBool>,
    rows: usize,
    last_t: f64,
    /// Write every `stride`-th row given.
    stride: usize,
    /// Rows given so far.
    given: usize,
    /// The last row given, when it was not written (written by `finish`).
    pending: Option<LogRow>,
}

/// Rows a [`LogWriter`]'s ring holds (about 2.5 MB): the flight runs ahead
/// of its formatter by at most this many rows, then waits for it.
pub const LOG_RING_ROWS: usize = 4096;

/// The formatting and writing half of a [`LogWriter`], on its own thread:
/// the rows it is given are checked already.
struct RowFormatter<W: Write> {
    label: String,
    out: BufWriter<W>,
    text: RowText,
}

impl<W: Write> RowFormatter<W> {
    /// Format one checked row and write it.
    fn write(&mut self, r: &LogRow) -> Result<(), LogCsvError> {
        self.out
            .write_all(self.text.format(r).as_bytes())
            .map_err(|e| io_err(&self.label, e))
    }

    /// Write the rows of `ring` until its writer is gone, then flush; the
    /// rows written. Waits a little when the ring is empty.
    fn run(mut self, mut ring: rtrb::Consumer<LogRow>) -> Result<usize, LogCsvError> {
        let mut rows = 0;
        loop {
            match ring.pop() {
                Ok(r) => {
                    self.write(&r)?;
                    rows += 1;
                }
                Err(_) if ring.is_abandoned() => {
                    // the last rows pushed before the writer went
                    while let Ok(r) = ring.pop() {
                        self.write(&r)?;
                        rows += 1;
                    }
                    break;
                }
                // (a millisecond: the flight fills at most a tenth of the
                // ring meanwhile, and a lock-step SITL run is not woken
                // 5000 times a second)
                Err(_) => std::thread::sleep(std::time::Duration::from_millis(1)),
            }
        }
        self.out.flush().map_err(|e| io_err(&self.label, e))?;
        Ok(rows)
    }
}

/// The size of a `log.csv` before it is written: [`estimate_log_size`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogSizeEstimate {
    /// Data rows.
    pub rows: u64,
    /// Bytes of one row, its newline included (mean).
    pub bytes_per_row: f64,
    /// Bytes of the file, header included.
    pub bytes: u64,
}

/// Bytes of `log.csv`'s header line (its newline included).
pub fn header_bytes() -> u64 {
    LOG_SCHEMA.iter().map(|c| c.name.len() as u64 + 1).sum()
}

/// Bytes of one row as [`LogWriter`] writes it (its newline included).
pub fn row_bytes(r: &LogRow) -> usize {
    RowText::new().format(r).len()
}

/// The text of `log.csv` rows, one at a time: every column of
/// [`LOG_SCHEMA`] in order, each number as [`LogWriter`] writes it, the
/// newline included. Its buffers are reused: no allocation per row.
#[derive(Default)]
pub struct RowText {
    line: String,
    digits: zmij::Buffer,
}

impl RowText {
    /// A formatter with room for a row.
    pub fn new() -> Self {
        RowText {
            line: String::with_capacity(2048),
            digits: zmij::Buffer::new(),
        }
    }

    /// The line of one row. The values must be finite ([`LogWriter`]
    /// checks them before formatting).
    pub fn format(&mut self, r: &LogRow) -> &str {
        self.line.clear();
        for (j, c) in LOG_SCHEMA.iter().enumerate() {
            if j > 0 {
                self.line.push(',');
            }
            put(&mut self.line, c.value(r), &mut self.digits);
        }
        self.line.push('\n');
        &self.line
    }
}

/// The rows a writer of stride `stride` writes of `given` rows: every
/// `stride`-th from the first, and the last.
pub fn strided_rows(given: u64, stride: u64) -> u64 {
    let stride = stride.max(1);
    match given {
        0 => 0,
        m => (m - 1) / stride + 1 + u64::from((m - 1) % stride != 0),
    }
}

/// Estimate the size of a `log.csv` of `rows` data rows whose times are
/// `times_s` (each row's `t_s`, in order; only up to 2000 of them, evenly
/// spread, are formatted), from `sample` rows of the same flight (e.g. its
/// first second flown): each row costs the mean width of the sample's
/// cells, the time column the mean width of the flight's own times (its
/// digits grow with the duration). `None` without a sample row.
pub fn estimate_log_size(
    sample: &[LogRow],
    rows: u64,
    time_at: impl Fn(u64) -> f64,
) -> Option<LogSizeEstimate> {
    if sample.is_empty() {
        return None;
    }
    let width = |v: f64| {
        let mut line = String::with_capacity(32);
        put(&mut line, v, &mut zmij::Buffer::new());
        line.len() as f64
    };
    let sample_rows = sample.iter().map(|r| row_bytes(r) as f64).sum::<f64>();
    let sample_t = sample.iter().map(|r| width(r.t_s)).sum::<f64>();
    let n = sample.len() as f64;
    let picks = rows.min(2000);
    let t_width = if picks == 0 {
        0.0
    } else {
        (0..picks)
            .map(|i| time_at(i * (rows - 1) / (picks - 1).max(1)))
            .map(width)
            .sum::<f64>()
            / picks as f64
    };
    let bytes_per_row = (sample_rows - sample_t) / n + t_width;
    Some(LogSizeEstimate {
        rows,
        bytes_per_row,
        bytes: header_bytes() + (bytes_per_row * rows as f64).round() as u64,
    })
}

impl LogWriter {
    /// Create (truncate) the file and write the header. Fails, naming the
    /// file, when the folder does not exist or is not writable: call it
    /// before flying.
    pub fn create(path: &Path) -> Result<Self, LogCsvError> {
        let label = path.display().to_string();
        let file = File::create(path).map_err(|e| io_err(&label, e))?;
        Self::start(path, label, file)
    }

    /// Write the header to `out`, then start the formatter thread on it.
    fn start<W: Write + Send + 'static>(
        path: &Path,
        label: String,
        out: W,
    ) -> Result<Self, LogCsvError> {
        let mut out = BufWriter::with_capacity(1 << 16, out);
        let header = LOG_SCHEMA.map(|c| c.name).join(",");
        out.write_all(header.as_bytes())
            .and_then(|()| out.write_all(b"\n"))
            .and_then(|()| out.flush())
            .map_err(|e| io_err(&label, e))?;
        let (ring, rows_out) = rtrb::RingBuffer::new(LOG_RING_ROWS);
        let failed = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let formatter = RowFormatter {
            label: label.clone(),
            out,
            text: RowText::new(),
        };
        let flag = std::sync::Arc::clone(&failed);
        let worker = std::thread::Builder::new()
            .name("log.csv".into())
            .spawn(move || {
                let r = formatter.run(rows_out);
                if r.is_err() {
                    flag.store(true, std::sync::atomic::Ordering::Release);
                }
                r
            })
            .map_err(|e| io_err(&label, format!("starting its writer thread: {e}")))?;
        Ok(Self {
            path: path.to_path_buf(),
            label,
            ring: Some(ring),
            worker: Some(worker),
            failed,
            rows: 0,
            last_t: f64::NEG_INFINITY,
            stride: 1,
            given: 0,
            pending: None,
        })
    }

    /// Write only every `stride`-th row given from the first, and the last
    /// one given (at [`Self::finish`]): the log at a lower rate. A row not
    /// written is not checked. `stride` 0 counts as 1.
    #[must_use]
    pub fn with_stride(mut self, stride: usize) -> Self {
        self.stride = stride.max(1);
        self
    }

    /// The stride ([`Self::with_stride`]).
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Append one row (with a stride, every n-th; see
    /// [`Self::with_stride`]). A non-finite value or a time that does not
    /// increase is an error (nothing of the row is written).
    pub fn write(&mut self, r: &LogRow) -> Result<(), LogCsvError> {
        let take = self.given % self.stride == 0;
        self.given += 1;
        if !take {
            self.pending = Some(*r);
            return Ok(());
        }
        self.pending = None;
        self.write_row(r)
    }

    /// Check one row (finite values, increasing time) and hand it to the
    /// formatter thread, waiting while its ring is full. A write error of
    /// that thread is returned here, at the next row (or by
    /// [`Self::finish`]).
    fn write_row(&mut self, r: &LogRow) -> Result<(), LogCsvError> {
        let line = self.rows + 2;
        if !row_is_finite(r) {
            // the column to name: the first of the schema that is not finite
            for c in &LOG_SCHEMA {
                let v = c.value(r);
                if !v.is_finite() {
                    return Err(LogCsvError::NonFiniteValue {
                        path: self.label.clone(),
                        line,
                        name: c.name.to_string(),
                        value: v,
                        t_s: r.t_s,
                    });
                }
            }
        }
        if r.t_s <= self.last_t {
            return Err(LogCsvError::TimeNotIncreasing {
                path: self.label.clone(),
                line,
                t_s: r.t_s,
                previous_s: self.last_t,
            });
        }
        let mut row = *r;
        loop {
            if self.failed.load(std::sync::atomic::Ordering::Acquire) {
                return Err(self.worker_error());
            }
            let Some(ring) = self.ring.as_mut() else {
                return Err(io_err(&self.label, "written after its end"));
            };
            match ring.push(row) {
                Ok(()) => break,
                Err(rtrb::PushError::Full(back)) => {
                    row = back;
                    std::thread::yield_now();
                }
            }
        }
        self.rows += 1;
        self.last_t = r.t_s;
        Ok(())
    }

    /// The formatter thread's error (it has stopped).
    fn worker_error(&mut self) -> LogCsvError {
        match self.worker.take().map(std::thread::JoinHandle::join) {
            Some(Ok(Err(e))) => e,
            Some(Ok(Ok(_))) | None => io_err(&self.label, "its writer thread stopped"),
            Some(Err(_)) => io_err(&self.label, "its writer thread panicked"),
        }
    }

    /// Write the last row given if the stride skipped it, flush and close;
    /// returns the number of data rows.
    pub fn finish(mut self) -> Result<usize, LogCsvError> {
        if let Some(r) = self.pending.take() {
            self.write_row(&r)?;
        }
        // the formatter ends when the ring's writer is gone
        drop(self.ring.take());
        match self.worker.take().map(std::thread::JoinHandle::join) {
            Some(Ok(Ok(rows))) => Ok(rows),
            Some(Ok(Err(e))) => Err(e),
            None => Err(io_err(&self.label, "its writer thread stopped")),
            Some(Err(_)) => Err(io_err(&self.label, "its writer thread panicked")),
        }
    }
}

/// Is every column of `r` finite? The row's fields are checked as arrays
/// (several times faster than the schema's column walk, which names the
/// column when one is not); the derived columns, the estimator's errors, are
/// differences that can overflow and are checked as written.
fn row_is_finite(r: &LogRow) -> bool {
    let all = |v: &[f64]| v.iter().fold(true, |ok, x| ok & x.is_finite());
    r.t_s.is_finite()
        & all(r.x.as_slice())
        & all(r.u.as_slice())
        & all(&r.reference)
        & all(&r.output)
        & all(&r.estimate9)
        & all(&r.measured9)
        & all(&r.wind_ned)
        & all(&r.lambda)
        & all(&r.thrust)
        & all(&r.imu_health)
        & all(&r.excitation)
        & (0..9).fold(true, |ok, i| ok & estimator_error(r, i).is_finite())
}

impl Drop for LogWriter {
    /// A writer dropped without [`LogWriter::finish`] (a flight that ended
    /// in an error) still writes and flushes the rows it was given.
    fn drop(&mut self) {
        drop(self.ring.take());
        if let Some(w) = self.worker.take() {
            // its error has no one to go to: the caller is on its own error path
            let _ = w.join();
        }
    }
}

/// Write a whole log (every `decimation`-th row from the first) to `path`;
/// returns the number of data rows.
pub fn write_log(path: &Path, log: &[LogRow], decimation: u32) -> Result<usize, LogCsvError> {
    let mut w = LogWriter::create(path)?;
    for r in log.iter().step_by(decimation.max(1) as usize) {
        w.write(r)?;
    }
    w.finish()
}

#[cfg(test)]
mod format_tests {
    use super::{put, put_fmt};

    fn same(v: f64, buf: &mut zmij::Buffer) {
        let (mut a, mut b) = (String::new(), String::new());
        put(&mut a, v, buf);
        put_fmt(&mut b, v);
        assert_eq!(a, b, "{v:?} (bits {:#x})", v.to_bits());
        assert_eq!(a.parse::<f64>().map(f64::to_bits), Ok(v.to_bits()), "{a}");
    }

    #[test]
    fn the_fast_formatter_writes_the_text_of_core_fmt() {
        let mut buf = zmij::Buffer::new();
        let mut special = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            1e-4,
            1e-4 * (1.0 - f64::EPSILON),
            1e9,
            1e9 * (1.0 - f64::EPSILON / 2.0),
            999_999_999.999_999_9,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            123_456_789.0,
            0.000_123_4,
            1e16,
            1e15,
            1e21,
            1e22,
            1e-5,
            2.5e-7,
            0.3,
            2.0f64.powi(60),
            std::f64::consts::PI,
        ];
        for e in -324..=308 {
            let p: f64 = format!("1e{e}").parse().unwrap_or(1.0);
            special.extend([p, -p, p * 3.0, p / 7.0]);
        }
        for v in special {
            if v.is_finite() {
                same(v, &mut buf);
            }
        }
        // random bit patterns (every magnitude) and random values of log
        // magnitudes (-10..10): splitmix64
        let mut s: u64 = 0x1234_5678;
        let mut next = || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        };
        for _ in 0..300_000 {
            let v = f64::from_bits(next());
            if v.is_finite() {
                same(v, &mut buf);
            }
            let u = (next() >> 11) as f64 / 2f64.powi(53);
            let w = (u - 0.5) * 10f64.powf((u * 20.0 - 10.0).round());
            same(w, &mut buf);
            // the magnitudes of a log, 1e-6 .. 1e14, uniformly in log
            let u2 = (next() >> 11) as f64 / 2f64.powi(53);
            same(
                10f64.powf(u2 * 20.0 - 6.0) * if u2 > 0.5 { -1.0 } else { 1.0 },
                &mut buf,
            );
            // few fraction bits: integers and halves, quarters, ... near 1e13
            let m = (next() >> 20) as f64;
            same(m / f64::from(1u32 << (next() % 12)), &mut buf);
        }
    }
}

#[cfg(test)]
mod writer_tests {
    use super::{LOG_RING_ROWS, LogCsvError, LogWriter, RowText};
    use crate::closed_loop::LogRow;
    use helicon_model::{Input, State};
    use std::io::Write;
    use std::path::Path;
    use std::sync::{Arc, Mutex};

    fn row(t_s: f64) -> LogRow {
        LogRow {
            t_s,
            x: State::from_fn(|i, _| 0.1 * i as f64 + t_s),
            u: Input::from_fn(|i, _| 0.01 * i as f64),
            reference: [1.0, 0.0, -0.5, 0.25],
            output: [0.0; 4],
            estimate9: [0.3; 9],
            measured9: [0.2; 9],
            wind_ned: [0.0; 3],
            lambda: [0.05, 0.1],
            thrust: [137.5, 4.0],
            inflow_residual: [0.0; 2],
            imu_health: [0.0; 3],
            excitation: [0.0; 4],
        }
    }

    /// An output that takes `room` bytes, then fails as a full disk does;
    /// what it took is kept.
    struct Disk {
        room: usize,
        taken: Arc<Mutex<Vec<u8>>>,
    }

    impl Write for Disk {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            let mut t = self.taken.lock().map_err(|_| std::io::ErrorKind::Other)?;
            if t.len() + buf.len() > self.room {
                return Err(std::io::ErrorKind::StorageFull.into());
            }
            t.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    fn writer(room: usize) -> (LogWriter, Arc<Mutex<Vec<u8>>>) {
        let taken = Arc::new(Mutex::new(Vec::new()));
        let disk = Disk {
            room,
            taken: Arc::clone(&taken),
        };
        let w = LogWriter::start(Path::new("log.csv"), "log.csv".into(), disk).unwrap();
        (w, taken)
    }

    #[test]
    fn the_writer_thread_writes_every_row_in_order_as_formatted() {
        // more rows than the ring holds: the flight waits for the formatter
        let n = 3 * LOG_RING_ROWS + 7;
        let (mut w, taken) = writer(usize::MAX);
        let mut text = RowText::new();
        let mut expected = String::new();
        for k in 0..n {
            let r = row(k as f64 * 0.0025 + 0.0025);
            w.write(&r).unwrap();
            expected.push_str(text.format(&r));
        }
        assert_eq!(w.finish().unwrap(), n);
        let taken = taken.lock().unwrap();
        let file = std::str::from_utf8(&taken).unwrap();
        let (header, body) = file.split_once('\n').unwrap();
        assert!(header.starts_with("t_s,"));
        assert_eq!(body, expected);
    }

    #[test]
    fn a_full_disk_is_an_error_naming_the_file_not_a_lost_log() {
        // room for the header and a few rows: the formatter fails, and the
        // flight hears of it at a later row or at the end
        let (mut w, _) = writer(20_000);
        let mut err = None;
        for k in 0..100_000 {
            if let Err(e) = w.write(&row(f64::from(k) + 1.0)) {
                err = Some(e);
                break;
            }
        }
        let e = match err {
            Some(e) => e,
            None => w.finish().unwrap_err(),
        };
        assert!(
            matches!(&e, LogCsvError::Io { path, .. } if path == "log.csv"),
            "{e}"
        );
    }

    #[test]
    fn a_non_finite_value_is_refused_on_the_flight_thread_naming_its_column() {
        let (mut w, _) = writer(usize::MAX);
        w.write(&row(1.0)).unwrap();
        let mut bad = row(2.0);
        bad.thrust[1] = f64::NAN;
        let e = w.write(&bad).unwrap_err();
        assert!(
            matches!(&e, LogCsvError::NonFiniteValue { line: 3, name, .. } if name == "force_tr_y_n"),
            "{e}"
        );
        // an overflowing estimator error is refused too (its inputs are finite)
        let mut far = row(3.0);
        far.estimate9[0] = -f64::MAX;
        far.x[helicon_model::state::REDUCED_OFFSET] = f64::MAX;
        assert!(matches!(
            w.write(&far),
            Err(LogCsvError::NonFiniteValue { .. })
        ));
        assert_eq!(w.finish().unwrap(), 1);
    }
}
