//! Serial transport: a serial port opened with the `serialport` crate
//! (built without libudev), a pseudo-terminal pair for software-in-the-loop
//! runs, and the staleness watch of a sensor.
//!
//! Writing never waits for the transmission: [`SerialLink::write_all`]
//! queues the bytes in the kernel's output buffer (a non-blocking handle
//! of the device) and returns. A buffer that cannot take a frame (the
//! line slower than what is written, or nobody reading a pseudo-terminal)
//! is [`TransportError::Full`]: the frame is dropped, never waited for
//! beyond [`PARTIAL_WRITE_WAIT`].

use crate::error::{EncodeError, TransportError, check_range};
use rustix::fd::OwnedFd;
use std::fs::File;
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The longest a write waits: only for the rest of a frame the kernel took
/// in part (a frame is never left half written when its rest fits soon).
pub const PARTIAL_WRITE_WAIT: Duration = Duration::from_millis(1);

/// The kernel's output buffer is taken as full when it is not writable:
/// on Linux a terminal is writable when fewer than 256 bytes wait to be sent
/// and there is room.
fn writable(fd: &OwnedFd, timeout: Duration) -> Result<bool, std::io::Error> {
    use rustix::event::PollFlags;
    match poll_one(fd, PollFlags::OUT, timeout)? {
        None => Ok(false),
        Some(r) if r.intersects(PollFlags::ERR | PollFlags::HUP | PollFlags::NVAL) => Err(
            std::io::Error::new(ErrorKind::BrokenPipe, "the device hung up"),
        ),
        Some(r) => Ok(r.contains(PollFlags::OUT)),
    }
}

/// Whether the line has bytes to read, waiting at most `timeout`: as the
/// `serialport` crate's own read decides (a hang-up is
/// [`ErrorKind::BrokenPipe`], any other error event an error), without its
/// allocations: it reports a wait that timed out as an [`std::io::Error`]
/// carrying a formatted message, three allocations for each look at an
/// idle line.
fn readable(fd: &OwnedFd, timeout: Duration) -> Result<bool, std::io::Error> {
    use rustix::event::PollFlags;
    match poll_one(fd, PollFlags::IN, timeout)? {
        None => Ok(false),
        Some(r) if r.intersects(PollFlags::HUP | PollFlags::NVAL) => Err(std::io::Error::new(
            ErrorKind::BrokenPipe,
            "the device hung up",
        )),
        Some(r) if r == PollFlags::IN => Ok(true),
        Some(_) => Err(std::io::Error::other("the line reported an error")),
    }
}

/// One `poll` of `fd` for `events`, waiting at most `timeout`: the events
/// that came, `None` when none did in time (or a signal interrupted).
fn poll_one(
    fd: &OwnedFd,
    events: rustix::event::PollFlags,
    timeout: Duration,
) -> Result<Option<rustix::event::PollFlags>, std::io::Error> {
    use rustix::event::{PollFd, Timespec, poll};
    let ts = Timespec {
        tv_sec: i64::try_from(timeout.as_secs()).unwrap_or(i64::MAX),
        tv_nsec: i64::from(timeout.subsec_nanos()),
    };
    let mut fds = [PollFd::new(fd, events)];
    match poll(&mut fds, Some(&ts)) {
        Ok(0) | Err(rustix::io::Errno::INTR) => Ok(None),
        Ok(_) => Ok(Some(fds[0].revents())),
        Err(e) => Err(e.into()),
    }
}

/// An open serial port with a read timeout; writes queue in the kernel's
/// buffer without waiting for the transmission.
pub struct SerialLink {
    /// The port as the `serialport` crate configured it (8N1, the baud
    /// rate, exclusive): kept open for its settings and its lock.
    port: Box<dyn serialport::SerialPort>,
    /// A non-blocking handle of the device (its own open file description)
    /// that reads and writes: a read waits in `poll` up to `read_timeout`,
    /// then takes what the line holds; a write never waits.
    fd: OwnedFd,
    /// How long [`SerialLink::read_chunk`] waits at most.
    read_timeout: Duration,
    path: PathBuf,
    baud: u32,
}

impl core::fmt::Debug for SerialLink {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SerialLink")
            .field("path", &self.path)
            .finish()
    }
}

impl SerialLink {
    /// Opens `path` at `baud` (8N1, no flow control); reads wait at most
    /// `read_timeout`; writes do not wait ([`SerialLink::write_all`]).
    pub fn open(path: &Path, baud: u32, read_timeout: Duration) -> Result<Self, TransportError> {
        use rustix::fs::{Mode, OFlags};
        // the handle first: the port's exclusive mode refuses later opens
        let fd = rustix::fs::open(
            path,
            OFlags::RDWR | OFlags::NOCTTY | OFlags::NONBLOCK | OFlags::CLOEXEC,
            Mode::empty(),
        )
        .map_err(|e| TransportError::Io {
            what: format!("opening {}", path.display()),
            source: e.into(),
        })?;
        let name = path.to_string_lossy();
        let port = serialport::new(name, baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(read_timeout)
            .open()
            .map_err(|source| TransportError::Serial {
                path: path.to_path_buf(),
                source,
            })?;
        Ok(Self {
            port,
            fd,
            read_timeout,
            path: path.to_path_buf(),
            baud,
        })
    }

    /// A second handle on the same port (e.g. a reader thread and a writer).
    pub fn try_clone(&self) -> Result<Self, TransportError> {
        let port = self
            .port
            .try_clone()
            .map_err(|source| TransportError::Serial {
                path: self.path.clone(),
                source,
            })?;
        let fd = self.fd.try_clone().map_err(|source| TransportError::Io {
            what: format!("cloning {}", self.path.display()),
            source,
        })?;
        Ok(Self {
            port,
            fd,
            read_timeout: self.read_timeout,
            path: self.path.clone(),
            baud: self.baud,
        })
    }

    /// The baud rate the port was opened at.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// The device path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads what is available into `buf`, waiting at most the read timeout;
    /// `Ok(0)` when nothing arrived in time (an empty `buf` reads nothing).
    ///
    /// The line is read only once it is readable (one `poll`, then one
    /// `read`; a look at an idle line is the `poll` alone and allocates
    /// nothing), so a read of nothing from a readable line is its end: an
    /// error ([`ErrorKind::UnexpectedEof`]), the device lost. (A
    /// pseudo-terminal whose master closed, or a terminal hung up, polls as
    /// hung up: an error before any read.)
    pub fn read_chunk(&mut self, buf: &mut [u8]) -> Result<usize, TransportError> {
        let io = |source: std::io::Error| TransportError::Io {
            what: format!("reading {}", self.path.display()),
            source,
        };
        if buf.is_empty() || !readable(&self.fd, self.read_timeout).map_err(io)? {
            return Ok(0);
        }
        match rustix::io::read(&self.fd, &mut *buf) {
            Ok(0) => Err(io(std::io::Error::new(
                ErrorKind::UnexpectedEof,
                "end of file: the line ended",
            ))),
            Ok(n) => Ok(n),
            Err(rustix::io::Errno::AGAIN | rustix::io::Errno::INTR) => Ok(0),
            Err(e) => Err(io(e.into())),
        }
    }

    /// Reads what is available into `buf`, waiting at most `timeout`
    /// (which becomes the link's read timeout); `Ok(0)` when nothing
    /// arrived in time. Setting the timeout is no system call.
    pub fn read_timeout(
        &mut self,
        buf: &mut [u8],
        timeout: Duration,
    ) -> Result<usize, TransportError> {
        self.read_timeout = timeout;
        self.read_chunk(buf)
    }

    /// Queues all of `bytes` (one frame) in the kernel's output buffer and
    /// returns without waiting for their transmission (no `tcdrain`: a
    /// 16-byte servo frame takes 1.4 ms on the line at 115200 baud).
    ///
    /// A buffer that cannot take them is [`TransportError::Full`]: when it
    /// is not writable nothing is written (the frame is dropped whole);
    /// when the kernel takes a part, the rest is waited for at most
    /// [`PARTIAL_WRITE_WAIT`], then dropped (the receiver's decoder skips
    /// the truncated frame by its checksum). Never blocks longer.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        match self.try_write(bytes)? {
            Written::All => Ok(()),
            Written::Dropped { queued } => Err(TransportError::Full {
                path: self.path.clone(),
                queued,
                len: bytes.len(),
            }),
        }
    }

    /// [`SerialLink::write_all`] for a hot path: a frame the buffer cannot
    /// take is [`Written::Dropped`], not an error, and nothing is
    /// allocated (only an I/O error, naming the device, allocates).
    pub fn try_write(&mut self, bytes: &[u8]) -> Result<Written, TransportError> {
        let io = |source: std::io::Error| TransportError::Io {
            what: format!("writing {}", self.path.display()),
            source,
        };
        if bytes.is_empty() {
            return Ok(Written::All);
        }
        if !writable(&self.fd, Duration::ZERO).map_err(io)? {
            return Ok(Written::Dropped { queued: 0 });
        }
        let mut done = 0;
        let mut waited = false;
        while done < bytes.len() {
            match rustix::io::write(&self.fd, &bytes[done..]) {
                Ok(n) => done += n,
                Err(rustix::io::Errno::INTR) => {}
                Err(rustix::io::Errno::AGAIN) => {
                    // a part taken: wait once, boundedly, for the rest
                    if done == 0 || waited {
                        return Ok(Written::Dropped { queued: done });
                    }
                    waited = true;
                    if !writable(&self.fd, PARTIAL_WRITE_WAIT).map_err(io)? {
                        return Ok(Written::Dropped { queued: done });
                    }
                }
                Err(e) => return Err(io(e.into())),
            }
        }
        Ok(Written::All)
    }
}

/// What [`SerialLink::try_write`] did with a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Written {
    /// Queued whole in the kernel's output buffer.
    All,
    /// Dropped: the buffer could not take it; `queued` of its bytes were
    /// written (a truncated frame the receiver's checksum rejects).
    Dropped {
        /// Bytes of the frame the kernel took.
        queued: usize,
    },
}

/// A pseudo-terminal pair for software-in-the-loop: the simulator plays the
/// device on the master side, the on-board software opens
/// [`PtyPair::slave_path`] as if it were the device's serial port. The
/// line is in raw mode (no echo, no line editing, 8-bit clean). The pair
/// keeps a handle on the slave side open so that the master never reads
/// end-of-file or an error while the on-board side reopens the port.
#[derive(Debug)]
pub struct PtyPair {
    master: File,
    slave_path: PathBuf,
    _slave_hold: OwnedFd,
}

fn pty_err(step: &'static str) -> impl FnOnce(rustix::io::Errno) -> TransportError {
    move |e| TransportError::Pty {
        step,
        source: e.into(),
    }
}

impl PtyPair {
    /// Creates the pair.
    pub fn open() -> Result<Self, TransportError> {
        use rustix::fs::{Mode, OFlags};
        use rustix::pty::{OpenptFlags, grantpt, openpt, ptsname, unlockpt};
        use rustix::termios::{OptionalActions, tcgetattr, tcsetattr};
        let master = openpt(OpenptFlags::RDWR | OpenptFlags::NOCTTY | OpenptFlags::CLOEXEC)
            .map_err(pty_err("posix_openpt"))?;
        grantpt(&master).map_err(pty_err("grantpt"))?;
        unlockpt(&master).map_err(pty_err("unlockpt"))?;
        let name = ptsname(&master, Vec::new()).map_err(pty_err("ptsname"))?;
        let slave_path = PathBuf::from(name.to_string_lossy().into_owned());
        let slave = rustix::fs::open(
            &slave_path,
            OFlags::RDWR | OFlags::NOCTTY | OFlags::CLOEXEC,
            Mode::empty(),
        )
        .map_err(pty_err("opening the slave"))?;
        let mut t = tcgetattr(&slave).map_err(pty_err("tcgetattr"))?;
        t.make_raw();
        tcsetattr(&slave, OptionalActions::Now, &t).map_err(pty_err("tcsetattr"))?;
        Ok(Self {
            master: File::from(master),
            slave_path,
            _slave_hold: slave,
        })
    }

    /// The path of the slave side (e.g. `/dev/pts/7`).
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }

    /// The master side, for reading and writing.
    pub fn master(&mut self) -> &mut File {
        &mut self.master
    }

    /// A second handle on the master side (e.g. for a reader thread).
    pub fn try_clone_master(&self) -> Result<File, TransportError> {
        self.master
            .try_clone()
            .map_err(|source| TransportError::Io {
                what: "cloning the pseudo-terminal master".into(),
                source,
            })
    }

    /// Reads what is available on the master side, waiting at most
    /// `timeout`; `Ok(0)` when nothing arrived in time.
    pub fn read_timeout(
        &mut self,
        buf: &mut [u8],
        timeout: Duration,
    ) -> Result<usize, TransportError> {
        read_with_timeout(&mut self.master, buf, timeout)
    }

    /// Waits at most `timeout` until the slave side's input holds bytes;
    /// whether it does. The kernel moves what the master wrote to the
    /// slave on a worker thread, after the write has returned: a lock-step
    /// simulator that writes one device's bytes, then the device that
    /// paces the reader, waits here in between so that the reader finds
    /// both. Nothing is read (the bytes stay for the slave's reader).
    pub fn wait_delivered(&self, timeout: Duration) -> Result<bool, TransportError> {
        use rustix::event::{PollFd, PollFlags, Timespec, poll};
        let ts = Timespec {
            tv_sec: i64::try_from(timeout.as_secs()).unwrap_or(i64::MAX),
            tv_nsec: i64::from(timeout.subsec_nanos()),
        };
        let mut fds = [PollFd::new(&self._slave_hold, PollFlags::IN)];
        match poll(&mut fds, Some(&ts)) {
            Ok(n) => Ok(n > 0),
            Err(rustix::io::Errno::INTR) => Ok(false),
            Err(e) => Err(TransportError::Io {
                what: "waiting for the pseudo-terminal's slave side".into(),
                source: e.into(),
            }),
        }
    }

    /// Writes all of `bytes` to the master side.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.master
            .write_all(bytes)
            .map_err(|source| TransportError::Io {
                what: format!(
                    "writing the pseudo-terminal of {}",
                    self.slave_path.display()
                ),
                source,
            })
    }
}

/// Waits at most `timeout` for `file` to be readable, then reads; `Ok(0)`
/// on timeout.
pub fn read_with_timeout(
    file: &mut File,
    buf: &mut [u8],
    timeout: Duration,
) -> Result<usize, TransportError> {
    use rustix::event::{PollFd, PollFlags, Timespec, poll};
    let io = |source: std::io::Error| TransportError::Io {
        what: "reading a pseudo-terminal".into(),
        source,
    };
    let ts = Timespec {
        tv_sec: i64::try_from(timeout.as_secs()).unwrap_or(i64::MAX),
        tv_nsec: i64::from(timeout.subsec_nanos()),
    };
    let mut fds = [PollFd::new(&*file, PollFlags::IN)];
    match poll(&mut fds, Some(&ts)) {
        Ok(0) => return Ok(0),
        Ok(_) => {}
        Err(rustix::io::Errno::INTR) => return Ok(0),
        Err(e) => return Err(io(e.into())),
    }
    match file.read(buf) {
        Ok(n) => Ok(n),
        Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => Ok(0),
        Err(e) => Err(io(e)),
    }
}

/// Last-seen time of one sensor and its staleness threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaleDetector {
    threshold_s: f64,
    last_seen_s: Option<f64>,
}

impl StaleDetector {
    /// A detector that calls the sensor stale when its last message is older
    /// than `threshold_s` (finite, > 0; e.g. three sample periods).
    pub fn new(threshold_s: f64) -> Result<Self, EncodeError> {
        let t = check_range("stale threshold_s", threshold_s, f64::MIN_POSITIVE, 1e6)?;
        Ok(Self {
            threshold_s: t,
            last_seen_s: None,
        })
    }

    /// Records a message at `t_s` (a non-finite time is ignored).
    pub fn seen(&mut self, t_s: f64) {
        if t_s.is_finite() {
            self.last_seen_s = Some(t_s);
        }
    }

    /// Seconds since the last message, `None` if none yet. A clock that went
    /// backwards gives 0.
    pub fn age_s(&self, now_s: f64) -> Option<f64> {
        self.last_seen_s.map(|t| (now_s - t).max(0.0))
    }

    /// True when no message was ever seen, or the last one is older than
    /// the threshold, or `now_s` is not finite.
    pub fn is_stale(&self, now_s: f64) -> bool {
        if !now_s.is_finite() {
            return true;
        }
        self.age_s(now_s).is_none_or(|a| a > self.threshold_s)
    }

    /// The threshold (s).
    pub fn threshold_s(&self) -> f64 {
        self.threshold_s
    }
}
