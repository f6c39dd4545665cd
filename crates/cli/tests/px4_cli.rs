//! `helicon sitl --px4` from the outside: a bad `[px4]` file is refused
//! naming the file and the field; a run serves a stand-in PX4 (a TCP
//! client speaking MAVLink) on the OS-chosen port it prints, and SIGINT
//! ends it with `timing.json` (the steps counted) and the run folder.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

use helicon_gcs::mavlink::dialects::common::{
    HEARTBEAT_DATA, HIL_ACTUATOR_CONTROLS_DATA, HilActuatorControlsFlags, MavMessage, MavModeFlag,
};
use helicon_gcs::mavlink::{MavHeader, MavlinkReader, write_v2_msg};
use helicon_test_support::tmpdir;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn a_bad_px4_mapping_is_refused_naming_file_and_field() {
    let dir = tmpdir("bad");
    let text = std::fs::read_to_string(root().join("examples/px4/bergen_twin.toml"))
        .unwrap()
        .replacen("tail_channel = 2", "tail_channel = 1", 1);
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, text).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(["sitl"])
        .arg(root().join("scenarios/demo.toml"))
        .args(["--px4", "127.0.0.1:0", "--px4-config"])
        .arg(&bad)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("bad.toml") && err.contains("px4.tail_channel"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_px4_run_serves_steps_and_sigint_writes_its_files() {
    let dir = tmpdir("run");
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(["sitl"])
        .arg(root().join("scenarios/demo.toml"))
        .args(["--px4", "127.0.0.1:0", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let addr = loop {
        let line = lines.next().expect("a line naming the port").unwrap();
        if let Some(i) = line.find("tcp ") {
            break line[i + 4..].split(' ').next().unwrap().to_string();
        }
    };
    let mut stream = TcpStream::connect(&addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut reader = MavlinkReader::new(stream.try_clone().unwrap());
    let mut header = MavHeader::default();
    let controls = MavMessage::HIL_ACTUATOR_CONTROLS(HIL_ACTUATOR_CONTROLS_DATA {
        time_usec: 0,
        flags: HilActuatorControlsFlags::HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP,
        controls: [0.0; 16],
        mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
    });
    // the hello and the first answer in one write: lock-step from the
    // first contact (no free-running step can come between them)
    let mut hello = Vec::new();
    write_v2_msg(
        &mut hello,
        header,
        &MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()),
    )
    .unwrap();
    header.sequence = 1;
    write_v2_msg(&mut hello, header, &controls).unwrap();
    stream.write_all(&hello).unwrap();
    let mut last = 0;
    for k in 0..=500u64 {
        loop {
            let (_, m) = reader.read_any_message::<MavMessage>().unwrap();
            if let MavMessage::HIL_SENSOR(s) = m {
                assert_eq!(s.time_usec, k * 4000);
                last = s.time_usec;
                break;
            }
        }
        if k > 0 && k < 500 {
            header.sequence = header.sequence.wrapping_add(1);
            write_v2_msg(&mut stream, header, &controls).unwrap();
        }
    }
    assert_eq!(last, 2_000_000);
    kill(
        Pid::from_raw(i32::try_from(child.id()).unwrap()),
        Signal::SIGINT,
    )
    .unwrap();
    let status = child.wait().unwrap();
    assert_eq!(
        status.code(),
        Some(130),
        "SIGINT ends it as the other modes"
    );
    let timing: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("timing.json")).unwrap()).unwrap();
    assert_eq!(timing["backend"], "px4");
    assert_eq!(timing["frames"], 500);
    assert_eq!(timing["step_us"], 4000);
    assert_eq!(timing["counts"]["connections"], 1);
    assert!(timing["frames_per_s"].as_f64().unwrap() > 0.0);
    assert!(out.join("log.csv").is_file() && out.join("summary.json").is_file());
    drop(stream);
    std::fs::remove_dir_all(&dir).unwrap();
}
