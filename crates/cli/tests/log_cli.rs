//! Runs `helicon log export` and `helicon log info` as a user would.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../ulog/tests/fixtures")
        .join(name)
}

#[test]
fn export_writes_one_csv_per_topic_and_the_text_files() {
    let dir = tmpdir("export");
    let out = dir.join("csv");
    let ulg = fixture("helicon_sample.ulg");
    let (ok, stdout, stderr) = helicon(&[
        "log",
        "export",
        ulg.to_str().unwrap(),
        "--csv",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("control 0: 60 rows"), "{stdout}");
    let control = std::fs::read_to_string(out.join("helicon_sample_control_0.csv")).unwrap();
    let mut lines = control.lines();
    let head = lines.next().unwrap();
    assert!(head.starts_with("timestamp,sample,t_s,"), "{head}");
    assert_eq!(lines.count(), 60);
    for topic in [
        "sensor_imu",
        "helicon_mag",
        "helicon_gps",
        "navigation",
        "servo_output",
        // PX4's topics beside them (no home: no geodetic ones)
        "vehicle_attitude",
        "sensor_combined",
        "vehicle_status",
    ] {
        assert!(
            out.join(format!("helicon_sample_{topic}_0.csv")).exists(),
            "{topic}"
        );
    }
    let msgs = std::fs::read_to_string(out.join("helicon_sample_messages.txt")).unwrap();
    assert!(
        msgs.contains("1125000 critical failsafe raised: RC signal lost"),
        "{msgs}"
    );
    assert!(msgs.contains("1050000 dropout 12 ms"), "{msgs}");
    let params = std::fs::read_to_string(out.join("helicon_sample_params.txt")).unwrap();
    assert_eq!(
        params,
        "CTRL_DT 0.0025\nLOG_RATE 400\nCTRL_DT 0.005 @ 1050000\n"
    );
    let info = std::fs::read_to_string(out.join("helicon_sample_info.txt")).unwrap();
    assert!(info.contains("sys_name: helicon\n"), "{info}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn info_lists_topics_with_rates() {
    let ulg = fixture("helicon_sample.ulg");
    let (ok, stdout, stderr) = helicon(&["log", "info", ulg.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("control 0 60 1000000 1147500 400.000"),
        "{stdout}"
    );
    assert!(stdout.contains("dropouts: 12 ms"), "{stdout}");
}

#[test]
fn a_truncated_log_exports_what_it_holds_and_says_so() {
    let dir = tmpdir("truncated");
    let bytes = std::fs::read(fixture("helicon_sample.ulg")).unwrap();
    let cut = dir.join("cut.ulg");
    std::fs::write(&cut, &bytes[..bytes.len() / 2 + 7]).unwrap();
    let out = dir.join("csv");
    let (ok, stdout, stderr) = helicon(&[
        "log",
        "export",
        cut.to_str().unwrap(),
        "--csv",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("cut.ulg: truncated at byte"), "{stderr}");
    assert!(stdout.contains("control 0: "), "{stdout}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_inputs_are_errors_naming_the_file() {
    let dir = tmpdir("bad");
    let missing = dir.join("missing.ulg");
    let (ok, _, stderr) = helicon(&["log", "info", missing.to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.contains("missing.ulg: cannot read"), "{stderr}");
    let not_ulog = dir.join("notes.ulg");
    std::fs::write(&not_ulog, "t_s,x\n0,1\n").unwrap();
    let (ok, _, stderr) = helicon(&[
        "log",
        "export",
        not_ulog.to_str().unwrap(),
        "--csv",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(stderr.contains("notes.ulg: not a ULog file"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_corrupt_log_is_one_error_line_with_the_offset_and_rule() {
    let dir = tmpdir("corrupt");
    // a valid header, then two formats that refer to each other
    let mut f = b"ULog\x01\x12\x35\x01".to_vec();
    f.extend_from_slice(&0u64.to_le_bytes());
    for (kind, payload) in [
        (b'F', &b"a:uint64_t timestamp;b x;"[..]),
        (b'F', &b"b:a y;"[..]),
        (b'A', &b"\x00\x00\x00a"[..]),
    ] {
        f.extend_from_slice(&(payload.len() as u16).to_le_bytes());
        f.push(kind);
        f.extend_from_slice(payload);
    }
    let bad = dir.join("cycle.ulg");
    std::fs::write(&bad, &f).unwrap();
    for args in [
        vec!["log", "info", bad.to_str().unwrap()],
        vec![
            "log",
            "export",
            bad.to_str().unwrap(),
            "--csv",
            dir.join("out").to_str().unwrap(),
        ],
    ] {
        let (ok, _, stderr) = helicon(&args);
        assert!(!ok, "{args:?}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.starts_with("error: ")
                && stderr.contains(
                    "cycle.ulg: byte 53: 'A' message: topic `a`: types nest deeper than 8 levels"
                ),
            "{stderr}"
        );
    }
    // an output folder that is a file
    let file = dir.join("taken");
    std::fs::write(&file, "x").unwrap();
    let ulg = fixture("helicon_sample.ulg");
    let (ok, _, stderr) = helicon(&[
        "log",
        "export",
        ulg.to_str().unwrap(),
        "--csv",
        file.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(stderr.contains("taken: cannot create"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}
