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

use crate::config::RcConfig;
use crate::plausibility::GpsQuality;
use crate::runtime::{Arrival, Next, PortError, RcPort, SensorPort, ServoPort};
use crate::safety::RcInput;
use helicon_core::SensorFrame;
use helicon_core::state::Input;
use helicon_devices::avionics::{AvionicsMessage, ServoCommand};
use helicon_devices::{AvionicsDecoder, LocalNed, UbxDecoder, VnBinaryDecoder};
use helicon_devices::{SerialLink, TransportError, Written};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A device of the on-board computer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Device {
    /// The IMU with its magnetometer.
    Imu,
    /// The GPS receiver.
    Gps,
    /// The avionics board (servos out, receiver in).
    Avionics,
}

/// A device's port failed (a read error, its end, a hang-up: the device is
/// lost and its port is reopened with back-off) or was reopened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DeviceEvent {
    /// Which device.
    pub device: Device,
    /// Lost (true) or back (false).
    pub lost: bool,
}

impl DeviceEvent {
    /// The log's and the operator's text (at most 50 bytes: one MAVLink
    /// STATUSTEXT).
    pub fn text(&self) -> &'static str {
        match (self.device, self.lost) {
            (Device::Imu, true) => "IMU port lost, reopening",
            (Device::Imu, false) => "IMU port reopened",
            (Device::Gps, true) => "GPS port lost, reopening",
            (Device::Gps, false) => "GPS port reopened",
            (Device::Avionics, true) => "avionics port lost, reopening",
            (Device::Avionics, false) => "avionics port reopened",
        }
    }
}

/// The first wait before reopening a lost port.
pub const REOPEN_FIRST: Duration = Duration::from_millis(50);
/// The longest wait between two attempts to reopen a lost port (the wait
/// doubles from [`REOPEN_FIRST`] up to it).
pub const REOPEN_MAX: Duration = Duration::from_secs(2);

/// A device's port that survives the device: an error (a read or write
/// error, a hang-up) drops the port and marks the device lost; it is then
/// reopened by its path, first after [`REOPEN_FIRST`], then at doubling
/// intervals up to [`REOPEN_MAX`] (a USB adapter re-plugged, a
/// `/dev/serial/by-id` link pointing at the new device).
pub struct Reopening {
    device: Device,
    path: PathBuf,
    baud: u32,
    link: Option<SerialLink>,
    retry_at_ns: u64,
    backoff: Duration,
    /// Times the port was lost.
    pub losses: u64,
}

/// What one read of a [`Reopening`] port gave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkRead {
    /// Bytes read (0: nothing within the timeout).
    Bytes(usize),
    /// The port failed on this read: the device is lost.
    Lost,
    /// The port was reopened on this call.
    Reopened,
    /// The port is down (waiting to reopen).
    Down,
}

impl Reopening {
    /// `link`, opened at `baud`, as the port of `device`.
    pub fn new(device: Device, link: SerialLink, baud: u32) -> Self {
        Reopening {
            device,
            path: link.path().to_path_buf(),
            baud,
            link: Some(link),
            retry_at_ns: 0,
            backoff: REOPEN_FIRST,
            losses: 0,
        }
    }

    /// The port's link, when it is up.
    pub fn link_mut(&mut self) -> Option<&mut SerialLink> {
        self.link.as_mut()
    }

    /// Take `link` (a handle another thread reopened) as the port, when
    /// the port is down: true when taken.
    fn adopt(&mut self, link: SerialLink) -> bool {
        if self.link.is_some() {
            return false;
        }
        self.link = Some(link);
        self.backoff = REOPEN_FIRST;
        true
    }

    /// The port failed: drop it, retry after the back-off.
    pub fn lose(&mut self) {
        self.link = None;
        self.losses += 1;
        self.backoff = REOPEN_FIRST;
        self.retry_at_ns = crate::realtime::monotonic_ns() + duration_ns(self.backoff);
    }

    /// Reopen the port when it is down and its back-off has passed: true
    /// when it was reopened by this call.
    pub fn try_reopen(&mut self) -> bool {
        if self.link.is_some() {
            return false;
        }
        let now = crate::realtime::monotonic_ns();
        if now < self.retry_at_ns {
            return false;
        }
        match SerialLink::open(&self.path, self.baud, Duration::ZERO) {
            Ok(l) => {
                self.link = Some(l);
                self.backoff = REOPEN_FIRST;
                true
            }
            Err(_) => {
                self.backoff = (self.backoff * 2).min(REOPEN_MAX);
                self.retry_at_ns = now + duration_ns(self.backoff);
                false
            }
        }
    }

    /// Read what the port has, waiting at most `timeout` (a port that is
    /// down waits the timeout out, so a reader does not spin).
    pub fn read(&mut self, buf: &mut [u8], timeout: Duration) -> LinkRead {
        if self.link.is_none() {
            if self.try_reopen() {
                return LinkRead::Reopened;
            }
            if !timeout.is_zero() {
                std::thread::sleep(timeout);
            }
            return LinkRead::Down;
        }
        let Some(link) = self.link.as_mut() else {
            return LinkRead::Down;
        };
        match link.read_timeout(buf, timeout) {
            Ok(n) => LinkRead::Bytes(n),
            Err(_) => {
                self.lose();
                LinkRead::Lost
            }
        }
    }

    /// The event of a read's outcome, if it was one.
    fn event(&self, r: LinkRead) -> Option<DeviceEvent> {
        match r {
            LinkRead::Lost => Some(DeviceEvent {
                device: self.device,
                lost: true,
            }),
            LinkRead::Reopened => Some(DeviceEvent {
                device: self.device,
                lost: false,
            }),
            _ => None,
        }
    }
}

fn duration_ns(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

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

/// The IMU (with magnetometer) and GPS read by one sensor-server thread.
/// A port that fails (a read error, a hang-up) is the device lost: its
/// samples stop (the supervisor's stale limit acts: the IMU lost, the GPS
/// or magnetometer failsafe), the loss and the reopening are reported in
/// the next [`Arrival`], and the port is reopened with back-off
/// ([`Reopening`]); the sensor server never ends for a device.
pub struct DeviceSensors {
    imu: Reopening,
    gps: Reopening,
    pending_event: Option<DeviceEvent>,
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
        let (imu_baud, gps_baud) = (imu.baud(), gps.baud());
        DeviceSensors {
            imu: Reopening::new(Device::Imu, imu, imu_baud),
            gps: Reopening::new(Device::Gps, gps, gps_baud),
            pending_event: None,
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
    fn drain_gps(&mut self) {
        loop {
            let r = self.gps.read(&mut self.buf, Duration::ZERO);
            if let Some(e) = self.gps.event(r) {
                self.pending_event = Some(e);
            }
            let LinkRead::Bytes(n @ 1..) = r else {
                return;
            };
            let mut last = None;
            self.ubx.push_with(&self.buf[..n], |m| last = Some(m));
            if last.is_some() {
                self.pending_gps = last;
            }
        }
    }

    /// Times each port was lost so far (IMU, GPS).
    pub fn losses(&self) -> (u64, u64) {
        (self.imu.losses, self.gps.losses)
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
                gps_quality: None,
                device: self.pending_event.take(),
            });
        }
        self.last_imu_ns = Some(ns);
        let t_s = ns as f64 * 1e-9;
        let mut quality = None;
        let gps = self.pending_gps.take().map(|pvt| {
            quality = Some(GpsQuality::from_nav_pvt(&pvt));
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
            gps_quality: quality,
            device: self.pending_event.take(),
        })
    }
}

impl SensorPort for DeviceSensors {
    fn next(&mut self, timeout: Duration) -> Result<Next<Arrival>, PortError> {
        let r = self.imu.read(&mut self.buf, timeout);
        if let Some(e) = self.imu.event(r) {
            self.pending_event = Some(e);
        }
        let n = match r {
            LinkRead::Bytes(n) => n,
            _ => 0,
        };
        if n == 0 {
            // lock-step (the receiver read here too, only there): a look
            // that does not wait, polling the IMU, leaves the other lines to
            // the IMU's message, whose GPS and receiver bytes the simulator
            // delivers first (one system call a look). In real time every
            // look drains them: there the GPS would starve.
            if timeout.is_zero() && self.receiver.is_some() && self.pending_event.is_none() {
                return Ok(Next::Timeout);
            }
            // the GPS keeps being read while the IMU is silent
            self.drain_gps();
            self.drain_rc()?;
            // a device's loss or return is told at once (not a sample)
            return Ok(match self.pending_event.take() {
                Some(e) => Next::Item(Arrival {
                    frame: None,
                    arrived_ns: crate::realtime::monotonic_ns(),
                    rc: self.pending_rc.take(),
                    gps_quality: None,
                    device: Some(e),
                }),
                None => Next::Timeout,
            });
        }
        // the newest complete IMU message of the read (a reader that fell
        // behind keeps the newest sample)
        let mut newest = None;
        let buf = self.buf;
        self.vn.push_with(&buf[..n], |m| newest = Some(m));
        let Some(m) = newest else {
            return Ok(Next::Timeout);
        };
        self.drain_gps();
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

/// The receiver side of the avionics port. A port that fails is reopened
/// with back-off ([`Reopening`]); meanwhile the receiver is silent (the
/// supervisor's `stale.rc_s` takes it as the pilot's link lost).
pub struct DeviceRc {
    port: Reopening,
    decoder: AvionicsDecoder,
    config: RcConfig,
    buf: [u8; 256],
    slot: Option<ReopenSlot>,
    /// The port's event not yet taken (lost, reopened).
    event: Option<DeviceEvent>,
}

/// The avionics port reopened by the servo side, handed to the receiver
/// side (the port is opened exclusively: the receiver cannot open it a
/// second time). The lock is only tried, never waited for.
type ReopenSlot = std::sync::Arc<std::sync::Mutex<Option<SerialLink>>>;

/// The receiver and the servo sides of one avionics port (`link`), the
/// receiver read with `config`: when the line fails, the servo side
/// reopens the port with back-off and hands the receiver side its handle.
pub fn avionics_ports(
    link: SerialLink,
    config: RcConfig,
) -> Result<(DeviceRc, DeviceServos), PortError> {
    let rc_link = clone_port(&link)?;
    let slot = ReopenSlot::default();
    let mut rc = DeviceRc::new(rc_link).with_config(config);
    rc.slot = Some(slot.clone());
    let mut servos = DeviceServos::new(link);
    servos.slot = Some(slot);
    Ok((rc, servos))
}

impl DeviceRc {
    /// The receiver on (a handle of) the avionics port, with the default
    /// receiver settings.
    pub fn new(port: SerialLink) -> Self {
        let baud = port.baud();
        DeviceRc {
            port: Reopening::new(Device::Avionics, port, baud),
            decoder: AvionicsDecoder::new(),
            config: RcConfig::default(),
            buf: [0; 256],
            slot: None,
            event: None,
        }
    }

    /// The same receiver with the settings `config` (range, kill channel).
    #[must_use]
    pub fn with_config(mut self, config: RcConfig) -> Self {
        self.config = config;
        self
    }
}

/// The supervisor's view of a receiver frame under `config`: the sticks
/// (channels 1–4), the arm switch (channel 5 above 1500 µs), the kill
/// channel; a frame with any of these channels outside the receiver's
/// range is marked out of range (refused by the supervisor).
pub fn rc_input(rc: &helicon_devices::RcInput, config: &RcConfig) -> RcInput {
    let kill = config.kill_channel.map(|k| usize::from(k) - 1);
    let used = |i: usize| i < 5 || Some(i) == kill;
    let out_of_range = rc
        .channels_us
        .iter()
        .enumerate()
        .any(|(i, us)| used(i) && !(config.min_us..=config.max_us).contains(us));
    RcInput {
        servo: Input::from_fn(|i, _| stick_command(rc.channels_us[i])),
        manual: !rc.autonomous,
        armed: rc.channels_us[4] > 1500,
        failsafe: rc.failsafe,
        kill: kill.is_some_and(|k| rc.channels_us.get(k).is_some_and(|us| *us > 1500)),
        out_of_range,
    }
}

impl RcPort for DeviceRc {
    fn take_event(&mut self) -> Option<DeviceEvent> {
        self.event.take()
    }

    fn next(&mut self, timeout: Duration) -> Result<Next<RcInput>, PortError> {
        if self.port.link.is_none()
            && let Some(slot) = &self.slot
        {
            // the servo side reopens the (exclusive) port and hands it over
            if let Some(l) = slot.try_lock().ok().and_then(|mut g| g.take()) {
                if self.port.adopt(l) {
                    self.event = Some(DeviceEvent {
                        device: Device::Avionics,
                        lost: false,
                    });
                }
            } else {
                if !timeout.is_zero() {
                    std::thread::sleep(timeout);
                }
                return Ok(Next::Timeout);
            }
        }
        let r = self.port.read(&mut self.buf, timeout);
        if let Some(e) = self.port.event(r) {
            self.event = Some(e);
        }
        let LinkRead::Bytes(n) = r else {
            return Ok(Next::Timeout);
        };
        let mut last = None;
        self.decoder.push_with(&self.buf[..n], |m| {
            if let AvionicsMessage::Rc(rc) = m {
                last = Some(rc);
            }
        });
        Ok(match last {
            Some(rc) => Next::Item(rc_input(&rc, &self.config)),
            None => Next::Timeout,
        })
    }
}

/// The servo side of the avionics port. A frame the port's output buffer
/// cannot take (the line slower than the frames, the board not reading) is
/// dropped and counted, never waited for: the control task is not held up
/// by the line ([`SerialLink::write_all`]). A port that fails is reopened
/// with back-off ([`Reopening`]); the frames meanwhile are dropped and
/// counted.
pub struct DeviceServos {
    port: Reopening,
    seq: u8,
    dropped: u64,
    slot: Option<ReopenSlot>,
}

impl DeviceServos {
    /// The servos on (a handle of) the avionics port.
    pub fn new(port: SerialLink) -> Self {
        let baud = port.baud();
        DeviceServos {
            port: Reopening::new(Device::Avionics, port, baud),
            seq: 0,
            dropped: 0,
            slot: None,
        }
    }
}

impl ServoPort for DeviceServos {
    fn send(&mut self, u: &Input, throttle_hold: bool) -> Result<(), PortError> {
        let mut cmd = ServoCommand::from_inputs(self.seq, true, u).map_err(|e| PortError {
            port: "servo command".into(),
            message: e.to_string(),
        })?;
        cmd.throttle_hold = throttle_hold;
        self.seq = self.seq.wrapping_add(1);
        if self.port.try_reopen()
            && let (Some(slot), Some(link)) = (&self.slot, self.port.link.as_ref())
            && let Ok(clone) = link.try_clone()
            && let Ok(mut g) = slot.try_lock()
        {
            // the receiver side's handle of the reopened port
            *g = Some(clone);
        }
        let Some(link) = self.port.link_mut() else {
            self.dropped += 1;
            return Ok(());
        };
        // try_write: a dropped frame allocates nothing (a hot path)
        match link.try_write(cmd.encode().as_bytes()) {
            Ok(Written::All) => Ok(()),
            Ok(Written::Dropped { .. }) => {
                self.dropped += 1;
                Ok(())
            }
            Err(_) => {
                // the device is gone: reopened with back-off, frames dropped
                self.port.lose();
                self.dropped += 1;
                Ok(())
            }
        }
    }

    fn dropped(&self) -> u64 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use helicon_devices::PtyPair;

    /// A lost port is retried first after 50 ms, then at doubling
    /// intervals up to 2 s; no attempt before its time; the device back,
    /// the next attempt reopens it and the back-off starts again at 50 ms.
    /// (Each attempt's time is set due by hand: the schedule, not the wall
    /// clock, is under test.)
    #[test]
    fn a_lost_port_is_retried_at_doubling_intervals_up_to_two_seconds() {
        let pty = PtyPair::open().unwrap();
        let link = SerialLink::open(pty.slave_path(), 115_200, Duration::ZERO).unwrap();
        let mut r = Reopening::new(Device::Gps, link, 115_200);
        // the device gone from its path
        r.path = std::env::temp_dir().join(format!("helicon_gone_{}", std::process::id()));
        let t0 = crate::realtime::monotonic_ns();
        r.lose();
        assert!(r.link.is_none());
        assert_eq!(r.losses, 1);
        assert_eq!(r.backoff, REOPEN_FIRST);
        assert!(r.retry_at_ns >= t0 + duration_ns(REOPEN_FIRST));
        // before its time: no attempt, the schedule unchanged
        assert!(!r.try_reopen());
        assert_eq!(r.backoff, REOPEN_FIRST);
        let mut waits_ms = Vec::new();
        for _ in 0..8 {
            r.retry_at_ns = 0;
            let before = crate::realtime::monotonic_ns();
            assert!(!r.try_reopen());
            let after = crate::realtime::monotonic_ns();
            let wait = duration_ns(r.backoff);
            assert!(r.retry_at_ns >= before + wait && r.retry_at_ns <= after + wait);
            waits_ms.push(r.backoff.as_millis());
        }
        assert_eq!(waits_ms, [100, 200, 400, 800, 1600, 2000, 2000, 2000]);
        assert_eq!(REOPEN_MAX, Duration::from_secs(2));
        // the device back behind its path
        r.path = pty.slave_path().to_path_buf();
        r.retry_at_ns = 0;
        assert!(r.try_reopen());
        assert_eq!(r.backoff, REOPEN_FIRST);
        assert_eq!(
            r.event(LinkRead::Reopened),
            Some(DeviceEvent {
                device: Device::Gps,
                lost: false
            })
        );
    }
}
