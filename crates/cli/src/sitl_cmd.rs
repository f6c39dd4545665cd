//! `helicon sitl SCENARIO.toml --out DIR [--speed max|realtime] [--duration S] [--gcs ADDRESS]`:
//! fly a scenario software-in-the-loop: the simulator plays the hardware on
//! pseudo-terminals, the on-board runtime flies it through its device
//! drivers. Writes the on-board `flight.ulg`, the truth `log.csv`,
//! `timing.json`, and the run folder of `helicon sim` (summary, gains,
//! scenario, plots, report). With `--gcs` the ground station's navigator
//! flies instead of the scenario's references. With `--ardupilot-json [ADDR]`
//! it is ArduPilot's JSON physics backend instead (`helicon_sitl::ardupilot`):
//! ArduPilot's SITL flies the model; `timing.json` and the run folder. With
//! `--px4 [ADDR]` it is PX4's simulator instead (`helicon_sitl::px4`): PX4's
//! SITL connects over TCP and flies the model lock-stepped.

use crate::console::{Console, SimStatus};
use crate::signals::{Stop, mark_stopped};
use crate::sim_cmd::{
    LogArgs, folder_name, human_bytes, overrides_from, overrides_label, plan_log, prepare_step,
};
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use helicon_flight::config::{FailsafeConfig, RealtimeConfig, StaleLimits};
use helicon_sim::output::finish_run;
use helicon_sim::scenario::{OUTPUTS, Scenario};
use helicon_sitl::{self as sitl, Faults, Pilot, SitlOptions, Speed};
use std::path::PathBuf;

/// How fast the simulator runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SpeedArg {
    /// Lock-step: each IMU sample waits for its servo frame; as fast as the CPU allows.
    Max,
    /// The wall clock: the on-board control task runs on its own 400 Hz clock.
    Realtime,
}

/// `helicon sitl`.
#[derive(Args, Debug)]
pub struct SitlArgs {
    /// Scenario file (TOML, as for `helicon sim`; the sensor models and the
    /// whole navigation always fly).
    pub scenario: PathBuf,
    /// Output folder (default `out/sitl-<scenario name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Lock-step (`max`) or wall clock (`realtime`).
    #[arg(long, value_enum, default_value = "max")]
    pub speed: SpeedArg,
    /// Flight duration in seconds (overrides the scenario's `duration_s`).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Real time: do not ask for SCHED_FIFO for the control task.
    #[arg(long)]
    pub no_sched_fifo: bool,
    /// Inject a GPS loss from this time on (s).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub gps_loss_at: Option<f64>,
    /// The pilot's switch goes to manual at this time (s).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub manual_at: Option<f64>,
    /// The pilot's switch goes back to auto at this time (s; with `--manual-at`).
    #[arg(
        long,
        value_name = "S",
        allow_negative_numbers = true,
        requires = "manual_at"
    )]
    pub manual_until: Option<f64>,
    /// The receiver loses the pilot's transmitter from this time on (s): its
    /// frames carry the failsafe flag.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub rc_failsafe_at: Option<f64>,
    /// The receiver goes silent from this time on (s): no frames at all (a
    /// cut cable); lost after the on-board `stale.rc_s` (0.5 s).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub rc_silent_at: Option<f64>,
    /// The receiver's frames come back at this time (s; with `--rc-silent-at`).
    #[arg(
        long,
        value_name = "S",
        allow_negative_numbers = true,
        requires = "rc_silent_at"
    )]
    pub rc_silent_until: Option<f64>,
    /// Fly with a ground station: start the MAVLink 2 server at
    /// `udpout:HOST:PORT` (it sends to the ground station listening there),
    /// `udpin:HOST:PORT` (it listens) or `tcpin:HOST:PORT` (it accepts up to
    /// 4 TCP clients, the convention is port 5760), or at a comma-separated
    /// list of them (`udpin:127.0.0.1:14550,tcpin:127.0.0.1:5760`). The
    /// helicopter then starts disarmed, the simulated receiver is silent,
    /// and the navigator flies what the operator commands (arm, takeoff, missions): the scenario's
    /// `[[reference]]` are ignored. The helicopter starts on the ground
    /// (landing gear, drivetrain and ground effect on when the scenario has
    /// no `[ground]`), disarmed, rotor stopped, and the run lasts until
    /// stopped (Ctrl-C) unless `--duration` is given: its logs then go on
    /// in numbered parts of at most `--max-log-bytes` each (`flight.ulg`,
    /// `flight-0002.ulg`, …; `log.csv`, `log-0002.csv`, …).
    #[arg(long, value_name = "ADDRESS", conflicts_with_all = ["manual_at", "rc_failsafe_at", "rc_silent_at"])]
    pub gcs: Option<String>,
    /// Be ArduPilot's JSON physics backend instead of flying helicon's
    /// on-board program: listen for ArduPilot SITL's servo packets on UDP
    /// `ADDR` (default 127.0.0.1:9002; start ArduPilot with `--model
    /// JSON:HOST`), step the model one frame per new frame count, answer
    /// its state. The helicopter starts on the ground, rotor stopped
    /// (landing gear, drivetrain, ground effect on), the engine from the
    /// throttle output; the run lasts until stopped (Ctrl-C), at most
    /// `--duration` (default 3600 s). See docs/ardupilot-px4.md.
    #[arg(
        long,
        value_name = "ADDR",
        num_args = 0..=1,
        default_missing_value = helicon_sitl::ardupilot::DEFAULT_ADDRESS,
        conflicts_with_all = ["gcs", "speed", "gps_loss_at", "manual_at", "rc_failsafe_at", "rc_silent_at", "no_sched_fifo"]
    )]
    pub ardupilot_json: Option<String>,
    /// The `[ardupilot]` mapping of ArduPilot's servo outputs (TOML; default
    /// the Bergen Twin's, `examples/ardupilot/bergen_twin.toml`).
    #[arg(long, value_name = "FILE", requires = "ardupilot_json")]
    pub ardupilot_config: Option<PathBuf>,
    /// Be PX4's simulator instead of flying helicon's on-board program:
    /// listen on TCP `ADDR` (default 127.0.0.1:4560) for PX4 SITL's
    /// `simulator_mavlink`, send HIL_SENSOR/HIL_GPS/HIL_STATE_QUATERNION,
    /// step the model one 4 ms sensor period per HIL_ACTUATOR_CONTROLS. The
    /// helicopter starts on the ground, rotor stopped; a reconnection (PX4
    /// restarted) starts it there again; the run lasts until stopped
    /// (Ctrl-C), at most `--duration` (default 3600 s). See
    /// docs/ardupilot-px4.md.
    #[arg(
        long,
        value_name = "ADDR",
        num_args = 0..=1,
        default_missing_value = helicon_sitl::px4::DEFAULT_ADDRESS,
        conflicts_with_all = ["ardupilot_json", "gcs", "speed", "gps_loss_at", "manual_at", "rc_failsafe_at", "rc_silent_at", "no_sched_fifo"]
    )]
    pub px4: Option<String>,
    /// The `[px4]` mapping of PX4's actuator outputs (TOML; default the
    /// Bergen Twin's, `examples/px4/bergen_twin.toml`).
    #[arg(long, value_name = "FILE", requires = "px4")]
    pub px4_config: Option<PathBuf>,
    #[command(flatten)]
    pub log: LogArgs,
}

fn check_time(flag: &str, v: Option<f64>) -> Result<()> {
    if let Some(t) = v
        && !(t.is_finite() && t >= 0.0)
    {
        anyhow::bail!("{flag} {t}: must be a finite time >= 0 s");
    }
    Ok(())
}

/// The fault and pilot times of `a` must fall inside a flight of
/// `duration_s` (`source` names the scenario), and each `--…-until` after
/// its `--…-at`: an event that can never happen is refused, not flown
/// without it.
fn check_events(a: &SitlArgs, duration_s: f64, source: &str) -> Result<()> {
    for (flag, v) in [
        ("--gps-loss-at", a.gps_loss_at),
        ("--manual-at", a.manual_at),
        ("--rc-failsafe-at", a.rc_failsafe_at),
        ("--rc-silent-at", a.rc_silent_at),
    ] {
        if let Some(t) = v
            && t >= duration_s
        {
            anyhow::bail!(
                "{flag} {t}: after the flight's end ({source}: {duration_s} s); use --duration for a longer flight"
            );
        }
    }
    for (at_flag, at, until_flag, until) in [
        ("--manual-at", a.manual_at, "--manual-until", a.manual_until),
        (
            "--rc-silent-at",
            a.rc_silent_at,
            "--rc-silent-until",
            a.rc_silent_until,
        ),
    ] {
        if let (Some(at), Some(until)) = (at, until)
            && until <= at
        {
            anyhow::bail!("{until_flag} {until}: must be after {at_flag} {at}");
        }
    }
    Ok(())
}

/// The stride of `log.csv` ([`plan_log`]), after refusing a run whose
/// on-board log, never thinned, would alone pass `--max-log-bytes`. A run
/// until stopped (`parts`: its logs in parts of `--max-log-bytes`) is
/// neither refused nor thinned to fit: only `--log-rate` thins it.
fn plan_logs(
    case: &Scenario,
    prepared: &helicon_sim::closed_loop::Prepared,
    a: &SitlArgs,
    parts: bool,
) -> Result<usize> {
    if parts {
        // the stride of --log-rate alone: one sample's flight fits any bound
        let mut one = case.clone();
        one.duration_s = prepared.gains.set.sample_time_s;
        return plan_log(&one, prepared, &a.log);
    }
    // the on-board log is never thinned: refused when it alone is over
    let ulog_bytes =
        sitl::estimate_ulog_bytes(case, prepared.gains.set.sample_time_s, a.gcs.is_some());
    let (max, named) = a.log.limit(case);
    if ulog_bytes > max {
        anyhow::bail!(
            "flight.ulg (the on-board log, written at its full rate) of this flight would be about {}, over {named}: give a shorter --duration or a larger --max-log-bytes",
            human_bytes(ulog_bytes),
        );
    }
    plan_log(case, prepared, &a.log)
}

/// A ground-station run's design, `case` put on the ground, disarmed,
/// rotor stopped ([`sitl::ground_start`]), and without `--duration` until
/// stopped ([`until_stopped_s`]); told on `con`.
fn prepare_on_the_ground(
    case: &mut Scenario,
    a: &SitlArgs,
    con: &mut Console,
) -> Result<helicon_sim::closed_loop::Prepared> {
    let (mut grounded, params) = sitl::ground_start(case)
        .with_context(|| format!("scenario `{}`: putting it on the ground", case.name))?;
    if case.ground.is_none() {
        writeln!(
            con,
            "{}: on the ground {} m below the design point (landing gear, drivetrain and ground effect on), disarmed, rotor stopped",
            case.name,
            sitl::GROUND_START_DOWN_M
        );
    }
    let prepared =
        helicon_sim::closed_loop::prepare_with_params(&grounded, params).with_context(|| {
            format!(
                "scenario `{}`: preparing the design point and gains",
                grounded.name
            )
        })?;
    if a.duration.is_none() {
        let (max, named) = a.log.limit(&grounded);
        grounded.duration_s = until_stopped_s(&grounded, &prepared);
        writeln!(
            con,
            "{}: flying until stopped (Ctrl-C; the simulator's work limit is {:.0} h); flight.ulg and log.csv go on in numbered parts of at most {} each ({named})",
            grounded.name,
            grounded.duration_s / 3600.0,
            human_bytes(max)
        );
    }
    *case = grounded;
    Ok(prepared)
}

/// How long a ground-station run without `--duration` lasts unless
/// stopped: the simulator's work limit ([`MAX_PLANT_STEPS`] plant steps,
/// days of flight), 1 % under it. Its logs are bounded by parts
/// ([`SitlOptions::log_part_bytes`]), not by the duration.
///
/// [`MAX_PLANT_STEPS`]: helicon_sim::scenario::MAX_PLANT_STEPS
fn until_stopped_s(case: &Scenario, prepared: &helicon_sim::closed_loop::Prepared) -> f64 {
    let ts = prepared.gains.set.sample_time_s;
    let by_work =
        helicon_sim::scenario::MAX_PLANT_STEPS * ts / f64::from(case.plant.substeps.max(1));
    (0.99 * by_work).max(ts)
}

/// An autopilot backend's run, prepared: the one case on the ground, its
/// design point, the output folder and the log stride.
struct Backend {
    case: Scenario,
    prepared: helicon_sim::closed_loop::Prepared,
    out: PathBuf,
    log_stride: usize,
}

/// Prepare an autopilot backend's run of `a` (`what`: the autopilot, for
/// messages; `prefix`: of the default output folder).
fn prepare_backend(a: &SitlArgs, what: &str, prefix: &str) -> Result<Backend> {
    let duration = a.duration.or(Some(3600.0));
    let o = overrides_from(None, None, duration)?;
    let source = format!("{}{}", a.scenario.display(), overrides_label(&o));
    let base = Scenario::from_file(&a.scenario)?.with_overrides(&o, &source)?;
    let cases = base.cases();
    if cases.len() > 1 {
        anyhow::bail!(
            "{source}: {} cases; {what} flies one helicopter at a time (give a scenario without [[case]])",
            cases.len()
        );
    }
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from("out").join(format!("{prefix}-{}", folder_name(&base.name)))
    });
    let (case, params) = sitl::ground_start(&base)
        .with_context(|| format!("scenario `{}`: putting it on the ground", base.name))?;
    let prepared = helicon_sim::closed_loop::prepare_with_params(&case, params)
        .with_context(|| format!("scenario `{}`: preparing the design point", case.name))?;
    let log_stride = plan_log(&case, &prepared, &a.log)?;
    Ok(Backend {
        case,
        prepared,
        out,
        log_stride,
    })
}

/// A mapping file: `path`, or the shipped `default_text` named `default_name`.
fn mapping_source<T, E: std::error::Error + Send + Sync + 'static>(
    path: Option<&PathBuf>,
    default_text: &str,
    default_name: &str,
    from_file: impl Fn(&std::path::Path) -> Result<T, E>,
    from_str: impl Fn(&str, &str) -> Result<T, E>,
) -> Result<(T, String)> {
    Ok(match path {
        Some(path) => (from_file(path)?, path.display().to_string()),
        None => (
            from_str(default_text, default_name)?,
            default_name.to_string(),
        ),
    })
}

/// Finish an autopilot backend's run: `timing.json`, the run folder of the
/// last session (when it logged), the closing lines, and the exit of a
/// signal.
fn finish_backend(
    b: &Backend,
    mut con: Console,
    stop: &Stop,
    timing: &serde_json::Value,
    summary: Option<&helicon_sim::closed_loop::Summary>,
    log_rows: usize,
    line: String,
) -> Result<()> {
    let out = &b.out;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    sitl::write_timing(out, timing)?;
    if let Some(summary) = summary
        && log_rows > 0
    {
        let mut summary = summary.clone();
        mark_stopped(stop, &mut summary);
        finish_run(out, &b.case, &b.prepared, &summary, log_rows)
            .with_context(|| format!("writing the run outputs to {}", out.display()))?;
    }
    writeln!(con, "{}: {line}", b.case.name);
    writeln!(
        con,
        "  wrote timing.json{} to {}",
        if log_rows > 0 {
            ", log.csv, summary.json, plots"
        } else {
            ""
        },
        out.display()
    );
    // a signal ends the run as in the other modes: its files complete, exit 130/143
    if let Some(e) = stop.stopped(format!(
        "timing.json and the run folder of {} are complete",
        out.display()
    )) {
        let _ = con.finish();
        return Err(e.into());
    }
    con.finish()?;
    Ok(())
}

/// `helicon sitl --ardupilot-json`: helicon as ArduPilot's physics.
fn run_ardupilot(a: &SitlArgs, address: &str) -> Result<()> {
    use helicon_sitl::ardupilot::{
        ArduPilotMap, ArduPilotOptions, ArduPilotSection, ArduPilotServer, BERGEN_TWIN_TOML,
    };
    let b = prepare_backend(a, "ArduPilot", "ardupilot")?;
    let mut con = Console::stdout();
    let (section, file) = mapping_source(
        a.ardupilot_config.as_ref(),
        BERGEN_TWIN_TOML,
        "examples/ardupilot/bergen_twin.toml",
        ArduPilotSection::from_file,
        ArduPilotSection::from_toml_str,
    )?;
    let map = ArduPilotMap::new(section, b.prepared.model.params(), &file)?;
    let server = ArduPilotServer::bind(address)?;
    let stop = Stop::install()?;
    writeln!(
        con,
        "{}: ArduPilot JSON physics on udp {} ({}), on the ground, rotor stopped; waiting for ArduPilot's SITL (sim_vehicle.py -v ArduCopter -f heli --model JSON:{}); Ctrl-C ends, at most {:.0} s of model time",
        b.case.name,
        server.local_addr(),
        file,
        server.local_addr().ip(),
        b.case.duration_s
    );
    let options = ArduPilotOptions {
        out_dir: Some(b.out.clone()),
        log_stride: b.log_stride,
        stop: Some(stop.flag().clone()),
        silence_timeout: None,
        max_frames: None,
    };
    let r = server
        .run(&b.case, &b.prepared, &map, &options)
        .with_context(|| format!("scenario `{}`: ArduPilot JSON physics", b.case.name))?;
    let c = &r.counts;
    let line = format!(
        "{}; {} frames at {} Hz ({:.3} s of model time in the last session), {:.0} frames/s, {:.1}x real time; {} repeats, {} restarts, {} gaps, {} malformed packets, {} frames at another rate",
        r.ending.describe(),
        c.frames,
        r.frame_rate_hz.map_or("-".to_string(), |f| f.to_string()),
        r.model_time_s,
        r.frames_per_s,
        r.speed_x,
        c.repeats,
        c.restarts,
        c.gaps,
        c.malformed(),
        c.rate_mismatches
    );
    finish_backend(
        &b,
        con,
        &stop,
        &helicon_sitl::ardupilot::timing_json(&r),
        r.summary.as_ref(),
        r.log_rows,
        line,
    )
}

/// `helicon sitl --px4`: helicon as PX4's simulator.
fn run_px4(a: &SitlArgs, address: &str) -> Result<()> {
    use helicon_sitl::px4::{BERGEN_TWIN_TOML, Px4Map, Px4Options, Px4Section, Px4Server};
    let b = prepare_backend(a, "PX4", "px4")?;
    let mut con = Console::stdout();
    let (section, file) = mapping_source(
        a.px4_config.as_ref(),
        BERGEN_TWIN_TOML,
        "examples/px4/bergen_twin.toml",
        Px4Section::from_file,
        Px4Section::from_toml_str,
    )?;
    let map = Px4Map::new(section, b.prepared.model.params(), &file)?;
    let server = Px4Server::bind(address)?;
    let stop = Stop::install()?;
    writeln!(
        con,
        "{}: PX4 simulator on tcp {} ({}), on the ground, rotor stopped; waiting for PX4's SITL to connect (PX4_SIMULATOR=none make px4_sitl none, airframe examples/px4/bergen_twin.params); Ctrl-C ends, at most {:.0} s of model time",
        b.case.name,
        server.local_addr(),
        file,
        b.case.duration_s
    );
    let options = Px4Options {
        out_dir: Some(b.out.clone()),
        log_stride: b.log_stride,
        stop: Some(stop.flag().clone()),
        ..Px4Options::default()
    };
    let r = server
        .run(&b.case, &b.prepared, &map, &options)
        .with_context(|| format!("scenario `{}`: PX4 simulator", b.case.name))?;
    let c = &r.counts;
    let line = format!(
        "{}; {} steps of {} µs ({:.3} s of model time in the last connection), {:.0} steps/s, {:.1}x real time; {} connections, {} armed steps, {} malformed frames, {} junk bytes",
        r.ending.describe(),
        c.steps,
        r.step_us,
        r.model_time_s,
        r.steps_per_s,
        r.speed_x,
        c.connections,
        c.armed_messages,
        c.malformed(),
        c.junk_bytes
    );
    finish_backend(
        &b,
        con,
        &stop,
        &helicon_sitl::px4::timing_json(&r),
        r.summary.as_ref(),
        r.log_rows,
        line,
    )
}

/// Run `helicon sitl`.
pub fn run(a: &SitlArgs) -> Result<()> {
    match (&a.ardupilot_json, &a.px4) {
        (Some(address), _) => run_ardupilot(a, address),
        (None, Some(address)) => run_px4(a, address),
        (None, None) => run_onboard(a),
    }
}

/// `helicon sitl` flying helicon's on-board program.
#[allow(clippy::too_many_lines)] // one case after another: prepare, fly, write, print
fn run_onboard(a: &SitlArgs) -> Result<()> {
    check_time("--gps-loss-at", a.gps_loss_at)?;
    check_time("--manual-at", a.manual_at)?;
    check_time("--manual-until", a.manual_until)?;
    check_time("--rc-failsafe-at", a.rc_failsafe_at)?;
    check_time("--rc-silent-at", a.rc_silent_at)?;
    check_time("--rc-silent-until", a.rc_silent_until)?;
    let o = overrides_from(None, None, a.duration)?;
    let source = format!("{}{}", a.scenario.display(), overrides_label(&o));
    let base = Scenario::from_file(&a.scenario)?.with_overrides(&o, &source)?;
    let root = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("sitl-{}", folder_name(&base.name))));
    let cases = base.cases();
    for case in &cases {
        check_events(a, case.duration_s, &source)?;
    }
    let mut con = Console::stdout();
    let stop = Stop::install()?;
    for mut case in cases.iter().cloned() {
        case.controller.fusion = true;
        let out = if cases.len() > 1 {
            root.join(folder_name(&case.name))
        } else {
            root.clone()
        };
        let prepared = match a.gcs {
            Some(_) => prepare_on_the_ground(&mut case, a, &mut con)?,
            None => prepare_step(&case)?.0,
        };
        case.check_work(&source, prepared.gains.set.sample_time_s)?;
        let parts = a.gcs.is_some() && a.duration.is_none();
        let log_stride = plan_logs(&case, &prepared, a, parts)?;
        let status = SimStatus::start(a.speed == SpeedArg::Realtime, case.duration_s);
        let options = SitlOptions {
            speed: match a.speed {
                SpeedArg::Max => Speed::Max,
                SpeedArg::Realtime => Speed::Realtime,
            },
            out_dir: out.clone(),
            faults: Faults {
                gps_lost_from_s: a.gps_loss_at,
                ..Faults::default()
            },
            pilot: Pilot {
                manual_from_s: a.manual_at,
                manual_until_s: a.manual_until,
                rc_failsafe_s: a.rc_failsafe_at.map(|t| (t, f64::INFINITY)),
                rc_silent_s: a
                    .rc_silent_at
                    .map(|t| (t, a.rc_silent_until.unwrap_or(f64::INFINITY))),
                ..Pilot::default()
            },
            stale: StaleLimits::default(),
            failsafe: FailsafeConfig::default(),
            realtime: RealtimeConfig {
                sched_fifo: !a.no_sched_fifo,
                ..RealtimeConfig::default()
            },
            keep_frames: false,
            gcs: a.gcs.clone(),
            log_stride,
            log_part_bytes: parts.then(|| a.log.limit(&case).0),
            stop: Some(stop.flag().clone()),
            clock: Some(status.clock()),
        };
        let mut r = status
            .during(|| sitl::run(&case, &prepared, &options))
            .with_context(|| format!("scenario `{}`: software in the loop", case.name))?;
        for w in &r.onboard.realtime.warnings {
            eprintln!("warning: {w}");
        }
        mark_stopped(&stop, &mut r.summary);
        let timing = sitl::timing_json(&r, options.speed);
        sitl::write_timing(&out, &timing)?;
        finish_run(&out, &case, &prepared, &r.summary, r.log_rows)
            .with_context(|| format!("writing the run outputs to {}", out.display()))?;
        let s = &r.summary;
        writeln!(
            con,
            "{}: {} at t = {:.3} s{}; {} control steps, {:.1}x real time ({:.0}x per CPU second), final mode {}",
            case.name,
            s.termination,
            s.t_end_s,
            s.reason
                .as_deref()
                .map_or(String::new(), |r| format!(" ({r})")),
            r.onboard.steps,
            r.speed_x,
            if r.cpu_s > 0.0 {
                r.samples as f64 * r.sample_time_s / r.cpu_s
            } else {
                0.0
            },
            r.onboard.final_mode
        );
        for name in OUTPUTS {
            if let Some(m) = s.metrics.get(name) {
                writeln!(
                    con,
                    "  {name:<4} RMS error {:.4}, max {:.4}",
                    m.rms_error, m.max_abs_error
                );
            }
        }
        let t = &r.onboard;
        writeln!(
            con,
            "  timing: compute p50 {:.0} µs p99 {:.0} µs max {:.0} µs; sensor-to-servo p99 {:.0} µs; \
             wake-up jitter p99 {:.0} µs max {:.0} µs; {} deadline misses",
            t.compute.p50_us,
            t.compute.p99_us,
            t.compute.max_us,
            t.sensor_to_servo.p99_us,
            t.wakeup_jitter.p99_us,
            t.wakeup_jitter.max_us,
            t.deadline_misses
        );
        writeln!(
            con,
            "  wrote flight.ulg, log.csv, timing.json, summary.json, plots to {}",
            out.display()
        );
        if let Some(e) = stop.stopped(format!(
            "flight.ulg, log.csv, timing.json and summary.json of {} are complete",
            out.display()
        )) {
            let _ = con.finish();
            return Err(e.into());
        }
    }
    con.finish()?;
    Ok(())
}
