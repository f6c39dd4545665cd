//! `helicon onboard` and `helicon sitl` from the command line: bad input is
//! an error naming the file and the field (never a panic or a hang); a
//! short lock-step SITL run writes its files.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("helicon_onboard_cli_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run the binary in `d`: (exit code, stdout, stderr).
fn helicon(d: &Path, args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(args)
        .current_dir(d)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

const DEVICES: &str = "[devices.imu]\npath = \"/dev/null-imu\"\nbaud = 921600\n\
    [devices.gps]\npath = \"/dev/null-gps\"\nbaud = 115200\n\
    [devices.avionics]\npath = \"/dev/null-av\"\nbaud = 115200\n";

fn fails_with(d: &Path, args: &[&str], needles: &[&str]) {
    let (code, _, err) = helicon(d, args);
    assert_eq!(code, Some(1), "{args:?}: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: `{n}` not in: {err}");
    }
}

#[test]
fn onboard_bad_input_names_the_file_and_field() {
    let d = dir("bad");
    fails_with(
        &d,
        &["onboard", "--config", "missing.toml"],
        &["missing.toml", "cannot read"],
    );
    std::fs::write(
        d.join("stale.toml"),
        format!("gains = \"g.json\"\n{DEVICES}[stale]\ngps_s = -1.0\n"),
    )
    .unwrap();
    fails_with(
        &d,
        &["onboard", "--config", "stale.toml"],
        &["stale.toml", "stale.gps_s", "-1"],
    );
    std::fs::write(
        d.join("baud.toml"),
        format!("gains = \"g.json\"\n{}", DEVICES.replace("921600", "7")),
    )
    .unwrap();
    fails_with(
        &d,
        &["onboard", "--config", "baud.toml"],
        &["baud.toml", "devices.imu.baud"],
    );
    std::fs::write(
        d.join("nogains.toml"),
        format!("gains = \"g.json\"\n{DEVICES}"),
    )
    .unwrap();
    fails_with(&d, &["onboard", "--config", "nogains.toml"], &["g.json"]);
    fails_with(
        &d,
        &["onboard", "--config", "nogains.toml", "--duration", "nan"],
        &["--duration"],
    );
    // a real gains file, then a device that is not there
    std::fs::write(d.join("ok.toml"), "name = \"ok\"\nduration_s = 0.1\n").unwrap();
    let (code, _, err) = helicon(&d, &["sim", "ok.toml", "--out", "g"]);
    assert_eq!(code, Some(0), "{err}");
    std::fs::write(
        d.join("nodev.toml"),
        format!("gains = \"g/gains.json\"\n{DEVICES}"),
    )
    .unwrap();
    fails_with(
        &d,
        &["onboard", "--config", "nodev.toml"],
        &["/dev/null-imu", "cannot open"],
    );
}

#[test]
fn sitl_bad_flags_and_a_short_run() {
    let d = dir("sitl");
    std::fs::write(d.join("ok.toml"), "name = \"ok\"\nduration_s = 0.5\n").unwrap();
    fails_with(
        &d,
        &["sitl", "ok.toml", "--gps-loss-at", "nan"],
        &["--gps-loss-at"],
    );
    fails_with(&d, &["sitl", "ok.toml", "--duration", "0"], &["duration_s"]);
    fails_with(
        &d,
        &["sitl", "ok.toml", "--rc-failsafe-at", "-1"],
        &["--rc-failsafe-at"],
    );
    fails_with(
        &d,
        &["sitl", "ok.toml", "--rc-silent-at", "inf"],
        &["--rc-silent-at"],
    );
    // --rc-silent-until needs --rc-silent-at: a usage error (clap's code 2)
    let (code, _, err) = helicon(&d, &["sitl", "ok.toml", "--rc-silent-until", "1"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--rc-silent-at"), "{err}");
    fails_with(&d, &["sitl", "missing.toml"], &["missing.toml"]);
    let (code, out, err) = helicon(&d, &["sitl", "ok.toml", "--out", "o"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        out.contains("ok: completed at t = 0.500 s; 201 control steps"),
        "{out}"
    );
    for f in [
        "flight.ulg",
        "log.csv",
        "timing.json",
        "summary.json",
        "outputs.png",
    ] {
        assert!(d.join("o").join(f).exists(), "{f}");
    }
    let timing: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("o/timing.json")).unwrap()).unwrap();
    assert_eq!(timing["onboard"]["steps"], 201);
    assert_eq!(timing["onboard"]["servo_frames"], 201);
    assert_eq!(timing["onboard"]["servo_frames_dropped"], 0);
}
