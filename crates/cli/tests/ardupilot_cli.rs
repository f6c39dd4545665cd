//! `helicon sitl --ardupilot-json` from the outside: a bad `[ardupilot]`
//! file is refused naming the file and the field; a run serves a stand-in
//! autopilot's frames on the OS-chosen port it prints, and SIGINT ends it
//! with `timing.json` (the frames counted) and the run folder written.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn a_bad_mapping_is_refused_naming_file_and_field() {
    let dir = tmpdir("bad");
    let text = std::fs::read_to_string(root().join("examples/ardupilot/bergen_twin.toml"))
        .unwrap()
        .replacen("channel = 2", "channel = 1", 1);
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, text).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(["sitl"])
        .arg(root().join("scenarios/demo.toml"))
        .args(["--ardupilot-json", "127.0.0.1:0", "--ardupilot-config"])
        .arg(&bad)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("bad.toml") && err.contains("ardupilot.swash2.channel"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_serves_frames_and_sigint_writes_its_files() {
    let dir = tmpdir("run");
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(["sitl"])
        .arg(root().join("scenarios/demo.toml"))
        .args(["--ardupilot-json", "127.0.0.1:0", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let addr = loop {
        let line = lines.next().expect("a line naming the port").unwrap();
        if let Some(i) = line.find("udp ") {
            break line[i + 4..].split(' ').next().unwrap().to_string();
        }
    };
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    sock.set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut buf = [0u8; 2048];
    let mut last = String::new();
    for k in 0..800u32 {
        let mut b = Vec::new();
        b.extend_from_slice(&18458u16.to_le_bytes());
        b.extend_from_slice(&400u16.to_le_bytes());
        b.extend_from_slice(&k.to_le_bytes());
        for ch in 0..16 {
            let v: u16 = if ch < 4 { 1500 } else { 1000 };
            b.extend_from_slice(&v.to_le_bytes());
        }
        sock.send_to(&b, &addr).unwrap();
        let (n, _) = sock.recv_from(&mut buf).unwrap();
        last = String::from_utf8(buf[..n].to_vec()).unwrap();
    }
    let v: serde_json::Value = serde_json::from_str(last.trim()).unwrap();
    assert_eq!(v["timestamp"].as_f64().unwrap(), 2.0);
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
    assert_eq!(timing["backend"], "ardupilot-json");
    assert_eq!(timing["frames"], 800);
    assert_eq!(timing["frame_rate_hz"], 400);
    assert!(timing["frames_per_s"].as_f64().unwrap() > 0.0);
    assert!(out.join("log.csv").is_file() && out.join("summary.json").is_file());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        summary["reason"].as_str().unwrap().contains("SIGINT"),
        "{summary}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
