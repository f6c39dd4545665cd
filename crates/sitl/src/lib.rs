//! # helicon-sitl
//!
//! Software in the loop: the simulator plays the helicopter's hardware
//! (plant, wind, sensor models: `helicon_sim::closed_loop::Hardware`) and
//! speaks the devices' byte protocols on pseudo-terminals; the on-board
//! program (`helicon_flight::runtime`) opens the pty slave paths exactly as
//! it would open `/dev/ttyS*`, reads them through its drivers
//! (`helicon_flight::ports`), and its servo frames drive the plant. The
//! simulator stands in for the drivers' devices, never inside the flight
//! stack: this crate depends on both, and neither on it.
//!
//! Per control period the hardware writes, in this order: a receiver frame
//! (every 8th period, 50 Hz), the GPS receiver's NAV-PVT when a fix is
//! delivered, the IMU's VN-100 packet (with the magnetometer when sampled).
//!
//! - [`Speed::Max`], lock-step: the hardware then waits for the servo frame
//!   of that sample before stepping the plant; the control task is paced
//!   by IMU arrival. Deterministic and as fast as the machine allows.
//! - [`Speed::Realtime`]: the hardware runs on the wall clock (absolute
//!   deadlines) and the plant takes the newest servo frame at each period's
//!   end; the control task runs on its own 400 Hz clock.
//!
//! The on-board side is aligned on the ground to the simulator's initial
//! state (as `helicon sim` aligns its navigation), armed, and flies the
//! scenario's references (the ground station's mission uplink).

pub mod ardupilot;
pub mod lockstep;
pub mod log_parts;
pub mod px4;
pub(crate) mod swash;

use helicon_core::SensorFrame;
use helicon_core::state::Input;
use helicon_devices::avionics::{AvionicsMessage, RcInput as RcFrame};
use helicon_devices::{AvionicsDecoder, Geodetic, LocalNed, NavPvt, PtyPair, VnCommon};
use helicon_flight::config::{FailsafeConfig, RcConfig, RealtimeConfig, StaleLimits};
use helicon_flight::control::{ControlTask, StepReport};
use helicon_flight::ground;
use helicon_flight::landing::{Landing, LandingConfig};
use helicon_flight::mission::{Mission, References};
use helicon_flight::plausibility::{PlausibilityConfig, SensorGate};
use helicon_flight::ports::{DeviceSensors, avionics_ports, open_port, stick_us};
use helicon_flight::runtime::{self, Pacing, RunReport, RuntimeOptions};
use helicon_flight::safety::Supervisor;
use helicon_gcs::config::GcsSection;
use helicon_sim::closed_loop::{
    ClosedLoopError, Hardware, Prepared, Summary, Termination, flight_computer, imu_health_at,
};
use helicon_sim::excitation::Excitations;
use helicon_sim::log_csv::{LogCsvError, LogWriter};
use helicon_sim::scenario::Scenario;
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How fast the simulator runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Speed {
    /// Lock-step, as fast as the machine allows.
    Max,
    /// The wall clock.
    Realtime,
}

/// Faults injected by the hardware side.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Faults {
    /// The GPS receiver stops delivering from this time on (s).
    pub gps_lost_from_s: Option<f64>,
    /// The IMU repeats its last packet (its time does not advance) over
    /// this interval (s).
    pub imu_frozen_s: Option<(f64, f64)>,
    /// Over this interval (s) every tenth IMU packet repeats the one
    /// before (its time does not advance): the on-board program steps
    /// without a fresh sample one step in ten, as a real-time reader that
    /// falls behind now and then (never long enough for the stale limit).
    pub imu_stutter_s: Option<(f64, f64)>,
    /// The GPS receiver reports no fix over this interval (s): NAV-PVT
    /// messages with a valid checksum, fix type 0 and no valid-fix flag.
    pub gps_no_fix_s: Option<(f64, f64)>,
    /// One glitching fix, the first at or after this time (s): 10 km
    /// north, 5 km up, at 300 m/s north (a valid checksum).
    pub gps_glitch_at_s: Option<f64>,
    /// The GPS line hangs up at this time (s): the pseudo-terminal's
    /// master closes, the device is gone for the rest of the run.
    pub gps_hangup_at_s: Option<f64>,
    /// IMU samples of 3e38 m/s² along body x over this interval (s): finite,
    /// beyond any accelerometer's range.
    pub imu_absurd_s: Option<(f64, f64)>,
    /// A 3e38-gauss magnetic field over this interval (s).
    pub mag_absurd_s: Option<(f64, f64)>,
    /// Receiver frames with every channel at 65535 µs, and 0 µs every other
    /// frame, over this interval (s).
    pub rc_wild_s: Option<(f64, f64)>,
}

/// Whether `t` (s) is in the interval `span` (s), start included.
fn within(span: Option<(f64, f64)>, t: f64) -> bool {
    span.is_some_and(|(a, b)| t >= a && t < b)
}

/// The pilot's receiver.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pilot {
    /// The pilot's switch goes to manual at this time (s), the sticks at
    /// the trim plus [`Pilot::stick_offset`].
    pub manual_from_s: Option<f64>,
    /// The pilot's switch goes back to auto at this time (s).
    pub manual_until_s: Option<f64>,
    /// The sticks' offset from the trim (servo units).
    pub stick_offset: Input,
    /// The receiver is in failsafe over this interval (s): it lost the
    /// transmitter and sends its failsafe values (sticks centred, the
    /// pilot's switch at manual, the arm switch off), flagged.
    pub rc_failsafe_s: Option<(f64, f64)>,
    /// The receiver is silent over this interval (s): no frames at all (a
    /// cut cable, the avionics board resetting).
    pub rc_silent_s: Option<(f64, f64)>,
}

/// A SITL run's settings.
#[derive(Debug, Clone)]
pub struct SitlOptions {
    /// Lock-step or wall clock.
    pub speed: Speed,
    /// Output folder (`flight.ulg`, `log.csv`, `timing.json`).
    pub out_dir: PathBuf,
    /// Injected faults.
    pub faults: Faults,
    /// The pilot.
    pub pilot: Pilot,
    /// Stale limits.
    pub stale: StaleLimits,
    /// Failsafes.
    pub failsafe: FailsafeConfig,
    /// Real-time options of the on-board side (real-time speed only).
    pub realtime: RealtimeConfig,
    /// Keep every sensor frame the hardware sent and every servo command
    /// the plant received ([`SitlResult::sent`], [`SitlResult::received`]):
    /// memory grows with the flight, off for a run until stopped.
    pub keep_frames: bool,
    /// Fly with the ground station: the MAVLink server at this address
    /// (`udpout:HOST:PORT`, `udpin:HOST:PORT`, `tcpin:HOST:PORT`, or several
    /// comma-separated). The on-board side then
    /// starts disarmed, the simulated receiver stays silent (the ground
    /// station is the only link) and the navigator gives the references:
    /// the scenario's `[[reference]]` are not flown.
    pub gcs: Option<String>,
    /// Write every n-th kept row of `log.csv` (and the last): the truth log
    /// at a lower rate (1: every row; the summary uses every row).
    pub log_stride: usize,
    /// Each log file at most this many bytes: `flight.ulg` and `log.csv`
    /// go on in numbered parts ([`log_parts`]: `flight-0002.ulg`,
    /// `log-0002.csv`, …) when it is reached, the run carrying on (a run
    /// until stopped). `None`: one file each, unbounded.
    pub log_part_bytes: Option<u64>,
    /// Checked once per sample: once set, the run ends after the sample
    /// being flown, its files written as at a normal end and its summary
    /// [`Termination::Stopped`] (a signal handler's flag).
    pub stop: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// Set to the simulated time of each sample as it is flown (s, stored
    /// as `f64::to_bits`): what a status line shows of a running flight.
    pub clock: Option<std::sync::Arc<std::sync::atomic::AtomicU64>>,
}

/// How far under [`SitlOptions::log_part_bytes`] `log.csv`'s next part
/// begins (bytes): the writer's 64 KiB buffer not yet on the disk and the 64
/// rows (at most 2 KiB each) until the size is looked at again.
pub const CSV_PART_MARGIN_BYTES: u64 = 64 * 1024 + 64 * 2048;

/// Lock-step: how long the simulator waits at most for a line's bytes to
/// reach the on-board side before it writes the IMU's message
/// ([`PtyPair::wait_delivered`]; microseconds normally).
const DELIVERY_WAIT: Duration = Duration::from_millis(20);

/// The home of the local NED frame (the GPS receiver's WGS-84 position of
/// the origin): a field near Aalborg.
pub const HOME: (f64, f64, f64) = (57.0146, 9.9869, 20.0);

/// GPS time of week at t = 0 (s): Wednesday 00:00.
pub const TOW0_S: f64 = 259_200.0;

/// What a SITL run produced.
#[derive(Debug)]
pub struct SitlResult {
    /// The flight summary (as `helicon sim` writes it).
    pub summary: Summary,
    /// The on-board runtime's report.
    pub onboard: RunReport,
    /// Control periods flown.
    pub samples: u64,
    /// The control period (s).
    pub sample_time_s: f64,
    /// Wall time of the flight (s).
    pub wall_s: f64,
    /// Simulated time per wall time.
    pub speed_x: f64,
    /// CPU time of the process (both sides, all threads) during the flight (s).
    pub cpu_s: f64,
    /// Wall time the simulated hardware spent waiting for the on-board
    /// program's servo frames (s; lock-step): the on-board step and the
    /// transport both ways. The rest of [`SitlResult::wall_s`] is the
    /// hardware's own work.
    pub servo_wait_s: f64,
    /// The frames the hardware sent (when kept), in order.
    pub sent: Vec<SensorFrame>,
    /// The servo commands the plant received, in order (when kept).
    pub received: Vec<Input>,
    /// The on-board log (its first part).
    pub ulog: PathBuf,
    /// The on-board log's parts ([`SitlOptions::log_part_bytes`]; 1: the
    /// one file).
    pub ulog_parts: u32,
    /// The truth log (its first part).
    pub log_csv: PathBuf,
    /// The truth log's parts.
    pub log_csv_parts: u32,
    /// Its rows (all parts).
    pub log_rows: usize,
    /// The true state at the end of the flight (the simulator's frame).
    pub final_state: helicon_model::State,
    /// The true state at the start.
    pub initial_state: helicon_model::State,
}

/// Errors of a SITL run (a divergence is an outcome, not an error).
#[derive(Debug, thiserror::Error)]
pub enum SitlError {
    /// Preparing the scenario or the flight software.
    #[error(transparent)]
    Prepare(#[from] ClosedLoopError),
    /// Building the flight software.
    #[error(transparent)]
    Build(#[from] helicon_setup::BuildError),
    /// A configuration value the flight software cannot use.
    #[error(transparent)]
    Config(#[from] helicon_config::ConfigError),
    /// A pseudo-terminal or device.
    #[error("{0}")]
    Device(String),
    /// The on-board log.
    #[error("{path}: {message}")]
    Log {
        /// The file.
        path: String,
        /// What failed.
        message: String,
    },
    /// The truth log.
    #[error(transparent)]
    Csv(#[from] LogCsvError),
    /// The on-board program stopped answering.
    #[error("the on-board program sent no servo frame for sample {k} within {timeout_s} s")]
    Silent {
        /// The sample.
        k: usize,
        /// The wait (s).
        timeout_s: f64,
    },
}

fn dev<E: std::fmt::Display>(what: &str) -> impl FnOnce(E) -> SitlError + '_ {
    move |e| SitlError::Device(format!("{what}: {e}"))
}

/// The hardware's three devices on pseudo-terminals.
struct Wires {
    imu: PtyPair,
    gps: PtyPair,
    avionics: PtyPair,
}

/// Fly `scenario` (prepared) under SITL.
#[allow(clippy::too_many_lines)] // one loop: sense, speak, wait, step, log
pub fn run(
    scenario: &Scenario,
    prepared: &Prepared,
    options: &SitlOptions,
) -> Result<SitlResult, SitlError> {
    std::fs::create_dir_all(&options.out_dir).map_err(|e| SitlError::Log {
        path: options.out_dir.display().to_string(),
        message: format!("cannot create: {e}"),
    })?;
    let mut hw = Hardware::new(scenario, prepared)?;
    if options.gcs.is_some() {
        // the navigator gives the references, not the scenario
        hw = hw.without_heading_check();
    }
    let ts = hw.sample_time_s();
    let x0 = *hw.state();
    let p = prepared.model.params();
    let on_ground = scenario.ground.is_some_and(|g| g.on_ground);
    // home is where the helicopter stands: starting on the ground, the
    // on-board side's origin (its GPS home, the navigator's) is the ground
    // below the simulator's origin (the design point, in the air)
    let ground_down_m = if on_ground {
        p.landing_gear.ground_down_m
    } else {
        0.0
    };
    let mut x0_onboard = x0;
    x0_onboard[helicon_model::state::ix::Z] -= ground_down_m;
    let computer = flight_computer(&prepared.onboard_setup(scenario, &x0_onboard))?;
    let u_trim = prepared.gains.set.u_trim;
    let mut supervisor = Supervisor::new(options.stale, options.failsafe, 0.0);
    let home_geo = Geodetic::new(HOME.0, HOME.1, HOME.2).map_err(dev("home"))?;
    // (the origin itself in the air: bit for bit, no round trip)
    let onboard_home_geo = if on_ground {
        LocalNed::new(home_geo).to_geodetic(&nalgebra::Vector3::new(0.0, 0.0, ground_down_m))
    } else {
        home_geo
    };

    let mut wires = Wires {
        imu: PtyPair::open().map_err(dev("IMU pseudo-terminal"))?,
        gps: PtyPair::open().map_err(dev("GPS pseudo-terminal"))?,
        avionics: PtyPair::open().map_err(dev("avionics pseudo-terminal"))?,
    };
    let home = LocalNed::new(home_geo);
    // the on-board side opens the slave paths as its serial devices
    let imu_port = open_port(wires.imu.slave_path(), 921_600).map_err(dev("IMU"))?;
    let gps_port = open_port(wires.gps.slave_path(), 115_200).map_err(dev("GPS"))?;
    let av_port = open_port(wires.avionics.slave_path(), 115_200).map_err(dev("avionics"))?;
    let (rc_port, servo_port) =
        avionics_ports(av_port, RcConfig::default()).map_err(dev("avionics"))?;
    let sensors = DeviceSensors::new(
        imu_port,
        gps_port,
        LocalNed::new(onboard_home_geo),
        scenario.sensors.gps.latency_s,
    );
    let lockstep = options.speed == Speed::Max;
    // lock-step: the sensor server reads the receiver too (deterministic);
    // real time: the receiver has its own thread, as on board
    let (sensors, receiver) = if lockstep {
        (sensors.with_receiver(rc_port), None)
    } else {
        (sensors, Some(rc_port))
    };
    // the run folder's own log: a run flown again into its folder replaces it
    let ulog = options.out_dir.join("flight.ulg");
    let gcs_section = options.gcs.as_ref().map(|address| GcsSection {
        address: address.clone(),
        ..GcsSection::default()
    });
    let info = sitl_log_info(scenario, ts, gcs_section.as_ref(), onboard_home_geo)?;
    let log_err = |path: &Path, e: &dyn std::fmt::Display| SitlError::Log {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let log_csv = options.out_dir.join("log.csv");
    // the parts of an earlier run into this folder go: this run's are its own
    for first in [&ulog, &log_csv] {
        for n in 2.. {
            let p = log_parts::part_path(first, n);
            if std::fs::remove_file(&p).is_err() {
                break;
            }
        }
    }
    let part_bytes = options.log_part_bytes.unwrap_or(u64::MAX);
    let sink = log_parts::UlogParts::create(&ulog, part_bytes).map_err(|e| log_err(&ulog, &e))?;
    let log =
        FlightLog::new(sink, &info, FlushPolicy::default()).map_err(|e| log_err(&ulog, &e))?;
    let (downlink_tx, mut downlink) = rtrb::RingBuffer::new(1024);
    let realtime = if lockstep {
        RealtimeConfig {
            sched_fifo: false,
            priority: options.realtime.priority,
            mlockall: false,
        }
    } else {
        options.realtime
    };
    // the ground station arms; without one SITL starts armed, as a pilot
    // arms on the ground
    let (mission, server) = match &gcs_section {
        Some(section) => {
            let (m, server) = ground::start(section, onboard_home_geo, "--gcs", ts)
                .map_err(dev("ground station"))?;
            (m, Some(server))
        }
        None => {
            supervisor.arm();
            (
                Mission::new(References::Schedule(Box::new(
                    scenario.reference_schedule(),
                ))),
                None,
            )
        }
    };
    // the scenario's flight-test inputs, flown on board
    let mission = mission.with_excitation(
        Excitations::new(&scenario.excitation, &scenario.name).map_err(ClosedLoopError::from)?,
    );
    let mut task = ControlTask::new(computer, supervisor, u_trim)
        .with_imu_health(imu_health_at(
            p.environment.g_m_s2,
            ts,
            &scenario.sensors,
            &scenario.name,
        )?)
        .with_gate(SensorGate::new(
            &PlausibilityConfig::default(),
            &scenario.sensors,
            &scenario.name,
        )?)
        .with_servo_limits(p.servo_limits());
    if on_ground {
        // from the ground to the ground: the on-board ground logic flies
        task = task.with_landing(Landing::new(LandingConfig::default(), ts, &u_trim, 0.0));
    }
    let handle = runtime::spawn(
        task,
        mission,
        sensors,
        receiver,
        servo_port,
        log,
        Some(downlink_tx),
        RuntimeOptions {
            sample_time_s: ts,
            pacing: if lockstep {
                Pacing::Sensor
            } else {
                Pacing::Clock
            },
            max_steps: None,
            realtime,
            watchdog_s: 0.1,
            u_trim,
        },
    );

    // real time: the hardware is a real-time task too (devices keep their
    // rate), one priority above the on-board control task
    if !lockstep
        && options.realtime.sched_fifo
        && let Err(e) =
            helicon_flight::realtime::set_fifo(options.realtime.priority.saturating_add(1).min(99))
    {
        eprintln!("warning: SCHED_FIFO for the simulated hardware not permitted ({e})");
    }
    let mut writer = LogWriter::create(&log_csv)?.with_stride(options.log_stride);
    let mut csv_part = 1u32;
    let mut csv_rows_before = 0usize;
    let mut kept_in_part = 0u64;
    let mut servo_in = wires.avionics.try_clone_master().map_err(dev("avionics"))?;
    let mut decoder = AvionicsDecoder::new();
    let mut buf = [0u8; 256];
    let mut u = u_trim;
    let mut last_vn: Option<VnCommon> = None;
    let mut rc_seq = 0u8;
    let mut gps_up = true;
    let mut glitched = false;
    let mut sent = Vec::new();
    // (a long run grows it: at most ten minutes up front)
    let mut received = if options.keep_frames {
        Vec::with_capacity(hw.samples().min(240_000))
    } else {
        Vec::new()
    };
    let mut samples = 0u64;
    let mut last_report: Option<StepReport> = None;
    let mut servo_wait_s = 0.0;
    let timeout = Duration::from_secs(10);
    let t0 = helicon_flight::realtime::monotonic_ns();
    let wall0 = Instant::now();
    let cpu0 = helicon_flight::realtime::process_cpu_s();
    let mut failure = None;
    while let Some(s) = hw.sense() {
        let t = s.t_s;
        if let Some(c) = &options.clock {
            c.store(t.to_bits(), std::sync::atomic::Ordering::Relaxed);
        }
        // the receiver at 50 Hz (silent when the ground station flies)
        let silent = options
            .pilot
            .rc_silent_s
            .is_some_and(|(a, b)| t >= a && t < b);
        let wrote_rc = s.k % 8 == 0 && server.is_none() && !silent;
        if wrote_rc {
            let pilot = &options.pilot;
            let manual = pilot.manual_from_s.is_some_and(|m| t >= m)
                && pilot.manual_until_s.is_none_or(|m| t < m);
            let failsafe = within(pilot.rc_failsafe_s, t);
            let mut channels_us = [1500u16; 8];
            for i in 0..4 {
                channels_us[i] = stick_us(u_trim[i] + pilot.stick_offset[i]);
            }
            channels_us[4] = 2000; // armed
            if failsafe {
                channels_us = [1500u16; 8];
                channels_us[4] = 1000;
            }
            if within(options.faults.rc_wild_s, t) {
                channels_us = [if s.k % 16 == 0 { 65535 } else { 0 }; 8];
            }
            let frame = RcFrame {
                seq: rc_seq,
                autonomous: !manual && !failsafe,
                failsafe,
                channels_us,
                ..RcFrame::default()
            };
            rc_seq = rc_seq.wrapping_add(1);
            wires
                .avionics
                .write_all(frame.encode().as_bytes())
                .map_err(dev("avionics"))?;
        }
        // the GPS receiver
        let gps_on = options
            .faults
            .gps_lost_from_s
            .is_none_or(|t_loss| t < t_loss);
        if gps_up && options.faults.gps_hangup_at_s.is_some_and(|h| t >= h) {
            // the line hangs up: the master closes, the slave's path goes
            wires.gps = PtyPair::open().map_err(dev("GPS pseudo-terminal"))?;
            gps_up = false;
        }
        let wrote_gps = s.frame.gps.is_some() && gps_on && gps_up;
        if let (Some(fix), true, true) = (&s.frame.gps, gps_on, gps_up) {
            let itow_ms = ((TOW0_S + fix.epoch_s) * 1000.0).round() as u32;
            let mut fix = *fix;
            if !glitched && options.faults.gps_glitch_at_s.is_some_and(|g| t >= g) {
                glitched = true;
                fix.position_ned_m = nalgebra::Vector3::new(10_000.0, 0.0, -5_000.0);
                fix.velocity_ned_m_s = Some(nalgebra::Vector3::new(300.0, 0.0, 0.0));
            }
            let mut pvt =
                NavPvt::from_gps_fix(&fix, &home, itow_ms, 0.0).map_err(dev("GPS encoding"))?;
            if within(options.faults.gps_no_fix_s, t) {
                pvt.fix_type = 0;
                pvt.flags = 0;
            }
            wires
                .gps
                .write_all(pvt.encode().as_bytes())
                .map_err(dev("GPS"))?;
        }
        // lock-step: the receiver's and the GPS's bytes reach their lines
        // before the IMU's message (the kernel moves them after the write
        // returns; a reader that polls would otherwise find them a sample
        // late, and the run would not be the same twice)
        if lockstep {
            for (wrote, wire) in [(wrote_rc, &wires.avionics), (wrote_gps, &wires.gps)] {
                if wrote {
                    // looked at without sleeping first (the kernel's worker
                    // moves them within microseconds), then waited for
                    let looked = helicon_flight::realtime::spin_for(
                        helicon_flight::realtime::LOCKSTEP_SPIN,
                        || match wire.wait_delivered(Duration::ZERO) {
                            Ok(false) => None,
                            r => Some(r),
                        },
                    );
                    match looked {
                        Some(r) => r,
                        None => wire.wait_delivered(DELIVERY_WAIT),
                    }
                    .map_err(dev("line"))?;
                }
            }
        }
        // the IMU (and magnetometer): last, it paces the on-board software
        let frozen = within(options.faults.imu_frozen_s, t)
            || (within(options.faults.imu_stutter_s, t) && s.k % 10 == 9);
        let vn = match (frozen, last_vn) {
            (true, Some(v)) => v,
            _ => {
                let mut imu = s.frame.imu;
                if within(options.faults.imu_absurd_s, t) {
                    imu.specific_force_body_m_s2.x = 3e38;
                }
                let absurd = nalgebra::Vector3::new(3e38, 0.0, 0.0);
                let mag = if within(options.faults.mag_absurd_s, t) {
                    s.frame.mag_body.map(|_| absurd)
                } else {
                    s.frame.mag_body
                };
                VnCommon::from_samples(t, &imu, mag.as_ref()).map_err(dev("IMU encoding"))?
            }
        };
        last_vn = Some(vn);
        let bytes = vn.encode().map_err(dev("IMU encoding"))?;
        wires.imu.write_all(bytes.as_bytes()).map_err(dev("IMU"))?;
        if options.keep_frames {
            sent.push(s.frame);
        }
        // the servo frame
        if lockstep {
            let start = Instant::now();
            let mut got = None;
            // the on-board step takes microseconds: the line is polled a
            // little before the wait blocks (no wake-up from sleep per sample)
            while got.is_none() {
                if start.elapsed() > timeout {
                    failure = Some(SitlError::Silent {
                        k: s.k,
                        timeout_s: timeout.as_secs_f64(),
                    });
                    break;
                }
                let polled = helicon_flight::realtime::spin_for(
                    helicon_flight::realtime::LOCKSTEP_SPIN.saturating_sub(start.elapsed()),
                    || match helicon_devices::transport::read_with_timeout(
                        &mut servo_in,
                        &mut buf,
                        Duration::ZERO,
                    ) {
                        Ok(0) => None,
                        r => Some(r),
                    },
                );
                let n = match polled {
                    Some(r) => r,
                    None => helicon_devices::transport::read_with_timeout(
                        &mut servo_in,
                        &mut buf,
                        Duration::from_millis(100),
                    ),
                }
                .map_err(dev("avionics"))?;
                decoder.push_with(&buf[..n], |m| {
                    if let AvionicsMessage::Servo(c) = m {
                        got = Some((c.inputs(), c.throttle_hold));
                    }
                });
            }
            servo_wait_s += start.elapsed().as_secs_f64();
            match got {
                Some((v, hold)) => {
                    u = v;
                    hw.set_throttle_hold(hold);
                }
                None => break,
            }
        } else {
            let deadline = t0 + ((s.k + 1) as f64 * ts * 1e9) as u64;
            helicon_flight::realtime::sleep_until_ns(deadline);
            loop {
                let n = helicon_devices::transport::read_with_timeout(
                    &mut servo_in,
                    &mut buf,
                    Duration::ZERO,
                )
                .map_err(dev("avionics"))?;
                if n == 0 {
                    break;
                }
                let mut hold = None;
                decoder.push_with(&buf[..n], |m| {
                    if let AvionicsMessage::Servo(c) = m {
                        u = c.inputs();
                        hold = Some(c.throttle_hold);
                    }
                });
                if let Some(h) = hold {
                    hw.set_throttle_hold(h);
                }
            }
        }
        // the telemetry of this sample (lock-step: pushed before its servo
        // frame). A period without a report of its own (in real time the
        // on-board step late; a step without a fresh sample computes none)
        // logs the newest one the link had, as a ground station shows the
        // last telemetry: not zeros, which the estimate columns would show
        // as a false estimate of 0
        let mut report: Option<StepReport> = None;
        while let Ok(x) = downlink.pop() {
            if report.is_none_or(|r| x.telemetry.sample >= r.telemetry.sample) {
                report = Some(x);
            }
            if lockstep {
                break;
            }
        }
        if report.is_some() {
            last_report = report;
        } else {
            report = last_report;
        }
        if options.keep_frames {
            received.push(u);
        }
        samples += 1;
        let Some(mut step) = hw.actuate(&u, report.as_ref().map(|r| &r.telemetry)) else {
            break;
        };
        // the flight software's own columns, as `helicon sim` fills them
        if let Some(r) = &report {
            step.row.excitation = r.excitation.into();
            if let Some(h) = &r.imu_health {
                step.row.imu_health = [
                    h.vibration_rms_m_s2,
                    h.gravity_residual_m_s2,
                    f64::from(h.flags),
                ];
            }
        }
        if step.kept {
            writer.write(&step.row)?;
            kept_in_part += 1;
            // the part's size looked at every 64 kept rows: its next part
            // begins CSV_PART_MARGIN_BYTES under the bound (the writer's
            // buffer and the rows until the next look)
            if let Some(max) = options.log_part_bytes
                && kept_in_part % 64 == 0
                && std::fs::metadata(log_parts::part_path(&log_csv, csv_part))
                    .is_ok_and(|m| m.len() + CSV_PART_MARGIN_BYTES >= max)
            {
                csv_part += 1;
                let next = LogWriter::create(&log_parts::part_path(&log_csv, csv_part))?
                    .with_stride(options.log_stride);
                csv_rows_before += std::mem::replace(&mut writer, next).finish()?;
                kept_in_part = 0;
            }
        }
        if step.end.is_some() {
            break;
        }
        if options
            .stop
            .as_ref()
            .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
        {
            hw.abort(
                Termination::Stopped,
                format!("stopped on request at t = {t:.3} s"),
            );
            break;
        }
    }
    let wall_s = wall0.elapsed().as_secs_f64();
    let cpu_s = helicon_flight::realtime::process_cpu_s() - cpu0;
    handle.stop();
    let onboard = handle.join();
    if let Some(server) = server {
        server.stop();
    }
    let log_rows = csv_rows_before + writer.finish()?;
    let ulog_parts = (1..)
        .take_while(|&n| log_parts::part_path(&ulog, n).exists())
        .count() as u32;
    if let Some(e) = failure {
        return Err(e);
    }
    if let Some(e) = &onboard.error {
        hw.abort(
            Termination::NavigationFailure,
            format!("on-board program: {e}"),
        );
    }
    let summary = hw.summary();
    let sim_s = samples as f64 * ts;
    Ok(SitlResult {
        summary,
        onboard,
        samples,
        sample_time_s: ts,
        wall_s,
        speed_x: if wall_s > 0.0 { sim_s / wall_s } else { 0.0 },
        cpu_s,
        servo_wait_s,
        sent,
        received,
        ulog,
        ulog_parts,
        log_csv,
        log_csv_parts: csv_part,
        log_rows,
        final_state: *hw.state(),
        initial_state: x0,
    })
}

/// Ground height below the simulator's origin (m) when [`ground_start`]
/// puts a scenario on the ground: the design point (the trim, in the air)
/// stays where it was, 5 m above the skids' ground.
pub const GROUND_START_DOWN_M: f64 = 5.0;

/// `scenario` put on the ground, as `helicon sitl --gcs` flies it: its
/// parameters with the landing gear (the ground [`GROUND_START_DOWN_M`]
/// below the origin unless the parameters place it), the drivetrain and the
/// ground effect on, and a `[ground]` section starting on the skids, rotor
/// stopped. A scenario that already starts on the ground is returned as it
/// is. The operator times of `[ground]` (`spool_up_s`, `takeoff_s`: the
/// arming and the switch to auto that `helicon sim` plays) are not used by
/// SITL: its receiver or ground station arms, and the on-board ground logic
/// (the same `helicon sim` flies) takes off and lands.
pub fn ground_start(scenario: &Scenario) -> Result<(Scenario, helicon_model::Params), SitlError> {
    let mut params = helicon_sim::closed_loop::scenario_params(scenario)?;
    let mut s = scenario.clone();
    if s.ground.is_some_and(|g| g.on_ground) {
        return Ok((s, params));
    }
    let gear = &mut params.landing_gear;
    if !gear.is_enabled() {
        gear.enabled = 1.0;
    }
    if gear.ground_down_m <= gear.contact_z_m + 1.0 {
        gear.ground_down_m = GROUND_START_DOWN_M;
    }
    params.ground_effect.enabled = 1.0;
    params.drivetrain.enabled = 1.0;
    s.ground = Some(helicon_sim::ground::GroundSection {
        on_ground: true,
        spool_up_s: 0.0,
        takeoff_s: 0.0,
        ramp_s: 2.0_f64.min(s.duration_s.max(1e-3)),
        land_after_s: 0.0,
        shutdown_delay_s: 0.0,
    });
    Ok((s, params))
}

impl SitlResult {
    /// The control period flown (s).
    pub fn onboard_sample_time_s(&self) -> f64 {
        self.sample_time_s
    }
}

/// The flight log's identification, home, control period and initial
/// parameters of a SITL run of `scenario` at the control period `ts` (with
/// the ground station `gcs`, its parameter table; `home` the on-board
/// side's origin). Deterministic: no clock,
/// no machine id, so a lock-step run's log is the same bytes every time.
fn sitl_log_info(
    scenario: &Scenario,
    ts: f64,
    gcs: Option<&GcsSection>,
    home: Geodetic,
) -> Result<LogInfo, SitlError> {
    let table = match gcs {
        Some(section) => {
            ground::initial_parameters(section, home, "--gcs").map_err(dev("ground station"))?
        }
        None => Vec::new(),
    };
    Ok(LogInfo {
        sys_name: format!("helicon sitl {}", scenario.name),
        ver_hw: "HELICON_SITL".to_string(),
        sys_uuid: format!("helicon-sitl-{}", scenario.name),
        home: Some(home),
        control_period_us: Some((ts * 1e6).round() as u64),
        parameters: helicon_flight::records::log_parameters(ts, &table),
        ..LogInfo::default()
    })
}

/// The estimated size (bytes) of the on-board log `flight.ulg` that a SITL
/// run of `scenario` writes (the log the on-board program writes at its
/// full rate, never thinned): its header and definitions (exact: written
/// into memory), then per control period of `sample_time_s` the records of
/// one step (`sensor_imu`, `imu_health`, `control`, `navigation`,
/// `servo_output`, `timing`, and `estimator_bias` with the ESKF,
/// `excitation` with `[[excitation]]`), the magnetometer's and GPS's
/// records at their rates, the receiver's at 50 Hz (none with a ground
/// station, `gcs`), PX4's topics at their decimated rates
/// (`helicon_ulog::px4::bytes_per_s`) and a SYNC marker per flush. Events
/// and texts are not counted (a few per flight).
pub fn estimate_ulog_bytes(scenario: &Scenario, sample_time_s: f64, gcs: bool) -> u64 {
    use helicon_ulog::Record;
    use helicon_ulog::messages::{
        Control, EstimatorBias, Excitation, HeliconGps, HeliconMag, ImuHealth, Navigation, RcInput,
        SensorImu, ServoOutput, Timing,
    };
    // a data message: 3 bytes of header, 2 of message id, the record
    let msg = |size: usize| (size + 5) as f64;
    let mut step = msg(SensorImu::SIZE)
        + msg(ImuHealth::SIZE)
        + msg(Control::SIZE)
        + msg(Navigation::SIZE)
        + msg(ServoOutput::SIZE)
        + msg(Timing::SIZE);
    if scenario.estimator.kind == helicon_setup::estimator::EstimatorKind::Eskf {
        step += msg(EstimatorBias::SIZE);
    }
    if !scenario.excitation.is_empty() {
        step += msg(Excitation::SIZE);
    }
    let ts = sample_time_s.max(1e-6);
    let (mag_hz, gps_hz) = (scenario.sensors.mag.rate_hz, scenario.sensors.gps.rate_hz);
    let rc_hz = if gcs { 0.0 } else { 1.0 / (8.0 * ts) };
    let mut per_s = step / ts
        + msg(HeliconMag::SIZE) * mag_hz
        + msg(HeliconGps::SIZE) * gps_hz
        + msg(RcInput::SIZE) * rc_hz
        + helicon_ulog::px4::bytes_per_s(1.0 / ts, mag_hz, gps_hz, rc_hz);
    // a SYNC (11 bytes) per flush: every 0.1 s of log time, or 16 KiB
    let policy = FlushPolicy::default();
    let flushes_per_s =
        (1e6 / policy.interval_us.max(1) as f64).max(per_s / policy.max_bytes as f64);
    per_s += 11.0 * flushes_per_s;
    let gcs_section = gcs.then(GcsSection::default);
    let head = Geodetic::new(HOME.0, HOME.1, HOME.2)
        .map_err(dev("home"))
        .and_then(|home| sitl_log_info(scenario, ts, gcs_section.as_ref(), home))
        .ok()
        .and_then(|info| {
            FlightLog::new(Vec::new(), &info, policy)
                .and_then(FlightLog::finish)
                .ok()
        })
        .map_or(4096, |b| b.len() as u64);
    head + (per_s * scenario.duration_s.max(0.0)).round() as u64
}

/// `timing.json` of a SITL run.
pub fn timing_json(result: &SitlResult, speed: Speed) -> serde_json::Value {
    serde_json::json!({
        "speed": match speed { Speed::Max => "max", Speed::Realtime => "realtime" },
        "samples": result.samples,
        "wall_s": result.wall_s,
        "speed_x_realtime": result.speed_x,
        "cpu_s": result.cpu_s,
        "speed_x_realtime_per_cpu_s": if result.cpu_s > 0.0 { result.samples as f64 * result.onboard_sample_time_s() / result.cpu_s } else { 0.0 },
        "onboard": result.onboard,
    })
}

/// Write `timing.json` into `dir`.
pub fn write_timing(dir: &Path, value: &serde_json::Value) -> Result<PathBuf, SitlError> {
    let path = dir.join("timing.json");
    let text = serde_json::to_string_pretty(value).map_err(|e| SitlError::Log {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    std::fs::write(&path, text).map_err(|e| SitlError::Log {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    Ok(path)
}
