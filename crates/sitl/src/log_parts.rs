//! Logs in bounded parts: a run that flies until stopped (`helicon sitl
//! --gcs` without `--duration`) keeps each of its logs under a size by
//! going on in a new numbered file when the bound is reached, the run
//! carrying on. `flight.ulg` is followed by `flight-0002.ulg`,
//! `flight-0003.ulg`, …; `log.csv` by `log-0002.csv`, … ([`part_path`]).
//!
//! [`UlogParts`] is the byte sink of the on-board flight log: it cuts the
//! ULog stream between messages, and each part begins with the first's
//! header, definitions (flag bits, formats, information, parameters) and
//! subscriptions, so every part is a whole ULog file a reader opens alone;
//! the data goes on in the next part with its own timestamps. With no bound
//! ([`u64::MAX`]) it writes the one file, byte for byte as the writer gave
//! it.

use helicon_ulog::spec::{HEADER_LEN, MSG_HEADER_LEN, msg};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Part `n` of the log whose first part is `first`: `first` itself for
/// `n` ≤ 1, then `<stem>-<NNNN>.<ext>` beside it.
pub fn part_path(first: &Path, n: u32) -> PathBuf {
    if n <= 1 {
        return first.to_path_buf();
    }
    let stem = first
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    match first.extension() {
        Some(ext) => first.with_file_name(format!("{stem}-{n:04}.{}", ext.to_string_lossy())),
        None => first.with_file_name(format!("{stem}-{n:04}")),
    }
}

/// A ULog byte sink in parts of at most `max_bytes` each (a part holds at
/// least one data message beyond its definitions, so a bound below the
/// definitions' size still makes progress).
#[derive(Debug)]
pub struct UlogParts {
    first: PathBuf,
    part: u32,
    out: BufWriter<File>,
    /// Bytes in the current part.
    written: u64,
    max_bytes: u64,
    /// The header, the definitions and the subscriptions: each part's start.
    preamble: Vec<u8>,
    /// Bytes given that do not make a whole message yet.
    pending: Vec<u8>,
    header_done: bool,
    in_definitions: bool,
}

impl UlogParts {
    /// The first part at `first` (replacing a file there: a run's own
    /// folder), parts of at most `max_bytes`.
    pub fn create(first: &Path, max_bytes: u64) -> io::Result<UlogParts> {
        Ok(UlogParts {
            first: first.to_path_buf(),
            part: 1,
            out: BufWriter::with_capacity(1 << 16, File::create(first)?),
            written: 0,
            max_bytes,
            preamble: Vec::with_capacity(64 * 1024),
            pending: Vec::with_capacity(1 << 16),
            header_done: false,
            in_definitions: true,
        })
    }

    /// The parts begun so far (1 until the first bound is reached).
    pub fn parts(&self) -> u32 {
        self.part
    }

    fn emit(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.out.write_all(bytes)?;
        self.written += bytes.len() as u64;
        Ok(())
    }

    fn next_part(&mut self) -> io::Result<()> {
        self.out.flush()?;
        self.part += 1;
        self.out =
            BufWriter::with_capacity(1 << 16, File::create(part_path(&self.first, self.part))?);
        self.written = 0;
        let preamble = std::mem::take(&mut self.preamble);
        let r = self.emit(&preamble);
        self.preamble = preamble;
        r
    }

    /// Write the whole messages of `pending`, keeping the rest.
    fn drain_messages(&mut self) -> io::Result<()> {
        let pending = std::mem::take(&mut self.pending);
        let mut at = 0;
        let r = (|| {
            if !self.header_done {
                if pending.len() < HEADER_LEN {
                    return Ok(());
                }
                self.preamble.extend_from_slice(&pending[..HEADER_LEN]);
                self.emit(&pending[..HEADER_LEN])?;
                self.header_done = true;
                at = HEADER_LEN;
            }
            while pending.len() - at >= MSG_HEADER_LEN {
                let size = usize::from(u16::from_le_bytes([pending[at], pending[at + 1]]));
                let total = MSG_HEADER_LEN + size;
                if pending.len() - at < total {
                    break;
                }
                let m = &pending[at..at + total];
                let kind = m[2];
                let definition = matches!(
                    kind,
                    msg::FLAG_BITS
                        | msg::FORMAT
                        | msg::INFO
                        | msg::INFO_MULTIPLE
                        | msg::PARAMETER
                        | msg::PARAMETER_DEFAULT
                );
                if self.in_definitions && definition {
                    self.preamble.extend_from_slice(m);
                } else {
                    self.in_definitions = false;
                    let body = self.written > self.preamble.len() as u64;
                    if body && self.written + total as u64 > self.max_bytes {
                        self.next_part()?;
                    }
                    if kind == msg::ADD_LOGGED {
                        self.preamble.extend_from_slice(m);
                    }
                }
                self.emit(m)?;
                at += total;
            }
            Ok(())
        })();
        self.pending = pending;
        self.pending.drain(..at);
        r
    }
}

impl Write for UlogParts {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.pending.extend_from_slice(buf);
        self.drain_messages()?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test
    use super::*;
    use helicon_ulog::messages::Failsafe;
    use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, LogRecord};

    fn dir(tag: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("helicon-log-parts-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn part_names_follow_the_first() {
        let f = Path::new("/x/flight.ulg");
        assert_eq!(part_path(f, 1), PathBuf::from("/x/flight.ulg"));
        assert_eq!(part_path(f, 2), PathBuf::from("/x/flight-0002.ulg"));
        assert_eq!(
            part_path(Path::new("/x/log.csv"), 12),
            PathBuf::from("/x/log-0012.csv")
        );
    }

    /// `n` failsafe records 10 ms apart into a log through `sink`.
    fn fill<W: Write>(log: &mut FlightLog<W>, n: u64) {
        for k in 0..n {
            let rec = LogRecord::Failsafe(Failsafe {
                timestamp: 1_000 + k * 10_000,
                ..Failsafe::default()
            });
            log.write(&rec).unwrap();
        }
    }

    /// The timestamps of the `failsafe` records of one file, read alone.
    fn failsafe_stamps(p: &Path) -> Vec<u64> {
        use helicon_ulog::reader::{FileReader, Message};
        let mut r = FileReader::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let mut id = None;
        let mut formats = false;
        let mut out = Vec::new();
        while let Some(m) = r.next_message().unwrap() {
            match m {
                Message::Format(_) => formats = true,
                Message::AddLogged { msg_id, name, .. } if name == "failsafe" => {
                    id = Some(msg_id);
                }
                Message::Data { msg_id, payload } => {
                    // subscribed in this file, its formats in this file
                    assert!(
                        formats && id.is_some(),
                        "{}: data before its definitions",
                        p.display()
                    );
                    if Some(msg_id) == id {
                        out.push(u64::from_le_bytes(payload[..8].try_into().unwrap()));
                    }
                }
                _ => {}
            }
        }
        out
    }

    #[test]
    fn each_part_is_a_whole_log_and_the_data_goes_on() {
        let d = dir("parts");
        let first = d.join("flight.ulg");
        let info = LogInfo::default();
        // a bound that takes several parts
        let max = 20_000u64;
        let mut log = FlightLog::new(
            UlogParts::create(&first, max).unwrap(),
            &info,
            FlushPolicy::default(),
        )
        .unwrap();
        fill(&mut log, 5_000);
        let sink = log.finish().unwrap();
        let parts = sink.parts();
        drop(sink);
        assert!(parts >= 3, "{parts} parts");
        let mut stamps = Vec::new();
        for n in 1..=parts {
            let p = part_path(&first, n);
            let len = std::fs::metadata(&p).unwrap().len();
            // the bound, but for the last message that crossed it
            assert!(len <= max, "{}: {len} bytes", p.display());
            let mut got = failsafe_stamps(&p);
            assert!(!got.is_empty(), "{}: no data", p.display());
            stamps.append(&mut got);
        }
        // every record once, in order, across the parts
        let want: Vec<u64> = (0..5_000u64).map(|k| 1_000 + k * 10_000).collect();
        assert_eq!(stamps, want);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn without_a_bound_the_bytes_are_the_writers() {
        let d = dir("whole");
        let info = LogInfo::default();
        let mut plain = FlightLog::new(Vec::new(), &info, FlushPolicy::default()).unwrap();
        fill(&mut plain, 2_000);
        let plain = plain.finish().unwrap();
        let first = d.join("flight.ulg");
        let mut parted = FlightLog::new(
            UlogParts::create(&first, u64::MAX).unwrap(),
            &info,
            FlushPolicy::default(),
        )
        .unwrap();
        fill(&mut parted, 2_000);
        let sink = parted.finish().unwrap();
        assert_eq!(sink.parts(), 1);
        drop(sink);
        assert_eq!(std::fs::read(&first).unwrap(), plain);
        let _ = std::fs::remove_dir_all(&d);
    }
}
