//! SIGINT and SIGTERM end `helicon sim`, `helicon sitl` and `helicon
//! onboard` cleanly, through the real binary: the files a normal end
//! writes are there and complete (the ULog read to its end by the crate's
//! reader, `log.csv` by its reader, the summaries marked `stopped`), and the
//! exit status is 128 + the signal (130, 143). Each waits for the run to
//! have written something, with a bounded wait.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

#[allow(dead_code)] // only the scratch folder of the helpers is used here
mod common;

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::avionics::RcInput as RcFrame;
use helicon_devices::{Geodetic, LocalNed, NavPvt, PtyPair, VnCommon};
use helicon_ulog::reader::{Message, UlogReader};
use nalgebra::Vector3;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const WAIT: Duration = Duration::from_secs(120);

fn demo_scenario() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml")
}

/// Spawn `helicon args` in `dir`, stdout and stderr into files there.
fn spawn(dir: &Path, args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(dir.join("stdout.txt")).unwrap())
        .stderr(std::fs::File::create(dir.join("stderr.txt")).unwrap())
        .spawn()
        .unwrap()
}

/// Wait (bounded) until `ready` holds; the child must still be running.
fn wait_until(child: &mut Child, dir: &Path, what: &str, ready: impl Fn() -> bool) {
    let t0 = Instant::now();
    while !ready() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!(
                "ended ({status}) before {what}: {}",
                std::fs::read_to_string(dir.join("stderr.txt")).unwrap_or_default()
            );
        }
        if t0.elapsed() > WAIT {
            let _ = child.kill();
            panic!("no {what} within {WAIT:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Send `signal` and wait (bounded) for the exit code.
fn stop_with(child: &mut Child, signal: Signal) -> i32 {
    let pid = Pid::from_raw(i32::try_from(child.id()).unwrap());
    kill(pid, signal).unwrap();
    let t0 = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status
                .code()
                .expect("an exit code, not a death by the signal");
        }
        if t0.elapsed() > WAIT {
            let _ = child.kill();
            panic!("still running {WAIT:?} after {signal}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn size(p: &Path) -> u64 {
    std::fs::metadata(p).map(|m| m.len()).unwrap_or(0)
}

/// Read a ULog file to its end with the crate's reader: every byte a whole
/// message. Returns the number of data messages.
fn ulog_data_messages(path: &Path) -> usize {
    let bytes = std::fs::read(path).unwrap();
    let mut r = UlogReader::new(&bytes[..], &path.display().to_string()).unwrap();
    let mut data = 0;
    while let Some(m) = r.next_message().unwrap() {
        if matches!(m, Message::Data { .. }) {
            data += 1;
        }
    }
    assert_eq!(r.offset(), bytes.len() as u64, "{}", path.display());
    data
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `helicon sim` of an hour, stopped by `signal` while it flies: exit
/// `code`, the run folder complete for what was flown, the summary
/// `stopped` naming the signal.
fn sim_run_stopped_by(name: &str, signal: Signal, code: i32) {
    let d = common::tmpdir(name);
    let scenario = demo_scenario();
    let mut child = spawn(
        &d,
        &[
            "sim",
            scenario.to_str().unwrap(),
            "--duration",
            "3600",
            "--out",
            "run",
        ],
    );
    let log = d.join("run/log.csv");
    wait_until(&mut child, &d, "log rows", || size(&log) > 300_000);
    let got = stop_with(&mut child, signal);
    let err = std::fs::read_to_string(d.join("stderr.txt")).unwrap();
    assert_eq!(got, code, "{err}");
    assert!(err.contains(&format!("stopped by {signal}")), "{err}");
    let s = json(&d.join("run/summary.json"));
    assert_eq!(s["outcome"], "stopped", "{s}");
    assert_eq!(s["termination"], "stopped");
    assert!(
        s["reason"].as_str().unwrap().contains(signal.as_str()),
        "{s}"
    );
    let t_end = s["t_end_s"].as_f64().unwrap();
    assert!(t_end > 0.0 && t_end < 3600.0, "{t_end}");
    let back = helicon_sim::log_csv::read_log_csv(&log).unwrap();
    let t_last = *back.time_s().last().unwrap();
    assert!((t_last - t_end).abs() < 0.011, "{t_last} vs {t_end}");
    for f in ["gains.json", "scenario.toml", "report.md"] {
        assert!(d.join("run").join(f).exists(), "{f}");
    }
    let out = std::fs::read_to_string(d.join("stdout.txt")).unwrap();
    assert!(out.contains("outcome: STOPPED"), "{out}");
}

/// `helicon sim`, SIGINT (Ctrl-C): exit 130, the folder complete.
#[test]
fn sigint_ends_a_sim_run_with_its_folder_complete() {
    sim_run_stopped_by("sim_sigint", Signal::SIGINT, 130);
}

/// `helicon sim`, SIGTERM (a service manager's stop): exit 143, the folder
/// complete.
#[test]
fn sigterm_ends_a_sim_run_with_its_folder_complete() {
    sim_run_stopped_by("sim_sigterm", Signal::SIGTERM, 143);
}

/// A second signal while a run stops exits at once with its own status
/// (crates/cli/src/signals.rs): SIGINT, then SIGTERM 1 ms later, to a
/// `helicon sim` flying. The clean end after the first signal (the step
/// finished, `log.csv` flushed, the summary, the report and the plots
/// written) takes far longer than the 1 ms between the two, so the second
/// finds the run still stopping: exit 143, not 130, and no "stopped by"
/// line (the clean end's) on stderr.
#[test]
fn a_second_signal_while_stopping_exits_at_once() {
    let d = common::tmpdir("sim_second_signal");
    let scenario = demo_scenario();
    let mut child = spawn(
        &d,
        &[
            "sim",
            scenario.to_str().unwrap(),
            "--duration",
            "3600",
            "--out",
            "run",
        ],
    );
    let log = d.join("run/log.csv");
    wait_until(&mut child, &d, "log rows", || size(&log) > 300_000);
    let pid = Pid::from_raw(i32::try_from(child.id()).unwrap());
    kill(pid, Signal::SIGINT).unwrap();
    std::thread::sleep(Duration::from_millis(1));
    let code = stop_with(&mut child, Signal::SIGTERM);
    let err = std::fs::read_to_string(d.join("stderr.txt")).unwrap();
    assert_eq!(code, 143, "{err}");
    assert!(!err.contains("stopped by"), "{err}");
}

/// `helicon sitl` lock-step, stopped by `signal` while it flies: exit
/// `code`, the on-board ULog closed (read to its end), `log.csv`,
/// `timing.json` and the summary (`stopped`, naming the signal) written.
fn sitl_run_stopped_by(name: &str, signal: Signal, code: i32) {
    let d = common::tmpdir(name);
    let scenario = demo_scenario();
    let mut child = spawn(
        &d,
        &[
            "sitl",
            scenario.to_str().unwrap(),
            "--duration",
            "600",
            "--out",
            "run",
        ],
    );
    let ulg = d.join("run/flight.ulg");
    wait_until(&mut child, &d, "an on-board log", || size(&ulg) > 200_000);
    let got = stop_with(&mut child, signal);
    let err = std::fs::read_to_string(d.join("stderr.txt")).unwrap();
    assert_eq!(got, code, "{err}");
    assert!(err.contains(&format!("stopped by {signal}")), "{err}");
    let s = json(&d.join("run/summary.json"));
    assert_eq!(s["outcome"], "stopped", "{s}");
    assert!(
        s["reason"].as_str().unwrap().contains(signal.as_str()),
        "{s}"
    );
    let t_end = s["t_end_s"].as_f64().unwrap();
    assert!(t_end > 0.0 && t_end < 600.0, "{t_end}");
    let timing = json(&d.join("run/timing.json"));
    let steps = timing["onboard"]["steps"].as_u64().unwrap();
    assert!(steps > 100, "{timing}");
    assert!(ulog_data_messages(&ulg) > steps as usize);
    let back = helicon_sim::log_csv::read_log_csv(&d.join("run/log.csv")).unwrap();
    assert!(back.rows() > 10);
}

/// `helicon sitl`, SIGTERM: exit 143, its logs closed.
#[test]
fn sigterm_ends_a_sitl_run_with_its_logs_closed() {
    sitl_run_stopped_by("sitl_sigterm", Signal::SIGTERM, 143);
}

/// `helicon sitl`, SIGINT: exit 130, its logs closed.
#[test]
fn sigint_ends_a_sitl_run_with_its_logs_closed() {
    sitl_run_stopped_by("sitl_sigint", Signal::SIGINT, 130);
}

/// The scripted hardware of a still helicopter at home on pseudo-terminals
/// (IMU 400 Hz, GPS 5 Hz, receiver armed 50 Hz), on the wall clock until
/// `done`; writes the on-board configuration into `dir`.
fn hardware(dir: &Path, done: Arc<AtomicBool>) -> std::thread::JoinHandle<()> {
    use helicon_sim::closed_loop::prepare;
    use helicon_sim::scenario::Scenario;
    let s = Scenario::from_toml_str("name = \"hover\"\nduration_s = 1.0\n", "s.toml").unwrap();
    let prepared = prepare(&s).unwrap();
    prepared.gains.save(&dir.join("gains.json")).unwrap();
    let mut imu = PtyPair::open().unwrap();
    let mut gps = PtyPair::open().unwrap();
    let mut av = PtyPair::open().unwrap();
    let cfg = format!(
        "gains = \"gains.json\"\n\
         [devices.imu]\npath = \"{}\"\nbaud = 921600\n\
         [devices.gps]\npath = \"{}\"\nbaud = 115200\n\
         [devices.avionics]\npath = \"{}\"\nbaud = 115200\n\
         [stale]\nimu_s = 0.5\ngps_s = 5.0\nmag_s = 5.0\n\
         [landing]\nenabled = false\n\
         [log]\ndir = \"logs\"\n\
         [realtime]\nsched_fifo = false\nmlockall = false\n",
        imu.slave_path().display(),
        gps.slave_path().display(),
        av.slave_path().display(),
    );
    std::fs::write(dir.join("onboard.toml"), cfg).unwrap();
    let home = LocalNed::new(Geodetic::new(57.0146, 9.9869, 20.0).unwrap());
    let onboard =
        helicon_flight::config::OnboardConfig::from_file(&dir.join("onboard.toml")).unwrap();
    let field = Vector3::from(onboard.sensors.mag.field_ned);
    let g = prepared.model.params().environment.g_m_s2;
    std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut k = 0u64;
        // bounded: at most 5 minutes of samples
        while !done.load(Ordering::Relaxed) && k < 400 * 300 {
            let t = k as f64 * 0.0025;
            if k % 8 == 0 {
                let mut channels_us = [1500u16; 8];
                channels_us[4] = 2000;
                let rc = RcFrame {
                    autonomous: true,
                    channels_us,
                    ..RcFrame::default()
                };
                let _ = av.write_all(rc.encode().as_bytes());
            }
            if k % 80 == 0 {
                let fix = GpsFix {
                    epoch_s: t,
                    fix: GpsFixType::Fix3d,
                    position_ned_m: Vector3::zeros(),
                    velocity_ned_m_s: Some(Vector3::zeros()),
                };
                let itow = 259_200_000 + (t * 1000.0) as u32;
                let pvt = NavPvt::from_gps_fix(&fix, &home, itow, 0.0).unwrap();
                let _ = gps.write_all(pvt.encode().as_bytes());
            }
            let sample = ImuSample {
                specific_force_body_m_s2: Vector3::new(0.0, 0.0, -g),
                gyro_body_rad_s: Vector3::zeros(),
            };
            let mag = (k % 4 == 0).then_some(field);
            let vn = VnCommon::from_samples(t, &sample, mag.as_ref()).unwrap();
            let _ = imu.write_all(vn.encode().unwrap().as_bytes());
            k += 1;
            let next = Duration::from_secs_f64(k as f64 * 0.0025);
            if let Some(wait) = next.checked_sub(t0.elapsed()) {
                std::thread::sleep(wait);
            }
        }
    })
}

fn flight_logs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "ulg"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// `helicon onboard` without `--duration`, SIGINT while it flies: exit
/// 130, the flight log closed (read to its end), its timing report
/// (`flight-0001-…-timing.json`) with `"stopped_by": "SIGINT"`. A second
/// flight into the same folder gets the next number and its own report,
/// the first log and report untouched.
#[test]
fn sigint_ends_the_onboard_program_with_its_log_closed() {
    let d = common::tmpdir("onboard_sigint");
    let done = Arc::new(AtomicBool::new(false));
    let hw = hardware(&d, done.clone());
    let logs = d.join("logs");
    let mut child = spawn(&d, &["onboard", "--config", "onboard.toml"]);
    wait_until(&mut child, &d, "a flight log", || {
        flight_logs(&logs)
            .first()
            .is_some_and(|p| size(p) > 100_000)
    });
    let code = stop_with(&mut child, Signal::SIGINT);
    let err = std::fs::read_to_string(d.join("stderr.txt")).unwrap();
    assert_eq!(code, 130, "{err}");
    assert!(err.contains("stopped by SIGINT"), "{err}");
    let first = flight_logs(&logs);
    assert_eq!(first.len(), 1, "{first:?}");
    let name = first[0].file_name().unwrap().to_str().unwrap().to_string();
    assert!(
        name.starts_with("flight-0001-") && name.ends_with("Z.ulg"),
        "{name}"
    );
    // the flight's own timing report beside its log
    let first_timing = logs.join(name.replace(".ulg", "-timing.json"));
    let timing = json(&first_timing);
    assert_eq!(timing["stopped_by"], "SIGINT", "{timing}");
    let steps = timing["steps"].as_u64().unwrap();
    assert!(steps > 100, "{timing}");
    assert!(ulog_data_messages(&first[0]) > steps as usize);
    let bytes = std::fs::read(&first[0]).unwrap();
    let timing_bytes = std::fs::read(&first_timing).unwrap();

    // a second, short flight in the same folder (same second or not)
    let mut child = spawn(
        &d,
        &["onboard", "--config", "onboard.toml", "--duration", "0.5"],
    );
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > WAIT {
            let _ = child.kill();
            panic!("the second flight did not end");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    done.store(true, Ordering::Relaxed);
    hw.join().unwrap();
    let err = std::fs::read_to_string(d.join("stderr.txt")).unwrap();
    assert_eq!(status.code(), Some(0), "{err}");
    let both = flight_logs(&logs);
    assert_eq!(both.len(), 2, "{both:?}");
    let second = both[1].file_name().unwrap().to_str().unwrap();
    assert!(second.starts_with("flight-0002-"), "{second}");
    assert_eq!(
        std::fs::read(&first[0]).unwrap(),
        bytes,
        "the first log untouched"
    );
    assert!(ulog_data_messages(&both[1]) > 0);
    // the second flight's report is its own: the first one's is untouched
    assert_eq!(
        json(&logs.join(second.replace(".ulg", "-timing.json")))["stopped_by"],
        serde_json::Value::Null
    );
    assert_eq!(
        std::fs::read(&first_timing).unwrap(),
        timing_bytes,
        "the first flight's timing report untouched"
    );
    assert!(!logs.join("timing.json").exists());
}

/// `helicon onboard`, SIGTERM while it flies (a service manager stopping
/// the flight computer's unit): exit 143, the log closed, its timing
/// report with `"stopped_by": "SIGTERM"`.
#[test]
fn sigterm_ends_the_onboard_program_with_its_log_closed() {
    let d = common::tmpdir("onboard_sigterm");
    let done = Arc::new(AtomicBool::new(false));
    let hw = hardware(&d, done.clone());
    let logs = d.join("logs");
    let mut child = spawn(&d, &["onboard", "--config", "onboard.toml"]);
    wait_until(&mut child, &d, "a flight log", || {
        flight_logs(&logs)
            .first()
            .is_some_and(|p| size(p) > 100_000)
    });
    let code = stop_with(&mut child, Signal::SIGTERM);
    done.store(true, Ordering::Relaxed);
    hw.join().unwrap();
    let err = std::fs::read_to_string(d.join("stderr.txt")).unwrap();
    assert_eq!(code, 143, "{err}");
    assert!(err.contains("stopped by SIGTERM"), "{err}");
    let logs_now = flight_logs(&logs);
    assert_eq!(logs_now.len(), 1, "{logs_now:?}");
    let name = logs_now[0].file_name().unwrap().to_str().unwrap();
    let timing = json(&logs.join(name.replace(".ulg", "-timing.json")));
    assert_eq!(timing["stopped_by"], "SIGTERM", "{timing}");
    let steps = timing["steps"].as_u64().unwrap();
    assert!(steps > 100, "{timing}");
    assert!(ulog_data_messages(&logs_now[0]) > steps as usize);
}
