//! The device drivers of the on-board program: serial ports read through
//! `helicon-devices`' decoders into the runtime's [`SensorPort`],
//! [`RcPort`] and [`ServoPort`].
//!
//! - IMU + magnetometer: VectorNav VN-100 binary (Common group: time since
//!   startup, angular rate, acceleration, MagPres); the IMU's own time
//!   stamps the frame; a message whose time did not advance is not a fresh
//!   sample (a stuck sensor).
//! - GPS: u-blox UBX NAV-PVT, converted to the local NED frame of the
//!   configured home. The fix's epoch on the on-board clock is its GPS time
//!   of week less the offset measured at the first fix, less the receiver's
//!   nominal latency (`sensors.gps.latency_s`).
//! - Avionics: the project's framed servo/RC protocol. The receiver's
//!   sticks are the first four channels, 1500 µs ± 1000 µs per unit of
//!   servo command; the pilot's switch is the frame's `autonomous` flag;
//!   the arm switch is channel 5 above 1500 µs; the frame's failsafe flag
//!   (the receiver lost the transmitter) is passed on to the supervisor.
//!
//! The devices are `helicon-devices`' [`SerialLink`]s (raw 8N1 at the baud
//! rate); the avionics port's link is cloned for the receiver and the
//! servos (a reader and a writer thread).

use crate::runtime::{Arrival, Next, PortError, RcPort, SensorPort, ServoPort};
use crate::safety::RcInput;
use helicon_core::SensorFrame;
use helicon_core::state::Input;
use helicon_devices::avionics::{AvionicsMessage, ServoCommand};
use helicon_devices::{AvionicsDecoder, LocalNed, UbxDecoder, VnBinaryDecoder};
use helicon_devices::{SerialLink, TransportError, Written};
use std::path::Path;
use std::time::Duration;

/// The baud rates a device can be opened at.
pub const BAUDS: [u32; 9] = [
    9600, 19200, 38400, 57600, 115_200, 230_400, 460_800, 921_600, 1_000_000,
];

/// Open the serial device `path` at `baud` (one of [`BAUDS`]) as the
/// program opens `/dev/ttyS*` (a pty slave in SITL).
pub fn open_port(path: &Path, baud: u32) -> Result<SerialLink, PortError> {
    if !BAUDS.contains(&baud) {
        return Err(PortError {
            port: path.display().to_string(),
            message: format!("baud rate {baud} not one of {BAUDS:?}"),
        });
    }
    SerialLink::open(path, baud, Duration::ZERO).map_err(|e| PortError {
        port: path.display().to_string(),
        message: format!("cannot open: {e}"),
    })
}

/// A second handle on the device of `link` (a reader and a writer thread).
pub fn clone_port(link: &SerialLink) -> Result<SerialLink, PortError> {
    link.try_clone()
        .map_err(|e| port_error(link, "cannot clone", &e))
}

fn port_error(link: &SerialLink, what: &str, e: &TransportError) -> PortError {
    PortError {
        port: link.path().display().to_string(),
        message: format!("{what}: {e}"),
    }
}

/// Read what `link` has, waiting at most `timeout`: `Ok(0)` on timeout; an
/// error once the device is gone (hung up, EIO).
fn read_port(link: &mut SerialLink, buf: &mut [u8], timeout: Duration) -> Result<usize, PortError> {
    link.read_timeout(buf, timeout)
        .map_err(|e| port_error(link, "read", &e))
}

/// The IMU (with magnetometer) and GPS read by one sensor-server thread.
pub struct DeviceSensors {
    imu: SerialLink,
    gps: SerialLink,
    vn: VnBinaryDecoder,
    ubx: UbxDecoder,
    home: LocalNed,
    gps_latency_s: f64,
    tow_offset_s: Option<f64>,
    last_imu_ns: Option<u64>,
    pending_gps: Option<helicon_devices::NavPvt>,
    pending_mag: Option<nalgebra::Vector3<f64>>,
    receiver: Option<DeviceRc>,
    pending_rc: Option<RcInput>,
    buf: [u8; 512],
}

impl DeviceSensors {
    /// The sensors on their ports; GPS positions in the NED frame of `home`.
    pub fn new(imu: SerialLink, gps: SerialLink, home: LocalNed, gps_latency_s: f64) -> Self {
        DeviceSensors {
            imu,
            gps,
            vn: VnBinaryDecoder::new(),
            ubx: UbxDecoder::new(),
            home,
            gps_latency_s,
            tow_offset_s: None,
            last_imu_ns: None,
            pending_gps: None,
            pending_mag: None,
            receiver: None,
            pending_rc: None,
            buf: [0; 512],
        }
    }

    /// Also read the receiver (a handle of the avionics port), drained
    /// before each IMU frame is assembled, as the GPS is: lock-step SITL,
    /// where the receiver's frames then reach the control step they
    /// precede. On board the receiver has its own thread (manual must work
    /// without the IMU).
    #[must_use]
    pub fn with_receiver(mut self, rc: DeviceRc) -> Self {
        self.receiver = Some(rc);
        self
    }

    fn drain_rc(&mut self) -> Result<(), PortError> {
        if let Some(rc) = self.receiver.as_mut() {
            while let Next::Item(r) = rc.next(Duration::ZERO)? {
                self.pending_rc = Some(r);
            }
        }
        Ok(())
    }

    /// Bytes rejected by the decoders so far (IMU, GPS).
    pub fn rejected(&self) -> (u64, u64) {
        (
            self.vn.stats().discarded_bytes,
            self.ubx.stats().discarded_bytes,
        )
    }

    /// Read whatever the GPS port holds now (no waiting): the receiver's
    /// bytes written before the IMU message are decoded before its frame
    /// is assembled.
    fn drain_gps(&mut self) -> Result<(), PortError> {
        loop {
            let n = read_port(&mut self.gps, &mut self.buf, Duration::ZERO)?;
            if n == 0 {
                return Ok(());
            }
            let mut last = None;
            self.ubx.push_with(&self.buf[..n], |m| last = Some(m));
            if last.is_some() {
                self.pending_gps = last;
            }
        }
    }

    fn assemble(&mut self, m: &helicon_devices::VnCommon) -> Option<Arrival> {
        let arrived_ns = crate::realtime::monotonic_ns();
        if let Some(mag) = m.mag_body_gauss() {
            self.pending_mag = Some(mag);
        }
        let (Some(ns), Some(imu)) = (m.time_startup_ns, m.imu_sample()) else {
            return None;
        };
        if self.last_imu_ns.is_some_and(|last| ns <= last) {
            // the IMU's time did not advance: not a fresh sample
            return Some(Arrival {
                frame: None,
                arrived_ns,
                rc: self.pending_rc.take(),
            });
        }
        self.last_imu_ns = Some(ns);
        let t_s = ns as f64 * 1e-9;
        let gps = self.pending_gps.take().map(|pvt| {
            let tow_s = f64::from(pvt.itow_ms) * 1e-3;
            let offset = *self.tow_offset_s.get_or_insert(tow_s - t_s);
            pvt.to_gps_fix(&self.home, tow_s - offset - self.gps_latency_s)
        });
        Some(Arrival {
            frame: Some(SensorFrame {
                t_s,
                imu,
                mag_body: self.pending_mag.take(),
                gps,
            }),
            arrived_ns,
            rc: self.pending_rc.take(),
        })
    }
}

impl SensorPort for DeviceSensors {
    fn next(&mut self, timeout: Duration) -> Result<Next<Arrival>, PortError> {
        let n = read_port(&mut self.imu, &mut self.buf, timeout)?;
        if n == 0 {
            // the GPS keeps being read while the IMU is silent
            self.drain_gps()?;
            return Ok(Next::Timeout);
        }
        // the newest complete IMU message of the read (a reader that fell
        // behind keeps the newest sample)
        let mut newest = None;
        let buf = self.buf;
        self.vn.push_with(&buf[..n], |m| newest = Some(m));
        let Some(m) = newest else {
            return Ok(Next::Timeout);
        };
        self.drain_gps()?;
        self.drain_rc()?;
        Ok(self.assemble(&m).map_or(Next::Timeout, Next::Item))
    }
}

/// The stick mapping of the receiver: servo command ↔ pulse width.
pub fn stick_us(u: f64) -> u16 {
    (1500.0 + 1000.0 * u).clamp(800.0, 2200.0).round() as u16
}

/// The servo command of a stick's pulse width.
pub fn stick_command(us: u16) -> f64 {
    (f64::from(us) - 1500.0) / 1000.0
}

/// The receiver side of the avionics port.
pub struct DeviceRc {
    port: SerialLink,
    decoder: AvionicsDecoder,
    buf: [u8; 256],
}

impl DeviceRc {
    /// The receiver on (a handle of) the avionics port.
    pub fn new(port: SerialLink) -> Self {
        DeviceRc {
            port,
            decoder: AvionicsDecoder::new(),
            buf: [0; 256],
        }
    }
}

impl RcPort for DeviceRc {
    fn next(&mut self, timeout: Duration) -> Result<Next<RcInput>, PortError> {
        let n = read_port(&mut self.port, &mut self.buf, timeout)?;
        let mut last = None;
        self.decoder.push_with(&self.buf[..n], |m| {
            if let AvionicsMessage::Rc(rc) = m {
                last = Some(rc);
            }
        });
        Ok(match last {
            Some(rc) => Next::Item(RcInput {
                servo: Input::from_fn(|i, _| stick_command(rc.channels_us[i])),
                manual: !rc.autonomous,
                armed: rc.channels_us[4] > 1500,
                failsafe: rc.failsafe,
            }),
            None => Next::Timeout,
        })
    }
}

/// The servo side of the avionics port. A frame the port's output buffer
/// cannot take (the line slower than the frames, the board not reading) is
/// dropped and counted, never waited for: the control task is not held up
/// by the line ([`SerialLink::write_all`]).
pub struct DeviceServos {
    port: SerialLink,
    seq: u8,
    dropped: u64,
}

impl DeviceServos {
    /// The servos on (a handle of) the avionics port.
    pub fn new(port: SerialLink) -> Self {
        DeviceServos {
            port,
            seq: 0,
            dropped: 0,
        }
    }
}

impl ServoPort for DeviceServos {
    fn send(&mut self, u: &Input) -> Result<(), PortError> {
        let cmd = ServoCommand::from_inputs(self.seq, true, u).map_err(|e| PortError {
            port: "servo command".into(),
            message: e.to_string(),
        })?;
        self.seq = self.seq.wrapping_add(1);
        // try_write: a dropped frame allocates nothing (a hot path)
        match self.port.try_write(cmd.encode().as_bytes()) {
            Ok(Written::All) => Ok(()),
            Ok(Written::Dropped { .. }) => {
                self.dropped += 1;
                Ok(())
            }
            Err(e) => Err(port_error(&self.port, "write", &e)),
        }
    }

    fn dropped(&self) -> u64 {
        self.dropped
    }
}
