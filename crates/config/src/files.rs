//! Reading user files with bounds: every reader of a file a user names
//! opens it here, so that no input can stall or exhaust a command.
//!
//! - Only regular files are read. A FIFO would block the open (or the first
//!   read) until some other process writes; a character device such as
//!   `/dev/zero` or `/dev/urandom` never ends; a folder cannot be read. Each
//!   is refused before it is opened ([`FileRefusal::NotRegular`]), and the
//!   opened file is checked again (it may have been swapped in between).
//! - What is read is bounded: [`read_text_bounded`] refuses a file longer
//!   than its limit ([`FileRefusal::TooLarge`]) without reading past it, and
//!   [`open_bounded`] gives a streaming reader ([`Bounded`]) that fails with
//!   the same error at the first byte beyond its limit (a file still being
//!   written stays bounded too).
//! - A line-oriented file (a CSV log, readings, rows of numbers) is read
//!   through [`open_lines_bounded`]: bounded as a whole, and each line
//!   (the header row included) bounded too ([`FileRefusal::LineTooLong`]),
//!   so that no reader buffers one endless record.
//!
//! Each refusal is a [`ConfigError::Io`] naming the file, its cause an
//! [`std::io::Error`] carrying a [`FileRefusal`] (found with
//! [`FileRefusal::of`]).

use crate::ConfigError;
use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::Path;

/// The largest configuration or text file read whole (16 MiB): the
/// toolkit's TOML and JSON files are a few kilobytes.
pub const MAX_TEXT_BYTES: u64 = 16 << 20;

/// The largest data file (a CSV log) read (4 GiB: a 400 Hz log of 40
/// columns is about 0.25 GB an hour).
pub const MAX_DATA_BYTES: u64 = 4 << 30;

/// The longest line of a line-oriented file (1 MiB: a CSV header of a
/// thousand columns is some 20 kB).
pub const MAX_LINE_BYTES: u64 = 1 << 20;

/// Why a file was not read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FileRefusal {
    /// Not a regular file: a FIFO, a device, a socket or a folder.
    #[error("not a regular file ({kind}); only regular files are read")]
    NotRegular {
        /// What it is: `a FIFO`, `a character device`, `a folder`, …
        kind: &'static str,
    },
    /// Longer than the reader's limit.
    #[error("longer than {max_bytes} bytes, the most this reader accepts")]
    TooLarge {
        /// The limit (bytes).
        max_bytes: u64,
    },
    /// A line longer than the reader's limit.
    #[error("line {line} is longer than {max_bytes} bytes, the most this reader accepts")]
    LineTooLong {
        /// The line (1-based).
        line: u64,
        /// The limit (bytes, without the line end).
        max_bytes: u64,
    },
}

impl FileRefusal {
    /// The refusal carried by an I/O error made here (`None` for any other
    /// I/O error).
    pub fn of(e: &std::io::Error) -> Option<FileRefusal> {
        e.get_ref()?.downcast_ref::<FileRefusal>().copied()
    }

    /// As an I/O error (kind `InvalidInput` or `FileTooLarge`).
    pub fn into_io(self) -> std::io::Error {
        let kind = match self {
            FileRefusal::NotRegular { .. } => ErrorKind::InvalidInput,
            FileRefusal::TooLarge { .. } | FileRefusal::LineTooLong { .. } => {
                ErrorKind::FileTooLarge
            }
        };
        std::io::Error::new(kind, self)
    }
}

fn kind_of(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() { "a folder" } else { "not a file" }
}

/// The I/O error of `path` not being a regular file, if it is not one
/// (`stat` only: nothing is opened, so a FIFO cannot block).
fn refuse_irregular(meta: &std::fs::Metadata) -> std::io::Result<()> {
    if meta.is_file() {
        Ok(())
    } else {
        Err(FileRefusal::NotRegular {
            kind: kind_of(meta.file_type()),
        }
        .into_io())
    }
}

/// Open `path` for reading if it is a regular file (symbolic links
/// followed). The error names the file; see the module documentation.
pub fn open_regular(path: &Path) -> Result<File, ConfigError> {
    let io = |source| ConfigError::Io {
        file: path.display().to_string(),
        action: "read",
        source,
    };
    refuse_irregular(&std::fs::metadata(path).map_err(io)?).map_err(io)?;
    let f = File::open(path).map_err(io)?;
    refuse_irregular(&f.metadata().map_err(io)?).map_err(io)?;
    Ok(f)
}

/// A reader that fails ([`FileRefusal::TooLarge`]) rather than give more
/// than `max_bytes` bytes: the input of a streaming reader of user files.
#[derive(Debug)]
pub struct Bounded<R> {
    inner: R,
    left: u64,
    max_bytes: u64,
}

impl<R: Read> Bounded<R> {
    /// `inner`, of which at most `max_bytes` bytes will be read.
    pub fn new(inner: R, max_bytes: u64) -> Self {
        Bounded {
            inner,
            left: max_bytes,
            max_bytes,
        }
    }

    /// The limit (bytes).
    pub fn max_bytes(&self) -> u64 {
        self.max_bytes
    }
}

impl<R: Read> Read for Bounded<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.left == 0 {
            // at the limit: the input may end here, else it is too long
            let mut one = [0u8; 1];
            return match self.inner.read(&mut one)? {
                0 => Ok(0),
                _ => Err(FileRefusal::TooLarge {
                    max_bytes: self.max_bytes,
                }
                .into_io()),
            };
        }
        let want = buf
            .len()
            .min(usize::try_from(self.left).unwrap_or(usize::MAX));
        let n = self.inner.read(&mut buf[..want])?;
        self.left -= n as u64;
        Ok(n)
    }
}

/// A reader that fails ([`FileRefusal::LineTooLong`]) at the first line
/// longer than `max_line_bytes` bytes (`\n` ends a line).
#[derive(Debug)]
pub struct LineBounded<R> {
    inner: R,
    max_line_bytes: u64,
    /// Bytes since the last line end.
    run: u64,
    /// Lines ended so far.
    lines: u64,
}

impl<R: Read> LineBounded<R> {
    /// `inner`, whose lines may be at most `max_line_bytes` long.
    pub fn new(inner: R, max_line_bytes: u64) -> Self {
        LineBounded {
            inner,
            max_line_bytes,
            run: 0,
            lines: 0,
        }
    }
}

impl<R: Read> Read for LineBounded<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        for &b in &buf[..n] {
            if b == b'\n' {
                self.lines += 1;
                self.run = 0;
            } else {
                self.run += 1;
                // a `\r` before the `\n` is part of the line end
                if self.run > self.max_line_bytes.saturating_add(u64::from(b == b'\r')) {
                    return Err(FileRefusal::LineTooLong {
                        line: self.lines + 1,
                        max_bytes: self.max_line_bytes,
                    }
                    .into_io());
                }
            }
        }
        Ok(n)
    }
}

/// Open the regular file `path` for a line-oriented reader (CSV): at most
/// `max_bytes` bytes in all ([`MAX_DATA_BYTES`] for a log), each line at
/// most `max_line_bytes` ([`MAX_LINE_BYTES`]).
pub fn open_lines_bounded(
    path: &Path,
    max_bytes: u64,
    max_line_bytes: u64,
) -> Result<LineBounded<Bounded<File>>, ConfigError> {
    Ok(LineBounded::new(
        open_bounded(path, max_bytes)?,
        max_line_bytes,
    ))
}

/// Open the regular file `path` for a streaming reader that reads at most
/// `max_bytes` bytes of it (`u64::MAX`: any regular file, as a flight log).
pub fn open_bounded(path: &Path, max_bytes: u64) -> Result<Bounded<File>, ConfigError> {
    Ok(Bounded::new(open_regular(path)?, max_bytes))
}

/// The text of the regular file `path`, refused when longer than
/// `max_bytes` (nothing beyond the limit is read) or not UTF-8.
pub fn read_text_bounded(path: &Path, max_bytes: u64) -> Result<String, ConfigError> {
    let io = |source| ConfigError::Io {
        file: path.display().to_string(),
        action: "read",
        source,
    };
    let f = open_regular(path)?;
    // the length a regular file says it has sizes the buffer (within the
    // limit); a file that grows is still stopped at the limit
    let hint = f.metadata().map_or(0, |m| m.len()).min(max_bytes);
    let mut text = String::with_capacity(usize::try_from(hint).unwrap_or(0));
    Bounded::new(f, max_bytes)
        .read_to_string(&mut text)
        .map_err(io)?;
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("helicon_config_{}_{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_file_at_the_limit_is_read_one_byte_more_is_refused() {
        let d = scratch("limit");
        let p = d.join("a.toml");
        std::fs::write(&p, "x = 1\n").unwrap();
        assert_eq!(read_text_bounded(&p, 6).unwrap(), "x = 1\n");
        let e = read_text_bounded(&p, 5).unwrap_err();
        let ConfigError::Io { file, source, .. } = &e else {
            panic!("{e:?}")
        };
        assert_eq!(file, &p.display().to_string());
        assert_eq!(
            FileRefusal::of(source),
            Some(FileRefusal::TooLarge { max_bytes: 5 })
        );
        assert!(e.to_string().ends_with("a.toml: cannot read"), "{e}");
        let mut s = String::new();
        let mut b = open_bounded(&p, 6).unwrap();
        assert_eq!(b.read_to_string(&mut s).unwrap(), 6);
        let mut b = open_bounded(&p, 2).unwrap();
        let e = b.read_to_string(&mut String::new()).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::FileTooLarge);
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn a_line_beyond_its_limit_is_refused_naming_it() {
        let d = scratch("lines");
        let p = d.join("a.csv");
        std::fs::write(&p, "t_s,x\r\n0,123\n1,2\n").unwrap();
        let mut s = String::new();
        open_lines_bounded(&p, 100, 5)
            .unwrap()
            .read_to_string(&mut s)
            .unwrap();
        assert_eq!(s, "t_s,x\r\n0,123\n1,2\n");
        let e = open_lines_bounded(&p, 100, 4)
            .unwrap()
            .read_to_string(&mut String::new())
            .unwrap_err();
        assert_eq!(
            FileRefusal::of(&e),
            Some(FileRefusal::LineTooLong {
                line: 1,
                max_bytes: 4
            })
        );
        std::fs::write(&p, "ab\ncd\nefgh").unwrap();
        let e = open_lines_bounded(&p, 100, 3)
            .unwrap()
            .read_to_string(&mut String::new())
            .unwrap_err();
        assert_eq!(
            FileRefusal::of(&e),
            Some(FileRefusal::LineTooLong {
                line: 3,
                max_bytes: 3
            })
        );
        assert!(
            e.to_string().contains("line 3 is longer than 3 bytes"),
            "{e}"
        );
        std::fs::remove_dir_all(d).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn devices_folders_and_fifos_are_refused_without_reading() {
        let d = scratch("kinds");
        let refusal = |p: &Path| match read_text_bounded(p, MAX_TEXT_BYTES) {
            Err(ConfigError::Io { source, .. }) => FileRefusal::of(&source),
            other => panic!("{other:?}"),
        };
        assert_eq!(
            refusal(Path::new("/dev/zero")),
            Some(FileRefusal::NotRegular {
                kind: "a character device"
            })
        );
        assert_eq!(
            refusal(&d),
            Some(FileRefusal::NotRegular { kind: "a folder" })
        );
        // a FIFO nobody writes: an open would block forever
        let fifo = d.join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            assert_eq!(
                refusal(&fifo),
                Some(FileRefusal::NotRegular { kind: "a FIFO" })
            );
            assert!(open_bounded(&fifo, 10).is_err());
        }
        // a missing file keeps the system's error
        match read_text_bounded(&d.join("missing"), 10) {
            Err(ConfigError::Io { source, .. }) => {
                assert_eq!(source.kind(), ErrorKind::NotFound);
                assert_eq!(FileRefusal::of(&source), None);
            }
            other => panic!("{other:?}"),
        }
        std::fs::remove_dir_all(d).unwrap();
    }
}
