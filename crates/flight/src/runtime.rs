//! The on-board runtime of thesis Figure 3.5 as threads:
//!
//! ```text
//!  IMU+mag port ─┐                       ┌─► avionics-out ─► servo port
//!  GPS port ─────┴► sensor server ─ring─► control task ─ring─┤   (watchdog)
//!                                  ▲      (400 Hz)           └─► logger ─► flight.ulg
//!  RC port ─────► receiver ───ring─┘         ring ──────────────────┘
//! ```
//!
//! The rings are `rtrb` single-producer single-consumer rings (lock-free,
//! allocated once at start); a ring that is full drops the newest item and
//! counts it. Threads waiting for work park and are unparked by the producer.
//!
//! The control task is paced either by the clock ([`Pacing::Clock`]: absolute
//! deadlines on `CLOCK_MONOTONIC`, one period apart and phase-locked to
//! 250 µs after the IMU's arrivals; the frame that arrived since the last
//! deadline is used, none means no fresh IMU sample; a silent IMU leaves
//! the deadlines running) or by sensor arrival
//! ([`Pacing::Sensor`]: one step per IMU message, the lock-step of SITL, where
//! on-board time is k·Ts from the first message). Either way each step is
//! the [`ControlTask`]'s and sends exactly one servo frame.

use crate::control::{ControlTask, DISARM_REFUSED_TEXT, RC_REFUSED_TEXT, StepReport, Tick};
pub use crate::mission::{LastStep, Mission, flight_mode};
use crate::realtime::{self, LatencyStats, LatencySummary, RealtimeStatus};
use crate::records::{FlightRecord, step_records, write_record};
use crate::safety::{Mode, RcInput};
use helicon_core::SensorFrame;
use helicon_core::state::Input;
use helicon_gcs::link::VehicleEvent;
use helicon_ulog::messages::Timing;
use helicon_ulog::{FlightLog, timestamp_us};
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::{self, Thread};
use std::time::Duration;

/// What a port read gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Next<T> {
    /// An item.
    Item(T),
    /// Nothing within the timeout.
    Timeout,
    /// The port was closed (end of a SITL run, a device unplugged).
    Closed,
}

/// An error of a port (decoding errors are counted by the port, not raised).
#[derive(Debug, thiserror::Error)]
#[error("{port}: {message}")]
pub struct PortError {
    /// The device path or name.
    pub port: String,
    /// What went wrong.
    pub message: String,
}

/// A superseded arrival's measurements that the newer one lacks, moved
/// onto it: a control task that fell behind keeps the newest IMU sample,
/// and with it the GPS fix (and its quality), the magnetometer sample and
/// the receiver frame that came with an older one, so that a late step
/// never loses a fix (each is still checked for plausibility when used).
fn carry_over(old: Arrival, new: &mut Arrival) {
    if let (Some(o), Some(n)) = (old.frame, new.frame.as_mut()) {
        if n.gps.is_none() && o.gps.is_some() {
            n.gps = o.gps;
            new.gps_quality = old.gps_quality;
        }
        if n.mag_body.is_none() {
            n.mag_body = o.mag_body;
        }
    }
    if new.rc.is_none() {
        new.rc = old.rc;
    }
}

/// One IMU message as the sensor server assembled it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrival {
    /// The frame: the IMU sample with the magnetometer and GPS decoded
    /// since the previous one; `None` when the IMU's sample time did not
    /// advance (a stuck sensor: not a fresh sample).
    pub frame: Option<SensorFrame>,
    /// When the message was decoded (`CLOCK_MONOTONIC`, ns).
    pub arrived_ns: u64,
    /// The receiver's newest frame, when the sensor server also reads the
    /// receiver (lock-step: its frames written before the IMU message then
    /// reach the same control step, deterministically).
    pub rc: Option<RcInput>,
    /// The GPS receiver's own report of the frame's fix (satellites,
    /// accuracies), when the frame has a fix and the receiver gives one.
    pub gps_quality: Option<crate::plausibility::GpsQuality>,
    /// A device lost or reopened since the last arrival.
    pub device: Option<crate::ports::DeviceEvent>,
}

/// The sensor devices (IMU with magnetometer, GPS) read together.
pub trait SensorPort: Send + 'static {
    /// Block up to `timeout` for the next IMU message.
    fn next(&mut self, timeout: Duration) -> Result<Next<Arrival>, PortError>;
}

/// The receiver side of the avionics board.
pub trait RcPort: Send + 'static {
    /// Block up to `timeout` for the next receiver frame.
    fn next(&mut self, timeout: Duration) -> Result<Next<RcInput>, PortError>;

    /// The port's event since the last call (its device lost or reopened),
    /// logged and told to the ground station as the sensors' are.
    fn take_event(&mut self) -> Option<crate::ports::DeviceEvent> {
        None
    }
}

/// The receiver thread's item: a frame, or its port's event.
#[derive(Debug, Clone, Copy)]
enum RcItem {
    Frame(RcInput),
    Device(crate::ports::DeviceEvent),
}

/// The servo side of the avionics board.
pub trait ServoPort: Send + 'static {
    /// Send one servo frame, without waiting for its transmission;
    /// `throttle_hold`: the engine cut (on the ground, disarmed).
    fn send(&mut self, u: &Input, throttle_hold: bool) -> Result<(), PortError>;

    /// Frames dropped so far because the port could not take them (its
    /// output buffer full): counted, not errors.
    fn dropped(&self) -> u64 {
        0
    }
}

/// How the control task is paced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pacing {
    /// Absolute deadlines on the monotonic clock (on board, real-time SITL).
    Clock,
    /// One step per IMU message (lock-step SITL).
    Sensor,
}

/// Runtime options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RuntimeOptions {
    /// The control period (s): the parameters' `control.sample_time_s`.
    pub sample_time_s: f64,
    /// Pacing.
    pub pacing: Pacing,
    /// Stop after this many control steps (`None`: until the sensor port
    /// closes or [`RuntimeHandle::stop`]).
    pub max_steps: Option<u64>,
    /// The real-time options asked for.
    pub realtime: crate::config::RealtimeConfig,
    /// Silence of the control task after which the avionics thread commands
    /// the trim (s; clock pacing only).
    pub watchdog_s: f64,
    /// The trim (watchdog and disarmed commands).
    pub u_trim: Input,
}

/// What a run measured (`timing.json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunReport {
    /// Control steps run.
    pub steps: u64,
    /// Steps whose deadline was missed (clock pacing).
    pub deadline_misses: u64,
    /// IMU frames that arrived while an earlier one was still unused
    /// (clock pacing: the older IMU sample is dropped; its GPS fix,
    /// magnetometer sample and receiver frame move onto the newer one).
    pub frames_superseded: u64,
    /// Steps without a fresh IMU sample.
    pub steps_without_imu: u64,
    /// Log records dropped (a ring full) or refused by the writer.
    pub log_dropped: u64,
    /// Servo frames handed to the port (including those it dropped).
    pub servo_frames: u64,
    /// Servo frames the avionics port dropped: its output buffer could not
    /// take them (the line slower than the frames, or nobody reading); the
    /// control task never waits for the line.
    pub servo_frames_dropped: u64,
    /// Watchdog trips.
    pub watchdog_trips: u64,
    /// Receiver frames refused: a channel outside the receiver's range
    /// (`rc.min_us`…`rc.max_us`); their sticks and switches were not used.
    pub rc_frames_refused: u64,
    /// Wake-up lateness after the deadline (clock pacing).
    pub wakeup_jitter: LatencySummary,
    /// Compute time of a step (wake-up to servo command handed over).
    pub compute: LatencySummary,
    /// IMU message decoded to servo frame sent.
    pub sensor_to_servo: LatencySummary,
    /// The real-time setup.
    pub realtime: RealtimeStatus,
    /// The mode at the end.
    pub final_mode: String,
    /// The first port or log error, if any.
    pub error: Option<String>,
}

/// A running on-board program.
pub struct RuntimeHandle {
    stop: Arc<AtomicBool>,
    /// Stops the control task only: the others drain what it sent, then stop.
    stop_control: Arc<AtomicBool>,
    control: thread::JoinHandle<ControlResult>,
    others: Vec<thread::JoinHandle<ThreadResult>>,
    realtime: RealtimeStatus,
    wakers: Vec<Thread>,
}

struct ControlResult {
    /// Lock-step: the servo frames, latency and port error of the control
    /// task's own I/O.
    direct: Option<ThreadResult>,
    steps: u64,
    misses: u64,
    superseded: u64,
    without_imu: u64,
    log_dropped: u64,
    rc_refused: u64,
    jitter: LatencyStats,
    compute: LatencyStats,
    final_mode: Mode,
}

#[derive(Default)]
struct ThreadResult {
    servo_frames: u64,
    servo_dropped: u64,
    watchdog_trips: u64,
    latency: Option<LatencyStats>,
    log_dropped: u64,
    error: Option<String>,
}

/// The servo ring's item: what to send and when its IMU message arrived.
#[derive(Debug, Clone, Copy)]
struct ServoItem {
    u: Input,
    throttle_hold: bool,
    /// On the ground (the watchdog then cuts the engine at ground idle
    /// rather than fly the trim).
    on_ground: bool,
    arrived_ns: Option<u64>,
}

const FRAME_RING: usize = 64;
const RC_RING: usize = 64;
const SERVO_RING: usize = 64;
const LOG_RING: usize = 16_384;
const POLL: Duration = Duration::from_millis(50);
/// The logger's own wake-up period (at 400 Hz about 60 records pile up).
const LOG_POLL: Duration = Duration::from_millis(10);
/// Clock pacing: how long after the IMU message's arrival the control task
/// wakes (the phase it locks to).
const SENSOR_LAG_NS: u64 = 250_000;

/// Spawn the runtime: sensor server, receiver (when `rc` is given; else
/// the sensor port reports the receiver's frames), control task,
/// avionics-out and logger threads. `log` is owned by the logger thread and finished
/// when the runtime ends; `downlink`, when given, receives each step's
/// telemetry (the ground link; SITL fills the truth log's estimate columns
/// from it).
#[allow(clippy::too_many_lines)] // the threads of Figure 3.5, started in order
pub fn spawn<S, R, V, W>(
    task: ControlTask,
    mission: Mission,
    sensors: S,
    rc: Option<R>,
    servos: V,
    log: FlightLog<W>,
    downlink: Option<rtrb::Producer<StepReport>>,
    options: RuntimeOptions,
) -> RuntimeHandle
where
    S: SensorPort,
    R: RcPort,
    V: ServoPort,
    W: Write + Send + 'static,
{
    let mut realtime = RealtimeStatus {
        sched_fifo: false,
        mlockall: false,
        warnings: Vec::new(),
    };
    if options.realtime.mlockall {
        match realtime::lock_memory() {
            Ok(()) => realtime.mlockall = true,
            Err(e) => realtime
                .warnings
                .push(format!("mlockall not permitted ({e}): memory not locked")),
        }
    }
    let stop = Arc::new(AtomicBool::new(false));
    let stop_control = Arc::new(AtomicBool::new(false));
    let sensors_closed = Arc::new(AtomicBool::new(false));
    let last_output_ns = Arc::new(AtomicU64::new(realtime::monotonic_ns()));
    let (frame_tx, frame_rx) = rtrb::RingBuffer::<Arrival>::new(FRAME_RING);
    let (rc_tx, rc_rx) = rtrb::RingBuffer::<RcItem>::new(RC_RING);
    let (servo_tx, servo_rx) = rtrb::RingBuffer::<ServoItem>::new(SERVO_RING);
    let (log_tx, log_rx) = rtrb::RingBuffer::<FlightRecord>::new(LOG_RING);
    let (wlog_tx, wlog_rx) = rtrb::RingBuffer::<FlightRecord>::new(64);

    // logger (normal priority)
    let logger = {
        let stop = stop.clone();
        thread::Builder::new()
            .name("logger".into())
            .spawn(move || logger_loop(log, log_rx, wlog_rx, &stop))
    };
    let logger_thread = logger.as_ref().ok().map(|h| h.thread().clone());

    // lock-step: the control task reads the sensors and writes the servos
    // itself (the pacing is the sensor's anyway): two thread hand-overs per
    // sample instead of four
    let direct = options.pacing == Pacing::Sensor;
    let mut sensors = Some(sensors);
    let mut servos = Some(servos);
    let direct_io: Option<(Box<dyn SensorPort>, Box<dyn ServoPort>)> = if direct {
        match (sensors.take(), servos.take()) {
            (Some(a), Some(b)) => Some((Box::new(a), Box::new(b))),
            _ => None,
        }
    } else {
        None
    };

    // avionics-out
    let avionics = servos.take().map(|servos| {
        let stop = stop.clone();
        let last = last_output_ns.clone();
        let logger_thread = logger_thread.clone();
        thread::Builder::new()
            .name("avionics-out".into())
            .spawn(move || {
                // the servo frame leaves as soon as the step is done: one
                // below the control task, as the sensor server
                if options.realtime.sched_fifo {
                    let _ = realtime::set_fifo(options.realtime.priority.saturating_sub(1).max(1));
                }
                avionics_loop(
                    servos,
                    servo_rx,
                    wlog_tx,
                    &stop,
                    &last,
                    logger_thread,
                    options,
                )
            })
    });
    let avionics_thread = avionics
        .as_ref()
        .and_then(|h| h.as_ref().ok())
        .map(|h| h.thread().clone());

    // control task
    let (fifo_tx, fifo_rx) = std::sync::mpsc::channel::<Result<(), String>>();
    let control = {
        let stop = stop_control.clone();
        let closed = sensors_closed.clone();
        let last = last_output_ns.clone();
        let wake_out = avionics_thread.clone();
        let wake_log = logger_thread.clone();
        thread::Builder::new()
            .name("control".into())
            .spawn(move || {
                if options.realtime.sched_fifo {
                    let _ = fifo_tx.send(realtime::set_fifo(options.realtime.priority));
                } else {
                    let _ = fifo_tx.send(Ok(()));
                }
                let ctx = ControlCtx {
                    frames: frame_rx,
                    rc: rc_rx,
                    servo: servo_tx,
                    log: log_tx,
                    stop: &stop,
                    closed: &closed,
                    last_output_ns: &last,
                    wake_out,
                    wake_log,
                    downlink,
                    direct: direct_io.map(|(sensors, servos)| Direct {
                        sensors,
                        servos,
                        latency: LatencyStats::new(),
                        frames: 0,
                        drop_log: DropLog::default(),
                        error: None,
                    }),
                    options,
                };
                control_loop(task, mission, ctx)
            })
    };
    match fifo_rx.recv() {
        Ok(Ok(())) => realtime.sched_fifo = options.realtime.sched_fifo,
        Ok(Err(e)) => realtime.warnings.push(format!(
            "SCHED_FIFO not permitted ({e}): the control task runs at normal priority"
        )),
        Err(_) => realtime
            .warnings
            .push("the control task did not start".to_string()),
    }
    let control_thread = control.as_ref().ok().map(|h| h.thread().clone());

    // sensor server and receiver (SCHED_FIFO one below the control task)
    let sensor = sensors.take().map(|sensors| {
        let stop = stop.clone();
        let closed = sensors_closed.clone();
        let wake = control_thread.clone();
        thread::Builder::new()
            .name("sensor-server".into())
            .spawn(move || {
                if options.realtime.sched_fifo {
                    let _ = realtime::set_fifo(options.realtime.priority.saturating_sub(1).max(1));
                }
                sensor_loop(sensors, frame_tx, &stop, &closed, wake)
            })
    });
    let receiver = rc.map(|rc| {
        let stop = stop.clone();
        thread::Builder::new()
            .name("receiver".into())
            .spawn(move || receiver_loop(rc, rc_tx, &stop))
    });
    let mut others = Vec::new();
    let mut wakers = Vec::new();
    for h in [sensor, receiver, avionics, Some(logger)]
        .into_iter()
        .flatten()
    {
        match h {
            Ok(h) => {
                wakers.push(h.thread().clone());
                others.push(h);
            }
            Err(e) => realtime
                .warnings
                .push(format!("a thread did not start: {e}")),
        }
    }
    let control = match control {
        Ok(h) => h,
        Err(e) => {
            // no control task: stop everything at once
            stop.store(true, Ordering::SeqCst);
            stop_control.store(true, Ordering::SeqCst);
            realtime.warnings.push(format!("control task: {e}"));
            thread::spawn(|| ControlResult {
                direct: None,
                steps: 0,
                misses: 0,
                superseded: 0,
                without_imu: 0,
                log_dropped: 0,
                rc_refused: 0,
                jitter: LatencyStats::new(),
                compute: LatencyStats::new(),
                final_mode: Mode::Disarmed,
            })
        }
    };
    RuntimeHandle {
        stop,
        stop_control,
        control,
        others,
        realtime,
        wakers,
    }
}

impl RuntimeHandle {
    /// The real-time warnings of the start (privileges refused).
    pub fn warnings(&self) -> Vec<String> {
        self.realtime.warnings.clone()
    }

    /// Ask the control task to stop (after its current step); [`RuntimeHandle::join`]
    /// then stops the other threads once they have handled all it sent.
    pub fn stop(&self) {
        self.stop_control.store(true, Ordering::SeqCst);
        for t in &self.wakers {
            t.unpark();
        }
        self.control.thread().unpark();
    }

    /// Whether the control task has ended (then [`RuntimeHandle::join`]
    /// returns once the other threads have drained what it sent).
    pub fn is_finished(&self) -> bool {
        self.control.is_finished()
    }

    /// Wait for the control task to end (its step limit, the sensor port
    /// closed, or [`RuntimeHandle::stop`]), stop the others, and report.
    pub fn join(self) -> RunReport {
        let c = self.control.join();
        self.stop.store(true, Ordering::SeqCst);
        for t in &self.wakers {
            t.unpark();
        }
        let mut report = RunReport {
            steps: 0,
            deadline_misses: 0,
            frames_superseded: 0,
            steps_without_imu: 0,
            log_dropped: 0,
            servo_frames: 0,
            servo_frames_dropped: 0,
            watchdog_trips: 0,
            rc_frames_refused: 0,
            wakeup_jitter: LatencyStats::new().summary(),
            compute: LatencyStats::new().summary(),
            sensor_to_servo: LatencyStats::new().summary(),
            realtime: self.realtime,
            final_mode: Mode::Disarmed.as_str().to_string(),
            error: None,
        };
        match c {
            Ok(c) => {
                if let Some(d) = c.direct {
                    report.servo_frames += d.servo_frames;
                    report.servo_frames_dropped += d.servo_dropped;
                    if let Some(l) = d.latency {
                        report.sensor_to_servo = l.summary();
                    }
                    report.error = d.error;
                }
                report.steps = c.steps;
                report.deadline_misses = c.misses;
                report.frames_superseded = c.superseded;
                report.steps_without_imu = c.without_imu;
                report.log_dropped += c.log_dropped;
                report.rc_frames_refused = c.rc_refused;
                report.wakeup_jitter = c.jitter.summary();
                report.compute = c.compute.summary();
                report.final_mode = c.final_mode.as_str().to_string();
            }
            Err(_) => report.error = Some("the control task panicked".into()),
        }
        for h in self.others {
            match h.join() {
                Ok(r) => {
                    report.servo_frames += r.servo_frames;
                    report.servo_frames_dropped += r.servo_dropped;
                    report.watchdog_trips += r.watchdog_trips;
                    report.log_dropped += r.log_dropped;
                    if let Some(l) = r.latency {
                        report.sensor_to_servo = l.summary();
                    }
                    if report.error.is_none() {
                        report.error = r.error;
                    }
                }
                Err(_) => {
                    report
                        .error
                        .get_or_insert_with(|| "a thread panicked".into());
                }
            }
        }
        report
    }
}

fn sensor_loop<S: SensorPort>(
    mut port: S,
    mut ring: rtrb::Producer<Arrival>,
    stop: &AtomicBool,
    closed: &AtomicBool,
    wake: Option<Thread>,
) -> ThreadResult {
    let mut result = ThreadResult::default();
    while !stop.load(Ordering::Relaxed) {
        match port.next(POLL) {
            Ok(Next::Item(a)) => {
                // a full ring means the control task is not keeping up: drop and count
                if ring.push(a).is_err() {
                    result.log_dropped += 1;
                }
                if let Some(t) = &wake {
                    t.unpark();
                }
            }
            Ok(Next::Timeout) => {}
            Ok(Next::Closed) => break,
            Err(e) => {
                result.error = Some(e.to_string());
                break;
            }
        }
    }
    closed.store(true, Ordering::SeqCst);
    if let Some(t) = &wake {
        t.unpark();
    }
    result
}

fn receiver_loop<R: RcPort>(
    mut port: R,
    mut ring: rtrb::Producer<RcItem>,
    stop: &AtomicBool,
) -> ThreadResult {
    let mut result = ThreadResult::default();
    while !stop.load(Ordering::Relaxed) {
        let next = port.next(POLL);
        if let Some(e) = port.take_event() {
            let _ = ring.push(RcItem::Device(e));
        }
        match next {
            Ok(Next::Item(rc)) => {
                let _ = ring.push(RcItem::Frame(rc));
            }
            Ok(Next::Timeout) => {}
            Ok(Next::Closed) => break,
            Err(e) => {
                result.error = Some(e.to_string());
                break;
            }
        }
    }
    result
}

struct ControlCtx<'a> {
    frames: rtrb::Consumer<Arrival>,
    rc: rtrb::Consumer<RcItem>,
    servo: rtrb::Producer<ServoItem>,
    log: rtrb::Producer<FlightRecord>,
    stop: &'a AtomicBool,
    closed: &'a AtomicBool,
    last_output_ns: &'a AtomicU64,
    wake_out: Option<Thread>,
    wake_log: Option<Thread>,
    downlink: Option<rtrb::Producer<StepReport>>,
    direct: Option<Direct>,
    options: RuntimeOptions,
}

/// The control task's own I/O in lock-step.
struct Direct {
    sensors: Box<dyn SensorPort>,
    servos: Box<dyn ServoPort>,
    latency: LatencyStats,
    frames: u64,
    /// The servo drops logged so far.
    drop_log: DropLog,
    error: Option<String>,
}

#[allow(clippy::too_many_lines)] // one loop: wait, gather, step, hand over, log
fn control_loop(
    mut task: ControlTask,
    mut mission: Mission,
    mut ctx: ControlCtx<'_>,
) -> ControlResult {
    let ts_s = ctx.options.sample_time_s;
    let period_ns = (ts_s * 1e9).round() as u64;
    let mut jitter = LatencyStats::new();
    let mut compute = LatencyStats::new();
    let mut steps = 0u64;
    let mut misses = 0u64;
    let mut superseded = 0u64;
    let mut without_imu = 0u64;
    let mut log_dropped = 0u64;
    let t0_ns = realtime::monotonic_ns();
    let mut deadline_ns = t0_ns + period_ns;
    let mut missed_last = false;
    let mut device_events = DeviceEvents::default();
    let mut last = LastStep {
        telemetry: None,
        mode: task.mode(),
        servo: ctx.options.u_trim,
        load: 0.0,
    };
    loop {
        if ctx.stop.load(Ordering::Relaxed) {
            break;
        }
        if ctx.options.max_steps.is_some_and(|m| steps >= m) {
            break;
        }
        // wait for the step
        let (wake_ns, late_ns, arrival) = match ctx.options.pacing {
            Pacing::Clock => {
                // the sensor port closed (a device gone, the end of a run)
                // and every frame it delivered used: the program ends
                if ctx.closed.load(Ordering::SeqCst) && ctx.frames.is_empty() {
                    break;
                }
                realtime::sleep_until_ns(deadline_ns);
                let now = realtime::monotonic_ns();
                let late = now.saturating_sub(deadline_ns);
                // take the newest frame that arrived since the last step
                // (a device's event alone does not supersede a frame)
                let mut newest: Option<Arrival> = None;
                while let Ok(a) = ctx.frames.pop() {
                    if let Some(e) = a.device {
                        device_events.push_event(e);
                    }
                    if a.frame.is_none() && newest.is_some_and(|n| n.frame.is_some()) {
                        continue;
                    }
                    let mut a = a;
                    if let Some(old) = newest {
                        superseded += 1;
                        carry_over(old, &mut a);
                    }
                    newest = Some(a);
                }
                (now, late, newest)
            }
            Pacing::Sensor => {
                // lock-step: the control task reads the sensors itself
                let Some(d) = ctx.direct.as_mut() else { break };
                // the simulator answers within microseconds: polled a
                // little before blocking (no wake-up from sleep per sample)
                let mut spun = realtime::spin_for(realtime::LOCKSTEP_SPIN, || {
                    match d.sensors.next(Duration::ZERO) {
                        Ok(Next::Timeout) => None,
                        r => Some(r),
                    }
                });
                let a = loop {
                    match spun.take().unwrap_or_else(|| d.sensors.next(POLL)) {
                        Ok(Next::Item(a)) => break Some(a),
                        Ok(Next::Timeout) if !ctx.stop.load(Ordering::Relaxed) => {}
                        Ok(_) => break None,
                        Err(e) => {
                            d.error.get_or_insert(e.to_string());
                            break None;
                        }
                    }
                };
                let Some(a) = a else { break };
                if let Some(e) = a.device {
                    device_events.push_event(e);
                }
                (realtime::monotonic_ns(), 0, Some(a))
            }
        };
        if ctx.options.pacing == Pacing::Clock {
            jitter.push(late_ns);
        }
        let now_s = match ctx.options.pacing {
            Pacing::Clock => (wake_ns - t0_ns) as f64 * 1e-9,
            Pacing::Sensor => steps as f64 * ts_s,
        };
        let mut rc = arrival.and_then(|a| a.rc);
        while let Ok(r) = ctx.rc.pop() {
            match r {
                RcItem::Frame(f) => rc = Some(f),
                RcItem::Device(e) => device_events.push_event(e),
            }
        }
        let frame = arrival.and_then(|a| a.frame);
        if frame.is_none() {
            without_imu += 1;
        }
        let tick = Tick {
            now_s,
            frame,
            deadline_missed: missed_last,
            rc,
            reference: mission.step(now_s, &last, &mut task),
            gps_quality: arrival.and_then(|a| a.gps_quality),
        };
        // the navigator's modes, events and tuning, for the log
        if let Some(news) = mission.take_news()
            && ctx
                .log
                .push(FlightRecord::Navigator { t_s: now_s, news })
                .is_err()
        {
            log_dropped += 1;
        }
        let out = task.step_with(&tick, mission.excitation());
        for e in device_events.drain() {
            mission.notify(now_s, VehicleEvent::Warning(e.text()));
            if ctx
                .log
                .push(FlightRecord::Device {
                    t_s: now_s,
                    event: e,
                })
                .is_err()
            {
                log_dropped += 1;
            }
        }
        if let Some((kind, _)) = out.rejection {
            mission.notify(now_s, VehicleEvent::Warning(kind.text()));
        }
        if out.rc_refusal.is_some() {
            mission.notify(now_s, VehicleEvent::Warning(RC_REFUSED_TEXT));
        }
        if out.disarm_refusal.is_some() {
            mission.notify(now_s, VehicleEvent::Warning(DISARM_REFUSED_TEXT));
        }
        if let Some(c) = out.imu_health_change {
            mission.notify(now_s, VehicleEvent::Warning(c.text()));
        }
        if let Some(link) = out.rc_link_change {
            mission.notify(now_s, VehicleEvent::Warning(link.rc_text()));
        }
        if let Some(l) = &out.landing
            && let Some((_, to)) = l.change
        {
            mission.notify(
                now_s,
                if l.takeoff_aborted {
                    VehicleEvent::Warning("take-off given up: no lift-off")
                } else {
                    VehicleEvent::Notice(to.text())
                },
            );
        }
        if out.telemetry.is_some() {
            last.telemetry = out.telemetry;
        }
        last.mode = out.mode;
        last.servo = out.servo;
        // the telemetry downlink before the servo frame: whoever waits for
        // the servo frame finds the sample's telemetry
        if let (Some(d), Some(r)) = (ctx.downlink.as_mut(), out.report()) {
            let _ = d.push(r);
        }
        if let Some(d) = ctx.direct.as_mut() {
            match d.servos.send(&out.servo, out.throttle_hold) {
                Ok(()) => d.frames += 1,
                Err(e) => {
                    d.error.get_or_insert(e.to_string());
                }
            }
            if let Some(rec) = d.drop_log.record(d.servos.dropped(), || now_s)
                && ctx.log.push(rec).is_err()
            {
                log_dropped += 1;
            }
            if let Some(a) = arrival {
                d.latency
                    .push(realtime::monotonic_ns().saturating_sub(a.arrived_ns));
            }
        } else {
            let item = ServoItem {
                u: out.servo,
                throttle_hold: out.throttle_hold,
                on_ground: task
                    .landing()
                    .is_some_and(crate::landing::Landing::on_ground),
                arrived_ns: arrival.map(|a| a.arrived_ns),
            };
            if ctx.servo.push(item).is_err() {
                log_dropped += 1;
            }
            if let Some(t) = &ctx.wake_out {
                t.unpark();
            }
        }
        let done_ns = realtime::monotonic_ns();
        ctx.last_output_ns.store(done_ns, Ordering::Relaxed);
        compute.push(done_ns.saturating_sub(wake_ns));
        last.load = done_ns.saturating_sub(wake_ns) as f64 / period_ns.max(1) as f64;
        // a step that ends after the next deadline missed it
        missed_last = ctx.options.pacing == Pacing::Clock && done_ns > deadline_ns + period_ns;
        if missed_last {
            misses += 1;
        }
        let timing = Timing {
            timestamp: timestamp_us(now_s, "timing").unwrap_or(0),
            sample: steps,
            wakeup_jitter_us: i32::try_from(late_ns / 1000).unwrap_or(i32::MAX),
            compute_time_us: u32::try_from(done_ns.saturating_sub(wake_ns) / 1000)
                .unwrap_or(u32::MAX),
            deadline_misses: u32::try_from(misses).unwrap_or(u32::MAX),
            log_dropped: u32::try_from(log_dropped).unwrap_or(u32::MAX),
        };
        let ring = &mut ctx.log;
        let mut dropped = 0;
        let res = step_records(&tick, &out, timing, &mut |r| {
            if ring.push(r).is_err() {
                dropped += 1;
            }
        });
        log_dropped += dropped + u64::from(res.is_err());
        // the logger wakes on its own every LOG_POLL; it is woken early
        // only when its ring fills past a quarter (one wake-up less per step)
        if ctx.log.slots() < LOG_RING * 3 / 4
            && let Some(t) = &ctx.wake_log
        {
            t.unpark();
        }
        steps += 1;
        if ctx.options.pacing == Pacing::Clock {
            deadline_ns += period_ns;
            // phase lock to the IMU: the deadline follows the IMU's arrival
            // by SENSOR_LAG_NS (a first-order loop, 1/8 of the error per
            // step, at most 50 µs a step), so each step finds exactly one
            // fresh sample and the servo frame leaves within the period
            if let Some(a) = arrival {
                // the error wrapped into (−Ts/2, Ts/2]: a sample that arrived
                // just after the last deadline reads as late, not early
                let period = i128::from(period_ns);
                let lag = wake_ns as i128 - i128::from(a.arrived_ns);
                let err =
                    (lag - i128::from(SENSOR_LAG_NS) + period / 2).rem_euclid(period) - period / 2;
                let shift = (err / 8).clamp(-50_000, 50_000);
                let shifted = i128::from(deadline_ns) - shift;
                deadline_ns = u64::try_from(shifted).unwrap_or(deadline_ns);
            }
            // after a long stall, skip the deadlines already past (counted)
            let now = realtime::monotonic_ns();
            while deadline_ns + period_ns < now {
                deadline_ns += period_ns;
                misses += 1;
            }
        }
    }
    ControlResult {
        direct: ctx.direct.map(|d| ThreadResult {
            servo_frames: d.frames,
            servo_dropped: d.servos.dropped(),
            latency: Some(d.latency),
            error: d.error,
            ..ThreadResult::default()
        }),
        steps,
        misses,
        superseded,
        without_imu,
        log_dropped,
        rc_refused: task.rc_refused(),
        jitter,
        compute,
        final_mode: task.mode(),
    }
}

/// Device events waiting for the next control step (a fixed array: no
/// allocation; more than four in one step keep the last four).
#[derive(Debug, Default)]
struct DeviceEvents {
    events: [Option<crate::ports::DeviceEvent>; 4],
}

impl DeviceEvents {
    fn push_event(&mut self, e: crate::ports::DeviceEvent) {
        if let Some(slot) = self.events.iter_mut().find(|s| s.is_none()) {
            *slot = Some(e);
        } else {
            self.events.rotate_left(1);
            self.events[3] = Some(e);
        }
    }

    fn drain(&mut self) -> impl Iterator<Item = crate::ports::DeviceEvent> {
        let events = std::mem::take(&mut self.events);
        events.into_iter().flatten()
    }
}

fn avionics_loop<V: ServoPort>(
    mut port: V,
    mut ring: rtrb::Consumer<ServoItem>,
    mut log: rtrb::Producer<FlightRecord>,
    stop: &AtomicBool,
    last_output_ns: &AtomicU64,
    wake_log: Option<Thread>,
    options: RuntimeOptions,
) -> ThreadResult {
    let mut result = ThreadResult {
        latency: Some(LatencyStats::new()),
        ..Default::default()
    };
    let watchdog_ns = (options.watchdog_s * 1e9) as u64;
    let t0 = realtime::monotonic_ns();
    let mut tripped = false;
    let mut drop_log = DropLog::default();
    // the last frame's engine and ground state (for the watchdog)
    let mut last = (false, false);
    loop {
        let mut sent = false;
        while let Ok(item) = ring.pop() {
            last = (item.throttle_hold, item.on_ground);
            if let Err(e) = port.send(&item.u, item.throttle_hold) {
                result.error.get_or_insert(e.to_string());
            } else {
                result.servo_frames += 1;
                sent = true;
            }
            let t_s = || realtime::monotonic_ns().saturating_sub(t0) as f64 * 1e-9;
            if let Some(rec) = drop_log.record(port.dropped(), t_s)
                && log.push(rec).is_err()
            {
                result.log_dropped += 1;
            }
            if let (Some(a), Some(l)) = (item.arrived_ns, result.latency.as_mut()) {
                l.push(realtime::monotonic_ns().saturating_sub(a));
            }
        }
        if sent {
            tripped = false;
        }
        if stop.load(Ordering::Relaxed) && ring.is_empty() {
            break;
        }
        // the watchdog: a silent control task hands the servos to the trim
        // in the air; on the ground it cuts the engine at ground idle (the
        // trim's collective would lift off with nothing flying it)
        let now = realtime::monotonic_ns();
        let silent = now.saturating_sub(last_output_ns.load(Ordering::Relaxed));
        if options.pacing == Pacing::Clock && !tripped && silent > watchdog_ns {
            tripped = true;
            result.watchdog_trips += 1;
            let (u, hold) = match last {
                (_, true) => (Input::zeros(), true),
                (hold, false) => (options.u_trim, hold),
            };
            if port.send(&u, hold).is_ok() {
                result.servo_frames += 1;
            }
            let rec = FlightRecord::Watchdog {
                t_s: now.saturating_sub(t0) as f64 * 1e-9,
                silent_s: silent as f64 * 1e-9,
            };
            if log.push(rec).is_err() {
                result.log_dropped += 1;
            }
            if let Some(t) = &wake_log {
                t.unpark();
            }
        }
        thread::park_timeout(Duration::from_secs_f64(options.watchdog_s / 4.0));
    }
    result.servo_dropped = port.dropped();
    result
}

/// The servo drops logged so far: a count is worth a log text at the first
/// drop, then at each doubling of the count last logged. One for the
/// control task's own port, one for the avionics thread's.
#[derive(Debug, Default)]
struct DropLog {
    /// The count last logged (0: none yet).
    logged: u64,
}

impl DropLog {
    /// The record of `dropped` frames so far, stamped `t_s()`, when the
    /// count is worth a text (then taken as logged). No allocation.
    fn record(&mut self, dropped: u64, t_s: impl FnOnce() -> f64) -> Option<FlightRecord> {
        let worth =
            dropped > self.logged && (self.logged == 0 || dropped.ilog2() > self.logged.ilog2());
        worth.then(|| {
            self.logged = dropped;
            FlightRecord::ServoDropped {
                t_s: t_s(),
                dropped,
            }
        })
    }
}

fn logger_loop<W: Write>(
    mut log: FlightLog<W>,
    mut ring: rtrb::Consumer<FlightRecord>,
    mut watchdog: rtrb::Consumer<FlightRecord>,
    stop: &AtomicBool,
) -> ThreadResult {
    let mut result = ThreadResult::default();
    loop {
        let stopping = stop.load(Ordering::SeqCst);
        let mut any = false;
        for r in [&mut ring, &mut watchdog] {
            while let Ok(rec) = r.pop() {
                any = true;
                if let Err(e) = write_record(&mut log, &rec) {
                    result.log_dropped += 1;
                    result.error.get_or_insert(e.to_string());
                }
            }
        }
        if stopping && !any {
            break;
        }
        if !any {
            thread::park_timeout(LOG_POLL);
        }
    }
    if let Err(e) = log.finish() {
        result.error.get_or_insert(e.to_string());
    }
    result
}

#[cfg(test)]
mod tests {
    use super::{Arrival, DropLog, carry_over};
    use crate::records::FlightRecord;
    use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame};
    use nalgebra::Vector3;

    fn arrival(t_s: f64, gps: bool, mag: bool) -> Arrival {
        let imu = ImuSample {
            specific_force_body_m_s2: Vector3::new(0.0, 0.0, -9.81),
            gyro_body_rad_s: Vector3::zeros(),
        };
        let mut frame = SensorFrame::imu_only(t_s, imu);
        if gps {
            frame.gps = Some(GpsFix {
                epoch_s: t_s,
                fix: GpsFixType::Fix3d,
                position_ned_m: Vector3::new(t_s, 0.0, 0.0),
                velocity_ned_m_s: None,
            });
        }
        if mag {
            frame.mag_body = Some(Vector3::new(t_s, 0.0, 0.0));
        }
        Arrival {
            frame: Some(frame),
            arrived_ns: 0,
            rc: None,
            gps_quality: None,
            device: None,
        }
    }

    /// A late control step keeps the newest IMU sample and the GPS fix and
    /// magnetometer sample of the frames it superseded; the newer frame's
    /// own measurements win.
    #[test]
    fn a_superseded_frame_gives_its_fix_to_the_newer_one() {
        let mut newer = arrival(0.0025, false, false);
        carry_over(arrival(0.0, true, true), &mut newer);
        let f = newer.frame.unwrap();
        assert_eq!(f.t_s, 0.0025);
        assert_eq!(f.gps.unwrap().position_ned_m.x, 0.0);
        assert_eq!(f.mag_body.unwrap().x, 0.0);
        let mut own = arrival(0.005, true, true);
        carry_over(arrival(0.0, true, true), &mut own);
        let f = own.frame.unwrap();
        assert_eq!(f.gps.unwrap().position_ned_m.x, 0.005);
        assert_eq!(f.mag_body.unwrap().x, 0.005);
    }

    /// Servo drops are logged at the first and at each doubling (the powers
    /// of two up to 40), stamped with the time given.
    #[test]
    fn servo_drops_are_logged_at_the_first_and_each_doubling() {
        let mut log = DropLog::default();
        let mut at = Vec::new();
        for n in 0..=40u64 {
            if let Some(r) = log.record(n, || n as f64) {
                assert!(
                    matches!(r, FlightRecord::ServoDropped { t_s, dropped } if dropped == n && t_s == n as f64),
                    "{r:?}"
                );
                at.push(n);
            }
        }
        assert_eq!(at, vec![1, 2, 4, 8, 16, 32]);
    }
}
